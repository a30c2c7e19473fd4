//! The commissioning stages, one file per stage, in the order
//! [`super::commission`] runs them. Each stage takes the
//! [`Stages`] context (the runner that drives the axis, the log, the
//! computation time), does its experiment or computation, and returns its
//! result as a named struct; none reaches back to an earlier stage.
//!
//! | stage | file |
//! | --- | --- |
//! | 1. plausibility of the data sheet, supervisor and bootstrap controller | [`plausibility`] |
//! | 2. take the axis (first hold) | [`take_axis`] |
//! | 3. holding torque and friction where the axis was taken, the bootstrap fitted to the friction, the move to the worst-case position | [`holding_torque`], [`take_axis::move_to_worst_case`] |
//! | 4. excitation amplitude | [`amplitude`] |
//! | 5. open-loop identification (restarts against its drift: [`drift`]); 5b, 5c: the belt stiffness at the validation target and near the start | [`identification`] |
//! | 6. controller design | [`design`] |
//! | 7. friction runs, the rigid inertia from their momentum balance; 7b: the delivered design on the measured friction | [`friction`], [`momentum`], [`design::delivered_design`] |
//! | 8. validation moves | [`validation_moves`] |

pub mod amplitude;
pub mod design;
pub mod drift;
pub mod friction;
pub mod holding_torque;
pub mod identification;
pub mod momentum;
pub mod plausibility;
pub mod take_axis;
pub mod validation_moves;

use super::runner::Runner;

/// How long one stage kept the axis busy (simulated time on a simulated
/// axis, so the same on every run), in the order the stages ran.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StageAxisTime {
    /// The stage, as its log line names it (`holding torque`, `friction`, ...).
    pub stage: String,
    /// Axis time from the end of the previous stage to the end of this one, s.
    pub axis_time_s: f64,
}

/// The context every stage works in: the runner that drives the axis, one log
/// line per finished stage, and the wall-clock time spent computing.
pub struct Stages<'r, 'a> {
    /// The runner (axis, supervisor, progress).
    pub runner: &'r mut Runner<'a>,
    /// One line per finished stage, `name: text [axis busy ...]`.
    pub log: Vec<String>,
    /// Wall-clock time spent computing (FFT, fit, design), s.
    pub compute_s: f64,
    /// The axis time of each finished stage; they add up to the runner's
    /// busy time at the last one.
    pub axis_times: Vec<StageAxisTime>,
}

impl<'r, 'a> Stages<'r, 'a> {
    /// The context for `runner`, the log starting with `log`.
    pub fn new(runner: &'r mut Runner<'a>, log: Vec<String>) -> Self {
        Stages {
            runner,
            log,
            compute_s: 0.0,
            axis_times: Vec::new(),
        }
    }

    /// Busy time of the axis at the end of the last finished stage, s.
    fn accounted_s(&self) -> f64 {
        self.axis_times.iter().map(|t| t.axis_time_s).sum()
    }

    /// Announce a stage (progress bar with `samples` steps, 0 = unknown).
    pub fn start(&mut self, name: &str, samples: u64) {
        self.runner.progress().stage_started(name, samples);
    }

    /// Finish a stage with its log line (the busy time is appended).
    /// Its axis time (since the previous stage finished) goes to
    /// [`Stages::axis_times`].
    pub fn finish(&mut self, name: &str, line: String) {
        let busy = self.runner.busy_time_s();
        let axis_time_s = (busy - self.accounted_s()).max(0.0);
        self.axis_times.push(StageAxisTime {
            stage: name.to_string(),
            axis_time_s,
        });
        let line = format!("{line} [axis busy {busy:.1} s]");
        self.runner.progress().stage_finished(&line);
        self.log.push(format!("{name}: {line}"));
    }

    /// Run a computation and add its wall-clock time to [`Stages::compute_s`].
    /// The axis is never left alone meanwhile: an axis whose time runs in
    /// real time is held in closed loop every cycle ([`Runner::hold_while`]).
    pub fn compute<T: Send>(
        &mut self,
        f: impl FnOnce() -> crate::Result<T> + Send,
    ) -> crate::Result<T> {
        let t0 = std::time::Instant::now();
        let out = self.runner.hold_while(f);
        self.compute_s += t0.elapsed().as_secs_f64();
        out?
    }
}
