//! The safety defects of the excitation, holding-torque and
//! validation stages: plants of the seeded study (seed 12; one of seed 13) that ended in a
//! travel stop or left their travel window, and the measurement noise as a
//! plant parameter.

use beltune::commission::NoProgress;
use beltune::commission::{commission_simulated, CommissioningConfig};
use beltune::model::{rigs, MeasurementNoise};
use beltune::sim::{SimAxis, SimConfig};
use beltune::study::{run_plant, Class, Outcome, OutcomeKind, Ranges};

fn plant(index: u64) -> Outcome {
    run_plant(
        12,
        index,
        &Ranges::default(),
        &CommissioningConfig::default(),
    )
    .unwrap()
}

/// Plants #24 and #38 (15.7 and 16.1 kg, tilt +12 / +29 deg) ended "during
/// validation moves: at 82.2 mm the axis could not stop before -10.3 mm",
/// #38 with the cart 29.3 mm outside the window: the unmeasured return ran
/// under the designed feedback, which on these axes hunts at the torque
/// limit. It now runs under the bootstrap cascade at positioning limits.
#[test]
fn the_validation_return_ends_in_no_travel_stop() {
    for index in [24, 38] {
        let o = plant(index);
        assert!(!o.travel_violation, "#{index}: {:?}", o.travel_excess_m);
        assert!(
            !o.message.contains("travel window"),
            "#{index}: {}",
            o.message
        );
    }
}

/// Plant #8 (18.7 kg, tilt -66 deg) tripped in closed loop on a 0.5 m/s
/// spike of the fast velocity estimate while the cart crept; the stop
/// planned from the spike drove the cart 50 mm out of the window. The stop
/// now starts from a velocity the rigid-body estimate confirms.
#[test]
fn a_stop_ends_inside_the_window() {
    let o = plant(8);
    assert!(
        !o.travel_violation,
        "cart {:.1} mm outside: {}",
        o.travel_excess_m * 1e3,
        o.message
    );
}

/// Seed 13, plant #787 (16.9 kg on a 59 deg slope, little friction): the
/// identification's open-loop PRBS drifted 57 mm, to 2.5 mm below the
/// window's upper edge, the next stage's first closed-loop sample tripped
/// the look-ahead, and the stop (preloaded then with the mean command of the
/// last 20 ms, 0.44 N m short of the load: fixed in the runner, see
/// `the_stop_preload_after_an_open_loop_excitation_is_its_mean_issue_12`)
/// let the load push the cart 4.6 mm out of the window. An open-loop
/// excitation now ends early where the closed loop could no longer take the
/// axis over with 10 mm to spare, and starts again against its drift: the
/// plant commissions, inside its window.
#[test]
fn an_open_loop_excitation_that_drifts_starts_again_against_its_drift() {
    let o = run_plant(13, 787, &Ranges::default(), &CommissioningConfig::default()).unwrap();
    assert_eq!(o.class, Class::Success, "{}", o.message);
    assert!(
        !o.travel_violation,
        "cart {:.1} mm outside",
        o.travel_excess_m * 1e3
    );
}

/// Plant #97 (16.7 kg, tilt +78 deg, 2.10 N m of gravity) was refused on
/// its first hold (2.365 N m: gravity plus the static friction the sagging
/// load met); physics lets it be stopped. The refusal is left to the
/// holding-torque stage, which measures gravity without friction.
#[test]
fn the_first_hold_does_not_refuse_a_stoppable_axis() {
    let o = plant(97);
    assert!(o.feasibility.feasible, "{:?}", o.feasibility);
    assert!(!o.message.contains("take axis"), "{}", o.message);
    assert!(!o.travel_violation);
}

/// Plants #530, #597, #777, #804 and #839 (23.7-25.9 kg, tilt +68 to +86
/// deg: 2.90-3.11 N m of gravity towards the lower edge, torque limit 3.1
/// N m) ended "during take axis: safety stop: ... axis stopped at" -66 to
/// -294 mm, up to 284 mm outside the window: the slow bootstrap loop let
/// the load fall for 60 ms to 0.31 m/s, which the 0.2 N m left of the limit
/// cannot brake in 60 mm, and the stop then dropped the torque that held
/// it. #949 and #983 (gravity towards +x) fell 125 mm and ended in the
/// holding-torque runs with "record too short" and a following-error stop.
/// The take now catches the load with the holding torque its first fall
/// shows, the stop keeps the torque that held it, and a first hold beyond
/// the stop's command budget is refused there, inside the window.
#[test]
fn heavy_steep_loads_are_caught_and_refused_inside_the_window() {
    for index in [530, 597, 777, 804, 839, 949, 983] {
        let o = plant(index);
        assert!(!o.feasibility.feasible, "#{index}: {:?}", o.feasibility);
        assert!(
            !o.travel_violation && o.travel_excess_m == 0.0,
            "#{index}: {:.1} mm outside ({})",
            o.travel_excess_m * 1e3,
            o.message
        );
        assert_eq!(o.class, Class::CorrectRefusal, "#{index}: {}", o.message);
        assert!(
            o.message.starts_with("during take axis: infeasible")
                && o.message.contains("to hold its load"),
            "#{index}: {}",
            o.message
        );
    }
}

/// Plants #822 and #959 (1.3 and 1.7 kg, Coulomb friction 0.25 and 0.30
/// N m, feasible) ended "during validation moves: safety stop: at -3.0 mm
/// the axis could not stop before -10.0 mm": the unmeasured return ran the
/// slow positioning loop at the validation move's 1.1 m/s, lagged 30 mm and
/// overshot its approach point 15 mm inside the window by 18 mm. It now
/// runs within the positioning limits the loop moved the axis with before.
#[test]
fn the_return_of_a_light_cart_with_high_friction_ends_in_no_travel_stop() {
    for index in [822, 959] {
        let o = plant(index);
        assert!(o.feasibility.feasible, "#{index}: {:?}", o.feasibility);
        assert!(!o.travel_violation, "#{index}: {}", o.message);
        assert_ne!(o.kind, OutcomeKind::Failed, "#{index}: {}", o.message);
    }
}

fn commission_sim_c(seed: u64, noise: MeasurementNoise) -> (Vec<f64>, Vec<f64>, f64) {
    let plant = rigs::builtin("sim-c", None).unwrap();
    let run = commission_simulated(
        &plant,
        SimConfig {
            seed,
            noise: Some(noise),
            ..SimConfig::default()
        },
        None,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("sim-c: {e}"));
    let torques = run
        .delivered_move()
        .expect("the delivered move ran")
        .record
        .samples
        .iter()
        .map(|s| s.torque_actual_nm)
        .collect();
    (
        run.excitation.position_m,
        torques,
        run.validation.nonlinear.max_tracking_error_m,
    )
}

/// The noise is the plant's and `--seed` picks its realization:
/// the same seed gives the same commissioning, another seed another
/// record; without noise the seed changes nothing (the record is
/// noise-free) and the actual torque is the command, delayed.
#[test]
fn the_seed_picks_the_noise_realization() {
    let noisy = MeasurementNoise {
        torque_nm: 5e-3,
        encoder_counts: 0.3,
    };
    let a = commission_sim_c(1, noisy);
    let b = commission_sim_c(1, noisy);
    let c = commission_sim_c(2, noisy);
    assert_eq!(a, b);
    assert_ne!(a.0, c.0, "another seed, the same excitation record");
    let z1 = commission_sim_c(1, MeasurementNoise::NONE);
    let z2 = commission_sim_c(2, MeasurementNoise::NONE);
    assert_eq!(z1, z2, "noise-free records depend on the seed");
    assert_ne!(z1.0, a.0);
}

/// The plant file's `[noise]` reaches the simulator; a configured noise
/// replaces it; zero noise measures the delayed command exactly.
#[test]
fn the_plant_file_carries_the_noise() {
    let text = toml::to_string(&rigs::builtin("sim-a", None).unwrap()).unwrap();
    assert!(text.contains("[noise]"), "{text}");
    let with = text.replace("encoder_counts = 0.0", "encoder_counts = 0.25");
    let plant: rigs::Plant = toml::from_str(&with).unwrap();
    assert_eq!(plant.noise().encoder_counts, 0.25);
    let axis = SimAxis::new(&plant, SimConfig::default()).unwrap();
    assert_eq!(axis.noise(), plant.noise());
    let mut quiet = SimAxis::new(
        &plant,
        SimConfig {
            noise: Some(MeasurementNoise::NONE),
            ..SimConfig::default()
        },
    )
    .unwrap();
    for _ in 0..100 {
        let m = quiet.step(0.5);
        assert_eq!(m.torque_actual_nm, quiet.applied_torque_nm());
    }
    let bad = text.replace("encoder_counts = 0.0", "encoder_counts = -1.0");
    let plant: rigs::Plant = toml::from_str(&bad).unwrap();
    assert!(plant.validate().is_err());
    assert!(SimAxis::new(&plant, SimConfig::default()).is_err());
}

/// Plant #155 (20.6 kg on a 54 deg slope, held with 2.1 of 3.1 N m) ended
/// "during friction runs: safety stop: following error 50.00 mm": the runs
/// accelerated at 10 m/s^2, which needs 2.7 N m more than the axis has left
/// after holding its load. The runs now accelerate with what the torque
/// budget allows (1.4 m/s^2 here).
#[test]
fn the_friction_runs_accelerate_within_the_torque_left() {
    let o = plant(155);
    assert!(
        o.kind != OutcomeKind::Failed,
        "the commissioning must end with a controller: {}",
        o.message
    );
    assert!(!o.travel_violation, "{}", o.travel_excess_m);
}

/// Plant #248 (18.0 kg, belt x0.57) ended "during validation moves: safety
/// stop: following error 50.00 mm": its honest (slow) design, a 1.3 Hz
/// position loop, trails the Table A.8 move by about 50 mm without
/// feedforward, the comparison variant the thesis' chapter 5 runs first.
/// The following-error limit now guards only the delivered controller's
/// move (nonlinear feedforward); the comparison variants run to the end.
#[test]
fn a_slow_loop_s_comparison_moves_do_not_stop_the_commissioning() {
    // the comparison moves run only on request (issue 31)
    let cfg = CommissioningConfig {
        compare_feedforward: true,
        ..CommissioningConfig::default()
    };
    let o = run_plant(12, 248, &Ranges::default(), &cfg).unwrap();
    assert!(
        o.kind != OutcomeKind::Failed,
        "the commissioning must end with a controller: {}",
        o.message
    );
    assert!(!o.travel_violation, "{}", o.travel_excess_m);
}
