//! Monte Carlo robustness study: a seeded generator of physically
//! plausible belt axes derived from the egc70 data sheet ([`generate`]), a
//! computed feasibility classification ([`Feasibility`]), one commissioning per
//! plant with the simulation truth watched ([`run_plant`]), and the table of
//! the issue over many plants ([`Table`]).
//!
//! Each failure is classified: a plant that is infeasible by physics and was
//! refused or stopped safely inside its travel window is a *correct refusal*;
//! any failure of a feasible plant, any travel-window violation and any silent
//! success that misses its limits is a *defect*.

mod generator;
mod table;

pub use generator::{generate, GeneratedPlant, Ranges};
pub use table::{Table, TableRow};

use crate::axis::{Axis, AxisError, AxisInfo, Measurement};
use crate::commission::safety::StopCapability;
use crate::commission::validation::{table_a8_limits, MoveSpec};
use crate::commission::{commission, CommissioningConfig, DataSheet};
use crate::design::ControllerDesign;
use crate::model::rigs::Plant;
use crate::sim::SimAxis;
use beltune_rt::trajectory::{State, Trajectory};
use serde::Serialize;

/// What physics allows for a plant, computed from its true parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Feasibility {
    /// Holding torque (gravity), N m.
    pub holding_nm: f64,
    /// Coulomb friction at the motor, N m.
    pub coulomb_nm: f64,
    /// Peak torque of the Table A.8 move on the rigid body (inertia, gravity,
    /// viscous and Coulomb friction), N m.
    pub table_a8_torque_nm: f64,
    /// Torque limit, N m.
    pub torque_limit_nm: f64,
    /// The axis can be held and stopped safely in both directions
    /// ([`StopCapability::from_axis`] on the true values) and the validation
    /// move fits its travel window: commissioning must succeed.
    pub feasible: bool,
    /// The rigid-body torque of the Table A.8 move, gravity and friction stay
    /// below the torque limit (the definition).
    pub table_a8_feasible: bool,
    /// Near a boundary of the classification (within 10 % of the torque
    /// involved): measurement error may decide either way, so neither outcome
    /// is a defect.
    pub marginal: bool,
}

/// The feasibility of `plant` for the validation `spec` in the window `ds`.
pub fn feasibility(plant: &Plant, ds: &DataSheet, spec: &MoveSpec) -> Feasibility {
    let info = plant.info();
    let t_max = info.torque_max_nm.min(ds.torque_max_nm);
    let totals = plant.friction_totals();
    let (j, i_t, holding) = match plant {
        Plant::Physical(p) => (
            p.linearize(p.worst_case_position_m())
                .map(|m| m.rigid_inertia())
                .unwrap_or(f64::NAN),
            p.i_t(),
            -p.i_t() * p.gravity_force_n(),
        ),
        Plant::Linear(l) => (l.two_mass.rigid_inertia(), l.two_mass.i_t, 0.0),
    };
    let limits = beltune_rt::trajectory::Limits {
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
        ..spec.limits
    };
    let start = spec.start_m.max(ds.travel_min_m + 0.01);
    let target = spec.target_m.min(ds.travel_max_m - 0.07);
    let move_fits = target - start > 0.05;
    let mut peak = f64::INFINITY;
    if let Ok(t) = Trajectory::plan(&State::at_rest(start), &State::at_rest(target), &limits) {
        peak = 0.0;
        let d = t.duration_s();
        for k in 0..=400 {
            let s = t.sample(d * k as f64 / 400.0);
            let w = s.velocity / i_t;
            let tau = j * s.acceleration / i_t
                + holding
                + totals.viscous_nm_s_per_rad * w
                + totals.coulomb_nm * w.signum();
            peak = peak.max(tau.abs());
        }
    }
    let stoppable = |scale: f64| {
        StopCapability::from_axis(t_max * scale, j, i_t, holding, totals.coulomb_nm).is_ok()
    };
    let feasible = stoppable(1.0) && move_fits;
    let marginal = stoppable(0.9) != stoppable(1.1);
    Feasibility {
        holding_nm: holding,
        coulomb_nm: totals.coulomb_nm,
        table_a8_torque_nm: peak,
        torque_limit_nm: t_max,
        feasible,
        table_a8_feasible: feasible && peak < t_max,
        marginal,
    }
}

/// How one plant's commissioning ended.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum OutcomeKind {
    /// A controller that met its limits.
    Success,
    /// A controller, but the verdict says it misses its limits (said so).
    LimitsNotMet,
    /// Refused or stopped (safety stop, infeasible, fit failed, ...).
    Failed,
}

/// The classification of an outcome.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Class {
    /// Success on a feasible plant.
    Success,
    /// An infeasible (or marginal) plant refused or stopped safely.
    CorrectRefusal,
    /// A feasible plant failed, the cart left its window, or a bad success
    /// was silent.
    Defect,
}

/// One plant of the study.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    /// Index of the plant in the study.
    pub index: u64,
    /// The generated plant's variations.
    pub plant: GeneratedPlant,
    /// What physics allows.
    pub feasibility: Feasibility,
    /// How it ended.
    pub kind: OutcomeKind,
    /// Classification.
    pub class: Class,
    /// The error or the verdict's failures.
    pub message: String,
    /// Whether the true cart left the travel window at any time.
    pub travel_violation: bool,
    /// Largest excursion of the true cart beyond the window, m (0 inside).
    pub travel_excess_m: f64,
    /// Velocity-loop phase margin of the delivered controller on the true
    /// linearized plant at the identification position, deg.
    pub true_velocity_phase_margin_deg: Option<f64>,
    /// The commissioning's guaranteed velocity phase margin, deg.
    pub guaranteed_velocity_phase_margin_deg: Option<f64>,
    /// Relative errors of the identification: `f_z`, `m_c`, Coulomb friction.
    pub f_z_error: Option<f64>,
    /// `m_c` relative error.
    pub m_c_error: Option<f64>,
    /// Coulomb friction relative error.
    pub coulomb_error: Option<f64>,
    /// Static error of the nonlinear-feedforward move, m.
    pub static_error_m: Option<f64>,
    /// Largest cart error of the nonlinear-feedforward move, m.
    pub max_cart_error_m: Option<f64>,
    /// The validation used the fastest feasible move instead of Table A.8's.
    pub reduced_move: Option<bool>,
}

/// Remembers the stage running (for the failure messages).
#[derive(Default)]
struct StageName(String);

impl crate::commission::Progress for StageName {
    fn stage_started(&mut self, name: &str, _total_samples: u64) {
        self.0 = name.to_string();
    }
    fn advance(&mut self, _samples: u64) {}
    fn stage_finished(&mut self, _summary: &str) {}
}

/// An axis that records the true cart excursion beyond a window.
struct Watched {
    inner: SimAxis,
    window: (f64, f64),
    excess_m: f64,
}

impl Axis for Watched {
    fn info(&self) -> AxisInfo {
        self.inner.info()
    }

    fn exchange(&mut self, torque_command_nm: f64) -> Result<Measurement, AxisError> {
        let m = self.inner.step(torque_command_nm);
        let x = self.inner.cart_position_m();
        let excess = (self.window.0 - x).max(x - self.window.1).max(0.0);
        self.excess_m = self.excess_m.max(excess);
        Ok(m)
    }

    fn quick_stop(&mut self) -> Result<(), AxisError> {
        self.inner.quick_stop()
    }
}

/// Tolerance of the travel check for the true cart, m: the supervisor watches
/// the motor side; the belt stretch under gravity and the encoder's
/// resolution put the cart this far from it.
pub const TRAVEL_TOLERANCE_M: f64 = 1e-3;

fn velocity_margin_on(design: &ControllerDesign, truth: &crate::model::TwoMassParams) -> f64 {
    match crate::design::robust::margins_on(design, truth) {
        Ok(m) => m.velocity_phase_margin_deg,
        Err(_) => f64::NAN,
    }
}

/// What an identification of the simulated axis can see, from the simulator's
/// own (three-mass) physics, at one cart position.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IdentificationTruth {
    /// Antiresonance of the torque -> motor angle response, Hz: the motor
    /// held still, cart and end pulley oscillating on the belt (the lowest
    /// undamped mode of the three-mass model (2.20) linearized with the
    /// motor locked).
    pub f_z_hz: f64,
    /// Cart mass a two-mass model with the data-sheet `Theta_e` must have to
    /// carry the axis' rigid-body inertia: `m_c + Theta_r / r^2` (the end
    /// pulley turns with the belt and is not in the data sheet's `Theta_e`), kg.
    pub m_c_kg: f64,
}

/// The truth the identification is compared with.
///
/// The two-mass linearization [`crate::model::PhysicalParams::linearize`]
/// neglects the end-pulley inertia (thesis 2.1.4); the simulator does not.
/// With egc70's end pulley (0.15 kg at the belt) that puts the two-mass `f_z`
/// up to 5 % and `m_c` up to 13 % away from what the simulated axis shows on
/// a light cart, more than the accuracy the study measures.
pub fn identification_truth(
    p: &crate::model::PhysicalParams,
    xi_m: f64,
) -> crate::Result<IdentificationTruth> {
    let lin = crate::model::three_mass::ThreeMass::new(p)?.linearize(xi_m);
    // states (2.18): 0/1 motor, 2/3 end pulley, 4/5 cart; with the motor
    // locked the positions 2 and 4 obey x'' = K x (K = -M^-1 stiffness)
    let k = nalgebra::Matrix2::new(lin.a[(3, 2)], lin.a[(3, 4)], lin.a[(5, 2)], lin.a[(5, 4)]);
    let w2 = k
        .complex_eigenvalues()
        .iter()
        .map(|l| -l.re)
        .fold(f64::INFINITY, f64::min);
    let r = p.r_m;
    Ok(IdentificationTruth {
        f_z_hz: w2.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
        m_c_kg: p.m_c() + p.theta_end_pulley_kg_m2 / (r * r),
    })
}

/// Commission plant `index` of the study seeded `seed` with `cfg`.
pub fn run_plant(
    seed: u64,
    index: u64,
    ranges: &Ranges,
    cfg: &CommissioningConfig,
) -> crate::Result<Outcome> {
    let g = generate(seed, index, ranges)?;
    let plant = Plant::Physical(g.params.clone());
    let start = 0.05;
    let ds = DataSheet::for_plant(&plant, start, None);
    let feas = feasibility(
        &plant,
        &ds,
        &MoveSpec {
            limits: table_a8_limits(),
            ..cfg.validation
        },
    );
    let sim = SimAxis::new(&plant, g.sim_config(start))?;
    let mut axis = Watched {
        inner: sim,
        window: (ds.travel_min_m, ds.travel_max_m),
        excess_m: 0.0,
    };
    let mut progress = StageName::default();
    let result = commission(&mut axis, &ds, cfg, &mut progress);
    let travel_violation = axis.excess_m > TRAVEL_TOLERANCE_M;
    let mut out = Outcome {
        index,
        plant: g.clone(),
        feasibility: feas,
        kind: OutcomeKind::Failed,
        class: Class::Defect,
        message: String::new(),
        travel_violation,
        travel_excess_m: axis.excess_m,
        true_velocity_phase_margin_deg: None,
        guaranteed_velocity_phase_margin_deg: None,
        f_z_error: None,
        m_c_error: None,
        coulomb_error: None,
        static_error_m: None,
        max_cart_error_m: None,
        reduced_move: None,
    };
    match result {
        Ok(run) => {
            let truth = plant.linearize(run.identification_position_m)?;
            let rel = |a: f64, b: f64| ((a - b) / b).abs();
            out.true_velocity_phase_margin_deg = Some(velocity_margin_on(&run.design, &truth));
            out.guaranteed_velocity_phase_margin_deg =
                Some(run.guaranteed.velocity_phase_margin_deg);
            let seen = identification_truth(&g.params, run.identification_position_m)?;
            out.f_z_error = Some(rel(run.identified.f_z_hz, seen.f_z_hz));
            out.m_c_error = Some(rel(run.identified.m_c, seen.m_c_kg));
            let c_true = plant.friction_totals().coulomb_nm;
            out.coulomb_error = Some(rel(run.friction.coulomb_nm, c_true));
            out.static_error_m = Some(run.validation.nonlinear.static_error_m);
            out.max_cart_error_m = Some(run.validation.nonlinear.max_tracking_error_m);
            out.reduced_move = Some(run.validation_move.reduced);
            if run.verdict.passed {
                out.kind = OutcomeKind::Success;
            } else {
                out.kind = OutcomeKind::LimitsNotMet;
                out.message = run.verdict.failures().join("; ");
            }
        }
        Err(e) => {
            out.message = format!("during {}: {e}", progress.0);
        }
    }
    out.class = classify(&out);
    Ok(out)
}

/// The classification rule (see the module docs).
pub fn classify(o: &Outcome) -> Class {
    if o.travel_violation {
        return Class::Defect;
    }
    let excused = !o.feasibility.feasible || o.feasibility.marginal;
    match o.kind {
        OutcomeKind::Success => {
            if o.true_velocity_phase_margin_deg
                .is_some_and(|pm| pm >= 30.0)
            {
                Class::Success
            } else {
                Class::Defect
            }
        }
        // A result that says it misses its limits is not silent; it is a
        // defect only on a plant that can do the move.
        OutcomeKind::LimitsNotMet | OutcomeKind::Failed => {
            if excused {
                Class::CorrectRefusal
            } else {
                Class::Defect
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The identification truth reduces to the two-mass linearization when
    /// the end pulley has no inertia, and sits below its `f_z` otherwise
    /// (the end pulley adds to the oscillating mass).
    #[test]
    fn identification_truth_is_the_two_mass_one_without_end_pulley() {
        let mut p = crate::model::rigs::egc70_params(0.0);
        let xi = p.stroke_m - 0.05;
        let with = identification_truth(&p, xi).unwrap();
        let two = p.linearize(xi).unwrap();
        assert!(with.f_z_hz < two.f_z_hz(), "{with:?} vs {}", two.f_z_hz());
        assert!(with.m_c_kg > two.m_c);
        p.theta_end_pulley_kg_m2 = 1e-12;
        let without = identification_truth(&p, xi).unwrap();
        let two = p.linearize(xi).unwrap();
        assert!(
            (without.f_z_hz / two.f_z_hz() - 1.0).abs() < 1e-3,
            "{without:?} vs {}",
            two.f_z_hz()
        );
        assert!((without.m_c_kg / two.m_c - 1.0).abs() < 1e-6);
    }

    /// The yardstick checked independently: the two-mass fit
    /// (data-sheet `Theta_e`, the commissioning's lines and band) of the
    /// exact frequency response of the simulator's linear three-mass model
    /// (no friction, no noise) finds the truth's `f_z` (the motor-locked
    /// mode) within 0.05 % on a loaded cart and +1.8 % on the empty one, and
    /// an `m_c` below the truth's rigid-body `m_c + Theta_r / r^2`: -1.3 % at
    /// 11.2 and 25 kg, -7.2 % on the empty cart (0.96 kg, where the end
    /// pulley's 0.15 kg is 14 % of the moving mass). A two-mass model with the
    /// data sheet's motor inertia cannot carry both the three-mass rigid
    /// inertia and its mode pair; on loaded carts the fit's `m_c` is the cart
    /// alone. That structural part of the `m_c` error (measured -1.2 to
    /// -4.2 % over 72 study plants, median -1.9 %) is the model's, not the
    /// identification's.
    #[test]
    fn identification_truth_is_what_a_fit_of_the_exact_three_mass_frf_shows() {
        use crate::ident::{fit_two_mass, FitConfig, Frf, LineStatus};
        for payload in [0.0, 11.2, 25.0] {
            let p = crate::model::rigs::egc70_params(payload);
            let xi = p.stroke_m - 0.05;
            let lin = crate::model::three_mass::ThreeMass::new(&p)
                .unwrap()
                .linearize(xi);
            // the commissioning's grid: PRBS order 9, clock 16 samples at 10 kHz
            let (ts, n) = (1e-4, 511 * 16);
            let df = 1.0 / (n as f64 * ts);
            let lines = n / 2 + 1;
            let freq_hz: Vec<f64> = (0..lines).map(|k| k as f64 * df).collect();
            let frf = Frf {
                response: freq_hz
                    .iter()
                    .map(|&f| {
                        if f > 0.0 {
                            lin.frf_motor_angle(2.0 * std::f64::consts::PI * f)
                        } else {
                            crate::lti::C64::new(0.0, 0.0)
                        }
                    })
                    .collect(),
                coherence: vec![1.0; lines],
                line_status: freq_hz
                    .iter()
                    .map(|&f| {
                        if (3.0..=625.0).contains(&f) {
                            LineStatus::Usable
                        } else {
                            LineStatus::OutsideBand
                        }
                    })
                    .collect(),
                input_power: vec![1.0; lines],
                freq_hz,
                ts_s: ts,
                n_periods: 2,
            };
            let fit = fit_two_mass(
                &frf,
                &FitConfig {
                    theta_e: Some(p.theta_e()),
                    i_t: p.i_t(),
                    n_log_lines: 60,
                    ..FitConfig::default()
                },
            )
            .unwrap();
            let truth = identification_truth(&p, xi).unwrap();
            let f_z = fit.f_z_hz / truth.f_z_hz - 1.0;
            let m_c = fit.params.m_c / truth.m_c_kg - 1.0;
            // measured: f_z +1.8 % at 0 kg, -0.04 % at 11.2 and 25 kg;
            // m_c -7.2 %, -1.3 %, -1.3 %
            assert!(f_z.abs() < 0.025, "{payload} kg: f_z {f_z:+.4}");
            assert!((-0.08..0.0).contains(&m_c), "{payload} kg: m_c {m_c:+.4}");
        }
    }

    #[test]
    fn the_generator_is_seeded_and_stays_in_its_ranges() {
        let r = Ranges::default();
        let a = generate(7, 3, &r).unwrap();
        let b = generate(7, 3, &r).unwrap();
        assert_eq!(a, b);
        let c = generate(7, 4, &r).unwrap();
        assert_ne!(a, c);
        for i in 0..200 {
            let g = generate(11, i, &r).unwrap();
            assert!((0.0..=25.0).contains(&g.payload_kg));
            assert!((0.5..=2.0).contains(&g.stiffness_factor));
            assert!((0.3..=3.0).contains(&g.viscous_factor));
            assert!((0.3..=3.0).contains(&g.coulomb_factor));
            assert!((-90.0..=90.0).contains(&g.tilt_deg));
            assert!((0.5e-3..=2.0e-3 + 1e-12).contains(&g.params.dead_time_s));
            assert!((0.5..=4.0).contains(&g.encoder_factor));
            assert!((0.0..=5.0).contains(&g.noise_factor));
            g.params.validate().unwrap();
        }
    }

    /// The feasibility is computed: the vertical egc70 with 25 kg cannot hold
    /// its load within the stop budget; the horizontal empty one can do the
    /// Table A.8 move.
    #[test]
    fn feasibility_follows_the_torque_balance() {
        let spec = MoveSpec::default();
        let light = crate::model::rigs::builtin("egc70", Some(0.0)).unwrap();
        let ds = DataSheet::for_plant(&light, 0.05, None);
        let f = feasibility(&light, &ds, &spec);
        assert!(f.feasible && f.table_a8_feasible, "{f:?}");
        let mut heavy = crate::model::rigs::egc70_params(25.0);
        heavy.tilt_rad = 90f64.to_radians();
        let heavy = Plant::Physical(heavy);
        let f = feasibility(&heavy, &ds, &spec);
        assert!(!f.feasible && !f.table_a8_feasible, "{f:?}");
    }
}
