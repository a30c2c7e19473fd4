//! The runner drives an [`Axis`] sample by sample for all stages: it converts
//! encoder counts to cart coordinates, estimates the velocity, counts the busy
//! time, reports progress, asks the [`SafetySupervisor`] about every sample and,
//! on a violation, stops the excitation at once and brings the axis to rest
//! with a jerk-limited stop before returning [`Error::SafetyStop`].

use super::progress::Progress;
use super::safety::{SafetySupervisor, Violation};
use crate::plant::{Axis, AxisInfo, Measurement};
use crate::{Error, Result};
use beltune_rt::control::{CascadeConfig, CascadeController, MotionSample, Setpoint};
use beltune_rt::filter::{velocity_filter, FirstOrder};
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Velocity filter time constant used for supervision, s (as `T_R` of Table A.4).
const SUPERVISION_T_R_S: f64 = 2e-3;
/// How long the axis is held after a stop trajectory, s.
const STOP_SETTLE_S: f64 = 0.2;

/// One recorded sample of a stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    /// Controller used to stop the axis (the bootstrap controller until a design exists).
    stop_controller: CascadeConfig<f64>,
    stop_limits: Limits,
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
        let coeffs = velocity_filter(SUPERVISION_T_R_S, info.ts_s)?;
        let mut velocity = FirstOrder::new(coeffs);
        velocity.reset_to(origin_m, 0.0);
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
            stop_controller,
            stop_limits,
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
        let limit = self
            .info
            .torque_max_nm
            .min(self.supervisor.limits().torque_max_nm);
        let torque = if torque_nm.is_finite() {
            torque_nm.clamp(-limit, limit)
        } else {
            f64::NAN
        };
        if let Err(v) = self.supervisor.check(
            self.position_m(),
            self.velocity_m_s,
            torque,
            following_error_m,
        ) {
            return Err(self.stop_after(v));
        }
        self.raw_step(torque)
    }

    fn raw_step(&mut self, torque_nm: f64) -> Result<Sample> {
        let m = match self.axis.exchange(torque_nm) {
            Ok(m) => m,
            Err(error) => {
                // The host can no longer control the axis: the drive stops it.
                let quick_stop = self.axis.quick_stop().err();
                return Err(Error::Axis { error, quick_stop });
            }
        };
        self.last = m;
        self.samples += 1;
        self.progress.advance(1);
        let pos = self.position_m();
        self.velocity_m_s = self.velocity.step(pos);
        Ok(Sample {
            torque_command_nm: torque_nm,
            torque_actual_nm: m.torque_actual_nm,
            motor_angle_rad: self.motor_angle_rad(),
            position_m: pos,
            cart_position_m: m.cart_position_m,
        })
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

    /// Stop after a violation and turn it into the error that ends the command.
    fn stop_after(&mut self, v: Violation) -> Error {
        let stop = self.stop();
        let mut reason = v.to_string();
        match stop {
            Ok(at) => reason.push_str(&format!("; axis stopped at {:.1} mm", at * 1e3)),
            Err(e) => reason.push_str(&format!("; the stop itself failed: {e}")),
        }
        Error::SafetyStop { reason }
    }

    /// Bring the axis to rest with a jerk-limited stop under the stop
    /// controller; returns the rest position, m. The supervisor is not asked
    /// during the stop (it is the reaction), but the torque stays limited.
    pub fn stop(&mut self) -> Result<f64> {
        let ts = self.info.ts_s;
        let v = if self.velocity_m_s.is_finite() {
            self.velocity_m_s
        } else {
            0.0
        };
        let p = self.position_m();
        let a_stop = self.stop_limits.a_max.min(-self.stop_limits.a_min);
        let rest = p + v.signum() * v * v / (2.0 * a_stop);
        let limits = Limits {
            position_min: f64::NEG_INFINITY,
            position_max: f64::INFINITY,
            ..self.stop_limits
        };
        let start = State {
            position: p,
            velocity: v,
            acceleration: 0.0,
        };
        let traj = Trajectory::plan(&start, &State::at_rest(rest), &limits)?;
        let mut ctrl = CascadeController::new(self.stop_controller)?;
        ctrl.reset_to(self.motor_angle_rad());
        let n = ((traj.duration_s() + STOP_SETTLE_S) / ts).ceil() as u64;
        let limit = self.info.torque_max_nm;
        for k in 0..n {
            let s = traj.sample(k as f64 * ts);
            let sp = Setpoint::at(MotionSample {
                angle_rad: self.position_to_angle_rad(s.position),
                velocity_rad_s: s.velocity / self.i_t,
                acceleration_rad_s2: s.acceleration / self.i_t,
            });
            let out = ctrl.step(&sp, self.motor_angle_rad());
            let tau = if out.torque_nm.is_finite() {
                out.torque_nm.clamp(-limit, limit)
            } else {
                0.0
            };
            self.raw_step(tau)?;
        }
        Ok(self.position_m())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs;
    use crate::plant::AxisError;
    use crate::procedure::bootstrap::bootstrap_controller;
    use crate::procedure::progress::NoProgress;
    use crate::procedure::safety::SafetyLimits;
    use crate::sim::{SimAxis, SimConfig};

    /// A simulated axis that claims real time and counts its exchanges.
    struct RealTime {
        sim: SimAxis,
        real_time: bool,
        exchanges: u64,
    }

    impl Axis for RealTime {
        fn info(&self) -> AxisInfo {
            self.sim.info()
        }
        fn exchange(
            &mut self,
            torque_command_nm: f64,
        ) -> std::result::Result<Measurement, AxisError> {
            self.exchanges += 1;
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

    fn with_runner<R>(real_time: bool, f: impl FnOnce(&mut Runner) -> R) -> (R, u64, f64) {
        let plant = rigs::builtin("egc70", None).unwrap();
        let info = plant.info();
        let start = 0.3;
        let mut axis = RealTime {
            sim: SimAxis::new(
                &plant,
                SimConfig {
                    initial_cart_position_m: Some(start),
                    ..SimConfig::default()
                },
            )
            .unwrap(),
            real_time,
            exchanges: 0,
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
        let limits = Limits {
            v_max: 0.5,
            v_min: -0.5,
            a_max: 4.0,
            a_min: -4.0,
            j_max: 40.0,
            j_min: -40.0,
            position_min: 0.0,
            position_max: 0.6,
        };
        let mut progress = NoProgress;
        let (r, drift) = {
            let mut runner =
                Runner::new(&mut axis, &mut progress, sup, i_t, start, ctrl, limits).unwrap();
            let r = f(&mut runner);
            (r, (runner.position_m() - start).abs())
        };
        (r, axis.exchanges, drift)
    }

    #[test]
    fn issue_14_a_real_time_axis_is_held_in_closed_loop_while_the_computation_runs() {
        let ((value, during), exchanges, drift) = with_runner(true, |runner| {
            let before = runner.busy_samples();
            let v = runner
                .hold_while(|| {
                    std::thread::sleep(std::time::Duration::from_millis(30));
                    42
                })
                .unwrap();
            (v, runner.busy_samples() - before)
        });
        assert_eq!(value, 42);
        // 30 ms of computation at about 0.1 ms per exchange: dozens of cycles held
        assert!(during >= 20, "{during} cycles held");
        assert_eq!(exchanges, during);
        // the axis (vertical load none, friction) stays where it was
        assert!(drift < 1e-3, "drift {drift} m");
    }

    #[test]
    fn a_simulated_axis_waits_for_the_computation() {
        let (during, exchanges, _) = with_runner(false, |runner| {
            let before = runner.busy_samples();
            runner
                .hold_while(|| std::thread::sleep(std::time::Duration::from_millis(5)))
                .unwrap();
            runner.busy_samples() - before
        });
        assert_eq!((during, exchanges), (0, 0));
    }
}
