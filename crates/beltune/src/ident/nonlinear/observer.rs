//! The cart observer: the cart's equation of motion (2.25b) with its
//! Coulomb friction (2.23), driven by the measured motor angle, gives the
//! belt torque the motor felt; the motor's equation (2.25a) is what is left
//! over (the equation error).
//!
//! With `p = i_t phi_m` the motor-side belt end (m) the cart obeys
//!
//! ```text
//! m_c xi'' = c (p - xi) + d (p' - xi') - d_c xi' - F_c sign(xi') + F_g
//! ```
//!
//! and the motor
//!
//! ```text
//! Theta_e phi_m'' = tau(t - T_t) - i_t^2 d_m phi_m' - tau_c sign(phi_m') - tau_b,
//! tau_b = i_t (c (p - xi) + d (p' - xi')).
//! ```
//!
//! The cart is tied to the measured motor by the belt, so its simulated
//! motion does not drift away from the axis' the way a simulation driven by
//! the torque alone does (an integrator with stick-slip: the smallest
//! parameter change moves every later stick event); that makes the error
//! of the motor equation a smooth, well-conditioned function of the cart's
//! parameters.
//!
//! Between stick-slip events the cart is linear and the belt end moves
//! linearly over a sample, so each sample's smooth step is exact: the
//! transition and the input gains of `[xi, xi']` come from one matrix
//! exponential per call (the record's parameters are fixed), 8
//! multiplications per sample. (An RK4 step, as in [`crate::sim`], cost
//! four evaluations of the acceleration, about 40 flops, and the friction-
//! aware fit spent three quarters of a commissioning's CPU time in it.)
//!
//! Stick-slip: the velocity-level (Moreau) step of [`crate::sim`] (the same
//! function, `coulomb_step`): after the
//! smooth step the friction impulse over the step is at most `h F_c`; a
//! cart whose free velocity it can cancel sticks.
//!
//! Cost: about 20 flops and one branch per sample.

use crate::sim::coulomb_step;

/// Parameters of the cart and belt (SI): the nonlinear part of the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CartParams {
    /// Cart mass `m_c`, kg.
    pub m_c: f64,
    /// Replacement belt stiffness `c` (2.26), N/m.
    pub c: f64,
    /// Belt damping `d` (2.27), N s/m.
    pub d: f64,
    /// Cart viscous friction `d_c`, N s/m.
    pub d_c: f64,
    /// Cart Coulomb friction `F_c` (2.23), N.
    pub f_c: f64,
}

/// The belt torque `tau_b` (N m) at every sample of the motor angle
/// `angle_rad` (sampled every `ts_s`), for a cart of `cart` with the
/// constant force `cart_force_n` (gravity along the axis, N) and the
/// transmission `i_t` (m/rad). The cart starts at rest where the belt holds
/// the constant force (`xi = p - F_g / c`); the first sample's torque is
/// that static one.
pub fn belt_torque(
    angle_rad: &[f64],
    ts_s: f64,
    i_t: f64,
    cart_force_n: f64,
    cart: &CartParams,
) -> Vec<f64> {
    let n = angle_rad.len();
    let mut out = vec![0.0; n];
    if n == 0 {
        return out;
    }
    let inv_m = 1.0 / cart.m_c;
    let (c, d, f_g) = (cart.c, cart.d, cart_force_n);
    let mut xi = i_t * angle_rad[0] + f_g / c;
    let mut v = 0.0f64;
    out[0] = i_t * c * (i_t * angle_rad[0] - xi);
    let dv_max = ts_s * cart.f_c * inv_m;
    let h = ts_s;
    let step = ExactStep::new(cart, f_g, h);
    for k in 1..n {
        let p0 = i_t * angle_rad[k - 1];
        let p1 = i_t * angle_rad[k];
        // the belt end moves linearly over the sample
        let pd = (p1 - p0) / h;
        let (x_f, v_f) = step.advance(xi, v, p0, pd);
        (xi, v) = coulomb_step(xi, v, x_f, v_f, dv_max, h);
        out[k] = i_t * (c * (p1 - xi) + d * (pd - v));
    }
    out
}

/// The exact step of the smooth cart over one sample `h`:
/// `m_c xi'' = c (p - xi) + d (p' - xi') - d_c xi' + F_g` with the belt end
/// `p(t) = p_0 + p' t` linear over the step. With `s = [xi, xi']`,
/// `s' = A s + e_2 (u_0 + u_1 t)`, `u_0 = (c p_0 + d p' + F_g) / m_c`,
/// `u_1 = c p' / m_c`, the exponential of the augmented matrix
/// `[[A, e_2, 0], [0, 0, 1], [0, 0, 0]] h` holds the transition `e^{A h}` and
/// the gains of `u_0` and `u_1`.
struct ExactStep {
    /// `e^{A h}`, row major.
    phi: [[f64; 2]; 2],
    /// Gains of `p_0`, `p'` and the constant, per state (`xi`, `xi'`).
    gain_p: [f64; 2],
    gain_pd: [f64; 2],
    constant: [f64; 2],
}

impl ExactStep {
    fn new(cart: &CartParams, f_g: f64, h: f64) -> Self {
        let inv_m = 1.0 / cart.m_c;
        let mut m = nalgebra::Matrix4::<f64>::zeros();
        m[(0, 1)] = h;
        m[(1, 0)] = -cart.c * inv_m * h;
        m[(1, 1)] = -(cart.d + cart.d_c) * inv_m * h;
        m[(1, 2)] = h;
        m[(2, 3)] = h;
        let e = m.exp();
        // column 2: the gain of u_0; column 3: of u_1
        let g0 = [e[(0, 2)], e[(1, 2)]];
        let g1 = [e[(0, 3)], e[(1, 3)]];
        let (c, d) = (cart.c * inv_m, cart.d * inv_m);
        ExactStep {
            phi: [[e[(0, 0)], e[(0, 1)]], [e[(1, 0)], e[(1, 1)]]],
            gain_p: [g0[0] * c, g0[1] * c],
            gain_pd: [g0[0] * d + g1[0] * c, g0[1] * d + g1[1] * c],
            constant: [g0[0] * f_g * inv_m, g0[1] * f_g * inv_m],
        }
    }

    /// `[xi, xi']` after one step from `(x, v)` with the belt end at `p0`
    /// moving at `pd`.
    #[inline]
    fn advance(&self, x: f64, v: f64, p0: f64, pd: f64) -> (f64, f64) {
        let f = &self.phi;
        (
            f[0][0] * x
                + f[0][1] * v
                + self.gain_p[0] * p0
                + self.gain_pd[0] * pd
                + self.constant[0],
            f[1][0] * x
                + f[1][1] * v
                + self.gain_p[1] * p0
                + self.gain_pd[1] * pd
                + self.constant[1],
        )
    }
}

/// The motor-side signals of the equation error, each a time series over
/// the record: what the parameters fixed in advance leave to explain, and
/// the regressors of the parameters solved linearly.
#[derive(Clone, Debug, PartialEq)]
pub struct MotorSignals {
    /// `tau(t - T_t) - Theta_e phi''` with the data-sheet `Theta_e` (0 when
    /// `Theta_e` is solved), N m.
    pub known_nm: Vec<f64>,
    /// `phi''` (central second difference), rad/s^2: the regressor of `Theta_e`.
    pub acceleration: Vec<f64>,
    /// `i_t^2 phi'` (central difference), m^2/s: the regressor of `d_m`.
    pub viscous: Vec<f64>,
    /// `sign(phi')` over [`SIGN_WINDOW_S`]: the regressor of `tau_c`.
    pub coulomb: Vec<f64>,
}

/// Window of the motor velocity whose sign the Coulomb regressor takes, s: a
/// quantized encoder moves by single counts at low speed, so the sample-wise
/// difference flickers between 0 and a spike; over 1 ms the direction is
/// clear.
pub const SIGN_WINDOW_S: f64 = 1e-3;

/// The motor signals of a record: torque command `torque` (N m, what the
/// drive was told), motor angle `angle_rad`, both sampled every `ts_s`; the
/// command reaches the motor `dead_samples` later. `theta_e`: the data-sheet
/// motor inertia (kg m^2), or `None` when it is solved too.
pub fn motor_signals(
    torque: &[f64],
    angle_rad: &[f64],
    ts_s: f64,
    i_t: f64,
    dead_samples: usize,
    theta_e: Option<f64>,
) -> MotorSignals {
    let n = angle_rad.len().min(torque.len());
    let at = |k: isize| angle_rad[k.clamp(0, n as isize - 1) as usize];
    let half = ((0.5 * SIGN_WINDOW_S / ts_s).round() as isize).max(1);
    let mut s = MotorSignals {
        known_nm: Vec::with_capacity(n),
        acceleration: Vec::with_capacity(n),
        viscous: Vec::with_capacity(n),
        coulomb: Vec::with_capacity(n),
    };
    for k in 0..n {
        let ki = k as isize;
        let a = (at(ki + 1) - 2.0 * at(ki) + at(ki - 1)) / (ts_s * ts_s);
        let w = (at(ki + 1) - at(ki - 1)) / (2.0 * ts_s);
        let dir = at(ki + half) - at(ki - half);
        let u = torque[k.saturating_sub(dead_samples)];
        s.known_nm.push(u - theta_e.unwrap_or(0.0) * a);
        s.acceleration.push(a);
        s.viscous.push(i_t * i_t * w);
        s.coulomb.push(if dir > 0.0 {
            1.0
        } else if dir < 0.0 {
            -1.0
        } else {
            0.0
        });
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stiff belt makes the belt torque the cart's inertia and friction:
    /// a constant acceleration `a` of the motor side gives
    /// `i_t (m_c a + d_c v + F_c)` once the cart slides (closed form).
    ///
    /// Tolerance 0.2 %: the belt mode (160 Hz, 2 % damped) has rung down to
    /// e^-9 by the compared sample; the friction step's velocity kick seen
    /// by the belt damping, `d h F_c / m_c` = 0.02 N, is 0.1 % of the force.
    #[test]
    fn a_stiff_belt_transmits_inertia_and_friction() {
        let (ts, i_t) = (1e-4, 0.0124);
        let cart = CartParams {
            m_c: 10.0,
            c: 1e7,
            d: 400.0,
            d_c: 20.0,
            f_c: 5.0,
        };
        let alpha = 50.0; // rad/s^2
        let angle: Vec<f64> = (0..5000)
            .map(|k| 0.5 * alpha * (k as f64 * ts).powi(2))
            .collect();
        let tb = belt_torque(&angle, ts, i_t, 0.0, &cart);
        let k = 4900;
        let v = i_t * alpha * k as f64 * ts;
        let expected = i_t * (cart.m_c * i_t * alpha + cart.d_c * v + cart.f_c);
        // the stiff belt's mode (about 1.6 kHz) rings down within 0.4 s
        assert!(
            (tb[k] / expected - 1.0).abs() < 2e-3,
            "{} vs {expected}",
            tb[k]
        );
    }

    /// The belt torque of the record with each sample's smooth step
    /// integrated by RK4 in `sub` substeps (the belt end linear over the
    /// sample, the same Moreau friction step after it): the independent
    /// reference of the exact step.
    fn belt_torque_rk4(
        angle: &[f64],
        ts: f64,
        i_t: f64,
        f_g: f64,
        cart: &CartParams,
        sub: usize,
    ) -> Vec<f64> {
        let (c, d, d_c, m) = (cart.c, cart.d, cart.d_c, cart.m_c);
        let mut xi = i_t * angle[0] + f_g / c;
        let mut v = 0.0f64;
        let mut out = vec![i_t * c * (i_t * angle[0] - xi)];
        let dv_max = ts * cart.f_c / m;
        let h = ts / sub as f64;
        for k in 1..angle.len() {
            let p0 = i_t * angle[k - 1];
            let pd = (i_t * angle[k] - p0) / ts;
            let acc = |x: f64, vv: f64, t: f64| {
                (c * (p0 + pd * t - x) + d * (pd - vv) - d_c * vv + f_g) / m
            };
            let (x0, v0) = (xi, v);
            for j in 0..sub {
                let t = j as f64 * h;
                let a1 = acc(xi, v, t);
                let a2 = acc(xi + 0.5 * h * v, v + 0.5 * h * a1, t + 0.5 * h);
                let a3 = acc(
                    xi + 0.5 * h * (v + 0.5 * h * a1),
                    v + 0.5 * h * a2,
                    t + 0.5 * h,
                );
                let a4 = acc(xi + h * (v + 0.5 * h * a2), v + h * a3, t + h);
                xi += h / 6.0
                    * (v + 2.0 * (v + 0.5 * h * a1) + 2.0 * (v + 0.5 * h * a2) + (v + h * a3));
                v += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
            }
            (xi, v) = coulomb_step(x0, v0, xi, v, dv_max, ts);
            out.push(i_t * (c * (i_t * angle[k] - xi) + d * (pd - v)));
        }
        out
    }

    /// The exact step against RK4 with 50 substeps per sample on a
    /// stick-slip record (a 35 Hz belt on a tilted axis, a motor that
    /// reverses): the same torques to 1e-9 of their range. RK4's error at
    /// 2 us on a 35 Hz mode, `(w h)^5 / 120` per step, is below 1e-13.
    #[test]
    fn the_exact_step_matches_a_fine_rk4() {
        let (ts, i_t) = (1e-4, 0.0124);
        let cart = CartParams {
            m_c: 12.0,
            c: 6e5,
            d: 60.0,
            d_c: 15.0,
            f_c: 20.0,
        };
        let f_g = -40.0;
        let angle: Vec<f64> = (0..20_000)
            .map(|k| {
                let t = k as f64 * ts;
                (0.02 * (2.0 * std::f64::consts::PI * 1.3 * t).sin()
                    + 0.001 * (2.0 * std::f64::consts::PI * 23.0 * t).sin())
                    / i_t
            })
            .collect();
        let exact = belt_torque(&angle, ts, i_t, f_g, &cart);
        let reference = belt_torque_rk4(&angle, ts, i_t, f_g, &cart, 50);
        let range = reference.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let worst = exact
            .iter()
            .zip(&reference)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(range > 0.1, "{range}");
        assert!(worst < 1e-9 * range, "{worst} of {range}");
        // the friction step is exercised: without it the torques differ
        let frictionless = belt_torque(&angle, ts, i_t, f_g, &CartParams { f_c: 0.0, ..cart });
        let friction = exact
            .iter()
            .zip(&frictionless)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(friction > 1e-2 * range, "{friction} of {range}");
    }

    /// A cart held by friction stays put: a motor-side stretch below
    /// `F_c / c` gives the spring torque `i_t c p` and no cart motion.
    #[test]
    fn a_small_stretch_does_not_break_the_cart_loose() {
        let (ts, i_t) = (1e-4, 0.0124);
        let cart = CartParams {
            m_c: 10.0,
            c: 2e5,
            d: 0.0,
            d_c: 0.0,
            f_c: 10.0,
        };
        // 40 um at the belt end: 8 N < 10 N
        let p_end = 40e-6;
        let angle: Vec<f64> = (0..2000)
            .map(|k| (k as f64 / 1000.0).min(1.0) * p_end / i_t)
            .collect();
        let tb = belt_torque(&angle, ts, i_t, 0.0, &cart);
        assert!(
            (tb[1999] - i_t * cart.c * p_end).abs() < 1e-9,
            "{}",
            tb[1999]
        );
    }

    /// The regressors: a constant motor acceleration gives that
    /// acceleration, the velocity and its sign; the command is delayed.
    #[test]
    fn motor_signals_are_the_motor_equation_terms() {
        let ts = 1e-4;
        let alpha = 20.0;
        let angle: Vec<f64> = (0..100)
            .map(|k| 0.5 * alpha * (k as f64 * ts).powi(2))
            .collect();
        let torque: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let s = motor_signals(&torque, &angle, ts, 0.01, 3, Some(2e-3));
        assert!((s.acceleration[50] - alpha).abs() < 1e-6);
        assert!((s.viscous[50] - 1e-4 * alpha * 50.0 * ts).abs() < 1e-12);
        assert_eq!(s.coulomb[50], 1.0);
        assert!((s.known_nm[50] - (47.0 - 2e-3 * alpha)).abs() < 1e-9);
    }
}
