//! Friction with its uncertainty: (3.36) with a torque offset,
//! `tau = tau_0 + d_v~ w + tau_c~ sign(w)`, by weighted least squares over
//! constant-velocity runs, with the covariance of the three.
//!
//! - Runs with a standard error each (the health check's runs,
//!   [`plateau_torque_sigma`]): weights `1 / sigma_i^2`, `cov = (A^T W A)^-1`.
//! - Runs without (the baseline's friction points): equal weights, the
//!   residual variance `s^2 = |r|^2 / (n - 3)` as every run's, `cov = s^2
//!   (A^T A)^-1` (unknown with three runs or fewer).

use crate::ident::friction::ConstantVelocityRun;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// (3.36) with an offset and the one-sigma uncertainty of each term.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrictionEstimate {
    /// Coulomb friction at the motor `tau_c~`, N m.
    pub coulomb_nm: f64,
    /// Its uncertainty, N m (NaN: unknown).
    #[serde(with = "super::nan_as_null")]
    pub coulomb_sigma_nm: f64,
    /// Viscous friction at the motor `d_v~`, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// Its uncertainty, N m s/rad (NaN: unknown).
    #[serde(with = "super::nan_as_null")]
    pub viscous_sigma_nm_s_per_rad: f64,
    /// The torque offset (the holding torque), N m.
    pub holding_nm: f64,
    /// Its uncertainty, N m (NaN: unknown).
    #[serde(with = "super::nan_as_null")]
    pub holding_sigma_nm: f64,
}

/// Fit (3.36) with an offset to `runs`; `sigma_nm` the standard error of
/// each run's mean torque (N m), or `None` for equal unknown errors. Errors
/// for fewer than three runs, runs that do not go both ways at two speeds
/// (a singular problem) or a non-positive or non-finite standard error.
pub fn fit_friction(
    runs: &[ConstantVelocityRun],
    sigma_nm: Option<&[f64]>,
) -> Result<FrictionEstimate> {
    let n = runs.len();
    if n < 3 {
        return Err(Error::TooShort {
            what: "friction runs with an offset".into(),
            needed: 3,
            got: n,
        });
    }
    if let Some(s) = sigma_nm {
        if s.len() != n || s.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(Error::invalid(
                "friction run standard error [N m]",
                s.iter()
                    .copied()
                    .find(|x| !(x.is_finite() && *x > 0.0))
                    .unwrap_or(f64::NAN),
                "one positive standard error per run",
            ));
        }
    }
    for (i, r) in runs.iter().enumerate() {
        if !(r.velocity_rad_s.is_finite() && r.mean_torque_nm.is_finite()) {
            return Err(Error::NonFinite {
                what: "constant-velocity run".into(),
                index: i,
            });
        }
    }
    let weight = |i: usize| sigma_nm.map_or(1.0, |s| 1.0 / s[i]);
    let a = DMatrix::from_fn(n, 3, |i, j| {
        weight(i)
            * match j {
                0 => runs[i].velocity_rad_s,
                1 => runs[i].velocity_rad_s.signum(),
                _ => 1.0,
            }
    });
    let b = DVector::from_fn(n, |i, _| weight(i) * runs[i].mean_torque_nm);
    let ata = a.transpose() * &a;
    let inv = ata.try_inverse().ok_or_else(|| Error::FitFailed {
        reason: "the friction runs do not go both ways at two speeds".into(),
    })?;
    let x = &inv * a.transpose() * &b;
    let cov = match sigma_nm {
        Some(_) => inv,
        None if n > 3 => {
            let r = &b - &a * &x;
            inv * (r.norm_squared() / (n - 3) as f64)
        }
        None => DMatrix::from_element(3, 3, f64::NAN),
    };
    let sd = |k: usize| cov[(k, k)].max(0.0).sqrt();
    if !x.iter().all(|v| v.is_finite()) {
        return Err(Error::FitFailed {
            reason: "the friction fit is not finite".into(),
        });
    }
    Ok(FrictionEstimate {
        viscous_nm_s_per_rad: x[0],
        viscous_sigma_nm_s_per_rad: sd(0),
        coulomb_nm: x[1],
        coulomb_sigma_nm: sd(1),
        holding_nm: x[2],
        holding_sigma_nm: sd(2),
    })
}

/// The standard error of the mean of `torque_nm` (one sample each) over
/// blocks of `block` samples: the spread of the block means over the square
/// root of their number, so that a ringing of the block's period (the belt
/// mode after the acceleration) and slow drifts count, N m. NaN with fewer
/// than three whole blocks.
pub fn plateau_torque_sigma(torque_nm: &[f64], block: usize) -> f64 {
    let block = block.max(1);
    let n = torque_nm.len() / block;
    if n < 3 {
        return f64::NAN;
    }
    let means: Vec<f64> = (0..n)
        .map(|k| torque_nm[k * block..(k + 1) * block].iter().sum::<f64>() / block as f64)
        .collect();
    let mean = means.iter().sum::<f64>() / n as f64;
    let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (var / n as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn run(w: f64, tau: f64) -> ConstantVelocityRun {
        ConstantVelocityRun {
            velocity_rad_s: w,
            mean_torque_nm: tau,
        }
    }

    /// Exact on (3.36) with an offset; four runs at two speeds both ways.
    #[test]
    fn the_terms_of_3_36_come_back_exactly() {
        let (h, c, d) = (0.31, 0.125, 2.5e-3);
        let tau = |w: f64| h + c * w.signum() + d * w;
        let runs: Vec<_> = [12.0, -12.5, 40.0, -39.0]
            .iter()
            .map(|&w| run(w, tau(w)))
            .collect();
        let f = fit_friction(&runs, Some(&[1e-3; 4])).unwrap();
        assert!((f.holding_nm - h).abs() < 1e-12, "{f:?}");
        assert!((f.coulomb_nm - c).abs() < 1e-12, "{f:?}");
        assert!((f.viscous_nm_s_per_rad - d).abs() < 1e-14, "{f:?}");
        // one-way runs are singular
        let up: Vec<_> = [12.0, 40.0, 30.0].iter().map(|&w| run(w, tau(w))).collect();
        assert!(fit_friction(&up, None).is_err());
        assert!(fit_friction(&runs[..2], None).is_err());
        assert!(fit_friction(&runs, Some(&[1e-3, 0.0, 1e-3, 1e-3])).is_err());
    }

    /// The stated uncertainty is the spread: over 4000 seeded draws of runs
    /// with Gaussian errors of their stated sigma, the standard deviation of
    /// each fitted term is its stated sigma within 5 % (the sampling error
    /// of a standard deviation over 4000 draws is 1.1 %).
    #[test]
    fn the_stated_uncertainty_is_the_spread_of_repeated_fits() {
        let (h, c, d) = (0.0, 0.125, 2.5e-3);
        let ws = [12.0, -12.0, 40.0, -40.0];
        let sig = [4e-3, 4e-3, 2e-3, 2e-3];
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let normal = rand_distr::StandardNormal;
        let mut got: Vec<[f64; 3]> = Vec::new();
        let mut stated = [0.0; 3];
        for _ in 0..4000 {
            let runs: Vec<_> = ws
                .iter()
                .zip(&sig)
                .map(|(&w, &s)| {
                    let z: f64 = rng.sample(normal);
                    run(w, h + c * w.signum() + d * w + s * z)
                })
                .collect();
            let f = fit_friction(&runs, Some(&sig)).unwrap();
            got.push([f.coulomb_nm, f.viscous_nm_s_per_rad, f.holding_nm]);
            stated = [
                f.coulomb_sigma_nm,
                f.viscous_sigma_nm_s_per_rad,
                f.holding_sigma_nm,
            ];
        }
        for k in 0..3 {
            let mean = got.iter().map(|g| g[k]).sum::<f64>() / got.len() as f64;
            let sd = (got.iter().map(|g| (g[k] - mean).powi(2)).sum::<f64>()
                / (got.len() - 1) as f64)
                .sqrt();
            assert!(
                (sd / stated[k] - 1.0).abs() < 0.05,
                "term {k}: {sd} vs {}",
                stated[k]
            );
        }
    }

    /// Block means: a constant has no spread; a sine of the block's period
    /// averages out of every block; white noise gives sigma / sqrt(n).
    #[test]
    fn the_plateau_error_counts_blocks() {
        assert_eq!(plateau_torque_sigma(&[0.2; 100], 10), 0.0);
        let sine: Vec<f64> = (0..400)
            .map(|k| 0.2 + 0.05 * (2.0 * std::f64::consts::PI * k as f64 / 40.0).sin())
            .collect();
        assert!(plateau_torque_sigma(&sine, 40) < 1e-12);
        assert!(plateau_torque_sigma(&[0.2; 20], 10).is_nan());
    }
}
