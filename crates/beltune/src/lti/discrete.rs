//! Discrete-time single-input single-output state-space models at the sampling
//! time `T_s`: Tustin sections of the real-time crate, the zero-order-hold (ZOH)
//! discretization of a continuous plant with a dead time that need not be a
//! multiple of `T_s`, series and feedback connections, closed-loop poles
//! (eigenvalues of the closed-loop state matrix, nalgebra's Schur decomposition)
//! and frequency responses at `z = e^{j w T_s}`.
//!
//! A state-space realization is used instead of polynomials in `z` because the
//! loop has clustered poles near `z = 1` (integrators, slow mechanics) whose
//! polynomial roots would be ill-conditioned.

use super::{Tf, C64};
use crate::error::{require_non_negative, require_positive};
use crate::{Error, Result};
use beltune_rt::filter::{FirstOrderCoeffs, SosCoeffs};
use nalgebra::{DMatrix, DVector, RowDVector};

/// Longest dead time [`StateSpace::zoh`] discretizes, in sample periods. Each
/// period is one state, and the loops' eigenvalue checks grow with the cube of
/// the state count; 256 periods (25.6 ms at 10 kHz) is far beyond any drive.
pub const MAX_DELAY_SAMPLES: usize = 256;

/// Typed error unless the dead time `dead_time_s` is at most
/// [`MAX_DELAY_SAMPLES`] sample periods of `ts_s`.
pub fn check_delay_samples(ts_s: f64, dead_time_s: f64) -> Result<()> {
    if dead_time_s / ts_s > MAX_DELAY_SAMPLES as f64 {
        return Err(Error::invalid(
            "dead_time_s",
            dead_time_s,
            format!(
                "must be at most {MAX_DELAY_SAMPLES} sample periods of {} s (what a design \
                 handles; a longer sampling time or a shorter dead time)",
                crate::error::short_number(ts_s)
            ),
        ));
    }
    Ok(())
}

/// `x[k+1] = A x[k] + B u[k]`, `y[k] = C x[k] + D u[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    /// State matrix `A` (n x n).
    pub a: DMatrix<f64>,
    /// Input vector `B` (n).
    pub b: DVector<f64>,
    /// Output row `C` (n).
    pub c: RowDVector<f64>,
    /// Feed-through `D`.
    pub d: f64,
}

impl StateSpace {
    /// A static gain (no state).
    pub fn gain(k: f64) -> Self {
        StateSpace {
            a: DMatrix::zeros(0, 0),
            b: DVector::zeros(0),
            c: RowDVector::zeros(0),
            d: k,
        }
    }

    /// Number of states.
    pub fn order(&self) -> usize {
        self.a.nrows()
    }

    /// A second-order section `(b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`.
    pub fn from_sos(s: &SosCoeffs<f64>) -> Self {
        StateSpace {
            a: DMatrix::from_row_slice(2, 2, &[-s.a1, -s.a2, 1.0, 0.0]),
            b: DVector::from_vec(vec![1.0, 0.0]),
            c: RowDVector::from_vec(vec![s.b1 - s.b0 * s.a1, s.b2 - s.b0 * s.a2]),
            d: s.b0,
        }
    }

    /// A first-order section `(b0 + b1 z^-1) / (1 + a1 z^-1)`.
    pub fn from_first_order(f: &FirstOrderCoeffs<f64>) -> Self {
        StateSpace {
            a: DMatrix::from_element(1, 1, -f.a1),
            b: DVector::from_element(1, 1.0),
            c: RowDVector::from_element(1, f.b1 - f.b0 * f.a1),
            d: f.b0,
        }
    }

    /// A delay of `n` samples, `z^-n`.
    pub fn delay(n: usize) -> Self {
        if n == 0 {
            return StateSpace::gain(1.0);
        }
        let mut a = DMatrix::zeros(n, n);
        for i in 1..n {
            a[(i, i - 1)] = 1.0;
        }
        let mut b = DVector::zeros(n);
        b[0] = 1.0;
        let mut c = RowDVector::zeros(n);
        c[n - 1] = 1.0;
        StateSpace { a, b, c, d: 0.0 }
    }

    /// ZOH discretization of a strictly proper continuous `tf` preceded by the dead
    /// time `dead_time_s` (non-negative, at most [`MAX_DELAY_SAMPLES`] sample
    /// periods: each period is a state; the fractional part of
    /// `dead_time_s / ts_s` is handled exactly by splitting the hold interval).
    pub fn zoh(tf: &Tf, ts_s: f64, dead_time_s: f64) -> Result<Self> {
        require_positive("ts_s", ts_s)?;
        require_non_negative("dead_time_s", dead_time_s)?;
        check_delay_samples(ts_s, dead_time_s)?;
        let n = tf.den.degree();
        let lead = tf.den.coeffs[n];
        if n == 0 || lead == 0.0 || tf.num.degree() >= n {
            return Err(Error::invalid(
                "tf",
                n as f64,
                "ZOH needs a strictly proper transfer function with a non-zero denominator",
            ));
        }
        // Time scaling s = w0 p keeps the companion matrix well balanced:
        // w0 is the Cauchy bound on the pole magnitudes.
        let den: Vec<f64> = tf.den.coeffs[..=n].iter().map(|c| c / lead).collect();
        let w0 = (0..n)
            .map(|k| den[k].abs().powf(1.0 / (n - k) as f64))
            .fold(0.0, f64::max)
            .max(1e-300);
        let num: Vec<f64> = (0..n)
            .map(|k| {
                tf.num.coeffs.get(k).copied().unwrap_or(0.0) / lead * w0.powi(k as i32)
                    / w0.powi(n as i32)
            })
            .collect();
        let den_p: Vec<f64> = (0..n)
            .map(|k| den[k] * w0.powi(k as i32) / w0.powi(n as i32))
            .collect();
        // Controllable canonical form in p: x_i' = x_{i+1}, x_n' = -sum den_p[k] x_{k+1} + u.
        let mut ac = DMatrix::zeros(n, n);
        for i in 0..n - 1 {
            ac[(i, i + 1)] = 1.0;
        }
        for k in 0..n {
            ac[(n - 1, k)] = -den_p[k];
        }
        let mut bc = DVector::zeros(n);
        bc[n - 1] = 1.0;
        let c = RowDVector::from_vec(num);
        // Scaled times.
        let h = w0 * ts_s;
        let delay = dead_time_s / ts_s;
        let whole = delay.floor() as usize;
        let frac = delay - whole as f64; // eps / T_s in [0, 1)
        let (phi, gamma_full) = exp_with_input(&ac, &bc, h)?;
        let (gamma0, gamma1) = if frac * h < 1e-12 * h {
            (gamma_full, None)
        } else {
            // Gamma0 = Gamma(T_s - eps); Gamma1 = e^{A (T_s - eps)} Gamma(eps).
            let (e_rest, g_rest) = exp_with_input(&ac, &bc, (1.0 - frac) * h)?;
            let (_, g_eps) = exp_with_input(&ac, &bc, frac * h)?;
            (g_rest, Some(e_rest * g_eps))
        };
        // State: [x; u[k-1]; ...; u[k-m]], m = whole + (1 if frac > 0).
        let m = whole + usize::from(gamma1.is_some());
        let dim = n + m;
        let mut a = DMatrix::zeros(dim, dim);
        a.view_mut((0, 0), (n, n)).copy_from(&phi);
        let mut b = DVector::zeros(dim);
        // coefficient of u[k-j] in x[k+1]
        let put = |j: usize, g: &DVector<f64>, a: &mut DMatrix<f64>, b: &mut DVector<f64>| {
            if j == 0 {
                b.rows_mut(0, n).copy_from(g);
            } else {
                a.view_mut((0, n + j - 1), (n, 1)).copy_from(g);
            }
        };
        put(whole, &gamma0, &mut a, &mut b);
        if let Some(g1) = &gamma1 {
            put(whole + 1, g1, &mut a, &mut b);
        }
        if m > 0 {
            b[n] = 1.0;
            for i in 1..m {
                a[(n + i, n + i - 1)] = 1.0;
            }
        }
        let mut cc = RowDVector::zeros(dim);
        cc.columns_mut(0, n).copy_from(&c);
        Ok(StateSpace {
            a,
            b,
            c: cc,
            d: 0.0,
        })
    }

    /// Series connection: `self` first, then `next` (`y = next(self(u))`).
    pub fn series(&self, next: &StateSpace) -> StateSpace {
        let (n1, n2) = (self.order(), next.order());
        let mut a = DMatrix::zeros(n1 + n2, n1 + n2);
        a.view_mut((0, 0), (n1, n1)).copy_from(&self.a);
        a.view_mut((n1, n1), (n2, n2)).copy_from(&next.a);
        a.view_mut((n1, 0), (n2, n1))
            .copy_from(&(&next.b * &self.c));
        let mut b = DVector::zeros(n1 + n2);
        b.rows_mut(0, n1).copy_from(&self.b);
        b.rows_mut(n1, n2).copy_from(&(&next.b * self.d));
        let mut c = RowDVector::zeros(n1 + n2);
        c.columns_mut(0, n1).copy_from(&(&self.c * next.d));
        c.columns_mut(n1, n2).copy_from(&next.c);
        StateSpace {
            a,
            b,
            c,
            d: self.d * next.d,
        }
    }

    /// Negative feedback `y = G (r - H y)` with `G = self` forward and `H = feedback`
    /// in the return path. Errors if the loop is algebraic (`1 + D_G D_H = 0`).
    pub fn feedback(&self, feedback: &StateSpace) -> Result<StateSpace> {
        let (g, h) = (self, feedback);
        let den = 1.0 + g.d * h.d;
        if den.abs() < 1e-12 {
            return Err(Error::invalid("1 + D_G D_H", den, "algebraic loop"));
        }
        let (n1, n2) = (g.order(), h.order());
        // y = (C1 x1 - D1 C2 x2 + D1 r) / den; u1 = r - C2 x2 - D2 y
        let cy1 = &g.c / den;
        let cy2 = &h.c * (-g.d / den);
        let dy = g.d / den;
        let mut cy = RowDVector::zeros(n1 + n2);
        cy.columns_mut(0, n1).copy_from(&cy1);
        cy.columns_mut(n1, n2).copy_from(&cy2);
        // u1 = r - C2 x2 - D2 y  ->  row and feed-through
        let mut cu = -(&cy * h.d);
        {
            let mut tail = cu.columns_mut(n1, n2);
            tail -= &h.c;
        }
        let du = 1.0 - h.d * dy;
        let mut a = DMatrix::zeros(n1 + n2, n1 + n2);
        a.view_mut((0, 0), (n1, n1)).copy_from(&g.a);
        a.view_mut((n1, n1), (n2, n2)).copy_from(&h.a);
        // x1' += B1 u1 ; x2' += B2 y
        let mut b = DVector::zeros(n1 + n2);
        {
            let add1 = &g.b * &cu;
            let mut top = a.rows_mut(0, n1);
            top += add1;
            let add2 = &h.b * &cy;
            let mut bottom = a.rows_mut(n1, n2);
            bottom += add2;
        }
        b.rows_mut(0, n1).copy_from(&(&g.b * du));
        b.rows_mut(n1, n2).copy_from(&(&h.b * dy));
        Ok(StateSpace { a, b, c: cy, d: dy })
    }

    /// Eigenvalues of `A` (the poles), complex.
    pub fn poles(&self) -> Vec<C64> {
        if self.order() == 0 {
            return vec![];
        }
        self.a.complex_eigenvalues().iter().copied().collect()
    }

    /// Largest pole magnitude (0 for a static gain); `< 1` means stable.
    pub fn spectral_radius(&self) -> f64 {
        self.poles().iter().map(|p| p.norm()).fold(0.0, f64::max)
    }

    /// Frequency response `C (zI - A)^{-1} B + D` at `z = e^{j w T_s}`.
    pub fn freq_response(&self, w_rad_s: f64, ts_s: f64) -> C64 {
        let n = self.order();
        if n == 0 {
            return C64::new(self.d, 0.0);
        }
        let z = C64::from_polar(1.0, w_rad_s * ts_s);
        let m = DMatrix::from_fn(n, n, |i, j| {
            let diag = if i == j { z } else { C64::new(0.0, 0.0) };
            diag - C64::new(self.a[(i, j)], 0.0)
        });
        let b = DVector::from_fn(n, |i, _| C64::new(self.b[i], 0.0));
        match m.lu().solve(&b) {
            Some(x) => (0..n).fold(C64::new(self.d, 0.0), |acc, i| acc + self.c[i] * x[i]),
            None => C64::new(f64::INFINITY, f64::INFINITY),
        }
    }

    /// Response to the input sequence `u` from zero state.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let mut x = DVector::zeros(self.order());
        u.iter()
            .map(|&uk| {
                let y = (&self.c * &x)[0] + self.d * uk;
                x = &self.a * &x + &self.b * uk;
                y
            })
            .collect()
    }
}

/// `(e^{A h}, int_0^h e^{A t} dt B)` from one matrix exponential of the augmented matrix.
fn exp_with_input(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    h: f64,
) -> Result<(DMatrix<f64>, DVector<f64>)> {
    let n = a.nrows();
    let mut m = DMatrix::zeros(n + 1, n + 1);
    m.view_mut((0, 0), (n, n)).copy_from(&(a * h));
    m.view_mut((0, n), (n, 1)).copy_from(&(b * h));
    let e = m.exp();
    if e.iter().any(|x| !x.is_finite()) {
        return Err(Error::invalid("ts_s", h, "matrix exponential overflowed"));
    }
    Ok((
        e.view((0, 0), (n, n)).into_owned(),
        e.column(n).rows(0, n).into_owned(),
    ))
}

/// Tustin discretization of the PI controller (4.6) `K_P + K_I / s` at `T_s`:
/// `b0 = K_P + K_I T_s / 2`, `b1 = -K_P + K_I T_s / 2`, `a1 = -1`.
pub fn tustin_pi(k_p: f64, k_i: f64, ts_s: f64) -> Result<FirstOrderCoeffs<f64>> {
    require_non_negative("k_p", k_p)?;
    require_non_negative("k_i", k_i)?;
    Ok(beltune_rt::filter::first_order_from_continuous(
        [k_p, k_i],
        [1.0, 0.0],
        ts_s,
        beltune_rt::filter::Prewarp::None,
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lti::freq::dead_time;

    const TS: f64 = 1e-4;

    /// ZOH of an integrator `1/s` with a dead time of 2.5 samples: step response
    /// is the exact ramp delayed by 2.5 T_s, sampled.
    #[test]
    fn zoh_integrator_with_fractional_dead_time_is_exact() {
        let g = Tf::from_descending(&[1.0], &[1.0, 0.0]);
        let ss = StateSpace::zoh(&g, TS, 2.5 * TS).unwrap();
        let y = ss.simulate(&[1.0; 10]);
        for (k, yk) in y.iter().enumerate() {
            let t = k as f64 * TS;
            let expect = (t - 2.5 * TS).max(0.0);
            assert!((yk - expect).abs() < 1e-15, "{k}: {yk} vs {expect}");
        }
    }

    /// ZOH of a second-order resonator: the discrete step response equals the
    /// continuous step response at the sampling instants (closed form).
    #[test]
    fn zoh_matches_continuous_step_response() {
        let (w, z) = (600.0, 0.05);
        let g = Tf::from_descending(&[w * w], &[1.0, 2.0 * z * w, w * w]);
        let ss = StateSpace::zoh(&g, TS, 1e-3).unwrap();
        let y = ss.simulate(&[1.0; 400]);
        let wd = w * (1.0 - z * z).sqrt();
        for (k, yk) in y.iter().enumerate() {
            let t = k as f64 * TS - 1e-3;
            let expect = if t <= 0.0 {
                0.0
            } else {
                1.0 - (-z * w * t).exp() * ((wd * t).cos() + z * w / wd * (wd * t).sin())
            };
            assert!((yk - expect).abs() < 1e-9, "{k}: {yk} vs {expect}");
        }
    }

    /// Closed loop of `z^-1`-delayed integrator `T_s/(z-1)` with gain k: pole at `1 - k T_s`.
    #[test]
    fn feedback_pole_and_series() {
        let g = Tf::from_descending(&[1.0], &[1.0, 0.0]);
        let k = 2000.0;
        let plant = StateSpace::zoh(&g, TS, 0.0).unwrap();
        let ol = StateSpace::gain(k).series(&plant);
        let cl = ol.feedback(&StateSpace::gain(1.0)).unwrap();
        let p = cl.poles();
        assert_eq!(p.len(), 1);
        assert!((p[0].re - (1.0 - k * TS)).abs() < 1e-12 && p[0].im.abs() < 1e-12);
        // frequency response of the delay chain equals e^{-j w n T_s}
        let d = StateSpace::delay(7);
        let w = 900.0;
        assert!((d.freq_response(w, TS) - dead_time(w, 7.0 * TS)).norm() < 1e-12);
        // section against the rt crate's own evaluation
        let sos = beltune_rt::filter::notch(700.0, 3.0, TS).unwrap();
        let h = StateSpace::from_sos(&sos).freq_response(650.0, TS);
        let r = sos.freq_response(650.0, TS);
        assert!((h - C64::new(r.re, r.im)).norm() < 1e-12);
        let pi = tustin_pi(0.1, 2.0, TS).unwrap();
        let h = StateSpace::from_first_order(&pi).freq_response(50.0, TS);
        let r = pi.freq_response(50.0, TS);
        assert!((h - C64::new(r.re, r.im)).norm() < 1e-12);
        // feedback with feed-through in both paths: y = 2 (r - 0.5 y) -> y = r
        let f = StateSpace::gain(2.0)
            .feedback(&StateSpace::gain(0.5))
            .unwrap();
        assert!((f.d - 1.0).abs() < 1e-15);
        assert!(StateSpace::gain(1.0)
            .feedback(&StateSpace::gain(-1.0))
            .is_err());
    }

    #[test]
    fn bad_input_is_an_error() {
        let proper = Tf::from_descending(&[1.0, 0.0], &[1.0, 1.0]);
        assert!(StateSpace::zoh(&proper, TS, 0.0).is_err());
        let g = Tf::from_descending(&[1.0], &[1.0, 0.0]);
        assert!(StateSpace::zoh(&g, 0.0, 0.0).is_err());
        assert!(StateSpace::zoh(&g, TS, -1.0).is_err());
        assert!(tustin_pi(-1.0, 1.0, TS).is_err());
    }
}
