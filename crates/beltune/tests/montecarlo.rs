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

#[test]
#[ignore = "issue 12 is not closed: the seeded sample still has defects (README, robustness study); run with --ignored"]
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
