//! `commissioning.json` (schema [`SCHEMA_VERSION`], docs/formats.md): every
//! number of a run, its verdict and its log. One type, [`CommissioningRecord`],
//! written by [`CommissioningRecord::to_json_text`] and read by
//! [`CommissioningRecord::parse`] (the identified model through the model
//! reader [`ModelFile::parse`], so that a `commissioning.json` is also a model
//! file for `beltune design --model`).
//!
//! Keys are written in the order of the struct. Sections a run does not have
//! are `null` (recorded data has no validation); a file from an older beltune
//! or written by hand may leave them out.

use super::model::{FrictionResult, IdentifiedModel, ModelFile};
use super::provenance::Provenance;
use super::SCHEMA_VERSION;
use crate::commission::recorded::RecordedCommissioning;
use crate::commission::stiffness::TargetStiffness;
use crate::commission::validation::Validation;
use crate::commission::Commissioning;
use crate::design::robust::GuaranteedMargins;
use crate::design::{DesignSummary, DriveForm};
use crate::ident::ModelUnits;
use crate::sim::Truth;
use crate::verdict::Verdict;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// `commissioning.json`: an identified-model record ([`ModelFile`]) with the
/// controller, the validation, the verdict and the log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CommissioningRecord {
    /// [`SCHEMA_VERSION`].
    #[serde(default)]
    pub schema_version: u32,
    /// Who wrote it: beltune version, date, command line, seed.
    #[serde(default)]
    pub provenance: Option<Provenance>,
    /// Name of the axis (built-in plant name or file, the recording, the drive).
    #[serde(default)]
    pub plant: String,
    /// The identified model (with sampling time, torque limit and units).
    pub identified: IdentifiedModel,
    /// Friction (`null` when it could not be measured).
    #[serde(default)]
    pub friction: Option<FrictionResult>,
    /// Controller: gains, prefilter, achieved margins.
    #[serde(default)]
    pub controller: Option<DesignSummary>,
    /// The controller in drive-menu form (`T_n`, `K_v`, filter frequency and damping).
    #[serde(default)]
    pub drive_form: Option<DriveForm>,
    /// The margins the controller keeps over the identification's uncertainty.
    #[serde(default)]
    pub guaranteed_margins: Option<GuaranteedMargins>,
    /// The three validation moves (`null` for recorded data: no axis to move).
    #[serde(default)]
    pub validation: Option<Validation>,
    /// The validation move that ran (`null` for recorded data).
    #[serde(default)]
    pub validation_move: Option<ValidationMove>,
    /// The one verdict ([`crate::verdict`]).
    #[serde(default)]
    pub verdict: Option<Verdict>,
    /// How long the axis was busy, s (recorded data: the record's duration).
    #[serde(default)]
    pub experiment_time_s: Option<f64>,
    /// How long each stage kept the axis busy, in the order they ran, s
    /// (empty for recorded data and in older files).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stage_axis_times: Vec<crate::commission::stages::StageAxisTime>,
    /// Computation time (FFT, fit, design), s.
    #[serde(default)]
    pub computation_time_s: Option<f64>,
    /// PRBS amplitude used, N m (`null` for recorded data).
    #[serde(default)]
    pub excitation_amplitude_nm: Option<f64>,
    /// Where the model was measured: the mean motor-side position over the
    /// compared periods of the excitation, m (`null` for recorded data).
    #[serde(default)]
    pub identification_position_m: Option<f64>,
    /// The belt stiffness where the validation move ends, which the static
    /// belt stretch of `controller.toml` uses (`null` for recorded data).
    #[serde(default)]
    pub target_stiffness: Option<TargetStiffness>,
    /// The thesis' fit of the FRF's magnitude (3.5), beside the model in
    /// `identified` when that is the friction-aware fit (absent for
    /// recorded data, where `identified` is the FRF fit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frf_fit: Option<crate::model::TwoMassParams>,
    /// The friction-aware fit of the nonlinear model (2.30): parameters,
    /// Coulomb friction of motor and cart, residuals; absent where it failed
    /// or for recorded data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_aware: Option<crate::ident::NonlinearFit>,
    /// For a simulated plant: the true values at the identification position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<Truth>,
    /// What the commissioning ran on (absent in files written before it was added).
    #[serde(default)]
    pub axis: Option<AxisRecord>,
    /// The stage log.
    #[serde(default)]
    pub log: Vec<String>,
    /// A design saved by the tuning page on this result: what was changed
    /// (absent for a commissioning).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tuning: Option<Tuning>,
}

/// What the tuning page changed in a saved set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tuning {
    /// `beltune serve`.
    pub saved_by: String,
    /// Where the design model came from.
    pub model_source: String,
    /// The knobs of the saved design.
    pub knobs: TuningKnobs,
    /// The simulated validation move of the saved design (`null`: it did not complete).
    pub simulated_validation: Option<crate::commission::validation::MoveSummary>,
    /// Who saved it.
    pub provenance: Provenance,
}

/// The design knobs of a saved set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TuningKnobs {
    /// `butterworth`, `notch` or `none`.
    pub prefilter: String,
    /// Velocity-loop phase margin asked for, deg.
    pub pm_velocity_deg: f64,
    /// Position-loop phase margin asked for, deg.
    pub pm_position_deg: f64,
    /// Resonance suppression `A_sup`, dB.
    pub resonance_suppression_db: f64,
    /// Prefilter attenuation at the resonance, dB.
    pub filter_attenuation_db: f64,
}

impl TuningKnobs {
    /// The knobs of a design.
    pub fn of(k: &crate::design::DesignKnobs) -> Self {
        TuningKnobs {
            prefilter: format!("{:?}", k.prefilter).to_lowercase(),
            pm_velocity_deg: k.pm_velocity_deg,
            pm_position_deg: k.pm_position_deg,
            resonance_suppression_db: k.resonance_suppression_db,
            filter_attenuation_db: k.attenuation_db(),
        }
    }
}

/// The validation move that ran: Table A.8's, or the fastest the axis can
/// do inside its travel window.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ValidationMove {
    /// Start of the move, m.
    pub start_m: f64,
    /// Target of the move, m.
    pub target_m: f64,
    /// Speed limit, m/s.
    pub v_max_m_s: f64,
    /// Acceleration limit, m/s^2.
    pub a_max_m_s2: f64,
    /// Jerk limit, m/s^3.
    pub j_max_m_s3: f64,
    /// Slower than Table A.8's move (the axis cannot do that one).
    pub reduced: bool,
}

/// What a commissioning ran on (`commissioning.json` key `axis`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AxisRecord {
    /// A simulated axis.
    Simulated {
        /// The plant's name (built-in) or file, as given.
        name: String,
        /// Payload on the cart, kg (`null`: a linear set, which has none).
        payload_kg: Option<f64>,
        /// Cart position at the start, m.
        start_position_m: f64,
        /// Noise seed of the simulation.
        seed: u64,
        /// Every parameter of the simulated plant (payload and tilt included).
        plant: Box<crate::model::rigs::Plant>,
    },
    /// Recorded data (CSV): no simulator truth.
    Recorded {
        /// The record's file.
        source: String,
        /// Open loop, or direct / indirect closed loop with where the
        /// excitation entered (absent in files written before it was recorded).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        identification: Option<crate::ident::IdentificationStrategy>,
    },
    /// A real drive (EtherCAT): no simulator truth.
    Ethercat {
        /// The interface and SubDevice.
        source: String,
    },
}

impl AxisRecord {
    /// The record of a simulated `plant` named `name`.
    pub fn simulated(
        name: &str,
        plant: &crate::model::rigs::Plant,
        start_position_m: f64,
        seed: u64,
    ) -> Self {
        let payload_kg = match plant {
            crate::model::rigs::Plant::Physical(p) => Some(p.payload_kg),
            crate::model::rigs::Plant::Linear(_) => None,
        };
        AxisRecord::Simulated {
            name: name.to_string(),
            payload_kg,
            start_position_m,
            seed,
            plant: Box::new(plant.clone()),
        }
    }

    /// The plant of a simulated axis.
    pub fn simulated_plant(&self) -> Option<&crate::model::rigs::Plant> {
        match self {
            AxisRecord::Simulated { plant, .. } => Some(plant),
            _ => None,
        }
    }
}

/// Where a run comes from: the axis' name, what it is, the simulator's truth
/// (simulated axes) and who ran it.
#[derive(Clone, Debug)]
pub struct Origin {
    /// Name of the axis (`egc70`, a plant file, `EtherCAT eth0 SubDevice 0 (...)`, a CSV file).
    pub name: String,
    /// What the run was made on.
    pub axis: AxisRecord,
    /// The simulator's truth at the identification position, if simulated.
    pub truth: Option<Truth>,
    /// Who ran it.
    pub provenance: Provenance,
}

impl CommissioningRecord {
    /// The record of a run on an axis.
    pub fn of_run(run: &Commissioning, origin: &Origin) -> Self {
        let mut identified = run.identified.clone();
        identified.ts_s = Some(run.design.input.ts_s);
        identified.torque_max_nm = Some(run.datasheet.torque_max_nm);
        identified.t_r_s = run.design.input.t_r_s;
        let m = &run.validation_move;
        CommissioningRecord {
            schema_version: SCHEMA_VERSION,
            provenance: Some(origin.provenance.clone()),
            plant: origin.name.clone(),
            identified,
            friction: Some(run.friction.clone()),
            controller: Some(run.design.summary()),
            drive_form: Some(DriveForm::of(&run.design)),
            guaranteed_margins: Some(run.guaranteed),
            validation: Some(run.validation.clone()),
            validation_move: Some(ValidationMove {
                start_m: m.start_m,
                target_m: m.target_m,
                v_max_m_s: m.limits.v_max,
                a_max_m_s2: m.limits.a_max,
                j_max_m_s3: m.limits.j_max,
                reduced: m.reduced,
            }),
            verdict: Some(run.verdict.clone()),
            experiment_time_s: Some(run.experiment_time_s),
            stage_axis_times: run.stage_axis_times.clone(),
            computation_time_s: Some(run.computation_time_s),
            excitation_amplitude_nm: Some(run.excitation_amplitude_nm),
            identification_position_m: Some(run.identification_position_m),
            target_stiffness: Some(run.target_stiffness),
            frf_fit: Some(run.frf_fit.params),
            friction_aware: run.nonlinear.clone(),
            truth: origin.truth.clone(),
            axis: Some(origin.axis.clone()),
            log: run.log.clone(),
            tuning: None,
        }
    }

    /// The record of a commissioning from recorded data: no validation, the
    /// record's duration as `experiment_time_s`.
    pub fn of_recorded(run: &RecordedCommissioning, origin: &Origin) -> Self {
        CommissioningRecord {
            schema_version: SCHEMA_VERSION,
            provenance: Some(origin.provenance.clone()),
            plant: origin.name.clone(),
            identified: run.identified.clone(),
            friction: run.friction.clone(),
            controller: Some(run.design.summary()),
            drive_form: Some(DriveForm::of(&run.design)),
            guaranteed_margins: Some(run.guaranteed),
            validation: None,
            validation_move: None,
            verdict: Some(run.verdict.clone()),
            experiment_time_s: Some(run.record_time_s),
            stage_axis_times: Vec::new(),
            computation_time_s: Some(run.computation_time_s),
            excitation_amplitude_nm: None,
            identification_position_m: None,
            target_stiffness: None,
            frf_fit: None,
            friction_aware: None,
            truth: None,
            axis: Some(origin.axis.clone()),
            log: run.log.clone(),
            tuning: None,
        }
    }

    /// The JSON text; in current units the unit suffixes of the keys are the
    /// current spelling ([`crate::units::relabel_keys`]).
    pub fn to_json_text(&self) -> Result<String> {
        let err = |e: serde_json::Error| Error::Report {
            reason: format!("{}: {e}", super::COMMISSIONING_FILE),
        };
        let mut v = serde_json::to_value(self).map_err(err)?;
        if self.identified.units == ModelUnits::Current {
            crate::units::relabel_keys(&mut v, &crate::units::current_key);
        }
        let mut text = serde_json::to_string_pretty(&v).map_err(err)?;
        text.push('\n');
        Ok(text)
    }

    /// Parse the text of a `commissioning.json`; `origin` names it in errors.
    /// The model and friction are read and checked by [`ModelFile::parse`];
    /// the sections beltune reads back (target stiffness, the simulated
    /// plant) are checked too.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let perr = |message: String| Error::Parse {
            path: origin.to_string(),
            message,
        };
        if !text.trim_start().starts_with('{') {
            return Err(perr("not a JSON document".into()));
        }
        let mut value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| perr(format!("not valid JSON: {e}")))?;
        if value
            .get("identified")
            .and_then(|v| v.as_object())
            .is_none()
        {
            return Err(perr(
                "no `identified` model: not a commissioning written by `beltune commission`".into(),
            ));
        }
        let model = ModelFile::parse(text, origin)?;
        let current = value
            .get("identified")
            .and_then(|i| i.get("units"))
            .and_then(|u| u.as_str())
            == Some("current");
        if current {
            crate::units::relabel_keys(&mut value, &crate::units::torque_key);
        }
        let mut record: CommissioningRecord =
            serde_json::from_value(value).map_err(|e| perr(e.to_string()))?;
        record.identified = model.identified;
        record.friction = model.friction;
        record.schema_version = model.schema_version;
        if let Some(t) = &record.target_stiffness {
            crate::error::require_positive("target_stiffness.c_n_per_m [N/m]", t.c_n_per_m)
                .map_err(|e| perr(e.to_string()))?;
        }
        if let Some(plant) = record.axis.as_ref().and_then(AxisRecord::simulated_plant) {
            plant
                .validate()
                .map_err(|e| perr(format!("the simulated plant of `axis`: {e}")))?;
        }
        Ok(record)
    }

    /// Read and parse `path` (at most [`crate::io::MAX_TEXT_BYTES`], a regular file).
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = crate::io::read_to_string_capped(path, crate::io::MAX_TEXT_BYTES)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The delivered move's summary (nonlinear feedforward), if validated.
    pub fn delivered_move(&self) -> Option<&crate::commission::validation::MoveSummary> {
        self.validation.as_ref().map(|v| &v.nonlinear)
    }
}
