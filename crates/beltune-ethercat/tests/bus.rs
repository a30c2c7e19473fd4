//! The master (ethercrab) against the virtual drive in-process: start-up,
//! cyclic CST exchange, scaling, faults.

use beltune::model::rigs;
use beltune_ethercat::cia402::State;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive};
use beltune_ethercat::master::inprocess::InProcess;
use beltune_ethercat::master::{EthercatAxis, MasterConfig, Storage};

fn drive(cycle_s: f64) -> VirtualDrive {
    let plant = rigs::builtin("egc70", None).unwrap();
    VirtualDrive::new(
        &plant,
        DriveConfig {
            cycle_s,
            ..DriveConfig::default()
        },
    )
    .unwrap()
}

fn open(storage: &Storage, cycle_s: f64) -> EthercatAxis<'_, InProcess<'_>> {
    let d = drive(cycle_s);
    EthercatAxis::open(
        storage,
        MasterConfig {
            cycle_s,
            ..MasterConfig::default()
        },
        |tx, rx| Ok(InProcess::new(tx, rx, d)),
    )
    .unwrap_or_else(|e| panic!("open: {e}"))
}

#[test]
fn the_master_finds_configures_and_enables_the_virtual_drive() {
    let storage = Storage::new();
    let mut axis = open(&storage, 1e-3);
    let id = axis.identity().clone();
    assert_eq!(id.name, "beltune virtual servo");
    assert_eq!(id.product_code, 0x0042_0402);
    assert!(id.dc, "SYNC0 in use");
    let fw = &axis.transport().drive().firmware;
    assert_eq!(fw.state(), State::OperationEnabled);
    let c0 = fw.cycles();
    // a constant torque accelerates the motor
    let mut last = axis.last();
    for _ in 0..200 {
        last = axis.exchange(0.5).unwrap();
    }
    let fw = &axis.transport().drive().firmware;
    assert_eq!(fw.cycles() - c0, 200, "one drive cycle per exchange");
    assert!(
        (fw.last_torque_nm() - 0.5).abs() < 2e-3,
        "torque {}",
        fw.last_torque_nm()
    );
    assert!(last.motor_counts > 1000, "counts {}", last.motor_counts);
    println!("{last:?}");
}
