//! The verdict's limits on the command line (`--max-tracking-error`,
//! `--max-static-error`). The verdict itself is the library's
//! ([`beltune::verdict`]): this file only turns flags into its limits.

use crate::exit::{ExitStatus, Failure};
use beltune::verdict::Limits;

/// Largest limit accepted, m: a belt axis' cart error beyond a metre is no
/// error bound any more (the verdict would pass every move that ran).
pub const MAX_LIMIT_M: f64 = 1.0;

/// The limits on the command line.
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
        let defaults = Limits::default();
        let limits = Limits {
            max_tracking_error_m: self
                .max_tracking_error
                .unwrap_or(defaults.max_tracking_error_m),
            max_static_error_m: self.max_static_error.unwrap_or(defaults.max_static_error_m),
            ..defaults
        };
        for (flag, v) in [
            ("--max-tracking-error", limits.max_tracking_error_m),
            ("--max-static-error", limits.max_static_error_m),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= MAX_LIMIT_M) {
                return Err(anyhow::Error::new(Failure::new(
                    ExitStatus::BadInput,
                    format!(
                        "{flag} must be a length in m above 0 and at most {} (a limit no move \
                         can miss judges nothing), got {}",
                        beltune::error::short_number(MAX_LIMIT_M),
                        beltune::error::short_number(v)
                    ),
                )));
            }
        }
        Ok(limits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flags_set_the_library_limits_and_refuse_non_lengths() {
        let none = LimitArgs {
            max_tracking_error: None,
            max_static_error: None,
        };
        assert_eq!(none.limits().unwrap(), Limits::default());
        let tight = LimitArgs {
            max_tracking_error: Some(2e-5),
            max_static_error: None,
        };
        assert_eq!(tight.limits().unwrap().max_tracking_error_m, 2e-5);
        for bad in [0.0, -1e-3, f64::NAN, f64::INFINITY, 1e308, -1e308, 1.5] {
            let l = LimitArgs {
                max_tracking_error: Some(bad),
                max_static_error: None,
            };
            let e = l.limits().unwrap_err().to_string();
            assert!(e.contains("--max-tracking-error"), "{e}");
        }
    }
}
