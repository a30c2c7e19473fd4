//! A closed-loop identification record written with the simulator: the
//! axis under the real-time cascade controller (`beltune_rt`), cruising at a
//! constant motor velocity, with a periodic excitation added to one of the
//! controller's inputs (thesis 3.3.2, 3.4: the closed-loop experiments run at
//! 100 mm/s so that the velocity keeps its sign). What a drive logs for
//! [`crate::ident::recorded`] with a reference column.

use super::SimAxis;
use crate::axis::Axis;
use crate::ident::ReferenceKind;
use crate::{Error, Result};
use beltune_rt::control::{CascadeConfig, CascadeController, MotionSample, Setpoint};
use std::fmt::Write as _;

/// The logged columns, one entry per sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClosedLoopRecording {
    /// Sampling time, s.
    pub ts_s: f64,
    /// The reference the excitation was added to: excitation torque (N m),
    /// velocity setpoint (motor rad/s) or position setpoint (motor rad).
    pub reference: Vec<f64>,
    /// The torque command applied to the drive (controller output plus a
    /// torque excitation), N m.
    pub torque_command_nm: Vec<f64>,
    /// The measured motor angle (encoder counts times the count's angle), rad.
    pub angle_rad: Vec<f64>,
    /// Samples whose command the controller saturated (the record is not
    /// linear there; the start from rest to the cruise velocity may).
    pub saturated_samples: usize,
    /// The last saturated sample, if any: identify after it.
    pub last_saturated_sample: Option<usize>,
}

impl ClosedLoopRecording {
    /// CSV text with the columns `t_s,ref,tau_cmd,phi`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t_s,ref,tau_cmd,phi\n");
        for k in 0..self.reference.len() {
            let _ = writeln!(
                s,
                "{},{},{},{}",
                k as f64 * self.ts_s,
                self.reference[k],
                self.torque_command_nm[k],
                self.angle_rad[k]
            );
        }
        s
    }
}

/// Run `axis` under `controller` for `excitation.len()` samples at the motor
/// velocity `cruise_rad_s`, with the excitation added where `kind` says:
/// to the torque command, to the velocity setpoint, or to the position
/// setpoint (the cruise ramp). The setpoints that do not carry the
/// excitation follow the cruise alone. Errors: an invalid controller, a
/// non-finite input.
pub fn run_closed_loop(
    axis: &mut SimAxis,
    controller: &CascadeConfig<f64>,
    kind: ReferenceKind,
    cruise_rad_s: f64,
    excitation: &[f64],
) -> Result<ClosedLoopRecording> {
    crate::error::require_all_finite("excitation", excitation)?;
    if !cruise_rad_s.is_finite() {
        return Err(Error::invalid(
            "cruise velocity (rad/s)",
            cruise_rad_s,
            "must be finite",
        ));
    }
    let info = axis.info();
    let mut ctrl = CascadeController::new(*controller)?;
    let count = |counts: i64| counts as f64 * info.motor_rad_per_count;
    let mut phi = axis.motor_angle_rad();
    ctrl.reset_to(phi);
    let phi0 = phi;
    let mut rec = ClosedLoopRecording {
        ts_s: info.ts_s,
        ..ClosedLoopRecording::default()
    };
    for (k, &e) in excitation.iter().enumerate() {
        let ramp = phi0 + cruise_rad_s * k as f64 * info.ts_s;
        let (angle, velocity, torque, reference) = match kind {
            ReferenceKind::Torque => (ramp, cruise_rad_s, e, e),
            ReferenceKind::Velocity => (ramp, cruise_rad_s + e, 0.0, cruise_rad_s + e),
            ReferenceKind::Position => (ramp + e, cruise_rad_s, 0.0, ramp + e),
        };
        let out = ctrl.step(
            &Setpoint::at(MotionSample {
                angle_rad: angle,
                velocity_rad_s: velocity,
                acceleration_rad_s2: 0.0,
            }),
            phi,
        );
        if out.saturated {
            rec.saturated_samples += 1;
            rec.last_saturated_sample = Some(k);
        }
        let tau = out.torque_nm + torque;
        rec.reference.push(reference);
        rec.torque_command_nm.push(tau);
        rec.angle_rad.push(phi);
        phi = count(axis.step(tau).motor_counts);
    }
    Ok(rec)
}
