//! The virtual CiA 402 servo drive: the [`Esc`] emulator with a firmware that
//! runs the CiA 402 state machine in cyclic synchronous torque mode and, as
//! its power stage and mechanics, [`beltune::sim::SimAxis`] (egc70 by
//! default) with its current-loop dead time, stepped once per cycle.
//!
//! Cycle (at every SYNC0 event, or at every complete output write when the
//! master uses no distributed clocks): take the outputs of the last frame
//! (controlword, mode, target torque), run the state machine, apply the
//! torque for one cycle (target torque in "operation enabled" and CST; a
//! braking torque `-D omega` in "quick stop active"; none otherwise), and
//! latch the inputs for the next frame (statusword, mode display, position,
//! velocity, torque, error code, and the cart position from the load-side
//! encoder as 0x60E4:01). The measurement in a frame is therefore the one
//! latched at the cycle before: one bus cycle of transport delay, as on a real
//! bus.
//!
//! When the master stops sending process data for the SM watchdog time
//! (100 ms), the ESC drops to SAFE-OP and the firmware removes the torque and
//! goes to "fault" with error code 0x8130 (communication: life guard error).

use crate::cia402::{self, Command, State, MODE_CST};
use crate::esc::sii::{Identity, SiiContent, SiiPdo, SiiSyncManager};
use crate::esc::{al_code, coe, AlState, Application, Esc, SyncManager};
use crate::od::{Access, Dictionary};
use crate::pdo::{self, Codec, Inputs, Layout, MappingEntry};
use crate::scaling::{self, Scaling};
use crate::Error;
use beltune::axis::Axis as _;
use beltune::model::rigs::Plant;
use beltune::sim::{SimAxis, SimConfig};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;

/// Identity of the virtual drive (vendor ID 0: not a registered vendor).
pub const IDENTITY: Identity = Identity {
    vendor_id: 0x0000_0000,
    product_code: 0x0042_0402,
    revision: 0x0001_0000,
    serial: 0x0000_0001,
};
/// Device name in the SII and 0x1008.
pub const NAME: &str = "beltune virtual servo";

/// Error code for the SM watchdog (CiA 301: life guard error or heartbeat error).
pub const ERROR_WATCHDOG: u16 = 0x8130;
/// Error code when the bus leaves OP with the power stage on (CiA 301: communication).
pub const ERROR_COMMUNICATION: u16 = 0x8100;

const SM0: u16 = 0x1000;
const SM1: u16 = 0x1080;
/// Default length of each mailbox sync manager, bytes (SM0 at 0x1000 and
/// SM1 at 0x1080 leave room for at most 128).
pub const MAILBOX_LEN: u16 = 128;
/// Shortest mailbox the drive accepts, bytes (a segmented SDO needs 16).
pub const MAILBOX_MIN: u16 = 32;
const SM2: u16 = 0x1100;
const SM3: u16 = 0x1180;

/// Faults a test can inject while the drive runs (shared with the test).
#[derive(Debug, Default)]
pub struct Faults {
    /// A non-zero CiA 402 error code raises a drive fault at the next cycle.
    pub drive_fault: AtomicU32,
    /// Responses to drop (frames lost on the wire), counted down per frame.
    pub drop_frames: AtomicU32,
    /// Requests to drop before they reach the drive (a master that stops
    /// sending: the drive's SM watchdog runs out), counted down per frame.
    pub drop_requests: AtomicU32,
    /// Answers to hold back until the next frame arrives (on the wire: a late
    /// answer, after the master's frame timeout), counted down per frame.
    pub late_answers: AtomicU32,
    /// The faults above take effect once the drive has run this many cycles
    /// (0: at once), so that a test can aim at a stage of a commissioning.
    pub after_cycles: AtomicU64,
}

impl Faults {
    /// Whether the faults are armed after `cycles` drive cycles.
    pub fn armed(&self, cycles: u64) -> bool {
        cycles >= self.after_cycles.load(Ordering::Relaxed)
    }

    /// Count one frame off `counter` if the faults are armed; true: drop it.
    pub fn take(&self, counter: &AtomicU32, cycles: u64) -> bool {
        self.armed(cycles)
            && counter
                .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1))
                .is_ok()
    }
}

/// Settings of the virtual drive.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveConfig {
    /// Cycle time of the drive (the SYNC0 period it accepts), s.
    pub cycle_s: f64,
    /// Simulator settings.
    pub sim: SimConfig,
    /// Rated torque as a fraction of the plant's torque limit (0x6076 is the
    /// limit times this; 0x6072 is its inverse in per mille).
    pub rated_fraction: f64,
    /// Position 0x6064 at power-up, increments: near the 32-bit end so that the
    /// master must unwrap.
    pub initial_position_inc: i32,
    /// Damping of the quick stop, N m s/rad (braking torque `-D omega`);
    /// `None`: `D = 0.25 Theta_e / (T + T_d)`, a quarter of what the motor
    /// inertia alone tolerates over one cycle plus the current-loop dead time
    /// (above it the braking loop oscillates at the belt resonance, where the
    /// motor moves without the cart).
    pub quick_stop_damping_nm_s: Option<f64>,
    /// Advertise distributed clocks (ESC feature register 0x0008); without
    /// them the drive runs SM-synchronous: one cycle per output frame, which
    /// makes a test independent of the host's scheduling.
    pub distributed_clocks: bool,
    /// Speed below which a quick stop is complete, rad/s.
    pub quick_stop_done_rad_s: f64,
    /// Length of each mailbox (SM0, SM1), bytes, [`MAILBOX_MIN`] ..=
    /// [`MAILBOX_LEN`]: objects longer than one mailbox (the device name
    /// 0x1008 in a short one) go as segmented SDO transfers.
    pub mailbox_bytes: u16,
}

impl Default for DriveConfig {
    fn default() -> Self {
        DriveConfig {
            cycle_s: 1e-3,
            sim: SimConfig::default(),
            rated_fraction: 0.5,
            initial_position_inc: i32::MAX - 20_000,
            quick_stop_damping_nm_s: None,
            distributed_clocks: true,
            quick_stop_done_rad_s: 0.05,
            mailbox_bytes: MAILBOX_LEN,
        }
    }
}

/// The drive's firmware (the ESC's application).
pub struct Firmware {
    od: Dictionary,
    sim: SimAxis,
    scaling: Scaling,
    cycle_ns: u32,
    state: State,
    prev_cw: u16,
    mode_display: i8,
    error_code: u16,
    codec: Option<Codec>,
    faults: Arc<Faults>,
    cfg: DriveConfig,
    load_nm_per_inc: u32,
    last_torque_nm: f64,
    cycles: u64,
    quick_stop_damping: f64,
    sdo: coe::SdoServer,
}

/// The virtual drive: ESC and firmware.
pub struct VirtualDrive {
    /// The ESC.
    pub esc: Esc,
    /// The firmware.
    pub firmware: Firmware,
}

impl VirtualDrive {
    /// A drive for `plant` running at `cfg.cycle_s`. The simulator runs at the
    /// drive's cycle (the plant's sample time is set to it).
    pub fn new(plant: &Plant, cfg: DriveConfig) -> Result<Self, Error> {
        if !(cfg.cycle_s.is_finite() && (50e-6..=10e-3).contains(&cfg.cycle_s)) {
            return Err(Error::Config {
                name: "cycle time",
                reason: format!("{} s is outside 50 us ..= 10 ms", cfg.cycle_s),
            });
        }
        let cycle_ns = (cfg.cycle_s * 1e9).round() as u32;
        if !(cfg.rated_fraction > 0.05 && cfg.rated_fraction <= 1.0) {
            return Err(Error::Config {
                name: "rated torque fraction",
                reason: format!("{} is outside (0.05, 1]", cfg.rated_fraction),
            });
        }
        if !(MAILBOX_MIN..=MAILBOX_LEN).contains(&cfg.mailbox_bytes) {
            return Err(Error::Config {
                name: "mailbox length",
                reason: format!(
                    "{} bytes is outside {MAILBOX_MIN} ..= {MAILBOX_LEN}",
                    cfg.mailbox_bytes
                ),
            });
        }
        let mut plant = plant.clone();
        match &mut plant {
            Plant::Physical(p) => p.ts_s = cfg.cycle_s,
            Plant::Linear(l) => l.ts_s = cfg.cycle_s,
        }
        let sim = SimAxis::new(&plant, cfg.sim.clone())?;
        let info = sim.info();
        let per_rev = 2.0 * PI / info.motor_rad_per_count;
        let increments = per_rev.round();
        if (per_rev - increments).abs() > 1e-6 * per_rev
            || increments < 4.0
            || increments > f64::from(u32::MAX)
        {
            return Err(Error::Config {
                name: "encoder",
                reason: format!("{per_rev} counts per revolution is not a whole number"),
            });
        }
        let rated_mnm = (info.torque_max_nm * cfg.rated_fraction * 1e3).round() as u32;
        let max_permille = (info.torque_max_nm * 1e3 / f64::from(rated_mnm) * 1e3).floor() as u16;
        let load_nm_per_inc = (cfg.sim.cart_encoder_resolution_m * 1e9).round().max(1.0) as u32;
        let scaling = Scaling::from_objects(
            rated_mnm,
            max_permille,
            increments as u32,
            1,
            Some(load_nm_per_inc),
        )?;
        let od = dictionary(&scaling, cycle_ns, load_nm_per_inc);
        let theta_e = match &plant {
            Plant::Physical(p) => p.theta_e(),
            Plant::Linear(l) => l.two_mass.theta_e,
        };
        let quick_stop_damping = match cfg.quick_stop_damping_nm_s {
            Some(d) if d.is_finite() && d > 0.0 => d,
            Some(d) => {
                return Err(Error::Config {
                    name: "quick stop damping",
                    reason: format!("{d} N m s/rad is not positive"),
                })
            }
            None => 0.25 * theta_e / (cfg.cycle_s + plant.dead_time_s()),
        };
        let distributed_clocks = cfg.distributed_clocks;
        let mailbox = cfg.mailbox_bytes;
        let firmware = Firmware {
            od,
            sim,
            scaling,
            cycle_ns,
            state: State::NotReadyToSwitchOn,
            prev_cw: 0,
            mode_display: 0,
            error_code: 0,
            codec: None,
            faults: Arc::new(Faults::default()),
            cfg,
            load_nm_per_inc,
            last_torque_nm: 0.0,
            cycles: 0,
            quick_stop_damping,
            sdo: coe::SdoServer::new(),
        };
        let mut esc = Esc::new(crate::esc::sii::build(&sii_content(mailbox)));
        esc.set_distributed_clocks(distributed_clocks);
        Ok(VirtualDrive { esc, firmware })
    }

    /// Handle one frame in place; false if it is not an EtherCAT frame.
    pub fn process_frame(&mut self, frame: &mut [u8]) -> bool {
        self.esc.process_frame(frame, &mut self.firmware)
    }

    /// Advance the drive's clock to `t_ns` (SYNC0 cycles, watchdog).
    pub fn advance_to(&mut self, t_ns: u64) {
        self.esc.advance_to(t_ns, &mut self.firmware);
    }

    /// The fault injector shared with tests.
    pub fn faults(&self) -> Arc<Faults> {
        Arc::clone(&self.firmware.faults)
    }
}

impl Firmware {
    /// The simulator (the truth for tests).
    pub fn sim(&self) -> &SimAxis {
        &self.sim
    }

    /// The CiA 402 state.
    pub fn state(&self) -> State {
        self.state
    }

    /// The error code 0x603F.
    pub fn error_code(&self) -> u16 {
        self.error_code
    }

    /// The drive's scaling objects.
    pub fn scaling(&self) -> Scaling {
        self.scaling
    }

    /// Torque applied in the last cycle, N m.
    pub fn last_torque_nm(&self) -> f64 {
        self.last_torque_nm
    }

    /// Cycles run.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// The drive's cycle, ns.
    pub fn cycle_ns(&self) -> u32 {
        self.cycle_ns
    }

    fn fault(&mut self, code: u16) {
        if !matches!(self.state, State::Fault | State::FaultReactionActive) {
            self.state = State::FaultReactionActive;
            self.error_code = code;
        }
    }

    fn sync_mode_dc(&self) -> bool {
        self.od.get_uint(0x1C32, 1) == Some(2)
    }
}

impl Application for Firmware {
    fn al_change(&mut self, from: AlState, to: AlState, sms: &[SyncManager; 4]) -> Result<(), u16> {
        if from == AlState::PreOp && to == AlState::SafeOp {
            let out = Layout::new(&self.od.assigned_mapping(pdo::SM2_ASSIGN))
                .map_err(|_| al_code::INVALID_OUTPUT_CONFIG)?;
            let inp = Layout::new(&self.od.assigned_mapping(pdo::SM3_ASSIGN))
                .map_err(|_| al_code::INVALID_INPUT_CONFIG)?;
            if !sms[2].enabled || sms[2].start != SM2 || usize::from(sms[2].len) != out.len() {
                return Err(al_code::INVALID_OUTPUT_CONFIG);
            }
            if !sms[3].enabled || sms[3].start != SM3 || usize::from(sms[3].len) != inp.len() {
                return Err(al_code::INVALID_INPUT_CONFIG);
            }
            // the firmware needs the objects it drives: without them it has nothing to follow
            let codec = Codec::new(out, inp).map_err(|_| al_code::INVALID_OUTPUT_CONFIG)?;
            self.codec = Some(codec);
        }
        if to < AlState::SafeOp {
            self.codec = None;
        }
        if from == AlState::Op && self.state.torque_enabled() {
            self.fault(ERROR_COMMUNICATION);
        }
        Ok(())
    }

    fn mailbox(&mut self, request: &[u8], state: AlState) -> Option<Vec<u8>> {
        let capacity = usize::from(self.cfg.mailbox_bytes);
        self.sdo.handle(request, &mut self.od, state, capacity)
    }

    fn wants_sync0(&self) -> bool {
        self.sync_mode_dc()
    }

    fn watchdog_expired(&mut self) {
        self.fault(ERROR_WATCHDOG);
        self.last_torque_nm = 0.0;
    }

    fn cycle(&mut self, _t_ns: u64, op: bool, outputs: &[u8], inputs: &mut [u8]) {
        self.cycles += 1;
        let Some(codec) = self.codec.clone() else {
            return;
        };
        let out = if op {
            codec.unpack_outputs(outputs).ok()
        } else {
            None
        };
        let (cw, mode, target) = match out {
            Some(o) => (o.controlword, o.mode, o.target_torque_permille),
            None => (0, 0, 0),
        };
        let injected = if self.faults.armed(self.cycles) {
            self.faults.drive_fault.swap(0, Ordering::Relaxed)
        } else {
            0
        };
        if injected != 0 {
            self.fault(injected as u16);
        }
        // automatic transitions
        self.state = match self.state {
            State::NotReadyToSwitchOn => State::SwitchOnDisabled, // 1
            State::FaultReactionActive => State::Fault,           // 14
            s => s,
        };
        if !op && self.state.torque_enabled() {
            self.fault(ERROR_COMMUNICATION);
        }
        let before = self.state;
        let cmd = Command::from_controlword(cw, self.prev_cw);
        self.state = cia402::drive_transition(self.state, cmd);
        if self.state == State::SwitchOnDisabled && before == State::Fault {
            self.error_code = 0;
        }
        self.prev_cw = cw;
        if mode == MODE_CST {
            self.mode_display = MODE_CST;
        } else if !self.state.torque_enabled() {
            self.mode_display = mode.max(0);
        }
        let omega = self.sim.motor_velocity_rad_s();
        let lim = self.scaling.torque_limit_nm();
        let torque = match self.state {
            State::OperationEnabled if self.mode_display == MODE_CST => {
                self.scaling.permille_to_nm(target).clamp(-lim, lim)
            }
            State::QuickStopActive => {
                if omega.abs() < self.cfg.quick_stop_done_rad_s {
                    self.state = State::SwitchOnDisabled; // quick stop option 2: done, power off
                    0.0
                } else {
                    (-self.quick_stop_damping * omega).clamp(-lim, lim)
                }
            }
            _ => 0.0,
        };
        self.last_torque_nm = torque;
        let m = self.sim.step(torque);
        let q = self.sim.info().motor_rad_per_count;
        let position = i64::from(self.cfg.initial_position_inc).wrapping_add(m.motor_counts) as i32;
        let velocity = (self.sim.motor_velocity_rad_s() / q)
            .round()
            .clamp(i32::MIN as f64, i32::MAX as f64) as i32;
        let load = m.cart_position_m.map(|x| {
            (x * 1e9 / f64::from(self.load_nm_per_inc))
                .round()
                .clamp(i32::MIN as f64, i32::MAX as f64) as i32
        });
        let mut sw = self.state.statusword_bits() | cia402::SW_REMOTE;
        if !matches!(
            self.state,
            State::SwitchOnDisabled | State::NotReadyToSwitchOn | State::Fault
        ) {
            sw |= cia402::SW_VOLTAGE_ENABLED;
        }
        if self.state == State::OperationEnabled && self.mode_display == MODE_CST {
            sw |= cia402::SW_FOLLOWS_TARGET;
        }
        let inp = Inputs {
            statusword: sw,
            mode_display: self.mode_display,
            position_inc: position,
            velocity_inc_s: velocity,
            torque_permille: self.scaling.nm_to_permille(m.torque_actual_nm),
            error_code: self.error_code,
            load_position_inc: load,
        };
        let _ = codec.pack_inputs(&inp, inputs);
        // the objects behind the process data, for SDO reads
        self.od.set(cia402::STATUSWORD, 0, &sw.to_le_bytes());
        self.od
            .set(cia402::ERROR_CODE, 0, &self.error_code.to_le_bytes());
        self.od.set(
            cia402::MODES_OF_OPERATION_DISPLAY,
            0,
            &[self.mode_display as u8],
        );
        self.od
            .set(pdo::POSITION_ACTUAL, 0, &position.to_le_bytes());
        self.od
            .set(pdo::VELOCITY_ACTUAL, 0, &velocity.to_le_bytes());
        self.od
            .set(pdo::TORQUE_ACTUAL, 0, &inp.torque_permille.to_le_bytes());
        if let Some(l) = load {
            self.od
                .set(pdo::ADDITIONAL_POSITION_ACTUAL, 1, &l.to_le_bytes());
        }
    }
}

fn rx_mappable() -> Vec<MappingEntry> {
    pdo::OUTPUTS.to_vec()
}

fn tx_mappable() -> Vec<MappingEntry> {
    let mut v = pdo::INPUTS.to_vec();
    v.push(pdo::LOAD_POSITION);
    v
}

fn dictionary(s: &Scaling, cycle_ns: u32, load_nm_per_inc: u32) -> Dictionary {
    use Access::*;
    let mut od = Dictionary::new(rx_mappable(), tx_mappable());
    let u8v = |v: u8| vec![v];
    let u16v = |v: u16| v.to_le_bytes().to_vec();
    let u32v = |v: u32| v.to_le_bytes().to_vec();
    od.insert(0x1000, 0, u32v(0x0002_0192), Ro); // device type: CiA 402 servo
    od.insert(0x1008, 0, NAME.as_bytes().to_vec(), Ro);
    od.insert(0x1018, 0, u8v(4), Ro);
    od.insert(0x1018, 1, u32v(IDENTITY.vendor_id), Ro);
    od.insert(0x1018, 2, u32v(IDENTITY.product_code), Ro);
    od.insert(0x1018, 3, u32v(IDENTITY.revision), Ro);
    od.insert(0x1018, 4, u32v(IDENTITY.serial), Ro);
    od.insert(0x1C00, 0, u8v(4), Ro);
    for (i, t) in [1u8, 2, 3, 4].iter().enumerate() {
        od.insert(0x1C00, i as u8 + 1, u8v(*t), Ro);
    }
    // default mapping: the standard one with the load position
    let rx = rx_mappable();
    let tx = tx_mappable();
    od.insert(pdo::RX_PDO, 0, u8v(rx.len() as u8), RwPreOp);
    for (i, e) in rx.iter().enumerate() {
        od.insert(pdo::RX_PDO, i as u8 + 1, u32v(e.to_u32()), RwPreOp);
    }
    od.insert(pdo::TX_PDO, 0, u8v(tx.len() as u8), RwPreOp);
    for (i, e) in tx.iter().enumerate() {
        od.insert(pdo::TX_PDO, i as u8 + 1, u32v(e.to_u32()), RwPreOp);
    }
    od.insert(pdo::SM2_ASSIGN, 0, u8v(1), RwPreOp);
    od.insert(pdo::SM2_ASSIGN, 1, u16v(pdo::RX_PDO), RwPreOp);
    od.insert(pdo::SM3_ASSIGN, 0, u8v(1), RwPreOp);
    od.insert(pdo::SM3_ASSIGN, 1, u16v(pdo::TX_PDO), RwPreOp);
    for idx in [0x1C32u16, 0x1C33] {
        od.insert(idx, 0, u8v(9), Ro);
        od.insert(idx, 1, u16v(1), RwPreOp); // sync type: 1 SM-synchronous, 2 DC SYNC0
        od.insert(idx, 2, u32v(cycle_ns), Ro); // cycle time, ns
        od.insert(idx, 4, u16v(0x0007), Ro); // supported: free run, SM, DC SYNC0
        od.insert(idx, 5, u32v(cycle_ns), Ro); // minimum cycle time
        od.insert(idx, 6, u32v(cycle_ns / 10), Ro); // calc and copy time
        od.insert(idx, 9, u32v(0), Ro); // delay time
    }
    od.insert(cia402::ERROR_CODE, 0, u16v(0), Ro);
    od.insert(cia402::CONTROLWORD, 0, u16v(0), Rw);
    od.insert(cia402::STATUSWORD, 0, u16v(0), Ro);
    od.insert(0x605A, 0, (2i16).to_le_bytes().to_vec(), Rw); // quick stop option code
    od.insert(cia402::MODES_OF_OPERATION, 0, u8v(0), Rw);
    od.insert(cia402::MODES_OF_OPERATION_DISPLAY, 0, u8v(0), Ro);
    od.insert(pdo::POSITION_ACTUAL, 0, u32v(0), Ro);
    od.insert(pdo::VELOCITY_ACTUAL, 0, u32v(0), Ro);
    od.insert(pdo::TARGET_TORQUE, 0, u16v(0), Rw);
    od.insert(scaling::MAX_TORQUE, 0, u16v(s.max_torque_permille), Ro);
    od.insert(
        scaling::RATED_TORQUE,
        0,
        u32v((s.rated_torque_nm * 1e3).round() as u32),
        Ro,
    );
    od.insert(pdo::TORQUE_ACTUAL, 0, u16v(0), Ro);
    od.insert(scaling::ENCODER_RESOLUTION, 0, u8v(2), Ro);
    od.insert(
        scaling::ENCODER_RESOLUTION,
        1,
        u32v(s.encoder_increments),
        Ro,
    );
    od.insert(
        scaling::ENCODER_RESOLUTION,
        2,
        u32v(s.motor_revolutions),
        Ro,
    );
    // interpolation time: cycle in units of 10^-6 s when whole, else 10^-7 s
    let (v, e) = if cycle_ns % 1000 == 0 && cycle_ns / 1000 <= 255 {
        ((cycle_ns / 1000) as u8, -6i8)
    } else {
        ((cycle_ns / 100).min(255) as u8, -7i8)
    };
    od.insert(scaling::INTERPOLATION_TIME, 0, u8v(2), Ro);
    od.insert(scaling::INTERPOLATION_TIME, 1, u8v(v), Ro);
    od.insert(scaling::INTERPOLATION_TIME, 2, vec![e as u8], Ro);
    od.insert(pdo::ADDITIONAL_POSITION_ACTUAL, 0, u8v(1), Ro);
    od.insert(pdo::ADDITIONAL_POSITION_ACTUAL, 1, u32v(0), Ro);
    od.insert(cia402::SUPPORTED_DRIVE_MODES, 0, u32v(1 << 9), Ro); // CST only
    od.insert(
        scaling::LOAD_ENCODER_RESOLUTION,
        0,
        u32v(load_nm_per_inc),
        Ro,
    );
    od
}

fn sii_content(mailbox: u16) -> SiiContent {
    let entries = |m: &[MappingEntry]| {
        m.iter()
            .map(|e| {
                // CoE data types: 0x0006 UNSIGNED16, 0x0002 INTEGER8, 0x0003 INTEGER16, 0x0004 INTEGER32
                let ty = match (e.index, e.bits) {
                    (cia402::CONTROLWORD | cia402::STATUSWORD | cia402::ERROR_CODE, _) => 0x06,
                    (_, 8) => 0x02,
                    (_, 16) => 0x03,
                    _ => 0x04,
                };
                (e.index, e.sub_index, ty, e.bits)
            })
            .collect()
    };
    SiiContent {
        identity: IDENTITY,
        name: NAME.into(),
        mailbox: (SM0, mailbox, SM1, mailbox),
        sync_managers: vec![
            SiiSyncManager {
                start: SM0,
                len: mailbox,
                control: 0x26,
                ty: 1,
            },
            SiiSyncManager {
                start: SM1,
                len: mailbox,
                control: 0x22,
                ty: 2,
            },
            SiiSyncManager {
                start: SM2,
                len: 0,
                control: 0x64,
                ty: 3,
            },
            SiiSyncManager {
                start: SM3,
                len: 0,
                control: 0x20,
                ty: 4,
            },
        ],
        fmmus: vec![1, 2, 3, 0],
        rx_pdos: vec![SiiPdo {
            index: pdo::RX_PDO,
            sync_manager: 2,
            entries: entries(&rx_mappable()),
        }],
        tx_pdos: vec![SiiPdo {
            index: pdo::TX_PDO,
            sync_manager: 3,
            entries: entries(&tx_mappable()),
        }],
    }
}
