//! Frequency responses of series connections (rational factors and the exact
//! dead time `e^{-s t_T}`), unity feedback `L / (1 + L)`, logarithmic grids and
//! Bode data with an unwrapped phase.

use super::{Tf, C64};
use crate::error::{require_non_negative, require_positive};
use crate::{Error, Result};

/// One factor of a series connection.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Element {
    /// A rational transfer function in `s`.
    Rational(Tf),
    /// The exact dead time `e^{-s t_T}` (no Pade approximation), `t_T` in s (3.25).
    DeadTime {
        /// Dead time `t_T` in s.
        seconds: f64,
    },
    /// A constant real gain.
    Gain(f64),
}

impl Element {
    /// Value at `s = j w`, `w` in rad/s.
    pub fn freq_response(&self, w_rad_s: f64) -> C64 {
        match self {
            Element::Rational(tf) => tf.freq_response(w_rad_s),
            Element::DeadTime { seconds } => dead_time(w_rad_s, *seconds),
            Element::Gain(k) => C64::new(*k, 0.0),
        }
    }
}

/// A series connection of [`Element`]s; its frequency response is the product.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Chain {
    /// The factors, in signal order (the order does not change the product).
    pub elements: Vec<Element>,
}

impl Chain {
    /// The empty chain (response 1).
    pub fn new() -> Self {
        Chain::default()
    }

    /// This chain followed by `element`.
    pub fn then(mut self, element: Element) -> Self {
        self.elements.push(element);
        self
    }

    /// This chain followed by a rational factor.
    pub fn then_tf(self, tf: Tf) -> Self {
        self.then(Element::Rational(tf))
    }

    /// Frequency response (product of all factors) at `w` in rad/s.
    pub fn freq_response(&self, w_rad_s: f64) -> C64 {
        self.elements
            .iter()
            .fold(C64::new(1.0, 0.0), |acc, e| acc * e.freq_response(w_rad_s))
    }
}

/// The exact dead time `e^{-j w t_T}` (3.25).
pub fn dead_time(w_rad_s: f64, dead_time_s: f64) -> C64 {
    C64::from_polar(1.0, -w_rad_s * dead_time_s)
}

/// Unity negative feedback `T = L / (1 + L)` of an open-loop value `L`.
pub fn feedback(open_loop: C64) -> C64 {
    open_loop / (1.0 + open_loop)
}

/// Magnitude in dB, `20 log10 |x|`.
pub fn db(magnitude: f64) -> f64 {
    20.0 * magnitude.log10()
}

/// Linear gain of a dB value, `10^(x/20)`.
pub fn from_db(x_db: f64) -> f64 {
    10f64.powf(x_db / 20.0)
}

/// `n >= 2` logarithmically spaced frequencies from `w_min` to `w_max` (both in rad/s, included).
pub fn log_grid(w_min_rad_s: f64, w_max_rad_s: f64, n: usize) -> Result<Vec<f64>> {
    require_positive("w_min_rad_s", w_min_rad_s)?;
    require_positive("w_max_rad_s", w_max_rad_s)?;
    if w_max_rad_s <= w_min_rad_s {
        return Err(Error::invalid(
            "w_max_rad_s",
            w_max_rad_s,
            format!("must exceed w_min_rad_s = {w_min_rad_s}"),
        ));
    }
    if n < 2 {
        return Err(Error::invalid(
            "n",
            n as f64,
            "a grid needs at least 2 points",
        ));
    }
    let (a, b) = (w_min_rad_s.ln(), w_max_rad_s.ln());
    Ok((0..n)
        .map(|i| {
            if i == n - 1 {
                w_max_rad_s
            } else {
                (a + (b - a) * i as f64 / (n - 1) as f64).exp()
            }
        })
        .collect())
}

/// One point of a Bode diagram.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodePoint {
    /// Angular frequency in rad/s.
    pub omega_rad_s: f64,
    /// Magnitude in dB.
    pub magnitude_db: f64,
    /// Phase in degrees, unwrapped along the grid (the first point lies in (-180, 180]).
    pub phase_deg: f64,
}

/// Bode data of `response` on `grid` (ascending, rad/s), with the phase unwrapped
/// so that consecutive points differ by less than 180 degrees.
pub fn bode(response: impl Fn(f64) -> C64, grid: &[f64]) -> Result<Vec<BodePoint>> {
    let mut out: Vec<BodePoint> = Vec::with_capacity(grid.len());
    for &w in grid {
        require_non_negative("omega_rad_s", w)?;
        let h = response(w);
        if !(h.re.is_finite() && h.im.is_finite()) || h.norm() == 0.0 {
            return Err(Error::NonFinite {
                what: format!("frequency response at {w} rad/s"),
                index: out.len(),
            });
        }
        let raw = h.arg().to_degrees();
        let phase_deg = match out.last() {
            None => raw,
            Some(prev) => unwrap_near(raw, prev.phase_deg),
        };
        out.push(BodePoint {
            omega_rad_s: w,
            magnitude_db: db(h.norm()),
            phase_deg,
        });
    }
    Ok(out)
}

/// The value `raw + k 360` (integer `k`) closest to `reference`, degrees.
pub fn unwrap_near(raw_deg: f64, reference_deg: f64) -> f64 {
    raw_deg + 360.0 * ((reference_deg - raw_deg) / 360.0).round()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Exact dead time: unit magnitude, phase -w t_T (not a Pade approximation, which
    /// would deviate by more than 1 degree beyond w t_T = 2 rad).
    #[test]
    fn dead_time_is_exact() {
        let t = 1e-3;
        let grid = log_grid(1.0, 2e4, 300).unwrap();
        let b = bode(|w| dead_time(w, t), &grid).unwrap();
        for p in b {
            assert!(p.magnitude_db.abs() < 1e-12);
            assert!((p.phase_deg + (p.omega_rad_s * t).to_degrees()).abs() < 1e-9);
        }
    }

    /// Product of an integrator and a first-order lag against the closed form
    /// `1 / (j w (T j w + 1))`.
    #[test]
    fn chain_is_the_product() {
        let integ = Tf::from_descending(&[1.0], &[1.0, 0.0]);
        let lag = Tf::from_descending(&[1.0], &[0.01, 1.0]);
        let c = Chain::new()
            .then_tf(integ)
            .then_tf(lag)
            .then(Element::Gain(3.0))
            .then(Element::DeadTime { seconds: 0.0 });
        for w in [0.3, 10.0, 100.0, 1e4] {
            let s = C64::new(0.0, w);
            let expect = 3.0 / (s * (0.01 * s + 1.0));
            assert!((c.freq_response(w) - expect).norm() < 1e-12 * expect.norm());
        }
        // feedback of an integrator k/s is the first-order lag k/(s+k): -3 dB at w = k
        let k = 50.0;
        let t = feedback(C64::new(0.0, -k / k));
        assert!((t.norm() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
    }

    /// A chain of many lags has its phase unwrapped past -180 degrees.
    #[test]
    fn phase_is_unwrapped() {
        let lag = Tf::from_descending(&[1.0], &[1.0, 1.0]);
        let c = Chain::new()
            .then_tf(lag.clone())
            .then_tf(lag.clone())
            .then_tf(lag.clone())
            .then_tf(lag);
        let grid = log_grid(0.01, 1000.0, 500).unwrap();
        let b = bode(|w| c.freq_response(w), &grid).unwrap();
        let last = b.last().unwrap();
        assert!((last.phase_deg + 4.0 * (1000f64).atan().to_degrees()).abs() < 1e-6);
        assert!((b[0].phase_deg + 4.0 * (0.01f64).atan().to_degrees()).abs() < 1e-9);
        assert!((unwrap_near(170.0, -200.0) + 190.0).abs() < 1e-12);
        assert!((from_db(db(PI)) - PI).abs() < 1e-12);
    }

    #[test]
    fn bad_grids_are_errors() {
        assert!(log_grid(0.0, 1.0, 10).is_err());
        assert!(log_grid(10.0, 1.0, 10).is_err());
        assert!(log_grid(1.0, 10.0, 1).is_err());
        assert!(log_grid(1.0, f64::NAN, 10).is_err());
        let g = log_grid(1.0, 100.0, 3).unwrap();
        assert!((g[1] - 10.0).abs() < 1e-12 && g[2] == 100.0);
        assert!(bode(|_| C64::new(f64::NAN, 0.0), &g).is_err());
    }
}
