//! The one-command self-commissioning: the stages of issue 6 in order, each
//! reporting progress and one log line:
//!
//! 1. plausibility of the data-sheet values;
//! 2. take the axis (hold it while the integrator carries the load) and move
//!    to the identification position (cart farthest from the motor, thesis 2.2);
//! 3. holding torque (thesis chapter 7), friction-free from a slow run up and down;
//! 4. excitation amplitude from small values upwards until the motion clears
//!    friction and noise (thesis 3.4);
//! 5. open-loop PRBS identification with averaging, coherence, dead time and
//!    the fit (3.2-3.5);
//! 6. controller design (chapter 4);
//! 7. friction runs at constant velocity with the designed controller (3.6);
//! 8. validation move with no, linear and nonlinear feedforward (chapter 5).

use super::bootstrap::bootstrap_controller;
use super::motion::{move_to, track, TrackOptions, TrackRecord};
use super::progress::Progress;
use super::result::{FrictionResult, IdentifiedModel, Validation};
use super::runner::{Runner, Sample};
use super::safety::{SafetyLimits, SafetySupervisor};
use super::validation::{
    run_move, validation_controller, validation_track_options, FeedforwardVariant, MoveResult,
    MoveSpec,
};
use crate::design::{design, ControllerDesign, DesignInput, DesignKnobs, FrictionParams};
use crate::ident::dead_time::{estimate_dead_time, DeadTime};
use crate::ident::etfe::{etfe, EtfeConfig, Frf};
use crate::ident::fit::{fit_two_mass, FitConfig, TwoMassFit};
use crate::ident::friction::{
    fit_constant_velocity, fit_viscous_only, ConstantVelocityRun, FrictionFit,
};
use crate::plant::Axis;
use crate::{Error, Result};
use beltune_rt::control::{CascadeConfig, CascadeController, Feedforward, Setpoint};
use beltune_rt::prbs::Prbs;
use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::time::Instant;

/// What the drive knows before commissioning: data sheets and mounting.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DataSheet {
    /// Motor-side inertia `Theta_e` (motor, coupling, pulley), kg m^2.
    pub theta_e_kg_m2: f64,
    /// Transmission `i_t = r / i_g`, m/rad.
    pub i_t_m: f64,
    /// Moving mass as far as known (cart plus the payload the user states), kg.
    pub moving_mass_kg: f64,
    /// Cart position at motor encoder count 0 (from homing), m.
    pub origin_m: f64,
    /// Allowed travel, m (inside the stroke).
    pub travel_min_m: f64,
    /// Allowed travel, m.
    pub travel_max_m: f64,
    /// Torque limit for the commissioning, N m.
    pub torque_max_nm: f64,
    /// Speed limit for the commissioning, m/s.
    pub velocity_max_m_s: f64,
}

impl DataSheet {
    /// Stage 1: plausibility. Typed errors for non-physical values.
    pub fn validate(&self) -> Result<()> {
        use crate::error::{require_finite, require_positive};
        require_positive("theta_e [kg m^2]", self.theta_e_kg_m2)?;
        require_positive("i_t [m/rad]", self.i_t_m)?;
        require_positive("moving mass [kg]", self.moving_mass_kg)?;
        require_finite("origin [m]", self.origin_m)?;
        require_positive("torque limit [N m]", self.torque_max_nm)?;
        require_positive("velocity limit [m/s]", self.velocity_max_m_s)?;
        if !(self.travel_min_m.is_finite()
            && self.travel_max_m.is_finite()
            && self.travel_max_m - self.travel_min_m > 0.05)
        {
            return Err(Error::invalid(
                "travel window [m]",
                self.travel_max_m - self.travel_min_m,
                "needs min < max with at least 50 mm of travel",
            ));
        }
        if self.origin_m < self.travel_min_m || self.origin_m > self.travel_max_m {
            return Err(Error::invalid(
                "start position [m]",
                self.origin_m,
                format!(
                    "the axis starts outside the travel window [{:.3}, {:.3}] m",
                    self.travel_min_m, self.travel_max_m
                ),
            ));
        }
        Ok(())
    }

    /// What a technician enters for a plant: its data-sheet inertia,
    /// transmission, moving mass (cart plus stated payload), torque limit, and a
    /// travel window inside the stroke (Table A.8: -10 mm to stroke - 30 mm;
    /// a linear set without stroke gets 0.6 m). `origin_m` is the homing result,
    /// `travel_window_m` overrides the window.
    pub fn for_plant(
        plant: &crate::model::rigs::Plant,
        origin_m: f64,
        travel_window_m: Option<(f64, f64)>,
    ) -> Self {
        use crate::model::rigs::Plant;
        let (theta_e, i_t, mass, stroke) = match plant {
            Plant::Physical(p) => (p.theta_e(), p.i_t(), p.m_c(), p.stroke_m),
            Plant::Linear(l) => (l.two_mass.theta_e, l.two_mass.i_t, l.two_mass.m_c, 0.6),
        };
        let (lo, hi) = travel_window_m.unwrap_or((-0.01, stroke - 0.03));
        DataSheet {
            theta_e_kg_m2: theta_e,
            i_t_m: i_t,
            moving_mass_kg: mass,
            origin_m,
            travel_min_m: lo,
            travel_max_m: hi,
            torque_max_nm: plant.info().torque_limit_nm,
            velocity_max_m_s: 2.5,
        }
    }

    /// Rigid-body inertia from the data sheet, `Theta_e + i_t^2 m`, kg m^2.
    pub fn rigid_inertia(&self) -> f64 {
        self.theta_e_kg_m2 + self.i_t_m * self.i_t_m * self.moving_mass_kg
    }
}

/// Excitation settings (thesis 3.1, 3.4).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExcitationConfig {
    /// PRBS order `n_PRBS`.
    pub prbs_order: u32,
    /// PRBS clock period `P_PRBS`, samples.
    pub clock_period: u32,
    /// Periods averaged (`n_m`).
    pub periods: usize,
    /// Leading periods discarded as transient.
    pub skip_periods: usize,
    /// A fixed amplitude `A_PRBS` in N m instead of the search (expert use).
    pub fixed_amplitude_nm: Option<f64>,
    /// First amplitude tried, as a fraction of the torque limit.
    pub amplitude_start_fraction: f64,
    /// Factor between successive amplitudes.
    pub amplitude_growth: f64,
    /// Largest amplitude allowed, as a fraction of the torque limit.
    pub amplitude_max_fraction: f64,
    /// The chosen amplitude is the first that moves the axis, times this margin
    /// (Coulomb friction must be small against the excitation for the
    /// small-signal FRF to show the linear model).
    pub amplitude_margin: f64,
    /// Lowest frequency used by the fit, Hz: below it the stick-slip of
    /// Coulomb friction dominates the response to a PRBS.
    pub fit_band_min_hz: f64,
    /// Fraction of 2 ms windows in which the encoder must move for an amplitude to count.
    pub moving_fraction: f64,
    /// Samples per amplitude test burst.
    pub burst_samples: usize,
    /// Log-spaced lines used by the fit.
    pub n_log_lines: usize,
}

impl Default for ExcitationConfig {
    fn default() -> Self {
        ExcitationConfig {
            prbs_order: 9,
            clock_period: 16,
            periods: 2,
            skip_periods: 1,
            fixed_amplitude_nm: None,
            amplitude_start_fraction: 0.02,
            amplitude_growth: 1.5,
            amplitude_max_fraction: 0.5,
            amplitude_margin: 6.0,
            fit_band_min_hz: 3.0,
            moving_fraction: 0.9,
            burst_samples: 1500,
            n_log_lines: 60,
        }
    }
}

/// Everything the commissioning can be told.
#[derive(Clone, Debug, PartialEq)]
pub struct CommissioningConfig {
    /// Design knobs (thesis 4.2-4.3).
    pub knobs: DesignKnobs,
    /// Excitation settings.
    pub excitation: ExcitationConfig,
    /// Velocity-filter time constant `T_R`, s.
    pub t_r_s: f64,
    /// Speeds of the friction runs (each in both directions), m/s.
    pub friction_speeds_m_s: Vec<f64>,
    /// Length of each friction run, m.
    pub friction_run_m: f64,
    /// The validation move.
    pub validation: MoveSpec,
    /// Largest following error allowed in closed-loop stages, m.
    pub following_error_max_m: f64,
}

impl Default for CommissioningConfig {
    fn default() -> Self {
        CommissioningConfig {
            knobs: DesignKnobs::default(),
            excitation: ExcitationConfig::default(),
            t_r_s: 2e-3,
            friction_speeds_m_s: vec![0.1, 0.25, 0.4],
            friction_run_m: 0.1,
            validation: MoveSpec::default(),
            following_error_max_m: 0.05,
        }
    }
}

/// Limits of the positioning moves (low speed, a tenth of Table A.8's
/// acceleration), m/s, m/s^2, m/s^3.
fn positioning_limits(ds: &DataSheet) -> Limits {
    Limits {
        v_max: 0.5,
        v_min: -0.5,
        a_max: 4.0,
        a_min: -4.0,
        j_max: 40.0,
        j_min: -40.0,
        position_min: ds.travel_min_m,
        position_max: ds.travel_max_m,
    }
}

/// Everything a commissioning run produced.
#[derive(Clone, Debug)]
pub struct Commissioning {
    /// The data sheet used.
    pub datasheet: DataSheet,
    /// Where the FRF was measured, m.
    pub identification_position_m: f64,
    /// Holding torque, N m.
    pub holding_torque_nm: f64,
    /// PRBS amplitude `A_PRBS` used (values +-A/2), N m.
    pub excitation_amplitude_nm: f64,
    /// FRF from the torque command to the motor angle.
    pub frf: Frf,
    /// The fit.
    pub fit: TwoMassFit,
    /// The dead time.
    pub dead_time: DeadTime,
    /// The model summary.
    pub identified: IdentifiedModel,
    /// The controller design.
    pub design: ControllerDesign,
    /// Friction points (motor velocity rad/s, torque N m).
    pub friction_points: Vec<ConstantVelocityRun>,
    /// Friction fit.
    pub friction_fit: FrictionFit,
    /// Friction summary.
    pub friction: FrictionResult,
    /// The three validation moves: none, linear, nonlinear.
    pub moves: [MoveResult; 3],
    /// Summaries of the moves.
    pub validation: Validation,
    /// The open-loop excitation of stage 5 and the axis' response.
    pub excitation: ExcitationTrace,
    /// Time the axis was busy, s.
    pub experiment_time_s: f64,
    /// Wall-clock time spent computing (FFT, fit, design), s.
    pub computation_time_s: f64,
    /// One log line per stage.
    pub log: Vec<String>,
}

/// The identification experiment as recorded (stage 5): the PRBS torque
/// command and the motor-side position, with the limits it ran under.
#[derive(Clone, Debug, Default)]
pub struct ExcitationTrace {
    /// Time since the axis was taken, s.
    pub time_s: Vec<f64>,
    /// Torque command (holding torque plus PRBS), N m.
    pub torque_command_nm: Vec<f64>,
    /// Motor-side position `i_t phi_m`, m.
    pub position_m: Vec<f64>,
    /// Torque limit of the commissioning, N m.
    pub torque_limit_nm: f64,
    /// Allowed travel, m.
    pub travel_min_m: f64,
    /// Allowed travel, m.
    pub travel_max_m: f64,
}

struct Stages<'r, 'a> {
    runner: &'r mut Runner<'a>,
    log: Vec<String>,
    compute_s: f64,
}

impl<'r, 'a> Stages<'r, 'a> {
    fn start(&mut self, name: &str, samples: u64) {
        self.runner.progress().stage_started(name, samples);
    }
    fn finish(&mut self, name: &str, line: String) {
        let line = format!("{line} [axis busy {:.1} s]", self.runner.busy_time_s());
        self.runner.progress().stage_finished(&line);
        self.log.push(format!("{name}: {line}"));
    }
}

/// Commission `axis`. The axis must be homed (`datasheet.origin_m`).
pub fn commission(
    axis: &mut dyn Axis,
    datasheet: &DataSheet,
    cfg: &CommissioningConfig,
    progress: &mut dyn Progress,
) -> Result<Commissioning> {
    // ---- 1. plausibility ----
    progress.stage_started("plausibility", 0);
    datasheet.validate()?;
    let info = axis.info();
    let ts = info.sample_time_s;
    let torque_max = datasheet.torque_max_nm.min(info.torque_limit_nm);
    let j_ds = datasheet.rigid_inertia();
    let limits = SafetyLimits {
        travel_min_m: datasheet.travel_min_m,
        travel_max_m: datasheet.travel_max_m,
        torque_max_nm: torque_max,
        velocity_max_m_s: datasheet.velocity_max_m_s,
        following_error_max_m: cfg.following_error_max_m,
    };
    // Stop deceleration: what 60 % of the torque limit gives on the data-sheet
    // inertia (the rest is margin for friction, gravity and the loop), at most 20 m/s^2.
    let a_stop = (0.6 * torque_max / j_ds * datasheet.i_t_m).min(20.0);
    let supervisor = SafetySupervisor::new(limits, a_stop)?;
    let boot = bootstrap_controller(j_ds, datasheet.i_t_m, ts, torque_max)?;
    let stop_limits = Limits {
        a_max: a_stop,
        a_min: -a_stop,
        j_max: 20.0 * a_stop,
        j_min: -20.0 * a_stop,
        ..positioning_limits(datasheet)
    };
    let line = format!(
        "data sheet ok: Theta_e {:.2} kg mm^2, i_t {:.3} mm/rad, rigid inertia {:.3e} kg m^2, torque limit {:.2} N m, travel [{:.0}, {:.0}] mm",
        datasheet.theta_e_kg_m2 * 1e6,
        datasheet.i_t_m * 1e3,
        j_ds,
        torque_max,
        datasheet.travel_min_m * 1e3,
        datasheet.travel_max_m * 1e3
    );
    progress.stage_finished(&line);
    let mut runner = Runner::new(
        axis,
        progress,
        supervisor,
        datasheet.i_t_m,
        datasheet.origin_m,
        boot,
        stop_limits,
    )?;
    let mut st = Stages {
        runner: &mut runner,
        log: vec![format!("plausibility: {line}")],
        compute_s: 0.0,
    };
    let pos_limits = positioning_limits(datasheet);

    // ---- 2a. take the axis: hold it where it is until the integrator carries
    // the load (a vertical axis sags first), for a first holding torque ----
    st.start("take axis", 0);
    let start = st.runner.position_m();
    let catch_s = 0.3;
    let rec = hold(st.runner, &boot, catch_s)?;
    let tail = &rec[rec.len() / 2..];
    let first_hold = tail.iter().map(|s| s.torque_command_nm).sum::<f64>() / tail.len() as f64;
    let mut boot = boot;
    boot.torque_offset_nm = first_hold;
    st.runner.set_stop_controller(boot);
    let line = format!(
        "held at {:.1} mm (sag {:.2} mm) with {first_hold:+.3} N m",
        st.runner.position_m() * 1e3,
        (st.runner.position_m() - start) * 1e3
    );
    st.finish("take axis", line);

    // ---- 2. identification position ----
    let width = datasheet.travel_max_m - datasheet.travel_min_m;
    let id_pos = datasheet.travel_max_m - (0.12 * width).max(0.05);
    st.start("move to worst-case position", 0);
    move_to(st.runner, &boot, id_pos, &pos_limits, 0.1)?;
    let line = format!(
        "at {:.1} mm (cart far from the motor: longest belt segment, lowest resonance)",
        st.runner.position_m() * 1e3
    );
    st.finish("position", line);

    // ---- 3. holding torque ----
    st.start("holding torque", 0);
    let holding = holding_torque(st.runner, &boot, id_pos, datasheet)?;
    let line = format!(
        "{holding:+.4} N m (mean of slow up and down runs: friction cancels; offset for the open-loop excitation)"
    );
    st.finish("holding torque", line);
    let mut boot_hold = boot;
    boot_hold.torque_offset_nm = holding;
    st.runner.set_stop_controller(boot_hold);

    // ---- 4. excitation amplitude ----
    let ex = &cfg.excitation;
    st.start("excitation amplitude", 0);
    let amplitude = match ex.fixed_amplitude_nm {
        Some(a) => crate::error::require_positive("excitation amplitude [N m]", a)?.min(torque_max),
        None => find_amplitude(
            st.runner,
            &boot_hold,
            id_pos,
            &pos_limits,
            holding,
            torque_max,
            ex,
        )?,
    };
    let line = format!(
        "A_PRBS = {:.3} N m (+-{:.3} N m around the holding torque)",
        amplitude,
        amplitude / 2.0
    );
    st.finish("excitation", line);

    // ---- 5. identification ----
    let mut prbs = Prbs::new(ex.prbs_order, ex.clock_period, amplitude)?;
    let period = prbs.period_samples() as usize;
    let n = period * (ex.periods + ex.skip_periods);
    st.start("identification (open loop)", n as u64);
    move_to(st.runner, &boot_hold, id_pos, &pos_limits, 0.05)?;
    let mut cmd = Vec::with_capacity(n);
    let mut act = Vec::with_capacity(n);
    let mut ang = Vec::with_capacity(n);
    let mut pos = Vec::with_capacity(n);
    let t_start = st.runner.busy_time_s();
    for _ in 0..n {
        let tau = holding + prbs.step();
        let s = st.runner.step(tau, None)?;
        cmd.push(s.torque_command_nm);
        act.push(s.torque_actual_nm);
        ang.push(s.motor_angle_rad);
        pos.push(s.position_m);
    }
    let t0 = Instant::now();
    let f_max = 0.4 / ts; // below 0.4 f_s: the PRBS spectrum and the Tustin/ZOH effects stay mild
    let ecfg = EtfeConfig {
        sample_time_s: ts,
        period_samples: period,
        skip_periods: ex.skip_periods,
        integrator: true,
        band_hz: Some((
            ex.fit_band_min_hz,
            f_max.min(1.0 / (ex.clock_period as f64 * ts)),
        )),
        ..EtfeConfig::default()
    };
    let frf = etfe(&cmd, &ang, &ecfg)?;
    let excitation = ExcitationTrace {
        time_s: (0..n).map(|k| t_start + k as f64 * ts).collect(),
        torque_command_nm: cmd.clone(),
        position_m: pos,
        torque_limit_nm: torque_max,
        travel_min_m: datasheet.travel_min_m,
        travel_max_m: datasheet.travel_max_m,
    };
    let frf_actual = etfe(&act, &ang, &ecfg)?;
    let fcfg = FitConfig {
        theta_e: Some(datasheet.theta_e_kg_m2),
        i_t: datasheet.i_t_m,
        n_log_lines: ex.n_log_lines,
        ..FitConfig::default()
    };
    let fit = fit_two_mass(&frf, &fcfg)?;
    let f_band = ecfg.band_hz.map(|b| b.1).unwrap_or(0.5 / ts);
    if !(fit.f_z_hz.is_finite()
        && fit.f_r_hz.is_finite()
        && fit.f_r_hz < f_band
        && fit.f_z_hz > 0.0)
    {
        return Err(Error::FitFailed {
            reason: format!(
                "the fitted model (f_r {:.3e} Hz, f_z {:.3e} Hz) has no resonance inside the measured band up to {:.0} Hz; check the excitation and the data sheet",
                fit.f_r_hz, fit.f_z_hz, f_band
            ),
        });
    }
    let max_dt = (10e-3 / ts) as usize;
    let dead_time = estimate_dead_time(&frf, &frf_actual, fit.f_r_hz, max_dt)?;
    st.compute_s += t0.elapsed().as_secs_f64();
    let identified = IdentifiedModel::from_fit(&fit, &frf, dead_time.seconds, id_pos);
    let p = fit.params;
    let mean_coh = identified.mean_coherence;
    let line = format!(
        "f_r {:.2} Hz, f_z {:.2} Hz, m_c {:.2} kg, c {:.1} kN/m, d_m {:.2} N s/m, d_c {:.2} N s/m, dead time {:.2} ms, fit {:.2} dB rms, coherence {:.3}",
        fit.f_r_hz,
        fit.f_z_hz,
        p.m_c,
        p.c / 1e3,
        p.d_m,
        p.d_c,
        dead_time.seconds * 1e3,
        fit.fit_rms_db,
        mean_coh
    );
    st.finish("identification", line);

    // ---- 6. design ----
    st.start("controller design", 0);
    let t0 = Instant::now();
    let input = DesignInput {
        model: p,
        dead_time_s: dead_time.seconds,
        t_r_s: cfg.t_r_s,
        ts_s: ts,
        friction: None,
    };
    let des = design(&input, &cfg.knobs)?;
    st.compute_s += t0.elapsed().as_secs_f64();
    let feedback = cascade_from_design(&des, torque_max, holding)?;
    st.runner.set_stop_controller(feedback);
    let line = format!(
        "K_P {:.4} N m s/rad, K_I {:.3} N m/rad, K_PP {:.2} 1/s; velocity loop {:.1} Hz / {:.1} deg, position loop {:.1} Hz / {:.1} deg, {:.2} dB at w_r",
        des.k_p,
        des.k_i,
        des.k_pp,
        des.velocity_margins.crossover_rad_s / (2.0 * std::f64::consts::PI),
        des.velocity_margins.phase_margin_deg,
        des.position_margins.crossover_rad_s / (2.0 * std::f64::consts::PI),
        des.position_margins.phase_margin_deg,
        des.gain_at_resonance_db
    );
    st.finish("design", line);

    // ---- 7. friction ----
    st.start("friction runs", 0);
    let n_t = (dead_time.seconds / ts).round() as usize;
    let mut ff_lin_cfg = feedback;
    ff_lin_cfg.feedforward = Feedforward::linear(p.rigid_inertia(), 0.0);
    let points = friction_runs(st.runner, &ff_lin_cfg, datasheet, cfg, n_t, fit.f_z_hz)?;
    let t0 = Instant::now();
    let mut friction_fit = fit_constant_velocity(&points)?;
    let linear_fit = fit_viscous_only(&points)?;
    if friction_fit.coulomb_nm < 0.0 || friction_fit.viscous_nms_per_rad < 0.0 {
        // A physical friction model has both terms >= 0; a negative Coulomb
        // term means the runs show none (a purely viscous axis).
        friction_fit = FrictionFit {
            coulomb_nm: 0.0,
            ..linear_fit
        };
    }
    st.compute_s += t0.elapsed().as_secs_f64();
    let torque_rms = (points.iter().map(|r| r.mean_torque_nm.powi(2)).sum::<f64>()
        / points.len().max(1) as f64)
        .sqrt();
    let friction = FrictionResult {
        viscous: friction_fit.viscous_nms_per_rad.max(0.0),
        coulomb: friction_fit.coulomb_nm,
        linear_viscous: linear_fit.viscous_nms_per_rad.max(0.0),
        relative_residual: friction_fit.rms_residual_nm / torque_rms.max(f64::MIN_POSITIVE),
        holding_torque_nm: holding,
    };
    let line = format!(
        "d_v {:.3e} N m s/rad, tau_c {:.4} N m (viscous-only fit {:.3e}), {} runs, residual {:.3}",
        friction.viscous,
        friction.coulomb,
        friction.linear_viscous,
        points.len(),
        friction.relative_residual
    );
    st.finish("friction", line);
    let input = DesignInput {
        friction: Some(FrictionParams {
            viscous_n_m_s_per_rad: friction.viscous,
            coulomb_n_m: friction.coulomb,
        }),
        ..input
    };
    let des = ControllerDesign {
        feedforward: crate::design::Feedforward::design(&p, input.friction.as_ref())?,
        input,
        ..des
    };

    // ---- 8. validation ----
    let m_e = p.rigid_inertia();
    let opts = validation_track_options(&p, dead_time.seconds, ts, holding);
    let move_samples = ((cfg.validation.settle_s + 1.5) / ts) as u64 * 3;
    st.start("validation moves", move_samples);
    let mut moves: Vec<MoveResult> = Vec::with_capacity(3);
    let return_limits = Limits {
        position_min: datasheet.travel_min_m,
        position_max: datasheet.travel_max_m,
        ..cfg.validation.limits
    };
    for variant in FeedforwardVariant::ALL {
        let c = validation_controller(&feedback, m_e, &friction, variant);
        // Return to the start with the thesis' own limits (it is not measured).
        moves.push(run_move(
            st.runner,
            &feedback,
            &return_limits,
            &c,
            opts,
            &cfg.validation,
        )?);
    }
    let validation = Validation {
        none: moves[0].summary.clone(),
        linear: moves[1].summary.clone(),
        nonlinear: moves[2].summary.clone(),
    };
    let line = format!(
        "max cart error: none {:.3} mm, linear {:.3} mm, nonlinear {:.3} mm; static (nonlinear) {:.1} um",
        validation.none.max_tracking_error_m * 1e3,
        validation.linear.max_tracking_error_m * 1e3,
        validation.nonlinear.max_tracking_error_m * 1e3,
        validation.nonlinear.static_error_m * 1e6
    );
    st.finish("validation", line);
    let experiment_time_s = st.runner.busy_time_s();
    let log = std::mem::take(&mut st.log);
    let computation_time_s = st.compute_s;
    let moves: [MoveResult; 3] = moves.try_into().map_err(|_| Error::TooShort {
        what: "validation moves".into(),
        needed: 3,
        got: 0,
    })?;
    Ok(Commissioning {
        datasheet: *datasheet,
        identification_position_m: id_pos,
        holding_torque_nm: holding,
        excitation_amplitude_nm: amplitude,
        frf,
        fit,
        dead_time,
        identified,
        design: des,
        friction_points: points,
        friction_fit,
        friction,
        moves,
        validation,
        excitation,
        experiment_time_s,
        computation_time_s,
        log,
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

/// Hold the current position with `ctrl` for `duration_s` (no following-error
/// check: the load may sag while the integrator takes it).
fn hold(runner: &mut Runner, ctrl: &CascadeConfig<f64>, duration_s: f64) -> Result<Vec<Sample>> {
    let ts = runner.info().sample_time_s;
    let mut c = CascadeController::new(*ctrl)?;
    let target = runner.motor_angle_rad();
    c.reset_to(target);
    let n = (duration_s / ts).ceil() as usize;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let o = c.step(&Setpoint::hold(target), runner.motor_angle_rad());
        out.push(runner.step(o.torque_nm, None)?);
    }
    Ok(out)
}

/// Stage 3: the torque that holds the cart against gravity, from a slow run up
/// and a slow run down around `center_m`: the mean of the two mean torques
/// cancels Coulomb and viscous friction (thesis chapter 7 proposes an
/// integrating position loop; its static torque is only known within the
/// friction band, this is not).
fn holding_torque(
    runner: &mut Runner,
    ctrl: &CascadeConfig<f64>,
    center_m: f64,
    ds: &DataSheet,
) -> Result<f64> {
    let v = 0.1;
    let half = 0.03;
    let limits = Limits {
        v_max: v,
        v_min: -v,
        a_max: 4.0,
        a_min: -4.0,
        j_max: 100.0,
        j_min: -100.0,
        position_min: ds.travel_min_m,
        position_max: ds.travel_max_m,
    };
    move_to(runner, ctrl, center_m - half, &positioning_limits(ds), 0.05)?;
    let mut torques = Vec::new();
    for target in [center_m + half, center_m - half] {
        let traj = Trajectory::plan(
            &State::at_rest(runner.position_m()),
            &State::at_rest(target),
            &limits,
        )?;
        let rec = track(runner, ctrl, &traj, 0.0, TrackOptions::default())?;
        let point = constant_velocity_point(&rec, v, None).ok_or_else(|| Error::TooShort {
            what: "holding-torque run (constant-velocity part)".into(),
            needed: 40,
            got: 0,
        })?;
        torques.push(point.mean_torque_nm);
    }
    move_to(runner, ctrl, center_m, &positioning_limits(ds), 0.05)?;
    Ok(0.5 * (torques[0] + torques[1]))
}

/// Stage 4: increase the PRBS amplitude from a small value until the motor
/// moves in most 2 ms windows (the response clears friction and quantization),
/// re-centring between bursts. Never beyond the maximum fraction of the torque limit.
fn find_amplitude(
    runner: &mut Runner,
    hold: &CascadeConfig<f64>,
    center_m: f64,
    limits: &Limits,
    holding_nm: f64,
    torque_max: f64,
    ex: &ExcitationConfig,
) -> Result<f64> {
    let window = 20usize;
    let mut a = ex.amplitude_start_fraction * torque_max;
    let a_max = ex.amplitude_max_fraction * torque_max;
    loop {
        let mut prbs = Prbs::new(ex.prbs_order, ex.clock_period, a)?;
        move_to(runner, hold, center_m, limits, 0.05)?;
        let mut counts = Vec::with_capacity(ex.burst_samples);
        for _ in 0..ex.burst_samples {
            runner.step(holding_nm + prbs.step(), None)?;
            counts.push(runner.last().motor_counts);
        }
        let windows = counts.len() / window;
        let moving = (0..windows)
            .filter(|w| counts[w * window] != counts[(w + 1) * window - 1])
            .count();
        let fraction = moving as f64 / windows.max(1) as f64;
        if fraction >= ex.moving_fraction {
            return Ok((a * ex.amplitude_margin).min(a_max));
        }
        if a >= a_max {
            return Err(Error::NoExcitation {
                what: format!(
                    "the axis does not move freely even at A_PRBS = {a:.3} N m ({:.0} % of 2 ms windows moving); check brakes and friction",
                    fraction * 100.0
                ),
            });
        }
        a = (a * ex.amplitude_growth).min(a_max);
    }
}

/// Stage 7: constant-velocity runs back and forth (thesis 3.6, "periodic
/// triangular-shaped reference"), the running-in part discarded; one point per
/// run: mean motor velocity and mean torque over the constant-velocity part.
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
    let a_run = 10.0;
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

/// Running-in time discarded at the start of a constant-velocity plateau
/// (thesis 3.6), s: several time constants of the velocity loop and of the
/// cart's oscillation after the acceleration phase.
const RUNNING_IN_S: f64 = 0.05;

/// Mean velocity and torque over the part of a run where the desired velocity
/// is at its plateau, after the running-in time.
///
/// The cart rings at about the antiresonance after the acceleration phase
/// (lightly damped belt mode); averaging over a whole number of periods of
/// `f_ring_hz` cancels that oscillation from the mean torque and velocity.
fn constant_velocity_point(
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
