//! The health of a belt axis over its life: a short experiment (at most
//! about five seconds of axis time) that measures what wears, each quantity
//! compared with the baseline commissioning and its uncertainty, a verdict
//! per quantity and a recommendation in words (docs/health.md).
//!
//! | file | what |
//! | --- | --- |
//! | [`config`] | the quantities, their limits, the experiment's settings |
//! | [`baseline`] | the commissioning compared with, and the uncertainty of each of its quantities |
//! | [`experiment`] | the runs and excitations on the axis, built from the commissioning's stages |
//! | [`friction`] | (3.36) with an offset and its covariance |
//! | [`compare`] | each quantity against the baseline, the verdict per quantity, the recommendations |
//!
//! This file holds the order: plausibility (stage 1), the experiment, the
//! comparison.

pub mod baseline;
pub mod compare;
pub mod config;
pub mod experiment;
pub mod friction;

pub use baseline::Baseline;
pub use compare::{Comparison, Status};
pub use config::{HealthConfig, HealthExperiment, HealthLimits, Limit, Quantity};
pub use experiment::Measured;

use crate::axis::Axis;
use crate::commission::runner::Runner;
use crate::commission::stages::Stages;
use crate::commission::{CommissioningConfig, DataSheet, Progress};
use crate::Result;
use serde::{Deserialize, Serialize};

/// A value and its one-sigma uncertainty, in the unit of its quantity
/// (`sigma` NaN: unknown).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its one-sigma uncertainty.
    #[serde(with = "nan_as_null")]
    pub sigma: f64,
}

impl Estimate {
    /// `value +- sigma`.
    pub fn new(value: f64, sigma: f64) -> Self {
        Estimate { value, sigma }
    }
}

/// A health check's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HealthCheck {
    /// What was measured.
    pub measured: Measured,
    /// Each quantity against the baseline.
    pub comparisons: Vec<Comparison>,
    /// The worst status of the quantities.
    pub status: Status,
    /// How long the axis was busy, s.
    pub experiment_time_s: f64,
    /// Wall-clock time of the fits, s.
    pub computation_time_s: f64,
    /// One line per stage.
    pub log: Vec<String>,
}

impl HealthCheck {
    /// The recommendations: the blocks that no longer fit, then the
    /// quantities that are not `ok`, worst first.
    pub fn recommendations(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .measured
            .failures
            .iter()
            .map(|f| {
                let block = f.split_once(": ").map_or(f.as_str(), |(b, _)| b);
                format!("the belt's response {block} no longer fits the commissioned two-mass axis (a slack span, backlash, a loose clamp): re-tension the belt, check the clamps and the pulleys, then re-commission")
            })
            .collect();
        let mut c: Vec<&Comparison> = self
            .comparisons
            .iter()
            .filter(|c| c.recommendation.is_some())
            .collect();
        c.sort_by_key(|c| std::cmp::Reverse(c.status));
        out.extend(c.iter().filter_map(|c| c.recommendation.clone()));
        out
    }

    /// The comparison of `q`, if measured.
    pub fn comparison(&self, q: Quantity) -> Option<&Comparison> {
        self.comparisons.iter().find(|c| c.quantity == q)
    }

    /// The judgement of `measured` against `baseline` (the experiment's time and log given).
    pub fn judge(
        baseline: &Baseline,
        measured: Measured,
        limits: &HealthLimits,
        experiment_time_s: f64,
        computation_time_s: f64,
        log: Vec<String>,
    ) -> HealthCheck {
        let comparisons = compare::compare(baseline, &measured, limits);
        let mut status = comparisons
            .iter()
            .map(|c| c.status)
            .max()
            .unwrap_or_default();
        if !measured.failures.is_empty() {
            // a commissioned belt whose response no longer fits a two-mass
            // model has changed beyond any limit
            status = Status::Act;
        }
        let mut check = HealthCheck {
            measured,
            comparisons,
            status,
            experiment_time_s,
            computation_time_s,
            log,
        };
        let recs = check.recommendations();
        check.log.push(format!(
            "verdict: {}{}",
            status.word(),
            recs.iter().map(|r| format!("; {r}")).collect::<String>()
        ));
        check
    }
}

/// Check the health of `axis` (homed, `datasheet.origin_m`) against
/// `baseline` (docs/health.md). The axis is refused before it moves where
/// the data sheet or the limits are not plausible.
pub fn health_check(
    axis: &mut dyn Axis,
    datasheet: &DataSheet,
    baseline: &Baseline,
    cfg: &HealthConfig,
    progress: &mut dyn Progress,
) -> Result<HealthCheck> {
    cfg.limits.validate()?;
    validate_experiment(&cfg.experiment)?;
    progress.stage_started("plausibility", 0);
    let info = axis.info();
    let plaus = crate::commission::stages::plausibility::plausibility(
        &info,
        datasheet,
        &CommissioningConfig::default(),
    )?;
    progress.stage_finished(&plaus.line);
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
    let measured = experiment::run(
        &mut st,
        plaus.bootstrap,
        datasheet,
        baseline,
        &cfg.experiment,
        plaus.torque_max_nm,
    )?;
    let busy = st.runner.busy_time_s();
    let mut log = std::mem::take(&mut st.log);
    if busy > cfg.experiment.max_axis_time_s {
        log.push(format!(
            "note: the axis was busy {busy:.2} s, more than the {:.1} s a health check is meant to take",
            cfg.experiment.max_axis_time_s
        ));
    }
    Ok(HealthCheck::judge(
        baseline,
        measured,
        &cfg.limits,
        busy,
        st.compute_s,
        log,
    ))
}

/// Check the health of `plant` on the simulator, with the data sheet
/// `beltune commission` gives it ([`crate::commission::commission_simulated`]).
pub fn health_simulated(
    plant: &crate::model::Plant,
    sim: crate::sim::SimConfig,
    travel_window_m: Option<(f64, f64)>,
    baseline: &Baseline,
    cfg: &HealthConfig,
    progress: &mut dyn Progress,
) -> Result<HealthCheck> {
    let start = sim.initial_cart_position_m.unwrap_or(0.05);
    let ds = DataSheet::for_plant(plant, start, travel_window_m);
    let mut axis = crate::sim::SimAxis::new(
        plant,
        crate::sim::SimConfig {
            initial_cart_position_m: Some(start),
            ..sim
        },
    )?;
    health_check(&mut axis, &ds, baseline, cfg, progress)
}

/// Check the health from a recording instead of an axis (`beltune health
/// --csv`): the two-mass fit of a recorded excitation (taken as made where
/// the baseline was identified, at its amplitude) and, if given, the
/// friction regressed from a recorded motion (without an uncertainty: the
/// regression gives none). Only these quantities are compared.
pub fn health_of_recording(
    fit: &crate::ident::TwoMassFit,
    friction: Option<&crate::ident::friction::MotionFriction>,
    record_time_s: f64,
    baseline: &Baseline,
    limits: &HealthLimits,
) -> Result<HealthCheck> {
    limits.validate()?;
    let nan = f64::NAN;
    let far = experiment::PositionFit {
        position_m: nan,
        amplitude_nm: baseline.excitation_amplitude_nm.unwrap_or(nan),
        params: fit.params,
        sigma: fit.uncertainty,
        method: crate::record::model::IdentificationMethod::FrfFit,
        mass_held: false,
        frf_fit: fit.params,
        frf_sigma: fit.uncertainty,
        fit_rms_db: fit.fit_rms_db,
    };
    let friction = friction.map(|f| friction::FrictionEstimate {
        coulomb_nm: f.coulomb,
        coulomb_sigma_nm: nan,
        viscous_nm_s_per_rad: f.viscous,
        viscous_sigma_nm_s_per_rad: nan,
        holding_nm: f.offset,
        holding_sigma_nm: nan,
    });
    let measured = Measured {
        far: Some(far),
        far_half: None,
        near: None,
        runs: Vec::new(),
        friction,
        failures: Vec::new(),
    };
    let log = vec![format!(
        "recording: f_r {:.2} Hz, f_z {:.2} Hz, c {:.1} kN/m, m_c {:.2} kg, fit {:.2} dB rms",
        fit.f_r_hz,
        fit.f_z_hz,
        fit.params.c / 1e3,
        fit.params.m_c,
        fit.fit_rms_db
    )];
    Ok(HealthCheck::judge(
        baseline,
        measured,
        limits,
        record_time_s,
        0.0,
        log,
    ))
}

/// Typed error for experiment settings out of range.
pub fn validate_experiment(e: &HealthExperiment) -> Result<()> {
    use crate::error::require_range;
    require_range("prbs_order", f64::from(e.prbs_order), 4.0, 12.0)?;
    require_range("clock_period_s", e.clock_period_s, 1e-5, 0.1)?;
    require_range("periods", e.periods as f64, 2.0, 16.0)?;
    require_range("slow_speed_m_s", e.slow_speed_m_s, 1e-3, 2.0)?;
    require_range("slow_run_m", e.slow_run_m, 1e-3, 1.0)?;
    require_range("fast_speed_m_s", e.fast_speed_m_s, 1e-3, 5.0)?;
    require_range("max_axis_time_s", e.max_axis_time_s, 0.1, 600.0)?;
    if e.fast_speed_m_s <= e.slow_speed_m_s {
        return Err(crate::Error::invalid(
            "fast_speed_m_s",
            e.fast_speed_m_s,
            "the fast runs must be faster than the slow ones (two speeds separate Coulomb from viscous friction)",
        ));
    }
    Ok(())
}

/// `NaN` as JSON `null` and back (an unknown uncertainty, an unknown position).
pub(crate) mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        if x.is_finite() {
            s.serialize_f64(*x)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}
