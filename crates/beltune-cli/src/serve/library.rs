//! Where the tuning page's design model comes from: a result folder (read by
//! the library's one folder reader, [`ResultFolder::read`]) or the built-in
//! axis, commissioned once at start-up exactly as `beltune commission` does
//! with its defaults (egc70, 11.2 kg, seed 1): the page then shows the model,
//! the design and the numbers of the report. Plot data, the simulated
//! validation move, the verdict and the saved set come from the library (the
//! same code the report and the commissioning use).

use anyhow::Context;
use beltune::model::TwoMassParams;
use std::path::{Path, PathBuf};

use super::api::{
    BodeData, CommissionedNumbers, Curve, DefaultAttenuation, DesignResponse, EffectiveKnobs,
    FrfOverlay, Gains, Knobs, LoopMargins, MoveData, PrefilterInfo, PrefilterKind,
};
use super::tuner::{ModelSummary, SavedFile, TuneError, Tuner};
use beltune::commission::validation::{
    simulate_validation_move, FeedforwardVariant, MoveResult, MoveSpec,
};
use beltune::commission::{commission_simulated, Commissioning, CommissioningConfig, NoProgress};
use beltune::design::robust::{design_identified, DesignRule, RobustDesign};
use beltune::design::{
    ControllerDesign, DesignInput, DesignKnobs, Dynamics, Prefilter,
    PrefilterKind as DesignPrefilterKind,
};
use beltune::ident::FitModel;
use beltune::lti::StabilityMargins;
use beltune::model::rigs::{self, LinearPlant, Plant};
use beltune::record::commissioning::{AxisRecord, Origin};
use beltune::record::model::FrictionResult;
use beltune::record::provenance::Provenance;
use beltune::report::folder::{ResultFolder, ResultSet, TunedDesign};
use beltune::report::plot_data;
use beltune::report::BodeCurve;
use beltune::sim::{SimConfig, Truth};
use beltune::verdict::{judge, MoveInput, ValidatedOn, VerdictInput};
use std::time::Instant;

/// File read from `--commissioning DIR`.
pub const COMMISSIONING_FILE: &str = beltune::record::COMMISSIONING_FILE;
/// Points of the loop plots (the library's grid, shared with the report).
pub const PLOT_POINTS: usize = plot_data::LOOP_PLOT_POINTS;
/// Seed of the built-in commissioning (the default of `beltune commission`).
pub const BUILTIN_SEED: u64 = 1;
/// Cart position at the start of the built-in commissioning (the default of
/// `beltune commission --start-position`), m.
pub const BUILTIN_START_POSITION_M: f64 = 0.05;
/// Seed of the page's simulated moves.
pub const MOVE_SEED: u64 = 1;

/// The model the page designs for: a result (read from a folder, or made
/// in-process for the built-in axis) and where it came from.
#[derive(Debug, Clone)]
pub struct DesignModel {
    /// Human-readable origin.
    pub source: String,
    /// The result: its record (model, friction, validation, the simulated
    /// plant it ran on) and data files (FRF, excitation, friction runs).
    pub result: ResultFolder,
    /// Whether the result was read from a folder (a saved report then says
    /// which files the folder lacks).
    pub from_folder: bool,
    /// The exact design input of an in-process commissioning (sampling time,
    /// velocity filter), if known.
    pub input: Option<DesignInput>,
}

impl DesignModel {
    /// The identified two-mass parameters.
    pub fn params(&self) -> TwoMassParams {
        self.result.record.identified.params()
    }

    /// The identified dead time, s.
    pub fn dead_time_s(&self) -> f64 {
        self.result.record.identified.dead_time_s
    }

    /// The identified friction, if any.
    pub fn friction(&self) -> Option<&FrictionResult> {
        self.result.record.friction.as_ref()
    }
}

/// Read a result folder (`dir/commissioning.json`, the data files beside it)
/// with the library's folder reader; a model the page cannot design for (no
/// positive dead time, negative friction) is refused naming the file.
pub fn load_commissioning(dir: &Path) -> anyhow::Result<DesignModel> {
    let path = dir.join(COMMISSIONING_FILE);
    let result = ResultFolder::read(dir)?;
    let id = &result.record.identified;
    beltune::error::require_positive("dead_time_s [s]", id.dead_time_s)
        .with_context(|| format!("{}: identified model", path.display()))?;
    if let Some(f) = &result.record.friction {
        beltune::error::require_non_negative(
            "friction.viscous [N m s/rad]",
            f.viscous_nm_s_per_rad,
        )
        .and_then(|_| beltune::error::require_non_negative("friction.coulomb [N m]", f.coulomb_nm))
        .with_context(|| format!("{}: friction", path.display()))?;
    }
    Ok(DesignModel {
        source: format!("commissioning {}", dir.display()),
        result,
        from_folder: true,
        input: None,
    })
}

/// The commissioning `beltune commission` runs with its defaults: the
/// built-in egc70 with 11.2 kg, seed [`BUILTIN_SEED`], start at
/// [`BUILTIN_START_POSITION_M`], default knobs. Deterministic.
pub fn builtin_commissioning() -> beltune::Result<(Plant, Commissioning)> {
    let plant = rigs::builtin("egc70", None)?;
    let sim = SimConfig {
        seed: BUILTIN_SEED,
        initial_cart_position_m: Some(BUILTIN_START_POSITION_M),
        ..SimConfig::default()
    };
    let run = commission_simulated(
        &plant,
        sim,
        None,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )?;
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
    /// The model along the stroke (the commissioning's data sheet), if known.
    stroke: Option<beltune::model::stroke::StrokeVariation>,
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
        let record = &model.result.record;
        let mut input = model
            .input
            .unwrap_or_else(|| DesignInput::new(model.params(), model.dead_time_s()));
        input.friction = model.friction().map(FrictionResult::params);
        input
            .validate()
            .with_context(|| format!("design input from {}", model.source))?;
        let (move_plant, nominal_payload_kg) = match &record.axis {
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
        let torque_max_nm = match (&move_plant, record.identified.torque_max_nm) {
            (_, Some(t)) => t,
            (MovePlant::Simulated(_, p), None) => p.info().torque_max_nm,
            (MovePlant::Identified, None) => rigs::builtin("egc70", None)?.info().torque_max_nm,
        };
        let friction = model.friction().cloned().unwrap_or_default();
        Ok(LibraryTuner {
            sigmas: (record.identified.m_c_sigma, record.identified.c_sigma),
            stroke: record.identified.stroke_variation,
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
        let origin = Origin {
            name: name.to_string(),
            axis: AxisRecord::simulated(name, plant, BUILTIN_START_POSITION_M, BUILTIN_SEED),
            truth: Some(Truth::of_plant(plant, run.identification_position_m)?),
            provenance: Provenance::of_this_process(Some(BUILTIN_SEED)),
        };
        let set = ResultSet::of_run(run, &origin).context("the result of the built-in run")?;
        let model = DesignModel {
            source: format!(
                "built-in {name} commissioned at start-up ({} kg payload, seed {BUILTIN_SEED})",
                rigs::EGC70_DEFAULT_PAYLOAD_KG
            ),
            result: ResultFolder {
                dir: PathBuf::new(),
                record: set.record,
                data: set.data,
            },
            from_folder: false,
            // the identified model: the design rule derives its design model
            // from it (design::robust::design_model), as the commissioning did;
            // `run.design.input.model` is that derived model already
            input: Some(DesignInput {
                model: run.fit.params,
                ..run.design.input
            }),
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
        self.robust_design(knobs).map(|r| r.design)
    }

    /// [`Self::design`] with the margins it guarantees over the
    /// identification's uncertainty.
    pub fn robust_design(&self, knobs: &Knobs) -> Result<RobustDesign, TuneError> {
        let k = self.design_knobs(knobs)?;
        // the page always sends its prefilter: the default one is no expert knob
        let explicit = knobs
            .prefilter
            .is_some_and(|p| to_design_kind(p) != DesignKnobs::default().prefilter)
            || knobs.filter_attenuation_db.is_some()
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
            self.stroke.as_ref(),
            &k,
            rule,
        )
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
                let mut two_mass = self.model.params();
                two_mass.m_c += payload_kg;
                // docs/thesis-map.md: the FRF fit's d_m, d_c contain Coulomb friction seen as
                // small-signal damping; over a 0.5 m move the axis sees the friction of
                // Section 3.6. So the linear move plant takes its viscous friction
                // (translational equivalent on the motor side) and no cart damping.
                if let Some(f) = self.model.friction() {
                    two_mass.d_m = f.viscous_nm_s_per_rad / (two_mass.i_t * two_mass.i_t);
                    two_mass.d_c = 0.0;
                }
                Ok(Plant::Linear(LinearPlant {
                    two_mass,
                    dead_time_s: self.model.dead_time_s(),
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
            self.model.result.record.target_stiffness.as_ref(),
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
        let payload = beltune::error::short_number(payload_kg);
        let stroke_m = match self.move_plant(payload_kg) {
            Ok(p) => p.stroke_m(),
            Err(_) => None,
        };
        if let (Some(stroke_m), Some(at_mm)) = (stroke_m, stop_position_mm(&text)) {
            if at_mm > stroke_m * 1e3 {
                return format!(
                    "{payload} kg payload refused: with this controller the simulated axis cannot \
                     be stopped inside its {:.0} mm stroke (a real axis would hit its end stop); the \
                     design assumes {} kg: lower the payload, raise the phase margins, or commission \
                     with the payload on the cart",
                    stroke_m * 1e3,
                    self.nominal_payload_kg
                );
            }
        }
        format!("simulated move with {payload} kg payload: {text}")
    }

    fn frf_overlay(&self) -> Option<FrfOverlay> {
        let lines = self.model.result.data.frf.as_ref()?;
        let tf = FitModel::WithBeltDamping.tf(&self.model.params());
        let p = plot_data::frf_display(lines, &tf, self.model.dead_time_s(), vec![]).ok()?;
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
            f_r_hz: self.model.params().f_r_hz(),
            f_z_hz: self.model.params().f_z_hz(),
            nominal_payload_kg: self.nominal_payload_kg,
            measured_frf: self.frf_overlay(),
            commissioned: self
                .model
                .result
                .record
                .delivered_move()
                .map(|m| CommissionedNumbers {
                    max_error_m: m.max_tracking_error_m,
                    static_error_m: m.static_error_m,
                }),
            commissioned_verdict: self.model.result.record.verdict.as_ref().map(|v| v.text()),
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
            plot_data::loop_data(&d).map_err(|e| TuneError::Internal(format!("plot data: {e}")))?;
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
        let set = self.tuned_set(knobs)?;
        let files = set
            .files()
            .map_err(|e| TuneError::Internal(format!("saved set: {e}")))?;
        Ok(files
            .into_iter()
            .map(|(name, bytes)| SavedFile { name, bytes })
            .collect())
    }
}

impl LibraryTuner {
    /// The result set Save writes for `knobs`: the loaded result with the new
    /// design, its verdict judged on the simulated move.
    pub fn tuned_set(&self, knobs: &Knobs) -> Result<ResultSet, TuneError> {
        let robust = self.robust_design(knobs)?;
        let d = &robust.design;
        let payload_kg = self.payload_kg(knobs);
        let sim = self.validation_move(d, payload_kg);
        let sim_error = sim
            .as_ref()
            .err()
            .map(|e| self.move_error_text(e, payload_kg));
        let sim = sim.ok();
        let verdict = judge(&VerdictInput {
            limits: &beltune::verdict::Limits::default(),
            validation: sim.as_ref().map(|m| MoveInput {
                summary: &m.summary,
                record_after_move_s: MoveSpec::default().settle_s,
                torque_max_nm: self.torque_max_nm,
                on: ValidatedOn::Simulation,
            }),
            guaranteed: Some(&robust.guaranteed),
            design: d,
            identified: Some(&self.model.result.record.identified),
            controller_file: beltune::record::CONTROLLER_FILE,
        });
        ResultSet::of_tuned(&TunedDesign {
            base: &self.model.result,
            from_folder: self.model.from_folder,
            source: self.model.source.clone(),
            design: d,
            guaranteed: Some(robust.guaranteed),
            verdict,
            sim: sim.as_ref(),
            sim_error,
            move_label: self.move_label(),
            payload_kg,
            friction: &self.friction,
            target_stiffness: self.model.result.record.target_stiffness.as_ref(),
            torque_max_nm: self.torque_max_nm,
        })
        .map_err(|e| TuneError::Internal(format!("saved set: {e}")))
    }

    fn controller_toml_of(&self, d: &ControllerDesign) -> Result<String, TuneError> {
        beltune::record::controller::ControllerFile::from_design(
            d,
            &self.friction,
            self.model.result.record.target_stiffness.as_ref(),
            self.torque_max_nm,
            self.model.result.record.identified.units,
            Provenance::of_this_process(None),
        )
        .and_then(|f| f.to_toml())
        .map_err(|e| TuneError::Internal(e.to_string()))
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
        assert_eq!(m.params().m_c, 13.44);
        assert_eq!(m.params().d, 0.0);
        assert_eq!(m.dead_time_s(), 0.001);
        assert_eq!(m.friction().unwrap().coulomb_nm, 0.125);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The payload slider at its limit (30 kg) once ended
    /// "axis stopped at 640.9 mm", beyond the 600 mm stroke. Whatever the
    /// knobs, the simulated move either completes inside the travel window or
    /// stops inside the stroke (its stop planned with the deceleration the
    /// heavier axis really has), and says where.
    #[test]
    fn the_heaviest_payload_stays_inside_the_stroke() {
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
