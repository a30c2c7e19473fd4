//! The full commissioning through ethercrab against the virtual
//! drive in-process, at 1 kHz and 4 kHz bus cycles. Reference values as for
//! the direct simulation (crates/beltune/tests/commission.rs): the
//! simulator's own linearization at the identification position (truth), the
//! thesis' chapter-5 limits on the cart.

use beltune::commission::NoProgress;
use beltune::commission::{commission, Commissioning, CommissioningConfig, DataSheet};
use beltune::model::rigs::{self, Plant};
use beltune::sim::SimConfig;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive};
use beltune_ethercat::master::inprocess::InProcess;
use beltune_ethercat::master::{EthercatAxis, MasterConfig, Storage};

/// Issue 6/14: identified resonance and antiresonance within 2 % of the truth.
const FREQUENCY_TOLERANCE: f64 = 0.02;
/// Thesis chapter 5: maximum cart tracking error with nonlinear feedforward.
const MAX_TRACKING_ERROR_M: f64 = 1e-3;
/// Thesis chapter 5: static positioning error.
const STATIC_ERROR_M: f64 = 100e-6;

const START_M: f64 = 0.05;

fn run(cycle_s: f64) -> (Plant, Commissioning) {
    let plant = rigs::builtin("egc70", None).unwrap();
    let drive = VirtualDrive::new(
        &plant,
        DriveConfig {
            cycle_s,
            sim: SimConfig {
                seed: 1,
                initial_cart_position_m: Some(START_M),
                ..SimConfig::default()
            },
            ..DriveConfig::default()
        },
    )
    .unwrap();
    let storage = Storage::new();
    let mut axis = EthercatAxis::open(
        &storage,
        MasterConfig {
            cycle_s,
            use_dc: true,
            ..MasterConfig::default()
        },
        |tx, rx| Ok(InProcess::new(tx, rx, drive)),
    )
    .unwrap_or_else(|e| panic!("open: {e}"));
    let ds = DataSheet::for_plant(&plant, START_M, None);
    let run = commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("commissioning at {} us failed: {e}", cycle_s * 1e6));
    (plant, run)
}

fn check(cycle_s: f64) {
    let (plant, run) = run(cycle_s);
    let truth = plant.linearize(run.identification_position_m).unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    let nl = &run.validation.nonlinear;
    eprintln!(
        "{} us: f_r {:.2} (truth {:.2}), f_z {:.2} (truth {:.2}), max error {:.3} mm, static {:.1} um, busy {:.1} s",
        cycle_s * 1e6,
        run.identified.f_r_hz,
        truth.f_r_hz(),
        run.identified.f_z_hz,
        truth.f_z_hz(),
        nl.max_tracking_error_m * 1e3,
        nl.static_error_m * 1e6,
        run.experiment_time_s
    );
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

/// At 1 kHz the cart met the thesis' 1 mm only once the record
/// paired each measurement with the desired position of its own instant
/// (`procedure::motion::track`; before: 1.97 mm).
#[test]
fn commissioning_through_ethercrab_at_1_khz_meets_the_thesis_limits() {
    check(1e-3);
}

#[test]
fn commissioning_through_ethercrab_at_2_khz_meets_the_thesis_limits() {
    check(500e-6);
}

#[test]
fn commissioning_through_ethercrab_at_4_khz_meets_the_thesis_limits() {
    check(250e-6);
}
