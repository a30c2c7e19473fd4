//! The one error type of the `beltune` library. Variants are structured so that
//! the CLI can print one precise line; each module adds what it needs in its
//! own section below.

use std::path::PathBuf;

/// Result with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything the library reports instead of panicking or returning NaN.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    // ---- parameters and models ----
    /// A parameter is non-finite or outside its physical range.
    #[error("invalid parameter `{name}` = {}: {reason}", short_number(*value))]
    InvalidParameter {
        /// Parameter name (field name, with its unit where it helps).
        name: String,
        /// The offending value.
        value: f64,
        /// Why it is not accepted.
        reason: String,
    },
    /// A named plant is not built in.
    #[error("unknown plant `{name}` (built in: {known})")]
    UnknownPlant {
        /// The requested name.
        name: String,
        /// The built-in names, comma separated.
        known: String,
    },

    // ---- data records ----
    /// A record contains NaN or infinity.
    #[error("non-finite value in `{what}` at sample {index}")]
    NonFinite {
        /// Which signal.
        what: String,
        /// Zero-based sample index.
        index: usize,
    },
    /// A record is too short for what was asked.
    #[error("record too short for {what}: needs {needed} samples, has {got}")]
    TooShort {
        /// What needed the samples.
        what: String,
        /// Samples needed.
        needed: usize,
        /// Samples available.
        got: usize,
    },
    /// Signals that must have equal lengths do not.
    #[error("length mismatch: {what}")]
    LengthMismatch {
        /// Description of the mismatch.
        what: String,
    },
    /// The input signal does not excite the system.
    #[error("no excitation: {what}")]
    NoExcitation {
        /// What was found instead.
        what: String,
    },
    /// A CSV file is malformed (missing column, bad cell, non-monotonic time, ...).
    #[error("{path}: {message}")]
    Csv {
        /// The file.
        path: String,
        /// What is wrong, naming the column and the row.
        message: String,
    },

    // ---- identification and design ----
    /// A parametric fit did not converge or gave a non-physical result.
    #[error("fit failed: {reason}")]
    FitFailed {
        /// Why.
        reason: String,
    },
    /// The requested design has no solution.
    #[error("infeasible design: {reason}")]
    Infeasible {
        /// Why no solution exists.
        reason: String,
    },
    /// An open loop's gain or phase never crosses its critical value on the frequency grid.
    #[error("no {what} crossover of the open loop between {w_min_rad_s} and {w_max_rad_s} rad/s")]
    NoCrossover {
        /// `gain` (|L| = 1) or `phase` (arg L = -180 deg).
        what: String,
        /// Lowest grid frequency, rad/s.
        w_min_rad_s: f64,
        /// Highest grid frequency, rad/s.
        w_max_rad_s: f64,
    },
    /// A designed loop is unstable.
    #[error("unstable closed loop: {reason}")]
    Unstable {
        /// Which loop and why.
        reason: String,
    },

    // ---- commissioning ----
    /// The safety supervisor stopped the axis.
    #[error("safety stop: {reason}")]
    SafetyStop {
        /// Which limit was violated, with the values.
        reason: String,
    },

    /// A cyclic exchange with the axis failed; the drive was told to quick
    /// stop (`quick_stop` says why that failed too, if it did).
    #[error("axis: {error}{}", quick_stop.map(|q| format!("; the quick stop failed too: {q}")).unwrap_or_default())]
    Axis {
        /// Why the exchange failed.
        error: crate::axis::AxisError,
        /// Why the quick stop failed, if it did.
        quick_stop: Option<crate::axis::AxisError>,
    },

    // ---- report ----
    /// A plot could not be drawn or the report not rendered.
    #[error("report: {reason}")]
    Report {
        /// What failed.
        reason: String,
    },

    // ---- history database ----
    /// The history database could not be opened, migrated, read or written.
    #[error("history database {location}: {reason}")]
    Database {
        /// The file or the server (without a password).
        location: String,
        /// What failed.
        reason: String,
    },

    // ---- files ----
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A configuration file could not be parsed.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The real-time crate refused a configuration.
    #[error("real-time core: {0}")]
    Rt(#[from] beltune_rt::Error),
}

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(name: impl Into<String>, value: f64, reason: impl Into<String>) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            value,
            reason: reason.into(),
        }
    }
}

/// `Ok(x)` if `x` is finite and `> 0`.
pub fn require_positive(name: &str, x: f64) -> Result<f64> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(Error::invalid(name, x, "must be finite and > 0"))
    }
}

/// `Ok(x)` if `x` is finite and `>= 0`.
pub fn require_non_negative(name: &str, x: f64) -> Result<f64> {
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(Error::invalid(name, x, "must be finite and >= 0"))
    }
}

/// `Ok(x)` if `x` is finite.
pub fn require_finite(name: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::invalid(name, x, "must be finite"))
    }
}

/// `Ok(())` if every sample is finite, else [`Error::NonFinite`] naming the first bad index.
pub fn require_all_finite(what: &str, xs: &[f64]) -> Result<()> {
    match xs.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(index) => Err(Error::NonFinite {
            what: what.to_string(),
            index,
        }),
    }
}

/// `Ok(x)` if `x` is finite and `lo <= x <= hi` (a plausibility bound; the
/// message gives the range in the unit of the name).
pub fn require_range(name: &str, x: f64, lo: f64, hi: f64) -> Result<f64> {
    if x.is_finite() && x >= lo && x <= hi {
        Ok(x)
    } else {
        Err(Error::invalid(
            name,
            x,
            format!("must be finite and within [{lo:e}, {hi:e}] (plausible physical range)"),
        ))
    }
}

/// Significant digits [`short_number`] keeps: below the 15-17 of a full
/// `f64`, so that the last-bit noise of decimal fractions rounds away
/// (`0.049999999999999996` reads `0.05`), far above what any quantity in a
/// message resolves.
pub const SHORT_NUMBER_DIGITS: usize = 12;

/// The one number format of messages: the shortest text that reads back as
/// the value rounded to [`SHORT_NUMBER_DIGITS`] significant digits, in
/// exponent form where that is shorter (`1e308`, not 309 digits; `5e-324`,
/// not 324 zeros; `0.05`, `-2.5`, `5`). `NaN`, `inf` and `-inf` as Rust
/// prints them.
pub fn short_number(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{:.*e}", SHORT_NUMBER_DIGITS - 1, x)
        .parse()
        .unwrap_or(x);
    // Debug prints the shortest round-trip form: `5.0`, `1e308`, `1e-7`
    let debug = format!("{rounded:?}");
    let text = match debug.strip_suffix(".0") {
        Some(int) => int.to_string(),
        None => debug.replace(".0e", "e"),
    };
    if text == "-0" {
        "0".into()
    } else {
        text
    }
}
