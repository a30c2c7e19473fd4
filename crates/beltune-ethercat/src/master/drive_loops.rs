//! The drive's own loops from the master's side: the designed cascade
//! written into the drive's manufacturer objects by SDO ([`crate::loops`])
//! and read back, the drive switched to cyclic synchronous position (CSP,
//! mode 8), and the validation move of the commissioning run again with the
//! drive closing its position and velocity loops while the master only
//! sends the trajectory. The move is summarised and judged as every
//! validation is ([`beltune::commission::validation::summarize`],
//! [`beltune::verdict::judge`]).
//!
//! The master sends the motor setpoint `n_T` cycles ahead (target position
//! 0x607A, velocity offset 0x60B1, increments); the drive keeps the last
//! `n_T + 1` and uses the oldest for its loops and the newest for the
//! feedforward, as the host's cascade does with
//! [`beltune_rt::control::Setpoint::with_preview`]. The answer to exchange
//! `k` carries what the drive latched at the end of cycle `k - 1`: the
//! state at `k T`, paired with the setpoint of `k T`.

use super::{DriveMeasurement, EthercatAxis, Transport};
use crate::cia402::{Command, State, MODE_CSP};
use crate::pdo::Outputs;
use crate::Error;
use beltune::axis::AxisError;
use beltune::commission::motion::{Path, TrackRecord};
use beltune::commission::runner::Sample;
use beltune::commission::validation::{
    cart_at_rest_m, summarize, validation_controller, validation_track_options, FeedforwardVariant,
    MoveSpec, MoveSummary,
};
use beltune::commission::{
    cascade_from_design, positioning_limits, Commissioning, CommissioningConfig,
};
use beltune::verdict::Verdict;
use beltune_rt::control::{CartSample, SetpointConversion};
use beltune_rt::trajectory::{Approach, State as Rest, Trajectory};

/// Rest at the validation start before the measured move, s.
pub const SETTLE_BEFORE_MOVE_S: f64 = 0.5;

/// What the validation with the drive's own loops found.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopsValidation {
    /// Parameters written by SDO and read back equal.
    pub parameters_written: usize,
    /// Feedforward preview, cycles.
    pub preview_cycles: u8,
    /// The validation move (nonlinear feedforward) closed in the drive.
    pub summary: MoveSummary,
    /// Its verdict, as every validation is judged.
    pub verdict: Verdict,
}

impl<T: Transport> EthercatAxis<'_, T> {
    /// Write `objects` (`(index, sub-index, bytes)`: 1, 2 or 4 bytes, e.g.
    /// [`DriveProfile::objects`]) by SDO, each read back and compared;
    /// between two transfers one process-data cycle with `hold_torque_nm`
    /// (CST) keeps the watchdog fed and the axis held. Returns the number of
    /// objects written.
    pub fn write_objects(
        &mut self,
        objects: &[(u16, u8, Vec<u8>)],
        hold_torque_nm: f64,
    ) -> Result<usize, Error> {
        for (index, sub, bytes) in objects {
            let (index, sub) = (*index, *sub);
            let n = self.cfg.subdevice;
            let md = &self.maindevice;
            let group = &self.group;
            let write = async {
                let sd = match group {
                    super::Group::Dc(g) => g.subdevice(md, n),
                    super::Group::NoDc(g) => g.subdevice(md, n),
                }?;
                // the value's bytes as they are (a REAL32 as its bit pattern)
                match bytes.len() {
                    4 => {
                        let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                        sd.sdo_write(index, sub, v).await?;
                        let back: u32 = sd.sdo_read(index, sub).await?;
                        Ok(back.to_le_bytes().to_vec())
                    }
                    2 => {
                        sd.sdo_write(index, sub, u16::from_le_bytes([bytes[0], bytes[1]]))
                            .await?;
                        let back: u16 = sd.sdo_read(index, sub).await?;
                        Ok(back.to_le_bytes().to_vec())
                    }
                    _ => {
                        sd.sdo_write(index, sub, bytes[0]).await?;
                        let back: u8 = sd.sdo_read(index, sub).await?;
                        Ok(vec![back])
                    }
                }
            };
            let back = super::run(&mut self.transport, write)
                .map_err(|e| Error::bus(format!("loop parameter {index:#06x}:{sub:02x}"), e))?;
            if &back != bytes {
                return Err(Error::Unsupported {
                    name: self.identity.name.clone(),
                    reason: format!(
                        "loop parameter {index:#06x}:{sub:02x} reads back {back:02x?}, written {bytes:02x?}"
                    ),
                });
            }
            self.exchange(hold_torque_nm)
                .map_err(|e| Error::bus("hold between parameter writes", e))?;
        }
        Ok(objects.len())
    }

    /// One CSP cycle: the drive's loops follow `target_inc` (0x607A, the
    /// drive's position frame) with the velocity `velocity_inc_s` (0x60B1).
    pub fn exchange_position(
        &mut self,
        target_inc: i32,
        velocity_inc_s: i32,
    ) -> Result<DriveMeasurement, AxisError> {
        if let Some(e) = self.failed {
            return Err(e);
        }
        if self
            .interrupt
            .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
        {
            self.failed = Some(AxisError::Interrupted);
            return Err(AxisError::Interrupted);
        }
        self.outputs = Outputs {
            controlword: Command::EnableOperation.controlword(),
            mode: MODE_CSP,
            target_torque_permille: 0,
            target_position_inc: target_inc,
            velocity_offset_inc_s: velocity_inc_s,
        };
        let r = self
            .cycle_raw()
            .and_then(|i| match State::from_statusword(i.statusword) {
                State::OperationEnabled => Ok(i),
                State::Fault | State::FaultReactionActive => Err(AxisError::DriveFault {
                    error_code: i.error_code,
                }),
                _ => Err(AxisError::NotOperational),
            });
        match r {
            Ok(i) => Ok(self.measure(i)),
            Err(e) => {
                self.failed = Some(e);
                Err(e)
            }
        }
    }

    /// The drive's raw position (0x6064) at motor count 0 of this axis.
    fn raw_zero_inc(&self) -> i32 {
        self.last
            .inputs
            .position_inc
            .wrapping_sub(self.last.motor_counts as i32)
    }
}

/// Follow `path` (cart coordinates, m) with the drive's own loops, then hold
/// its end for `settle_s`: the setpoint `preview` cycles ahead each cycle.
#[allow(clippy::too_many_arguments)]
fn follow<T: Transport>(
    axis: &mut EthercatAxis<'_, T>,
    conv: &SetpointConversion<f64>,
    origin_m: f64,
    i_t_m: f64,
    path: &impl Path,
    settle_s: f64,
    preview: u8,
) -> Result<TrackRecord, AxisError> {
    let ts = axis.cycle_s();
    let q = axis.scaling().motor_rad_per_inc();
    let zero = axis.raw_zero_inc();
    let duration = path.duration_s();
    let n = ((duration + settle_s.max(0.0)) / ts).ceil() as usize;
    let mut rec = TrackRecord {
        trajectory_duration_s: duration,
        ..Default::default()
    };
    for k in 0..n {
        let t = k as f64 * ts;
        let ahead_t = t + f64::from(preview) * ts;
        let s = path.sample(ahead_t);
        let m = conv.motor_sample_held(
            &CartSample {
                position_m: s.position - origin_m,
                velocity_m_s: s.velocity,
                acceleration_m_s2: s.acceleration,
                jerk_m_s3: s.jerk,
            },
            path.lead_hold(ahead_t),
        );
        let target = zero.wrapping_add((m.angle_rad / q).round() as i64 as i32);
        let velocity = (m.velocity_rad_s / q)
            .round()
            .clamp(i32::MIN as f64, i32::MAX as f64);
        let d = axis.exchange_position(target, velocity as i32)?;
        let phi = d.motor_counts as f64 * q;
        let desired = path.sample(t);
        rec.time_s.push(t);
        rec.desired_m.push(desired.position);
        rec.desired_velocity_m_s.push(desired.velocity);
        rec.samples.push(Sample {
            torque_command_nm: d.torque_actual_nm,
            torque_actual_nm: d.torque_actual_nm,
            motor_angle_rad: phi,
            position_m: origin_m + i_t_m * phi,
            cart_position_m: d.cart_position_m,
        });
    }
    Ok(rec)
}

/// The validation move of `run` again with the drive's own loops: the
/// delivered controller (nonlinear feedforward) written into the drive's
/// objects as `profile` maps them and read back, CSP, a move back to the
/// validation start and the measured move (Table A.8's or the one the run
/// planned), summarised and judged against `cfg`'s limits.
pub fn validate_with_drive_loops<T: Transport>(
    axis: &mut EthercatAxis<'_, T>,
    run: &Commissioning,
    cfg: &CommissioningConfig,
    profile: &crate::profile::DriveProfile,
) -> Result<LoopsValidation, Error> {
    let ts = axis.cycle_s();
    let axis_err = |what: &str| {
        let what = what.to_string();
        move |e: AxisError| Error::bus(what.clone(), e)
    };
    let lib = |e: beltune::Error| Error::Sim(e);
    let preview = (run.dead_time.seconds / ts)
        .round()
        .clamp(0.0, crate::loops::MAX_PREVIEW as f64) as u8;
    let planned = run.validation_move;
    let feedback =
        cascade_from_design(&run.design, run.torque_max_nm, run.holding_torque_nm).map_err(lib)?;
    let c = validation_controller(
        &feedback,
        run.design.feedforward.inertia_kg_m2,
        run.fit.params.i_t,
        &run.friction,
        run.target_stiffness.stiffness_at(planned.target_m),
        FeedforwardVariant::Nonlinear,
    );
    let objects = profile.objects(&c, preview)?;
    let written = axis.write_objects(&objects, run.holding_torque_nm)?;
    let ds = &run.datasheet;
    let origin = ds.origin_m;
    let opts = validation_track_options(
        &run.fit.params,
        usize::from(preview),
        run.holding_torque_nm,
        &run.target_stiffness,
        &run.friction,
        origin,
    );
    let conv = SetpointConversion::new(ds.i_t_m, opts.belt_stretch).map_err(|e| lib(e.into()))?;
    let q = axis.scaling().motor_rad_per_inc();
    let here = origin + ds.i_t_m * axis.last().motor_counts as f64 * q;
    // back to the validation start with the drive's loops, at the
    // positioning limits, then the measured move
    let back = Trajectory::plan(
        &Rest::at_rest(here),
        &Rest::at_rest(planned.start_m),
        &positioning_limits(ds),
    )
    .map_err(|e| lib(e.into()))?;
    follow(
        axis,
        &conv,
        origin,
        ds.i_t_m,
        &back,
        SETTLE_BEFORE_MOVE_S,
        preview,
    )
    .map_err(axis_err("move to the validation start in CSP"))?;
    let here = origin + ds.i_t_m * axis.last().motor_counts as f64 * q;
    let start = cart_at_rest_m(here, origin, &opts.belt_stretch);
    let spec = MoveSpec {
        start_m: planned.start_m,
        target_m: planned.target_m,
        limits: planned.limits,
        ..cfg.validation
    };
    let path = match spec.approach(&opts.belt_stretch, origin) {
        Some(a) => Approach::plan(&Rest::at_rest(start), spec.target_m, &spec.limits, &a),
        None => Trajectory::plan(
            &Rest::at_rest(start),
            &Rest::at_rest(spec.target_m),
            &spec.limits,
        )
        .map(Approach::direct),
    }
    .map_err(|e| lib(e.into()))?;
    let record = follow(axis, &conv, origin, ds.i_t_m, &path, spec.settle_s, preview)
        .map_err(axis_err("validation move in CSP"))?;
    let summary = summarize(record).map_err(lib)?.summary;
    let verdict = beltune::verdict::judge(&beltune::verdict::VerdictInput {
        limits: &cfg.limits,
        validation: Some(beltune::verdict::MoveInput {
            summary: &summary,
            record_after_move_s: cfg.validation.settle_s,
            torque_max_nm: run.torque_max_nm,
            on: beltune::verdict::ValidatedOn::Axis,
        }),
        guaranteed: Some(&run.guaranteed),
        design: &run.design,
        identified: Some(&run.identified),
        controller_file: beltune::record::CONTROLLER_FILE,
    });
    Ok(LoopsValidation {
        parameters_written: written,
        preview_cycles: preview,
        summary,
        verdict,
    })
}
