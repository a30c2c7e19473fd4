//! The health check on the simulated egc70 against a commissioning of it:
//! what it measures against the simulator's truth (an independent
//! reference), the detection of ageing (a 10 % stiffness loss, a 30 %
//! friction rise, a slack span, a worn guide) and the false-alarm rate over
//! healthy runs with different seeds and noise, each within five seconds of
//! axis time.

use beltune::commission::{commission_simulated, CommissioningConfig, NoProgress};
use beltune::health::{health_simulated, Baseline, HealthCheck, HealthConfig, Quantity, Status};
use beltune::model::{builtin, MeasurementNoise, PhysicalParams, Plant, Wear};
use beltune::record::commissioning::{AxisRecord, Origin};
use beltune::record::folder::OutputTarget;
use beltune::record::provenance::Provenance;
use beltune::report::folder::ResultSet;
use beltune::sim::SimConfig;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Healthy runs of the false-alarm sweep in CI (the issue asks for 50 or
/// more); `health_sweep_full` runs 500.
const HEALTHY_RUNS: u64 = 60;
/// Runs per ageing case in the detection sweep.
const AGED_RUNS: u64 = 8;
/// The axis time a health check may take, s.
const MAX_AXIS_TIME_S: f64 = 5.0;

fn egc70() -> PhysicalParams {
    match builtin("egc70", None).unwrap() {
        Plant::Physical(p) => p,
        Plant::Linear(_) => unreachable!(),
    }
}

/// The baseline: egc70 commissioned once (seed 1), its result folder
/// written and read back as `beltune health --baseline` reads it.
fn baseline() -> &'static Baseline {
    static B: OnceLock<Baseline> = OnceLock::new();
    B.get_or_init(|| {
        let plant = builtin("egc70", None).unwrap();
        let sim = SimConfig {
            seed: 1,
            ..SimConfig::default()
        };
        let run = commission_simulated(
            &plant,
            sim,
            None,
            &CommissioningConfig::default(),
            &mut NoProgress,
        )
        .unwrap();
        let origin = Origin {
            name: "egc70".into(),
            axis: AxisRecord::simulated("egc70", &plant, 0.05, 1),
            truth: None,
            provenance: Provenance::of_this_process(Some(1)),
        };
        let dir =
            std::env::temp_dir().join(format!("beltune-health-baseline-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        ResultSet::of_run(&run, &origin)
            .unwrap()
            .write(&OutputTarget::Exact {
                dir: dir.clone(),
                force: false,
            })
            .unwrap();
        let b = Baseline::read(&dir).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        b
    })
}

/// Seed `k`'s noise: torque noise 1-10 mN m and encoder noise 0-1 count,
/// cycling through combinations.
fn noise(k: u64) -> MeasurementNoise {
    MeasurementNoise {
        torque_nm: [1e-3, 2e-3, 5e-3, 1e-2][(k % 4) as usize],
        encoder_counts: [0.0, 0.3, 1.0][((k / 4) % 3) as usize],
    }
}

fn check(wear: Wear, k: u64) -> HealthCheck {
    let plant = Plant::Physical(PhysicalParams { wear, ..egc70() });
    let sim = SimConfig {
        seed: 1000 + k,
        noise: Some(noise(k)),
        ..SimConfig::default()
    };
    let h = health_simulated(
        &plant,
        sim,
        None,
        baseline(),
        &HealthConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("{wear:?} run {k}: {e}"));
    assert!(
        h.experiment_time_s <= MAX_AXIS_TIME_S,
        "{wear:?} run {k}: the axis was busy {:.2} s",
        h.experiment_time_s
    );
    h
}

fn status(h: &HealthCheck, q: Quantity) -> Status {
    h.comparison(q).map_or(Status::Ok, |c| c.status)
}

/// What the check measures on a healthy egc70 against the simulator's truth
/// where it measured (the linearization (2.33) and the friction totals
/// (3.36) of the plant): the far stiffness within 2 % (the
/// identification's own accuracy on this axis is 1 %), Coulomb and viscous
/// friction within 3 % and 5 %, the holding torque within 5 mN m.
#[test]
fn the_health_check_measures_the_truth() {
    let p = egc70();
    let plant = Plant::Physical(p.clone());
    let totals = plant.friction_totals();
    let h = check(Wear::default(), 1);
    let far = h.measured.far.as_ref().unwrap();
    let truth = plant.linearize(far.position_m).unwrap();
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(
        rel(far.params.c, truth.c) < 0.02,
        "c {} truth {}",
        far.params.c,
        truth.c
    );
    let f = h.measured.friction.unwrap();
    assert!(
        rel(f.coulomb_nm, totals.coulomb_nm) < 0.03,
        "{f:?} {totals:?}"
    );
    assert!(
        rel(f.viscous_nm_s_per_rad, totals.viscous_nm_s_per_rad) < 0.05,
        "{f:?} {totals:?}"
    );
    assert!(f.holding_nm.abs() < 5e-3, "{f:?}");
}

/// Healthy runs (seeds and noise levels varied) raise no alarm: no quantity
/// asks for action, and none is even on watch. And the uncertainty each run
/// states covers the spread of its value over the runs: the standard
/// deviation of the far stiffness, the Coulomb and the viscous friction over
/// the runs is at most twice the mean stated one-sigma value (a stated
/// uncertainty far below the real spread would turn noise into alarms).
#[test]
fn healthy_runs_raise_no_alarm() {
    let _ = baseline();
    let runs: Vec<HealthCheck> = (0..HEALTHY_RUNS)
        .into_par_iter()
        .map(|k| check(Wear::default(), k))
        .collect();
    let findings: Vec<String> = runs
        .iter()
        .enumerate()
        .flat_map(|(k, h)| {
            h.comparisons
                .iter()
                .filter(|c| c.status != Status::Ok)
                .map(move |c| {
                    format!(
                        "run {k}: {} {} {:?}",
                        c.quantity.key(),
                        c.change_text(),
                        c.status
                    )
                })
                .chain(
                    h.measured
                        .failures
                        .iter()
                        .map(move |f| format!("run {k}: {f}")),
                )
        })
        .collect();
    assert!(findings.is_empty(), "false alarms: {findings:#?}");
    for q in [
        Quantity::StiffnessFar,
        Quantity::CoulombFriction,
        Quantity::ViscousFriction,
    ] {
        let (values, sigmas): (Vec<f64>, Vec<f64>) = runs
            .iter()
            .map(|h| {
                let c = h.comparison(q).unwrap();
                (c.measured.value, c.measured.sigma)
            })
            .unzip();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let stated = sigmas.iter().sum::<f64>() / n;
        eprintln!("{}: spread {sd:.3e}, stated {stated:.3e}", q.key());
        assert!(
            sd <= 2.0 * stated,
            "{}: spread {sd} against stated {stated}",
            q.key()
        );
    }
}

/// Each ageing of the simulator is found in every run: a 10 % belt
/// stiffness loss (the far stiffness at least on watch), a 30 % friction
/// rise (Coulomb and viscous friction beyond their +20 % limit), a slack
/// span (a pretension of 90 N, below the forces of the excitation's +-62 N
/// at the belt and the cart's inertia: the resonance drops with the
/// amplitude, at least on watch; of 40 N: the response no longer fits a
/// two-mass model, the axis asks for action), a worn guide (3 N more cart
/// friction: Coulomb beyond its limit).
#[test]
fn ageing_is_detected() {
    let _ = baseline();
    let cases: [(&str, Wear); 5] = [
        (
            "stiffness -10 %",
            Wear {
                belt_stiffness_loss: 0.10,
                ..Wear::default()
            },
        ),
        (
            "friction +30 %",
            Wear {
                friction_growth: 0.30,
                ..Wear::default()
            },
        ),
        (
            "slack span",
            Wear {
                belt_pretension_n: Some(90.0),
                ..Wear::default()
            },
        ),
        (
            "slack belt",
            Wear {
                belt_pretension_n: Some(40.0),
                ..Wear::default()
            },
        ),
        (
            "worn guide",
            Wear {
                guide_wear_n: 3.0,
                ..Wear::default()
            },
        ),
    ];
    let missed: Vec<String> = cases
        .par_iter()
        .flat_map(|(name, wear)| {
            (0..AGED_RUNS)
                .into_par_iter()
                .filter_map(|k| {
                    let h = check(*wear, k);
                    let found = match *name {
                        "stiffness -10 %" => status(&h, Quantity::StiffnessFar) >= Status::Watch,
                        "friction +30 %" => {
                            status(&h, Quantity::CoulombFriction) == Status::Act
                                && status(&h, Quantity::ViscousFriction) == Status::Act
                        }
                        "slack span" => {
                            status(&h, Quantity::AmplitudeDependence) >= Status::Watch
                                && h.comparison(Quantity::AmplitudeDependence)
                                    .is_some_and(|c| c.change < 0.0)
                        }
                        "slack belt" => h.status == Status::Act,
                        _ => status(&h, Quantity::CoulombFriction) == Status::Act,
                    };
                    (!found).then(|| {
                        format!("{name} run {k}: {:?} {:?}", h.status, h.recommendations())
                    })
                })
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(missed.is_empty(), "missed: {missed:#?}");
}

/// The full false-alarm sweep: 500 healthy runs (about a minute on two cores).
#[test]
#[ignore = "the long sweep; CI runs `healthy_runs_raise_no_alarm`"]
fn health_sweep_full() {
    let _ = baseline();
    let alarms: usize = (0..500u64)
        .into_par_iter()
        .map(|k| usize::from(check(Wear::default(), k).status != Status::Ok))
        .sum();
    assert_eq!(alarms, 0);
}
