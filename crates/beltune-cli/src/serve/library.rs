//! Where the tuning page's design model comes from: a commissioning folder
//! (`commissioning.json`, written by `beltune commission`) or the built-in axis.

use anyhow::Context;
use beltune::model::TwoMassParams;
use serde::Deserialize;
use std::path::Path;

use super::api::{
    BodeData, Curve, DefaultAttenuation, DesignResponse, EffectiveKnobs, Gains, Knobs, LoopMargins,
    MoveData, PrefilterInfo, PrefilterKind,
};
use super::tuner::{ModelSummary, TuneError, Tuner};
use beltune::design::{
    self, ControllerDesign, DesignInput, DesignKnobs, Dynamics, FrictionParams, Prefilter,
    PrefilterKind as DesignPrefilterKind,
};
use beltune::lti::{BodePoint, StabilityMargins};
use beltune::model::rigs::{self, LinearPlant, Plant};
use beltune::procedure::commission::cascade_from_design;
use beltune::procedure::motion::TrackOptions;
use beltune::procedure::outputs;
use beltune::procedure::result::FrictionResult;
use beltune::procedure::runner::Runner;
use beltune::procedure::validation::{run_move, MoveResult, MoveSpec};
use beltune::procedure::{NoProgress, SafetyLimits, SafetySupervisor};
use beltune::sim::{SimAxis, SimConfig};
use beltune_rt::control::{BeltStretch, Feedforward as RtFeedforward};
use beltune_rt::trajectory::Limits;
use std::time::Instant;

/// File read from `--commissioning DIR`.
pub const COMMISSIONING_FILE: &str = "commissioning.json";

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
}

/// The parts of `commissioning.json` the tuning page needs.
#[derive(Debug, Clone, Deserialize)]
pub struct CommissioningFile {
    /// Identified model (the keys `beltune design` reads; extra keys are ignored).
    pub identified: beltune::design::IdentifiedModel,
    /// Identified friction (optional).
    #[serde(default)]
    pub friction: Option<FrictionTotals>,
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
    /// Torque limit of the drive from the record, N m (`None`: egc70's).
    pub torque_max_nm: Option<f64>,
}

/// Read `dir/commissioning.json`; every failure names the file.
pub fn load_commissioning(dir: &Path) -> anyhow::Result<DesignModel> {
    let path = dir.join(COMMISSIONING_FILE);
    let text = beltune::io::read_to_string_capped(&path, beltune::io::MAX_TEXT_BYTES)?;
    let file = beltune::design::ModelFile::parse(&text, &path.display().to_string())
        .with_context(|| format!("parsing {}", path.display()))?;
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
    });
    if let Some(f) = friction {
        beltune::error::require_non_negative(
            "friction.viscous [N m s/rad]",
            f.viscous_nm_s_per_rad,
        )
        .and_then(|_| beltune::error::require_non_negative("friction.coulomb [N m]", f.coulomb_nm))
        .with_context(|| format!("{}: friction", path.display()))?;
    }
    Ok(DesignModel {
        source: format!("commissioning {}", dir.display()),
        params,
        dead_time_s: id.dead_time_s,
        friction,
        torque_max_nm: id.torque_max_nm,
    })
}

/// Frequency grid of the plots: from [`PLOT_DECADES_BELOW`] decades below the lowest
/// of antiresonance and the two crossovers up to the Nyquist frequency,
/// [`PLOT_POINTS`] log-spaced points (enough to draw the resonance; the margins
/// come from the design's own fine grid).
pub const PLOT_POINTS: usize = 300;
/// Decades of the plot grid below the lowest characteristic frequency.
pub const PLOT_DECADES_BELOW: f64 = 2.0;

/// Which plant the simulated move runs on.
#[derive(Debug, Clone)]
enum MovePlant {
    /// The built-in egc70 (nonlinear three-mass model) with the slider's payload.
    Egc70,
    /// The identified linear model with the slider's payload added to `m_c`.
    Identified,
}

/// The [`Tuner`] backed by the beltune library: [`beltune::design::design`] for
/// the controller (the same function `beltune design` runs). The design always
/// uses the nominal model; only the simulated move sees the payload slider.
pub struct LibraryTuner {
    model: DesignModel,
    input: DesignInput,
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
        let mut input = DesignInput::new(model.params, model.dead_time_s);
        input.friction = model.friction.map(|f| FrictionParams {
            viscous_nm_s_per_rad: f.viscous_nm_s_per_rad,
            coulomb_nm: f.coulomb_nm,
        });
        input
            .validate()
            .with_context(|| format!("design input from {}", model.source))?;
        let torque_max_nm = match model.torque_max_nm {
            Some(t) => t,
            None => rigs::builtin("egc70", None)?.info().torque_max_nm,
        };
        Ok(LibraryTuner {
            model,
            input,
            nominal_payload_kg: 0.0,
            move_plant: MovePlant::Identified,
            torque_max_nm,
        })
    }

    /// Tuner for the built-in egc70 axis: its two-mass linearization at the
    /// worst-case (lowest-resonance) cart position with the default payload.
    pub fn builtin() -> anyhow::Result<Self> {
        let plant = rigs::builtin("egc70", None)?;
        let params = plant.worst_case_two_mass()?;
        let friction = plant.friction_totals();
        let model = DesignModel {
            source: format!(
                "built-in egc70 ({} kg payload, cart at {:.3} m)",
                rigs::EGC70_DEFAULT_PAYLOAD_KG,
                plant.worst_case_position_m()
            ),
            params,
            dead_time_s: plant.dead_time_s(),
            friction: Some(FrictionTotals {
                viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
                coulomb_nm: friction.coulomb_nm,
                linear_viscous_nm_s_per_rad: None,
                holding_torque_nm: None,
            }),
            torque_max_nm: None,
        };
        let mut tuner = LibraryTuner::new(model)?;
        tuner.nominal_payload_kg = rigs::EGC70_DEFAULT_PAYLOAD_KG;
        tuner.move_plant = MovePlant::Egc70;
        Ok(tuner)
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

    /// The design for `knobs`. Every library error is caused by the knobs (the
    /// model was validated at start-up), so all are [`TuneError::Infeasible`]
    /// with the library's message.
    pub fn design(&self, knobs: &Knobs) -> Result<ControllerDesign, TuneError> {
        let k = self.design_knobs(knobs)?;
        design::design(&self.input, &k).map_err(|e| TuneError::Infeasible(e.to_string()))
    }

    /// The payload the move uses for `knobs`, kg.
    fn payload_kg(&self, knobs: &Knobs) -> f64 {
        knobs.payload_kg.unwrap_or(self.nominal_payload_kg)
    }

    /// The plant of the simulated move with `payload_kg`.
    pub fn move_plant(&self, payload_kg: f64) -> beltune::Result<Plant> {
        match self.move_plant {
            MovePlant::Egc70 => rigs::builtin("egc70", Some(payload_kg)),
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
                }))
            }
        }
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

fn curve(points: &[BodePoint]) -> Curve {
    Curve {
        magnitude_db: points.iter().map(|p| p.magnitude_db).collect(),
        phase_deg: points.iter().map(|p| p.phase_deg).collect(),
    }
}

impl Tuner for LibraryTuner {
    fn model(&self) -> ModelSummary {
        ModelSummary {
            source: self.model.source.clone(),
            f_r_hz: self.model.params.f_r_hz(),
            f_z_hz: self.model.params.f_z_hz(),
            nominal_payload_kg: self.nominal_payload_kg,
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
        let lowest = d
            .omega_z_rad_s
            .min(d.velocity_margins.crossover_rad_s)
            .min(d.position_margins.crossover_rad_s);
        let w_max = std::f64::consts::PI / d.input.ts_s;
        let w_min = lowest * 10f64.powf(-PLOT_DECADES_BELOW);
        let plot = d
            .plot_data(w_min, w_max, PLOT_POINTS)
            .map_err(|e| TuneError::Internal(format!("plot data: {e}")))?;
        let omega_rad_s = plot
            .velocity_open_loop
            .iter()
            .map(|p| p.omega_rad_s)
            .collect();
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
        let (validation_move, move_error) = match self.simulate_move(&d, payload_kg) {
            Ok(m) => (Some(m), None),
            Err(e) => (None, Some(e)),
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
                omega_rad_s,
                open_loop_velocity: curve(&plot.velocity_open_loop),
                open_loop_position: curve(&plot.position_open_loop),
                closed_loop_position: curve(&plot.position_closed_loop),
            },
            validation_move,
            move_error,
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        })
    }

    fn controller_toml(&self, knobs: &Knobs) -> Result<String, TuneError> {
        let d = self.design(knobs)?;
        let friction = self.model.friction.unwrap_or(FrictionTotals {
            viscous_nm_s_per_rad: 0.0,
            coulomb_nm: 0.0,
            linear_viscous_nm_s_per_rad: None,
            holding_torque_nm: None,
        });
        let friction = FrictionResult {
            viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
            coulomb_nm: friction.coulomb_nm,
            linear_viscous_nm_s_per_rad: friction
                .linear_viscous_nm_s_per_rad
                .unwrap_or(friction.viscous_nm_s_per_rad),
            relative_residual: 0.0,
            holding_torque_nm: friction.holding_torque_nm.unwrap_or(0.0),
        };
        let body = outputs::controller_toml(
            &d,
            &friction,
            self.torque_max_nm,
            beltune::ident::ModelUnits::Torque,
            beltune::provenance::Provenance::of_this_process(None),
        )
        .map_err(|e| TuneError::Internal(e.to_string()))?;
        let k = &d.knobs;
        Ok(format!(
            "# beltune controller, saved by `beltune serve` (same layout as `beltune commission`)\n\
             # model: {}\n\
             # knobs: prefilter {:?}, velocity PM {} deg, position PM {} deg, \
             A_sup {} dB, filter attenuation {} dB\n\
             # achieved: velocity PM {:.2} deg at {:.2} rad/s, position PM {:.2} deg at {:.2} rad/s\n\n{body}",
            self.model.source,
            k.prefilter,
            k.pm_velocity_deg,
            k.pm_position_deg,
            k.resonance_suppression_db,
            k.attenuation_db(),
            d.velocity_margins.phase_margin_deg,
            d.velocity_margins.crossover_rad_s,
            d.position_margins.phase_margin_deg,
            d.position_margins.crossover_rad_s,
        ))
    }
}

/// Largest number of points of each move trace sent to the page.
pub const MOVE_TRACE_POINTS: usize = 400;
/// Following error at which the simulated move is aborted (a badly damped or
/// unstable design under a payload the design did not assume), m.
pub const MOVE_FOLLOWING_ERROR_MAX_M: f64 = 0.1;
/// Deceleration of the supervisor's jerk-limited stop, m/s^2.
pub const MOVE_STOP_DECELERATION_M_S2: f64 = 20.0;

impl LibraryTuner {
    /// The thesis validation move (0 -> 0.5 m, Table A.8 limits,
    /// [`MoveSpec::default`]) on the simulated plant with `payload_kg`, with the
    /// nonlinear feedforward (egc70; linear inertia + viscous for the linear
    /// identified plant, which has no Coulomb friction) and the refinements
    /// `beltune commission` validates with (filtered desired velocity, dead-time preview, belt-stretch
    /// compensation from the design model). Composed from the library's
    /// [`SimAxis`], [`Runner`] and [`run_move`]; a safety stop is reported as text.
    fn simulate_move(&self, d: &ControllerDesign, payload_kg: f64) -> Result<MoveData, String> {
        self.run_validation_move(d, payload_kg)
            .map_err(|e| format!("simulated move with {payload_kg} kg payload: {e}"))
    }

    fn run_validation_move(
        &self,
        d: &ControllerDesign,
        payload_kg: f64,
    ) -> beltune::Result<MoveData> {
        let plant = self.move_plant(payload_kg)?;
        let info = plant.info();
        let spec = MoveSpec::default();
        let config = SimConfig {
            initial_cart_position_m: Some(spec.start_m),
            ..SimConfig::default()
        };
        let mut axis = SimAxis::new(&plant, config)?;
        let torque_max = info.torque_max_nm;
        let feedback = cascade_from_design(d, torque_max, 0.0)?;
        let a_stop = MOVE_STOP_DECELERATION_M_S2;
        let supervisor = SafetySupervisor::new(
            SafetyLimits {
                travel_min_m: spec.limits.position_min,
                travel_max_m: spec.limits.position_max,
                torque_max_nm: torque_max,
                velocity_max_m_s: spec.limits.v_max,
                following_error_max_m: MOVE_FOLLOWING_ERROR_MAX_M,
            },
            a_stop,
        )?;
        let stop_limits = Limits {
            a_max: a_stop,
            a_min: -a_stop,
            j_max: 20.0 * a_stop,
            j_min: -20.0 * a_stop,
            ..spec.limits
        };
        let mut progress = NoProgress;
        let mut runner = Runner::new(
            &mut axis,
            &mut progress,
            supervisor,
            d.input.model.i_t,
            spec.start_m,
            feedback,
            stop_limits,
        )?;
        let ff = &d.feedforward;
        let mut controller = feedback;
        controller.feedforward = match self.move_plant {
            MovePlant::Egc70 => {
                RtFeedforward::nonlinear(ff.inertia_kg_m2, ff.viscous_nm_s_per_rad, ff.coulomb_nm)
            }
            // the linear move plant has no Coulomb friction to compensate
            MovePlant::Identified => {
                RtFeedforward::linear(ff.inertia_kg_m2, ff.viscous_nm_s_per_rad)
            }
        };
        controller.filter_desired_velocity = true;
        controller.feedforward_preview = true;
        let opts = TrackOptions {
            preview_samples: (d.input.dead_time_s / d.input.ts_s).round() as usize,
            belt_stretch: BeltStretch::On {
                m_c_kg: d.input.model.m_c,
                c_n_per_m: d.input.model.c,
            },
            check_following_error: true,
            // The simulated plants are horizontal: no holding force, no static stretch.
            static_stretch_m: 0.0,
        };
        let result = run_move(
            &mut runner,
            &feedback,
            &spec.limits,
            &controller,
            opts,
            &spec,
        )?;
        Ok(move_data(&result, payload_kg))
    }
}

/// Summary and traces (every k-th sample, at most [`MOVE_TRACE_POINTS`]) of a move.
fn move_data(r: &MoveResult, payload_kg: f64) -> MoveData {
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
