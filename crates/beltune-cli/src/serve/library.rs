//! Where the tuning page's design model comes from: a commissioning folder
//! (`commissioning.json` and `frf.csv`, written by `beltune commission`) or the
//! built-in axis, commissioned once at start-up exactly as `beltune commission`
//! does with its defaults (egc70, 11.2 kg, seed 1): the page then shows the
//! model, the design and the numbers of the report. Plot data and the simulated
//! validation move come from the library (`beltune::report::plot_data`,
//! `beltune::commission::validation::simulate_validation_move`), the same code
//! the report and the commissioning use.

use anyhow::Context;
use beltune::model::TwoMassParams;
use serde::Deserialize;
use std::path::{Path, PathBuf};

use super::api::{
    BodeData, CommissionedNumbers, Curve, DefaultAttenuation, DesignResponse, EffectiveKnobs,
    FrfOverlay, Gains, Knobs, LoopMargins, MoveData, PrefilterInfo, PrefilterKind,
};
use super::tuner::{ModelSummary, SavedFile, TuneError, Tuner};
use beltune::commission::result::{FrictionResult, MoveSummary, TargetStiffness};
use beltune::commission::validation::{
    simulate_validation_move, FeedforwardVariant, MoveResult, MoveSpec,
};
use beltune::commission::NoProgress;
use beltune::commission::{commission, Commissioning, CommissioningConfig, DataSheet};
use beltune::design::robust::{design_identified, DesignRule};
use beltune::design::{
    ControllerDesign, DesignInput, DesignKnobs, Dynamics, FrictionParams, Prefilter,
    PrefilterKind as DesignPrefilterKind,
};
use beltune::ident::FitModel;
use beltune::ident::ModelUnits;
use beltune::lti::StabilityMargins;
use beltune::model::rigs::{self, LinearPlant, Plant};
use beltune::record::folder::{self as outputs, AxisRecord};
use beltune::record::provenance::Provenance;
use beltune::report::build as report_build;
use beltune::report::plot_data::{self as plots, FrfLines};
use beltune::report::{
    render_html, BodeCurve, ExcitationPlot, FrictionPlot, ParameterRow, Report, Table,
};
use beltune::sim::{SimAxis, SimConfig};
use std::time::Instant;

/// File read from `--commissioning DIR`.
pub const COMMISSIONING_FILE: &str = "commissioning.json";
/// Points of the loop plots (the library's grid, shared with the report).
pub const PLOT_POINTS: usize = plots::LOOP_PLOT_POINTS;
/// Seed of the built-in commissioning (the default of `beltune commission`).
pub const BUILTIN_SEED: u64 = 1;
/// Cart position at the start of the built-in commissioning (the default of
/// `beltune commission --start-position`), m.
pub const BUILTIN_START_POSITION_M: f64 = 0.05;
/// Seed of the page's simulated moves.
pub const MOVE_SEED: u64 = 1;

/// Friction identified from constant-velocity runs (thesis 3.6), as seen at the motor.
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct FrictionTotals {
    /// Viscous friction d_v, N m s/rad.
    #[serde(alias = "viscous")]
    pub viscous_nm_s_per_rad: f64,
    /// Coulomb friction tau_c, N m.
    #[serde(alias = "coulomb")]
    pub coulomb_nm: f64,
    /// Viscous-only fit (linear feedforward), N m s/rad; absent: `viscous_nm_s_per_rad`.
    #[serde(default, alias = "linear_viscous")]
    pub linear_viscous_nm_s_per_rad: Option<f64>,
    /// Holding torque (tilted axis), N m; absent: 0.
    #[serde(default)]
    pub holding_torque_nm: Option<f64>,
    /// The cart's Coulomb friction, N (setpoint's stretch lead); absent: 0.
    #[serde(default)]
    pub cart_coulomb_n: f64,
    /// The cart's viscous friction, N s/m; absent: 0.
    #[serde(default)]
    pub cart_viscous_n_s_per_m: f64,
}

/// The validation summary of `commissioning.json` (nonlinear move only).
#[derive(Debug, Clone, Deserialize)]
pub struct ValidationFile {
    /// The move with nonlinear feedforward.
    pub nonlinear: MoveSummary,
}

/// The parts of `commissioning.json` the tuning page needs.
#[derive(Debug, Clone, Deserialize)]
pub struct CommissioningFile {
    /// Identified model (the keys `beltune design` reads; extra keys are ignored).
    pub identified: beltune::record::model::IdentifiedModel,
    /// Identified friction (optional).
    #[serde(default)]
    pub friction: Option<FrictionTotals>,
    /// The commissioning's validation (optional: recorded data has none).
    #[serde(default)]
    pub validation: Option<ValidationFile>,
}

/// The model the page designs for.
#[derive(Debug, Clone)]
pub struct DesignModel {
    /// Human-readable origin.
    pub source: String,
    /// Linear two-mass model.
    pub params: TwoMassParams,
    /// Current-loop dead time, s.
    pub dead_time_s: f64,
    /// Friction for the feedforward, if known.
    pub friction: Option<FrictionTotals>,
    /// The measured FRF (`frf.csv`), if known.
    pub frf: Option<FrfLines>,
    /// The commissioning's own validation move (nonlinear feedforward), if known.
    pub commissioned: Option<MoveSummary>,
    /// `commissioning.json` as read (saved sets patch its controller).
    pub json: Option<serde_json::Value>,
    /// The exact design input of an in-process commissioning (sampling time,
    /// velocity filter), if known.
    pub input: Option<DesignInput>,
    /// Torque limit of the drive from the record, N m (`None`: egc70's).
    pub torque_max_nm: Option<f64>,
    /// Unit system of the record (current units stay current units in a saved set).
    pub units: ModelUnits,
    /// What the commissioning ran on (`commissioning.json` key `axis`; absent in older files).
    pub axis: Option<AxisRecord>,
    /// The identification experiment as the report plots it (`excitation.csv`), if known.
    pub excitation: Option<ExcitationPlot>,
    /// The friction runs (`friction.csv`), if known.
    pub friction_runs: Option<FrictionPlot>,
    /// One-sigma uncertainty of the identified `m_c`, kg (NaN: unknown, 5 %).
    pub m_c_sigma: f64,
    /// One-sigma uncertainty of the identified `c`, N/m (NaN: unknown, 5 %).
    pub c_sigma: f64,
    /// The belt stiffness at the validation target (`commissioning.json` key
    /// `target_stiffness`), which the static stretch of a saved controller
    /// uses as the commissioning's did; `None`: the model's `c`.
    pub target_stiffness: Option<TargetStiffness>,
}

/// Read `dir/commissioning.json` (and `dir/frf.csv` when present); every
/// failure names the file.
pub fn load_commissioning(dir: &Path) -> anyhow::Result<DesignModel> {
    let path = dir.join(COMMISSIONING_FILE);
    let text = beltune::io::read_to_string_capped(&path, beltune::io::MAX_TEXT_BYTES)?;
    let file = beltune::record::model::ModelFile::parse(&text, &path.display().to_string())
        .with_context(|| format!("parsing {}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let commissioned = json
        .get("validation")
        .and_then(|v| v.get("nonlinear"))
        .and_then(|n| serde_json::from_value::<MoveSummary>(n.clone()).ok());
    let id = file.identified;
    let params = id.params();
    params
        .validate()
        .with_context(|| format!("{}: identified model", path.display()))?;
    beltune::error::require_positive("dead_time_s [s]", id.dead_time_s)
        .with_context(|| format!("{}: identified model", path.display()))?;
    let friction = file.friction.map(|f| FrictionTotals {
        viscous_nm_s_per_rad: f.viscous_nm_s_per_rad,
        coulomb_nm: f.coulomb_nm,
        linear_viscous_nm_s_per_rad: Some(f.linear_viscous_nm_s_per_rad),
        holding_torque_nm: Some(f.holding_torque_nm),
        cart_coulomb_n: f.cart_coulomb_n,
        cart_viscous_n_s_per_m: f.cart_viscous_n_s_per_m,
    });
    if let Some(f) = friction {
        beltune::error::require_non_negative(
            "friction.viscous [N m s/rad]",
            f.viscous_nm_s_per_rad,
        )
        .and_then(|_| beltune::error::require_non_negative("friction.coulomb [N m]", f.coulomb_nm))
        .with_context(|| format!("{}: friction", path.display()))?;
    }
    let frf_path = dir.join(plots::FRF_CSV);
    let frf = if frf_path.exists() {
        Some(
            plots::read_frf_csv(&frf_path)
                .with_context(|| format!("reading {}", frf_path.display()))?,
        )
    } else {
        None
    };
    let axis = match json.get("axis") {
        None | Some(serde_json::Value::Null) => None,
        Some(a) => Some(
            serde_json::from_value::<AxisRecord>(a.clone())
                .map_err(|e| anyhow::anyhow!("{}: `axis`: {e}", path.display()))?,
        ),
    };
    let target_stiffness = match json.get("target_stiffness") {
        None | Some(serde_json::Value::Null) => None,
        Some(t) => Some(
            serde_json::from_value::<TargetStiffness>(t.clone())
                .map_err(|e| anyhow::anyhow!("{}: `target_stiffness`: {e}", path.display()))?,
        ),
    };
    if let Some(t) = &target_stiffness {
        beltune::error::require_positive("target_stiffness.c_n_per_m [N/m]", t.c_n_per_m)
            .with_context(|| format!("{}: target_stiffness", path.display()))?;
    }
    if let Some(AxisRecord::Simulated { plant, .. }) = &axis {
        plant
            .validate()
            .with_context(|| format!("{}: the simulated plant of `axis`", path.display()))?;
    }
    let ex_path = dir.join(plots::EXCITATION_CSV);
    let excitation = if ex_path.exists() {
        Some(
            report_build::read_excitation_csv(&ex_path)
                .with_context(|| format!("reading {}", ex_path.display()))?,
        )
    } else {
        None
    };
    let fr_path = dir.join(plots::FRICTION_CSV);
    let friction_runs = match (&friction, fr_path.exists()) {
        (Some(f), true) => Some(
            report_build::read_friction_csv(&fr_path, f.viscous_nm_s_per_rad, f.coulomb_nm)
                .with_context(|| format!("reading {}", fr_path.display()))?,
        ),
        _ => None,
    };
    Ok(DesignModel {
        source: format!("commissioning {}", dir.display()),
        params,
        dead_time_s: id.dead_time_s,
        friction,
        frf,
        commissioned,
        json: Some(json),
        input: None,
        m_c_sigma: id.m_c_sigma,
        c_sigma: id.c_sigma,
        torque_max_nm: id.torque_max_nm,
        units: id.units,
        axis,
        excitation,
        friction_runs,
        target_stiffness,
    })
}

/// The commissioning `beltune commission` runs with its defaults: the
/// built-in egc70 with 11.2 kg, seed [`BUILTIN_SEED`], start at
/// [`BUILTIN_START_POSITION_M`], default knobs. Deterministic.
pub fn builtin_commissioning() -> beltune::Result<(Plant, Commissioning)> {
    let plant = rigs::builtin("egc70", None)?;
    let ds = DataSheet::for_plant(&plant, BUILTIN_START_POSITION_M, None);
    let cfg = CommissioningConfig::default();
    let sim = SimConfig {
        seed: BUILTIN_SEED,
        initial_cart_position_m: Some(BUILTIN_START_POSITION_M),
        ..SimConfig::default()
    };
    let mut axis = SimAxis::new(&plant, sim)?;
    let run = commission(&mut axis, &ds, &cfg, &mut NoProgress)?;
    Ok((plant, run))
}

/// Which plant the simulated move runs on.
#[derive(Debug, Clone)]
enum MovePlant {
    /// The simulated plant the commissioning ran on (named), with the
    /// slider's payload (a linear set: the payload added to its `m_c`).
    Simulated(String, Box<Plant>),
    /// The identified linear model with the slider's payload added to `m_c`
    /// (recorded data, a real drive, or a folder from before `axis` was recorded).
    Identified,
}

/// The [`Tuner`] backed by the beltune library: [`beltune::design::design`] for
/// the controller (the same function `beltune design` and the commissioning
/// run). The design always uses the nominal model; only the simulated move
/// sees the payload slider.
pub struct LibraryTuner {
    model: DesignModel,
    input: DesignInput,
    friction: FrictionResult,
    /// `m_c` and `c` one-sigma uncertainties of the identification.
    sigmas: (f64, f64),
    nominal_payload_kg: f64,
    move_plant: MovePlant,
    /// Torque limit written to controller.toml and used in the move: the
    /// record's (`identified.torque_max_nm`), else the egc70 drive's, N m.
    torque_max_nm: f64,
}

impl LibraryTuner {
    /// Tuner for an identified model (commissioning folder). The payload slider
    /// adds mass to the identified `m_c` (default 0 kg).
    pub fn new(model: DesignModel) -> anyhow::Result<Self> {
        let mut input = model
            .input
            .unwrap_or_else(|| DesignInput::new(model.params, model.dead_time_s));
        input.friction = model.friction.map(|f| FrictionParams {
            viscous_nm_s_per_rad: f.viscous_nm_s_per_rad,
            coulomb_nm: f.coulomb_nm,
        });
        input
            .validate()
            .with_context(|| format!("design input from {}", model.source))?;
        let (move_plant, nominal_payload_kg) = match &model.axis {
            Some(AxisRecord::Simulated {
                name,
                payload_kg,
                plant,
                ..
            }) => (
                MovePlant::Simulated(name.clone(), plant.clone()),
                payload_kg.unwrap_or(0.0),
            ),
            _ => (MovePlant::Identified, 0.0),
        };
        let torque_max_nm = match (&move_plant, model.torque_max_nm) {
            (_, Some(t)) => t,
            (MovePlant::Simulated(_, p), None) => p.info().torque_max_nm,
            (MovePlant::Identified, None) => rigs::builtin("egc70", None)?.info().torque_max_nm,
        };
        let f = model.friction.unwrap_or(FrictionTotals {
            viscous_nm_s_per_rad: 0.0,
            coulomb_nm: 0.0,
            linear_viscous_nm_s_per_rad: None,
            holding_torque_nm: None,
            cart_coulomb_n: 0.0,
            cart_viscous_n_s_per_m: 0.0,
        });
        let friction = FrictionResult {
            viscous_nm_s_per_rad: f.viscous_nm_s_per_rad,
            coulomb_nm: f.coulomb_nm,
            linear_viscous_nm_s_per_rad: f
                .linear_viscous_nm_s_per_rad
                .unwrap_or(f.viscous_nm_s_per_rad),
            relative_residual: 0.0,
            holding_torque_nm: f.holding_torque_nm.unwrap_or(0.0),
            cart_coulomb_n: f.cart_coulomb_n,
            cart_viscous_n_s_per_m: f.cart_viscous_n_s_per_m,
        };
        Ok(LibraryTuner {
            sigmas: (model.m_c_sigma, model.c_sigma),
            model,
            input,
            friction,
            nominal_payload_kg,
            move_plant,
            torque_max_nm,
        })
    }

    /// Tuner for the built-in egc70 axis: the model [`builtin_commissioning`]
    /// identifies, its friction and measured FRF; the simulated move runs on
    /// the egc70 itself with the slider's payload (default 11.2 kg).
    pub fn builtin() -> anyhow::Result<Self> {
        let (plant, run) = builtin_commissioning().context("built-in commissioning of egc70")?;
        Self::from_commissioning(&plant, &run, "egc70")
    }

    /// Tuner for an in-process commissioning `run` of the built-in `plant`.
    pub fn from_commissioning(
        plant: &Plant,
        run: &Commissioning,
        name: &str,
    ) -> anyhow::Result<Self> {
        let fit = &run.fit;
        let lines = plots::frf_lines(&run.frf, &fit.model.tf(&fit.params), run.dead_time.seconds)?;
        let axis = AxisRecord::simulated(name, plant, BUILTIN_START_POSITION_M, BUILTIN_SEED);
        let json = serde_json::to_value(outputs::commissioning_json(
            run,
            name,
            None,
            axis.clone(),
            Provenance::of_this_process(Some(BUILTIN_SEED)),
        ))
        .context("commissioning.json of the built-in run")?;
        let report = report_build::build_report(run, name, None, None, None)
            .context("report of the built-in run")?;
        let model = DesignModel {
            source: format!(
                "built-in {name} commissioned at start-up ({} kg payload, seed {BUILTIN_SEED})",
                rigs::EGC70_DEFAULT_PAYLOAD_KG
            ),
            // the identified model: the design rule derives its design model
            // from it (design::robust::design_model), as the commissioning did;
            // `run.design.input.model` is that derived model already
            params: run.fit.params,
            dead_time_s: run.design.input.dead_time_s,
            friction: Some(FrictionTotals {
                viscous_nm_s_per_rad: run.friction.viscous_nm_s_per_rad,
                coulomb_nm: run.friction.coulomb_nm,
                linear_viscous_nm_s_per_rad: Some(run.friction.linear_viscous_nm_s_per_rad),
                holding_torque_nm: Some(run.friction.holding_torque_nm),
                cart_coulomb_n: run.friction.cart_coulomb_n,
                cart_viscous_n_s_per_m: run.friction.cart_viscous_n_s_per_m,
            }),
            frf: Some(lines),
            commissioned: Some(run.validation.nonlinear.clone()),
            json: Some(json),
            m_c_sigma: run.identified.m_c_sigma,
            c_sigma: run.identified.c_sigma,
            input: Some(DesignInput {
                model: run.fit.params,
                ..run.design.input
            }),
            torque_max_nm: Some(plant.info().torque_max_nm),
            units: ModelUnits::Torque,
            axis: Some(axis),
            excitation: report.excitation,
            friction_runs: report.friction,
            target_stiffness: Some(run.target_stiffness),
        };
        LibraryTuner::new(model)
    }

    /// What the design library receives for `knobs` (defaults from
    /// [`DesignKnobs::default`], the one-knob mapping from [`Dynamics`]).
    pub fn design_knobs(&self, knobs: &Knobs) -> Result<DesignKnobs, TuneError> {
        let mut k = DesignKnobs::default();
        if let Some(p) = knobs.prefilter {
            k.prefilter = to_design_kind(p);
        }
        k.filter_attenuation_db = knobs.filter_attenuation_db;
        if let Some(x) = knobs.dynamics {
            let d = Dynamics::new(x).map_err(|e| TuneError::Infeasible(e.to_string()))?;
            return Ok(d.knobs(&k));
        }
        if let Some(v) = knobs.pm_velocity_deg {
            k.pm_velocity_deg = v;
        }
        if let Some(v) = knobs.pm_position_deg {
            k.pm_position_deg = v;
        }
        if let Some(v) = knobs.resonance_suppression_db {
            k.resonance_suppression_db = v;
        }
        Ok(k)
    }

    /// The design for `knobs`, by the commissioning's rule
    /// ([`beltune::design::robust::design_identified`]): without an expert
    /// knob the robust rule (what `beltune commission` delivers for the same
    /// model), with one the thesis' conditions for exactly those knobs. Every
    /// library error is caused by the knobs (the model was validated at
    /// start-up), so all are [`TuneError::Infeasible`] with the library's
    /// message.
    pub fn design(&self, knobs: &Knobs) -> Result<ControllerDesign, TuneError> {
        let k = self.design_knobs(knobs)?;
        // the page always sends its prefilter: the default one is no expert knob
        let explicit = knobs
            .prefilter
            .is_some_and(|p| to_design_kind(p) != DesignKnobs::default().prefilter)
            || knobs.filter_attenuation_db.is_some()
            || knobs.dynamics.is_some()
            || knobs.pm_velocity_deg.is_some()
            || knobs.pm_position_deg.is_some()
            || knobs.resonance_suppression_db.is_some();
        let rule = if explicit {
            DesignRule::Knobs
        } else {
            DesignRule::Robust
        };
        design_identified(
            &self.input,
            self.input.friction.map(|f| f.viscous_nm_s_per_rad),
            self.sigmas.0,
            self.sigmas.1,
            &k,
            rule,
        )
        .map(|r| r.design)
        .map_err(|e| TuneError::Infeasible(e.to_string()))
    }

    /// The payload the move uses for `knobs`, kg.
    fn payload_kg(&self, knobs: &Knobs) -> f64 {
        knobs.payload_kg.unwrap_or(self.nominal_payload_kg)
    }

    /// The plant of the simulated move with `payload_kg`.
    pub fn move_plant(&self, payload_kg: f64) -> beltune::Result<Plant> {
        match &self.move_plant {
            MovePlant::Simulated(_, plant) => match plant.as_ref() {
                Plant::Physical(_) => plant.with_payload(payload_kg),
                Plant::Linear(l) => {
                    let mut l = l.clone();
                    l.two_mass.m_c += payload_kg;
                    Ok(Plant::Linear(l))
                }
            },
            MovePlant::Identified => {
                let drive = rigs::builtin("egc70", None)?.info();
                let mut two_mass = self.model.params;
                two_mass.m_c += payload_kg;
                // docs/thesis-map.md: the FRF fit's d_m, d_c contain Coulomb friction seen as
                // small-signal damping; over a 0.5 m move the axis sees the friction of
                // Section 3.6. So the linear move plant takes its viscous friction
                // (translational equivalent on the motor side) and no cart damping.
                if let Some(f) = self.model.friction {
                    two_mass.d_m = f.viscous_nm_s_per_rad / (two_mass.i_t * two_mass.i_t);
                    two_mass.d_c = 0.0;
                }
                Ok(Plant::Linear(LinearPlant {
                    two_mass,
                    dead_time_s: self.model.dead_time_s,
                    torque_max_nm: drive.torque_max_nm,
                    motor_rad_per_count: drive.motor_rad_per_count,
                    ts_s: self.input.ts_s,
                    noise: beltune::model::MeasurementNoise::default(),
                }))
            }
        }
    }

    /// The feedforward variant and friction of the simulated move: the
    /// commissioning's nonlinear feedforward on the egc70; on the linear
    /// identified plant (no Coulomb friction) inertia and viscous friction.
    fn move_variant(&self) -> (FeedforwardVariant, FrictionResult) {
        match self.move_plant {
            MovePlant::Simulated(..) => (FeedforwardVariant::Nonlinear, self.friction.clone()),
            MovePlant::Identified => (
                FeedforwardVariant::Linear,
                FrictionResult {
                    linear_viscous_nm_s_per_rad: self.friction.viscous_nm_s_per_rad,
                    ..self.friction.clone()
                },
            ),
        }
    }

    /// Label of the simulated move.
    fn move_label(&self) -> String {
        match &self.move_plant {
            MovePlant::Simulated(name, _) => {
                format!("simulated on {name}, nonlinear feedforward")
            }
            MovePlant::Identified => {
                "simulated on the identified linear model, linear feedforward".into()
            }
        }
    }

    /// The thesis validation move (0 -> 0.5 m, Table A.8 limits) of design `d`
    /// on the simulated plant with `payload_kg`, through
    /// [`simulate_validation_move`] (controller and options of stage 8).
    pub fn validation_move(
        &self,
        d: &ControllerDesign,
        payload_kg: f64,
    ) -> beltune::Result<MoveResult> {
        let plant = self.move_plant(payload_kg)?;
        let (variant, friction) = self.move_variant();
        simulate_validation_move(
            &plant,
            d,
            &friction,
            self.model.target_stiffness.as_ref(),
            variant,
            &MoveSpec::default(),
            MOVE_SEED,
            MOVE_FOLLOWING_ERROR_MAX_M,
        )
    }

    /// The page's text for a simulated move that failed. A stop that ran
    /// past the stroke (a controller designed for the nominal payload on a
    /// much heavier cart, issue 13 item 3) is not shown as a position beyond
    /// the end: the payload is refused with the reason, since a real axis
    /// would hit its end stop.
    fn move_error_text(&self, e: &beltune::Error, payload_kg: f64) -> String {
        let text = e.to_string();
        let stroke_m = match self.move_plant(payload_kg) {
            Ok(p) => p.stroke_m(),
            Err(_) => None,
        };
        if let (Some(stroke_m), Some(at_mm)) = (stroke_m, stop_position_mm(&text)) {
            if at_mm > stroke_m * 1e3 {
                return format!(
                    "{payload_kg} kg payload refused: with this controller the simulated axis cannot \
                     be stopped inside its {:.0} mm stroke (a real axis would hit its end stop); the \
                     design assumes {} kg: lower the payload, raise the phase margins, or commission \
                     with the payload on the cart",
                    stroke_m * 1e3,
                    self.nominal_payload_kg
                );
            }
        }
        format!("simulated move with {payload_kg} kg payload: {text}")
    }

    fn frf_overlay(&self) -> Option<FrfOverlay> {
        let lines = self.model.frf.as_ref()?;
        let tf = FitModel::WithBeltDamping.tf(&self.model.params);
        let p = plots::frf_display(lines, &tf, self.model.dead_time_s, vec![]).ok()?;
        Some(FrfOverlay {
            freq_hz: p.measured.freq_hz,
            magnitude_db: p.measured.magnitude_db,
            phase_deg: p.measured.phase_deg,
            used_by_fit: p.usable,
            model_freq_hz: p.model.freq_hz,
            model_magnitude_db: p.model.magnitude_db,
            model_phase_deg: p.model.phase_deg,
        })
    }
}

fn to_design_kind(p: PrefilterKind) -> DesignPrefilterKind {
    match p {
        PrefilterKind::Butterworth => DesignPrefilterKind::Butterworth,
        PrefilterKind::Notch => DesignPrefilterKind::Notch,
        PrefilterKind::None => DesignPrefilterKind::None,
    }
}

fn from_design_kind(p: DesignPrefilterKind) -> PrefilterKind {
    match p {
        DesignPrefilterKind::Butterworth => PrefilterKind::Butterworth,
        DesignPrefilterKind::Notch => PrefilterKind::Notch,
        DesignPrefilterKind::None => PrefilterKind::None,
    }
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

fn loop_margins(m: &StabilityMargins) -> LoopMargins {
    LoopMargins {
        phase_margin_deg: m.phase_margin_deg,
        crossover_rad_s: m.crossover_rad_s,
        gain_margin_db: finite(m.gain_margin_db),
        phase_crossover_rad_s: finite(m.phase_crossover_rad_s),
    }
}

fn curve(c: &BodeCurve) -> Curve {
    Curve {
        magnitude_db: c.magnitude_db.clone(),
        phase_deg: c.phase_deg.clone(),
    }
}

impl Tuner for LibraryTuner {
    fn model(&self) -> ModelSummary {
        ModelSummary {
            source: self.model.source.clone(),
            f_r_hz: self.model.params.f_r_hz(),
            f_z_hz: self.model.params.f_z_hz(),
            nominal_payload_kg: self.nominal_payload_kg,
            measured_frf: self.frf_overlay(),
            commissioned: self
                .model
                .commissioned
                .as_ref()
                .map(|m| CommissionedNumbers {
                    max_error_m: m.max_tracking_error_m,
                    static_error_m: m.static_error_m,
                }),
        }
    }

    fn defaults(&self) -> EffectiveKnobs {
        let k = DesignKnobs::default();
        EffectiveKnobs {
            prefilter: from_design_kind(k.prefilter),
            pm_velocity_deg: k.pm_velocity_deg,
            pm_position_deg: k.pm_position_deg,
            resonance_suppression_db: k.resonance_suppression_db,
            filter_attenuation_db: k.attenuation_db(),
            dynamics: None,
            payload_kg: self.nominal_payload_kg,
        }
    }

    fn default_attenuation(&self) -> DefaultAttenuation {
        DefaultAttenuation {
            butterworth: DesignPrefilterKind::Butterworth.default_attenuation_db(),
            notch: DesignPrefilterKind::Notch.default_attenuation_db(),
        }
    }

    fn tune(&self, knobs: &Knobs) -> Result<DesignResponse, TuneError> {
        let started = Instant::now();
        let d = self.design(knobs)?;
        let loops =
            plots::loop_data(&d).map_err(|e| TuneError::Internal(format!("plot data: {e}")))?;
        let prefilter = match d.prefilter {
            Prefilter::Butterworth { omega_bw_rad_s } => PrefilterInfo {
                kind: PrefilterKind::Butterworth,
                omega_bw_rad_s: Some(omega_bw_rad_s),
                d_n: None,
                omega_notch_rad_s: None,
            },
            Prefilter::Notch { omega_r_rad_s, d_n } => PrefilterInfo {
                kind: PrefilterKind::Notch,
                omega_bw_rad_s: None,
                d_n: Some(d_n),
                omega_notch_rad_s: Some(omega_r_rad_s),
            },
            Prefilter::None => PrefilterInfo {
                kind: PrefilterKind::None,
                omega_bw_rad_s: None,
                d_n: None,
                omega_notch_rad_s: None,
            },
        };
        let payload_kg = self.payload_kg(knobs);
        let (validation_move, move_error) = match self.validation_move(&d, payload_kg) {
            Ok(m) => (Some(move_data(&m, payload_kg, self.move_label())), None),
            Err(e) => (None, Some(self.move_error_text(&e, payload_kg))),
        };
        Ok(DesignResponse {
            knobs: EffectiveKnobs {
                prefilter: from_design_kind(d.knobs.prefilter),
                pm_velocity_deg: d.knobs.pm_velocity_deg,
                pm_position_deg: d.knobs.pm_position_deg,
                resonance_suppression_db: d.knobs.resonance_suppression_db,
                filter_attenuation_db: d.knobs.attenuation_db(),
                dynamics: knobs.dynamics,
                payload_kg,
            },
            gains: Gains {
                k_p: d.k_p,
                k_i: d.k_i,
                k_pp: d.k_pp,
            },
            prefilter,
            velocity_loop: loop_margins(&d.velocity_margins),
            position_loop: loop_margins(&d.position_margins),
            gain_at_resonance_db: d.gain_at_resonance_db,
            bode: BodeData {
                omega_rad_s: loops
                    .freq_hz
                    .iter()
                    .map(|f| 2.0 * std::f64::consts::PI * f)
                    .collect(),
                freq_hz: loops.freq_hz.clone(),
                open_loop_velocity: curve(&loops.velocity_open_loop),
                open_loop_position: curve(&loops.position_open_loop),
                closed_loop_position: curve(&loops.position_closed_loop),
                closed_loop_velocity: curve(&loops.velocity_closed_loop),
                sensitivity_velocity: curve(&loops.velocity_sensitivity),
                sensitivity_position: curve(&loops.position_sensitivity),
            },
            validation_move,
            move_error,
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        })
    }

    fn controller_toml(&self, knobs: &Knobs) -> Result<String, TuneError> {
        let d = self.design(knobs)?;
        self.controller_toml_of(&d)
    }

    fn save_set(&self, knobs: &Knobs) -> Result<Vec<SavedFile>, TuneError> {
        let d = self.design(knobs)?;
        let toml = self.controller_toml_of(&d)?;
        let payload_kg = self.payload_kg(knobs);
        let sim = self.validation_move(&d, payload_kg);
        let sim_error = sim
            .as_ref()
            .err()
            .map(|e| self.move_error_text(e, payload_kg));
        let sim = sim.ok();
        let report = self
            .tuned_report(&d, sim.as_ref(), sim_error.as_deref(), payload_kg)
            .map_err(|e| TuneError::Internal(format!("report: {e}")))?;
        let html = render_html(&report).map_err(|e| TuneError::Internal(e.to_string()))?;
        let json = self.tuned_json(&d, sim.as_ref());
        let json = serde_json::to_string_pretty(&json)
            .map_err(|e| TuneError::Internal(format!("commissioning.json: {e}")))?;
        let mut files = vec![
            SavedFile {
                name: super::CONTROLLER_FILE.into(),
                bytes: toml.into_bytes(),
            },
            SavedFile {
                name: COMMISSIONING_FILE.into(),
                bytes: json.into_bytes(),
            },
            SavedFile {
                name: "report.html".into(),
                bytes: html.into_bytes(),
            },
        ];
        if let Some(lines) = &self.model.frf {
            files.push(SavedFile {
                name: plots::FRF_CSV.into(),
                bytes: plots::frf_csv(lines).into_bytes(),
            });
        }
        let loops = plots::loop_data(&d).map_err(|e| TuneError::Internal(e.to_string()))?;
        files.push(SavedFile {
            name: plots::LOOPS_CSV.into(),
            bytes: plots::loops_csv(&loops).into_bytes(),
        });
        // the loaded folder's experiment data, so that the saved set is complete on its own
        if let Some(e) = &self.model.excitation {
            files.push(SavedFile {
                name: plots::EXCITATION_CSV.into(),
                bytes: report_build::excitation_csv(e).into_bytes(),
            });
        }
        if let Some(f) = &self.model.friction_runs {
            files.push(SavedFile {
                name: plots::FRICTION_CSV.into(),
                bytes: report_build::friction_csv(f).into_bytes(),
            });
        }
        if !report.moves.is_empty() {
            files.push(SavedFile {
                name: plots::MOVES_CSV.into(),
                bytes: report_build::moves_csv(&report.moves).into_bytes(),
            });
        }
        Ok(files)
    }
}

impl LibraryTuner {
    fn controller_toml_of(&self, d: &ControllerDesign) -> Result<String, TuneError> {
        let body = outputs::controller_toml(
            d,
            &self.friction,
            self.model.target_stiffness.as_ref(),
            self.torque_max_nm,
            self.model.units,
            Provenance::of_this_process(None),
        )
        .map_err(|e| TuneError::Internal(e.to_string()))?;

        let k = &d.knobs;
        let hz = |w: f64| w / (2.0 * std::f64::consts::PI);
        Ok(format!(
            "# beltune controller, saved by `beltune serve` (same layout as `beltune commission`)\n\
             # model: {}\n\
             # knobs: prefilter {:?}, velocity PM {} deg, position PM {} deg, \
             A_sup {} dB, filter attenuation {} dB\n\
             # achieved: velocity PM {:.2} deg at {:.3} Hz, position PM {:.2} deg at {:.3} Hz\n\n{body}",
            self.model.source,
            k.prefilter,
            k.pm_velocity_deg,
            k.pm_position_deg,
            k.resonance_suppression_db,
            k.attenuation_db(),
            d.velocity_margins.phase_margin_deg,
            hz(d.velocity_margins.crossover_rad_s),
            d.position_margins.phase_margin_deg,
            hz(d.position_margins.crossover_rad_s),
        ))
    }

    /// `commissioning.json` of a saved set: the loaded one with the new
    /// controller; its measured validation belonged to the old controller and
    /// is replaced by `null`; the simulated move and the knobs are recorded.
    fn tuned_json(&self, d: &ControllerDesign, sim: Option<&MoveResult>) -> serde_json::Value {
        let mut v = self
            .model
            .json
            .clone()
            .unwrap_or_else(|| serde_json::json!({}));
        if let Some(obj) = v.as_object_mut() {
            obj.insert(
                "controller".into(),
                serde_json::to_value(d.summary()).unwrap_or_default(),
            );
            obj.insert("validation".into(), serde_json::Value::Null);
            obj.insert(
                "tuning".into(),
                serde_json::json!({
                    "saved_by": "beltune serve",
                    "model_source": self.model.source,
                    "knobs": {
                        "prefilter": format!("{:?}", d.knobs.prefilter).to_lowercase(),
                        "pm_velocity_deg": d.knobs.pm_velocity_deg,
                        "pm_position_deg": d.knobs.pm_position_deg,
                        "resonance_suppression_db": d.knobs.resonance_suppression_db,
                        "filter_attenuation_db": d.knobs.attenuation_db(),
                    },
                    "simulated_validation": sim.map(|m| serde_json::to_value(&m.summary).unwrap_or_default()),
                    "provenance": serde_json::to_value(Provenance::of_this_process(None)).unwrap_or_default(),
                }),
            );
        }
        // a record in current units keeps the current spelling of every key
        // (the loaded keys already have it; the new sections get it here)
        if self.model.units == ModelUnits::Current {
            beltune::units::relabel_keys(&mut v, &beltune::units::current_key);
        }
        v
    }

    /// The report of a saved set: the measured FRF (when known), the loops of
    /// the new design, its simulated move and a verdict judged on that move.
    fn tuned_report(
        &self,
        d: &ControllerDesign,
        sim: Option<&MoveResult>,
        sim_error: Option<&str>,
        payload_kg: f64,
    ) -> beltune::Result<Report> {
        let p = &self.model.params;
        let (f_z, f_r) = (p.f_z_hz(), p.f_r_hz());
        let loops = report_build::loop_plots(d, f_z, f_r)?;
        let tf = FitModel::WithBeltDamping.tf(p);
        let frf = match &self.model.frf {
            Some(lines) => Some(plots::frf_display(
                lines,
                &tf,
                self.model.dead_time_s,
                plots::resonance_markers(f_z, f_r),
            )?),
            None => None,
        };
        let id = self.model.json.as_ref().and_then(|j| j.get("identified"));
        let number = |k: &str| id.and_then(|i| i.get(k)).and_then(|v| v.as_f64());
        let label = self.move_label();
        let mut input = report_build::verdict_input(None, d, sim.map(|m| &m.summary));
        input.mean_coherence = number("mean_coherence");
        input.fit_rms_db = number("fit_rms_db");
        let verdict = beltune::report::verdict_old::verdict(&input);
        let row = |name: &str, unit: &str, v: f64, digits: usize| ParameterRow {
            name: name.into(),
            unit: unit.into(),
            before: None,
            after: format!("{v:.digits$}"),
            truth: None,
            value: Some(v),
        };
        let hz = |w: f64| w / (2.0 * std::f64::consts::PI);
        let l = beltune::units::labels(self.model.units);
        let stiffness = match self.model.units {
            ModelUnits::Torque => row("belt stiffness c", "kN/m", p.c / 1e3, 1),
            ModelUnits::Current => row("belt stiffness c", l.stiffness, p.c, 1),
        };
        let parameters = vec![
            row("resonance f_r", "Hz", f_r, 2),
            row("antiresonance f_z", "Hz", f_z, 2),
            row("moving mass m_c", l.mass, p.m_c, 2),
            stiffness,
            row("K_P", l.torque_per_velocity, d.k_p, 4),
            row("K_I", l.torque_per_angle, d.k_i, 3),
            row("K_PP", "1/s", d.k_pp, 3),
            row(
                "velocity crossover f_c",
                "Hz",
                hz(d.velocity_margins.crossover_rad_s),
                2,
            ),
            row(
                "velocity phase margin",
                "deg",
                d.velocity_margins.phase_margin_deg,
                2,
            ),
            row(
                "position crossover f_c",
                "Hz",
                hz(d.position_margins.crossover_rad_s),
                3,
            ),
            row(
                "position phase margin",
                "deg",
                d.position_margins.phase_margin_deg,
                2,
            ),
        ];
        let moves = sim
            .map(|m| vec![report_build::move_plot(m, &label)])
            .unwrap_or_default();
        let validation_rows = sim
            .map(|m| vec![report_build::validation_row(&label, &m.summary)])
            .unwrap_or_default();
        // The sections of the commissioning's report that need the experiment's
        // data: shown from the loaded folder, or said why they are absent.
        let mut absent = Vec::new();
        let folder_file = |name: &str| match &self.model.json {
            Some(_) => format!("the loaded folder has no {name}"),
            None => format!("no {name} is known"),
        };
        if self.model.excitation.is_none() {
            absent.push(vec![
                "identification experiment".to_string(),
                format!(
                    "{} (written by `beltune commission` on an axis; a record from a CSV file has no excitation trace of its own)",
                    folder_file(plots::EXCITATION_CSV)
                ),
            ]);
        }
        if self.model.friction_runs.is_none() {
            absent.push(vec![
                "friction".to_string(),
                format!(
                    "{} (the constant-velocity runs of `beltune commission` on an axis, or `--friction-csv`)",
                    folder_file(plots::FRICTION_CSV)
                ),
            ]);
        }
        if sim.is_none() {
            absent.push(vec![
                "validation move".to_string(),
                sim_error.map_or_else(
                    || format!("the simulated move with {payload_kg} kg payload did not complete"),
                    str::to_string,
                ),
            ]);
        }
        let mut tables = vec![report_build::drive_form_table(d, self.model.units)];
        if !absent.is_empty() {
            tables.push(Table {
                title: "Sections not in this report".into(),
                header: vec!["section".into(), "why".into()],
                rows: absent,
            });
        }
        Ok(Report {
            title: format!("beltune tuning report: {}", self.model.source),
            summary: format!(
                "Saved by the tuning page. The design model is the one of {}; the verdict is judged on a \
                 simulated validation move with {payload_kg} kg payload ({label}), not on the axis. \
                 Run `beltune commission` again to validate on the axis.",
                self.model.source
            ),
            frf,
            controller: Some(loops.controller),
            open_loops: loops.open_loops,
            closed_loops: loops.closed_loops,
            moves,
            parameters,
            validation_rows,
            verdict: Some(verdict),
            provenance: Some(Provenance::of_this_process(None)),
            excitation: self.model.excitation.clone(),
            friction: self.model.friction_runs.clone(),
            tables,
            ..Report::default()
        })
    }
}

/// A saved set on disk.
#[derive(Debug, Clone)]
pub struct SavedSet {
    /// The new folder.
    pub dir: PathBuf,
    /// File names written.
    pub files: Vec<String>,
    /// Bytes of `controller.toml`.
    pub controller_bytes: usize,
}

/// Write `files` into a new folder `tuned-<UTC time>` (`-2`, `-3`, ... if
/// taken) under `dir`: first into a hidden temporary folder unique to this
/// save, then renamed, so the set appears whole or not at all and nothing
/// earlier is overwritten (a rename onto a folder another save created in
/// the meantime fails, and the next name is tried).
pub fn write_saved_set(dir: &Path, files: &[SavedFile]) -> anyhow::Result<SavedSet> {
    static SAVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let stamp: String = Provenance::now(Vec::new(), None)
        .created_utc
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect();
    let unique = SAVES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(
        ".tuned-{stamp}-{}-{unique}.partial",
        std::process::id()
    ));
    std::fs::create_dir(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
    let result = (|| -> anyhow::Result<SavedSet> {
        for f in files {
            beltune::io::write_atomic(&tmp.join(&f.name), &f.bytes)?;
        }
        for n in 1.. {
            let name = if n == 1 {
                format!("tuned-{stamp}")
            } else {
                format!("tuned-{stamp}-{n}")
            };
            let target = dir.join(name);
            if std::fs::symlink_metadata(&target).is_ok() {
                continue;
            }
            match std::fs::rename(&tmp, &target) {
                Ok(()) => {
                    return Ok(SavedSet {
                        dir: target,
                        files: files.iter().map(|f| f.name.clone()).collect(),
                        controller_bytes: files
                            .iter()
                            .find(|f| f.name == super::CONTROLLER_FILE)
                            .map_or(0, |f| f.bytes.len()),
                    })
                }
                // another save took the name between the check and the rename
                Err(_) if std::fs::symlink_metadata(&target).is_ok() => continue,
                Err(e) => {
                    return Err(anyhow::Error::new(e).context(format!(
                        "renaming {} to {}",
                        tmp.display(),
                        target.display()
                    )))
                }
            }
        }
        unreachable!("the name search ends with a free name or an error")
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result
}

/// The rest position of a safety stop, mm, from the supervisor's text
/// ("...; axis stopped at 619.8 mm", [`beltune::commission::runner`]).
fn stop_position_mm(text: &str) -> Option<f64> {
    text.rsplit("axis stopped at ")
        .next()
        .filter(|_| text.contains("axis stopped at "))
        .and_then(|t| t.split(" mm").next())
        .and_then(|t| t.trim().parse().ok())
}

/// Largest number of points of each move trace sent to the page.
pub const MOVE_TRACE_POINTS: usize = 400;
/// Following error at which the simulated move is aborted (a badly damped or
/// unstable design under a payload the design did not assume), m.
pub const MOVE_FOLLOWING_ERROR_MAX_M: f64 = 0.1;

/// Summary and traces (every k-th sample, at most [`MOVE_TRACE_POINTS`]) of a move.
fn move_data(r: &MoveResult, payload_kg: f64, plant: String) -> MoveData {
    let rec = &r.record;
    let n = rec.samples.len();
    let stride = n.div_ceil(MOVE_TRACE_POINTS).max(1);
    let error = if r.cart_error_m.len() == n {
        &r.cart_error_m
    } else {
        &r.motor_error_m
    };
    let pick = |f: &dyn Fn(usize) -> f64| (0..n).step_by(stride).map(f).collect::<Vec<f64>>();
    let s = &r.summary;
    MoveData {
        plant,
        payload_kg,
        max_error_m: s.max_tracking_error_m,
        static_error_m: s.static_error_m,
        settling_time_s: s.settling_time_s.and_then(finite),
        t_s: pick(&|i| rec.time_s[i]),
        desired_m: pick(&|i| rec.desired_m[i]),
        actual_m: pick(&|i| {
            let sample = &rec.samples[i];
            sample.cart_position_m.unwrap_or(sample.position_m)
        }),
        error_m: pick(&|i| error[i]),
        torque_nm: pick(&|i| rec.samples[i].torque_command_nm),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("beltune-serve-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn reads_identified_model_and_ignores_extras() {
        let dir = temp_dir("ok");
        let json = r#"{"identified": {"theta_e": 7.173e-5, "m_c": 13.44, "c": 203740.0,
            "d_m": 33.17, "d_c": 226.42, "i_t": 0.012414, "dead_time_s": 0.001, "fit_rms_db": 0.4},
            "friction": {"viscous": 0.00253, "coulomb": 0.125}, "design": {"k_p": 1}}"#;
        std::fs::write(dir.join(COMMISSIONING_FILE), json).unwrap();
        let m = load_commissioning(&dir).unwrap();
        assert_eq!(m.params.m_c, 13.44);
        assert_eq!(m.params.d, 0.0);
        assert_eq!(m.dead_time_s, 0.001);
        assert_eq!(m.friction.unwrap().coulomb_nm, 0.125);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 13 item 3: the payload slider at its limit (30 kg) once ended
    /// "axis stopped at 640.9 mm", beyond the 600 mm stroke. Whatever the
    /// knobs, the simulated move either completes inside the travel window or
    /// stops inside the stroke (its stop planned with the deceleration the
    /// heavier axis really has), and says where.
    #[test]
    fn the_heaviest_payload_stays_inside_the_stroke_issue_13_3() {
        let tuner = LibraryTuner::builtin().unwrap();
        let stroke_mm = rigs::builtin("egc70", None).unwrap().stroke_m().unwrap() * 1e3;
        let window_max_mm = MoveSpec::default().limits.position_max * 1e3;
        let (mut stops, mut refused) = (0, 0);
        for prefilter in [
            PrefilterKind::None,
            PrefilterKind::Notch,
            PrefilterKind::Butterworth,
        ] {
            for (pm_v, pm_p) in [(30.0, 40.0), (45.0, 40.0), (60.0, 40.0), (60.0, 80.0)] {
                let knobs = Knobs {
                    prefilter: Some(prefilter),
                    pm_velocity_deg: Some(pm_v),
                    pm_position_deg: Some(pm_p),
                    payload_kg: Some(30.0),
                    ..Knobs::default()
                };
                let Ok(r) = tuner.tune(&knobs) else { continue };
                let what = format!("{prefilter:?} {pm_v}/{pm_p} deg");
                match (&r.validation_move, &r.move_error) {
                    (Some(m), None) => {
                        let max_mm = m.actual_m.iter().fold(f64::MIN, |a, b| a.max(*b)) * 1e3;
                        assert!(max_mm <= window_max_mm, "{what}: moved to {max_mm} mm");
                    }
                    (None, Some(e)) => {
                        assert!(!e.contains("NaN") && !e.contains("inf"), "{what}: {e}");
                        if e.contains("refused") {
                            refused += 1;
                            assert!(e.contains("600 mm stroke") && e.contains("11.2 kg"), "{e}");
                            assert!(stop_position_mm(e).is_none(), "{what}: {e}");
                            continue;
                        }
                        stops += 1;
                        let at = stop_position_mm(e)
                            .unwrap_or_else(|| panic!("{what}: no stop position in `{e}`"));
                        assert!(at <= stroke_mm, "{what}: {e}");
                    }
                    other => panic!("{what}: {other:?}"),
                }
            }
        }
        // the sweep reaches the cases that stop (no prefilter, low margins)
        assert!(
            stops + refused > 0,
            "no setting stopped: the test did not reach its case"
        );
        assert_eq!(
            stop_position_mm("safety stop: x; axis stopped at 619.8 mm"),
            Some(619.8)
        );
        assert_eq!(stop_position_mm("safety stop: x"), None);
    }

    #[test]
    fn non_physical_or_missing_model_is_an_error_naming_the_file() {
        let dir = temp_dir("bad");
        let e = load_commissioning(&dir).unwrap_err();
        assert!(format!("{e:#}").contains(COMMISSIONING_FILE), "{e:#}");
        let json = r#"{"identified": {"theta_e": -1, "m_c": 13.44, "c": 203740.0,
            "d_m": 33.17, "d_c": 226.42, "i_t": 0.012414, "dead_time_s": 0.001}}"#;
        std::fs::write(dir.join(COMMISSIONING_FILE), json).unwrap();
        let e = format!("{:#}", load_commissioning(&dir).unwrap_err());
        assert!(e.contains("theta_e"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
