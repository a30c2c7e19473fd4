//! Exit statuses of the `beltune` command, one per kind of outcome, so that a
//! script (or a drive technician's batch file) can tell them apart.
//!
//! | status | meaning |
//! | --- | --- |
//! | 0 | success |
//! | 1 | any other error (I/O, an internal failure) |
//! | 2 | bad input: command line, a file's contents, a parameter out of range, data that cannot be fitted |
//! | 3 | safety stop: the supervisor stopped the axis during the commissioning, or the axis failed (drive fault, lost frames) and was quick-stopped |
//! | 4 | infeasible: no controller can be designed, or the axis cannot do what is asked |
//! | 5 | the commissioning ended with a controller that does not meet its own limits |
//! | 141 | the reader of stdout went away (SIGPIPE, as `head` causes) |
//!
//! A subcommand picks the status by returning an [`anyhow::Error`] that
//! carries a [`Failure`] in its chain; otherwise the kind of the library
//! error in the chain decides ([`status_of`]), and anything else is status 1.

/// The exit statuses (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExitStatus {
    /// 0: success.
    Success = 0,
    /// 1: any other error.
    Error = 1,
    /// 2: bad input.
    BadInput = 2,
    /// 3: the safety supervisor stopped the axis.
    SafetyStop = 3,
    /// 4: infeasible design or axis.
    Infeasible = 4,
    /// 5: finished, but the result does not meet its limits.
    LimitsNotMet = 5,
}

impl ExitStatus {
    /// The process exit code.
    pub fn code(self) -> i32 {
        self as i32
    }
}

impl std::fmt::Display for ExitStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ExitStatus::Success => "success",
            ExitStatus::Error => "error",
            ExitStatus::BadInput => "bad input",
            ExitStatus::SafetyStop => "safety stop",
            ExitStatus::Infeasible => "infeasible",
            ExitStatus::LimitsNotMet => "limits not met",
        })
    }
}

/// An error that ends the command with a chosen status; its text is the
/// one-line message.
#[derive(Debug)]
pub struct Failure {
    /// The exit status.
    pub status: ExitStatus,
    /// The one-line message.
    pub message: String,
}

impl Failure {
    /// A failure with `status` and `message`.
    pub fn new(status: ExitStatus, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Failure {}

/// The exit status an error asks for: a [`Failure`] anywhere in its chain
/// decides; else the kind of the first library error ([`beltune::Error`]):
/// a safety stop is 3, an infeasible or unstable design 4, malformed or
/// out-of-range input and data that cannot be fitted 2; anything else is 1.
pub fn status_of(e: &anyhow::Error) -> ExitStatus {
    if let Some(f) = e.downcast_ref::<Failure>() {
        return f.status;
    }
    for cause in e.chain() {
        if let Some(f) = cause.downcast_ref::<Failure>() {
            return f.status;
        }
        if let Some(lib) = cause.downcast_ref::<beltune::Error>() {
            return library_status(lib);
        }
        if let Some(rt) = cause.downcast_ref::<beltune_rt::Error>() {
            return rt_status(rt);
        }
        if let Some(io) = cause.downcast_ref::<std::io::Error>() {
            if names_a_wrong_path(io) {
                return ExitStatus::BadInput;
            }
        }
    }
    if let Some(lib) = e.downcast_ref::<beltune::Error>() {
        return library_status(lib);
    }
    ExitStatus::Error
}

/// The exit status of a library error.
pub fn library_status(e: &beltune::Error) -> ExitStatus {
    use beltune::Error as E;
    match e {
        E::SafetyStop { .. } | E::Axis { .. } => ExitStatus::SafetyStop,
        E::Infeasible { .. } | E::NoCrossover { .. } | E::Unstable { .. } => ExitStatus::Infeasible,
        E::InvalidParameter { .. }
        | E::UnknownPlant { .. }
        | E::NonFinite { .. }
        | E::TooShort { .. }
        | E::LengthMismatch { .. }
        | E::NoExcitation { .. }
        | E::Csv { .. }
        | E::Parse { .. }
        | E::FitFailed { .. } => ExitStatus::BadInput,
        E::Rt(rt) => rt_status(rt),
        E::Io { source, .. } if names_a_wrong_path(source) => ExitStatus::BadInput,
        _ => ExitStatus::Error,
    }
}

/// An I/O error that says the path the user gave is wrong (missing, a
/// folder where a file belongs or the other way round): bad input, like
/// every other command's missing input file, not a failure of the machine.
fn names_a_wrong_path(e: &std::io::Error) -> bool {
    use std::io::ErrorKind as K;
    matches!(
        e.kind(),
        K::NotFound | K::IsADirectory | K::NotADirectory | K::InvalidFilename
    )
}

/// The exit status of a real-time-core error: a bad parameter or target is
/// bad input, a request without a solution is infeasible.
pub fn rt_status(e: &beltune_rt::Error) -> ExitStatus {
    use beltune_rt::Error as E;
    match e {
        E::InvalidParameter { .. } | E::TargetOutsideLimits => ExitStatus::BadInput,
        E::PositionLimitsViolated { .. } | E::Infeasible { .. } => ExitStatus::Infeasible,
    }
}

/// The one-line message of an error: its cause chain joined by ": ", with a
/// cause that merely repeats the end of the text before it left out (an
/// `io::Error` wrapped in an error that already prints it); line breaks become
/// spaces.
pub fn one_line(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        let text = text.trim();
        if text.is_empty() || msg.ends_with(text) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(text);
    }
    msg.replace('\n', " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_is_found_anywhere_in_the_chain() {
        let e = anyhow::Error::new(Failure::new(ExitStatus::SafetyStop, "travel"))
            .context("commissioning");
        assert_eq!(status_of(&e), ExitStatus::SafetyStop);
        let lib = beltune::Error::SafetyStop {
            reason: "travel".into(),
        };
        let e = anyhow::Error::new(lib).context("commissioning");
        assert_eq!(status_of(&e), ExitStatus::SafetyStop);
        assert_eq!(status_of(&anyhow::anyhow!("x")), ExitStatus::Error);
    }

    #[test]
    fn a_repeated_cause_is_printed_once() {
        let io = std::io::Error::other("Is a directory (os error 21)");
        let e = anyhow::Error::new(io).context("reading x: Is a directory (os error 21)");
        assert_eq!(one_line(&e), "reading x: Is a directory (os error 21)");
    }
}
