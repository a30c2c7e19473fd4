//! Setpoints of the cascade in motor coordinates, and the conversion of a cart
//! trajectory sample (m) into a motor setpoint (rad), optionally with belt-stretch
//! compensation.
//!
//! Belt-stretch compensation (docs/thesis-map.md, "What the chapter-5 result needs";
//! beyond the thesis, which assumes a rigid belt for the feedforward): for the
//! undamped two-mass model the cart obeys `m_c xi'' = c (i_t phi_m - xi)`, so the
//! motor angle that makes the cart follow `xi_d` exactly is the flat output
//! relation `phi_d = (xi_d + m_c xi_d'' / c) / i_t`, with
//! `omega_d = (xi_d' + m_c xi_d''' / c) / i_t`. The acceleration of the
//! compensation, `m_c xi_d'''' / (c i_t)`, is dropped: a jerk-limited trajectory
//! has a piecewise-constant jerk, whose derivative is a train of impulses.
//!
//! The belt's stiffness depends on where the cart is (2.26): with the
//! compliance `K(xi) = 1 / c(xi)` and a constant force `F_s` the belt carries
//! at rest (gravity along a tilted axis), the cart
//! `m_c xi'' = (i_t phi_m - xi) / K(xi) - F_s` follows `xi_d` exactly for
//! `phi_d = (xi_d + K(xi_d) (m_c xi_d'' + F_s)) / i_t` and
//! `omega_d = (xi_d' + K m_c xi_d''' + K' xi_d' (m_c xi_d'' + F_s)) / i_t`
//! ([`BeltProfile`]). For (2.26) the compliance is exactly quadratic in
//! `xi`: `K = (l_1 + l_e)(l_2 + l_3 + 2 l_e) / (c_b (l_1 + l_2 + l_3 + 3 l_e))`
//! with `l_1 + l_2` constant, so three coefficients hold it over the stroke
//! (on a soft belt the stiffness along a 0.5 m move changed by a
//! factor two, and the constant one left the cart up to 0.6 mm off).
//!
//! The belt also carries the cart's own friction while it moves,
//! `d_c xi' + F_c sign(xi')` (2.30): the profile's `cart_viscous_n_s_per_m`
//! and `cart_coulomb_n` add it to the force the stretch is led by. The
//! Coulomb sign is ramped as `(v / v_c) |v / v_c|` below `v_c`: a linear
//! ramp retreated faster at the end of a move than the trajectory advanced,
//! so the motor setpoint reversed, the cascade's Coulomb feedforward flipped
//! and a stuck cart ended 0.25 mm off; the quadratic's rate vanishes with
//! the speed.

use crate::error::{finite, positive, Error};
use crate::Real;

/// One desired motion sample in motor coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct MotionSample<T = f64> {
    /// Desired motor angle `phi_d` in rad.
    pub angle_rad: T,
    /// Desired motor velocity `omega_d` in rad/s.
    pub velocity_rad_s: T,
    /// Desired motor acceleration `alpha_d` in rad/s^2.
    pub acceleration_rad_s2: T,
}

/// What the controller gets per sample: the current desired motion and the one
/// `n_T` samples ahead for the torque feedforward (dead-time preview).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Setpoint<T = f64> {
    /// The desired motion at this sample (position and velocity loops).
    pub now: MotionSample<T>,
    /// The desired motion `n_T` samples later (used by the feedforward when
    /// [`crate::control::CascadeConfig::feedforward_preview`] is on).
    pub ahead: MotionSample<T>,
}

impl<T: Real> Setpoint<T> {
    /// A setpoint without preview (`ahead = now`).
    pub fn at(now: MotionSample<T>) -> Self {
        Setpoint { now, ahead: now }
    }

    /// A setpoint with a preview sample for the feedforward.
    pub fn with_preview(now: MotionSample<T>, ahead: MotionSample<T>) -> Self {
        Setpoint { now, ahead }
    }

    /// Standstill at `angle_rad`.
    pub fn hold(angle_rad: T) -> Self {
        Self::at(MotionSample {
            angle_rad,
            velocity_rad_s: T::ZERO,
            acceleration_rad_s2: T::ZERO,
        })
    }
}

/// One sample of a cart trajectory (e.g. from the jerk-limited generator).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct CartSample<T = f64> {
    /// Cart position `xi_d` in m.
    pub position_m: T,
    /// Cart velocity in m/s.
    pub velocity_m_s: T,
    /// Cart acceleration in m/s^2.
    pub acceleration_m_s2: T,
    /// Cart jerk in m/s^3 (only used by the belt-stretch compensation).
    pub jerk_m_s3: T,
}

/// Belt-stretch compensation switch with the parameters it needs.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum BeltStretch<T = f64> {
    /// Rigid belt: `phi_d = xi_d / i_t` (the thesis).
    #[default]
    Off,
    /// Compensate the belt stretch of the two-mass model with one stiffness.
    On {
        /// Moving (cart) mass `m_c` in kg.
        m_c_kg: T,
        /// Belt stiffness `c` in N/m.
        c_n_per_m: T,
    },
    /// Compensate the belt stretch with the stiffness where the cart is and
    /// the static stretch under a constant force (see the module docs).
    Profile(BeltProfile<T>),
}

/// The belt's replacement compliance along the stroke, `K(xi) = 1 / c(xi)`,
/// as a quadratic about `reference_m` (exact for (2.26)), the moving mass
/// and the constant force the belt carries. Positions are those of the
/// converted [`CartSample`]s.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct BeltProfile<T = f64> {
    /// Moving (cart) mass `m_c` in kg.
    pub m_c_kg: T,
    /// Cart position the compliance is expanded about, m.
    pub reference_m: T,
    /// Compliance `K` at `reference_m`, m/N (`1 / c`).
    pub compliance_m_per_n: T,
    /// Slope `dK/dxi` at `reference_m`, 1/N.
    pub compliance_slope_per_n: T,
    /// Half the second derivative, `K''/2`, 1/(N m).
    pub compliance_curvature_per_n_m: T,
    /// Force the belt carries at rest, N: minus the constant force on the
    /// cart (gravity along a tilted axis: the holding torque over `i_t`).
    pub static_force_n: T,
    /// The cart's viscous friction `d_c`, N s/m: the belt carries
    /// `d_c xi'` more while the cart moves (0: not compensated).
    pub cart_viscous_n_s_per_m: T,
    /// The cart's Coulomb friction `F_c`, N: the belt carries
    /// `F_c sign(xi')` more while the cart moves (0: not compensated).
    pub cart_coulomb_n: T,
    /// Cart speed at which the Coulomb share reaches `F_c`, m/s: below it
    /// `sign(xi')` is the ramp `xi' / v_c`, so the lead grows while the
    /// move starts and falls back to the static stretch as it ends (must be
    /// positive where `cart_coulomb_n` is not 0).
    pub coulomb_velocity_m_s: T,
}

impl<T: Real> BeltProfile<T> {
    /// The compliance at cart position `xi_m`, m/N.
    #[inline]
    pub fn compliance_at(&self, xi_m: T) -> T {
        let x = xi_m - self.reference_m;
        self.compliance_m_per_n
            + x * (self.compliance_slope_per_n + x * self.compliance_curvature_per_n_m)
    }

    /// The force the belt carries for a cart sample beyond the static one
    /// and its time derivative, N and N/s: `m_c xi'' + d_c xi' + F_c s(xi')`
    /// with the ramped sign `s` (see [`Self::coulomb_velocity_m_s`]).
    #[inline]
    fn dynamic_force(&self, cart: &CartSample<T>) -> (T, T) {
        let (v, a) = (cart.velocity_m_s, cart.acceleration_m_s2);
        let mut force = self.m_c_kg * a + self.cart_viscous_n_s_per_m * v;
        let mut rate = self.m_c_kg * cart.jerk_m_s3 + self.cart_viscous_n_s_per_m * a;
        if self.cart_coulomb_n != T::ZERO {
            let vc = self.coulomb_velocity_m_s;
            if v >= vc {
                force += self.cart_coulomb_n;
            } else if v <= -vc {
                force -= self.cart_coulomb_n;
            } else {
                // s = (v / v_c) |v / v_c|: its rate vanishes with the speed,
                // so the lead's retreat at the end of a move never outruns
                // the trajectory (a linear ramp reversed the motor setpoint)
                let g = self.cart_coulomb_n / (vc * vc);
                let av = if v < T::ZERO { T::ZERO - v } else { v };
                force += g * v * av;
                rate += (g + g) * av * a;
            }
        }
        (force, rate)
    }
}

/// Cart trajectory sample -> motor setpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetpointConversion<T = f64> {
    /// `i_t = r / i_g` in m/rad.
    i_t_m_per_rad: T,
    inv_i_t: T,
    /// The belt model (compliance zero when belt-stretch compensation is off).
    belt: BeltProfile<T>,
}

impl<T: Real> SetpointConversion<T> {
    /// Conversion for transmission `i_t_m_per_rad` (> 0) and the chosen belt
    /// model. Errors for non-positive or non-finite parameters (a negative
    /// mass, a compliance that is not positive at the reference).
    pub fn new(i_t_m_per_rad: T, belt: BeltStretch<T>) -> Result<Self, Error> {
        let i_t = positive("i_t_m_per_rad", i_t_m_per_rad.to_f64())?;
        let mass = |m: T| {
            let m = m.to_f64();
            if m.is_finite() && m >= 0.0 {
                Ok(m)
            } else {
                Err(Error::InvalidParameter {
                    name: "m_c_kg",
                    reason: "must be finite and >= 0",
                })
            }
        };
        let profile = match belt {
            BeltStretch::Off => BeltProfile::default(),
            BeltStretch::On { m_c_kg, c_n_per_m } => BeltProfile {
                m_c_kg: T::from_f64(mass(m_c_kg)?),
                compliance_m_per_n: T::from_f64(1.0 / positive("c_n_per_m", c_n_per_m.to_f64())?),
                ..BeltProfile::default()
            },
            BeltStretch::Profile(p) => {
                mass(p.m_c_kg)?;
                positive("compliance_m_per_n", p.compliance_m_per_n.to_f64())?;
                finite("reference_m", p.reference_m.to_f64())?;
                finite("compliance_slope_per_n", p.compliance_slope_per_n.to_f64())?;
                finite(
                    "compliance_curvature_per_n_m",
                    p.compliance_curvature_per_n_m.to_f64(),
                )?;
                finite("static_force_n", p.static_force_n.to_f64())?;
                finite("cart_viscous_n_s_per_m", p.cart_viscous_n_s_per_m.to_f64())?;
                finite("cart_coulomb_n", p.cart_coulomb_n.to_f64())?;
                if p.cart_coulomb_n.to_f64() != 0.0 {
                    positive("coulomb_velocity_m_s", p.coulomb_velocity_m_s.to_f64())?;
                }
                p
            }
        };
        Ok(SetpointConversion {
            i_t_m_per_rad: T::from_f64(i_t),
            inv_i_t: T::from_f64(1.0 / i_t),
            belt: profile,
        })
    }

    /// `i_t` in m/rad.
    pub fn i_t_m_per_rad(&self) -> T {
        self.i_t_m_per_rad
    }

    /// The motor setpoint for a cart sample:
    /// `phi_d = (xi_d + K (F + F_s))/i_t`,
    /// `omega_d = (xi_d' + K F' + K' xi_d' (F + F_s))/i_t`,
    /// `alpha_d = xi_d''/i_t`, with the compliance `K(xi_d)` of the belt model
    /// (zero when off; constant `1/c` and `F_s = 0` for
    /// [`BeltStretch::On`]) and the force the moving cart needs
    /// `F = m_c xi_d'' + d_c xi_d' + F_c s(xi_d')` ([`BeltProfile`]). Cost: at
    /// most 19 multiplications, 14 additions and one division (the division
    /// only inside the Coulomb ramp).
    #[inline]
    pub fn motor_sample(&self, cart: &CartSample<T>) -> MotionSample<T> {
        let b = &self.belt;
        let x = cart.position_m - b.reference_m;
        let slope = b.compliance_slope_per_n + (x + x) * b.compliance_curvature_per_n_m;
        let k = b.compliance_m_per_n
            + x * (b.compliance_slope_per_n + x * b.compliance_curvature_per_n_m);
        let (force, rate) = b.dynamic_force(cart);
        let load = force + b.static_force_n;
        MotionSample {
            angle_rad: (cart.position_m + k * load) * self.inv_i_t,
            velocity_rad_s: (cart.velocity_m_s + k * rate + slope * cart.velocity_m_s * load)
                * self.inv_i_t,
            acceleration_rad_s2: cart.acceleration_m_s2 * self.inv_i_t,
        }
    }

    /// [`Self::motor_sample`] with the cart's Coulomb lead held in the
    /// direction `hold` (+1 or -1; 0: as [`Self::motor_sample`]): where the
    /// ramped sign `s(v)` of [`BeltProfile::coulomb_velocity_m_s`] falls
    /// short of `hold`, the angle gets the missing `K F_c (hold - s) / i_t`.
    /// The velocity and acceleration setpoints stay those of the ramp, so
    /// the velocity loop still sees the lead's retreat while the move
    /// slows (the form measured on the robustness study; a latched lead
    /// with a consistent velocity setpoint was not measured with the final
    /// creep as built). For the final approach of
    /// [`crate::trajectory::Approach`]: a cart dragged slowly
    /// lags its motor by the stretch of its kinetic friction, and the held
    /// lead stops it on the target. Cost: [`Self::motor_sample`] plus 6
    /// multiplications and a division.
    #[inline]
    pub fn motor_sample_held(&self, cart: &CartSample<T>, hold: T) -> MotionSample<T> {
        let mut m = self.motor_sample(cart);
        let b = &self.belt;
        if hold != T::ZERO && b.cart_coulomb_n != T::ZERO {
            let r = cart.velocity_m_s / b.coulomb_velocity_m_s;
            let s = if r > T::ONE {
                T::ONE
            } else if r < T::ZERO - T::ONE {
                T::ZERO - T::ONE
            } else if r < T::ZERO {
                T::ZERO - r * r
            } else {
                r * r
            };
            let missing = hold - s;
            if missing * hold > T::ZERO {
                let k = b.compliance_at(cart.position_m);
                m.angle_rad += k * b.cart_coulomb_n * missing * self.inv_i_t;
            }
        }
        m
    }

    /// The belt model the conversion uses (all zero when off).
    pub fn belt(&self) -> BeltProfile<T> {
        self.belt
    }

    /// Cart position seen from the motor with a rigid belt, `i_t phi_m`, in m.
    pub fn cart_position_m(&self, motor_angle_rad: T) -> T {
        self.i_t_m_per_rad * motor_angle_rad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest `|xi - xi_d|` of the cart `xi'' = accel(t, xi, xi')`
    /// integrated by RK4 at 1 us for `steps` steps from `xi_d(0)`, `xi_d'(0)`:
    /// the independent check of the flatness relations below.
    fn worst_cart_error_rk4(
        accel: &dyn Fn(f64, f64, f64) -> f64,
        cart: &dyn Fn(f64) -> CartSample<f64>,
        steps: usize,
    ) -> f64 {
        let c0 = cart(0.0);
        let (mut x, mut v) = (c0.position_m, c0.velocity_m_s);
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        let mut t = 0.0;
        for _ in 0..steps {
            let k1x = v;
            let k1v = accel(t, x, v);
            let k2x = v + 0.5 * h * k1v;
            let k2v = accel(t + 0.5 * h, x + 0.5 * h * k1x, k2x);
            let k3x = v + 0.5 * h * k2v;
            let k3v = accel(t + 0.5 * h, x + 0.5 * h * k2x, k3x);
            let k4x = v + h * k3v;
            let k4v = accel(t + h, x + h * k3x, k4x);
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            t += h;
            worst = worst.max((x - cart(t).position_m).abs());
        }
        worst
    }

    /// Accepted error of the RK4 integration of an exactly compensated cart, m.
    const RK4_TOL_M: f64 = 1e-9;

    /// A soft belt whose compliance changes with the cart's position
    /// (quadratic, 3.8 to 9.8 um/N between 0 and 0.5 m, like a soft egc70
    /// belt) and that carries a static force (gravity on a 30 deg slope).
    const SOFT_BELT: BeltProfile<f64> = BeltProfile {
        m_c_kg: M_C,
        reference_m: 0.5,
        compliance_m_per_n: 9.86e-6,
        compliance_slope_per_n: 1.0e-5,
        compliance_curvature_per_n_m: -5.0e-6,
        static_force_n: M_C * 9.81 * 0.5,
        cart_viscous_n_s_per_m: 0.0,
        cart_coulomb_n: 0.0,
        coulomb_velocity_m_s: 0.0,
    };

    /// `xi_d` from 0.01 to 0.49 m and back, `A (1 - cos w t)`, with its
    /// analytic derivatives.
    fn sweep(t: f64) -> CartSample<f64> {
        let (x0, amp, w) = (0.01, 0.24, 2.0 * core::f64::consts::PI * 1.5);
        CartSample {
            position_m: x0 + amp * (1.0 - libm::cos(w * t)),
            velocity_m_s: amp * w * libm::sin(w * t),
            acceleration_m_s2: amp * w * w * libm::cos(w * t),
            jerk_m_s3: -amp * w * w * w * libm::sin(w * t),
        }
    }

    /// The converted velocity of [`sweep`] is the derivative of the converted
    /// angle (central difference with step `d` s) at `times`, within
    /// `rel_tol` of the velocity (of 1 rad/s below it).
    fn assert_velocity_is_angle_derivative(
        conv: &SetpointConversion<f64>,
        times: &[f64],
        d: f64,
        rel_tol: f64,
    ) {
        for &t in times {
            let fd = (conv.motor_sample(&sweep(t + d)).angle_rad
                - conv.motor_sample(&sweep(t - d)).angle_rad)
                / (2.0 * d);
            let w_d = conv.motor_sample(&sweep(t)).velocity_rad_s;
            assert!(
                (fd - w_d).abs() < rel_tol * w_d.abs().max(1.0),
                "{t}: {fd} vs {w_d}"
            );
        }
    }

    /// Table A.4: m_c = 13.44 kg, c = 203.74 kN/m, i_t = 12.414 mm/rad.
    const M_C: f64 = 13.44;
    const C: f64 = 203.74e3;
    const I_T: f64 = 12.414e-3;

    #[test]
    fn rigid_conversion_divides_by_i_t() {
        let conv = SetpointConversion::new(I_T, BeltStretch::Off).unwrap();
        let s = conv.motor_sample(&CartSample {
            position_m: 0.5,
            velocity_m_s: 1.0,
            acceleration_m_s2: 10.0,
            jerk_m_s3: 40.0,
        });
        assert!((s.angle_rad - 0.5 / I_T).abs() < 1e-12);
        assert!((s.velocity_rad_s - 1.0 / I_T).abs() < 1e-12);
        assert!((s.acceleration_rad_s2 - 10.0 / I_T).abs() < 1e-9);
        assert!((conv.cart_position_m(s.angle_rad) - 0.5).abs() < 1e-15);
    }

    /// Independent check of the flatness relation: drive the undamped cart
    /// `m_c xi'' = c (i_t phi - xi)` with the compensated motor angle of a smooth
    /// (C^3) cart trajectory and integrate by RK4 at 1 us. The cart must follow
    /// `xi_d`; without compensation it lags by `m_c xi_d'' / c` (about 0.66 mm at
    /// 10 m/s^2 here) and rings.
    #[test]
    fn belt_stretch_compensation_makes_the_two_mass_cart_follow() {
        // xi_d(t) = A (1 - cos(w t)) for t in [0, T]: smooth, all derivatives analytic.
        let (amp, w) = (0.05, 2.0 * core::f64::consts::PI * 3.0);
        let cart = |t: f64| CartSample {
            position_m: amp * (1.0 - libm::cos(w * t)),
            velocity_m_s: amp * w * libm::sin(w * t),
            acceleration_m_s2: amp * w * w * libm::cos(w * t),
            jerk_m_s3: -amp * w * w * w * libm::sin(w * t),
        };
        let run = |belt: BeltStretch<f64>| -> f64 {
            let conv = SetpointConversion::new(I_T, belt).unwrap();
            let phi = |t: f64| conv.motor_sample(&cart(t)).angle_rad;
            // initial state consistent with the trajectory at t = 0
            let f = |t: f64, x: f64, _v: f64| C / M_C * (I_T * phi(t) - x);
            worst_cart_error_rk4(&f, &cart, 300_000)
        };
        let compensated = run(BeltStretch::On {
            m_c_kg: M_C,
            c_n_per_m: C,
        });
        let rigid = run(BeltStretch::Off);
        // static lag at the peak acceleration amp w^2 = 17.8 m/s^2: m_c a / c = 1.2 mm
        let lag = M_C * amp * w * w / C;
        assert!(rigid > 0.5 * lag, "rigid error {rigid} vs lag {lag}");
        // RK4 at h = 1 us on a 107 Hz mode: local error ~ (w_r h)^5, far below 1e-9 m.
        const RK4_TOL_M: f64 = 1e-9;
        assert!(compensated < RK4_TOL_M, "compensated error {compensated}");
    }

    /// The belt profile: a cart on a belt whose compliance changes
    /// with the cart's position (quadratic, 3.8 to 9.8 um/N over the move,
    /// like a soft egc70 belt between 0 and 0.5 m) and that carries a static
    /// force (gravity on a 30 deg slope), driven by the converted motor
    /// angle, follows `xi_d` exactly (RK4 at 1 us); the constant stiffness of
    /// the move's end leaves it more than 0.3 mm off. The converted velocity
    /// is the derivative of the converted angle (central difference).
    #[test]
    fn a_belt_profile_makes_the_cart_follow_where_the_stiffness_changes() {
        let profile = SOFT_BELT;
        let run = |belt: BeltStretch<f64>| -> f64 {
            let conv = SetpointConversion::new(I_T, belt).unwrap();
            let p = |t: f64| I_T * conv.motor_sample(&sweep(t)).angle_rad;
            // the true belt: the profile's compliance, its static force
            let f = |t: f64, x: f64| {
                ((p(t) - x) / profile.compliance_at(x) - profile.static_force_n) / M_C
            };
            worst_cart_error_rk4(&|t, x, _v| f(t, x), &sweep, 600_000)
        };
        // The cart starts where the profile's conversion puts it at rest; a
        // constant stiffness starts it with a wrong stretch too: both are
        // errors of the constant model.
        let exact = run(BeltStretch::Profile(profile));
        assert!(exact < RK4_TOL_M, "profile error {exact}");
        let end = BeltStretch::On {
            m_c_kg: M_C,
            c_n_per_m: 1.0 / profile.compliance_at(0.49),
        };
        let constant = run(end);
        assert!(constant > 3e-4, "constant-stiffness error {constant}");

        let conv = SetpointConversion::new(I_T, BeltStretch::Profile(profile)).unwrap();
        assert_velocity_is_angle_derivative(&conv, &[0.05, 0.2, 0.31], 1e-6, 1e-6);
    }

    /// The belt also carries the cart's friction while it moves
    /// (soft belts with a sticky cart: up to 0.3 mm of stretch). A cart
    /// with viscous friction and the ramped Coulomb sign of the profile,
    /// on the belt of the test above, follows `xi_d` exactly from rest
    /// (RK4 at 1 us); the profile without the friction leaves it lagging by
    /// about `(d_c v + F_c) / c`. The converted velocity is the derivative of
    /// the converted angle, inside the ramp too.
    #[test]
    fn the_cart_friction_lead_makes_the_rubbing_cart_follow() {
        let profile = BeltProfile {
            cart_viscous_n_s_per_m: 30.0,
            cart_coulomb_n: 15.0,
            coulomb_velocity_m_s: 0.05,
            ..SOFT_BELT
        };
        // the ramped Coulomb sign of the profile
        let sign = |v: f64| {
            let r = v / profile.coulomb_velocity_m_s;
            if r.abs() >= 1.0 {
                r.signum()
            } else {
                r * r.abs()
            }
        };
        let run = |belt: BeltProfile<f64>| -> f64 {
            let conv = SetpointConversion::new(I_T, BeltStretch::Profile(belt)).unwrap();
            let p = |t: f64| I_T * conv.motor_sample(&sweep(t)).angle_rad;
            let f = |t: f64, x: f64, v: f64| {
                ((p(t) - x) / profile.compliance_at(x)
                    - profile.static_force_n
                    - profile.cart_viscous_n_s_per_m * v
                    - profile.cart_coulomb_n * sign(v))
                    / M_C
            };
            worst_cart_error_rk4(&f, &sweep, 300_000)
        };
        let exact = run(profile);
        assert!(exact < RK4_TOL_M, "with the friction lead: {exact}");
        let without = run(BeltProfile {
            cart_viscous_n_s_per_m: 0.0,
            cart_coulomb_n: 0.0,
            ..profile
        });
        // (30 N s/m * 2.26 m/s + 15 N) * 3.8 um/N at least: 0.3 mm
        assert!(without > 3e-4, "without: {without}");

        let conv = SetpointConversion::new(I_T, BeltStretch::Profile(profile)).unwrap();
        // t = 0.002 s: v = 0.0107 m/s, inside the Coulomb ramp
        assert_velocity_is_angle_derivative(&conv, &[0.002, 0.01, 0.2, 0.31], 1e-7, 1e-5);
    }

    /// The held Coulomb lead of the final approach: at rest (and
    /// below the ramp's speed) the angle leads by the whole stretch of the
    /// cart's kinetic friction in the held direction, so that a cart
    /// dragged there from behind (belt force `F_s + F_c` at the edge of its
    /// friction band: static equilibrium `xi = i_t phi - K (F_s + F_c)`)
    /// rests on `xi_d`; beyond the ramp's speed, without a hold and against
    /// it the conversion is unchanged; the velocity setpoint is never
    /// changed.
    #[test]
    fn the_held_lead_rests_a_dragged_cart_on_its_target() {
        let profile = BeltProfile {
            cart_coulomb_n: 15.0,
            coulomb_velocity_m_s: 0.02,
            ..SOFT_BELT
        };
        let conv = SetpointConversion::new(I_T, BeltStretch::Profile(profile)).unwrap();
        let at = |x: f64, v: f64| CartSample {
            position_m: x,
            velocity_m_s: v,
            ..CartSample::default()
        };
        for (x, hold) in [(0.1, 1.0), (0.45, 1.0), (0.3, -1.0)] {
            let held = conv.motor_sample_held(&at(x, 0.0), hold);
            let k = profile.compliance_at(x);
            let force = profile.static_force_n + hold * profile.cart_coulomb_n;
            let cart = I_T * held.angle_rad - k * force;
            assert!((cart - x).abs() < 1e-12, "{x} {hold}: cart at {cart}");
            let plain = conv.motor_sample(&at(x, 0.0));
            assert_eq!(held.velocity_rad_s, plain.velocity_rad_s);
            assert_eq!(conv.motor_sample_held(&at(x, 0.0), 0.0), plain);
            // slower than the ramp in the held direction: topped up to full
            let slow = conv.motor_sample_held(&at(x, hold * 0.01), hold);
            let full = conv.motor_sample_held(&at(x, hold * 0.05), hold);
            let lead = |m: MotionSample<f64>| I_T * m.angle_rad - x;
            assert!((lead(slow) - lead(held)).abs() < 1e-12);
            assert_eq!(full, conv.motor_sample(&at(x, hold * 0.05)));
        }
    }

    #[test]
    fn invalid_conversion_parameters_are_errors() {
        assert!(SetpointConversion::new(0.0, BeltStretch::Off).is_err());
        assert!(SetpointConversion::new(
            I_T,
            BeltStretch::On {
                m_c_kg: M_C,
                c_n_per_m: 0.0
            }
        )
        .is_err());
        assert!(SetpointConversion::new(
            I_T,
            BeltStretch::On {
                m_c_kg: f64::NAN,
                c_n_per_m: C
            }
        )
        .is_err());
        let ok = BeltProfile {
            m_c_kg: M_C,
            reference_m: 0.5,
            compliance_m_per_n: 1.0 / C,
            compliance_slope_per_n: 1e-5,
            compliance_curvature_per_n_m: -5e-6,
            static_force_n: 10.0,
            cart_viscous_n_s_per_m: 8.0,
            cart_coulomb_n: 13.0,
            coulomb_velocity_m_s: 0.05,
        };
        assert!(SetpointConversion::new(I_T, BeltStretch::Profile(ok)).is_ok());
        for bad in [
            BeltProfile {
                compliance_m_per_n: 0.0,
                ..ok
            },
            BeltProfile {
                compliance_slope_per_n: f64::INFINITY,
                ..ok
            },
            BeltProfile {
                static_force_n: f64::NAN,
                ..ok
            },
            BeltProfile { m_c_kg: -1.0, ..ok },
            BeltProfile {
                cart_coulomb_n: f64::NAN,
                ..ok
            },
            BeltProfile {
                cart_viscous_n_s_per_m: f64::INFINITY,
                ..ok
            },
            BeltProfile {
                coulomb_velocity_m_s: 0.0,
                ..ok
            },
        ] {
            assert!(SetpointConversion::new(I_T, BeltStretch::Profile(bad)).is_err());
        }
    }
}
