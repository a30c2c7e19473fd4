//! What a real master meets in a real drive, in-process: refusals reach the
//! master as SDO aborts, the objects behind the process data are current in
//! every state, the mode written by SDO works without 0x6060 in the RxPDO,
//! a watchdog fault is in the first inputs after it and in a CoE emergency,
//! a SYNC0 cycle other than the drive's is refused, and the master leaves
//! the bus in INIT with no error latched, after a good run and after a
//! watchdog fault.

use beltune::model::rigs;
use beltune_ethercat::cia402::State;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive, ERROR_WATCHDOG};
use beltune_ethercat::esc::coe::abort;
use beltune_ethercat::esc::{al_code, AlState, Application, SyncManager};
use beltune_ethercat::master::inprocess::InProcess;
use beltune_ethercat::master::{EthercatAxis, MasterConfig, Storage};

fn drive() -> VirtualDrive {
    let plant = rigs::builtin("egc70", None).unwrap();
    VirtualDrive::new(&plant, DriveConfig::default()).unwrap()
}

/// An expedited SDO download request (CiA 301: ccs 1, e = 1, s = 1, n = 4 - len).
fn download(index: u16, sub: u8, data: &[u8]) -> Vec<u8> {
    let mut r = 10u16.to_le_bytes().to_vec();
    r.extend_from_slice(&[0, 0, 0, 0x13, 0x00, 0x20]);
    r.push(0x23 | (((4 - data.len()) as u8) << 2));
    r.extend_from_slice(&index.to_le_bytes());
    r.push(sub);
    let mut d = data.to_vec();
    d.resize(4, 0);
    r.extend_from_slice(&d);
    r.resize(128, 0);
    r
}

/// An SDO upload request (ccs 2).
fn upload(index: u16, sub: u8) -> Vec<u8> {
    let mut r = 10u16.to_le_bytes().to_vec();
    r.extend_from_slice(&[0, 0, 0, 0x13, 0x00, 0x20, 0x40]);
    r.extend_from_slice(&index.to_le_bytes());
    r.push(sub);
    r.resize(128, 0);
    r
}

/// `Ok(data)` of an upload or download answer, `Err(abort code)` of an abort.
fn answer(a: &[u8]) -> Result<Vec<u8>, u32> {
    let service = u16::from_le_bytes([a[6], a[7]]) >> 12;
    if a[8] == 0x80 {
        // ETG.1000.6 5.6.2.7.1: an abort goes as an SDO request
        assert_eq!(service, 2, "abort transfer is an SDO request");
        return Err(u32::from_le_bytes(a[12..16].try_into().unwrap()));
    }
    assert_eq!(service, 3, "SDO response");
    let n = if a[8] & 0x02 != 0 {
        4 - usize::from((a[8] >> 2) & 3)
    } else {
        4
    };
    Ok(a[12..12 + n].to_vec())
}

fn sdo(d: &mut VirtualDrive, req: &[u8], state: AlState) -> Result<Vec<u8>, u32> {
    answer(&d.firmware.mailbox(req, state).expect("an answer"))
}

#[test]
fn refused_sdo_requests_reach_the_master_as_aborts_and_change_nothing() {
    let mut d = drive();
    let pre = AlState::PreOp;
    // CiA 301 table 22
    assert_eq!(
        sdo(&mut d, &download(0x6041, 0, &[0, 0]), pre),
        Err(abort::READ_ONLY)
    );
    assert_eq!(
        sdo(&mut d, &download(0x6060, 0, &[10, 0]), pre),
        Err(abort::LENGTH_TOO_HIGH)
    );
    assert_eq!(sdo(&mut d, &upload(0x5FFF, 0), pre), Err(abort::NO_OBJECT));
    assert_eq!(
        sdo(&mut d, &download(0x1C12, 0, &[2]), pre),
        Err(abort::VALUE_TOO_HIGH)
    );
    assert_eq!(sdo(&mut d, &download(0x1C12, 0, &[0]), pre), Ok(vec![0; 4]));
    assert_eq!(sdo(&mut d, &download(0x1600, 0, &[0]), pre), Ok(vec![0; 4]));
    assert_eq!(
        sdo(
            &mut d,
            &download(0x1600, 1, &0x1000_0020u32.to_le_bytes()),
            pre
        ),
        Err(abort::NOT_MAPPABLE)
    );
    // mapping only in PRE-OP
    assert_eq!(
        sdo(&mut d, &download(0x1600, 0, &[3]), AlState::Op),
        Err(abort::DEVICE_STATE)
    );
    assert_eq!(sdo(&mut d, &upload(0x6060, 0), pre), Ok(vec![0]));
    assert_eq!(
        sdo(&mut d, &upload(0x1600, 1), pre),
        Ok(0x6040_0010u32.to_le_bytes().to_vec())
    );
}

#[test]
fn the_statusword_and_the_position_are_current_before_any_cycle() {
    let mut d = drive();
    let sw = sdo(&mut d, &upload(0x6041, 0), AlState::PreOp).unwrap();
    // CiA 402: "switch on disabled" (0x0040 under 0x004F), remote (bit 9)
    assert_eq!(u16::from_le_bytes([sw[0], sw[1]]), 0x0240);
    let pos = sdo(&mut d, &upload(0x6064, 0), AlState::PreOp).unwrap();
    assert_eq!(
        i32::from_le_bytes(pos.try_into().unwrap()),
        DriveConfig::default().initial_position_inc
    );
}

fn sm(start: u16, len: u16) -> SyncManager {
    SyncManager {
        start,
        len,
        control: 0x64,
        enabled: true,
    }
}

#[test]
fn an_rxpdo_without_the_mode_runs_in_the_mode_written_by_sdo() {
    let mut d = drive();
    let pre = AlState::PreOp;
    for (i, s, v) in [
        (0x1C12u16, 0u8, vec![0u8]),
        (0x1600, 0, vec![0]),
        (0x1600, 1, 0x6040_0010u32.to_le_bytes().to_vec()),
        (0x1600, 2, 0x6071_0010u32.to_le_bytes().to_vec()),
        (0x1600, 0, vec![2]),
        (0x1C12, 0, vec![1]),
        (0x6060, 0, vec![10]),
    ] {
        assert!(
            sdo(&mut d, &download(i, s, &v), pre).is_ok(),
            "{i:#06x}:{s}"
        );
    }
    // outputs 4 bytes (0x6040, 0x6071), default inputs 19 bytes
    let sms = [
        sm(0x1000, 128),
        sm(0x1080, 128),
        sm(0x1100, 4),
        sm(0x1180, 19),
    ];
    assert_eq!(
        d.firmware.al_change(AlState::PreOp, AlState::SafeOp, &sms),
        Ok(())
    );
    assert_eq!(
        d.firmware.al_change(AlState::SafeOp, AlState::Op, &sms),
        Ok(())
    );
    let mut inputs = vec![0u8; 19];
    for (k, cw) in [0x06u16, 0x07, 0x0F, 0x0F].iter().enumerate() {
        let mut out = cw.to_le_bytes().to_vec();
        out.extend_from_slice(&100i16.to_le_bytes());
        d.firmware.cycle(k as u64, true, &out, &mut inputs);
    }
    assert_eq!(d.firmware.state(), State::OperationEnabled);
    // statusword: operation enabled; mode display 10 (CST)
    assert_eq!(u16::from_le_bytes([inputs[0], inputs[1]]) & 0x006F, 0x0027);
    assert_eq!(inputs[2], 10);
    assert!(d.firmware.last_torque_nm() > 0.0);
}

fn open(storage: &Storage, use_dc: bool) -> EthercatAxis<'_, InProcess<'_>> {
    let d = drive();
    EthercatAxis::open(
        storage,
        MasterConfig {
            use_dc,
            ..MasterConfig::default()
        },
        |tx, rx| Ok(InProcess::new(tx, rx, d)),
    )
    .unwrap_or_else(|e| panic!("open: {e}"))
}

#[test]
fn without_distributed_clocks_a_watchdog_fault_is_in_the_first_inputs_and_an_emergency() {
    let storage = Storage::new();
    let mut axis = open(&storage, false);
    assert!(!axis.identity().dc);
    for _ in 0..50 {
        axis.exchange(0.2).unwrap();
    }
    axis.pause_cycles(150);
    let d = axis.transport().drive();
    assert_eq!(d.esc.al_status_code(), al_code::SM_WATCHDOG);
    // the very first exchange after the silence sees the fault and its code
    assert_eq!(
        axis.exchange(0.0).unwrap_err(),
        beltune::axis::AxisError::DriveFault {
            error_code: ERROR_WATCHDOG
        }
    );
    // and the mailbox holds a CoE emergency (service 1) with 0x8130 and
    // the error register's generic and communication bits (CiA 301 7.2.7)
    let m = axis
        .transport()
        .drive()
        .esc
        .sm1_message()
        .expect("an emergency");
    assert_eq!(m[5] & 0x0F, 3, "CoE");
    assert_eq!(u16::from_le_bytes([m[6], m[7]]) >> 12, 1, "emergency");
    assert_eq!(u16::from_le_bytes([m[8], m[9]]), ERROR_WATCHDOG);
    assert_eq!(m[10], 0x11);
}

#[test]
fn a_sync0_cycle_other_than_the_drives_is_refused() {
    // the drive runs at 1 ms; a master at 2 ms configures SYNC0 = 2 ms
    let plant = rigs::builtin("egc70", None).unwrap();
    let d = VirtualDrive::new(&plant, DriveConfig::default()).unwrap();
    let storage = Storage::new();
    let r = EthercatAxis::open(
        &storage,
        MasterConfig {
            cycle_s: 2e-3,
            use_dc: true,
            ..MasterConfig::default()
        },
        |tx, rx| Ok(InProcess::new(tx, rx, d)),
    );
    let e = r.err().expect("refused");
    assert!(e.to_string().contains("SAFE-OP"), "{e}");
}

#[test]
fn the_master_leaves_the_bus_in_init_without_a_latched_error() {
    for dc in [true, false] {
        let storage = Storage::new();
        let mut axis = open(&storage, dc);
        for _ in 0..100 {
            axis.exchange(0.2).unwrap();
        }
        axis.quick_stop().unwrap();
        let down = axis.shut_down();
        let d = axis.transport().drive();
        assert!(down.reached);
        assert_eq!(
            (down.al_state, down.error, down.al_status_code),
            (1, false, 0)
        );
        assert_eq!((d.esc.al_state(), d.esc.al_error()), (AlState::Init, false));
        assert_eq!(d.firmware.state(), State::SwitchOnDisabled);
        // nothing left for the watchdog: a second later still INIT, no error
        axis.pause_cycles(1000);
        let d = axis.transport().drive();
        assert_eq!((d.esc.al_state(), d.esc.al_error()), (AlState::Init, false));
        assert_eq!(d.esc.stats().watchdog_expiries, 0);
    }
}

#[test]
fn after_a_watchdog_fault_the_master_still_leaves_init_and_no_error() {
    let storage = Storage::new();
    let mut axis = open(&storage, true);
    for _ in 0..20 {
        axis.exchange(0.2).unwrap();
    }
    axis.pause_cycles(200);
    assert!(axis.exchange(0.0).is_err());
    let _ = axis.quick_stop();
    let down = axis.shut_down();
    assert_eq!(
        (down.al_state, down.error, down.al_status_code),
        (1, false, 0)
    );
    let d = axis.transport().drive();
    assert_eq!((d.esc.al_state(), d.esc.al_error()), (AlState::Init, false));
}
