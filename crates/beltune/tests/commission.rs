//! The one-command self-commissioning on the simulated EGC-70 axis.
//!
//! Reference values: thesis chapter 5 (0 -> 500 mm move with nonlinear
//! feedforward: dynamic error below 1 mm, static error below 100 um) and the
//! simulator's own linearization at the identification position (truth).

use beltune::axis::Axis;
use beltune::commission::NoProgress;
use beltune::commission::{
    commission, commission_simulated, Commissioning, CommissioningConfig, DataSheet,
};
use beltune::model::rigs::{self, Plant};
use beltune::sim::{SimAxis, SimConfig};
use beltune::Error;

/// Identified resonance and antiresonance within 2 % of the truth.
const FREQUENCY_TOLERANCE: f64 = 0.02;
/// Thesis chapter 5: maximum cart tracking error with nonlinear feedforward.
const MAX_TRACKING_ERROR_M: f64 = 1e-3;
/// Thesis chapter 5: static positioning error.
const STATIC_ERROR_M: f64 = 100e-6;
/// The axis busy at most 15 s (issue 31; measured 13.5 s). It was 26.0 s:
/// the thesis' FRF alone takes about 16 s, and the two comparison moves
/// (no and linear feedforward), neither judged nor delivered, took 7-8 s;
/// they now run only on request. `tests/axis_time.rs` budgets each stage.
const EXPERIMENT_TIME_GUARD_S: f64 = 15.0;

fn run(payload_kg: Option<f64>, tilt_deg: Option<f64>) -> (Plant, Commissioning) {
    run_with(payload_kg, tilt_deg, &CommissioningConfig::default())
}

fn run_with(
    payload_kg: Option<f64>,
    tilt_deg: Option<f64>,
    cfg: &CommissioningConfig,
) -> (Plant, Commissioning) {
    let mut plant = rigs::builtin("egc70", payload_kg).unwrap();
    if let (Some(t), Plant::Physical(p)) = (tilt_deg, &mut plant) {
        p.tilt_rad = t.to_radians();
    }
    let run = commission_simulated(&plant, SimConfig::default(), None, cfg, &mut NoProgress)
        .unwrap_or_else(|e| panic!("commissioning failed: {e}"));
    (plant, run)
}

fn assert_validation_meets_thesis(run: &Commissioning) {
    let nl = &run.validation.nonlinear;
    assert!(
        nl.max_tracking_error_m < MAX_TRACKING_ERROR_M,
        "max cart error {:.3} mm",
        nl.max_tracking_error_m * 1e3
    );
    assert!(
        nl.static_error_m < STATIC_ERROR_M,
        "static error {:.1} um",
        nl.static_error_m * 1e6
    );
}

#[test]
fn egc70_with_payload_identifies_within_2_percent_and_tracks_like_the_thesis() {
    let (plant, run) = run(None, None);
    let truth = plant.linearize(run.identification_position_m).unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(
        rel(run.identified.f_r_hz, truth.f_r_hz()) < FREQUENCY_TOLERANCE,
        "f_r {} vs {}",
        run.identified.f_r_hz,
        truth.f_r_hz()
    );
    assert!(
        rel(run.identified.f_z_hz, truth.f_z_hz()) < FREQUENCY_TOLERANCE,
        "f_z {} vs {}",
        run.identified.f_z_hz,
        truth.f_z_hz()
    );
    assert!((run.identified.dead_time_s - plant.dead_time_s()).abs() <= 1e-4 + 1e-12);
    assert_validation_meets_thesis(&run);
    // the comparison moves run only on request
    assert!(run.validation.none.is_none() && run.validation.linear.is_none());
    assert_eq!(run.moves.len(), 1);
    assert!(
        run.experiment_time_s < EXPERIMENT_TIME_GUARD_S,
        "{}",
        run.experiment_time_s
    );
    // The computation time is wall-clock time of a shared machine: it is
    // printed by `beltune commission` ("time:" line, about 0.3 s against 20 s
    // of axis time in a release build) and not asserted here.
    // the design met its own (nominal) conditions, and the margins the robust
    // rule guarantees over the identification's uncertainty
    let k = run.design.knobs;
    assert!((run.design.velocity_margins.phase_margin_deg - k.pm_velocity_deg).abs() < 0.01);
    assert!((run.design.position_margins.phase_margin_deg - k.pm_position_deg).abs() < 0.01);
    assert!(
        run.guaranteed.velocity_phase_margin_deg
            >= beltune::design::robust::GUARANTEED_PHASE_MARGIN_DEG,
        "{:?}",
        run.guaranteed
    );
}

/// Thesis chapter 5's comparison, on request (`--compare-feedforward`):
/// the same move without feedforward and with linear feedforward runs
/// first, and the errors order as in thesis chapter 5: nonlinear <
/// linear < none. The two extra moves and their returns cost axis time,
/// 7-8 s on egc70 before issue 31 (each move with its return to the start,
/// its final approach and the second recorded after it).
#[test]
fn comparison_moves_on_request_order_as_the_thesis() {
    let cfg = CommissioningConfig {
        compare_feedforward: true,
        ..CommissioningConfig::default()
    };
    let (_, run) = run_with(None, None, &cfg);
    assert_validation_meets_thesis(&run);
    let v = &run.validation;
    let (none, linear) = (v.none.as_ref().unwrap(), v.linear.as_ref().unwrap());
    assert!(
        v.nonlinear.max_tracking_error_m < linear.max_tracking_error_m
            && linear.max_tracking_error_m < none.max_tracking_error_m,
        "expected nonlinear < linear < none: {:?}",
        v
    );
    let variants: Vec<_> = run.moves.iter().map(|m| m.variant).collect();
    use beltune::commission::validation::FeedforwardVariant as F;
    assert_eq!(variants, [F::None, F::Linear, F::Nonlinear]);
    let validation_s = run
        .stage_axis_times
        .iter()
        .find(|t| t.stage == "validation")
        .unwrap()
        .axis_time_s;
    // the stage's axis time holds the three recorded moves (and their returns)
    let recorded_s: f64 = run
        .moves
        .iter()
        .map(|m| m.result.record.time_s.last().copied().unwrap_or(0.0))
        .sum();
    assert!(
        validation_s > recorded_s,
        "{validation_s} s, moves {recorded_s} s"
    );
}

#[test]
fn egc70_without_payload_meets_the_same_limits() {
    let (_, run) = run(Some(0.0), None);
    assert_validation_meets_thesis(&run);
}

#[test]
fn egc70_tilted_30_degrees_meets_the_same_limits() {
    let (plant, run) = run(None, Some(30.0));
    // holding torque = i_t m g sin(alpha) within the friction (Coulomb) band
    let Plant::Physical(p) = &plant else {
        unreachable!()
    };
    let expected = p.i_t() * p.m_c() * 9.81 * 30f64.to_radians().sin();
    assert!(
        (run.holding_torque_nm - expected).abs() < plant.friction_totals().coulomb_nm,
        "holding {} vs {}",
        run.holding_torque_nm,
        expected
    );
    assert_validation_meets_thesis(&run);
}

#[test]
fn egc70_vertical_meets_the_same_limits() {
    let (_, run) = run(None, Some(90.0));
    assert_validation_meets_thesis(&run);
}

/// A light cart excited with a generous fixed amplitude in a narrow window:
/// the commissioning must stop it inside the window with a clear message.
/// The excitation's guard band ends the PRBS before the supervisor
/// has to, and refuses the window as too short for the drift.
#[test]
fn excitation_that_would_leave_the_travel_window_is_stopped_inside_it() {
    let plant = rigs::builtin("sim-b", None).unwrap();
    let start = 0.05;
    let mut axis = SimAxis::new(
        &plant,
        SimConfig {
            initial_cart_position_m: Some(start),
            ..SimConfig::default()
        },
    )
    .unwrap();
    let window = (0.0, 0.12);
    let ds = DataSheet::for_plant(&plant, start, Some(window));
    let mut cfg = CommissioningConfig::default();
    cfg.excitation.fixed_amplitude_nm = Some(1.5);
    // a slow PRBS (long clock period, as the thesis' PRBS^7_128 and slower)
    // moves the cart in long strokes
    cfg.excitation.prbs_order = 7;
    cfg.excitation.clock_period_s = 512.0 * 100e-6;
    // as given (`--prbs-clock-ms`), not shortened for sim-b's resonance
    cfg.excitation.band_from_data_sheet = false;
    let err = commission(&mut axis, &ds, &cfg, &mut NoProgress).unwrap_err();
    match &err {
        Error::SafetyStop { reason } => assert!(reason.contains("travel window"), "{reason}"),
        Error::Infeasible { reason } => {
            assert!(reason.contains("does not fit its drift"), "{reason}")
        }
        _ => panic!("expected a stop or a refusal for the drift, got {err}"),
    }
    let x = axis.cart_position_m();
    assert!(x > window.0 && x < window.1, "cart at {x} m");
    assert!(
        axis.cart_velocity_m_s().abs() < 1e-2,
        "not at rest: {} m/s",
        axis.cart_velocity_m_s()
    );
}

/// Motor on top (negative tilt): gravity pulls the cart towards the end pulley,
/// next to which the identification runs; the holding torque must be accurate
/// enough that the open-loop excitation does not drift into the window's end.
#[test]
fn egc70_vertical_motor_on_top_meets_the_same_limits() {
    let (_, run) = run(None, Some(-90.0));
    assert_validation_meets_thesis(&run);
}

/// An axis that fails after `fail_after` good exchanges (a drive fault, as a
/// fieldbus axis reports it), and records whether it was quick-stopped.
struct FailingAxis {
    inner: SimAxis,
    fail_after: u64,
    exchanges: u64,
    quick_stopped: bool,
}

impl beltune::axis::Axis for FailingAxis {
    fn info(&self) -> beltune::axis::AxisInfo {
        self.inner.info()
    }

    fn exchange(
        &mut self,
        torque_command_nm: f64,
    ) -> Result<beltune::axis::Measurement, beltune::axis::AxisError> {
        assert!(!self.quick_stopped, "exchange after the quick stop");
        self.exchanges += 1;
        if self.exchanges > self.fail_after {
            return Err(beltune::axis::AxisError::DriveFault { error_code: 0x7500 });
        }
        Ok(self.inner.step(torque_command_nm))
    }

    fn quick_stop(&mut self) -> Result<(), beltune::axis::AxisError> {
        self.quick_stopped = true;
        Ok(())
    }
}

/// The fallible axis seam: a drive fault in the middle of the
/// commissioning (here during the excitation-amplitude bursts, after 4 s of
/// the axis' time) ends it at once with the drive's code, after exactly one
/// quick stop and no further exchange.
#[test]
fn a_drive_fault_ends_the_commissioning_with_a_quick_stop() {
    let plant = rigs::builtin("egc70", None).unwrap();
    let start = 0.05;
    let inner = SimAxis::new(
        &plant,
        SimConfig {
            seed: 1,
            initial_cart_position_m: Some(start),
            ..SimConfig::default()
        },
    )
    .unwrap();
    let fail_after = (4.0 / inner.info().ts_s) as u64;
    let mut axis = FailingAxis {
        inner,
        fail_after,
        exchanges: 0,
        quick_stopped: false,
    };
    let ds = DataSheet::for_plant(&plant, start, None);
    let err = commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            Error::Axis {
                error: beltune::axis::AxisError::DriveFault { error_code: 0x7500 },
                quick_stop: None
            }
        ),
        "{err}"
    );
    assert!(axis.quick_stopped);
    assert_eq!(axis.exchanges, fail_after + 1);
    assert_eq!(err.to_string(), "axis: the drive reports fault 0x7500");
}

/// The procedure's settings are in seconds, so a slower cycle (a
/// PC fieldbus master at 1 kHz) uses the same configuration: the PRBS clock
/// of 1.6 ms is 16 samples at 10 kHz and 2 at 1 kHz (rounded), the bursts
/// and windows scale alike.
#[test]
fn excitation_settings_derive_their_sample_counts_from_the_cycle_time() {
    let ex = beltune::commission::ExcitationConfig::default();
    assert_eq!(ex.clock_samples(100e-6), 16);
    assert_eq!(ex.clock_samples(1e-3), 2);
    assert_eq!(ex.clock_samples(250e-6), 6);
    assert_eq!(ex.burst_samples(100e-6), 1500);
    assert_eq!(ex.burst_samples(1e-3), 150);
    assert_eq!(ex.moving_window_samples(100e-6), 20);
    assert_eq!(ex.moving_window_samples(1e-3), 2);
    // Degenerate values never give zero samples.
    let odd = beltune::commission::ExcitationConfig {
        clock_period_s: 0.0,
        burst_s: f64::NAN,
        ..ex
    };
    assert_eq!(odd.clock_samples(1e-3), 1);
    assert_eq!(odd.burst_samples(1e-3), 1);
}
