//! The virtual drive's object dictionary: the one source of what the drive
//! offers. The CoE SDO server and SDO information serve it
//! ([`crate::od::Dictionary`]), the SII EEPROM's sync-manager and PDO
//! categories are built from it ([`sii_content`]), and so is the ESI file
//! ([`crate::esi`]); a test checks that the three agree.
//!
//! CiA 301 communication objects (device type, error register, name,
//! identity, PDO mapping and assignment, sync manager types and
//! synchronisation 0x1C32/0x1C33 with every ETG.1020 entry up to the
//! delay time: SDO information is read sub-index by sub-index), CiA 402 (ETG.6010) drive objects of
//! cyclic synchronous torque mode, and the manufacturer object 0x2110 (the
//! load-side encoder's resolution). Free PDO mapping: every entry marked
//! [`Pdo::Rx`] or [`Pdo::Tx`] may be mapped, in any order.

use crate::cia402;
use crate::esc::sdo_info::{OBJECT_CODE_ARRAY, OBJECT_CODE_RECORD};
use crate::esc::sii::{Identity, SiiContent, SiiPdo, SiiSyncManager};
use crate::loops;
use crate::od::{data_type as dt, Access, Dictionary, Pdo};
use crate::pdo::{self, MappingEntry};
use crate::scaling::{self, Scaling};

/// Identity of the virtual drive (vendor ID 0: not a registered vendor).
pub const IDENTITY: Identity = Identity {
    vendor_id: 0x0000_0000,
    product_code: 0x0042_0402,
    revision: 0x0001_0000,
    serial: 0x0000_0001,
};
/// Device name in the SII, the ESI and 0x1008.
pub const NAME: &str = "beltune virtual servo";
/// Error register (CiA 301, UNSIGNED8): bit 0 generic error, bit 4 communication.
pub const ERROR_REGISTER: u16 = 0x1001;
/// Torque offset (CiA 402, INTEGER16, per mille of the rated torque), added
/// to the target torque in CST.
pub const TORQUE_OFFSET: u16 = 0x60B2;
/// Target position (CiA 402, INTEGER32, increments): CSP's setpoint.
pub const TARGET_POSITION: u16 = 0x607A;
/// Velocity offset (CiA 402, INTEGER32, increments/s): CSP's velocity setpoint.
pub const VELOCITY_OFFSET: u16 = 0x60B1;
/// Following error actual value (CiA 402, INTEGER32, increments).
pub const FOLLOWING_ERROR: u16 = 0x60F4;
/// Device type 0x1000: CiA 402 (402 = 0x0192), servo drive (0x0002 in the
/// high word).
pub const DEVICE_TYPE: u32 = 0x0002_0192;

/// Physical start address of SM0 (mailbox master to drive).
pub const SM0_START: u16 = 0x1000;
/// Physical start address of SM1 (mailbox drive to master).
pub const SM1_START: u16 = 0x1080;
/// Physical start address of SM2 (outputs).
pub const SM2_START: u16 = 0x1100;
/// Physical start address of SM3 (inputs).
pub const SM3_START: u16 = 0x1180;
/// SM control bytes (ETG.1000.4 table 58): mailbox write with interrupt,
/// mailbox read, buffered write with watchdog, buffered read.
pub const SM_CONTROL: [u8; 4] = [0x26, 0x22, 0x64, 0x20];

/// What the dictionary's values depend on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectValues {
    /// The drive's scaling objects.
    pub scaling: Scaling,
    /// The drive's cycle, ns.
    pub cycle_ns: u32,
    /// Load-side encoder resolution, nm per increment.
    pub load_nm_per_inc: u32,
}

/// The outputs mapped by default (RxPDO 0x1600): controlword, mode, target torque.
pub fn default_rx() -> Vec<MappingEntry> {
    pdo::OUTPUTS.to_vec()
}

/// The inputs mapped by default (TxPDO 0x1A00): the axis' inputs with the load position.
pub fn default_tx() -> Vec<MappingEntry> {
    let mut v = pdo::INPUTS.to_vec();
    v.push(pdo::LOAD_POSITION);
    v
}

/// The drive's object dictionary with its power-up values.
pub fn dictionary(v: &ObjectValues) -> Dictionary {
    use Access::*;
    let mut od = Dictionary::new();
    let u8v = |x: u8| vec![x];
    let u16v = |x: u16| x.to_le_bytes().to_vec();
    let u32v = |x: u32| x.to_le_bytes().to_vec();
    let s = &v.scaling;
    // ---- CiA 301 ----
    od.var(
        0x1000,
        "Device type",
        dt::UNSIGNED32,
        Ro,
        Pdo::No,
        u32v(DEVICE_TYPE),
    );
    od.var(
        ERROR_REGISTER,
        "Error register",
        dt::UNSIGNED8,
        Ro,
        Pdo::Tx,
        u8v(0),
    );
    od.var(
        0x1008,
        "Manufacturer device name",
        dt::VISIBLE_STRING,
        Ro,
        Pdo::No,
        NAME.as_bytes().to_vec(),
    );
    od.object(0x1018, "Identity", OBJECT_CODE_RECORD);
    od.entry(
        0x1018,
        0,
        "Number of entries",
        dt::UNSIGNED8,
        Ro,
        Pdo::No,
        u8v(4),
    );
    for (sub, name, x) in [
        (1, "Vendor ID", IDENTITY.vendor_id),
        (2, "Product code", IDENTITY.product_code),
        (3, "Revision", IDENTITY.revision),
        (4, "Serial number", IDENTITY.serial),
    ] {
        od.entry(0x1018, sub, name, dt::UNSIGNED32, Ro, Pdo::No, u32v(x));
    }
    for (index, name, entries) in [
        (pdo::RX_PDO, "RxPDO 1 mapping", default_rx()),
        (pdo::TX_PDO, "TxPDO 1 mapping", default_tx()),
    ] {
        od.object(index, name, OBJECT_CODE_RECORD);
        let n = entries.len() as u8;
        od.entry(
            index,
            0,
            "Number of entries",
            dt::UNSIGNED8,
            RwPreOp,
            Pdo::No,
            u8v(n),
        );
        for (k, e) in entries.iter().enumerate() {
            let sub = k as u8 + 1;
            let name = format!("SubIndex {sub:03}");
            od.entry(
                index,
                sub,
                &name,
                dt::UNSIGNED32,
                RwPreOp,
                Pdo::No,
                u32v(e.to_u32()),
            );
        }
    }
    od.object(0x1C00, "Sync manager type", OBJECT_CODE_ARRAY);
    od.entry(
        0x1C00,
        0,
        "Number of entries",
        dt::UNSIGNED8,
        Ro,
        Pdo::No,
        u8v(4),
    );
    for (k, t) in [1u8, 2, 3, 4].iter().enumerate() {
        let sub = k as u8 + 1;
        let name = format!("SubIndex {sub:03}");
        od.entry(0x1C00, sub, &name, dt::UNSIGNED8, Ro, Pdo::No, u8v(*t));
    }
    for (index, name, pdo_index) in [
        (pdo::SM2_ASSIGN, "RxPDO assign", pdo::RX_PDO),
        (pdo::SM3_ASSIGN, "TxPDO assign", pdo::TX_PDO),
    ] {
        od.object(index, name, OBJECT_CODE_ARRAY);
        od.entry(
            index,
            0,
            "Number of entries",
            dt::UNSIGNED8,
            RwPreOp,
            Pdo::No,
            u8v(1),
        );
        od.entry(
            index,
            1,
            "SubIndex 001",
            dt::UNSIGNED16,
            RwPreOp,
            Pdo::No,
            u16v(pdo_index),
        );
    }
    for (index, name) in [
        (0x1C32u16, "SM output parameter"),
        (0x1C33, "SM input parameter"),
    ] {
        od.object(index, name, OBJECT_CODE_RECORD);
        od.entry(
            index,
            0,
            "Number of entries",
            dt::UNSIGNED8,
            Ro,
            Pdo::No,
            u8v(9),
        );
        // ETG.1020: sync type (1 SM-synchronous, 2 DC SYNC0), cycle time,
        // shift time, supported sync types (free run, SM, DC SYNC0), minimum
        // cycle time, calc and copy time, minimum delay, get cycle time, delay
        let u32e = |x: u32| (dt::UNSIGNED32, x.to_le_bytes().to_vec());
        let u16e = |x: u16| (dt::UNSIGNED16, x.to_le_bytes().to_vec());
        for (sub, name, (ty, value)) in [
            (2u8, "Cycle time", u32e(v.cycle_ns)),
            (3, "Shift time", u32e(0)),
            (4, "Sync modes supported", u16e(0x0007)),
            (5, "Minimum cycle time", u32e(v.cycle_ns)),
            (6, "Calc and copy time", u32e(v.cycle_ns / 10)),
            (7, "Minimum delay time", u32e(0)),
            (8, "Get cycle time", u16e(0)),
            (9, "Delay time", u32e(0)),
        ] {
            od.entry(index, sub, name, ty, Ro, Pdo::No, value);
        }
        od.entry(
            index,
            1,
            "Sync mode",
            dt::UNSIGNED16,
            RwPreOp,
            Pdo::No,
            u16v(1),
        );
    }
    // ---- manufacturer ----
    od.var(
        scaling::LOAD_ENCODER_RESOLUTION,
        "Load encoder resolution [nm/inc]",
        dt::UNSIGNED32,
        Ro,
        Pdo::No,
        u32v(v.load_nm_per_inc),
    );
    // ---- CiA 402 ----
    od.var(
        cia402::ERROR_CODE,
        "Error code",
        dt::UNSIGNED16,
        Ro,
        Pdo::Tx,
        u16v(0),
    );
    od.var(
        cia402::CONTROLWORD,
        "Controlword",
        dt::UNSIGNED16,
        Rw,
        Pdo::Rx,
        u16v(0),
    );
    od.var(
        cia402::STATUSWORD,
        "Statusword",
        dt::UNSIGNED16,
        Ro,
        Pdo::Tx,
        u16v(0),
    );
    od.var(
        0x605A,
        "Quick stop option code",
        dt::INTEGER16,
        Rw,
        Pdo::No,
        u16v(2),
    );
    let mode = cia402::MODES_OF_OPERATION;
    od.var(
        mode,
        "Modes of operation",
        dt::INTEGER8,
        Rw,
        Pdo::Rx,
        u8v(0),
    );
    let display = cia402::MODES_OF_OPERATION_DISPLAY;
    od.var(
        display,
        "Modes of operation display",
        dt::INTEGER8,
        Ro,
        Pdo::Tx,
        u8v(0),
    );
    let position = pdo::POSITION_ACTUAL;
    od.var(
        position,
        "Position actual value",
        dt::INTEGER32,
        Ro,
        Pdo::Tx,
        u32v(0),
    );
    let velocity = pdo::VELOCITY_ACTUAL;
    od.var(
        velocity,
        "Velocity actual value",
        dt::INTEGER32,
        Ro,
        Pdo::Tx,
        u32v(0),
    );
    let target = pdo::TARGET_TORQUE;
    od.var(target, "Target torque", dt::INTEGER16, Rw, Pdo::Rx, u16v(0));
    od.var(
        scaling::MAX_TORQUE,
        "Max torque",
        dt::UNSIGNED16,
        Ro,
        Pdo::No,
        u16v(s.max_torque_permille),
    );
    let rated = (s.rated_torque_nm * 1e3).round() as u32;
    let rated_index = scaling::RATED_TORQUE;
    od.var(
        rated_index,
        "Motor rated torque",
        dt::UNSIGNED32,
        Ro,
        Pdo::No,
        u32v(rated),
    );
    let torque = pdo::TORQUE_ACTUAL;
    od.var(
        torque,
        "Torque actual value",
        dt::INTEGER16,
        Ro,
        Pdo::Tx,
        u16v(0),
    );
    let resolution = scaling::ENCODER_RESOLUTION;
    od.object(resolution, "Position encoder resolution", OBJECT_CODE_ARRAY);
    od.entry(
        resolution,
        0,
        "Number of entries",
        dt::UNSIGNED8,
        Ro,
        Pdo::No,
        u8v(2),
    );
    let inc = u32v(s.encoder_increments);
    od.entry(
        resolution,
        1,
        "Encoder increments",
        dt::UNSIGNED32,
        Ro,
        Pdo::No,
        inc,
    );
    let revs = u32v(s.motor_revolutions);
    od.entry(
        resolution,
        2,
        "Motor revolutions",
        dt::UNSIGNED32,
        Ro,
        Pdo::No,
        revs,
    );
    od.var(
        TORQUE_OFFSET,
        "Torque offset",
        dt::INTEGER16,
        Rw,
        Pdo::Rx,
        u16v(0),
    );
    // interpolation time: cycle in units of 10^-6 s when whole, else 10^-7 s
    let (value, exp) = if v.cycle_ns % 1000 == 0 && v.cycle_ns / 1000 <= 255 {
        ((v.cycle_ns / 1000) as u8, -6i8)
    } else {
        ((v.cycle_ns / 100).min(255) as u8, -7i8)
    };
    let interp = scaling::INTERPOLATION_TIME;
    od.object(interp, "Interpolation time period", OBJECT_CODE_RECORD);
    od.entry(
        interp,
        0,
        "Number of entries",
        dt::UNSIGNED8,
        Ro,
        Pdo::No,
        u8v(2),
    );
    od.entry(
        interp,
        1,
        "Time period units",
        dt::UNSIGNED8,
        Ro,
        Pdo::No,
        u8v(value),
    );
    od.entry(
        interp,
        2,
        "Time period index",
        dt::INTEGER8,
        Ro,
        Pdo::No,
        vec![exp as u8],
    );
    let load = pdo::ADDITIONAL_POSITION_ACTUAL;
    od.object(load, "Additional position actual value", OBJECT_CODE_ARRAY);
    od.entry(
        load,
        0,
        "Number of entries",
        dt::UNSIGNED8,
        Ro,
        Pdo::No,
        u8v(1),
    );
    od.entry(
        load,
        1,
        "Load position",
        dt::INTEGER32,
        Ro,
        Pdo::Tx,
        u32v(0),
    );
    let modes = cia402::SUPPORTED_DRIVE_MODES;
    // CSP (bit 7, the drive's own loops) and CST (bit 9)
    let supported = (1 << 7) | (1 << 9);
    od.var(
        modes,
        "Supported drive modes",
        dt::UNSIGNED32,
        Ro,
        Pdo::No,
        u32v(supported),
    );
    let target = TARGET_POSITION;
    od.var(
        target,
        "Target position",
        dt::INTEGER32,
        Rw,
        Pdo::Rx,
        u32v(0),
    );
    let offset = VELOCITY_OFFSET;
    od.var(
        offset,
        "Velocity offset",
        dt::INTEGER32,
        Rw,
        Pdo::Rx,
        u32v(0),
    );
    let following = FOLLOWING_ERROR;
    od.var(
        following,
        "Following error actual value",
        dt::INTEGER32,
        Ro,
        Pdo::Tx,
        u32v(0),
    );
    loop_objects(&mut od);
    od
}

/// The manufacturer objects of the drive's own loops ([`crate::loops`]):
/// REAL32 parameters and UNSIGNED8 bit sets, writable in any state (the
/// drive builds its controller from them when it enters CSP).
fn loop_objects(od: &mut Dictionary) {
    use Access::*;
    for (index, name, code) in [
        (loops::POSITION_LOOP, "Position loop", OBJECT_CODE_RECORD),
        (loops::VELOCITY_LOOP, "Velocity loop", OBJECT_CODE_RECORD),
        (loops::PREFILTER, "Prefilter", OBJECT_CODE_ARRAY),
        (loops::FEEDFORWARD, "Feedforward", OBJECT_CODE_RECORD),
        (loops::OPTIONS, "Loop options", OBJECT_CODE_RECORD),
    ] {
        od.object(index, name, code);
    }
    let mut highest = std::collections::BTreeMap::<u16, u8>::new();
    for p in &loops::PARAMETERS {
        let zero = 0f32.to_le_bytes().to_vec();
        od.entry(p.index, p.sub, p.name, dt::REAL32, Rw, Pdo::No, zero);
        let n = highest.entry(p.index).or_default();
        *n = (*n).max(p.sub);
    }
    for (index, sub, name) in [
        (
            loops::FEEDFORWARD,
            loops::TERMS_SUB,
            "Terms (bits: inertia, viscous, Coulomb)",
        ),
        (
            loops::OPTIONS,
            loops::OPTIONS_SUB,
            "Options (bits: filtered desired velocity, preview, conditional integration)",
        ),
        (
            loops::OPTIONS,
            loops::PREVIEW_SUB,
            "Feedforward preview [cycles]",
        ),
    ] {
        od.entry(index, sub, name, dt::UNSIGNED8, Rw, Pdo::No, vec![0]);
        let n = highest.entry(index).or_default();
        *n = (*n).max(sub);
    }
    for (index, n) in highest {
        od.entry(
            index,
            0,
            "Number of entries",
            dt::UNSIGNED8,
            Ro,
            Pdo::No,
            vec![n],
        );
    }
}

/// The SII content of the drive with mailboxes of `mailbox` bytes: sync
/// managers, FMMUs and the default PDOs as the dictionary maps them.
pub fn sii_content(od: &Dictionary, mailbox: u16) -> SiiContent {
    let pdo = |index: u16, sm: u8| SiiPdo {
        index,
        sync_manager: sm,
        entries: od
            .entries_of(index)
            .filter(|(sub, _)| *sub > 0)
            .map(|(_, e)| {
                let raw = u32::from_le_bytes(e.data[..4].try_into().unwrap_or([0; 4]));
                let m = MappingEntry::from_u32(raw);
                let ty = od
                    .entry_def(m.index, m.sub_index)
                    .map_or(0, |d| d.data_type as u8);
                (m.index, m.sub_index, ty, m.bits)
            })
            .collect(),
    };
    let sm = |n: usize, start: u16, len: u16| SiiSyncManager {
        start,
        len,
        control: SM_CONTROL[n],
        ty: n as u8 + 1,
    };
    SiiContent {
        identity: IDENTITY,
        name: NAME.into(),
        mailbox: (SM0_START, mailbox, SM1_START, mailbox),
        sync_managers: vec![
            sm(0, SM0_START, mailbox),
            sm(1, SM1_START, mailbox),
            sm(2, SM2_START, 0),
            sm(3, SM3_START, 0),
        ],
        fmmus: vec![1, 2, 3, 0],
        rx_pdos: vec![pdo(pdo::RX_PDO, 2)],
        tx_pdos: vec![pdo(pdo::TX_PDO, 3)],
    }
}
