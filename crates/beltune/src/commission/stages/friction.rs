//! Stage 7: friction from constant-velocity runs back and forth with the
//! designed controller (thesis 3.6, "periodic triangular-shaped reference"),
//! the running-in part discarded; one point per run (mean motor velocity, mean
//! torque), then the Coulomb + viscous fit (3.35)-(3.36).

use super::super::motion::{move_to, track, FollowingError, TrackOptions, TrackRecord};
use super::super::runner::Runner;
use super::super::{positioning_limits, CommissioningConfig, DataSheet};
use super::momentum::{
    momentum_phase, plateau_middle, rigid_inertia_from_phases, MomentumPhase, RigidInertia,
    VelocityWindow,
};
use super::Stages;
use crate::ident::friction::{
    fit_constant_velocity, fit_viscous_only, ConstantVelocityRun, FrictionFit,
};
use crate::record::model::FrictionResult;
use crate::Result;
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Running-in time discarded at the start of a constant-velocity plateau
/// (thesis 3.6), s: several time constants of the velocity loop and of the
/// cart's oscillation after the acceleration phase.
pub const RUNNING_IN_S: f64 = 0.05;
/// Largest acceleration of the friction runs, m/s^2.
const RUN_ACCELERATION_M_S2: f64 = 10.0;
/// Share of the torque left after gravity and Coulomb friction (within
/// [`super::validation_moves::MOVE_TORQUE_FRACTION`] of the limit) that
/// the friction runs' acceleration may take; the rest is the feedback's.
const RUN_TORQUE_SHARE: f64 = 0.8;

/// The friction runs' acceleration, m/s^2: [`RUN_ACCELERATION_M_S2`], or
/// less where the torque the axis has left after holding its load
/// (`holding_nm`) and its Coulomb friction (`coulomb_nm`) within
/// [`super::validation_moves::MOVE_TORQUE_FRACTION`] of `torque_max_nm`
/// cannot accelerate the rigid `inertia_kg_m2` that hard (plant
/// #155, 20.6 kg on a 54 deg slope, held with 2.1 of 3.1 N m; 10 m/s^2 needed
/// 2.7 N m more, and the runs ended in a following-error stop; now 1.4
/// m/s^2). `None`
/// where nothing is left.
pub fn run_acceleration_m_s2(
    torque_max_nm: f64,
    holding_nm: f64,
    coulomb_nm: f64,
    inertia_kg_m2: f64,
    i_t_m: f64,
) -> Option<f64> {
    let budget = super::validation_moves::MOVE_TORQUE_FRACTION * torque_max_nm
        - holding_nm.abs()
        - coulomb_nm.max(0.0);
    let a = RUN_TORQUE_SHARE * budget * i_t_m / inertia_kg_m2;
    (a.is_finite() && a > 0.0).then(|| a.min(RUN_ACCELERATION_M_S2))
}

/// What stage 7 hands on.
pub struct FrictionStage {
    /// One point per run.
    pub points: Vec<ConstantVelocityRun>,
    /// The Coulomb + viscous fit.
    pub fit: FrictionFit,
    /// The summary used by the feedforward.
    pub result: FrictionResult,
    /// Rigid-body inertia `m_e` from the momentum balances between
    /// consecutive runs ([`super::momentum`]); `None` when the runs do not
    /// determine it.
    pub rigid_inertia: Option<RigidInertia>,
}

/// What stage 7 runs with.
#[derive(Clone, Copy, Debug)]
pub struct FrictionInputs<'a> {
    /// The designed feedback cascade (no feedforward, holding torque as offset).
    pub feedback: &'a CascadeConfig<f64>,
    /// Rigid inertia of the identified model, kg m^2: the runs' inertia feedforward.
    pub inertia_kg_m2: f64,
    /// Samples of feedforward preview (the current loop's dead time).
    pub preview: usize,
    /// The cart's ringing frequency, Hz (averaged out of the plateaus).
    pub f_ring_hz: f64,
    /// Holding torque of stage 3, N m.
    pub holding_nm: f64,
    /// Coulomb friction of stage 3, N m.
    pub coulomb_nm: f64,
    /// The friction-aware model where it is the one used: the cart's share
    /// of the friction comes from it.
    pub friction_aware: Option<&'a crate::ident::NonlinearFit>,
}

/// Stage 7: runs at the configured speeds with the feedback cascade and
/// inertia feedforward. Where the friction-aware model is used, the cart's
/// share of the friction is its (the belt carries it, and the setpoint leads
/// by its stretch); its viscous split is loose (its `d_c` came out 2-6 times
/// the truth, 52 against 9 N s/m on egc70 over EtherCAT, which led the cart
/// 0.25 mm ahead at speed), so it is bounded by the whole axis' viscous
/// friction the runs measured.
pub fn friction_stage(
    st: &mut Stages,
    inputs: &FrictionInputs,
    ds: &DataSheet,
    cfg: &CommissioningConfig,
) -> Result<FrictionStage> {
    let mut ctrl = *inputs.feedback;
    ctrl.feedforward = beltune_rt::control::Feedforward::linear(inputs.inertia_kg_m2, 0.0);
    let ctrl = &ctrl;
    let (preview, f_ring_hz, holding_nm, coulomb_nm) = (
        inputs.preview,
        inputs.f_ring_hz,
        inputs.holding_nm,
        inputs.coulomb_nm,
    );
    st.start("friction runs", 0);
    let torque_max = st.runner.supervisor().limits().torque_max_nm;
    let inertia = ctrl.feedforward.params.inertia_kg_m2;
    let a_run = run_acceleration_m_s2(torque_max, holding_nm, coulomb_nm, inertia, ds.i_t_m)
        .ok_or_else(|| crate::Error::Infeasible {
            reason: format!(
                "holding the load ({:.3} N m) and its friction ({:.3} N m) leave nothing of {:.0} % of the torque limit {torque_max:.3} N m for the friction runs",
                holding_nm.abs(),
                coulomb_nm,
                100.0 * super::validation_moves::MOVE_TORQUE_FRACTION
            ),
        })?;
    let runs = friction_runs(st.runner, ctrl, ds, cfg, preview, f_ring_hz, a_run)?;
    let mut points: Vec<ConstantVelocityRun> = runs.iter().map(|r| r.point).collect();
    // The holding torque again, from the runs: stage 3's short
    // runs of a sticky tilted axis were up to 0.1 N m off, and the feedforward
    // needs it within a few hundredths (the slow position loop integrates
    // any torque error into a lag of a millimetre).
    let refined = refined_holding_nm(&points, holding_nm, coulomb_nm, torque_max);
    for p in &mut points {
        p.mean_torque_nm -= refined - holding_nm;
    }
    let holding_nm = refined;
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
        // the cart's share: set from the friction-aware model when it is used
        cart_coulomb_n: 0.0,
        cart_viscous_n_s_per_m: 0.0,
    };
    // Inside `compute`: a real-time axis is held every cycle meanwhile.
    let rigid_inertia = st.compute(|| {
        let phases: Vec<MomentumPhase> = phases_between_runs(&runs, preview)
            .iter()
            .map(|ph| {
                ph.friction_compensated(holding_nm, result.viscous_nm_s_per_rad, result.coulomb_nm)
            })
            .collect();
        Ok(rigid_inertia_from_phases(&phases))
    })?;
    let line = format!(
        "d_v {:.3e} N m s/rad, tau_c {:.4} N m (viscous-only fit {:.3e}), {} runs, residual {:.3}; holding torque {:+.4} N m (runs up and down; stage 3 {:+.4}); {}",
        result.viscous_nm_s_per_rad,
        result.coulomb_nm,
        result.linear_viscous_nm_s_per_rad,
        points.len(),
        result.relative_residual,
        holding_nm,
        ctrl.torque_offset_nm,
        match rigid_inertia {
            Some(m) => format!(
                "rigid inertia from the runs' momentum balance {:.4e} kg m^2 (+-{:.1} %, FRF fit {:.4e})",
                m.inertia_kg_m2,
                100.0 * m.sigma_kg_m2 / m.inertia_kg_m2,
                ctrl.feedforward.params.inertia_kg_m2
            ),
            None => "the runs do not determine the rigid inertia (FRF fit kept)".into(),
        }
    );
    st.finish("friction", line);
    let mut result = result;
    if let Some(n) = inputs.friction_aware {
        let axis_viscous = result.viscous_nm_s_per_rad / (ds.i_t_m * ds.i_t_m);
        result.cart_coulomb_n = n.f_c_cart_n.max(0.0);
        result.cart_viscous_n_s_per_m = n.params.d_c.clamp(0.0, axis_viscous.max(0.0));
    }
    Ok(FrictionStage {
        points,
        fit,
        result,
        rigid_inertia,
    })
}

/// The holding torque from the friction runs `points` (mean torques less
/// the assumed `holding_nm`), N m: `holding_nm` plus the offset of the fit
/// of (3.36) with a torque offset ([`crate::ident::friction::fit_with_offset`]),
/// where the runs go both ways and the offset is within the larger of the
/// Coulomb friction `coulomb_nm` and 5 % of `torque_max_nm` (more is not a
/// measurement error of stage 3 but a fault: stage 3's value is kept).
pub fn refined_holding_nm(
    points: &[ConstantVelocityRun],
    holding_nm: f64,
    coulomb_nm: f64,
    torque_max_nm: f64,
) -> f64 {
    let bound = coulomb_nm.max(0.05 * torque_max_nm);
    match crate::ident::friction::fit_with_offset(points) {
        Ok(f) if f.offset_nm.is_finite() && f.offset_nm.abs() <= bound => holding_nm + f.offset_nm,
        _ => holding_nm,
    }
}

/// A friction run: its constant-velocity point and the middle of its
/// plateau (for the momentum balance between consecutive runs).
struct FrictionRun {
    point: ConstantVelocityRun,
    record: TrackRecord,
    middle: Option<VelocityWindow>,
}

/// The phases between the plateaus of consecutive friction runs `runs`
/// (recorded back to back), `preview` samples of dead time.
fn phases_between_runs(runs: &[FrictionRun], preview: usize) -> Vec<MomentumPhase> {
    runs.windows(2)
        .filter_map(|pair| {
            let (r1, r2) = (&pair[0], &pair[1]);
            let (a, b) = (r1.middle?, r2.middle?);
            let ts = r1.record.time_s.get(1).copied()? - r1.record.time_s[0];
            let n1 = r1.record.samples.len();
            let mut samples = r1.record.samples[a.start..].to_vec();
            samples.extend_from_slice(&r2.record.samples);
            let a0 = VelocityWindow {
                start: 0,
                len: a.len,
            };
            let b0 = VelocityWindow {
                start: n1 - a.start + b.start,
                len: b.len,
            };
            momentum_phase(&samples, ts, a0, b0, preview)
        })
        .collect()
}

fn friction_runs(
    runner: &mut Runner,
    ctrl: &CascadeConfig<f64>,
    ds: &DataSheet,
    cfg: &CommissioningConfig,
    preview: usize,
    f_ring_hz: f64,
    a_run: f64,
) -> Result<Vec<FrictionRun>> {
    let pos_limits = positioning_limits(ds);
    let mut points = Vec::new();
    let opts = TrackOptions {
        preview_samples: preview,
        following_error: FollowingError::Limited,
        ..Default::default()
    };
    let speeds = &cfg.friction_speeds_m_s;
    if speeds.is_empty() {
        return Ok(points);
    }
    let lengths: Vec<f64> = speeds
        .iter()
        .map(|&v| run_length_m(v, cfg.friction_plateau_s, a_run, ds))
        .collect();
    let v_top = speeds.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let stop_room = {
        let sup = runner.supervisor();
        2.0 * sup
            .stopping_distance_m(v_top)
            .max(sup.stopping_distance_m(-v_top))
    };
    let base = runs_base_m(
        ds,
        &lengths,
        stop_room,
        cfg.validation.start_m,
        runner.position_m(),
    );
    // Back to back (the momentum balance between consecutive runs needs no
    // gap): every speed runs forward over its own length from `base` and
    // back to it, so that no run crosses more than its own length at its
    // speed (with a common centre the slow run's way back to where the
    // fast one started took 0.75 s of axis time on egc70).
    move_to(runner, ctrl, base, &pos_limits, 0.05)?;
    for (&v, &length) in speeds.iter().zip(&lengths) {
        for target in [base + length, base] {
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
            if let Some(p) = constant_velocity_point_with_inertia(
                &rec,
                v,
                Some(f_ring_hz),
                Some(ctrl.feedforward.params.inertia_kg_m2),
            ) {
                // The torque offset (holding torque) is gravity, not friction (3.35).
                points.push(FrictionRun {
                    point: ConstantVelocityRun {
                        mean_torque_nm: p.mean_torque_nm - ctrl.torque_offset_nm,
                        ..p
                    },
                    middle: plateau_middle(&rec, v, f_ring_hz),
                    record: rec,
                });
            }
        }
    }
    Ok(points)
}

/// Where the friction runs of lengths `lengths_m` (m) start and end, m:
/// as near the validation start `validation_start_m` as the window of `ds`
/// allows with [`RUN_MARGIN_M`] and `stop_room_m` (twice the supervisor's
/// stopping distance from the fastest run) at the lower end and the
/// margin beyond the longest run at the upper end, so that the return to
/// the validation start afterwards is short; where the window is too short
/// for that room, the runs are centred in it. Where the axis is
/// (`position_m`) only breaks a tie.
pub fn runs_base_m(
    ds: &DataSheet,
    lengths_m: &[f64],
    stop_room_m: f64,
    validation_start_m: f64,
    position_m: f64,
) -> f64 {
    let longest = lengths_m.iter().fold(0.0_f64, |m, l| m.max(*l));
    let stop_room = if stop_room_m.is_finite() {
        stop_room_m.max(0.0)
    } else {
        0.0
    };
    let lo = ds.travel_min_m + RUN_MARGIN_M + stop_room;
    let hi = ds.travel_max_m - RUN_MARGIN_M - longest;
    let center = 0.5 * (ds.travel_min_m + ds.travel_max_m) - 0.5 * longest;
    if lo > hi {
        return center;
    }
    let wanted = if validation_start_m.is_finite() {
        validation_start_m
    } else {
        position_m
    };
    wanted.clamp(lo, hi)
}

/// Distance kept from either end of the travel window by the friction runs, m.
const RUN_MARGIN_M: f64 = 0.02;

/// Length of a friction run at speed `v` (m/s): `plateau_s` at that speed
/// plus the acceleration and deceleration at `a_run` (m/s^2), at most the
/// travel window less [`RUN_MARGIN_M`] at either end, m.
pub fn run_length_m(v: f64, plateau_s: f64, a_run: f64, ds: &DataSheet) -> f64 {
    let wanted = v * plateau_s.max(0.0) + v * v / a_run;
    let room = ds.travel_max_m - ds.travel_min_m - 2.0 * RUN_MARGIN_M;
    wanted.min(room).max(0.0)
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
    constant_velocity_point_with_inertia(rec, v, f_ring_hz, None)
}

/// [`constant_velocity_point`] with the momentum balance of the rigid body
/// `inertia` (kg m^2): the velocity loop is still settling on a short plateau
/// (the motor velocity rose by 8 % over the 0.16 s plateau of a
/// 0.4 m/s run, which put 0.05 N m of acceleration torque into the "friction"),
/// so the mean torque over `[t_a, t_b]` is the mean friction plus
/// `J (omega(t_b) - omega(t_a)) / (t_b - t_a)`, which is subtracted. The end
/// velocities are the mean slopes of the motor angle over one ringing period
/// at either end, the torque is averaged between the centres of those windows.
pub fn constant_velocity_point_with_inertia(
    rec: &TrackRecord,
    v: f64,
    f_ring_hz: Option<f64>,
    inertia: Option<f64>,
) -> Option<ConstantVelocityRun> {
    let plateau: Vec<usize> = (0..rec.samples.len())
        .filter(|&k| (rec.desired_velocity_m_s[k].abs() - v).abs() < 1e-6 * v.max(1.0))
        .collect();
    let ts = rec.time_s.get(1).copied().unwrap_or(1.0);
    let skip = (RUNNING_IN_S / ts).round() as usize;
    if plateau.len() < skip + 100 {
        return None;
    }
    let ring_period = f_ring_hz
        .filter(|f| f.is_finite() && *f > 0.0)
        .map(|f| ((1.0 / (f * ts)).round() as usize).max(1));
    let mut end = plateau.len();
    if let Some(period) = ring_period {
        let whole = (end - skip) / period * period;
        if whole >= 100 {
            end = skip + whole;
        }
    }
    let plateau = &plateau[..end];
    let used: &[usize] = &plateau[skip..];
    let angle = |k: usize| rec.samples[used[k]].motor_angle_rad;
    let time = |k: usize| rec.time_s[used[k]];
    let last = used.len() - 1;
    let dt = time(last) - time(0);
    let velocity_rad_s = (angle(last) - angle(0)) / dt;
    let mean_torque = |a: usize, b: usize| {
        used[a..=b]
            .iter()
            .map(|&k| rec.samples[k].torque_command_nm)
            .sum::<f64>()
            / (b - a + 1) as f64
    };
    let window = ring_period.unwrap_or((MOMENTUM_WINDOW_S / ts).round() as usize);
    let torque_nm = match inertia.filter(|j| j.is_finite() && *j > 0.0) {
        Some(j) if window >= 2 && 2 * window <= used.len() => {
            let w_a = (angle(window) - angle(0)) / (time(window) - time(0));
            let w_b = (angle(last) - angle(last - window)) / (time(last) - time(last - window));
            let (a, b) = (window / 2, last - window / 2);
            mean_torque(a, b) - j * (w_b - w_a) / (time(b) - time(a))
        }
        _ => mean_torque(0, last),
    };
    Some(ConstantVelocityRun {
        velocity_rad_s,
        mean_torque_nm: torque_nm,
    })
}

/// End-velocity window of the momentum balance when the ringing frequency is
/// unknown, s.
const MOMENTUM_WINDOW_S: f64 = 0.01;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commission::runner::Sample;

    /// A rigid body `J` whose velocity still settles on the plateau
    /// (`omega = omega_0 (1 + 0.08 (1 - e^{-t/tau}))`, as plant #26 of the
    /// issue-12 study did on its 0.4 m/s run), driven by friction
    /// `tau_f` plus `J omega'`.
    fn settling_run(j: f64, tau_f: f64) -> TrackRecord {
        let ts = 1e-4;
        let (v, i_t, w0, tau) = (0.4, 0.0124, 0.4 / 0.0124 * 0.93, 0.05);
        let n = 2000;
        let mut rec = TrackRecord {
            time_s: vec![],
            desired_m: vec![],
            desired_velocity_m_s: vec![],
            samples: vec![],
            trajectory_duration_s: n as f64 * ts,
        };
        for k in 0..n {
            let t = k as f64 * ts;
            let e = (-t / tau).exp();
            let angle = w0 * (t + 0.08 * (t - tau * (1.0 - e)));
            let accel = w0 * 0.08 * e / tau;
            rec.time_s.push(t);
            rec.desired_m.push(v * t);
            rec.desired_velocity_m_s.push(v);
            rec.samples.push(Sample {
                torque_command_nm: tau_f + j * accel,
                torque_actual_nm: tau_f + j * accel,
                motor_angle_rad: angle,
                position_m: i_t * angle,
                cart_position_m: None,
            });
        }
        rec
    }

    /// The friction runs' acceleration from the torque budget, against the
    /// closed form `0.8 (0.9 tau_max - |tau_hold| - tau_c) i_t / J`, capped at
    /// 10 m/s^2; nothing left is `None`. Plant #155 of the robustness study: 3.1 N m,
    /// 2.1 N m holding, 0.19 N m Coulomb, J 3.4e-3 kg m^2: 1.76 m/s^2.
    #[test]
    fn the_runs_accelerate_with_the_torque_left() {
        let (i_t, j) = (0.012414, 3.4e-3);
        let a = run_acceleration_m_s2(3.1, -2.1156, 0.1909, j, i_t).unwrap();
        let expected = 0.8 * (0.9 * 3.1 - 2.1156 - 0.1909) * i_t / j;
        assert!(
            (a - expected).abs() < 1e-12 && (a - 1.41).abs() < 0.01,
            "{a}"
        );
        assert_eq!(run_acceleration_m_s2(3.1, 0.0, 0.1, 1e-3, i_t), Some(10.0));
        assert_eq!(run_acceleration_m_s2(3.1, 2.8, 0.1, j, i_t), None);
        assert_eq!(run_acceleration_m_s2(3.1, 0.0, 0.1, f64::NAN, i_t), None);
    }

    /// The acceleration torque of a settling velocity loop is not
    /// friction. Without the momentum balance the mean torque is more than
    /// 10 % too high here; with it the friction comes out within 1 %.
    #[test]
    fn momentum_balance_removes_the_settling_torque() {
        let (j, tau_f) = (3e-3, 0.12);
        let rec = settling_run(j, tau_f);
        let plain = constant_velocity_point(&rec, 0.4, Some(22.5)).unwrap();
        let balanced =
            constant_velocity_point_with_inertia(&rec, 0.4, Some(22.5), Some(j)).unwrap();
        assert!(
            (plain.mean_torque_nm / tau_f - 1.0).abs() > 0.1,
            "the example must settle visibly: {plain:?}"
        );
        assert!(
            (balanced.mean_torque_nm / tau_f - 1.0).abs() < 0.01,
            "{balanced:?}"
        );
    }
}
