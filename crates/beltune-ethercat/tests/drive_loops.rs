//! The controller inside the drive, in-process: after the commissioning
//! through ethercrab, the delivered cascade is written into the virtual
//! drive's loop objects by SDO and read back, the drive switches to CSP and
//! closes its own position and velocity loops, and the validation move run
//! that way meets the thesis' chapter-5 limits (< 1 mm, < 100 um on the
//! cart), judged by the one verdict.

use beltune::commission::NoProgress;
use beltune::commission::{commission, CommissioningConfig, DataSheet};
use beltune::model::rigs;
use beltune::sim::SimConfig;
use beltune_ethercat::cia402::MODE_CSP;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive};
use beltune_ethercat::loops;
use beltune_ethercat::master::drive_loops::validate_with_drive_loops;
use beltune_ethercat::master::inprocess::InProcess;
use beltune_ethercat::master::{EthercatAxis, MasterConfig, Storage};
use beltune_ethercat::profile::DriveProfile;

/// Thesis chapter 5: maximum cart tracking error with nonlinear feedforward.
const MAX_TRACKING_ERROR_M: f64 = 1e-3;
/// Thesis chapter 5: static positioning error.
const STATIC_ERROR_M: f64 = 100e-6;
const START_M: f64 = 0.05;

#[test]
fn the_designed_controller_runs_in_the_drive_and_meets_the_thesis_limits() {
    let plant = rigs::builtin("egc70", None).unwrap();
    let drive = VirtualDrive::new(
        &plant,
        DriveConfig {
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
    let mut axis = EthercatAxis::open(&storage, MasterConfig::default(), |tx, rx| {
        Ok(InProcess::new(tx, rx, drive))
    })
    .unwrap_or_else(|e| panic!("open: {e}"));
    assert!(
        axis.identity().csp,
        "the drive offers CSP and its outputs are mapped"
    );
    let ds = DataSheet::for_plant(&plant, START_M, None);
    let cfg = CommissioningConfig::default();
    let run = commission(&mut axis, &ds, &cfg, &mut NoProgress).unwrap();
    let profile = DriveProfile::virtual_servo();
    let v = validate_with_drive_loops(&mut axis, &run, &cfg, &profile)
        .unwrap_or_else(|e| panic!("validation in the drive: {e}"));
    let host = &run.validation.nonlinear;
    eprintln!(
        "in the drive: {} parameters, preview {} cycles, max cart error {:.3} mm (host {:.3} mm), static {:.1} um (host {:.1} um), verdict {}",
        v.parameters_written,
        v.preview_cycles,
        v.summary.max_tracking_error_m * 1e3,
        host.max_tracking_error_m * 1e3,
        v.summary.static_error_m * 1e6,
        host.static_error_m * 1e6,
        v.verdict.text()
    );
    // every REAL32 parameter and the three bit sets
    assert_eq!(v.parameters_written, loops::PARAMETERS.len() + 3);
    let fw = &axis.transport().drive().firmware;
    assert_eq!(fw.mode_display(), MODE_CSP, "the drive closed its loops");
    // the drive's objects hold the design (as f32): K_PP
    let k_pp = f32::from_le_bytes(
        fw.objects()
            .get(loops::POSITION_LOOP, 1)
            .unwrap()
            .try_into()
            .unwrap(),
    );
    assert!(
        (f64::from(k_pp) - run.design.k_pp).abs() < 1e-5 * run.design.k_pp,
        "K_PP {k_pp} vs {}",
        run.design.k_pp
    );
    assert!(
        v.summary.max_tracking_error_m < MAX_TRACKING_ERROR_M,
        "max cart error {:.3} mm",
        v.summary.max_tracking_error_m * 1e3
    );
    assert!(
        v.summary.static_error_m < STATIC_ERROR_M,
        "static error {:.1} um",
        v.summary.static_error_m * 1e6
    );
    assert!(v.verdict.passed, "verdict: {}", v.verdict.text());
}
