//! The experiment: the one-command self-commissioning of an axis behind the
//! [`crate::axis::Axis`] trait, stage by stage under a safety supervisor,
//! each stage reporting progress and one log line:
//!
//! 1. plausibility of the data-sheet values;
//! 2. take the axis (hold it while the integrator carries the load);
//! 3. holding torque (thesis chapter 7), friction-free from slow runs up and
//!    down at two speeds where the axis was taken, which also separate
//!    Coulomb from viscous friction; the bootstrap controller is fitted to
//!    the friction, then moves the axis to the identification position (cart
//!    farthest from the motor, thesis 2.2);
//! 4. excitation amplitude from small values upwards until the motion clears
//!    friction and noise (thesis 3.4);
//! 5. open-loop PRBS identification with averaging, coherence, dead time and
//!    the fit (3.2-3.5); 5b, 5c: the belt stiffness along the stroke;
//! 6. controller design (chapter 4);
//! 7. friction runs at constant velocity with the designed controller (3.6),
//!    then the delivered design on the friction they measured;
//! 8. validation move with nonlinear feedforward (chapter 5), judged by
//!    [`crate::verdict`]; with no and linear feedforward first only on
//!    request ([`CommissioningConfig::compare_feedforward`]).
//!
//! Each stage's axis time goes to [`Commissioning::stage_axis_times`]
//! (issue 31: at most 15 s in all by default; `tests/axis_time.rs`).
//!
//! | file | what |
//! | --- | --- |
//! | [`config`] | data sheet, excitation settings, limits of the moves |
//! | [`band`] | the resonance range the data sheet allows; the PRBS for it |
//! | [`runner`], [`safety`], [`motion`] | driving the axis sample by sample under the supervisor |
//! | [`bootstrap`], [`bootstrap_margin`] | the controller before the axis is identified, its margin over the resonances the data sheet allows |
//! | [`stages`] | one file per stage |
//! | [`validation`] | the validation move (also simulated, for the tuning page) |
//! | [`stiffness`] | the belt stiffness along the stroke |
//! | [`result`] | what a run produced |
//! | [`recorded`] | commissioning from a recording instead of an axis |
//!
//! This file holds only the order of the stages.

pub mod band;
pub mod bootstrap;
pub mod bootstrap_margin;
pub mod config;
pub mod motion;
pub mod progress;
pub mod recorded;
pub mod result;
pub mod runner;
pub mod safety;
pub mod stages;
pub mod stiffness;
pub mod validation;

pub use config::{
    check_travel_window, positioning_limits, CommissioningConfig, DataSheet, ExcitationConfig,
};
pub use progress::{LogProgress, NoProgress, Progress};
pub use result::{Commissioning, ExcitationTrace};
pub use safety::{SafetyLimits, SafetySupervisor, Violation};

use self::runner::Runner;
use self::safety::StopCapability;
use self::stages::Stages;
use crate::axis::Axis;
use crate::design::ControllerDesign;
use crate::Result;
use beltune_rt::control::{CascadeConfig, Feedforward};

/// Commission `axis`. The axis must be homed (`datasheet.origin_m`).
pub fn commission(
    axis: &mut dyn Axis,
    datasheet: &DataSheet,
    cfg: &CommissioningConfig,
    progress: &mut dyn Progress,
) -> Result<Commissioning> {
    // ---- 1. plausibility ----
    progress.stage_started("plausibility", 0);
    let info = axis.info();
    let ts = info.ts_s;
    let plaus = stages::plausibility::plausibility(&info, datasheet, cfg)?;
    progress.stage_finished(&plaus.line);
    let torque_max = plaus.torque_max_nm;
    let mut runner = Runner::new(
        axis,
        progress,
        plaus.supervisor,
        datasheet.i_t_m,
        datasheet.origin_m,
        plaus.bootstrap,
        plaus.stop_limits,
    )?;
    let mut st = Stages::new(&mut runner, vec![format!("plausibility: {}", plaus.line)]);
    let pos_limits = positioning_limits(datasheet);

    // ---- 2. take the axis, identification position ----
    let taken = stages::take_axis::take_axis(&mut st, plaus.bootstrap, datasheet, torque_max)?;
    let id_pos = taken.identification_position_m;

    // ---- 3. holding torque and friction where the axis was taken, the
    // bootstrap fitted to the friction, the move to the worst case ----
    let center = stages::holding_torque::run_center_m(st.runner.position_m(), datasheet);
    let held = stages::holding_torque::holding_torque_stage(
        &mut st,
        &taken.bootstrap,
        center,
        datasheet,
        torque_max,
    )?;
    let holding = held.holding_nm;
    let boot_hold = stages::holding_torque::fitted_bootstrap(&held, datasheet, ts, torque_max)?;
    let crossover_hz = |c: &CascadeConfig<f64>| {
        c.gains.k_p_nm_s_per_rad / datasheet.rigid_inertia() / (2.0 * std::f64::consts::PI)
    };
    if crossover_hz(&boot_hold) < 0.99 * crossover_hz(&taken.bootstrap) {
        st.log.push(format!(
            "bootstrap loop for the whole stroke: {:.2} Hz (near the start {:.2} Hz), the measured Coulomb friction fed forward",
            crossover_hz(&boot_hold),
            crossover_hz(&taken.bootstrap)
        ));
    }
    st.runner.set_stop_controller(boot_hold);
    stages::take_axis::move_to_worst_case(&mut st, &boot_hold, id_pos, datasheet)?;

    // ---- 4. excitation amplitude ----
    let band = band::ResonanceBand::of(datasheet);
    let excitation = cfg.excitation.for_band(ts, band.as_ref());
    if excitation != cfg.excitation {
        st.log.push(format!(
            "excitation: PRBS clock {:.2} ms, order {} for resonances up to {:.0} Hz at {:.0} Hz sampling",
            excitation.clock_period_s * 1e3,
            excitation.prbs_order,
            band.map_or(f64::NAN, |b| b.f_r_max_hz()),
            1.0 / ts
        ));
    }
    let ex = &excitation;
    let amplitude = stages::amplitude::amplitude_stage(
        &mut st,
        &boot_hold,
        id_pos,
        &pos_limits,
        holding,
        torque_max,
        ex,
    )?;

    // ---- 5. identification ----
    let mut ident = stages::identification::identification(
        &mut st,
        &boot_hold,
        id_pos,
        &pos_limits,
        holding,
        amplitude,
        held.friction_nm,
        ex,
        datasheet,
    )?;
    // ---- 5b, 5c. belt stiffness where the validation move ends and near
    // where it starts: the compliance along the stroke ----
    let target_stiffness = stages::identification::stiffness_profile(
        &mut st,
        &boot_hold,
        stages::validation_moves::validation_target_m(&cfg.validation, datasheet),
        stages::identification::start_side_position_m(datasheet, ident.excursion_m),
        &stages::identification::StiffnessInputs {
            main: &ident.fit,
            ident_position_m: ident.measured_position_m,
            excitation_center_m: ident.center_m,
            limits: &pos_limits,
            holding_nm: holding,
            amplitude_nm: amplitude,
            dead_time_s: ident.dead_time.seconds,
            coulomb_nm: ident.total_coulomb_nm(held.friction_nm),
            ex,
            datasheet,
        },
    )?;
    let rigid_inertia = ident.fit.params.rigid_inertia();
    // The stops now brake the identified inertia.
    st.runner.set_stop_capability(StopCapability::from_axis(
        torque_max,
        rigid_inertia,
        datasheet.i_t_m,
        holding,
        held.friction_nm,
    )?)?;
    let excitation = ident.take_excitation(torque_max, datasheet);

    // ---- 6. design ----
    let designed = stages::design::design_stage(
        &mut st,
        &ident.fit,
        datasheet.stroke_variation.as_ref(),
        ident.dead_time.seconds,
        torque_max,
        holding,
        cfg,
    )?;

    // ---- 7. friction ----
    let n_t = (ident.dead_time.seconds / ts).round() as usize;
    let fr = stages::friction::friction_stage(
        &mut st,
        &stages::friction::FrictionInputs {
            feedback: &designed.feedback,
            inertia_kg_m2: rigid_inertia,
            preview: n_t,
            f_ring_hz: ident.fit.f_z_hz,
            holding_nm: holding,
            coulomb_nm: held.friction_nm,
            friction_aware: ident.friction_aware(),
        },
        datasheet,
        cfg,
    )?;
    // the holding torque the friction runs measured
    let holding = fr.result.holding_torque_nm;
    let boot_hold = CascadeConfig {
        torque_offset_nm: holding,
        ..boot_hold
    };
    st.runner.set_stop_capability(StopCapability::from_axis(
        torque_max,
        rigid_inertia,
        datasheet.i_t_m,
        holding,
        fr.result.coulomb_nm,
    )?)?;
    // ---- 7b. the delivered design, on the friction the runs measured ----
    let delivered = stages::design::delivered_design(
        &mut st,
        &designed.design,
        &ident.fit,
        datasheet.stroke_variation.as_ref(),
        &fr,
        torque_max,
        holding,
        cfg,
    )?;

    // ---- 8. validation ----
    let val = stages::validation_moves::validation_moves(
        &mut st,
        &delivered.feedback,
        &boot_hold,
        &ident.fit,
        delivered.design.feedforward.inertia_kg_m2,
        &fr.result,
        n_t,
        holding,
        &target_stiffness,
        datasheet,
        cfg,
    )?;
    let mut run = Commissioning {
        datasheet: *datasheet,
        torque_max_nm: torque_max,
        identification_position_m: ident.measured_position_m,
        holding_torque_nm: holding,
        target_stiffness,
        excitation_amplitude_nm: amplitude,
        frf: ident.frf,
        fit: ident.fit,
        frf_fit: ident.frf_fit,
        nonlinear: ident.nonlinear,
        dead_time: ident.dead_time,
        identified: ident.identified,
        design: delivered.design,
        friction_points: fr.points,
        friction_fit: fr.fit,
        friction: fr.result,
        moves: val.moves,
        validation: val.validation,
        validation_move: val.planned,
        guaranteed: delivered.guaranteed,
        verdict: crate::verdict::Verdict::default(),
        excitation,
        experiment_time_s: 0.0,
        stage_axis_times: Vec::new(),
        computation_time_s: 0.0,
        log: Vec::new(),
    };
    run.verdict = judge_run(&run, cfg);
    let verdict = &run.verdict;
    st.log.push(format!(
        "verdict: {}{}",
        verdict.text(),
        verdict
            .warnings
            .iter()
            .map(|w| format!("; warning: {}: {}", w.topic, w.reason))
            .collect::<String>(),
    ));
    run.experiment_time_s = st.runner.busy_time_s();
    run.stage_axis_times = std::mem::take(&mut st.axis_times);
    run.computation_time_s = st.compute_s;
    run.log = std::mem::take(&mut st.log);
    Ok(run)
}

/// Commission `plant` on the simulator, as `beltune commission` does: the
/// data sheet the plant gives ([`DataSheet::for_plant`], inside
/// `travel_window_m` if given), the cart starting at
/// `sim.initial_cart_position_m` (0.05 m when not set).
pub fn commission_simulated(
    plant: &crate::model::Plant,
    sim: crate::sim::SimConfig,
    travel_window_m: Option<(f64, f64)>,
    cfg: &CommissioningConfig,
    progress: &mut dyn Progress,
) -> Result<Commissioning> {
    let start = sim.initial_cart_position_m.unwrap_or(0.05);
    let ds = DataSheet::for_plant(plant, start, travel_window_m);
    let mut axis = crate::sim::SimAxis::new(
        plant,
        crate::sim::SimConfig {
            initial_cart_position_m: Some(start),
            ..sim
        },
    )?;
    commission(&mut axis, &ds, cfg, progress)
}

/// The verdict on a run ([`crate::verdict::judge`]): its delivered
/// controller's validation move (nonlinear feedforward) against the limits of
/// `cfg`, and the margins it guarantees.
pub fn judge_run(run: &Commissioning, cfg: &CommissioningConfig) -> crate::verdict::Verdict {
    crate::verdict::judge(&crate::verdict::VerdictInput {
        limits: &cfg.limits,
        validation: Some(crate::verdict::MoveInput {
            summary: &run.validation.nonlinear,
            record_after_move_s: cfg.validation.settle_s,
            torque_max_nm: run.torque_max_nm,
            on: crate::verdict::ValidatedOn::Axis,
        }),
        guaranteed: Some(&run.guaranteed),
        design: &run.design,
        identified: Some(&run.identified),
        controller_file: crate::record::CONTROLLER_FILE,
    })
}

/// The real-time cascade for a design, without feedforward (the validation
/// adds each variant), with a constant torque offset.
pub fn cascade_from_design(
    des: &ControllerDesign,
    torque_max_nm: f64,
    torque_offset_nm: f64,
) -> Result<CascadeConfig<f64>> {
    let mut c = des.cascade_config(torque_max_nm)?;
    c.feedforward = Feedforward::none();
    c.torque_offset_nm = torque_offset_nm;
    Ok(c)
}
