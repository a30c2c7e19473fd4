//! The seeded CI sample of the Monte Carlo robustness study. Every
//! failure must be a correct refusal of an infeasible plant, the true cart
//! never leaves its travel window, and every delivered controller keeps a
//! velocity-loop phase margin of at least 30 deg on the true linearized plant.
//! (`beltune montecarlo --plants 1000` runs the full study; README.)

use beltune::commission::CommissioningConfig;
use beltune::study::{run_plant, Class, OutcomeKind, Ranges, Table};
use rayon::prelude::*;

/// Seed of the CI sample (the README's study uses the same generator).
const SEED: u64 = 12;
/// Plants in the CI sample: about 25 s on two cores (the cart observer's
/// exact step made a plant's commissioning 3x cheaper; the sample was 24).
const PLANTS: u64 = 96;
/// Successes the sample must keep: the full study (README) has 88 among
/// these plants and 8 correct refusals of axes too heavy to hold; more
/// refusals than 16 would be a commissioning that gives up on feasible axes.
const MIN_SUCCESSES: usize = 80;
/// The true-plant velocity margin never below this, deg.
const MIN_TRUE_PHASE_MARGIN_DEG: f64 = 30.0;

/// The static error: plant #4 of the sample (3 kg, tilted 26 deg,
/// Coulomb friction x1.44) ended 189 um short of its target with the cart
/// stuck, because the Coulomb feedforward dropped with the trajectory's
/// velocity and the integrator needed seconds to build the torque; with the
/// controller's Coulomb hold (beltune-rt, refinement (c)) it meets the
/// thesis' 100 um.
#[test]
fn the_coulomb_hold_brings_a_sticking_cart_to_its_target() {
    let o = run_plant(SEED, 4, &Ranges::default(), &CommissioningConfig::default()).unwrap();
    let e = o.static_error_m.expect("a controller");
    assert!(e < 100e-6, "static error {:.1} um ({})", e * 1e6, o.message);
}

/// The static error: plant #252 (13.3 kg, horizontal, slow loops)
/// overshot its target by 0.38 mm at the motor and stuck there, 440 um from
/// the target at the cart, while the integrator built the breakaway torque at
/// 0.01 N m per 100 ms; with the controller's Coulomb breakaway (beltune-rt,
/// refinement (c): the hold re-engages toward the target beyond 20 um) it
/// meets the thesis' 100 um (24 um).
#[test]
fn the_coulomb_breakaway_brings_an_overshooting_cart_back() {
    let o = run_plant(
        SEED,
        252,
        &Ranges::default(),
        &CommissioningConfig::default(),
    )
    .unwrap();
    let e = o.static_error_m.expect("a controller");
    assert!(e < 100e-6, "static error {:.1} um ({})", e * 1e6, o.message);
}

/// The check: on the sample every failure is a correct refusal of an
/// infeasible plant (no defect: the static error and the max cart error meet
/// the thesis' limits on every feasible plant), the true cart stays inside
/// its window, and every delivered controller, whether its move met the
/// limits or not, is stable on the true linearized plant with at least 30 deg
/// velocity-loop phase margin.
#[test]
fn the_seeded_ci_sample_has_no_defects_and_keeps_its_margins() {
    let cfg = CommissioningConfig::default();
    let ranges = Ranges::default();
    // in parallel as `beltune montecarlo` runs the study (rayon keeps the order)
    let outcomes: Vec<_> = (0..PLANTS)
        .into_par_iter()
        .map(|i| run_plant(SEED, i, &ranges, &cfg).unwrap())
        .collect();
    let table = Table::new(&outcomes);
    eprintln!("{}", table.markdown());
    for o in &outcomes {
        assert!(
            !o.travel_violation,
            "plant #{}: the cart left the window by {:.1} mm ({})",
            o.index,
            o.travel_excess_m * 1e3,
            o.message
        );
        if let Some(pm) = o.true_velocity_phase_margin_deg {
            assert!(
                pm >= MIN_TRUE_PHASE_MARGIN_DEG,
                "plant #{}: {pm:.1} deg on the true plant ({})",
                o.index,
                o.message
            );
        }
        assert_ne!(o.class, Class::Defect, "plant #{}: {:?}", o.index, o);
    }
    let successes = outcomes
        .iter()
        .filter(|o| o.kind == OutcomeKind::Success)
        .count();
    assert!(
        successes >= MIN_SUCCESSES,
        "{successes} successes of {PLANTS}"
    );
}

/// Plants of the CI sample drawn with the dynamics beyond the model.
const UNMODELED_PLANTS: u64 = 24;

/// With the dynamics real axes have drawn (current loop, frame mode,
/// cogging, ripple, encoder line errors, tooth mesh: `Ranges::unmodeled`)
/// the commissioning stays safe on the first 24 plants of the CI seed: the
/// true cart never leaves its window and every delivered controller keeps
/// 30 deg on the true linearized plant. (It does not yet stay free of
/// defects: seed 12's 96-plant sample had 7 feasible plants miss their
/// limits, e.g. #38's max cart error 1.08 mm; docs/robustness.md.)
#[test]
fn with_unmodeled_dynamics_drawn_the_commissioning_stays_safe() {
    let cfg = CommissioningConfig::default();
    let ranges = Ranges {
        unmodeled: true,
        ..Ranges::default()
    };
    let outcomes: Vec<_> = (0..UNMODELED_PLANTS)
        .into_par_iter()
        .map(|i| run_plant(SEED, i, &ranges, &cfg).unwrap())
        .collect();
    eprintln!("{}", Table::new(&outcomes).markdown());
    for o in &outcomes {
        assert!(
            !o.plant.params.unmodeled.is_off(),
            "plant #{} drew nothing",
            o.index
        );
        assert!(
            !o.travel_violation,
            "plant #{}: the cart left the window by {:.1} mm ({})",
            o.index,
            o.travel_excess_m * 1e3,
            o.message
        );
        if let Some(pm) = o.true_velocity_phase_margin_deg {
            assert!(
                pm >= MIN_TRUE_PHASE_MARGIN_DEG,
                "plant #{}: {pm:.1} deg on the true plant ({})",
                o.index,
                o.message
            );
        }
    }
}

/// The seeds of docs/robustness.md's table.
const PAGE_SEEDS: [u64; 2] = [12, 13];
/// Plants per seed of the full study.
const PAGE_PLANTS: u64 = 1000;

/// The counts of one seed as docs/robustness.md's table row writes them:
/// `| seed | feasible (A.8-capable) | successes | correct refusals | defects | travel violations |`.
fn page_row(seed: u64, outcomes: &[beltune::study::Outcome]) -> String {
    let count =
        |f: &dyn Fn(&beltune::study::Outcome) -> bool| outcomes.iter().filter(|o| f(o)).count();
    format!(
        "| {seed} | {} ({}) | {} | {} | {} | {} |",
        count(&|o| o.feasibility.feasible),
        count(&|o| o.feasibility.table_a8_feasible),
        count(&|o| o.class == Class::Success),
        count(&|o| o.class == Class::CorrectRefusal),
        count(&|o| o.class == Class::Defect),
        count(&|o| o.travel_violation),
    )
}

/// The full study of the documentation, seed by seed: the table of
/// docs/robustness.md is what the study measures today. About 5 minutes per
/// seed on two cores in release: `cargo test -p beltune --release --test
/// montecarlo -- --ignored`.
#[test]
#[ignore = "the full study: 1000 plants per seed, minutes in release"]
fn the_robustness_page_shows_what_the_study_measures() {
    let page = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/robustness.md"),
    )
    .unwrap();
    let cfg = CommissioningConfig::default();
    let ranges = Ranges::default();
    for seed in PAGE_SEEDS {
        let outcomes: Vec<_> = (0..PAGE_PLANTS)
            .into_par_iter()
            .map(|i| run_plant(seed, i, &ranges, &cfg).unwrap())
            .collect();
        let row = page_row(seed, &outcomes);
        assert!(
            page.lines().any(|l| l.trim() == row),
            "docs/robustness.md lacks the row `{row}` that seed {seed} gives today"
        );
    }
}
