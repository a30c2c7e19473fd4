//! The one error type of the real-time crate.

use core::fmt;

/// What can go wrong when a real-time object is configured or planned.
/// Per-sample `step()` functions never fail: they saturate or hold instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Error {
    /// A parameter is non-finite or outside its physical range.
    InvalidParameter {
        /// Name of the parameter, as in the docs of the constructor.
        name: &'static str,
        /// Why the value is not accepted.
        reason: &'static str,
    },
    /// The requested target lies outside the position limits.
    TargetOutsideLimits,
    /// The planned (time-optimal) trajectory would leave the position limits
    /// on its way to an admissible target (overshoot or braking distance).
    PositionLimitsViolated {
        /// Lowest position the planned trajectory reaches (m or rad).
        lowest: f64,
        /// Highest position the planned trajectory reaches (m or rad).
        highest: f64,
    },
    /// No solution exists for the request (e.g. inconsistent limits).
    Infeasible {
        /// Why no solution exists.
        reason: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidParameter { name, reason } => {
                write!(f, "invalid parameter `{name}`: {reason}")
            }
            Error::TargetOutsideLimits => write!(f, "target position outside the position limits"),
            Error::PositionLimitsViolated { lowest, highest } => write!(
                f,
                "the time-optimal trajectory leaves the position limits (it reaches {lowest} .. {highest})"
            ),
            Error::Infeasible { reason } => write!(f, "infeasible: {reason}"),
        }
    }
}

impl core::error::Error for Error {}

/// `Ok(x)` if `x` is finite and `x > 0`, else [`Error::InvalidParameter`].
pub(crate) fn positive(name: &'static str, x: f64) -> Result<f64, Error> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: "must be finite and > 0",
        })
    }
}

/// `Ok(x)` if `x` is finite, else [`Error::InvalidParameter`].
pub(crate) fn finite(name: &'static str, x: f64) -> Result<f64, Error> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::InvalidParameter {
            name,
            reason: "must be finite",
        })
    }
}
