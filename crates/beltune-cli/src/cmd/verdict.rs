//! The verdict on a commissioning's validation move: does the controller meet
//! the limits (thesis chapter 5: a maximum cart tracking error below 1 mm
//! during the 0 -> 500 mm move, a static error below 100 um, with the
//! nonlinear feedforward that `controller.toml` carries)?
//!
//! Kept small on purpose: when the library gives its own verdict, [`judge`]
//! becomes a conversion of it.

use beltune::commission::result::MoveSummary;
use serde::Serialize;

/// Thesis chapter 5: largest cart tracking error of the validation move, m
/// (the library's [`beltune::verdict::MAX_TRACKING_ERROR_M`]).
pub const THESIS_MAX_TRACKING_ERROR_M: f64 = beltune::verdict::MAX_TRACKING_ERROR_M;
/// Thesis chapter 5: static positioning error after the move, m
/// ([`beltune::verdict::MAX_STATIC_ERROR_M`]).
pub const THESIS_MAX_STATIC_ERROR_M: f64 = beltune::verdict::MAX_STATIC_ERROR_M;

/// The limits on the command line (`--max-tracking-error`, `--max-static-error`).
#[derive(clap::Args, Clone, Debug)]
pub struct LimitArgs {
    /// Largest cart tracking error the validation move may show, m (default: the thesis' 1 mm).
    #[arg(long, value_name = "M")]
    pub max_tracking_error: Option<f64>,
    /// Largest static cart error after the validation move, m (default: the thesis' 100 um).
    #[arg(long, value_name = "M")]
    pub max_static_error: Option<f64>,
}

impl LimitArgs {
    /// The limits, or one line saying which is not a positive length.
    pub fn limits(&self) -> anyhow::Result<Limits> {
        let tracking = self
            .max_tracking_error
            .unwrap_or(THESIS_MAX_TRACKING_ERROR_M);
        let stat = self.max_static_error.unwrap_or(THESIS_MAX_STATIC_ERROR_M);
        for (flag, v) in [
            ("--max-tracking-error", tracking),
            ("--max-static-error", stat),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(anyhow::Error::new(crate::exit::Failure::new(
                    crate::exit::ExitStatus::BadInput,
                    format!("{flag} must be a positive length in m, got {v}"),
                )));
            }
        }
        Ok(Limits {
            max_tracking_error_m: tracking,
            max_static_error_m: stat,
        })
    }
}

/// The limits a validation move is judged against.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Limits {
    /// Largest allowed cart tracking error, m.
    pub max_tracking_error_m: f64,
    /// Largest allowed static cart error, m.
    pub max_static_error_m: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_tracking_error_m: THESIS_MAX_TRACKING_ERROR_M,
            max_static_error_m: THESIS_MAX_STATIC_ERROR_M,
        }
    }
}

/// One judged quantity.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Check {
    /// `max_tracking_error` or `static_error`.
    pub name: &'static str,
    /// Measured value, m.
    pub value_m: f64,
    /// Limit, m.
    pub limit_m: f64,
    /// `value_m < limit_m` (a non-finite value fails).
    pub passed: bool,
}

/// The verdict: every check and whether all passed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verdict {
    /// All checks passed.
    pub passed: bool,
    /// The checks, tracking error first.
    pub checks: Vec<Check>,
}

/// Judge the move with the controller that is delivered (nonlinear feedforward).
pub fn judge(nonlinear: &MoveSummary, limits: &Limits) -> Verdict {
    let check = |name, value_m: f64, limit_m: f64| Check {
        name,
        value_m,
        limit_m,
        passed: value_m.is_finite() && value_m < limit_m,
    };
    let checks = vec![
        check(
            "max_tracking_error",
            nonlinear.max_tracking_error_m,
            limits.max_tracking_error_m,
        ),
        check(
            "static_error",
            nonlinear.static_error_m,
            limits.max_static_error_m,
        ),
    ];
    Verdict {
        passed: checks.iter().all(|c| c.passed),
        checks,
    }
}

impl Check {
    /// `max cart error 0.640 mm < 1 mm`, in mm or um as fits the limit.
    pub fn text(&self) -> String {
        let label = match self.name {
            "max_tracking_error" => "max cart error",
            "static_error" => "static error",
            other => other,
        };
        let (scale, unit, digits) = if self.limit_m < 1e-3 {
            (1e6, "um", 1)
        } else {
            (1e3, "mm", 3)
        };
        let op = if self.passed { "<" } else { ">=" };
        format!(
            "{label} {:.digits$} {unit} {op} {} {unit}",
            self.value_m * scale,
            crate::term::tidy(self.limit_m * scale)
        )
    }
}

impl Verdict {
    /// `PASS: ...` or `FAIL: ...` with every check.
    pub fn text(&self) -> String {
        let word = if self.passed { "PASS" } else { "FAIL" };
        let checks: Vec<String> = self.checks.iter().map(Check::text).collect();
        format!("{word}: {}", checks.join(", "))
    }

    /// The checks that failed, as text.
    pub fn failures(&self) -> Vec<String> {
        self.checks
            .iter()
            .filter(|c| !c.passed)
            .map(Check::text)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moved(max_m: f64, static_m: f64) -> MoveSummary {
        MoveSummary {
            max_tracking_error_m: max_m,
            static_error_m: static_m,
            ..MoveSummary::default()
        }
    }

    #[test]
    fn each_limit_decides_and_nan_fails() {
        let l = Limits::default();
        assert!(judge(&moved(0.64e-3, 31e-6), &l).passed);
        let v = judge(&moved(1.2e-3, 31e-6), &l);
        assert!(!v.passed && !v.checks[0].passed && v.checks[1].passed);
        assert_eq!(v.failures(), ["max cart error 1.200 mm >= 1 mm"]);
        let v = judge(&moved(0.5e-3, 150e-6), &l);
        assert!(!v.passed && v.checks[0].passed && !v.checks[1].passed);
        assert_eq!(v.failures(), ["static error 150.0 um >= 100 um"]);
        // Exactly at the limit is not below it.
        assert!(!judge(&moved(1e-3, 0.0), &l).passed);
        assert!(!judge(&moved(f64::NAN, 0.0), &l).passed);
        assert_eq!(
            judge(&moved(0.64e-3, 31.3e-6), &l).text(),
            "PASS: max cart error 0.640 mm < 1 mm, static error 31.3 um < 100 um"
        );
    }
}
