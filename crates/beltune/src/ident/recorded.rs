//! Identification from a recorded periodic excitation in a CSV file (what a
//! real drive logs): columns chosen by name, validated, then ETFE with Clary's
//! method II and coherence (3.2), the two-mass fit (3.5) and, with an
//! actual-torque column, the current-loop dead time (3.27). Used by
//! `beltune identify` and by `beltune commission --csv`.

use super::closed_loop::{
    direct_from_record, indirect_from_record, ClosedLoopMethod, IdentificationStrategy,
    KnownController, ReferenceKind,
};
use super::csv_columns::{check_not_constant, check_uniform_time, read_csv_columns};
use super::dead_time::{estimate_dead_time, DeadTime};
use super::etfe::{etfe, EtfeConfig, Frf};
use super::fit::{fit_two_mass, FitConfig, TwoMassFit};
use crate::{Error, Result};
use std::path::Path;

/// Which columns hold what, and how the excitation is structured.
#[derive(Clone, Debug)]
pub struct RecordedExcitation<'a> {
    /// The CSV file (header row, columns by name).
    pub csv: &'a Path,
    /// Time column, s.
    pub time: &'a str,
    /// Input column: desired torque in N m (or current in A).
    pub input: &'a str,
    /// Output column: motor angle, rad.
    pub output: &'a str,
    /// Actual-torque column for the dead time (3.27), if logged.
    pub actual_torque: Option<&'a str>,
    /// Samples per period; `None`: detected from an exactly periodic input.
    pub period_samples: Option<usize>,
    /// Leading periods discarded as transient.
    pub skip_periods: usize,
    /// ETFE settings other than sampling time, period and skip (taken from the file and the fields above).
    pub etfe: EtfeConfig,
    /// Fit settings.
    pub fit: FitConfig,
    /// A closed-loop record: the reference column and the method; `None`:
    /// an open-loop record (`input` is the excitation).
    pub closed_loop: Option<ClosedLoopRecord<'a>>,
}

/// The closed-loop part of a record (see [`super::closed_loop`]): `input`
/// is then the torque command the drive applied (excitation plus
/// controller output), `reference` the column the excitation was added to.
#[derive(Clone, Debug)]
pub struct ClosedLoopRecord<'a> {
    /// Reference column: the excitation torque (N m), the velocity setpoint
    /// (motor rad/s) or the position setpoint (motor rad).
    pub reference: &'a str,
    /// Which of the three it is.
    pub kind: ReferenceKind,
    /// Direct or indirect.
    pub method: ClosedLoopMethod,
    /// The controller the drive ran: needed by the indirect method.
    pub controller: Option<KnownController>,
}

/// The result of [`identify_recorded`].
#[derive(Clone, Debug)]
pub struct RecordedIdentification {
    /// FRF input -> output with coherence and line flags.
    pub frf: Frf,
    /// The fitted two-mass model.
    pub fit: TwoMassFit,
    /// The dead time, when an actual-torque column was given.
    pub dead_time: Option<DeadTime>,
    /// Sampling time of the file, s.
    pub ts_s: f64,
    /// Samples per period.
    pub period_samples: usize,
    /// Whether the period was detected from the input ([`detect_period`])
    /// rather than given.
    pub period_detected: bool,
    /// Rows in the file.
    pub rows: usize,
    /// Open loop, direct or indirect closed loop.
    pub method: IdentificationStrategy,
}

/// Shortest period [`detect_period`] reports, samples (a shorter true period
/// is reported as its smallest multiple of at least this many samples).
pub const MIN_DETECTED_PERIOD: usize = 8;

/// Fraction of the compared sample pairs that may break the periodicity in
/// [`detect_period`] (0.1 %).
pub const PERIOD_GLITCH_FRACTION: f64 = 1e-3;

/// The period of a generated periodic excitation, in samples: the smallest
/// `P >= MIN_DETECTED_PERIOD`, at most half the record, such that
/// - `|x[k + P] - x[k]|` stays within 1 % of the signal's range over the
///   whole record (every overlapping pair of periods, not only the first
///   two: a PRBS starts with runs of up to `n_PRBS P_PRBS` equal samples,
///   which any shorter shift reproduces over its first run), except for at
///   most [`PERIOD_GLITCH_FRACTION`] of the pairs (a logger's glitch: the
///   bench recording's last reference sample is one), and
/// - the first `P` samples already span the signal's range (within twice that
///   tolerance; the range between the 0.1 % and 99.9 % quantiles, so that a
///   glitch does not count), which a true period does and a shift along a slow drift or
///   inside a constant run does not.
///
/// `None` when no such `P` exists (not exactly periodic, fewer than two
/// periods, or a constant signal). Cost: one pass per candidate that
/// survives the range test, each ending once its mismatches exceed the
/// glitch allowance.
pub fn detect_period(x: &[f64]) -> Option<usize> {
    let periodic_at = |p: usize, tol: f64| {
        let pairs = x.len() - p;
        let allowed = (pairs as f64 * PERIOD_GLITCH_FRACTION) as usize;
        let mut bad = 0usize;
        for (a, b) in x[p..].iter().zip(x) {
            if (a - b).abs() > tol {
                bad += 1;
                if bad > allowed {
                    return false;
                }
            }
        }
        true
    };
    // the range without the glitches: 0.1 % and 99.9 % quantiles
    if x.len() < 2 * MIN_DETECTED_PERIOD || x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut sorted = x.to_vec();
    let q = |s: &mut Vec<f64>, f: f64| {
        let k = ((s.len() - 1) as f64 * f).round() as usize;
        *s.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let lo = q(&mut sorted, PERIOD_GLITCH_FRACTION);
    let hi = q(&mut sorted, 1.0 - PERIOD_GLITCH_FRACTION);
    let range = hi - lo;
    if !(range.is_finite() && range > 0.0) {
        return None;
    }
    let tol = 0.01 * range;
    let (mut pmin, mut pmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for (p, &v) in x.iter().enumerate().take(x.len() / 2 + 1) {
        // after this, pmin/pmax span x[..p]
        if p >= MIN_DETECTED_PERIOD && pmax - pmin >= range - 2.0 * tol && periodic_at(p, tol) {
            return Some(p);
        }
        pmin = pmin.min(v);
        pmax = pmax.max(v);
    }
    None
}

/// The period of a closed-loop reference: of the reference itself, or of
/// its increments (a position setpoint that ramps at a constant velocity
/// plus a periodic excitation).
fn detect_reference_period(x: &[f64]) -> Option<usize> {
    detect_period(x).or_else(|| {
        let d: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        detect_period(&d)
    })
}

/// Read, validate and identify. Errors name the file, the column and the row.
pub fn identify_recorded(r: &RecordedExcitation) -> Result<RecordedIdentification> {
    let shown = r.csv.display().to_string();
    let mut names = vec![r.time, r.input, r.output];
    if let Some(a) = r.actual_torque {
        names.push(a);
    }
    if let Some(cl) = &r.closed_loop {
        if !names.contains(&cl.reference) {
            names.push(cl.reference);
        }
    }
    let cols = read_csv_columns(r.csv, &names)?;
    // the excitation: the input of an open-loop record, the reference of a closed-loop one
    let excitation_name = r.closed_loop.as_ref().map_or(r.input, |c| c.reference);
    check_not_constant(&cols, excitation_name)?;
    let column = |name: &str| {
        cols.column(name).ok_or_else(|| Error::Csv {
            path: shown.clone(),
            message: format!("missing column `{name}`"),
        })
    };
    let input = column(r.input)?;
    let excitation = column(excitation_name)?;
    let period = match r.period_samples {
        Some(p) => p,
        None => match &r.closed_loop {
            None => detect_period(input),
            Some(_) => detect_reference_period(excitation),
        }
        .ok_or_else(|| Error::Csv {
            path: shown.clone(),
            message: format!(
                "cannot detect the period of `{excitation_name}` (not exactly periodic); give the period in samples"
            ),
        })?,
    };
    let needed = r
        .skip_periods
        .checked_add(2)
        .and_then(|p| p.checked_mul(period))
        .unwrap_or(usize::MAX);
    if cols.rows() < needed {
        return Err(Error::Csv {
            path: shown,
            message: format!(
                "too few samples: {} data rows, but {} skipped + 2 averaged periods of {period} samples need {}",
                cols.rows(),
                r.skip_periods,
                if needed == usize::MAX { "more than can be addressed".to_string() } else { needed.to_string() }
            ),
        });
    }
    let sampling = check_uniform_time(&cols, r.time, needed, 0.01)?;
    let cfg = EtfeConfig {
        ts_s: sampling.ts_s,
        period_samples: period,
        skip_periods: r.skip_periods,
        ..r.etfe
    };
    let output = column(r.output)?;
    let (frf, method) = match &r.closed_loop {
        None => (etfe(input, output, &cfg)?, IdentificationStrategy::OpenLoop),
        Some(cl) => match cl.method {
            ClosedLoopMethod::Direct => (
                direct_from_record(excitation, input, output, &cfg)?,
                IdentificationStrategy::DirectClosedLoop { reference: cl.kind },
            ),
            ClosedLoopMethod::Indirect => {
                let controller = cl.controller.as_ref().ok_or_else(|| Error::Csv {
                    path: shown.clone(),
                    message: "the indirect closed-loop method needs the controller the drive ran (controller.toml)".to_string(),
                })?;
                (
                    indirect_from_record(excitation, output, cl.kind, controller, &cfg)?,
                    IdentificationStrategy::IndirectClosedLoop { reference: cl.kind },
                )
            }
        },
    };
    let fit = fit_two_mass(&frf, &r.fit)?;
    let dead_time = match r.actual_torque {
        Some(col) => {
            let actual = etfe(column(col)?, output, &cfg)?;
            Some(estimate_dead_time(&frf, &actual, fit.f_r_hz, period / 4)?)
        }
        None => None,
    };
    Ok(RecordedIdentification {
        frf,
        fit,
        dead_time,
        ts_s: sampling.ts_s,
        period_samples: period,
        period_detected: r.period_samples.is_none(),
        rows: cols.rows(),
        method,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn period_of_a_repeated_pattern_is_found() {
        // k^2 mod 37 has no shorter period than 37 (37 is prime)
        let base: Vec<f64> = (0..37).map(|k| ((k * k) % 37) as f64).collect();
        let x: Vec<f64> = base.iter().cycle().take(37 * 4).copied().collect();
        assert_eq!(detect_period(&x), Some(37));
        let ramp: Vec<f64> = (0..100).map(|k| k as f64).collect();
        assert_eq!(detect_period(&ramp), None);
        assert_eq!(detect_period(&[1.0; 64]), None);
        assert_eq!(detect_period(&x[..60]), None, "fewer than two periods");
    }

    /// Regression: an input that starts with a long run of equal samples
    /// (beltune's own PRBS starts with `n_PRBS` equal values of `P_PRBS`
    /// samples each) used to be taken as period 8, because only the first two
    /// candidate periods were compared.
    #[test]
    fn a_long_constant_run_at_the_start_is_not_a_period() {
        let mut one = vec![1.0; 80];
        one.extend((0..50).map(|k| if (k * 7) % 11 < 5 { 1.0 } else { -1.0 }));
        let x: Vec<f64> = one.iter().cycle().take(one.len() * 3).copied().collect();
        assert_eq!(detect_period(&x), Some(130));
    }

    /// A recorded reference with a logger glitch (the bench recording's last
    /// sample breaks the pattern) still has its period.
    #[test]
    fn a_single_glitch_keeps_the_period() {
        let base: Vec<f64> = (0..37).map(|k| ((k * k) % 37) as f64).collect();
        let mut x: Vec<f64> = base.iter().cycle().take(37 * 40).copied().collect();
        let last = x.len() - 1;
        x[last] += 20.0;
        assert_eq!(detect_period(&x), Some(37));
    }

    /// A slow drift is not periodic, however small its per-sample step.
    #[test]
    fn a_slow_drift_is_not_a_period() {
        let drift: Vec<f64> = (0..100_000).map(|k| k as f64 * 1e-6).collect();
        assert_eq!(detect_period(&drift), None);
    }
}
