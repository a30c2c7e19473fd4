//! The runner drives an [`Axis`] sample by sample for all stages: it converts
//! encoder counts to cart coordinates, estimates the velocity, counts the busy
//! time, reports progress, asks the [`SafetySupervisor`] about every sample and,
//! on a violation, stops the excitation at once and brings the axis to rest
//! with a jerk-limited stop before returning [`Error::SafetyStop`].
//!
//! It keeps the last [`STOP_HISTORY_S`] of samples in a ring buffer; on a
//! safety stop it hands them, with the violation and the limits, to
//! [`Progress::safety_stopped`] (a [`SafetyStopRecord`]) so that the caller
//! can write a diagnostic file. Cost: one copy of a [`HistorySample`] per
//! sample, no allocation after [`Runner::new`].

use super::progress::Progress;
use super::safety::{SafetyLimits, SafetySupervisor, Violation};
use crate::axis::{Axis, AxisInfo, Measurement};
use crate::{Error, Result};
use beltune_rt::control::{CascadeConfig, CascadeController, MotionSample, Setpoint};
use beltune_rt::filter::{velocity_filter, FirstOrder};
use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::collections::VecDeque;

/// How long the axis is held after a stop trajectory, s.
const STOP_SETTLE_S: f64 = 0.2;
/// Speed below which a stopped axis counts as at rest, m/s.
const STOP_REST_SPEED_M_S: f64 = 1e-3;
/// Longest extra hold after a stop's settling time, s.
const STOP_REST_MAX_S: f64 = 1.0;
/// Share of the supervisor's following-error limit by which the axis may
/// leave its stop trajectory before the stop drops its controller for the
/// damping brake (a stable stop follows within a few mm).
const STOP_DIVERGENCE_SHARE: f64 = 0.5;
/// Time constant of the damping brake, s: `J / (D i_t^2)` with the stop
/// capability's inertia. The brake damps the rigid-body velocity (the
/// moving average of [`RigidVelocity`], blind to the resonance), a
/// collocated damper, stable on any two-mass axis; 50 ms is five times the
/// estimate's lag.
const STOP_BRAKE_TIME_S: f64 = 0.05;
/// Speed at which the damping brake reaches the torque limit when the
/// inertia is not known yet, m/s.
const STOP_BRAKE_FULL_SPEED_M_S: f64 = 0.1;
/// Window of each of the two moving averages of the rigid-body velocity
/// estimate used in open-loop stages, s (see [`RigidVelocity`]).
const RIGID_VELOCITY_WINDOW_S: f64 = 20e-3;

/// The cart's rigid-body velocity as the motor encoder shows it, without the
/// belt resonance: two cascaded moving averages of the motor-side velocity
/// over [`RIGID_VELOCITY_WINDOW_S`] each. In open loop the motor vibrates at
/// the resonance (0.85 m/s peak while the cart moves at 0.1 m/s);
/// that vibration moves the motor by `v / w` (millimetres), not towards the
/// window edge. The gain at `f` is `sinc^2(f W)`: zero at 50 Hz and its
/// multiples, below 4 % above 80 Hz; the lag is `W` (20 ms).
#[derive(Clone, Debug)]
struct RigidVelocity {
    positions: Vec<f64>,
    velocities: Vec<f64>,
    index: usize,
    filled: usize,
    sum: f64,
    window_s: f64,
}

impl RigidVelocity {
    fn new(ts: f64, position_m: f64) -> Self {
        let n = ((RIGID_VELOCITY_WINDOW_S / ts).round() as usize).max(1);
        RigidVelocity {
            positions: vec![position_m; n],
            velocities: vec![0.0; n],
            index: 0,
            filled: 0,
            sum: 0.0,
            window_s: n as f64 * ts,
        }
    }

    /// Add the position of one sample; returns the estimate, m/s.
    fn step(&mut self, position_m: f64) -> f64 {
        let n = self.positions.len();
        let oldest = self.positions[self.index];
        let v = (position_m - oldest) / self.window_s;
        self.positions[self.index] = position_m;
        self.sum += v - self.velocities[self.index];
        self.velocities[self.index] = v;
        self.index = (self.index + 1) % n;
        self.filled = (self.filled + 1).min(n);
        if self.filled == n && self.index == 0 {
            // refresh the running sum once per window against rounding drift
            self.sum = self.velocities.iter().sum();
        }
        self.sum / n as f64
    }
}
/// How much history a [`SafetyStopRecord`] holds: the samples of the last
/// second before the violation, s.
pub const STOP_HISTORY_S: f64 = 1.0;

/// One recorded sample of a stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Sample {
    /// Torque command sent to the drive, N m.
    pub torque_command_nm: f64,
    /// Measured actual torque, N m.
    pub torque_actual_nm: f64,
    /// Motor angle from the encoder, rad.
    pub motor_angle_rad: f64,
    /// Motor-side cart position `origin + i_t phi_m`, m.
    pub position_m: f64,
    /// Cart position from the evaluation encoder (simulation truth), m.
    pub cart_position_m: Option<f64>,
}

/// One sample of the history kept for a safety stop's diagnostic.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct HistorySample {
    /// Busy time of the axis at this sample (since the runner started), s.
    pub time_s: f64,
    /// The sample.
    #[serde(flatten)]
    pub sample: Sample,
    /// Filtered motor-side cart velocity the supervisor judged, m/s.
    pub velocity_m_s: f64,
    /// Following error the supervisor judged, m (`None` in open-loop stages
    /// and during a stop).
    pub following_error_m: Option<f64>,
}

/// What the runner knew when the supervisor stopped the axis, handed to
/// [`Progress::safety_stopped`] before [`Error::SafetyStop`] is returned.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SafetyStopRecord {
    /// Which limit was violated, with the values.
    pub violation: Violation,
    /// The limits the supervisor enforced.
    pub limits: SafetyLimits,
    /// Busy time of the axis at the violation, s.
    pub time_s: f64,
    /// Position the supervisor judged, m.
    pub position_m: f64,
    /// Velocity the supervisor judged, m/s.
    pub velocity_m_s: f64,
    /// Torque command that was refused (after saturation), N m.
    pub torque_command_nm: f64,
    /// Following error that was judged, m (`None` in open-loop stages).
    pub following_error_m: Option<f64>,
    /// Where the stop brought the axis to rest, m (`None` if the stop failed).
    pub stop_position_m: Option<f64>,
    /// Why the stop itself failed, if it did.
    pub stop_error: Option<String>,
    /// The samples of the last [`STOP_HISTORY_S`] before the violation, oldest first.
    pub history: Vec<HistorySample>,
}

/// What the runner knew when an exchange with the axis failed, handed to
/// [`Progress::exchange_failed`] before [`Error::Axis`] is returned.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisFailureRecord {
    /// Why the exchange failed.
    pub error: crate::axis::AxisError,
    /// Why the drive's quick stop failed too, if it did.
    pub quick_stop: Option<crate::axis::AxisError>,
    /// The limits the supervisor enforced.
    pub limits: SafetyLimits,
    /// Busy time of the axis at the failed exchange, s.
    pub time_s: f64,
    /// Motor-side cart position of the last good exchange, m.
    pub position_m: f64,
    /// Filtered velocity of the last good exchange, m/s.
    pub velocity_m_s: f64,
    /// Torque command of the failed exchange, N m.
    pub torque_command_nm: f64,
    /// Following error of the failed exchange, m (`None` in open loop).
    pub following_error_m: Option<f64>,
    /// The samples of the last [`STOP_HISTORY_S`] before the failure, oldest first.
    pub history: Vec<HistorySample>,
}

/// Drives the axis for the whole procedure.
pub struct Runner<'a> {
    axis: &'a mut dyn Axis,
    progress: &'a mut dyn Progress,
    info: AxisInfo,
    supervisor: SafetySupervisor,
    i_t: f64,
    origin_m: f64,
    samples: u64,
    last: Measurement,
    velocity: FirstOrder<f64>,
    velocity_m_s: f64,
    rigid: RigidVelocity,
    rigid_velocity_m_s: f64,
    /// Whether the last step was open loop (no following error).
    open_loop: bool,
    /// Controller used to stop the axis (the bootstrap controller until a design exists).
    stop_controller: CascadeConfig<f64>,
    stop_limits: Limits,
    /// Ring buffer of the last [`STOP_HISTORY_S`] of samples.
    history: VecDeque<HistorySample>,
    history_len: usize,
}

impl<'a> Runner<'a> {
    /// A runner for `axis`. `origin_m` is the cart position at encoder count 0
    /// (from homing); `i_t` converts the motor angle to belt travel, m/rad.
    pub fn new(
        axis: &'a mut dyn Axis,
        progress: &'a mut dyn Progress,
        supervisor: SafetySupervisor,
        i_t: f64,
        origin_m: f64,
        stop_controller: CascadeConfig<f64>,
        stop_limits: Limits,
    ) -> Result<Self> {
        let info = axis.info();
        crate::error::require_positive("ts_s", info.ts_s)?;
        crate::error::require_positive("motor_rad_per_count", info.motor_rad_per_count)?;
        crate::error::require_positive("i_t", i_t)?;
        crate::error::require_finite("origin_m", origin_m)?;
        let coeffs = velocity_filter(crate::design::DEFAULT_T_R_S, info.ts_s)?;
        let mut velocity = FirstOrder::new(coeffs);
        velocity.reset_to(origin_m, 0.0);
        let rigid = RigidVelocity::new(info.ts_s, origin_m);
        let history_len = ((STOP_HISTORY_S / info.ts_s).ceil() as usize).max(1);
        Ok(Runner {
            axis,
            progress,
            info,
            supervisor,
            i_t,
            origin_m,
            samples: 0,
            last: Measurement::default(),
            velocity,
            velocity_m_s: 0.0,
            rigid,
            rigid_velocity_m_s: 0.0,
            open_loop: false,
            stop_controller,
            stop_limits,
            history: VecDeque::with_capacity(history_len),
            history_len,
        })
    }

    /// Static facts of the axis.
    pub fn info(&self) -> AxisInfo {
        self.info
    }

    /// Transmission `i_t`, m/rad.
    pub fn i_t(&self) -> f64 {
        self.i_t
    }

    /// Cart position at encoder count 0, m.
    pub fn origin_m(&self) -> f64 {
        self.origin_m
    }

    /// The supervisor.
    pub fn supervisor(&self) -> &SafetySupervisor {
        &self.supervisor
    }

    /// Replace the stop capability of the supervisor and of the stop
    /// trajectory (when holding torque, inertia or friction become known).
    pub fn set_stop_capability(&mut self, capability: super::safety::StopCapability) -> Result<()> {
        self.supervisor.set_capability(capability)
    }

    /// Replace the controller used for stops (after the design).
    pub fn set_stop_controller(&mut self, config: CascadeConfig<f64>) {
        self.stop_controller = config;
    }

    /// The progress sink.
    pub fn progress(&mut self) -> &mut dyn Progress {
        &mut *self.progress
    }

    /// Samples the axis has been busy so far.
    pub fn busy_samples(&self) -> u64 {
        self.samples
    }

    /// Busy time so far, s.
    pub fn busy_time_s(&self) -> f64 {
        self.samples as f64 * self.info.ts_s
    }

    /// The last measurement.
    pub fn last(&self) -> Measurement {
        self.last
    }

    /// Motor angle of the last measurement, rad.
    pub fn motor_angle_rad(&self) -> f64 {
        self.last.motor_counts as f64 * self.info.motor_rad_per_count
    }

    /// Motor-side cart position of the last measurement, m.
    pub fn position_m(&self) -> f64 {
        self.origin_m + self.i_t * self.motor_angle_rad()
    }

    /// Filtered motor-side cart velocity, m/s.
    pub fn velocity_m_s(&self) -> f64 {
        self.velocity_m_s
    }

    /// Rigid-body cart velocity (the belt resonance averaged out), m/s.
    pub fn rigid_velocity_m_s(&self) -> f64 {
        self.rigid_velocity_m_s
    }

    /// The velocity the supervisor and the stop use: in open loop the
    /// rigid-body estimate (the motor-side vibration at the resonance is no
    /// cart motion), in closed loop the fast estimate.
    fn supervised_velocity_m_s(&self) -> f64 {
        if self.open_loop {
            self.rigid_velocity_m_s
        } else {
            self.velocity_m_s
        }
    }

    /// Cart position for a motor angle, m.
    pub fn angle_to_position_m(&self, angle_rad: f64) -> f64 {
        self.origin_m + self.i_t * angle_rad
    }

    /// Motor angle for a cart position, rad.
    pub fn position_to_angle_rad(&self, position_m: f64) -> f64 {
        (position_m - self.origin_m) / self.i_t
    }

    /// Apply one torque command (saturated to the axis' limit) after the
    /// supervisor approved the state; on a violation, stop and return the
    /// error. A failed exchange ends in the drive's quick stop and
    /// [`Error::Axis`].
    pub fn step(&mut self, torque_nm: f64, following_error_m: Option<f64>) -> Result<Sample> {
        self.step_tracking(torque_nm, following_error_m, true)
    }

    /// [`Runner::step`] in closed loop whose following error `following_error_m`
    /// is recorded but not limited: a move whose lag is expected (the
    /// validation's comparison variants without feedforward). The
    /// look-ahead is the closed loop's; travel, velocity and torque are
    /// supervised as always.
    pub fn step_unlimited(&mut self, torque_nm: f64, following_error_m: f64) -> Result<Sample> {
        self.step_tracking(torque_nm, Some(following_error_m), false)
    }

    fn step_tracking(
        &mut self,
        torque_nm: f64,
        following_error_m: Option<f64>,
        limit_following_error: bool,
    ) -> Result<Sample> {
        let limit = self
            .info
            .torque_max_nm
            .min(self.supervisor.limits().torque_max_nm);
        let torque = if torque_nm.is_finite() {
            torque_nm.clamp(-limit, limit)
        } else {
            f64::NAN
        };
        self.open_loop = following_error_m.is_none();
        // In closed loop the fast estimate, where the rigid-body estimate
        // confirms it (a chattering loop on a coarse encoder shows
        // 0.5 m/s spikes over a creeping cart, which tripped the look-ahead);
        // where the smaller rigid-body estimate is judged, the look-ahead
        // adds its lag.
        let (velocity, lag) = if self.open_loop {
            (self.rigid_velocity_m_s, 0.0)
        } else {
            self.closed_loop_velocity()
        };
        // a tracking loop whose error is not limited is judged as one with no
        // error (the closed loop's look-ahead)
        let judged = following_error_m.map(|e| if limit_following_error { e } else { 0.0 });
        if let Err(v) =
            self.supervisor
                .check_lagged(self.position_m(), velocity, lag, torque, judged)
        {
            return Err(self.stop_after(v, torque, following_error_m));
        }
        self.raw_step(torque, following_error_m)
    }

    /// The velocity the closed loop's look-ahead judges and its lag, m/s and
    /// s: the fast estimate where the rigid-body estimate confirms it, else
    /// the smaller one with the rigid estimate's lag.
    fn closed_loop_velocity(&self) -> (f64, f64) {
        let v = stop_start_velocity(self.velocity_m_s, self.rigid_velocity_m_s);
        let lag = if v.abs() < self.velocity_m_s.abs() {
            RIGID_VELOCITY_WINDOW_S
        } else {
            0.0
        };
        (v, lag)
    }

    /// Whether a closed-loop stage could take the axis over now with
    /// `margin_m` to spare: the position is `margin_m` inside the travel
    /// window, and the closed loop's look-ahead (as [`Runner::step`] judges
    /// its first sample) passes from `margin_m` further in the direction of
    /// motion. An open-loop excitation ends early where it does not (issue
    /// 12: seed 13 plant #787's PRBS drifted 57 mm, to 2.5 mm from the edge,
    /// and the next stage's first closed-loop sample tripped).
    pub fn closed_loop_handover_clear(&self, margin_m: f64) -> bool {
        let l = self.supervisor.limits();
        let pos = self.position_m();
        if !(pos - margin_m >= l.travel_min_m && pos + margin_m <= l.travel_max_m) {
            return false;
        }
        let (v, lag) = self.closed_loop_velocity();
        let ahead = pos + if v < 0.0 { -margin_m } else { margin_m };
        self.supervisor
            .check_lagged(ahead, v, lag, 0.0, Some(0.0))
            .is_ok()
    }

    fn raw_step(&mut self, torque_nm: f64, following_error_m: Option<f64>) -> Result<Sample> {
        let m = match self.axis.exchange(torque_nm) {
            Ok(m) => m,
            Err(error) => {
                // The host can no longer control the axis: the drive stops it.
                let quick_stop = self.axis.quick_stop().err();
                let record = AxisFailureRecord {
                    error,
                    quick_stop,
                    limits: *self.supervisor.limits(),
                    time_s: self.busy_time_s(),
                    position_m: self.position_m(),
                    velocity_m_s: self.velocity_m_s,
                    torque_command_nm: torque_nm,
                    following_error_m,
                    history: self.history.iter().copied().collect(),
                };
                self.progress.exchange_failed(&record);
                return Err(Error::Axis { error, quick_stop });
            }
        };
        self.last = m;
        self.samples += 1;
        self.progress.advance(1);
        let pos = self.position_m();
        self.velocity_m_s = self.velocity.step(pos);
        self.rigid_velocity_m_s = self.rigid.step(pos);
        let sample = Sample {
            torque_command_nm: torque_nm,
            torque_actual_nm: m.torque_actual_nm,
            motor_angle_rad: self.motor_angle_rad(),
            position_m: pos,
            cart_position_m: m.cart_position_m,
        };
        if self.history.len() == self.history_len {
            self.history.pop_front();
        }
        self.history.push_back(HistorySample {
            time_s: self.busy_time_s(),
            sample,
            velocity_m_s: self.velocity_m_s,
            following_error_m,
        });
        Ok(sample)
    }

    /// Run the computation `f` without leaving the axis unsupervised. For an
    /// axis whose time runs in real time ([`Axis::runs_in_real_time`]), `f`
    /// runs on a scoped thread while this thread keeps the axis in closed loop
    /// every cycle: the stop controller (bootstrap or designed) holds the
    /// position the axis had when the computation started, under the
    /// supervisor (following error included). An error of the hold (a
    /// violation, a failed exchange) is returned after `f` has finished; a
    /// panic in `f` is resumed here. For a simulated axis `f` just runs
    /// (its time stands still meanwhile).
    pub fn hold_while<T: Send>(&mut self, f: impl FnOnce() -> T + Send) -> Result<T> {
        if !self.axis.runs_in_real_time() {
            return Ok(f());
        }
        let mut ctrl = CascadeController::new(self.stop_controller)?;
        let hold_angle = self.motor_angle_rad();
        ctrl.reset_to(hold_angle);
        let sp = Setpoint::at(MotionSample {
            angle_rad: hold_angle,
            velocity_rad_s: 0.0,
            acceleration_rad_s2: 0.0,
        });
        std::thread::scope(|scope| {
            let job = scope.spawn(f);
            let mut held = Ok(());
            while !job.is_finished() {
                let out = ctrl.step(&sp, self.motor_angle_rad());
                let following = (self.motor_angle_rad() - hold_angle) * self.i_t;
                if let Err(e) = self.step(out.torque_nm, Some(following)) {
                    held = Err(e);
                    break;
                }
            }
            let value = match job.join() {
                Ok(v) => v,
                Err(panic) => std::panic::resume_unwind(panic),
            };
            held.map(|()| value)
        })
    }

    /// Stop after a violation, hand the record to the progress sink and turn
    /// the violation into the error that ends the command.
    fn stop_after(
        &mut self,
        v: Violation,
        torque_command_nm: f64,
        following_error_m: Option<f64>,
    ) -> Error {
        let history: Vec<HistorySample> = self.history.iter().copied().collect();
        let (time_s, position_m, velocity_m_s) =
            (self.busy_time_s(), self.position_m(), self.velocity_m_s);
        let stop = self.stop();
        let mut reason = v.to_string();
        match &stop {
            Ok(at) => reason.push_str(&format!("; axis stopped at {:.1} mm", at * 1e3)),
            Err(e) => reason.push_str(&format!("; the stop itself failed: {e}")),
        }
        let record = SafetyStopRecord {
            violation: v,
            limits: *self.supervisor.limits(),
            time_s,
            position_m,
            velocity_m_s,
            torque_command_nm,
            following_error_m,
            stop_position_m: stop.as_ref().ok().copied(),
            stop_error: stop.err().map(|e| e.to_string()),
            history,
        };
        self.progress.safety_stopped(&record);
        Error::SafetyStop { reason }
    }

    /// Mean torque command, N m: what has been holding the load, the loop's
    /// vibration and an excitation averaged out; 0 before any sample. Over
    /// the last [`RIGID_VELOCITY_WINDOW_S`] in closed loop, over the whole
    /// history ([`STOP_HISTORY_S`]) in open loop or within that window of
    /// it (a closed-loop stage may have just begun). In open loop the
    /// command is the holding torque plus a PRBS, which averages out over
    /// many of its bits, not over 20 ms (seed 13 plant #787: 20 ms
    /// of mostly one PRBS level preloaded the stop 0.44 N m short of the
    /// 1.84 N m that held a load on a 59 deg slope; the load pushed the
    /// stop 6.9 mm on, 3.8 mm out of the window).
    fn recent_torque_nm(&self) -> f64 {
        let short = ((RIGID_VELOCITY_WINDOW_S / self.info.ts_s).round() as usize).max(1);
        let open = self.open_loop
            || self
                .history
                .iter()
                .rev()
                .take(short)
                .any(|h| h.following_error_m.is_none());
        let n = if open {
            ((STOP_HISTORY_S / self.info.ts_s).round() as usize).max(1)
        } else {
            short
        };
        let (sum, count) = self
            .history
            .iter()
            .rev()
            .take(n)
            .fold((0.0, 0usize), |(s, c), h| {
                (s + h.sample.torque_command_nm, c + 1)
            });
        if count == 0 || !sum.is_finite() {
            0.0
        } else {
            sum / count as f64
        }
    }

    /// Bring the axis to rest with a jerk-limited stop under the stop
    /// controller; returns the rest position, m. The supervisor is not asked
    /// during the stop (it is the reaction), but the torque stays limited.
    pub fn stop(&mut self) -> Result<f64> {
        let ts = self.info.ts_s;
        let v = stop_start_velocity(self.supervised_velocity_m_s(), self.rigid_velocity_m_s);
        let p = self.position_m();
        // Brake with what the axis has in this direction (gravity),
        // never harder than the configured stop limits.
        let a_stop = stop_deceleration(
            self.supervisor.capability(),
            self.supervisor.limits(),
            self.stop_limits.a_max.min(-self.stop_limits.a_min),
            p,
            v,
        );
        let jerk = super::safety::STOP_JERK_PER_DECELERATION * a_stop;
        let rest = p + v.signum() * stop_distance_m(v, a_stop);
        let limits = Limits {
            position_min: f64::NEG_INFINITY,
            position_max: f64::INFINITY,
            a_max: a_stop,
            a_min: -a_stop,
            j_max: jerk,
            j_min: -jerk,
            ..self.stop_limits
        };
        let start = State {
            position: p,
            velocity: v,
            acceleration: 0.0,
        };
        let traj = Trajectory::plan(&start, &State::at_rest(rest), &limits)?;
        // A designed cascade comes without feedforward (the validation adds
        // it): the stop's deceleration is fed forward with the inertia the
        // capability was computed for, so that the feedback does not have to
        // build the braking torque from a growing error (a heavy
        // cart braking downhill overshot its stop by 20 mm).
        let mut config = self.stop_controller;
        let inertia = self.supervisor.capability().inertia_kg_m2;
        if !config.feedforward.terms.inertia && inertia > 0.0 {
            config.feedforward = beltune_rt::control::Feedforward::linear(inertia, 0.0);
        }
        let mut ctrl = CascadeController::new(config)?;
        // Bumpless: the stop continues from the torque the axis was getting
        // (a reset integrator dropped the 3.1 N m that held a
        // heavy vertical load, which fell 65 mm instead of 10 mm).
        let w0 = v / self.i_t;
        let feedforward = config.feedforward.torque_nm(w0, 0.0);
        ctrl.reset_to_holding(
            self.motor_angle_rad(),
            self.recent_torque_nm() - feedforward,
        );
        let n = ((traj.duration_s() + STOP_SETTLE_S) / ts).ceil() as u64;
        let limit = self.info.torque_max_nm;
        // Hold on after the settling time until the axis is at rest (an
        // open-loop stop starts from the rigid-body velocity, which lags a
        // hard acceleration), at most STOP_REST_MAX_S longer.
        let extra = (STOP_REST_MAX_S / ts).ceil() as u64;
        // A stop controller that does not follow its trajectory (unstable on
        // this axis) is dropped for a damping brake on the rigid-body velocity.
        let diverged_m = STOP_DIVERGENCE_SHARE * self.supervisor.limits().following_error_max_m;
        // N s/m at the cart; without a known inertia (before the axis is
        // taken) the torque limit is reached at STOP_BRAKE_FULL_SPEED_M_S.
        let damping = if inertia > 0.0 {
            inertia / (STOP_BRAKE_TIME_S * self.i_t * self.i_t)
        } else {
            limit / (self.i_t * STOP_BRAKE_FULL_SPEED_M_S)
        };
        let mut braking = false;
        for k in 0..n + extra {
            let at_rest = if braking {
                self.rigid_velocity_m_s.abs() < STOP_REST_SPEED_M_S
            } else {
                self.velocity_m_s.abs() < STOP_REST_SPEED_M_S
            };
            if k >= n && at_rest {
                break;
            }
            let s = traj.sample(k as f64 * ts);
            braking |= (self.position_m() - s.position).abs() > diverged_m;
            let tau = if braking {
                // N s/m at the cart times m/s, as a motor torque.
                config.torque_offset_nm - damping * self.i_t * self.rigid_velocity_m_s
            } else {
                let sp = Setpoint::at(MotionSample {
                    angle_rad: self.position_to_angle_rad(s.position),
                    velocity_rad_s: s.velocity / self.i_t,
                    acceleration_rad_s2: s.acceleration / self.i_t,
                });
                ctrl.step(&sp, self.motor_angle_rad()).torque_nm
            };
            let tau = if tau.is_finite() {
                tau.clamp(-limit, limit)
            } else {
                0.0
            };
            self.raw_step(tau, None)?;
        }
        Ok(self.position_m())
    }
}

/// The velocity a stop starts its trajectory from: the supervised estimate,
/// but never beyond the rigid-body estimate in magnitude, and zero when the
/// two disagree in sign. A chattering closed loop on a coarse
/// encoder showed 0.5 m/s spikes in the fast estimate while the cart crept
/// at 0.02 m/s; the stop planned from the spike drove the axis 58 mm on,
/// out of the window. A real motion shows in both (the rigid estimate lags
/// a hard acceleration by its 20 ms window: the stop then starts slower
/// and its controller brakes the difference).
fn stop_start_velocity(supervised_m_s: f64, rigid_m_s: f64) -> f64 {
    if !(supervised_m_s.is_finite() && rigid_m_s.is_finite()) || supervised_m_s * rigid_m_s <= 0.0 {
        return 0.0;
    }
    supervised_m_s.signum() * supervised_m_s.abs().min(rigid_m_s.abs())
}

/// Braking distance of a jerk-limited stop from `(v, a = 0)` with the
/// deceleration `a` and the jerk [`super::safety::STOP_JERK_PER_DECELERATION`]
/// times it: the ramp adds `|v| a / (2 j)` to `v^2 / (2 a)`, m.
fn stop_distance_m(velocity_m_s: f64, deceleration_m_s2: f64) -> f64 {
    let v = velocity_m_s.abs();
    v * v / (2.0 * deceleration_m_s2) + v / (2.0 * super::safety::STOP_JERK_PER_DECELERATION)
}

/// The deceleration of a stop from `position_m` at `velocity_m_s`: the
/// planned one of the direction (at most `configured_m_s2`, the stop
/// limits); if that stop would end closer than
/// [`super::safety::STOP_EDGE_MARGIN_M`] to the window's edge (or beyond
/// it), as much more as it takes to stop there, up to the capability's
/// reserve (the look-ahead trips when the planned stop would end
/// outside, so a stop with the planned deceleration always did).
fn stop_deceleration(
    capability: &super::safety::StopCapability,
    limits: &SafetyLimits,
    configured_m_s2: f64,
    position_m: f64,
    velocity_m_s: f64,
) -> f64 {
    let v = velocity_m_s;
    let planned = capability.deceleration_for(v).min(configured_m_s2);
    if v == 0.0 {
        return planned;
    }
    let edge = if v > 0.0 {
        limits.travel_max_m - super::safety::STOP_EDGE_MARGIN_M
    } else {
        limits.travel_min_m + super::safety::STOP_EDGE_MARGIN_M
    };
    let room = (edge - position_m) * v.signum();
    if stop_distance_m(v, planned) <= room {
        return planned;
    }
    let reserve = capability.reserve_deceleration_for(v).max(planned);
    // v^2 / (2 a) + |v| / (2 k) <= room
    let braking_room = room - v.abs() / (2.0 * super::safety::STOP_JERK_PER_DECELERATION);
    if braking_room <= 0.0 {
        return reserve;
    }
    (v * v / (2.0 * braking_room)).clamp(planned, reserve)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axis::AxisError;
    use crate::commission::bootstrap::bootstrap_controller;
    use crate::commission::progress::NoProgress;
    use crate::commission::safety::SafetyLimits;
    use crate::model::rigs;
    use crate::sim::{SimAxis, SimConfig};

    /// Stop limits of the runner tests (window 0 .. 0.6 m).
    const TEST_STOP_LIMITS: Limits = Limits {
        v_max: 0.5,
        v_min: -0.5,
        a_max: 5.0,
        a_min: -5.0,
        j_max: 100.0,
        j_min: -100.0,
        position_min: 0.0,
        position_max: 0.6,
    };

    /// The simulated `plant` with its cart at `start_m`.
    fn sim_at(plant: &rigs::Plant, start_m: f64) -> SimAxis {
        SimAxis::new(
            plant,
            SimConfig {
                initial_cart_position_m: Some(start_m),
                ..SimConfig::default()
            },
        )
        .unwrap()
    }

    /// The supervisor of the runner tests: window 0 .. 0.6 m, torque limit
    /// `torque_max_nm`, speed `velocity_max_m_s` and following error
    /// `following_error_max_m` limits, stop deceleration 5 m/s^2.
    fn test_supervisor(
        torque_max_nm: f64,
        velocity_max_m_s: f64,
        following_error_max_m: f64,
    ) -> SafetySupervisor {
        let limits = SafetyLimits {
            travel_min_m: 0.0,
            travel_max_m: 0.6,
            torque_max_nm,
            velocity_max_m_s,
            following_error_max_m,
        };
        SafetySupervisor::new(limits, 5.0).unwrap()
    }

    /// A simulated axis that claims real time and counts its exchanges.
    struct RealTime {
        sim: SimAxis,
        real_time: bool,
        /// The exchange count, shared with the computation thread.
        exchanges: std::sync::Arc<std::sync::atomic::AtomicU64>,
    }

    impl Axis for RealTime {
        fn info(&self) -> AxisInfo {
            self.sim.info()
        }
        fn exchange(
            &mut self,
            torque_command_nm: f64,
        ) -> std::result::Result<Measurement, AxisError> {
            self.exchanges
                .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            // a bus cycle takes time: the computation thread runs meanwhile
            std::thread::sleep(std::time::Duration::from_micros(100));
            self.sim.exchange(torque_command_nm)
        }
        fn quick_stop(&mut self) -> std::result::Result<(), AxisError> {
            Ok(())
        }
        fn runs_in_real_time(&self) -> bool {
            self.real_time
        }
    }

    /// Run `f` with a runner on egc70 (`real_time`: the axis says it runs in
    /// real time); `f` also gets the exchange count the axis keeps.
    fn with_runner<R>(
        real_time: bool,
        f: impl FnOnce(&mut Runner, &std::sync::atomic::AtomicU64) -> R,
    ) -> (R, u64, f64) {
        let shared = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let plant = rigs::builtin("egc70", None).unwrap();
        let info = plant.info();
        let start = 0.3;
        let mut axis = RealTime {
            sim: sim_at(&plant, start),
            real_time,
            exchanges: shared.clone(),
        };
        let i_t = 0.078 / (2.0 * std::f64::consts::PI);
        let j = 1.4e-4 + i_t * i_t * 12.16;
        let ctrl = bootstrap_controller(j, i_t, info.ts_s, info.torque_max_nm).unwrap();
        let sup = SafetySupervisor::new(
            SafetyLimits {
                travel_min_m: 0.0,
                travel_max_m: 0.6,
                torque_max_nm: info.torque_max_nm,
                velocity_max_m_s: 1.0,
                following_error_max_m: 0.01,
            },
            5.0,
        )
        .unwrap();
        let limits = crate::commission::config::positioning_limits_in(0.0, 0.6);
        let mut progress = NoProgress;
        let (r, drift) = {
            let mut runner =
                Runner::new(&mut axis, &mut progress, sup, i_t, start, ctrl, limits).unwrap();
            let r = f(&mut runner, &shared);
            (r, (runner.position_m() - start).abs())
        };
        (r, shared.load(std::sync::atomic::Ordering::SeqCst), drift)
    }

    #[test]
    fn a_real_time_axis_is_held_in_closed_loop_while_the_computation_runs() {
        // The computation ends once the axis has been held for HELD cycles
        // (counted by the axis, not timed: a loaded machine stretches every
        // sleep, and a timed wait once saw fewer cycles than it asked for).
        const HELD: u64 = 50;
        let ((value, during), exchanges, drift) = with_runner(true, |runner, count| {
            let before = runner.busy_samples();
            let start = count.load(std::sync::atomic::Ordering::SeqCst);
            let v = runner
                .hold_while(|| {
                    let t0 = std::time::Instant::now();
                    while count.load(std::sync::atomic::Ordering::SeqCst) < start + HELD
                        && t0.elapsed() < std::time::Duration::from_secs(60)
                    {
                        std::thread::sleep(std::time::Duration::from_micros(200));
                    }
                    42
                })
                .unwrap();
            (v, runner.busy_samples() - before)
        });
        assert_eq!(value, 42);
        assert!(during >= HELD, "{during} cycles held");
        assert_eq!(exchanges, during);
        // the axis (vertical load none, friction) stays where it was
        assert!(drift < 1e-3, "drift {drift} m");
    }

    #[test]
    fn a_simulated_axis_waits_for_the_computation() {
        let (during, exchanges, _) = with_runner(false, |runner, _| {
            let before = runner.busy_samples();
            runner
                .hold_while(|| std::thread::sleep(std::time::Duration::from_millis(5)))
                .unwrap();
            runner.busy_samples() - before
        });
        assert_eq!((during, exchanges), (0, 0));
    }

    /// False open-loop travel trips: the motor side vibrating at
    /// the resonance with 0.85 m/s peak while the cart drifts at 0.1 m/s must
    /// read as 0.1 m/s to the look-ahead. Worst case inside the band the
    /// filter claims (above 80 Hz: gain below 4 %): 0.85 * 0.04 = 0.034 m/s.
    #[test]
    fn the_rigid_velocity_ignores_the_resonance_vibration() {
        let ts = 100e-6;
        for f in [50.0, 80.0, 111.0, 150.0, 400.0] {
            let w = 2.0 * std::f64::consts::PI * f;
            let amp = 0.85 / w;
            let mut rv = RigidVelocity::new(ts, 0.0);
            let mut worst: f64 = 0.0;
            for k in 0..20_000 {
                let t = k as f64 * ts;
                let v = rv.step(0.1 * t + amp * (w * t).sin());
                if t > 0.05 {
                    worst = worst.max((v - 0.1).abs());
                }
            }
            assert!(worst < 0.035, "{f} Hz: error {worst} m/s");
        }
        // a genuine speed change shows within two windows
        let mut rv = RigidVelocity::new(ts, 0.0);
        let mut v = 0.0;
        for k in 0..400 {
            v = rv.step(0.3 * k as f64 * ts);
        }
        assert!((v - 0.3).abs() < 1e-9, "{v}");
    }

    /// Stops ending outside the window: the look-ahead trips when
    /// the planned stop would end outside, so a stop with the planned
    /// deceleration always did; it brakes with the reserve to end
    /// STOP_EDGE_MARGIN_M inside instead, and with the planned one where
    /// there is room.
    #[test]
    fn a_stop_near_the_edge_brakes_with_its_reserve() {
        use crate::commission::safety::{StopCapability, STOP_EDGE_MARGIN_M};
        let cap = StopCapability::from_axis(3.1, 2e-3, 0.0124, 0.3, 0.0).unwrap();
        let limits = SafetyLimits {
            travel_min_m: -0.01,
            travel_max_m: 0.57,
            torque_max_nm: 3.1,
            velocity_max_m_s: 2.5,
            following_error_max_m: 0.05,
        };
        let planned = cap.deceleration_negative_m_s2;
        assert!(cap.reserve_deceleration_negative_m_s2 > planned);
        // plenty of room: the planned deceleration
        assert_eq!(stop_deceleration(&cap, &limits, 100.0, 0.3, -0.5), planned);
        // downhill towards the lower edge, the planned stop ends outside
        let (p, v) = (0.015, -0.5);
        assert!(p - stop_distance_m(v, planned) < limits.travel_min_m + STOP_EDGE_MARGIN_M);
        let a = stop_deceleration(&cap, &limits, 100.0, p, v);
        assert!(a > planned && a <= cap.reserve_deceleration_negative_m_s2);
        let rest = p - stop_distance_m(v, a);
        assert!(
            (rest - (limits.travel_min_m + STOP_EDGE_MARGIN_M)).abs() < 1e-9,
            "rest {rest}"
        );
        // beyond the reserve: all of it
        let a = stop_deceleration(&cap, &limits, 100.0, -0.005, -2.0);
        assert_eq!(a, cap.reserve_deceleration_negative_m_s2);
    }

    /// A heavy load fell 65 mm in its stop, 56.8 mm out of the
    /// window: plant #839: the stop continues from the torque that held
    /// the load (the mean of the last 20 ms of commands), not from a reset
    /// integrator and the stop controller's offset. A 20 kg cart on a
    /// vertical egc70 held by its holding torque (2.5 N m) stays where it
    /// is when stopped; from zero torque it would fall until the loop
    /// built 2.5 N m again.
    #[test]
    fn a_stop_keeps_the_torque_that_held_the_load() {
        let mut p = rigs::egc70_params(20.0);
        p.tilt_rad = 90f64.to_radians();
        let hold = -p.i_t() * p.gravity_force_n();
        assert!(hold.abs() > 2.0, "{hold}");
        let plant = rigs::Plant::Physical(p.clone());
        let info = plant.info();
        let start = 0.3;
        let mut axis = sim_at(&plant, start);
        let j = plant.worst_case_two_mass().unwrap().rigid_inertia();
        let boot = bootstrap_controller(j, p.i_t(), info.ts_s, info.torque_max_nm).unwrap();
        assert_eq!(boot.torque_offset_nm, 0.0);
        let supervisor = test_supervisor(info.torque_max_nm, 2.5, 0.05);
        let mut progress = NoProgress;
        let mut runner = Runner::new(
            &mut axis,
            &mut progress,
            supervisor,
            p.i_t(),
            start,
            boot,
            TEST_STOP_LIMITS,
        )
        .unwrap();
        // held open loop by its holding torque until the belt has settled
        for _ in 0..(0.5 / info.ts_s) as usize {
            runner.step(hold, None).unwrap();
        }
        let before = runner.position_m();
        let rest = runner.stop().unwrap();
        assert!(
            (rest - before).abs() < 1e-3,
            "held at {:.2} mm, stopped at {:.2} mm",
            before * 1e3,
            rest * 1e3
        );
    }

    /// A 0.5 m/s spike of the fast estimate over a creeping cart
    /// starts no stop trajectory at 0.5 m/s; a real motion does.
    #[test]
    fn a_stop_starts_from_a_confirmed_velocity() {
        assert_eq!(stop_start_velocity(0.5, 0.02), 0.02);
        assert_eq!(stop_start_velocity(-0.5, -0.6), -0.5);
        assert_eq!(stop_start_velocity(0.5, -0.01), 0.0);
        assert_eq!(stop_start_velocity(f64::NAN, 0.3), 0.0);
    }

    /// A stop whose controller is unstable on the axis (stop 13: a bootstrap
    /// loop that the cart's stiction had kept quiet oscillated once the cart
    /// slid, and the stop kept that loop and ran 3.7 m past the window in the
    /// simulation) falls back to damping the rigid-body velocity: it ends at
    /// rest, near where it started.
    #[test]
    fn a_stop_with_an_unstable_controller_brakes_by_damping() {
        let plant = rigs::builtin("egc70", None).unwrap();
        let start = 0.3;
        let mut axis = sim_at(&plant, start);
        let info = plant.info();
        let model = plant.worst_case_two_mass().unwrap();
        let (i_t, j) = (model.i_t, model.rigid_inertia());
        let mut unstable = bootstrap_controller(j, i_t, info.ts_s, info.torque_max_nm).unwrap();
        // 300 times the velocity gain: crossover far beyond the dead time.
        unstable.gains.k_p_nm_s_per_rad *= 300.0;
        let mut progress = NoProgress;
        let mut runner = Runner::new(
            &mut axis,
            &mut progress,
            test_supervisor(info.torque_max_nm, 2.5, 0.05),
            i_t,
            start,
            unstable,
            TEST_STOP_LIMITS,
        )
        .unwrap();
        runner
            .set_stop_capability(
                super::super::safety::StopCapability::from_axis(
                    info.torque_max_nm,
                    j,
                    i_t,
                    0.0,
                    0.0,
                )
                .unwrap(),
            )
            .unwrap();
        // Push the cart to about 0.1 m/s, then stop.
        while runner.rigid_velocity_m_s() < 0.1 {
            runner.step(0.5, None).unwrap();
        }
        let from = runner.position_m();
        let rest = runner.stop().unwrap();
        assert!(rest.is_finite());
        assert!(
            (rest - from).abs() < 0.05,
            "the stop from {from:.4} m ended at {rest:.4} m"
        );
        assert!(
            runner.rigid_velocity_m_s().abs() < 0.01,
            "{}",
            runner.rigid_velocity_m_s()
        );
    }

    /// Seed 13 plant #787: a stop right after an open-loop PRBS
    /// starts from the mean command over the last second (the holding
    /// torque, the PRBS averaged out over its bits), not from the last
    /// 20 ms, which are mostly one PRBS level (0.44 N m short of the load
    /// on #787). egc70, open loop, a PRBS of 20 ms bits around 0.1 N m.
    #[test]
    fn the_stop_preload_after_an_open_loop_excitation_is_its_mean() {
        let plant = rigs::builtin("egc70", None).unwrap();
        let start = 0.3;
        let mut axis = sim_at(&plant, start);
        let info = plant.info();
        let model = plant.worst_case_two_mass().unwrap();
        let boot = bootstrap_controller(
            model.rigid_inertia(),
            model.i_t,
            info.ts_s,
            info.torque_max_nm,
        )
        .unwrap();
        let mut progress = NoProgress;
        let mut runner = Runner::new(
            &mut axis,
            &mut progress,
            test_supervisor(info.torque_max_nm, 2.5, 0.05),
            model.i_t,
            start,
            boot,
            TEST_STOP_LIMITS,
        )
        .unwrap();
        let clock = (20e-3 / info.ts_s).round() as u32;
        let mut prbs = beltune_rt::prbs::Prbs::new(9, clock, 0.6).unwrap();
        let n = (1.5 / info.ts_s) as usize;
        let mut cmd = Vec::with_capacity(n);
        for _ in 0..n {
            cmd.push(
                runner
                    .step(0.1 + prbs.step(), None)
                    .unwrap()
                    .torque_command_nm,
            );
        }
        let mean = |k: usize| cmd[n - k..].iter().sum::<f64>() / k as f64;
        let second = mean(runner.history.len());
        let last_20_ms = mean((RIGID_VELOCITY_WINDOW_S / info.ts_s).round() as usize);
        assert!(
            (last_20_ms - second).abs() > 0.2,
            "the example needs one PRBS level at the end: {last_20_ms} vs {second}"
        );
        let preload = runner.recent_torque_nm();
        assert!(
            (preload - second).abs() < 1e-9,
            "preload {preload} N m, mean of the last second {second} N m"
        );
    }

    /// Keeps the record a safety stop hands over.
    #[derive(Default)]
    struct Recorder(Option<SafetyStopRecord>);
    impl Progress for Recorder {
        fn stage_started(&mut self, _: &str, _: u64) {}
        fn advance(&mut self, _: u64) {}
        fn stage_finished(&mut self, _: &str) {}
        fn safety_stopped(&mut self, record: &SafetyStopRecord) {
            self.0 = Some(record.clone());
        }
    }

    /// Push the light cart of `sim-b` open loop with a constant torque out of a
    /// narrow window: the record holds exactly the last second of samples
    /// before the violation, in order and contiguous, ending at the sample the
    /// supervisor refused to continue from.
    #[test]
    fn a_safety_stop_hands_over_the_last_second_of_samples() {
        let plant = rigs::builtin("sim-b", None).unwrap();
        let start = 0.05;
        let mut axis = sim_at(&plant, start);
        let info = plant.info();
        let i_t = match &plant {
            rigs::Plant::Linear(l) => l.two_mass.i_t,
            rigs::Plant::Physical(p) => p.i_t(),
        };
        let j = plant.worst_case_two_mass().unwrap().rigid_inertia();
        let supervisor = test_supervisor(info.torque_max_nm, 2.5, 0.05);
        let limits = *supervisor.limits();
        let boot = bootstrap_controller(j, i_t, info.ts_s, info.torque_max_nm).unwrap();
        let mut rec = Recorder::default();
        let mut runner = Runner::new(
            &mut axis,
            &mut rec,
            supervisor,
            i_t,
            start,
            boot,
            TEST_STOP_LIMITS,
        )
        .unwrap();
        // A tiny torque first (well under a second of it), then a push.
        let mut steps = 0u64;
        let err = loop {
            let tau = if steps < 20_000 { 0.0 } else { 0.05 };
            match runner.step(tau, None) {
                Ok(_) => steps += 1,
                Err(e) => break e,
            }
            assert!(steps < 2_000_000, "no safety stop");
        };
        assert!(matches!(err, Error::SafetyStop { .. }), "{err}");
        let r = rec.0.expect("no record handed over");
        assert!(
            matches!(
                r.violation,
                Violation::Travel { .. }
                    | Violation::TravelAhead { .. }
                    | Violation::Velocity { .. }
            ),
            "{:?}",
            r.violation
        );
        let ts = info.ts_s;
        let n = (STOP_HISTORY_S / ts).ceil() as usize;
        assert!(
            steps as usize > n,
            "the run must be longer than the history"
        );
        assert_eq!(r.history.len(), n);
        assert_eq!(r.limits, limits);
        let last = r.history.last().unwrap();
        // The violation was judged on the last applied sample: its time, position, velocity.
        assert_eq!(last.time_s, r.time_s);
        assert_eq!(r.time_s, steps as f64 * ts);
        assert_eq!(last.sample.position_m, r.position_m);
        assert_eq!(last.velocity_m_s, r.velocity_m_s);
        for w in r.history.windows(2) {
            assert!((w[1].time_s - w[0].time_s - ts).abs() < 1e-9 * ts.max(1e-3));
        }
        assert!(r
            .history
            .iter()
            .all(|h| h.sample.torque_command_nm == 0.05 || h.sample.torque_command_nm == 0.0));
        assert!(r.stop_position_m.is_some() && r.stop_error.is_none());
        assert_eq!(r.torque_command_nm, 0.05);
    }

    /// A simulated axis whose exchange fails after `good` exchanges.
    struct FailsAfter {
        sim: SimAxis,
        good: u64,
        quick_stops: u32,
    }

    impl Axis for FailsAfter {
        fn info(&self) -> AxisInfo {
            self.sim.info()
        }
        fn exchange(&mut self, torque_nm: f64) -> std::result::Result<Measurement, AxisError> {
            if self.good == 0 {
                return Err(AxisError::Timeout { cycles: 4 });
            }
            self.good -= 1;
            self.sim.exchange(torque_nm)
        }
        fn quick_stop(&mut self) -> std::result::Result<(), AxisError> {
            self.quick_stops += 1;
            Ok(())
        }
    }

    /// Keeps the record a failed exchange hands over.
    #[derive(Default)]
    struct FailureRecorder(Vec<AxisFailureRecord>);
    impl Progress for FailureRecorder {
        fn stage_started(&mut self, _: &str, _: u64) {}
        fn advance(&mut self, _: u64) {}
        fn stage_finished(&mut self, _: &str) {}
        fn exchange_failed(&mut self, record: &AxisFailureRecord) {
            self.0.push(record.clone());
        }
    }

    /// A failed exchange hands over the last second of samples
    /// (for the same diagnostic as a safety stop), once, after the drive's
    /// quick stop.
    #[test]
    fn a_failed_exchange_hands_over_the_last_second_of_samples() {
        let plant = rigs::builtin("egc70", None).unwrap();
        let info = plant.info();
        let start = 0.3;
        let good = (1.5 / info.ts_s) as u64;
        let mut axis = FailsAfter {
            sim: sim_at(&plant, start),
            good,
            quick_stops: 0,
        };
        let i_t = 0.078 / (2.0 * std::f64::consts::PI);
        let j = 1.4e-4 + i_t * i_t * 12.16;
        let boot = bootstrap_controller(j, i_t, info.ts_s, info.torque_max_nm).unwrap();
        let supervisor = test_supervisor(info.torque_max_nm, 1.0, 0.01);
        let limits = *supervisor.limits();
        let mut rec = FailureRecorder::default();
        let mut runner = Runner::new(
            &mut axis,
            &mut rec,
            supervisor,
            i_t,
            start,
            boot,
            TEST_STOP_LIMITS,
        )
        .unwrap();
        let mut steps = 0u64;
        let err = loop {
            match runner.step(0.01, None) {
                Ok(_) => steps += 1,
                Err(e) => break e,
            }
            assert!(steps <= good, "the axis did not fail");
        };
        assert_eq!(steps, good);
        assert!(
            matches!(
                err,
                Error::Axis {
                    error: AxisError::Timeout { cycles: 4 },
                    quick_stop: None
                }
            ),
            "{err}"
        );
        assert_eq!(axis.quick_stops, 1);
        assert_eq!(rec.0.len(), 1, "handed over once");
        let r = &rec.0[0];
        assert_eq!(r.error, AxisError::Timeout { cycles: 4 });
        assert_eq!(r.limits, limits);
        assert_eq!(r.torque_command_nm, 0.01);
        let n = (STOP_HISTORY_S / info.ts_s).ceil() as usize;
        assert_eq!(r.history.len(), n, "one second of samples");
        let last = r.history.last().unwrap();
        assert!(
            (last.time_s - r.time_s).abs() < 1e-12,
            "ends at the failure"
        );
        assert!((last.time_s - good as f64 * info.ts_s).abs() < 1e-9);
        assert_eq!(last.sample.position_m, r.position_m);
    }
}
