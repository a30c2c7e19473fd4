//! Issue 12: built-in plants that the thesis' move does not fit, and the
//! verdict of the result.

use beltune::model::rigs;
use beltune::procedure::commission::{commission, CommissioningConfig, DataSheet};
use beltune::procedure::NoProgress;
use beltune::sim::{SimAxis, SimConfig};

fn commission_builtin(
    name: &str,
    payload_kg: Option<f64>,
) -> beltune::procedure::commission::Commissioning {
    let plant = rigs::builtin(name, payload_kg).unwrap();
    let start = 0.05;
    let mut axis = SimAxis::new(
        &plant,
        SimConfig {
            seed: 1,
            initial_cart_position_m: Some(start),
            ..SimConfig::default()
        },
    )
    .unwrap();
    let ds = DataSheet::for_plant(&plant, start, None);
    commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// sim-c's viscous friction (200 N s/m) needs 3.4 N m at the Table A.8
/// move's peak speed, more than the 3.1 N m limit: the validation runs the
/// fastest move the axis can do instead of failing, reports it as such, and
/// meets the thesis' accuracy with it.
#[test]
fn sim_c_validates_with_the_fastest_feasible_move_issue_12() {
    let run = commission_builtin("sim-c", None);
    assert!(run.validation_move.reduced, "{:?}", run.validation_move);
    assert!(run.verdict.reduced_move);
    assert!(run.verdict.meets_limits, "{:?}", run.verdict);
    assert!(run.validation_move.limits.v_max < 5.0);
    assert!(run
        .log
        .iter()
        .any(|l| l.contains("the fastest move the axis can do")));
}

/// egc70 at its heaviest payload of the issue's range commissions and says
/// what it guarantees.
#[test]
fn egc70_with_25_kg_meets_its_limits_issue_12() {
    let run = commission_builtin("egc70", Some(25.0));
    assert!(run.verdict.meets_limits, "{:?}", run.verdict);
    assert!(run.verdict.guaranteed.models > 0);
    assert!(run.log.iter().any(|l| l.starts_with("verdict:")));
}
