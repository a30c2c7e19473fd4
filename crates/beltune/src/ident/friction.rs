//! Friction identification (3.6).
//!
//! (a) Constant-velocity runs (3.35)-(3.36): at constant velocity the torque
//! is the friction `tau_R = d_v~ omega + tau_c~ sign(omega)`; a least-squares
//! fit over runs at the velocities of (A.1) gives `d_v~` and `tau_c~`. The
//! "linear" variant fits the viscous term only (the thesis' linear feedforward).
//!
//! (b) Any recorded motion with position and torque (or force) at any rate:
//! zero-phase low-pass filtering (2nd-order Butterworth forward and backward),
//! central differences for velocity and acceleration, then linear least
//! squares on `tau = J a + d_v v + tau_c sign(v) + tau_0`, with the samples
//! near zero velocity excluded. `sign(v)` passes through the same filter as
//! the torque, so that the filtered equation holds exactly.

use crate::error::require_all_finite;
use crate::{Error, Result};
use beltune_rt::filter::{butterworth_lowpass, Sos};
use nalgebra::{DMatrix, DVector};

/// The cart velocity sequence (A.1) of the thesis' friction runs, m/s.
pub const THESIS_VELOCITY_SEQUENCE_M_S: [f64; 38] = [
    2.0, 0.1, 0.01, 0.5, 1.9, 1.0, 0.001, 0.03, 0.7, 0.002, 0.4, 1.8, 0.02, 0.09, 1.7, 1.1, 0.003,
    0.009, 0.8, 1.6, 0.04, 0.004, 0.9, 1.2, 0.005, 1.4, 0.07, 0.6, 0.008, 0.3, 1.5, 0.006, 1.3,
    0.06, 0.007, 0.2, 0.08, 0.05,
];

/// One constant-velocity run: its velocity and mean torque.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ConstantVelocityRun {
    /// Motor velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Mean motor torque over the run after the running-in time, N m.
    pub mean_torque_nm: f64,
}

/// The friction model (3.36) fitted to constant-velocity runs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FrictionFit {
    /// `d_v~`, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// `tau_c~`, N m (0 for the linear variant).
    pub coulomb_nm: f64,
    /// RMS of the torque residuals, N m.
    pub rms_residual_nm: f64,
}

/// Mean torque of each run over `[start + running_in_s, end]`; `windows` are
/// `(start, end)` times in s. Velocity is the mean measured velocity there.
pub fn run_means(
    time_s: &[f64],
    velocity_rad_s: &[f64],
    torque_nm: &[f64],
    windows: &[(f64, f64)],
    running_in_s: f64,
) -> Result<Vec<ConstantVelocityRun>> {
    same_len(time_s, velocity_rad_s, "velocity")?;
    same_len(time_s, torque_nm, "torque")?;
    require_all_finite("velocity", velocity_rad_s)?;
    require_all_finite("torque", torque_nm)?;
    windows
        .iter()
        .map(|&(start, end)| {
            let idx: Vec<usize> = (0..time_s.len())
                .filter(|&k| time_s[k] >= start + running_in_s && time_s[k] <= end)
                .collect();
            if idx.is_empty() {
                return Err(Error::TooShort {
                    what: format!(
                        "constant-velocity run {start}..{end} s after {running_in_s} s running-in"
                    ),
                    needed: 1,
                    got: 0,
                });
            }
            let n = idx.len() as f64;
            Ok(ConstantVelocityRun {
                velocity_rad_s: idx.iter().map(|&k| velocity_rad_s[k]).sum::<f64>() / n,
                mean_torque_nm: idx.iter().map(|&k| torque_nm[k]).sum::<f64>() / n,
            })
        })
        .collect()
}

/// Least squares for `d_v~` and `tau_c~` (3.36) over the runs.
pub fn fit_constant_velocity(runs: &[ConstantVelocityRun]) -> Result<FrictionFit> {
    solve_runs(runs, true)
}

/// The linear variant: viscous friction only (no Coulomb term).
pub fn fit_viscous_only(runs: &[ConstantVelocityRun]) -> Result<FrictionFit> {
    solve_runs(runs, false)
}

/// (3.36) with a constant torque offset: `tau = tau_0 + d_v~ w + tau_c~ sign(w)`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct OffsetFrictionFit {
    /// The friction terms.
    pub friction: FrictionFit,
    /// The offset `tau_0`, N m: torque the runs need in either direction
    /// beyond friction (what gravity takes that the assumed holding torque
    /// did not).
    pub offset_nm: f64,
}

/// Least squares for `d_v~`, `tau_c~` and a torque offset over runs in both
/// directions: with runs at the same speeds either way the offset is the
/// mean torque of the two directions, which friction cancels from. Errors
/// (rank deficient) when the runs do not go both ways at two speeds or more.
pub fn fit_with_offset(runs: &[ConstantVelocityRun]) -> Result<OffsetFrictionFit> {
    if runs.len() < 4 {
        return Err(Error::TooShort {
            what: "friction fit with a torque offset (constant-velocity runs)".into(),
            needed: 4,
            got: runs.len(),
        });
    }
    check_runs(runs)?;
    let a = DMatrix::from_fn(runs.len(), 3, |i, j| match j {
        0 => runs[i].velocity_rad_s,
        1 => runs[i].velocity_rad_s.signum(),
        _ => 1.0,
    });
    let b = DVector::from_iterator(runs.len(), runs.iter().map(|r| r.mean_torque_nm));
    let x = lstsq(&a, &b)?;
    let r = &b - &a * &x;
    Ok(OffsetFrictionFit {
        friction: FrictionFit {
            viscous_nm_s_per_rad: x[0],
            coulomb_nm: x[1],
            rms_residual_nm: (r.norm_squared() / runs.len() as f64).sqrt(),
        },
        offset_nm: x[2],
    })
}

fn check_runs(runs: &[ConstantVelocityRun]) -> Result<()> {
    for (i, r) in runs.iter().enumerate() {
        if !(r.velocity_rad_s.is_finite() && r.mean_torque_nm.is_finite()) {
            return Err(Error::NonFinite {
                what: "constant-velocity run".into(),
                index: i,
            });
        }
    }
    Ok(())
}

fn solve_runs(runs: &[ConstantVelocityRun], coulomb: bool) -> Result<FrictionFit> {
    let cols = if coulomb { 2 } else { 1 };
    if runs.len() < cols + 1 {
        return Err(Error::TooShort {
            what: "friction fit (constant-velocity runs)".into(),
            needed: cols + 1,
            got: runs.len(),
        });
    }
    check_runs(runs)?;
    let a = DMatrix::from_fn(runs.len(), cols, |i, j| match j {
        0 => runs[i].velocity_rad_s,
        _ => runs[i].velocity_rad_s.signum(),
    });
    let b = DVector::from_iterator(runs.len(), runs.iter().map(|r| r.mean_torque_nm));
    let x = lstsq(&a, &b)?;
    let r = &b - &a * &x;
    Ok(FrictionFit {
        viscous_nm_s_per_rad: x[0],
        coulomb_nm: if coulomb { x[1] } else { 0.0 },
        rms_residual_nm: (r.norm_squared() / runs.len() as f64).sqrt(),
    })
}

/// Settings of [`identify_from_motion`].
#[derive(Clone, Debug, PartialEq)]
pub struct MotionFrictionConfig {
    /// Low-pass cut-off for position and torque, Hz; `None`: 1/50 of the sampling rate.
    pub cutoff_hz: Option<f64>,
    /// Samples with `|v|` below this fraction of the largest `|v|` are excluded.
    pub min_speed_fraction: f64,
}

impl Default for MotionFrictionConfig {
    fn default() -> Self {
        MotionFrictionConfig {
            cutoff_hz: None,
            min_speed_fraction: 0.05,
        }
    }
}

/// Inertia and friction from a recorded motion, in the record's units
/// (position in m and force in N give kg, N s/m, N, N; angle in rad and
/// torque in N m give kg m^2, N m s/rad, N m, N m).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MotionFriction {
    /// `J`: torque per acceleration.
    pub inertia: f64,
    /// `d_v`: torque per velocity.
    pub viscous: f64,
    /// `tau_c`: Coulomb friction (torque unit).
    pub coulomb: f64,
    /// `tau_0`: constant offset (gravity or bias), torque unit.
    pub offset: f64,
    /// `||tau - model|| / ||tau||` over the used samples.
    pub relative_residual: f64,
    /// Samples used by the regression.
    pub samples_used: usize,
    /// Low-pass cut-off used, Hz.
    pub cutoff_hz: f64,
}

/// Identify `tau = J a + d_v v + tau_c sign(v) + tau_0` from `time`,
/// `position` and `torque` (strictly increasing time, any rate; resampled
/// linearly to a uniform grid when the steps vary by more than 1 %).
///
/// Errors: length mismatch, non-finite values, non-increasing time, too few
/// samples, a motion in one direction only (Coulomb and offset then cannot
/// be told apart), a cut-off at or above Nyquist.
pub fn identify_from_motion(
    time_s: &[f64],
    position: &[f64],
    torque: &[f64],
    cfg: &MotionFrictionConfig,
) -> Result<MotionFriction> {
    same_len(time_s, position, "position")?;
    same_len(time_s, torque, "torque")?;
    require_all_finite("time", time_s)?;
    require_all_finite("position", position)?;
    require_all_finite("torque", torque)?;
    for (what, x) in [("time", time_s), ("position", position), ("torque", torque)] {
        require_bounded_energy(what, x)?;
    }
    const MIN_SAMPLES: usize = 50;
    if time_s.len() < MIN_SAMPLES {
        return Err(Error::TooShort {
            what: "friction identification from motion".into(),
            needed: MIN_SAMPLES,
            got: time_s.len(),
        });
    }
    if let Some(k) = (1..time_s.len()).find(|&k| time_s[k] <= time_s[k - 1]) {
        return Err(Error::invalid(
            "time",
            time_s[k],
            format!("not increasing at sample {k}"),
        ));
    }
    let n = time_s.len();
    let dt = (time_s[n - 1] - time_s[0]) / (n - 1) as f64;
    let uniform = time_s
        .windows(2)
        .all(|w| ((w[1] - w[0]) - dt).abs() <= 0.01 * dt);
    let (pos, tau) = if uniform {
        (position.to_vec(), torque.to_vec())
    } else {
        let grid: Vec<f64> = (0..n).map(|k| time_s[0] + k as f64 * dt).collect();
        (
            resample(time_s, position, &grid),
            resample(time_s, torque, &grid),
        )
    };
    let fs = 1.0 / dt;
    let fc = cfg.cutoff_hz.unwrap_or(fs / 50.0);
    if !(fc > 0.0 && fc < 0.45 * fs) {
        return Err(Error::invalid(
            "cutoff_hz",
            fc,
            format!("must lie in (0, 0.45 f_s) with f_s = {fs} Hz"),
        ));
    }
    if !(0.0..1.0).contains(&cfg.min_speed_fraction) {
        return Err(Error::invalid(
            "min_speed_fraction",
            cfg.min_speed_fraction,
            "must lie in [0, 1)",
        ));
    }
    let coeffs = butterworth_lowpass(2.0 * std::f64::consts::PI * fc, dt)?;
    let pos_f = zero_phase(&pos, coeffs);
    let tau_f = zero_phase(&tau, coeffs);
    // central differences
    let mut v = vec![0.0; n];
    for k in 1..n - 1 {
        v[k] = (pos_f[k + 1] - pos_f[k - 1]) / (2.0 * dt);
    }
    let mut a = vec![0.0; n];
    for k in 2..n - 2 {
        a[k] = (v[k + 1] - v[k - 1]) / (2.0 * dt);
    }
    // The torque is low-passed, so the Coulomb regressor must be too: the
    // same zero-phase filter applied to sign(v) keeps the regression
    // consistent (a filtered step instead of a sharp one at each reversal).
    let sign: Vec<f64> = v.iter().map(|x| x.signum()).collect();
    let sign_f = zero_phase(&sign, coeffs);
    // drop the edges (filter start-up): two periods of the cut-off
    let edge = ((2.0 * fs / fc).ceil() as usize).max(3).min(n / 4);
    let v_max = v[edge..n - edge].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let keep: Vec<usize> = (edge..n - edge)
        .filter(|&k| v[k].abs() > cfg.min_speed_fraction * v_max && v[k] != 0.0)
        .collect();
    let pos_count = keep.iter().filter(|&&k| v[k] > 0.0).count();
    let neg_count = keep.len() - pos_count;
    if pos_count < 10 || neg_count < 10 {
        return Err(Error::NoExcitation {
            what: format!(
                "friction needs motion in both directions ({pos_count} samples forward, {neg_count} backward above {:.0} % of the top speed)",
                100.0 * cfg.min_speed_fraction
            ),
        });
    }
    let phi = DMatrix::from_fn(keep.len(), 4, |i, j| {
        let k = keep[i];
        match j {
            0 => a[k],
            1 => v[k],
            2 => sign_f[k],
            _ => 1.0,
        }
    });
    let y = DVector::from_iterator(keep.len(), keep.iter().map(|&k| tau_f[k]));
    let x = lstsq(&phi, &y)?;
    let r = &y - &phi * &x;
    let norm_y = y.norm();
    let fit = MotionFriction {
        inertia: x[0],
        viscous: x[1],
        coulomb: x[2],
        offset: x[3],
        relative_residual: if norm_y > 0.0 { r.norm() / norm_y } else { 0.0 },
        samples_used: keep.len(),
        cutoff_hz: fc,
    };
    let peak = |f: &dyn Fn(usize) -> f64| keep.iter().map(|&k| f(k).abs()).fold(0.0, f64::max);
    check_plausible(&fit, peak(&|k| tau_f[k]), peak(&|k| a[k]), peak(&|k| v[k]))?;
    Ok(fit)
}

/// How many times the peak filtered torque one term of the fitted model may
/// reach before the fit counts as implausible (terms that cancel each other).
const MAX_TERM_TO_TORQUE: f64 = 100.0;

/// A fit whose numbers are not finite, or whose terms are far larger than the
/// torque they explain, is an error: nothing absurd reaches a file.
fn check_plausible(fit: &MotionFriction, tau_peak: f64, a_peak: f64, v_peak: f64) -> Result<()> {
    let values = [
        ("inertia", fit.inertia),
        ("viscous", fit.viscous),
        ("coulomb", fit.coulomb),
        ("offset", fit.offset),
        ("relative residual", fit.relative_residual),
    ];
    if let Some((name, v)) = values.iter().find(|(_, v)| !v.is_finite()) {
        return Err(Error::FitFailed {
            reason: format!(
                "friction fit: {name} is {v}; the record's values are too large or degenerate"
            ),
        });
    }
    let bound = MAX_TERM_TO_TORQUE * tau_peak;
    for (name, term) in [
        ("inertia x acceleration", fit.inertia * a_peak),
        ("viscous x velocity", fit.viscous * v_peak),
        ("coulomb", fit.coulomb),
        ("offset", fit.offset),
    ] {
        if !term.is_finite() || term.abs() > bound {
            return Err(Error::FitFailed {
                reason: format!(
                    "friction fit is implausible: the {name} term reaches {term:.3e}, more than \
                     {MAX_TERM_TO_TORQUE} times the largest torque {tau_peak:.3e}"
                ),
            });
        }
    }
    Ok(())
}

/// Error if the squares of `x` overflow: values that large (a cell of 1e308)
/// make every sum of the regression infinite.
fn require_bounded_energy(what: &str, x: &[f64]) -> Result<()> {
    let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // Sums of squares of n values up to `peak` stay far from overflow.
    if peak * peak * (x.len().max(1) as f64) < 1e300 {
        return Ok(());
    }
    let index = x.iter().position(|v| v.abs() == peak).unwrap_or(0);
    Err(Error::invalid(
        what,
        x[index],
        format!("sample {index} is too large to fit (check the units of the column)"),
    ))
}

/// Forward-backward filtering with one section, started in steady state.
fn zero_phase(x: &[f64], coeffs: beltune_rt::filter::SosCoeffs<f64>) -> Vec<f64> {
    let mut f = Sos::new(coeffs);
    f.reset_to(x[0]);
    let mut y: Vec<f64> = x.iter().map(|&v| f.step(v)).collect();
    let mut b = Sos::new(coeffs);
    b.reset_to(y[y.len() - 1]);
    for v in y.iter_mut().rev() {
        *v = b.step(*v);
    }
    y
}

/// Linear interpolation of `(t, x)` at the ascending `grid`.
fn resample(t: &[f64], x: &[f64], grid: &[f64]) -> Vec<f64> {
    let mut j = 0;
    grid.iter()
        .map(|&g| {
            while j + 2 < t.len() && t[j + 1] < g {
                j += 1;
            }
            let w = ((g - t[j]) / (t[j + 1] - t[j])).clamp(0.0, 1.0);
            x[j] + w * (x[j + 1] - x[j])
        })
        .collect()
}

fn lstsq(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>> {
    let svd = a.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    if smax.is_nan() || smax <= 0.0 || smin < 1e-10 * smax {
        return Err(Error::FitFailed {
            reason: "friction regression is rank deficient (the data do not separate the terms)"
                .into(),
        });
    }
    svd.solve(b, 0.0).map_err(|e| Error::FitFailed {
        reason: e.to_string(),
    })
}

fn same_len(a: &[f64], b: &[f64], what: &str) -> Result<()> {
    if a.len() != b.len() {
        return Err(Error::LengthMismatch {
            what: format!("time has {} samples, {what} {}", a.len(), b.len()),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Table A.10 (G_A): d_v~ = 2.530 mN m s/rad, tau_c~ = 0.125 N m.
    const D_V: f64 = 2.530e-3;
    const TAU_C: f64 = 0.125;
    /// Friction recovered within 5 %.
    const TOL: f64 = 0.05;

    /// Runs at the (A.1) velocities in both directions, torque (3.36) with
    /// 5 mN m Gaussian noise and a running-in transient that run_means discards.
    #[test]
    fn constant_velocity_runs_recover_table_a10() {
        let i_t = 0.078 / (2.0 * std::f64::consts::PI);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let noise = Normal::new(0.0, 5e-3).unwrap();
        let ts = 1e-3;
        let (mut t, mut v, mut tau, mut windows) = (vec![], vec![], vec![], vec![]);
        let mut now = 0.0;
        for (i, &xi_dot) in THESIS_VELOCITY_SEQUENCE_M_S.iter().enumerate() {
            let w = if i % 2 == 0 {
                xi_dot / i_t
            } else {
                -xi_dot / i_t
            };
            let start = now;
            for k in 0..500 {
                // first 0.1 s: a decaying transient (running-in)
                let transient = 0.5 * (-(k as f64) * ts / 0.02).exp();
                t.push(now);
                v.push(w * (1.0 - transient));
                tau.push(D_V * w + TAU_C * w.signum() + transient + noise.sample(&mut rng));
                now += ts;
            }
            windows.push((start, now - ts));
        }
        let runs = run_means(&t, &v, &tau, &windows, 0.2).unwrap();
        let fit = fit_constant_velocity(&runs).unwrap();
        assert!(
            (fit.viscous_nm_s_per_rad / D_V - 1.0).abs() < TOL,
            "{fit:?}"
        );
        assert!((fit.coulomb_nm / TAU_C - 1.0).abs() < TOL, "{fit:?}");
        // the linear variant absorbs Coulomb friction into a larger viscous term
        let lin = fit_viscous_only(&runs).unwrap();
        assert_eq!(lin.coulomb_nm, 0.0);
        assert!(lin.viscous_nm_s_per_rad > fit.viscous_nm_s_per_rad);
        assert!(lin.rms_residual_nm > fit.rms_residual_nm);
    }

    /// The holding torque of stage 3 was up to 0.1 N m off on
    /// sticky tilted axes; the friction runs determine the offset it left.
    /// Exact runs (3.36) plus an offset of 0.04 N m, three speeds each way:
    /// the fit returns the offset and the Table A.10 friction to rounding;
    /// runs in one direction only cannot separate the offset from Coulomb.
    #[test]
    fn the_friction_runs_give_the_torque_offset() {
        let offset = 0.04;
        let runs: Vec<ConstantVelocityRun> = [20.0, -20.0, 40.0, -40.0, 60.0, -60.0]
            .iter()
            .map(|&w: &f64| ConstantVelocityRun {
                velocity_rad_s: w,
                mean_torque_nm: offset + D_V * w + TAU_C * w.signum(),
            })
            .collect();
        let fit = fit_with_offset(&runs).unwrap();
        assert!((fit.offset_nm - offset).abs() < 1e-12, "{fit:?}");
        assert!((fit.friction.coulomb_nm - TAU_C).abs() < 1e-12, "{fit:?}");
        assert!(
            (fit.friction.viscous_nm_s_per_rad - D_V).abs() < 1e-14,
            "{fit:?}"
        );
        assert!(fit.friction.rms_residual_nm < 1e-12);
        // without the offset the Coulomb term absorbs it asymmetrically
        let plain = fit_constant_velocity(&runs).unwrap();
        assert!(plain.rms_residual_nm > 0.03, "{plain:?}");
        let one_way: Vec<_> = runs
            .iter()
            .copied()
            .filter(|r| r.velocity_rad_s > 0.0)
            .collect();
        assert!(matches!(
            fit_with_offset(&one_way),
            Err(Error::FitFailed { .. } | Error::TooShort { .. })
        ));
        let mut bad = runs.clone();
        bad[2].mean_torque_nm = f64::NAN;
        assert!(matches!(
            fit_with_offset(&bad),
            Err(Error::NonFinite { .. })
        ));
    }

    fn motion(rate_hz: f64, jitter: bool) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        // linear axis in m and N: J = 13.9 kg, d_v = 160 N s/m, f_c = 10 N, offset 3 N
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let noise = Normal::new(0.0, 0.5).unwrap();
        let (mut t, mut x, mut f) = (vec![], vec![], vec![]);
        let n = (20.0 * rate_hz) as usize;
        for k in 0..n {
            let tk = k as f64 / rate_hz
                + if jitter && k % 3 == 1 {
                    0.2 / rate_hz
                } else {
                    0.0
                };
            let w1 = 2.0 * std::f64::consts::PI * 0.3;
            let w2 = 2.0 * std::f64::consts::PI * 0.7;
            let pos = 0.2 * (w1 * tk).sin() + 0.05 * (w2 * tk).sin();
            let vel = 0.2 * w1 * (w1 * tk).cos() + 0.05 * w2 * (w2 * tk).cos();
            let acc = -0.2 * w1 * w1 * (w1 * tk).sin() - 0.05 * w2 * w2 * (w2 * tk).sin();
            t.push(tk);
            x.push(pos);
            f.push(13.9 * acc + 160.0 * vel + 10.0 * vel.signum() + 3.0 + noise.sample(&mut rng));
        }
        (t, x, f)
    }

    #[test]
    fn motion_regression_recovers_inertia_and_friction() {
        for (rate, jitter) in [(1000.0, false), (250.0, true)] {
            let (t, x, f) = motion(rate, jitter);
            let r = identify_from_motion(&t, &x, &f, &MotionFrictionConfig::default()).unwrap();
            println!("{rate} Hz: {r:?}");
            assert!((r.viscous / 160.0 - 1.0).abs() < TOL, "{r:?}");
            assert!((r.coulomb / 10.0 - 1.0).abs() < TOL, "{r:?}");
            assert!((r.inertia / 13.9 - 1.0).abs() < TOL, "{r:?}");
            assert!((r.offset - 3.0).abs() < 0.5, "{r:?}");
            assert!(r.relative_residual < 0.05, "{r:?}");
        }
    }

    #[test]
    fn motion_in_one_direction_or_bad_data_is_rejected() {
        let t: Vec<f64> = (0..1000).map(|k| k as f64 * 1e-3).collect();
        let x: Vec<f64> = t.iter().map(|t| t * t).collect();
        let f: Vec<f64> = t.iter().map(|t| 1.0 + t).collect();
        let cfg = MotionFrictionConfig::default();
        assert!(matches!(
            identify_from_motion(&t, &x, &f, &cfg),
            Err(Error::NoExcitation { .. })
        ));
        assert!(matches!(
            identify_from_motion(&t[..10], &x[..10], &f[..10], &cfg),
            Err(Error::TooShort { .. })
        ));
        let mut bad = x.clone();
        bad[5] = f64::NAN;
        assert!(identify_from_motion(&t, &bad, &f, &cfg).is_err());
        let mut tb = t.clone();
        tb[7] = tb[6];
        assert!(identify_from_motion(&tb, &x, &f, &cfg).is_err());
        assert!(fit_constant_velocity(&[]).is_err());
    }
}
