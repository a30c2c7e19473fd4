//! The health check's experiment on the axis: at most a few seconds, built
//! from the commissioning's stages (the runner and its supervisor, the
//! take-over, the open-loop PRBS and its fits, the constant-velocity points):
//!
//! 1. take the axis (stage 2) with the bootstrap controller fitted to the
//!    baseline's friction (stage 3's fit, without stage 3's runs);
//! 2. a slow run up and back (friction at the slow speed, both ways);
//! 3. the move to the far position is a fast run up (friction at speed);
//! 4. two open-loop PRBS blocks there, at the baseline's amplitude and at
//!    half of it (3.2-3.5 with the friction-aware fit: `f_r`, `f_z`, `c`,
//!    `m_c`, damping; the two amplitudes show whether the resonance
//!    depends on the amplitude);
//! 5. the move to the near position is a fast run down;
//! 6. one PRBS block there (the stiffness with the far model's mass held,
//!    as stages 5b/5c);
//! 7. (3.36) with an offset through the four runs: Coulomb and viscous
//!    friction and the holding torque, each with its uncertainty
//!    ([`super::friction`]).

use super::baseline::Baseline;
use super::config::HealthExperiment;
use super::friction::{fit_friction, plateau_torque_sigma, FrictionEstimate};
use crate::commission::config::{
    positioning_limits, POSITIONING_ACCELERATION_M_S2, POSITIONING_JERK_M_S3,
};
use crate::commission::motion::{track, FollowingError, TrackOptions, TrackRecord};
use crate::commission::safety::StopCapability;
use crate::commission::stages::friction::{constant_velocity_point_with_inertia, RUNNING_IN_S};
use crate::commission::stages::holding_torque::{fitted_bootstrap, Holding};
use crate::commission::stages::identification::{
    choose_model, etfe_config, excite, fit_frf, fit_friction_aware, start_side_position_m,
};
use crate::commission::stages::take_axis::take_axis;
use crate::commission::stages::Stages;
use crate::commission::{DataSheet, ExcitationConfig};
use crate::ident::etfe::etfe;
use crate::ident::fit::{FitModel, ParamUncertainty};
use crate::ident::friction::ConstantVelocityRun;
use crate::model::TwoMassParams;
use crate::record::model::IdentificationMethod;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};
use serde::{Deserialize, Serialize};

/// A two-mass model measured at one position and amplitude.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PositionFit {
    /// Mean motor-side position over the compared periods, m (NaN / `null`:
    /// unknown, a recording).
    #[serde(with = "super::nan_as_null")]
    pub position_m: f64,
    /// PRBS amplitude `A_PRBS`, N m (NaN / `null`: unknown).
    #[serde(with = "super::nan_as_null")]
    pub amplitude_nm: f64,
    /// The model (friction-aware where the baseline's is and the fit holds).
    pub params: TwoMassParams,
    /// Its one-sigma uncertainties (`None`: not computed).
    pub sigma: Option<ParamUncertainty>,
    /// How it was identified.
    pub method: IdentificationMethod,
    /// Whether `m_c` and `Theta_e` were held at the far model's.
    pub mass_held: bool,
    /// The thesis' FRF fit (3.5) of the same block (its damping).
    pub frf_fit: TwoMassParams,
    /// Its uncertainties.
    pub frf_sigma: Option<ParamUncertainty>,
    /// RMS error of the FRF fit, dB.
    #[serde(with = "super::nan_as_null")]
    pub fit_rms_db: f64,
}

impl PositionFit {
    /// Resonance (2.44), Hz.
    pub fn f_r_hz(&self) -> f64 {
        self.params.f_r_hz()
    }

    /// Antiresonance (2.45), Hz.
    pub fn f_z_hz(&self) -> f64 {
        self.params.f_z_hz()
    }
}

/// One friction run: its constant-velocity point and the standard error of
/// its mean torque.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionRun {
    /// Mean motor velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Mean torque command (holding torque and friction), N m.
    pub mean_torque_nm: f64,
    /// Its standard error, N m.
    pub sigma_nm: f64,
    /// Where the run went, m (from, to).
    pub from_m: f64,
    /// End of the run, m.
    pub to_m: f64,
}

/// What the experiment measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    /// Far from the motor, full amplitude (`None`: not fitted, see
    /// [`Self::failures`]).
    pub far: Option<PositionFit>,
    /// Far from the motor, half the amplitude (mass held; `None` for a
    /// recording).
    pub far_half: Option<PositionFit>,
    /// Near the start, full amplitude (mass held; `None` for a recording).
    pub near: Option<PositionFit>,
    /// The friction runs.
    pub runs: Vec<FrictionRun>,
    /// (3.36) with an offset through them (`None`: not measured).
    pub friction: Option<FrictionEstimate>,
    /// The excitation blocks whose response no longer fits a two-mass
    /// model, with why (a belt that behaves nonlinearly: a slack span,
    /// backlash).
    #[serde(default)]
    pub failures: Vec<String>,
}

/// The experiment (see the module docs) on the runner of `st`, after stage
/// 1 (`bootstrap` the data-sheet controller, `torque_max_nm` the limit).
pub(crate) fn run(
    st: &mut Stages,
    bootstrap: CascadeConfig<f64>,
    ds: &DataSheet,
    baseline: &Baseline,
    exp: &HealthExperiment,
    torque_max_nm: f64,
) -> Result<Measured> {
    let ts = st.runner.info().ts_s;
    // 1. take the axis; the bootstrap fitted to the baseline's friction
    let taken = take_axis(st, bootstrap, ds, torque_max_nm)?;
    let far_m = taken.identification_position_m;
    let bf = &baseline.friction;
    let assumed = Holding {
        holding_nm: bf.holding_torque_nm,
        friction_nm: bf.coulomb_nm.max(0.0),
        viscous_nm_s_per_rad: bf.viscous_nm_s_per_rad.max(0.0),
    };
    let boot = fitted_bootstrap(&assumed, ds, ts, torque_max_nm)?;
    st.runner.set_stop_controller(boot);
    st.runner.set_stop_capability(StopCapability::from_axis(
        torque_max_nm,
        ds.rigid_inertia(),
        ds.i_t_m,
        assumed.holding_nm,
        assumed.friction_nm,
    )?)?;
    let inertia = baseline.model.params().rigid_inertia();
    let ring_hz = baseline.model.f_z_hz;

    // 2. the slow runs up and back
    st.start("friction runs", 0);
    let lo = ds.travel_min_m + SLOW_RUN_CLEARANCE_M;
    let hi = ds.travel_max_m - SLOW_RUN_CLEARANCE_M - exp.slow_run_m;
    let start = st.runner.position_m().clamp(lo, hi.max(lo));
    let limits = |v: f64, jerk: f64| Limits {
        v_max: v,
        v_min: -v,
        a_max: POSITIONING_ACCELERATION_M_S2,
        a_min: -POSITIONING_ACCELERATION_M_S2,
        j_max: jerk,
        j_min: -jerk,
        position_min: ds.travel_min_m,
        position_max: ds.travel_max_m,
    };
    let mut runs = Vec::new();
    let slow = limits(exp.slow_speed_m_s, SLOW_RUN_JERK_M_S3);
    let fast = limits(exp.fast_speed_m_s, POSITIONING_JERK_M_S3);
    if (st.runner.position_m() - start).abs() > 1e-3 {
        crate::commission::motion::move_to(st.runner, &boot, start, &positioning_limits(ds), 0.02)?;
    }
    for target in [start + exp.slow_run_m, start] {
        runs.extend(friction_run(st, &boot, target, &slow, inertia, ring_hz)?);
    }
    // 3. the fast run up to the far position
    runs.extend(friction_run(st, &boot, far_m, &fast, inertia, ring_hz)?);
    let so_far = friction_of(&runs);
    let holding_nm = so_far.map_or(assumed.holding_nm, |f| f.holding_nm);
    let coulomb_nm = so_far.map_or(assumed.friction_nm, |f| f.coulomb_nm.max(0.0));
    st.finish(
        "friction runs",
        format!(
            "{} runs at {:.2} and {:.2} m/s; holding torque {holding_nm:+.4} N m",
            runs.len(),
            exp.slow_speed_m_s,
            exp.fast_speed_m_s
        ),
    );
    let boot_hold = CascadeConfig {
        torque_offset_nm: holding_nm,
        ..boot
    };
    st.runner.set_stop_controller(boot_hold);

    // 4. two amplitudes far from the motor
    let ex = ExcitationConfig {
        prbs_order: exp.prbs_order,
        clock_period_s: exp.clock_period_s,
        periods: exp.periods,
        skip_periods: 1,
        ..ExcitationConfig::default()
    };
    let amplitude = baseline
        .excitation_amplitude_nm
        .unwrap_or(ex.amplitude_max_fraction * torque_max_nm * 0.5)
        .min(ex.amplitude_max_fraction * torque_max_nm);
    let block = Block {
        hold: &boot_hold,
        limits: &positioning_limits(ds),
        holding_nm,
        coulomb_nm,
        ex: &ex,
        ds,
        dead_time_s: baseline.model.dead_time_s,
        same_method: baseline.model.method,
    };
    let mut failures = Vec::new();
    let mut fitted = |what: &str, r: std::result::Result<(PositionFit, f64), String>| match r {
        Ok(f) => Some(f),
        Err(why) => {
            failures.push(format!("{what}: {why}"));
            None
        }
    };
    let far = fitted(
        "far from the motor",
        block.measure(st, "excitation far", far_m, amplitude, None)?,
    );
    let excursion = far.as_ref().map_or(f64::NAN, |f| f.1);
    let far = far.map(|f| f.0);
    let held = far.as_ref().map(|f| f.params);
    let far_half = fitted(
        "far from the motor at half the amplitude",
        block.measure(
            st,
            "excitation far, half amplitude",
            far_m,
            0.5 * amplitude,
            held.as_ref(),
        )?,
    )
    .map(|f| f.0);

    // 5. the fast run down to the near position; 6. one block there
    let near_m = start_side_position_m(ds, excursion);
    runs.extend(friction_run(
        st, &boot_hold, near_m, &fast, inertia, ring_hz,
    )?);
    let near = fitted(
        "near the start",
        block.measure(st, "excitation near", near_m, amplitude, held.as_ref())?,
    )
    .map(|f| f.0);

    // 7. the friction through the four runs
    let friction = friction_of(&runs).ok_or_else(|| Error::TooShort {
        what: "health check friction runs with a constant-velocity part both ways at two speeds"
            .into(),
        needed: 3,
        got: runs.len(),
    })?;
    Ok(Measured {
        far,
        far_half,
        near,
        runs,
        friction: Some(friction),
        failures,
    })
}

/// Distance of the slow runs from the window's edges, m.
const SLOW_RUN_CLEARANCE_M: f64 = 0.03;
/// Jerk of the slow runs, m/s^3 (stage 3's).
const SLOW_RUN_JERK_M_S3: f64 = 100.0;

/// (3.36) with an offset through `runs`, where they determine it.
fn friction_of(runs: &[FrictionRun]) -> Option<FrictionEstimate> {
    let points: Vec<ConstantVelocityRun> = runs
        .iter()
        .map(|r| ConstantVelocityRun {
            velocity_rad_s: r.velocity_rad_s,
            mean_torque_nm: r.mean_torque_nm,
        })
        .collect();
    let sigma: Vec<f64> = runs.iter().map(|r| r.sigma_nm).collect();
    fit_friction(&points, Some(&sigma)).ok()
}

/// Run from where the axis is to `target_m` at rest within `limits` under
/// `ctrl`, and its constant-velocity point (momentum balance with the rigid
/// `inertia_kg_m2`, averaged over whole periods of the ringing at
/// `ring_hz`) with its standard error; `None` where the run has no plateau.
fn friction_run(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    target_m: f64,
    limits: &Limits,
    inertia_kg_m2: f64,
    ring_hz: f64,
) -> Result<Option<FrictionRun>> {
    let from = st.runner.position_m();
    let traj = Trajectory::plan(&State::at_rest(from), &State::at_rest(target_m), limits)?;
    let rec = track(
        st.runner,
        ctrl,
        &traj,
        0.02,
        TrackOptions {
            following_error: FollowingError::Limited,
            ..Default::default()
        },
    )?;
    let v = limits.v_max;
    let Some(point) =
        constant_velocity_point_with_inertia(&rec, v, Some(ring_hz), Some(inertia_kg_m2))
    else {
        return Ok(None);
    };
    let sigma = plateau_sigma(&rec, v, ring_hz);
    Ok(sigma.is_finite().then_some(FrictionRun {
        velocity_rad_s: point.velocity_rad_s,
        mean_torque_nm: point.mean_torque_nm,
        // a plateau of constant torque (no noise at all) still has the
        // encoder's resolution: never below 1e-6 N m
        sigma_nm: sigma.max(1e-6),
        from_m: from,
        to_m: target_m,
    }))
}

/// The standard error of a run's plateau torque: blocks of one ringing
/// period after the running-in ([`plateau_torque_sigma`]), N m.
fn plateau_sigma(rec: &TrackRecord, v: f64, ring_hz: f64) -> f64 {
    let ts = rec.time_s.get(1).copied().unwrap_or(1.0) - rec.time_s.first().copied().unwrap_or(0.0);
    let skip = (RUNNING_IN_S / ts).round() as usize;
    let torque: Vec<f64> = (0..rec.samples.len())
        .filter(|&k| (rec.desired_velocity_m_s[k].abs() - v).abs() < 1e-6 * v.max(1.0))
        .skip(skip)
        .map(|k| rec.samples[k].torque_command_nm)
        .collect();
    let block = ((1.0 / (ring_hz * ts)).round() as usize).max(2);
    plateau_torque_sigma(&torque, block)
}

/// What every PRBS block of the health check shares.
struct Block<'a> {
    hold: &'a CascadeConfig<f64>,
    limits: &'a Limits,
    holding_nm: f64,
    coulomb_nm: f64,
    ex: &'a ExcitationConfig,
    ds: &'a DataSheet,
    dead_time_s: f64,
    same_method: IdentificationMethod,
}

impl Block<'_> {
    /// One open-loop PRBS block at `center_m` with `amplitude_nm` and its
    /// fit; `held`: the model whose `m_c` and `Theta_e` are held. Returns
    /// the fit and the largest excursion from the centre, m; `Ok(Err(why))`
    /// where the response does not fit a two-mass model.
    fn measure(
        &self,
        st: &mut Stages,
        stage: &str,
        center_m: f64,
        amplitude_nm: f64,
        held: Option<&TwoMassParams>,
    ) -> Result<std::result::Result<(PositionFit, f64), String>> {
        let ts = st.runner.info().ts_s;
        let ex = self.ex;
        let e = excite(
            st,
            stage,
            self.hold,
            center_m,
            self.limits,
            self.holding_nm,
            amplitude_nm,
            ex.prbs_order,
            ex.periods + ex.skip_periods,
            ex,
        )?;
        let skip = ex.skip_periods * e.period;
        let position_m = e.pos[skip..].iter().sum::<f64>() / (e.pos.len() - skip).max(1) as f64;
        let excursion = e
            .pos
            .iter()
            .map(|p| (p - e.center_m).abs())
            .fold(0.0, f64::max);
        let fitted = st.compute(|| -> Result<_> {
            let ecfg = etfe_config(ts, e.period, ex.skip_periods, ex);
            let frf = etfe(&e.cmd, &e.ang, &ecfg)?;
            let frf_fit = fit_frf(&frf, &ecfg, ex, self.ds)?;
            let nl = fit_friction_aware(
                &e,
                &ecfg,
                &frf_fit,
                held,
                self.dead_time_s,
                self.holding_nm,
                self.coulomb_nm,
                self.ds,
            );
            Ok((frf_fit, nl))
        });
        let (frf_fit, nl) = match fitted {
            Ok(f) => f,
            Err(
                e @ (Error::FitFailed { .. } | Error::TooShort { .. } | Error::NoExcitation { .. }),
            ) => {
                let why = e.to_string();
                st.finish(
                    stage,
                    format!(
                        "at {:.1} mm, A_PRBS {amplitude_nm:.3} N m: not fitted ({why})",
                        position_m * 1e3
                    ),
                );
                return Ok(Err(why));
            }
            Err(e) => return Err(e),
        };
        let (params, sigma, method, mass_held) = match (self.same_method, held) {
            // the baseline's method: the friction-aware fit where it holds
            (IdentificationMethod::FrictionAware, _) => match nl {
                Ok(nl) if held.is_some() => (
                    nl.params,
                    nl.uncertainty,
                    IdentificationMethod::FrictionAware,
                    true,
                ),
                nl => {
                    let (fit, _, note) = choose_model(&frf_fit, nl);
                    let method = if note.is_none() && fit.model == FitModel::Nonlinear {
                        IdentificationMethod::FrictionAware
                    } else {
                        IdentificationMethod::FrfFit
                    };
                    (fit.params, fit.uncertainty, method, false)
                }
            },
            (IdentificationMethod::FrfFit, _) => (
                frf_fit.params,
                frf_fit.uncertainty,
                IdentificationMethod::FrfFit,
                false,
            ),
        };
        let fit = PositionFit {
            position_m,
            amplitude_nm,
            params,
            sigma,
            method,
            mass_held,
            frf_fit: frf_fit.params,
            frf_sigma: frf_fit.uncertainty,
            fit_rms_db: frf_fit.fit_rms_db,
        };
        st.finish(
            stage,
            format!(
                "at {:.1} mm, A_PRBS {amplitude_nm:.3} N m: f_r {:.2} Hz, f_z {:.2} Hz, c {:.1} kN/m, m_c {:.2} kg{} ({})",
                position_m * 1e3,
                fit.f_r_hz(),
                fit.f_z_hz(),
                params.c / 1e3,
                params.m_c,
                if mass_held { " held" } else { "" },
                match method {
                    IdentificationMethod::FrictionAware => "friction-aware fit",
                    IdentificationMethod::FrfFit => "FRF fit",
                }
            ),
        );
        Ok(Ok((fit, excursion)))
    }
}
