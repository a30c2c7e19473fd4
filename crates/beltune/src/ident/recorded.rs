//! Identification from a recorded periodic excitation in a CSV file (what a
//! real drive logs): columns chosen by name, validated, then ETFE with Clary's
//! method II and coherence (3.2), the two-mass fit (3.5) and, with an
//! actual-torque column, the current-loop dead time (3.27). Used by
//! `beltune identify` and by `beltune commission --csv`.

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
    /// Rows in the file.
    pub rows: usize,
}

/// The smallest `P` (at least 8) with `|x[k + P] - x[k]|` below 1 % of the
/// signal's range for `k < P` (the first two periods): the period of a
/// generated periodic excitation.
pub fn detect_period(x: &[f64]) -> Option<usize> {
    let lo = x.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = x.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let tol = 0.01 * (hi - lo);
    (8..=x.len() / 2).find(|&p| (0..p).all(|k| (x[k + p] - x[k]).abs() <= tol))
}

/// Read, validate and identify. Errors name the file, the column and the row.
pub fn identify_recorded(r: &RecordedExcitation) -> Result<RecordedIdentification> {
    let shown = r.csv.display().to_string();
    let mut names = vec![r.time, r.input, r.output];
    if let Some(a) = r.actual_torque {
        names.push(a);
    }
    let cols = read_csv_columns(r.csv, &names)?;
    check_not_constant(&cols, r.input)?;
    let column = |name: &str| {
        cols.column(name).ok_or_else(|| Error::Csv {
            path: shown.clone(),
            message: format!("missing column `{name}`"),
        })
    };
    let input = column(r.input)?;
    let period = match r.period_samples {
        Some(p) => p,
        None => detect_period(input).ok_or_else(|| Error::Csv {
            path: shown.clone(),
            message: format!(
                "cannot detect the period of `{}` (not exactly periodic); give the period in samples",
                r.input
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
    let frf = etfe(input, output, &cfg)?;
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
        rows: cols.rows(),
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
    }
}
