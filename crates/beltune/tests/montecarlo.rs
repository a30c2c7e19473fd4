//! Issue 12: the seeded CI sample of the Monte Carlo robustness study. Every
//! failure must be a correct refusal of an infeasible plant, the true cart
//! never leaves its travel window, and every delivered controller keeps a
//! velocity-loop phase margin of at least 30 deg on the true linearized plant.
//! (`beltune montecarlo --plants 1000` runs the full study; README.)

use beltune::procedure::commission::CommissioningConfig;
use beltune::study::{run_plant, Class, OutcomeKind, Ranges, Table};

/// Seed of the CI sample (the README's study uses the same generator).
const SEED: u64 = 12;
/// Plants in the CI sample: a few dozen, a few minutes on two cores.
const PLANTS: u64 = 24;
/// Issue 12: the true-plant velocity margin never below this, deg.
const MIN_TRUE_PHASE_MARGIN_DEG: f64 = 30.0;

/// What already holds on the sample (issue 12, the safety part): the true
/// cart stays inside its window, and every delivered controller, whether
/// its move met the limits or not, is stable on the true linearized plant
/// with at least 30 deg velocity-loop phase margin.
#[test]
fn the_seeded_ci_sample_is_safe_and_its_controllers_keep_their_margins_issue_12() {
    let cfg = CommissioningConfig::default();
    let ranges = Ranges::default();
    for i in 0..PLANTS {
        let o = run_plant(SEED, i, &ranges, &cfg).unwrap();
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

/// Issue 12, the static error: plant #4 of the sample (3 kg, tilted 26 deg,
/// Coulomb friction x1.44) ended 189 um short of its target with the cart
/// stuck, because the Coulomb feedforward dropped with the trajectory's
/// velocity and the integrator needed seconds to build the torque; with the
/// controller's Coulomb hold (beltune-rt, refinement (c)) it meets the
/// thesis' 100 um.
#[test]
fn the_coulomb_hold_brings_a_sticking_cart_to_its_target_issue_12() {
    let o = run_plant(SEED, 4, &Ranges::default(), &CommissioningConfig::default()).unwrap();
    let e = o.static_error_m.expect("a controller");
    assert!(e < 100e-6, "static error {:.1} um ({})", e * 1e6, o.message);
}

#[test]
#[ignore = "issue 12 is not closed: the seeded sample still has static-error defects (README, robustness study); run with --ignored"]
fn the_seeded_ci_sample_has_no_defects_issue_12() {
    let cfg = CommissioningConfig::default();
    let ranges = Ranges::default();
    let outcomes: Vec<_> = (0..PLANTS)
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
        if o.kind == OutcomeKind::Success {
            let pm = o.true_velocity_phase_margin_deg.unwrap();
            assert!(
                pm >= MIN_TRUE_PHASE_MARGIN_DEG,
                "plant #{}: {pm:.1} deg on the true plant",
                o.index
            );
        }
        assert_ne!(o.class, Class::Defect, "plant #{}: {:?}", o.index, o);
    }
}
