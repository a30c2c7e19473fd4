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

use crate::error::{positive, Error};
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
    /// Compensate the static belt stretch of the two-mass model.
    On {
        /// Moving (cart) mass `m_c` in kg.
        m_c_kg: T,
        /// Belt stiffness `c` in N/m.
        c_n_per_m: T,
    },
}

/// Cart trajectory sample -> motor setpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetpointConversion<T = f64> {
    /// `i_t = r / i_g` in m/rad.
    i_t_m_per_rad: T,
    inv_i_t: T,
    /// `m_c / c` in s^2 (0 when belt-stretch compensation is off).
    stretch_s2: T,
}

impl<T: Real> SetpointConversion<T> {
    /// Conversion for transmission `i_t_m_per_rad` (> 0) and the chosen belt
    /// model. Errors for non-positive or non-finite parameters.
    pub fn new(i_t_m_per_rad: T, belt: BeltStretch<T>) -> Result<Self, Error> {
        let i_t = positive("i_t_m_per_rad", i_t_m_per_rad.to_f64())?;
        let stretch = match belt {
            BeltStretch::Off => 0.0,
            BeltStretch::On { m_c_kg, c_n_per_m } => {
                let m = m_c_kg.to_f64();
                if !(m.is_finite() && m >= 0.0) {
                    return Err(Error::InvalidParameter {
                        name: "m_c_kg",
                        reason: "must be finite and >= 0",
                    });
                }
                m / positive("c_n_per_m", c_n_per_m.to_f64())?
            }
        };
        Ok(SetpointConversion {
            i_t_m_per_rad: T::from_f64(i_t),
            inv_i_t: T::from_f64(1.0 / i_t),
            stretch_s2: T::from_f64(stretch),
        })
    }

    /// `i_t` in m/rad.
    pub fn i_t_m_per_rad(&self) -> T {
        self.i_t_m_per_rad
    }

    /// The motor setpoint for a cart sample: `phi_d = (xi_d + m_c xi_d''/c)/i_t`,
    /// `omega_d = (xi_d' + m_c xi_d'''/c)/i_t`, `alpha_d = xi_d''/i_t`
    /// (compensation terms zero when off). Cost: 5 multiplications, 2 additions.
    #[inline]
    pub fn motor_sample(&self, cart: &CartSample<T>) -> MotionSample<T> {
        MotionSample {
            angle_rad: (cart.position_m + self.stretch_s2 * cart.acceleration_m_s2) * self.inv_i_t,
            velocity_rad_s: (cart.velocity_m_s + self.stretch_s2 * cart.jerk_m_s3) * self.inv_i_t,
            acceleration_rad_s2: cart.acceleration_m_s2 * self.inv_i_t,
        }
    }

    /// Cart position seen from the motor with a rigid belt, `i_t phi_m`, in m.
    pub fn cart_position_m(&self, motor_angle_rad: T) -> T {
        self.i_t_m_per_rad * motor_angle_rad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let c0 = cart(0.0);
            let (mut x, mut v) = (c0.position_m, c0.velocity_m_s);
            let f = |t: f64, x: f64| C / M_C * (I_T * phi(t) - x);
            let h = 1e-6;
            let mut worst: f64 = 0.0;
            let mut t = 0.0;
            for _ in 0..300_000 {
                let k1x = v;
                let k1v = f(t, x);
                let k2x = v + 0.5 * h * k1v;
                let k2v = f(t + 0.5 * h, x + 0.5 * h * k1x);
                let k3x = v + 0.5 * h * k2v;
                let k3v = f(t + 0.5 * h, x + 0.5 * h * k2x);
                let k4x = v + h * k3v;
                let k4v = f(t + h, x + h * k3x);
                x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
                v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
                t += h;
                worst = worst.max((x - cart(t).position_m).abs());
            }
            worst
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
    }
}
