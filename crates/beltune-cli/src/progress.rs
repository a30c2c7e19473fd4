//! Progress bars on stderr for the commissioning stages (indicatif).

use beltune::procedure::Progress;
use indicatif::{ProgressBar, ProgressStyle};

/// Draws one progress bar per stage and prints the stage's log line when it ends.
pub struct BarProgress {
    bar: Option<ProgressBar>,
    stage: String,
    quiet: bool,
}

impl BarProgress {
    /// `quiet` suppresses bars and log lines.
    pub fn new(quiet: bool) -> Self {
        BarProgress {
            bar: None,
            stage: String::new(),
            quiet,
        }
    }
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
            eprintln!("{:>28}: {}", self.stage, summary);
        }
    }
}
