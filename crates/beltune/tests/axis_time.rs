//! Issue 31: the default commissioning keeps the axis busy at most 15 s
//! (commercial one-button tuners take 10-30 s; before the issue egc70 took
//! 26.0 s, 7-8 s of it two comparison moves that were neither judged nor
//! delivered). Axis time is simulated time here (samples times the cycle
//! time), so the numbers are exact and the budgets are no timing assertions.
//!
//! The budget of each stage is what it physically needs, with the slack
//! stated: the PRBS periods of the excitation settings, the moves at the
//! positioning limits (planned here with the trajectory generator, not taken
//! from the run), the runs and holds the stage is made of.

use beltune::commission::config::{
    POSITIONING_ACCELERATION_M_S2, POSITIONING_JERK_M_S3, POSITIONING_SPEED_M_S,
};
use beltune::commission::{commission_simulated, Commissioning, CommissioningConfig, NoProgress};
use beltune::model::rigs;
use beltune::sim::SimConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Issue 31's target for the whole default commissioning, s.
const TOTAL_S: f64 = 15.0;

fn commission(name: &str, payload_kg: Option<f64>) -> Commissioning {
    let plant = rigs::builtin(name, payload_kg).unwrap();
    commission_simulated(
        &plant,
        SimConfig::default(),
        None,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Duration of a positioning move over `distance_m` from rest to rest, s.
fn positioning_move_s(distance_m: f64) -> f64 {
    let limits = Limits {
        v_max: POSITIONING_SPEED_M_S,
        v_min: -POSITIONING_SPEED_M_S,
        a_max: POSITIONING_ACCELERATION_M_S2,
        a_min: -POSITIONING_ACCELERATION_M_S2,
        j_max: POSITIONING_JERK_M_S3,
        j_min: -POSITIONING_JERK_M_S3,
        position_min: -10.0,
        position_max: 10.0,
    };
    Trajectory::plan(&State::at_rest(0.0), &State::at_rest(distance_m), &limits)
        .unwrap()
        .duration_s()
}

/// The budget of each stage that moves the axis, s, for a run on a window
/// of `width_m` whose identification excitation lasted `prbs_s`.
fn budgets(width_m: f64, prbs_s: f64, clock_s: f64) -> Vec<(&'static str, f64)> {
    // stage 5c: an order-7 PRBS, a transient and two averaged periods, and
    // the move from the far end to a quarter of the window
    let near_start_prbs_s = 3.0 * 127.0 * clock_s;
    vec![
        // the catch after enabling the drive (0.3 s) and nothing else
        ("take axis", 0.35),
        // slow runs up and down at two speeds, 60 mm each (issue 31's
        // baseline 1.9 s; issue 31 leaves the stage as it was)
        ("holding torque", 2.0),
        // to the far end of the window, 0.1 s of holds
        ("position", positioning_move_s(0.88 * width_m) + 0.1),
        // bursts of 0.15 s from 2 % of the torque limit up by 1.5 each (the
        // baseline's 1.5 s on egc70 at 11.2 kg; the empty cart needs more)
        ("excitation", 2.0),
        // the PRBS, the move to its centre and the holds
        ("identification", prbs_s + 0.25),
        (
            "belt stiffness near the start",
            near_start_prbs_s + positioning_move_s(0.7 * width_m) + 0.15,
        ),
        // the move to the runs' start and four runs of 0.3 s plateaus at 0.1
        // and 0.4 m/s with their ramps (at most 10 m/s^2) and holds
        (
            "friction",
            positioning_move_s(0.2 * width_m) + 4.0 * 0.3 + 2.0 * (0.1 + 0.15) + 0.3,
        ),
        // one move: the return (short: the friction runs end near the
        // start), the 15 mm creep, the trajectory (0.8 s for Table A.8's
        // 0.5 m, about 1.2 s for sim-c's reduced move), the final approach
        // (about 1 mm at 2 mm/s) and 0.4 s settled
        ("validation", 3.0),
    ]
}

fn check(name: &str, payload_kg: Option<f64>) -> Commissioning {
    let run = commission(name, payload_kg);
    let label = format!("{name} {payload_kg:?}");
    let stages: Vec<String> = run
        .stage_axis_times
        .iter()
        .map(|t| format!("{} {:.2}", t.stage, t.axis_time_s))
        .collect();
    eprintln!(
        "{label}: {:.2} s: {}; move {:.3} mm, {:.1} um",
        run.experiment_time_s,
        stages.join(", "),
        run.validation.nonlinear.max_tracking_error_m * 1e3,
        run.validation.nonlinear.static_error_m * 1e6
    );
    // the stages account for all of the axis time
    let sum: f64 = run.stage_axis_times.iter().map(|t| t.axis_time_s).sum();
    assert!(
        (sum - run.experiment_time_s).abs() < 1e-9,
        "{label}: stages {sum} s, busy {} s",
        run.experiment_time_s
    );
    assert!(
        run.experiment_time_s <= TOTAL_S,
        "{label}: axis busy {:.2} s",
        run.experiment_time_s
    );
    // no comparison moves unless asked for
    assert_eq!(run.moves.len(), 1, "{label}");
    let ds = run.datasheet;
    let ts = run.excitation.time_s[1] - run.excitation.time_s[0];
    let prbs_s = run.excitation.time_s.len() as f64 * ts;
    let clock_s = CommissioningConfig::default()
        .excitation
        .for_band(
            ts,
            beltune::commission::band::ResonanceBand::of(&ds).as_ref(),
        )
        .clock_period_s;
    let width = ds.travel_max_m - ds.travel_min_m;
    for (stage, budget) in budgets(width, prbs_s, clock_s) {
        let t = run
            .stage_axis_times
            .iter()
            .find(|t| t.stage == stage)
            .unwrap_or_else(|| panic!("{label}: no stage {stage}"));
        assert!(
            t.axis_time_s <= budget,
            "{label}: {stage} {:.3} s, budget {budget:.3} s",
            t.axis_time_s
        );
    }
    run
}

/// egc70 at the payloads of the issue: each stage within its budget, all
/// within 15 s; at the default 11.2 kg the delivered move stays as accurate
/// as before the issue (README: 0.046 mm, 3 um): within 0.1 mm and 10 um.
#[test]
fn egc70_commissions_within_15_s_of_axis_time() {
    for payload in [Some(0.0), None, Some(25.0)] {
        let run = check("egc70", payload);
        if payload.is_none() {
            let nl = &run.validation.nonlinear;
            assert!(nl.max_tracking_error_m < 0.1e-3, "{nl:?}");
            assert!(nl.static_error_m < 10e-6, "{nl:?}");
        }
    }
}

/// The linear sets sim-a, sim-b and sim-c (sim-c with its data sheet's
/// resonances up to 465 Hz: a 1.4 ms clock, order 10, 4.3 s of PRBS).
#[test]
fn the_simulated_sets_commission_within_15_s_of_axis_time() {
    for name in ["sim-a", "sim-b", "sim-c"] {
        check(name, None);
    }
}
