//! Stage 5: open-loop PRBS identification (thesis 3.2-3.5): one transient
//! period and the averaged periods around the holding torque, the FRF with
//! Clary's method II and coherence, the two-mass fit and the current-loop dead
//! time; then the friction-aware fit of the nonlinear model (2.30) to the
//! same record ([`crate::ident::nonlinear`]), which the design uses
//! where it explains the record better than the FRF fit.

use super::super::motion::move_to;
use super::super::{DataSheet, ExcitationConfig};
use super::Stages;
use crate::commission::stiffness::TargetStiffness;
use crate::design::MAX_DEAD_TIME_S;
use crate::ident::dead_time::{estimate_dead_time, DeadTime};
use crate::ident::etfe::{etfe, EtfeConfig, Frf};
use crate::ident::fit::{fit_two_mass, FitConfig, FitModel, TwoMassFit};
use crate::ident::nonlinear::{fit_nonlinear, NonlinearConfig, NonlinearFit};
use crate::model::TwoMassParams;
use crate::record::model::IdentifiedModel;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::prbs::Prbs;
use beltune_rt::trajectory::Limits;

/// What stage 5 hands on.
pub struct Identification {
    /// FRF from the torque command to the motor angle.
    pub frf: Frf,
    /// The model the design uses: the friction-aware fit where it explains
    /// the record better than the FRF fit ([`FitModel::Nonlinear`]), else the
    /// FRF fit.
    pub fit: TwoMassFit,
    /// The thesis' fit of the FRF's magnitude (3.5).
    pub frf_fit: TwoMassFit,
    /// The friction-aware fit, `None` where it failed ([`Self::nonlinear_note`]).
    pub nonlinear: Option<NonlinearFit>,
    /// Why the friction-aware fit is not used, if it is not.
    pub nonlinear_note: Option<String>,
    /// Mean motor-side position over the compared periods, m: where the
    /// model holds (the open-loop excitation moves the axis around the
    /// position it started at).
    pub measured_position_m: f64,
    /// Where the excitation started, m: the requested centre, or where it
    /// started again against the drift of an earlier attempt.
    pub center_m: f64,
    /// Largest distance of the axis from the excitation's centre during it, m.
    pub excursion_m: f64,
    /// The current-loop dead time.
    pub dead_time: DeadTime,
    /// The model summary.
    pub identified: IdentifiedModel,
    /// Time of each excitation sample since the axis was taken, s.
    pub excitation_time_s: Vec<f64>,
    /// Torque command of each sample (holding torque plus PRBS), N m.
    pub excitation_torque_nm: Vec<f64>,
    /// Motor-side position of each sample, m.
    pub excitation_position_m: Vec<f64>,
}

impl Identification {
    /// The friction-aware fit where it is the model used (it exists and
    /// explains the record better than the FRF fit).
    pub fn friction_aware(&self) -> Option<&NonlinearFit> {
        self.nonlinear
            .as_ref()
            .filter(|_| self.nonlinear_note.is_none())
    }

    /// The Coulomb friction at the motor, N m: the friction-aware model's
    /// (motor and cart), else stage 3's `stage3_coulomb_nm`.
    pub fn total_coulomb_nm(&self, stage3_coulomb_nm: f64) -> f64 {
        self.friction_aware().map_or(stage3_coulomb_nm, |n| {
            n.tau_c_motor_nm + n.cart_coulomb_nm()
        })
    }

    /// The excitation as recorded, with the torque limit and the travel
    /// window of `ds` it ran under (the record moves out of `self`).
    pub fn take_excitation(
        &mut self,
        torque_max_nm: f64,
        ds: &DataSheet,
    ) -> crate::commission::ExcitationTrace {
        crate::commission::ExcitationTrace {
            time_s: std::mem::take(&mut self.excitation_time_s),
            torque_command_nm: std::mem::take(&mut self.excitation_torque_nm),
            position_m: std::mem::take(&mut self.excitation_position_m),
            torque_max_nm,
            travel_min_m: ds.travel_min_m,
            travel_max_m: ds.travel_max_m,
        }
    }
}

/// One open-loop PRBS experiment as recorded (also the health check's,
/// [`crate::health`]).
pub(crate) struct Excitation {
    /// Busy time of the axis at the first sample, s.
    pub t_start_s: f64,
    /// Where the excitation started, m: the requested centre, or where it
    /// was moved to against the drift of an earlier attempt.
    pub center_m: f64,
    /// PRBS period, samples.
    pub period: usize,
    /// Torque command (holding torque plus PRBS), N m.
    pub cmd: Vec<f64>,
    /// Torque the drive reports, N m.
    pub act: Vec<f64>,
    /// Motor angle, rad.
    pub ang: Vec<f64>,
    /// Motor-side position, m.
    pub pos: Vec<f64>,
}

/// Room a closed loop must have to take the axis over from an open-loop
/// excitation, beyond the look-ahead's stopping distance, m: the motor-side
/// vibration at the resonance and the catch's overshoot. An excitation that
/// comes closer to the window's edge ends early ([`excite`]).
pub const EXCITATION_GUARD_M: f64 = 0.01;

/// Attempts of an open-loop excitation, each started against the drift of
/// the one before ([`excite`]).
const EXCITATION_ATTEMPTS: usize = 3;

/// Start the progress stage `stage`, move to `center_m` under `hold` and
/// excite the axis open loop around `holding_nm` with a PRBS of `order` (the
/// clock of `ex`) and amplitude `amplitude_nm` for `periods` periods.
///
/// Open loop, the axis drifts (a holding torque a little off, little
/// friction on a slope: robustness study seed 13 plant #787 drifted 57 mm). Where
/// the closed loop could no longer take the axis over with
/// [`EXCITATION_GUARD_M`] to spare ([`Runner::closed_loop_handover_clear`]),
/// the attempt ends, the hold catches the axis, and the next attempt starts
/// as far against the drift as the drift of the whole record extrapolates
/// to (linear in time), so that it ends near where the first began; where
/// the window is too short for that drift, or after
/// [`EXCITATION_ATTEMPTS`] attempts, the axis is stopped and the result is
/// [`Error::Infeasible`].
///
/// [`Runner::closed_loop_handover_clear`]: super::super::runner::Runner::closed_loop_handover_clear
#[allow(clippy::too_many_arguments)]
pub(crate) fn excite(
    st: &mut Stages,
    stage: &str,
    hold: &CascadeConfig<f64>,
    center_m: f64,
    limits: &Limits,
    holding_nm: f64,
    amplitude_nm: f64,
    order: u32,
    periods: usize,
    ex: &ExcitationConfig,
) -> Result<Excitation> {
    let ts = st.runner.info().ts_s;
    // each attempt runs a copy of the same sequence from its start
    let sequence = Prbs::new(order, ex.clock_samples(ts), amplitude_nm)?;
    let period = sequence.period_samples() as usize;
    let n = period * periods;
    st.start(stage, n as u64);
    let mut center = center_m;
    let mut attempt = 1;
    let mut measured_drift = None;
    loop {
        let mut prbs = sequence;
        move_to(st.runner, hold, center, limits, 0.05)?;
        let mut e = Excitation {
            t_start_s: st.runner.busy_time_s(),
            center_m: center,
            period,
            cmd: Vec::with_capacity(n),
            act: Vec::with_capacity(n),
            ang: Vec::with_capacity(n),
            pos: Vec::with_capacity(n),
        };
        for _ in 0..n {
            let tau = holding_nm + prbs.step();
            let s = st.runner.step(tau, None)?;
            e.cmd.push(s.torque_command_nm);
            e.act.push(s.torque_actual_nm);
            e.ang.push(s.motor_angle_rad);
            e.pos.push(s.position_m);
            if !st.runner.closed_loop_handover_clear(EXCITATION_GUARD_M) {
                break;
            }
        }
        if e.cmd.len() == n {
            return Ok(e);
        }
        let ended = super::drift::EndedAttempt {
            attempt,
            center_m: center,
            ended_m: st.runner.position_m(),
            done: e.cmd.len(),
            n,
            ts_s: ts,
        };
        let reading = ended.reading(EXCITATION_GUARD_M);
        let drift = reading.drift_m.or(measured_drift);
        let window = st.runner.supervisor().limits();
        // against a drift this attempt measured; where it began otherwise
        let preferred = center - reading.drift_m.unwrap_or(0.0);
        let next = super::drift::restart_center_m(
            preferred,
            drift.unwrap_or(0.0),
            window.travel_min_m,
            window.travel_max_m,
            EXCITATION_GUARD_M,
        );
        let Some(next) = next.filter(|_| attempt < EXCITATION_ATTEMPTS) else {
            // the axis still moves open loop: bring it to rest first
            let rest = st.runner.stop()?;
            return Err(Error::Infeasible {
                reason: super::drift::give_up_reason(stage, &reading, measured_drift, rest),
            });
        };
        measured_drift = drift;
        center = next;
        st.log.push(format!(
            "{stage}: {}; started again at {:.1} mm",
            reading.why,
            center * 1e3
        ));
        attempt += 1;
    }
}

/// The ETFE settings of an excitation with `period` samples per period
/// and `skip_periods` transient periods: Clary's method II, the band from
/// the fit's lower limit to 0.4 f_s (below it the PRBS spectrum and the
/// Tustin/ZOH effects stay mild) or the PRBS clock frequency.
pub(crate) fn etfe_config(
    ts: f64,
    period: usize,
    skip_periods: usize,
    ex: &ExcitationConfig,
) -> EtfeConfig {
    let f_max = 0.4 / ts;
    let clock = ex.clock_samples(ts);
    EtfeConfig {
        ts_s: ts,
        period_samples: period,
        skip_periods,
        integrator: true,
        band_hz: Some((ex.fit_band_min_hz, f_max.min(1.0 / (clock as f64 * ts)))),
        ..EtfeConfig::default()
    }
}

/// The two-mass fit of `frf` (the data-sheet `Theta_e`), refused when the
/// fitted model has no resonance inside the measured band.
pub(crate) fn fit_frf(
    frf: &Frf,
    ecfg: &EtfeConfig,
    ex: &ExcitationConfig,
    datasheet: &DataSheet,
) -> Result<TwoMassFit> {
    let fcfg = FitConfig {
        theta_e: Some(datasheet.theta_e_kg_m2),
        i_t: datasheet.i_t_m,
        n_log_lines: ex.n_log_lines,
        antiresonance_band_hz: datasheet.antiresonance_band_hz,
        ..FitConfig::default()
    };
    let fit = fit_two_mass(frf, &fcfg)?;
    let f_band = ecfg.band_hz.map(|b| b.1).unwrap_or(0.5 / ecfg.ts_s);
    if !(fit.f_z_hz.is_finite()
        && fit.f_r_hz.is_finite()
        && fit.f_r_hz < f_band
        && fit.f_z_hz > 0.0)
    {
        return Err(Error::FitFailed {
            reason: format!(
                "the fitted model (f_r {:.3e} Hz, f_z {:.3e} Hz) has no resonance inside the measured band up to {:.0} Hz (PRBS clock {:.2} ms); check the data sheet, or excite a wider band with a shorter clock (--prbs-clock-ms, at least one sample of {:.2} ms)",
                fit.f_r_hz, fit.f_z_hz, f_band, ex.clock_samples(ecfg.ts_s) as f64 * ecfg.ts_s * 1e3, ecfg.ts_s * 1e3
            ),
        });
    }
    Ok(fit)
}

/// Upper end of the friction-aware fit's band as a multiple of the FRF
/// fit's resonance: the lines above carry the motor inertia alone.
const NONLINEAR_BAND_RESONANCES: f64 = 2.5;

/// The friction-aware fit of the nonlinear model (2.30) to the excitation
/// `e` ([`crate::ident::nonlinear`]), started from the FRF fit `fit`, with
/// the dead time, the cart force the holding torque balances and the
/// Coulomb friction measured in stage 3 as its start. `held`: a model whose
/// mass `m_c` and motor inertia `Theta_e` are held (the stiffness elsewhere
/// along the stroke, stages 5b/5c: they do not change with the position);
/// `None`: both are solved.
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit_friction_aware(
    e: &Excitation,
    ecfg: &EtfeConfig,
    fit: &TwoMassFit,
    held: Option<&TwoMassParams>,
    dead_time_s: f64,
    holding_nm: f64,
    coulomb_hint_nm: f64,
    datasheet: &DataSheet,
) -> Result<NonlinearFit> {
    let (lo, hi) = ecfg.band_hz.unwrap_or((0.0, 0.5 / ecfg.ts_s));
    let start = match held {
        Some(m) => TwoMassParams {
            m_c: m.m_c,
            theta_e: m.theta_e,
            ..fit.params
        },
        None => fit.params,
    };
    fit_nonlinear(
        &e.cmd,
        &e.ang,
        &start,
        &NonlinearConfig {
            // solved where not held: the data sheet's motor inertia lacks
            // what else turns with the belt (the end pulley: the fitted rigid
            // inertia was 2 % light on average with it fixed, within 0.1 %
            // solved)
            theta_e: held.map(|m| m.theta_e),
            i_t: datasheet.i_t_m,
            ts_s: ecfg.ts_s,
            period_samples: ecfg.period_samples,
            skip_periods: ecfg.skip_periods,
            dead_time_s,
            band_hz: (lo, hi.min(NONLINEAR_BAND_RESONANCES * fit.f_r_hz)),
            cart_force_n: -holding_nm / datasheet.i_t_m,
            coulomb_hint_nm: coulomb_hint_nm.max(0.0),
            fixed_mass: held.is_some(),
        },
    )
}

/// Range of the friction-aware fit's motor inertia `Theta_e` relative to the
/// data sheet's in which the fit is used: the fit solves `Theta_e` (the data
/// sheet's lacks the end pulley and the belt: on the study's plants the fit
/// gave 1.00-1.03 times it); far outside, the record or the data sheet is
/// wrong, and the FRF fit with the data sheet's value stands.
const THETA_E_RANGE: (f64, f64) = (0.7, 1.5);

/// The model the design uses (see [`Identification::fit`]), the
/// friction-aware fit if there is one, and why it is not used, if not.
pub(crate) fn choose_model(
    frf_fit: &TwoMassFit,
    nonlinear: Result<NonlinearFit>,
) -> (TwoMassFit, Option<NonlinearFit>, Option<String>) {
    let theta_ratio = |nl: &NonlinearFit| nl.params.theta_e / frf_fit.params.theta_e;
    match nonlinear {
        Ok(nl) if !(THETA_E_RANGE.0..=THETA_E_RANGE.1).contains(&theta_ratio(&nl)) => {
            let why = format!(
                "the friction-aware fit's motor inertia is {:.2} times the data sheet's",
                theta_ratio(&nl)
            );
            (frf_fit.clone(), Some(nl), Some(why))
        }
        Ok(nl) if nl.improves_on_linear() => (
            TwoMassFit {
                params: nl.params,
                start: frf_fit.params,
                features: frf_fit.features,
                uncertainty: nl.uncertainty,
                f_r_hz: nl.f_r_hz,
                f_z_hz: nl.f_z_hz,
                fit_rms_db: frf_fit.fit_rms_db,
                n_lines: nl.n_lines,
                free_inertia: false,
                units: frf_fit.units,
                model: FitModel::Nonlinear,
            },
            Some(nl),
            None,
        ),
        Ok(nl) => {
            let why = format!(
                "the friction-aware fit explains the record no better: residual {:.3} against {:.3}",
                nl.residual, nl.linear_residual
            );
            (frf_fit.clone(), Some(nl), Some(why))
        }
        Err(e) => (
            frf_fit.clone(),
            None,
            Some(format!("friction-aware fit: {e}")),
        ),
    }
}

/// Stage 5: excite around `holding_nm` with amplitude `amplitude_nm` at
/// `center_m` (held there by `hold` between the moves) and identify;
/// `coulomb_hint_nm` is the Coulomb friction stage 3 measured (N m), the
/// friction-aware fit's start.
#[allow(clippy::too_many_arguments)]
pub fn identification(
    st: &mut Stages,
    hold: &CascadeConfig<f64>,
    center_m: f64,
    limits: &Limits,
    holding_nm: f64,
    amplitude_nm: f64,
    coulomb_hint_nm: f64,
    ex: &ExcitationConfig,
    datasheet: &DataSheet,
) -> Result<Identification> {
    let ts = st.runner.info().ts_s;
    let e = excite(
        st,
        "identification (open loop)",
        hold,
        center_m,
        limits,
        holding_nm,
        amplitude_nm,
        ex.prbs_order,
        ex.periods + ex.skip_periods,
        ex,
    )?;
    let skip = ex.skip_periods * e.period;
    let measured_position_m =
        e.pos[skip..].iter().sum::<f64>() / (e.pos.len() - skip).max(1) as f64;
    let (frf, frf_fit, dead_time, nonlinear) = st.compute(|| -> Result<_> {
        let ecfg = etfe_config(ts, e.period, ex.skip_periods, ex);
        let frf = etfe(&e.cmd, &e.ang, &ecfg)?;
        let frf_actual = etfe(&e.act, &e.ang, &ecfg)?;
        let fit = fit_frf(&frf, &ecfg, ex, datasheet)?;
        let max_dt = (MAX_DEAD_TIME_S / ts) as usize;
        let dead_time = estimate_dead_time(&frf, &frf_actual, fit.f_r_hz, max_dt)?;
        let nonlinear = fit_friction_aware(
            &e,
            &ecfg,
            &fit,
            None,
            dead_time.seconds,
            holding_nm,
            coulomb_hint_nm,
            datasheet,
        );
        Ok((frf, fit, dead_time, nonlinear))
    })?;
    let (fit, nonlinear, nonlinear_note) = choose_model(&frf_fit, nonlinear);
    let mut identified =
        IdentifiedModel::from_fit(&fit, &frf, dead_time.seconds, measured_position_m);
    // the quality of the FRF measurement and of its fit, whichever model is used
    identified.fit_rms_db = frf_fit.fit_rms_db;
    identified.stroke_variation = datasheet.stroke_variation;
    if let Some(nl) = nonlinear.as_ref().filter(|_| nonlinear_note.is_none()) {
        identified.method = crate::record::model::IdentificationMethod::FrictionAware;
        identified.motor_coulomb_nm = Some(nl.tau_c_motor_nm);
        identified.cart_coulomb_n = Some(nl.f_c_cart_n);
    }
    let p = fit.params;
    let model = match &nonlinear_note {
        None => format!(
            "friction-aware: Coulomb motor {:.3} N m, cart {:.2} N ({:.3} N m), belt damping {:.1} N s/m, residual {:.3} (FRF fit {:.3}); FRF fit f_z {:.2} Hz, m_c {:.2} kg",
            nonlinear.as_ref().map_or(f64::NAN, |n| n.tau_c_motor_nm),
            nonlinear.as_ref().map_or(f64::NAN, |n| n.f_c_cart_n),
            nonlinear.as_ref().map_or(f64::NAN, |n| n.cart_coulomb_nm()),
            p.d,
            nonlinear.as_ref().map_or(f64::NAN, |n| n.residual),
            nonlinear.as_ref().map_or(f64::NAN, |n| n.linear_residual),
            frf_fit.f_z_hz,
            frf_fit.params.m_c,
        ),
        Some(why) => format!("FRF fit ({why})"),
    };
    let line = format!(
        "f_r {:.2} Hz, f_z {:.2} Hz, m_c {:.2} kg, c {:.1} kN/m, d_m {:.2} N s/m, d_c {:.2} N s/m, dead time {:.2} ms, fit {:.2} dB rms, coherence {:.3}; model: {model}",
        fit.f_r_hz,
        fit.f_z_hz,
        p.m_c,
        p.c / 1e3,
        p.d_m,
        p.d_c,
        dead_time.seconds * 1e3,
        frf_fit.fit_rms_db,
        identified.mean_coherence
    );
    // what the two-mass model does not explain (ident::residual)
    let line = match crate::ident::fit_residual(&frf, &frf_fit) {
        Ok(r) => format!("{line}; {}", r.short()),
        Err(_) => line,
    };
    st.finish("identification", line);
    let n = e.cmd.len();
    Ok(Identification {
        frf,
        fit,
        frf_fit,
        nonlinear,
        nonlinear_note,
        measured_position_m,
        center_m: e.center_m,
        excursion_m: e
            .pos
            .iter()
            .map(|p| (p - e.center_m).abs())
            .fold(0.0, f64::max),
        dead_time,
        identified,
        excitation_time_s: (0..n).map(|k| e.t_start_s + k as f64 * ts).collect(),
        excitation_torque_nm: e.cmd,
        excitation_position_m: e.pos,
    })
}

/// Distance between the identification position and the validation target
/// below which the main fit's stiffness stands for the target's, m. The
/// replacement stiffness (2.26) changes by about `dxi / (l_1 + l_e)` along
/// the stroke, a few percent per 100 mm on the simulated axes; 5 mm keep the
/// error of a 1.5 mm static stretch (a heavy vertical axis) near 10 um.
pub const SAME_POSITION_M: f64 = 0.005;
/// PRBS order of the stiffness measurement at the validation target.
pub const TARGET_PRBS_ORDER: u32 = 9;
/// PRBS order of the stiffness measurement near the validation start (stage
/// 5c): two less than at the target, a quarter of its period (0.2 s at the
/// 1.6 ms clock, lines 4.9 Hz apart), 0.6 s of axis time instead of 2.5 s.
/// The stiffness there only shapes the compliance between the start and
/// the target (the static stretch at rest uses the target's); the FRF fit
/// only gives the start values of the friction-aware fit, which fits the
/// time record with the main model's mass and motor inertia held, so it
/// finds `c` from the record, not from the lines (within 5 % of (2.26) on
/// study plant 131, `tests/difficult_axes.rs`).
pub const START_SIDE_PRBS_ORDER: u32 = TARGET_PRBS_ORDER - 2;

/// What the identification leaves for measuring the belt stiffness
/// elsewhere (stages 5b, 5c): the model, where it was measured, and the
/// excitation's settings.
pub struct StiffnessInputs<'a> {
    /// The model the design uses (its `m_c` and `Theta_e` hold everywhere).
    pub main: &'a TwoMassFit,
    /// Where the model was measured (the mean position of its excitation), m.
    pub ident_position_m: f64,
    /// Where its excitation was centred, m: a position within
    /// [`SAME_POSITION_M`] of it is not measured again.
    pub excitation_center_m: f64,
    /// Positioning limits of the moves in between.
    pub limits: &'a Limits,
    /// Holding torque, N m.
    pub holding_nm: f64,
    /// PRBS amplitude, N m.
    pub amplitude_nm: f64,
    /// Current-loop dead time, s.
    pub dead_time_s: f64,
    /// Coulomb friction at the motor (the friction-aware fit's start), N m.
    pub coulomb_nm: f64,
    /// Excitation settings.
    pub ex: &'a ExcitationConfig,
    /// The data sheet.
    pub datasheet: &'a DataSheet,
}

/// The belt stiffness at `position_m` from an open-loop PRBS there (one
/// transient period and the two periods the coherence needs, of order
/// `order`): the FRF fit for the start values, then the
/// friction-aware fit with the main model's mass and motor inertia held
/// (the mass does not change along the stroke; on a sticking cart the FRF
/// fit's `c` carries the friction's error). `Ok(Err(reason))` where no fit
/// holds (the caller keeps what it has).
fn measure_stiffness(
    st: &mut Stages,
    stage: &str,
    hold: &CascadeConfig<f64>,
    position_m: f64,
    order: u32,
    inp: &StiffnessInputs,
) -> Result<std::result::Result<TargetStiffness, String>> {
    let ts = st.runner.info().ts_s;
    let ex = inp.ex;
    let skip = ex.skip_periods;
    let e = excite(
        st,
        stage,
        hold,
        position_m,
        inp.limits,
        inp.holding_nm,
        inp.amplitude_nm,
        order,
        skip + 2,
        ex,
    )?;
    let main = inp.main.params;
    let fitted = st.compute(|| -> Result<_> {
        let ecfg = etfe_config(ts, e.period, skip, ex);
        let frf = etfe(&e.cmd, &e.ang, &ecfg)?;
        let frf_fit = fit_frf(&frf, &ecfg, ex, inp.datasheet)?;
        let nl = fit_friction_aware(
            &e,
            &ecfg,
            &frf_fit,
            Some(&main),
            inp.dead_time_s,
            inp.holding_nm,
            inp.coulomb_nm,
            inp.datasheet,
        );
        Ok(match nl {
            Ok(nl) if nl.improves_on_linear() => (nl.params.c, nl.f_z_hz),
            _ => (frf_fit.params.c, frf_fit.f_z_hz),
        })
    });
    match fitted {
        Ok((c, f_z)) => Ok(Ok(TargetStiffness::constant(e.center_m, c, f_z, true))),
        Err(
            e @ (Error::FitFailed { .. } | Error::TooShort { .. } | Error::NoExcitation { .. }),
        ) => Ok(Err(e.to_string())),
        Err(e) => Err(e),
    }
}

/// Where the belt stiffness near the validation start is measured (stage
/// 5c), m: a quarter of the window (at least 0.1 m) inside its lower edge,
/// and at least twice the identification's largest excursion from its
/// centre `excursion_m` (plus 20 mm) inside it. The open-loop PRBS moves
/// the axis by tens of mm, on a tilted axis downhill, a light cart most; at
/// the 12 % the identification position keeps from the upper edge, 24 of the
/// study's first 270 plants ran into a travel stop there, and two light carts
/// on short strokes at 25 %. The compliance (2.26) is quadratic in the
/// position, so the point need not be at the start itself.
pub fn start_side_position_m(ds: &DataSheet, excursion_m: f64) -> f64 {
    let width = ds.travel_max_m - ds.travel_min_m;
    let room = if excursion_m.is_finite() {
        2.0 * excursion_m + 0.02
    } else {
        0.0
    };
    ds.travel_min_m + (0.25 * width).max(0.1).max(room)
}

/// Stages 5b and 5c: the belt stiffness where the validation move
/// ends (`target_m`) and near where it starts (`start_side_m`), each by an
/// open-loop PRBS there ([`measure_stiffness`]); with the identification
/// position's, the compliance through the three (exactly quadratic for
/// (2.26), [`TargetStiffness::through`]). A position within
/// [`SAME_POSITION_M`] of one measured already is not measured again; a
/// measurement that does not fit is left out and the log says so; three
/// points that do not make a belt (a convex compliance: measurement error)
/// leave the two that span the move, then the target's stiffness alone.
pub fn stiffness_profile(
    st: &mut Stages,
    hold: &CascadeConfig<f64>,
    target_m: f64,
    start_side_m: f64,
    inp: &StiffnessInputs,
) -> Result<TargetStiffness> {
    let main = inp.main;
    let id = inp.ident_position_m;
    let center = inp.excitation_center_m;
    let at_id = TargetStiffness::constant(id, main.params.c, main.f_z_hz, false);
    // one measurement per position not measured yet, each with its log line
    let measure =
        |st: &mut Stages, what: &str, x: f64, order: u32| -> Result<Option<TargetStiffness>> {
            let stage = format!("belt stiffness {what} (open loop)");
            let label = format!("belt stiffness {what}");
            if (x - center).abs() < SAME_POSITION_M {
                st.start(&label, 0);
                st.finish(
                    &label,
                    format!(
                        "{:.1} mm is the identification position: c {:.1} kN/m",
                        x * 1e3,
                        main.params.c / 1e3
                    ),
                );
                return Ok(None);
            }
            let (line, out) = match measure_stiffness(st, &stage, hold, x, order, inp)? {
                Ok(t) => (
                    format!(
                        "at {:.1} mm: f_z {:.2} Hz, c {:.1} kN/m",
                        x * 1e3,
                        t.f_z_hz,
                        t.c_n_per_m / 1e3
                    ),
                    Some(t),
                ),
                Err(why) => (format!("not measured at {:.1} mm ({why})", x * 1e3), None),
            };
            st.finish(&label, line);
            Ok(out)
        };
    let target = measure(st, "at the target", target_m, TARGET_PRBS_ORDER)?;
    let start_side = if start_side_m > target_m - SAME_POSITION_M {
        None
    } else {
        measure(st, "near the start", start_side_m, START_SIDE_PRBS_ORDER)?
    };
    // The compliance through the identification position's stiffness and
    // what was measured, about the target where it was measured (else
    // about the identification position).
    let reference = target.unwrap_or(at_id);
    let mut others: Vec<(f64, f64)> = Vec::new();
    if target.is_some() {
        others.push((id, main.params.c));
    }
    others.extend(start_side.map(|t| (t.position_m, t.c_n_per_m)));
    let window = (inp.datasheet.travel_min_m, inp.datasheet.travel_max_m);
    let spanning: Vec<(f64, f64)> = start_side
        .map(|t| (t.position_m, t.c_n_per_m))
        .into_iter()
        .collect();
    let (profile, shape) = match reference.through(&others, window, SAME_POSITION_M) {
        Some(p) if others.len() == 2 => (p, "quadratic through three positions"),
        Some(p) if others.len() == 1 => (p, "linear through two positions"),
        Some(p) => (p, "one stiffness for the stroke"),
        None => match reference.through(&spanning, window, SAME_POSITION_M) {
            Some(p) if !spanning.is_empty() => (
                p,
                "linear through two positions (the three do not make a belt's compliance)",
            ),
            _ => (reference, "one stiffness for the stroke"),
        },
    };
    st.start("belt stiffness along the stroke", 0);
    st.finish(
        "belt stiffness",
        format!(
            "{shape}: c {:.1} kN/m at {:.1} mm, {:.1} kN/m at {:.1} mm (window ends), identification {:.1} kN/m at {:.1} mm",
            profile.stiffness_at(window.0) / 1e3,
            window.0 * 1e3,
            profile.stiffness_at(window.1) / 1e3,
            window.1 * 1e3,
            main.params.c / 1e3,
            id * 1e3
        ),
    );
    Ok(profile)
}
