//! Closed-loop motion under the runner: follow a planned trajectory with the
//! cascaded controller of `beltune-rt`, move to a position.

use super::runner::{Runner, Sample};
use crate::Result;
use beltune_rt::control::{
    BeltStretch, CartSample, CascadeConfig, CascadeController, MotionSample, Setpoint,
    SetpointConversion,
};
use beltune_rt::trajectory::{Approach, Limits, State, Trajectory};

/// How the desired cart trajectory becomes the controller's motor setpoint.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrackOptions {
    /// Feedforward preview in samples (the current-loop dead time `n_T`), 0 for none.
    pub preview_samples: usize,
    /// Belt-stretch compensation (docs/thesis-map.md): `Off` for a rigid
    /// belt; a [`beltune_rt::control::BeltProfile`] also carries the static
    /// stretch under a constant force (gravity on a tilted axis: the cart
    /// hangs `K(xi) F` behind the motor), with positions measured from the
    /// runner's origin (the cart position at motor angle 0).
    pub belt_stretch: BeltStretch<f64>,
    /// How the supervisor treats the following error.
    pub following_error: FollowingError,
    /// End the hold after the path early once the error has settled
    /// (`None`: hold the whole settling time).
    pub end_when_settled: Option<SettledEnd>,
}

/// When a hold after a path may end before its settling time is over: once
/// the error (at the cart where it is measured, else at the motor) has
/// stayed within `band_m` for `hold_s` after the path ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettledEnd {
    /// Band around the desired position, m.
    pub band_m: f64,
    /// How long the error must stay within the band, s.
    pub hold_s: f64,
}

/// How the supervisor treats the following error of a tracked motion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FollowingError {
    /// Not computed: supervised as an open-loop motion.
    #[default]
    Unchecked,
    /// Closed loop, checked against the supervisor's limit.
    Limited,
    /// Closed loop, recorded but not limited ([`Runner::step_unlimited`]):
    /// a move whose lag is expected.
    Recorded,
}

/// A recorded closed-loop run.
#[derive(Clone, Debug, Default)]
pub struct TrackRecord {
    /// Time since the start of the run, s.
    pub time_s: Vec<f64>,
    /// Desired cart position, m.
    pub desired_m: Vec<f64>,
    /// Desired cart velocity, m/s.
    pub desired_velocity_m_s: Vec<f64>,
    /// What was measured.
    pub samples: Vec<Sample>,
    /// Duration of the trajectory itself (the rest is settling), s.
    pub trajectory_duration_s: f64,
}

/// A planned cart path [`track`] follows: a [`Trajectory`], or an
/// [`Approach`] (a move with its slow final approach).
pub trait Path {
    /// The desired cart state at `t_s` after the start (m, m/s, m/s^2, m/s^3).
    fn sample(&self, t_s: f64) -> beltune_rt::trajectory::Sample;
    /// Duration of the path, s.
    fn duration_s(&self) -> f64;
    /// Direction whose Coulomb lead the setpoint holds at `t_s` (+1, -1,
    /// or 0: none; [`SetpointConversion::motor_sample_held`]).
    fn lead_hold(&self, _t_s: f64) -> f64 {
        0.0
    }
}

impl Path for Trajectory {
    fn sample(&self, t_s: f64) -> beltune_rt::trajectory::Sample {
        Trajectory::sample(self, t_s)
    }
    fn duration_s(&self) -> f64 {
        Trajectory::duration_s(self)
    }
}

impl Path for Approach {
    fn sample(&self, t_s: f64) -> beltune_rt::trajectory::Sample {
        Approach::sample(self, t_s)
    }
    fn duration_s(&self) -> f64 {
        Approach::duration_s(self)
    }
    fn lead_hold(&self, t_s: f64) -> f64 {
        Approach::lead_hold(self, t_s)
    }
}

/// Motor setpoint for the cart path at `time_s` (relative to the encoder
/// origin), with the path's held Coulomb lead.
fn motor_sample(
    conv: &SetpointConversion<f64>,
    origin_m: f64,
    t: &impl Path,
    time_s: f64,
) -> MotionSample<f64> {
    let s = t.sample(time_s);
    conv.motor_sample_held(
        &CartSample {
            position_m: s.position - origin_m,
            velocity_m_s: s.velocity,
            acceleration_m_s2: s.acceleration,
            jerk_m_s3: s.jerk,
        },
        t.lead_hold(time_s),
    )
}

/// Follow `traj` (cart coordinates) with a controller built from `config`, then
/// hold its end for `settle_s` (less where `opts.end_when_settled` says the
/// error has settled). The controller starts bumplessly at the current
/// position.
pub fn track(
    runner: &mut Runner,
    config: &CascadeConfig<f64>,
    traj: &impl Path,
    settle_s: f64,
    opts: TrackOptions,
) -> Result<TrackRecord> {
    let ts = runner.info().ts_s;
    let mut ctrl = CascadeController::new(*config)?;
    ctrl.reset_to(runner.motor_angle_rad());
    let conv = SetpointConversion::new(runner.i_t(), opts.belt_stretch)?;
    let origin = runner.origin_m();
    let duration = traj.duration_s();
    let n = ((duration + settle_s.max(0.0)) / ts).ceil() as usize;
    let mut rec = TrackRecord {
        trajectory_duration_s: duration,
        ..Default::default()
    };
    rec.time_s.reserve(n);
    let mut desired = traj.sample(0.0);
    // samples in a row within the settled band after the path's end
    let mut settled = 0usize;
    let settled_needed = opts
        .end_when_settled
        .map(|e| (e.hold_s.max(0.0) / ts).ceil() as usize);
    for k in 0..n {
        let t = k as f64 * ts;
        let now = motor_sample(&conv, origin, traj, t);
        let ahead = motor_sample(&conv, origin, traj, t + opts.preview_samples as f64 * ts);
        let sp = Setpoint::with_preview(now, ahead);
        let out = ctrl.step(&sp, runner.motor_angle_rad());
        let e = desired.position - runner.position_m();
        let sample = match opts.following_error {
            FollowingError::Unchecked => runner.step(out.torque_nm, None)?,
            FollowingError::Limited => runner.step(out.torque_nm, Some(e))?,
            FollowingError::Recorded => runner.step_unlimited(out.torque_nm, e)?,
        };
        // The exchange returns what the drive measured at the end of the
        // cycle ([`crate::axis::Axis::exchange`]), i.e. at (k+1) T: the record
        // pairs it with the desired position of that instant. Pairing it with
        // the desired position at k T added up to v T to the tracking error
        // (1.36 mm at 1 ms for the Table A.8 move).
        let t_end = (k + 1) as f64 * ts;
        desired = traj.sample(t_end);
        rec.time_s.push(t_end);
        rec.desired_m.push(desired.position);
        rec.desired_velocity_m_s.push(desired.velocity);
        rec.samples.push(sample);
        if let (Some(end), Some(needed)) = (opts.end_when_settled, settled_needed) {
            if t_end > duration {
                let at = sample.cart_position_m.unwrap_or(sample.position_m);
                settled = if (desired.position - at).abs() <= end.band_m {
                    settled + 1
                } else {
                    0
                };
                if needed > 0 && settled >= needed {
                    break;
                }
            }
        }
    }
    Ok(rec)
}

/// Move from the current position to `target_m` at rest, within `limits`.
pub fn move_to(
    runner: &mut Runner,
    config: &CascadeConfig<f64>,
    target_m: f64,
    limits: &Limits,
    settle_s: f64,
) -> Result<TrackRecord> {
    let start = State::at_rest(runner.position_m());
    let traj = Trajectory::plan(&start, &State::at_rest(target_m), limits)?;
    track(
        runner,
        config,
        &traj,
        settle_s,
        TrackOptions {
            following_error: FollowingError::Limited,
            ..Default::default()
        },
    )
}
