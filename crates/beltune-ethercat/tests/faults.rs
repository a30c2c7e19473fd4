//! Faults injected in-process end safely with one line and no
//! result: a drive fault during the PRBS, lost frames for longer than the
//! allowed cycles, and a master that stops sending (the drive's SM watchdog
//! removes the torque).

use beltune::axis::AxisError;
use beltune::commission::Progress;
use beltune::commission::{commission, CommissioningConfig, DataSheet};
use beltune::model::rigs;
use beltune::sim::SimConfig;
use beltune::Error;
use beltune_ethercat::cia402::State;
use beltune_ethercat::drive::{DriveConfig, Faults, VirtualDrive, ERROR_WATCHDOG};
use beltune_ethercat::esc::{al_code, AlState};
use beltune_ethercat::master::inprocess::InProcess;
use beltune_ethercat::master::{EthercatAxis, MasterConfig, Storage};
use std::sync::atomic::Ordering;
use std::sync::Arc;

const START_M: f64 = 0.05;
/// CiA 402 error code injected: continuous over current (device internal).
const OVERCURRENT: u16 = 0x2310;

fn open(storage: &Storage) -> EthercatAxis<'_, InProcess<'_>> {
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
    EthercatAxis::open(storage, MasterConfig::default(), |tx, rx| {
        Ok(InProcess::new(tx, rx, drive))
    })
    .unwrap()
}

/// Injects a fault `after` samples into the PRBS.
struct InjectDuringPrbs {
    faults: Arc<Faults>,
    in_prbs: bool,
    samples: u64,
    after: u64,
    fault: fn(&Faults),
    injected: bool,
}

impl Progress for InjectDuringPrbs {
    fn stage_started(&mut self, name: &str, _total: u64) {
        self.in_prbs = name.starts_with("identification");
    }
    fn advance(&mut self, n: u64) {
        if self.in_prbs {
            self.samples += n;
            if self.samples >= self.after && !self.injected {
                (self.fault)(&self.faults);
                self.injected = true;
            }
        }
    }
    fn stage_finished(&mut self, _summary: &str) {}
}

fn commission_with(fault: fn(&Faults)) -> (Error, State, f64, u64) {
    let storage = Storage::new();
    let mut axis = open(&storage);
    let plant = rigs::builtin("egc70", None).unwrap();
    let ds = DataSheet::for_plant(&plant, START_M, None);
    let mut progress = InjectDuringPrbs {
        faults: axis.transport().drive().faults(),
        in_prbs: false,
        samples: 0,
        after: 300,
        fault,
        injected: false,
    };
    let r = commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut progress,
    );
    assert!(progress.injected, "the PRBS ran");
    let err = match r {
        Ok(_) => panic!("the commissioning must not produce a result after a fault"),
        Err(e) => e,
    };
    let fw = &axis.transport().drive().firmware;
    (
        err,
        fw.state(),
        fw.last_torque_nm(),
        axis.transport().frame_counts().1,
    )
}

#[test]
fn a_drive_fault_during_the_prbs_ends_with_one_line_and_no_torque() {
    let (err, state, torque, _) = commission_with(|f| {
        f.drive_fault
            .store(u32::from(OVERCURRENT), Ordering::Relaxed)
    });
    match &err {
        Error::Axis {
            error: AxisError::DriveFault { error_code },
            ..
        } => assert_eq!(*error_code, OVERCURRENT),
        e => panic!("unexpected error: {e}"),
    }
    let line = err.to_string();
    assert!(!line.contains('\n') && line.contains("0x2310"), "{line}");
    assert_eq!(state, State::Fault);
    assert_eq!(torque, 0.0);
}

#[test]
fn frames_lost_for_longer_than_allowed_end_in_a_quick_stop() {
    // MasterConfig::default() bridges 3 lost frames; 6 in a row are too many
    let (err, state, torque, dropped) =
        commission_with(|f| f.drop_frames.store(6, Ordering::Relaxed));
    match &err {
        Error::Axis {
            error: AxisError::Timeout { cycles },
            quick_stop: None,
        } => assert_eq!(*cycles, 4),
        e => panic!("unexpected error: {e}"),
    }
    assert!(!err.to_string().contains('\n'));
    assert!(dropped >= 4, "{dropped} frames dropped");
    // the frames came back for the quick stop: the drive braked and switched off
    assert_eq!(state, State::SwitchOnDisabled);
    assert_eq!(torque, 0.0);
}

#[test]
fn a_few_lost_frames_are_bridged() {
    let storage = Storage::new();
    let mut axis = open(&storage);
    let faults = axis.transport().drive().faults();
    faults.drop_frames.store(3, Ordering::Relaxed);
    for _ in 0..20 {
        axis.exchange(0.0)
            .expect("three lost frames are within the allowance");
    }
    assert_eq!(axis.transport().frame_counts().1, 3);
}

#[test]
fn a_master_that_stops_sending_loses_the_torque_to_the_drives_watchdog() {
    let storage = Storage::new();
    let mut axis = open(&storage);
    for _ in 0..100 {
        axis.exchange(0.3).unwrap();
    }
    assert!((axis.transport().drive().firmware.last_torque_nm() - 0.3).abs() < 2e-3);
    // 80 ms of silence: within the 100 ms watchdog the drive keeps the torque
    axis.pause_cycles(80);
    assert!(axis.transport().drive().firmware.last_torque_nm() > 0.29);
    // 150 ms: the watchdog expired, the torque is gone
    axis.pause_cycles(70);
    let d = axis.transport().drive();
    assert_eq!(d.firmware.last_torque_nm(), 0.0);
    assert_eq!(d.firmware.state(), State::Fault);
    assert_eq!(d.firmware.error_code(), ERROR_WATCHDOG);
    assert_eq!(
        (d.esc.al_state(), d.esc.al_status_code()),
        (AlState::SafeOp, al_code::SM_WATCHDOG)
    );
    // the master's next cycle reports it in one line
    let e = axis.exchange(0.3).unwrap_err();
    assert_eq!(
        e,
        AxisError::DriveFault {
            error_code: ERROR_WATCHDOG
        }
    );
    assert!(!e.to_string().contains('\n'));
    // and the cart coasts to rest under friction alone
    let v0 = axis
        .transport()
        .drive()
        .firmware
        .sim()
        .motor_velocity_rad_s()
        .abs();
    axis.pause_cycles(2000);
    let v1 = axis
        .transport()
        .drive()
        .firmware
        .sim()
        .motor_velocity_rad_s()
        .abs();
    assert!(v1 < 0.1 * v0.max(1e-3), "velocity {v0} -> {v1} rad/s");
}
