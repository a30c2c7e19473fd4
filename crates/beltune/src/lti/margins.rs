//! Gain crossover, phase margin, phase crossover and gain margin of an open
//! loop `L(j w)`, found on a log grid and refined by bisection to
//! [`REFINE_REL_TOL`] relative frequency.
//!
//! Conventions: the phase margin is `180 deg + arg L(j w_c)` with `arg` taken in
//! `(-360, 0]` deg, so it lies in `(-180, 180]` and does not depend on how the
//! phase is unwrapped. A phase crossover is a frequency where `L` is real and
//! negative; the gain margin is `-20 log10 |L|` there.

use super::freq::db;
use super::C64;
use crate::{Error, Result};

/// Relative frequency tolerance of the refined crossovers.
pub const REFINE_REL_TOL: f64 = 1e-12;

/// Stability margins of an open loop.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StabilityMargins {
    /// Phase margin at the critical gain crossover, degrees.
    pub phase_margin_deg: f64,
    /// The critical gain crossover `|L(j w_c)| = 1` (the one with the smallest
    /// phase margin), rad/s.
    pub crossover_rad_s: f64,
    /// Gain margin in dB at the critical phase crossover (the one with `|L| < 1`
    /// closest to 1); `+inf` if `L` never turns real negative with `|L| < 1` on the grid.
    pub gain_margin_db: f64,
    /// The critical phase crossover `arg L = -180 deg`, rad/s (`+inf` if none).
    pub phase_crossover_rad_s: f64,
    /// Delay margin `phase_margin / crossover`: the extra dead time that makes the loop
    /// marginally stable, s.
    pub delay_margin_s: f64,
    /// Number of gain crossovers on the grid (1 for a well-shaped loop).
    pub gain_crossover_count: usize,
}

/// `180 + arg L` in degrees with `arg L` taken in `(-360, 0]`.
pub fn phase_margin_deg_of(l: C64) -> f64 {
    let mut a = l.arg().to_degrees();
    if a > 0.0 {
        a -= 360.0;
    }
    180.0 + a
}

/// Bisection of `f` (sign change between `lo` and `hi`, both in rad/s) in `log w`
/// down to [`REFINE_REL_TOL`].
fn bisect(f: &impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let mut f_lo = f(lo);
    for _ in 0..200 {
        if hi / lo - 1.0 <= REFINE_REL_TOL {
            break;
        }
        let mid = (lo * hi).sqrt();
        let f_mid = f(mid);
        if f_mid == 0.0 {
            return mid;
        }
        if (f_mid > 0.0) == (f_lo > 0.0) {
            lo = mid;
            f_lo = f_mid;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

fn check_grid(grid: &[f64]) -> Result<()> {
    if grid.len() < 2 {
        return Err(Error::TooShort {
            what: "frequency grid for margins".into(),
            needed: 2,
            got: grid.len(),
        });
    }
    for (i, w) in grid.iter().enumerate() {
        if !w.is_finite() || *w <= 0.0 || (i > 0 && *w <= grid[i - 1]) {
            return Err(Error::invalid(
                "grid [rad/s]",
                *w,
                "must be positive, finite and strictly ascending",
            ));
        }
    }
    Ok(())
}

fn finite_response(l: &impl Fn(f64) -> C64, w: f64, index: usize) -> Result<C64> {
    let h = l(w);
    if h.re.is_finite() && h.im.is_finite() {
        Ok(h)
    } else {
        Err(Error::NonFinite {
            what: format!("open-loop response at {w} rad/s"),
            index,
        })
    }
}

/// All gain crossovers `|L(j w)| = 1` on `grid`, refined, ascending (rad/s).
pub fn gain_crossovers(l: impl Fn(f64) -> C64, grid: &[f64]) -> Result<Vec<f64>> {
    check_grid(grid)?;
    let f = |w: f64| l(w).norm().ln();
    let mut out = Vec::new();
    let mut prev = f64::NAN;
    for (i, &w) in grid.iter().enumerate() {
        let v = finite_response(&l, w, i)?.norm().ln();
        if i > 0 && (v > 0.0) != (prev > 0.0) {
            out.push(bisect(&f, grid[i - 1], w));
        }
        prev = v;
    }
    Ok(out)
}

/// All phase crossovers (`L` real and negative) on `grid`, refined, ascending (rad/s).
/// The grid must be fine enough that the phase moves by less than 180 degrees
/// between neighbouring points.
pub fn phase_crossovers(l: impl Fn(f64) -> C64, grid: &[f64]) -> Result<Vec<f64>> {
    check_grid(grid)?;
    let f = |w: f64| l(w).im;
    let mut out = Vec::new();
    let mut prev = C64::new(f64::NAN, f64::NAN);
    for (i, &w) in grid.iter().enumerate() {
        let h = finite_response(&l, w, i)?;
        if i > 0 && (h.im > 0.0) != (prev.im > 0.0) && (h.re < 0.0 || prev.re < 0.0) {
            let root = bisect(&f, grid[i - 1], w);
            if l(root).re < 0.0 {
                out.push(root);
            }
        }
        prev = h;
    }
    Ok(out)
}

/// Stability margins of `l` on `grid` (ascending, rad/s). Errors if `|L|` never
/// crosses 1 on the grid ([`Error::NoCrossover`]).
pub fn margins(l: impl Fn(f64) -> C64, grid: &[f64]) -> Result<StabilityMargins> {
    let gc = gain_crossovers(&l, grid)?;
    let (crossover_rad_s, phase_margin_deg) = gc
        .iter()
        .map(|&w| (w, phase_margin_deg_of(l(w))))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or_else(|| Error::NoCrossover {
            what: "gain".into(),
            w_min_rad_s: grid[0],
            w_max_rad_s: grid[grid.len() - 1],
        })?;
    let pc = phase_crossovers(&l, grid)?;
    let critical = pc
        .iter()
        .map(|&w| (w, l(w).norm()))
        .filter(|(_, m)| *m < 1.0)
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let (phase_crossover_rad_s, gain_margin_db) = match critical {
        Some((w, m)) => (w, -db(m)),
        None => (f64::INFINITY, f64::INFINITY),
    };
    Ok(StabilityMargins {
        phase_margin_deg,
        crossover_rad_s,
        gain_margin_db,
        phase_crossover_rad_s,
        delay_margin_s: phase_margin_deg.to_radians() / crossover_rad_s,
        gain_crossover_count: gc.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lti::freq::{dead_time, log_grid};

    /// Closed-form tolerance: the crossovers are refined to 1e-12 relative, so the
    /// margins agree with the analytic values far below this.
    const ANALYTIC_TOL: f64 = 1e-8;

    /// `L = k / (j w) e^{-j w T}`: crossover at `w_c = k`, phase margin
    /// `90 - k T` (deg of rad), phase crossover at `w = pi / (2T)`, gain margin
    /// `-20 log10 (k 2T / pi)`.
    #[test]
    fn integrator_with_dead_time_closed_form() {
        let (k, t) = (100.0, 1e-3);
        let l = |w: f64| C64::new(0.0, -k / w) * dead_time(w, t);
        let grid = log_grid(1.0, 1e5, 2000).unwrap();
        let m = margins(l, &grid).unwrap();
        assert!((m.crossover_rad_s / k - 1.0).abs() < ANALYTIC_TOL);
        let pm = 90.0 - (k * t).to_degrees();
        assert!((m.phase_margin_deg - pm).abs() < ANALYTIC_TOL);
        let wpc = std::f64::consts::PI / (2.0 * t);
        assert!((m.phase_crossover_rad_s / wpc - 1.0).abs() < ANALYTIC_TOL);
        let gm = -db(k / wpc);
        assert!((m.gain_margin_db - gm).abs() < ANALYTIC_TOL);
        assert_eq!(m.gain_crossover_count, 1);
        assert!((m.delay_margin_s - pm.to_radians() / k).abs() < 1e-12);
    }

    /// `L = k / (s (s + 1)^2)`: classic; phase crossover at 1 rad/s with |L| = k/2.
    #[test]
    fn third_order_gain_margin() {
        let k = 0.5;
        let l = |w: f64| {
            let s = C64::new(0.0, w);
            k / (s * (s + 1.0) * (s + 1.0))
        };
        let grid = log_grid(0.01, 100.0, 500).unwrap();
        let m = margins(l, &grid).unwrap();
        assert!((m.phase_crossover_rad_s - 1.0).abs() < ANALYTIC_TOL);
        assert!((m.gain_margin_db - -db(k / 2.0)).abs() < ANALYTIC_TOL);
        // crossover: k = w (1 + w^2)
        let wc = m.crossover_rad_s;
        assert!((wc * (1.0 + wc * wc) - k).abs() < 1e-9);
    }

    #[test]
    fn no_crossover_is_an_error() {
        let grid = log_grid(1.0, 10.0, 50).unwrap();
        let e = margins(|_| C64::new(0.1, 0.0), &grid).unwrap_err();
        assert!(matches!(e, Error::NoCrossover { .. }), "{e}");
        assert!(margins(|_| C64::new(f64::NAN, 0.0), &grid).is_err());
        assert!(margins(|_| C64::new(0.1, 0.0), &[1.0]).is_err());
        assert!(margins(|_| C64::new(0.1, 0.0), &[2.0, 1.0]).is_err());
    }

    #[test]
    fn phase_margin_convention() {
        assert!(
            (phase_margin_deg_of(C64::from_polar(1.0, (-120f64).to_radians())) - 60.0).abs()
                < 1e-12
        );
        assert!(
            (phase_margin_deg_of(C64::from_polar(1.0, (200f64).to_radians())) - 20.0).abs() < 1e-12
        );
        assert!(
            (phase_margin_deg_of(C64::from_polar(1.0, (-200f64).to_radians())) + 20.0).abs()
                < 1e-12
        );
    }
}
