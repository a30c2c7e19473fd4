//! Progress reporting of the commissioning stages. The library only calls this
//! trait; the command-line program draws progress bars (indicatif) from it.

use super::runner::{AxisFailureRecord, SafetyStopRecord};

/// Receives the progress of the commissioning procedure.
pub trait Progress {
    /// A stage starts; it will run about `total_samples` axis samples (0 if it runs none).
    fn stage_started(&mut self, name: &str, total_samples: u64);
    /// `samples` more axis samples of the current stage are done.
    fn advance(&mut self, samples: u64);
    /// The stage is done; `summary` is one log line of what it found.
    fn stage_finished(&mut self, summary: &str);
    /// The safety supervisor stopped the axis in the current stage; `record`
    /// holds the violation, the limits and the last second of samples (for a
    /// diagnostic file). Called once, after the stop and before the procedure
    /// returns [`crate::Error::SafetyStop`]. The default ignores it.
    fn safety_stopped(&mut self, _record: &SafetyStopRecord) {}
    /// An exchange with the axis failed in the current stage (lost frames,
    /// a drive fault, a watchdog) and the drive was told to quick stop;
    /// `record` holds the error and the last second of samples (for the
    /// same diagnostic as a safety stop). Called once, before the procedure
    /// returns [`crate::Error::Axis`]. The default ignores it.
    fn exchange_failed(&mut self, _record: &AxisFailureRecord) {}
}

/// Discards all progress (for tests and `--quiet`).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn stage_started(&mut self, _name: &str, _total_samples: u64) {}
    fn advance(&mut self, _samples: u64) {}
    fn stage_finished(&mut self, _summary: &str) {}
}

/// Records the log lines (the report shows them).
#[derive(Clone, Debug, Default)]
pub struct LogProgress {
    /// One line per finished stage: `"<stage>: <summary>"`.
    pub lines: Vec<String>,
    current: String,
}

impl Progress for LogProgress {
    fn stage_started(&mut self, name: &str, _total_samples: u64) {
        self.current = name.to_string();
    }
    fn advance(&mut self, _samples: u64) {}
    fn stage_finished(&mut self, summary: &str) {
        self.lines.push(format!("{}: {}", self.current, summary));
    }
}
