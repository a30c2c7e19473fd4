//! Stage 7: friction from constant-velocity runs back and forth with the
//! designed controller (thesis 3.6, "periodic triangular-shaped reference"),
//! the running-in part discarded; one point per run (mean motor velocity, mean
//! torque), then the Coulomb + viscous fit (3.35)-(3.36).

use super::super::commission::{positioning_limits, CommissioningConfig, DataSheet};
use super::super::motion::{move_to, track, TrackOptions, TrackRecord};
use super::super::result::FrictionResult;
use super::super::runner::Runner;
use super::Stages;
use crate::ident::friction::{
    fit_constant_velocity, fit_viscous_only, ConstantVelocityRun, FrictionFit,
};
use crate::Result;
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Running-in time discarded at the start of a constant-velocity plateau
/// (thesis 3.6), s: several time constants of the velocity loop and of the
/// cart's oscillation after the acceleration phase.
const RUNNING_IN_S: f64 = 0.05;
/// Acceleration of the friction runs, m/s^2.
const RUN_ACCELERATION_M_S2: f64 = 10.0;

/// What stage 7 hands on.
pub struct FrictionStage {
    /// One point per run.
    pub points: Vec<ConstantVelocityRun>,
    /// The Coulomb + viscous fit.
    pub fit: FrictionFit,
    /// The summary used by the feedforward.
    pub result: FrictionResult,
}

/// Stage 7: runs at the configured speeds with `ctrl` (the feedback cascade
/// with inertia feedforward), `preview` samples of feedforward preview;
/// `f_ring_hz` is the cart's ringing frequency (averaged out).
pub fn friction_stage(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    ds: &DataSheet,
    cfg: &CommissioningConfig,
    preview: usize,
    f_ring_hz: f64,
    holding_nm: f64,
) -> Result<FrictionStage> {
    st.start("friction runs", 0);
    let points = friction_runs(st.runner, ctrl, ds, cfg, preview, f_ring_hz)?;
    let (fit, linear_fit) = st.compute(|| -> Result<_> {
        let mut fit = fit_constant_velocity(&points)?;
        let linear_fit = fit_viscous_only(&points)?;
        if fit.coulomb_nm < 0.0 || fit.viscous_nm_s_per_rad < 0.0 {
            // A physical friction model has both terms >= 0; a negative Coulomb
            // term means the runs show none (a purely viscous axis).
            fit = FrictionFit {
                coulomb_nm: 0.0,
                ..linear_fit
            };
        }
        Ok((fit, linear_fit))
    })?;
    let torque_rms = (points.iter().map(|r| r.mean_torque_nm.powi(2)).sum::<f64>()
        / points.len().max(1) as f64)
        .sqrt();
    let result = FrictionResult {
        viscous_nm_s_per_rad: fit.viscous_nm_s_per_rad.max(0.0),
        coulomb_nm: fit.coulomb_nm,
        linear_viscous_nm_s_per_rad: linear_fit.viscous_nm_s_per_rad.max(0.0),
        relative_residual: fit.rms_residual_nm / torque_rms.max(f64::MIN_POSITIVE),
        holding_torque_nm: holding_nm,
    };
    let line = format!(
        "d_v {:.3e} N m s/rad, tau_c {:.4} N m (viscous-only fit {:.3e}), {} runs, residual {:.3}",
        result.viscous_nm_s_per_rad,
        result.coulomb_nm,
        result.linear_viscous_nm_s_per_rad,
        points.len(),
        result.relative_residual
    );
    st.finish("friction", line);
    Ok(FrictionStage {
        points,
        fit,
        result,
    })
}

fn friction_runs(
    runner: &mut Runner,
    ctrl: &CascadeConfig<f64>,
    ds: &DataSheet,
    cfg: &CommissioningConfig,
    preview: usize,
    f_ring_hz: f64,
) -> Result<Vec<ConstantVelocityRun>> {
    let center = 0.5 * (ds.travel_min_m + ds.travel_max_m);
    let half = 0.5 * cfg.friction_run_m;
    let a_run = RUN_ACCELERATION_M_S2;
    let pos_limits = positioning_limits(ds);
    move_to(runner, ctrl, center - half, &pos_limits, 0.05)?;
    let mut points = Vec::new();
    let opts = TrackOptions {
        preview_samples: preview,
        check_following_error: true,
        ..Default::default()
    };
    for &v in &cfg.friction_speeds_m_s {
        for target in [center + half, center - half] {
            let limits = Limits {
                v_max: v,
                v_min: -v,
                a_max: a_run,
                a_min: -a_run,
                j_max: 20.0 * a_run,
                j_min: -20.0 * a_run,
                position_min: ds.travel_min_m,
                position_max: ds.travel_max_m,
            };
            let traj = Trajectory::plan(
                &State::at_rest(runner.position_m()),
                &State::at_rest(target),
                &limits,
            )?;
            let rec = track(runner, ctrl, &traj, 0.02, opts)?;
            if let Some(p) = constant_velocity_point(&rec, v, Some(f_ring_hz)) {
                // The torque offset (holding torque) is gravity, not friction (3.35).
                points.push(ConstantVelocityRun {
                    mean_torque_nm: p.mean_torque_nm - ctrl.torque_offset_nm,
                    ..p
                });
            }
        }
    }
    Ok(points)
}

/// Mean velocity and torque over the part of a run where the desired velocity
/// is at its plateau `v`, after the running-in time.
///
/// The cart rings at about the antiresonance after the acceleration phase
/// (lightly damped belt mode); averaging over a whole number of periods of
/// `f_ring_hz` cancels that oscillation from the mean torque and velocity.
pub fn constant_velocity_point(
    rec: &TrackRecord,
    v: f64,
    f_ring_hz: Option<f64>,
) -> Option<ConstantVelocityRun> {
    let plateau: Vec<usize> = (0..rec.samples.len())
        .filter(|&k| (rec.desired_velocity_m_s[k].abs() - v).abs() < 1e-6 * v.max(1.0))
        .collect();
    let ts = rec.time_s.get(1).copied().unwrap_or(1.0);
    let skip = (RUNNING_IN_S / ts).round() as usize;
    if plateau.len() < skip + 100 {
        return None;
    }
    let mut end = plateau.len();
    if let Some(f) = f_ring_hz.filter(|f| f.is_finite() && *f > 0.0) {
        let period = (1.0 / (f * ts)).round() as usize;
        let whole = (end - skip) / period.max(1) * period;
        if whole >= 100 {
            end = skip + whole;
        }
    }
    let plateau = &plateau[..end];
    let used: &[usize] = &plateau[skip..];
    let first = &rec.samples[used[0]];
    let last = &rec.samples[*used.last()?];
    let dt = rec.time_s[*used.last()?] - rec.time_s[used[0]];
    let velocity_rad_s = (last.motor_angle_rad - first.motor_angle_rad) / dt;
    let torque_nm = used
        .iter()
        .map(|&k| rec.samples[k].torque_command_nm)
        .sum::<f64>()
        / used.len() as f64;
    Some(ConstantVelocityRun {
        velocity_rad_s,
        mean_torque_nm: torque_nm,
    })
}
