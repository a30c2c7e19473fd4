//! Progress bars on stderr for the commissioning stages (indicatif), the stage
//! log lines wrapped to [`term::WIDTH`] columns, and the capture of a safety
//! stop's record for the diagnostic file.

use crate::term;
use beltune::commission::runner::{AxisFailureRecord, SafetyStopRecord};
use beltune::commission::Progress;
use indicatif::{ProgressBar, ProgressStyle};

/// Columns of the stage name in front of a stage line.
pub const STAGE_WIDTH: usize = 28;

/// What the supervisor reported when it stopped the axis, or what the runner
/// reported when an exchange with the axis failed, and in which stage.
#[derive(Clone, Debug)]
pub struct StopCapture {
    /// The stage that was running.
    pub stage: String,
    /// Why the axis stopped, with the limits and the last second of samples.
    pub cause: StopCause,
}

/// Why the axis stopped.
#[derive(Clone, Debug)]
pub enum StopCause {
    /// The supervisor stopped it: a limit was violated.
    Limit(SafetyStopRecord),
    /// An exchange failed (lost frames, a drive fault, a watchdog); the
    /// drive was told to quick stop.
    Axis(AxisFailureRecord),
}

/// Draws one progress bar per stage and prints the stage's log line when it ends.
pub struct BarProgress {
    bar: Option<ProgressBar>,
    stage: String,
    quiet: bool,
    stop: Option<StopCapture>,
}

impl BarProgress {
    /// `quiet` suppresses bars and log lines.
    pub fn new(quiet: bool) -> Self {
        BarProgress {
            bar: None,
            stage: String::new(),
            quiet,
            stop: None,
        }
    }

    /// The safety stop the procedure reported, if any (taken once).
    pub fn take_safety_stop(&mut self) -> Option<StopCapture> {
        self.stop.take()
    }
}

/// A finished stage as the lines printed for it: the stage name right-aligned,
/// the summary wrapped to [`term::width`] columns, numbers tidied.
pub fn stage_lines(stage: &str, summary: &str) -> Vec<String> {
    term::wrap(
        stage,
        STAGE_WIDTH,
        &term::tidy_numbers(summary),
        term::width(),
    )
}

impl Progress for BarProgress {
    fn stage_started(&mut self, name: &str, total_samples: u64) {
        self.stage = name.to_string();
        if self.quiet {
            return;
        }
        let bar = ProgressBar::new(total_samples.max(1));
        let style = ProgressStyle::with_template("{prefix:>28} [{bar:30}] {percent:>3}%")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(name.to_string());
        self.bar = Some(bar);
    }

    fn advance(&mut self, samples: u64) {
        if let Some(b) = &self.bar {
            b.inc(samples);
        }
    }

    fn stage_finished(&mut self, summary: &str) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
        if !self.quiet {
            for line in stage_lines(&self.stage, summary) {
                eprintln!("{line}");
            }
        }
    }

    fn safety_stopped(&mut self, record: &SafetyStopRecord) {
        if let Some(b) = self.bar.take() {
            b.abandon();
        }
        // (after a failed exchange during the stop: the violation is the cause)
        self.stop = Some(StopCapture {
            stage: self.stage.clone(),
            cause: StopCause::Limit(record.clone()),
        });
    }

    fn exchange_failed(&mut self, record: &AxisFailureRecord) {
        if let Some(b) = self.bar.take() {
            b.abandon();
        }
        self.stop = Some(StopCapture {
            stage: self.stage.clone(),
            cause: StopCause::Axis(record.clone()),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The identification line of a commissioning was 190 columns.
    #[test]
    fn stage_lines_fit_100_columns() {
        let summary = "f_r 110.81 Hz, f_z 21.10 Hz, m_c 12.38 kg, c 217.5 kN/m, d_m 40.73 N s/m, d_c 185.75 N s/m, dead time 1.00 ms, fit 1.37 dB rms, coherence 0.992 [axis busy 7.3 s]";
        let lines = stage_lines("identification (open loop)", summary);
        assert!(lines.len() >= 2);
        assert!(lines.iter().all(|l| l.chars().count() <= term::WIDTH));
        let lines = stage_lines("limits", "window 0.049999999999999996 m");
        assert_eq!(lines, vec![format!("{:>28}: window 0.05 m", "limits")]);
    }
}
