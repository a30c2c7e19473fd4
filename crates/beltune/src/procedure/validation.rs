//! Stage 8 (thesis chapter 5): the validation move 0 -> 500 mm with the
//! trajectory limits of Table A.8, with no, linear and nonlinear feedforward,
//! measuring the cart tracking error (simulation truth or a cart encoder) and
//! the motor-side error.

use super::motion::{move_to, track, TrackOptions, TrackRecord};
use super::result::MoveSummary;
use super::runner::Runner;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Band within which the error counts as settled, m.
pub const SETTLING_BAND_M: f64 = 50e-6;
/// Window at the end of the record over which the static error is averaged, s.
pub const STATIC_WINDOW_S: f64 = 0.1;

/// The return to the validation start stops this far inside the window
/// before it creeps to the start, m.
pub const APPROACH_DISTANCE_M: f64 = 0.015;
/// Speed of the creep to the validation start, m/s.
pub const CREEP_SPEED_M_S: f64 = 0.2;

/// The validation move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveSpec {
    /// Start position, m.
    pub start_m: f64,
    /// Target position, m.
    pub target_m: f64,
    /// Trajectory limits (Table A.8 by default).
    pub limits: Limits,
    /// Time recorded after the trajectory ends, s.
    pub settle_s: f64,
}

impl Default for MoveSpec {
    /// The thesis move 0 -> 0.5 m with Table A.8: j 40 m/s^3, a 45 m/s^2,
    /// v 5 m/s, positions -0.01 .. 0.57 m; 1.0 s recorded after the move.
    fn default() -> Self {
        MoveSpec {
            start_m: 0.0,
            target_m: 0.5,
            limits: table_a8_limits(),
            settle_s: 1.0,
        }
    }
}

/// Table A.8 (`T_A`): the trajectory limits of all thesis experiments.
pub fn table_a8_limits() -> Limits {
    Limits {
        v_max: 5.0,
        v_min: -5.0,
        a_max: 45.0,
        a_min: -45.0,
        j_max: 40.0,
        j_min: -40.0,
        position_min: -0.01,
        position_max: 0.57,
    }
}

/// A recorded validation move and its summary.
#[derive(Clone, Debug, Default)]
pub struct MoveResult {
    /// The record.
    pub record: TrackRecord,
    /// Cart tracking error `xi_d - xi` per sample (empty without a cart measurement), m.
    pub cart_error_m: Vec<f64>,
    /// Motor-side error `xi_d - i_t phi_m` per sample, m.
    pub motor_error_m: Vec<f64>,
    /// The numbers.
    pub summary: MoveSummary,
}

/// Summarize a recorded move: maximum errors, static error, settling time.
pub fn summarize(record: TrackRecord) -> Result<MoveResult> {
    let n = record.samples.len();
    if n == 0 {
        return Err(Error::TooShort {
            what: "validation move".into(),
            needed: 1,
            got: 0,
        });
    }
    let motor_error_m: Vec<f64> = record
        .desired_m
        .iter()
        .zip(&record.samples)
        .map(|(d, s)| d - s.position_m)
        .collect();
    let cart_error_m: Vec<f64> = if record.samples.iter().all(|s| s.cart_position_m.is_some()) {
        record
            .desired_m
            .iter()
            .zip(&record.samples)
            .map(|(d, s)| d - s.cart_position_m.unwrap_or(f64::NAN))
            .collect()
    } else {
        Vec::new()
    };
    let judged = if cart_error_m.is_empty() {
        &motor_error_m
    } else {
        &cart_error_m
    };
    let max_abs = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let ts = if n > 1 {
        record.time_s[1] - record.time_s[0]
    } else {
        1.0
    };
    let window = ((STATIC_WINDOW_S / ts).round() as usize).clamp(1, n);
    let static_error_m = judged[n - window..].iter().map(|e| e.abs()).sum::<f64>() / window as f64;
    let end = record.trajectory_duration_s;
    // Last sample outside the band; settled from the next one on.
    let last_out = judged.iter().rposition(|e| e.abs() > SETTLING_BAND_M);
    let settling_time_s = match last_out {
        None => Some(0.0),
        Some(i) if i + 1 >= n => None,
        Some(i) => Some((record.time_s[i + 1] - end).max(0.0)),
    };
    let summary = MoveSummary {
        max_tracking_error_m: max_abs(judged),
        static_error_m,
        settling_time_s,
        max_motor_error_m: max_abs(&motor_error_m),
        max_torque_nm: record
            .samples
            .iter()
            .fold(0.0_f64, |m, s| m.max(s.torque_command_nm.abs())),
    };
    Ok(MoveResult {
        record,
        cart_error_m,
        motor_error_m,
        summary,
    })
}

/// Bring the axis to `spec.start_m` with `positioning` (at moderate limits),
/// then run the move with `controller` and summarize it.
pub fn run_move(
    runner: &mut Runner,
    positioning: &CascadeConfig<f64>,
    positioning_limits: &Limits,
    controller: &CascadeConfig<f64>,
    opts: TrackOptions,
    spec: &MoveSpec,
) -> Result<MoveResult> {
    if (runner.position_m() - spec.start_m).abs() > 1e-4 {
        // Issue 12: the start is 10 mm from the window's edge and the return
        // runs without feedforward; approach it from inside the window and
        // creep the last part, so that the feedback's overshoot cannot reach
        // the edge.
        let inside = if spec.target_m >= spec.start_m {
            1.0
        } else {
            -1.0
        };
        let approach = spec.start_m + inside * APPROACH_DISTANCE_M;
        if (runner.position_m() - approach).abs() > 1e-4 {
            move_to(runner, positioning, approach, positioning_limits, 0.0)?;
        }
        let creep = Limits {
            v_max: CREEP_SPEED_M_S,
            v_min: -CREEP_SPEED_M_S,
            a_max: positioning_limits.a_max.min(2.0),
            a_min: -positioning_limits.a_max.min(2.0),
            j_max: positioning_limits.j_max.min(40.0),
            j_min: -positioning_limits.j_max.min(40.0),
            ..*positioning_limits
        };
        move_to(runner, positioning, spec.start_m, &creep, 0.02)?;
    }
    let traj = Trajectory::plan(
        &State::at_rest(runner.position_m()),
        &State::at_rest(spec.target_m),
        &spec.limits,
    )?;
    let record = track(runner, controller, &traj, spec.settle_s, opts)?;
    summarize(record)
}
