//! An EtherCAT SubDevice controller (ESC) emulator: what the chip of a real
//! drive does with the frames of the master (ETG.1000.4, ETG.1000.6, the ESC
//! register description of ET1100-class controllers).
//!
//! - datagrams APRD/APWR/APRW, FPRD/FPWR/FPRW, BRD/BWR/BRW, LRD/LWR/LRW,
//!   ARMW/FRMW with the working counter of the standard (read +1, write +1,
//!   read-write +3; logical: +1 for a read FMMU hit, +2 for a write FMMU hit);
//! - registers: device information 0x0000-0x000F, station address 0x0010, DL
//!   status 0x0110, AL control/status/status code 0x0120/0x0130/0x0134, SM
//!   watchdog 0x0400/0x0420/0x0440, SII (EEPROM) interface 0x0500-0x050F, FMMUs
//!   0x0600, sync managers 0x0800, distributed clocks 0x0900-0x09A7;
//! - the AL state machine INIT / PRE-OP / SAFE-OP / OP with the checks of the
//!   standard (mailbox sync managers for PRE-OP, process-data sync managers for
//!   SAFE-OP, SYNC0 where the application asks for it) and error codes;
//! - mailbox sync managers (SM0 master to device, SM1 device to master): a write
//!   of the last byte hands the request to the application, whose answer waits
//!   in SM1 until the master has read its last byte;
//! - process data: SM2 (outputs) and SM3 (inputs) behind FMMUs; the
//!   application's cycle runs at every SYNC0 event when SYNC0 is active, else
//!   at every complete write of SM2 (SM-synchronous);
//! - the SM watchdog: in OP, without a complete SM2 write for the watchdog time
//!   (default 100 ms), the application is told to remove its outputs and the
//!   device falls back to SAFE-OP with AL status code 0x001B.
//!
//! Time is the device's local clock in ns, advanced by [`Esc::advance_to`]
//! (simulated time in-process, the monotonic clock on the wire).

pub mod coe;
pub mod frame;
pub mod sdo_info;
pub mod sii;

use frame::{Cmd, Datagram};

/// Size of the emulated memory: registers 0x0000-0x0FFF and 4 KiB of process RAM.
pub const MEMORY_SIZE: usize = 0x2000;

/// AL states (register 0x0130 bits 0-3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum AlState {
    /// INIT (1).
    Init = 1,
    /// PRE-OPERATIONAL (2): mailbox.
    PreOp = 2,
    /// SAFE-OPERATIONAL (4): inputs valid, outputs ignored.
    SafeOp = 4,
    /// OPERATIONAL (8).
    Op = 8,
}

impl core::fmt::Display for AlState {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            AlState::Init => "INIT",
            AlState::PreOp => "PRE-OP",
            AlState::SafeOp => "SAFE-OP",
            AlState::Op => "OP",
        })
    }
}

impl AlState {
    fn from_bits(b: u8) -> Option<AlState> {
        Some(match b & 0x0F {
            1 => AlState::Init,
            2 => AlState::PreOp,
            4 => AlState::SafeOp,
            8 => AlState::Op,
            _ => return None,
        })
    }
}

/// AL status codes used by the emulator (ETG.1000.6 table 11).
pub mod al_code {
    /// Invalid requested state change.
    pub const INVALID_STATE_CHANGE: u16 = 0x0011;
    /// Unknown requested state.
    pub const UNKNOWN_STATE: u16 = 0x0012;
    /// Bootstrap not supported.
    pub const BOOTSTRAP_NOT_SUPPORTED: u16 = 0x0013;
    /// Invalid mailbox configuration (PRE-OP).
    pub const INVALID_MAILBOX_CONFIG: u16 = 0x0016;
    /// Sync manager watchdog.
    pub const SM_WATCHDOG: u16 = 0x001B;
    /// Invalid output configuration.
    pub const INVALID_OUTPUT_CONFIG: u16 = 0x001D;
    /// Invalid input configuration.
    pub const INVALID_INPUT_CONFIG: u16 = 0x001E;
    /// Invalid DC SYNC configuration.
    pub const INVALID_DC_SYNC: u16 = 0x0030;
    /// DC SYNC0 cycle time not supported (the drive runs at its own cycle).
    pub const DC_SYNC0_CYCLE_TIME: u16 = 0x0036;
}

/// Mailbox answers and device messages the ESC keeps for SM1 at most; a
/// further request stays in SM0 (its status "full") and writes to SM0 are
/// not taken (working counter unchanged) until the master reads SM1, as a
/// real device's mailbox does.
pub const MAX_PENDING_MAILBOX: usize = 16;
/// SYNC0 events the application runs one by one in one [`Esc::advance_to`];
/// older ones (a clock that jumped, a SYNC0 cycle far below the
/// application's) are skipped and counted in [`EscStats::sync0_skipped`].
pub const MAX_SYNC0_PER_ADVANCE: u64 = 64;

/// A sync manager's configuration (registers 0x0800 + 8 n).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SyncManager {
    /// Physical start address.
    pub start: u16,
    /// Length, bytes.
    pub len: u16,
    /// Control byte (mode, direction, interrupts, watchdog).
    pub control: u8,
    /// Enabled (activate register bit 0).
    pub enabled: bool,
}

impl SyncManager {
    fn contains_last_byte(&self, start: usize, len: usize) -> bool {
        let last = usize::from(self.start) + usize::from(self.len);
        self.enabled && self.len > 0 && start < last && start + len >= last
    }
}

/// What the device's firmware does; the ESC calls it.
pub trait Application {
    /// The master requests an AL state change `from -> to` (after the ESC's
    /// own checks). `Err(code)` refuses it with an AL status code.
    fn al_change(&mut self, from: AlState, to: AlState, sms: &[SyncManager; 4]) -> Result<(), u16>;
    /// A mailbox request arrived (the whole SM0 buffer); the answer for SM1, if any.
    fn mailbox(&mut self, request: &[u8], state: AlState) -> Option<Vec<u8>>;
    /// One application cycle at local time `t_ns`: consume `outputs` (the
    /// last complete SM2 buffer; use them only when `op`), produce `inputs`
    /// (the SM3 buffer).
    fn cycle(&mut self, t_ns: u64, op: bool, outputs: &[u8], inputs: &mut [u8]);
    /// The SM watchdog expired: remove the outputs' effect at once.
    fn watchdog_expired(&mut self);
    /// Whether the application runs DC-synchronous (SYNC0 required for SAFE-OP).
    fn wants_sync0(&self) -> bool;
    /// Whether the application runs with a SYNC0 cycle of `cycle_ns`
    /// (checked at PRE-OP -> SAFE-OP and when the master changes SYNC0 in
    /// SAFE-OP or OP; refused with AL code 0x0036).
    fn accepts_sync0_cycle(&self, _cycle_ns: u32) -> bool {
        true
    }
    /// A message the device sends on its own (a CoE emergency), queued
    /// behind the mailbox answers; polled from PRE-OP on.
    fn outgoing(&mut self) -> Option<Vec<u8>> {
        None
    }
    /// Write the current inputs into `inputs` without running a cycle (the
    /// SM watchdog just expired: the master's next read must see the fault).
    fn refresh_inputs(&mut self, _inputs: &mut [u8]) {}
    /// Without SYNC0: the cycle on which the application runs by itself
    /// when no process data comes (`None`: only on process data).
    fn free_run_cycle_ns(&self) -> Option<u32> {
        None
    }
}

/// Counters for tests and diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EscStats {
    /// Frames processed.
    pub frames: u64,
    /// Datagrams processed.
    pub datagrams: u64,
    /// Application cycles run.
    pub cycles: u64,
    /// Mailbox requests handled.
    pub mailbox_requests: u64,
    /// Watchdog expiries.
    pub watchdog_expiries: u64,
    /// Application cycles in OP that found no output write since the cycle
    /// before (SYNC0: the master's frame came late; the cycle used the
    /// previous outputs again).
    pub cycles_without_new_outputs: u64,
    /// SYNC0 events skipped without an application cycle
    /// ([`MAX_SYNC0_PER_ADVANCE`]).
    pub sync0_skipped: u64,
    /// Mailbox repeat requests served (SM1 activate bit 1 toggled).
    pub mailbox_repeats: u64,
}

/// The emulated ESC.
pub struct Esc {
    mem: Vec<u8>,
    sii: Vec<u8>,
    al_state: AlState,
    al_error: bool,
    al_code: u16,
    time_ns: u64,
    /// Mailbox answers waiting for SM1 (at most [`MAX_PENDING_MAILBOX`]).
    pending: std::collections::VecDeque<Vec<u8>>,
    sm1_full: bool,
    /// The last message put into SM1, for the master's repeat request.
    last_sm1: Vec<u8>,
    /// A request held in SM0 while the answer queue is full.
    sm0_held: Option<Vec<u8>>,
    outputs: Vec<u8>,
    last_output_ns: u64,
    watchdog_expired: bool,
    next_sync0_ns: Option<u64>,
    /// Local time of the last application cycle, ns.
    last_cycle_ns: u64,
    cycle_due: bool,
    fresh_outputs: bool,
    stats: EscStats,
}

const REG_TYPE: usize = 0x0000;
const REG_STATION: usize = 0x0010;
const REG_DL_STATUS: usize = 0x0110;
const REG_AL_CONTROL: usize = 0x0120;
const REG_AL_STATUS: usize = 0x0130;
const REG_AL_CODE: usize = 0x0134;
const REG_WD_DIVIDER: usize = 0x0400;
const REG_WD_SM: usize = 0x0420;
const REG_WD_STATUS: usize = 0x0440;
const REG_SII_CONFIG: usize = 0x0500;
const REG_SII_CONTROL: usize = 0x0502;
const REG_SII_ADDRESS: usize = 0x0504;
const REG_SII_DATA: usize = 0x0508;
const REG_FMMU: usize = 0x0600;
const REG_SM: usize = 0x0800;
const REG_DC_PORT0: usize = 0x0900;
const REG_DC_SYSTEM_TIME: usize = 0x0910;
const REG_DC_RECEIVE_TIME: usize = 0x0918;
const REG_DC_OFFSET: usize = 0x0920;
const REG_DC_ACTIVATION: usize = 0x0981;
const REG_DC_START: usize = 0x0990;
const REG_DC_SYNC0_CYCLE: usize = 0x09A0;

impl Esc {
    /// An ESC in INIT with `sii` as its EEPROM content (bytes, little endian words).
    pub fn new(sii: Vec<u8>) -> Self {
        let mut mem = vec![0u8; MEMORY_SIZE];
        mem[REG_TYPE] = 0x11; // ET1100-like
        mem[0x0001] = 0x02; // revision
        mem[0x0004] = 8; // FMMUs
        mem[0x0005] = 8; // sync managers
        mem[0x0006] = 4; // process RAM, KiB
        mem[0x0007] = 0x0F; // ports 0, 1: MII; 2, 3: not implemented
                            // feature flags 0x0008: DC supported (bit 2), 64-bit DC (bit 3)
        mem[0x0008] = 0x0C;
        // DL status (ETG.1000.4 table 39): PDI operational (bit 0), PDI
        // watchdog reloaded (bit 1, not expired), physical link on port 0 only
        // (bit 4; 0x0007 says ports 2, 3 do not exist and port 1 has no
        // cable), port 0 open with communication (bit 9, loop bit 8 clear),
        // ports 1-3 loop closed without communication (bits 10, 12, 14): the
        // last device of a line, as a master counts it
        let dl: u16 = 0x0001 | 0x0002 | 0x0010 | 0x0200 | 0x0400 | 0x1000 | 0x4000;
        mem[REG_DL_STATUS..REG_DL_STATUS + 2].copy_from_slice(&dl.to_le_bytes());
        mem[REG_WD_DIVIDER..REG_WD_DIVIDER + 2].copy_from_slice(&2498u16.to_le_bytes());
        mem[REG_WD_SM..REG_WD_SM + 2].copy_from_slice(&1000u16.to_le_bytes());
        mem[REG_WD_STATUS] = 1;
        mem[REG_SII_CONTROL] = 0x40; // 8-byte reads
        let mut esc = Esc {
            mem,
            sii,
            al_state: AlState::Init,
            al_error: false,
            al_code: 0,
            time_ns: 0,
            pending: Default::default(),
            sm1_full: false,
            last_sm1: Vec::new(),
            sm0_held: None,
            outputs: Vec::new(),
            last_output_ns: 0,
            watchdog_expired: false,
            next_sync0_ns: None,
            last_cycle_ns: 0,
            cycle_due: false,
            fresh_outputs: false,
            stats: EscStats::default(),
        };
        esc.publish_al();
        esc
    }

    /// Offer distributed clocks (feature register 0x0008 bits 2, 3) or not
    /// (the registers stay, but a master will not configure SYNC0).
    pub fn set_distributed_clocks(&mut self, on: bool) {
        if on {
            self.mem[0x0008] |= 0x0C;
        } else {
            self.mem[0x0008] &= !0x0C;
        }
    }

    /// The SII EEPROM image, bytes.
    pub fn sii(&self) -> &[u8] {
        &self.sii
    }

    /// The AL state.
    pub fn al_state(&self) -> AlState {
        self.al_state
    }

    /// The AL status code (0 without error).
    pub fn al_status_code(&self) -> u16 {
        self.al_code
    }

    /// Whether an AL error indication is latched (0x0130 bit 4).
    pub fn al_error(&self) -> bool {
        self.al_error
    }

    /// Counters.
    pub fn stats(&self) -> EscStats {
        self.stats
    }

    /// Local time, ns.
    pub fn time_ns(&self) -> u64 {
        self.time_ns
    }

    /// Whether the SM watchdog has expired since the last OP.
    pub fn watchdog_has_expired(&self) -> bool {
        self.watchdog_expired
    }

    /// The sync manager `n` (0-3).
    pub fn sync_manager(&self, n: usize) -> SyncManager {
        let b = REG_SM + 8 * n;
        SyncManager {
            start: u16::from_le_bytes([self.mem[b], self.mem[b + 1]]),
            len: u16::from_le_bytes([self.mem[b + 2], self.mem[b + 3]]),
            control: self.mem[b + 4],
            enabled: self.mem[b + 6] & 1 != 0,
        }
    }

    fn sms(&self) -> [SyncManager; 4] {
        [0, 1, 2, 3].map(|n| self.sync_manager(n))
    }

    fn u16_at(&self, a: usize) -> u16 {
        u16::from_le_bytes([self.mem[a], self.mem[a + 1]])
    }

    fn u32_at(&self, a: usize) -> u32 {
        u32::from_le_bytes(self.mem[a..a + 4].try_into().expect("4 bytes"))
    }

    fn u64_at(&self, a: usize) -> u64 {
        u64::from_le_bytes(self.mem[a..a + 8].try_into().expect("8 bytes"))
    }

    fn set_u64(&mut self, a: usize, v: u64) {
        self.mem[a..a + 8].copy_from_slice(&v.to_le_bytes());
    }

    fn publish_al(&mut self) {
        self.mem[REG_AL_STATUS] = self.al_state as u8 | if self.al_error { 0x10 } else { 0 };
        self.mem[REG_AL_STATUS + 1] = 0;
        self.mem[REG_AL_CODE..REG_AL_CODE + 2].copy_from_slice(&self.al_code.to_le_bytes());
        self.mem[REG_WD_STATUS] = u8::from(!self.watchdog_expired);
    }

    fn publish_sm_status(&mut self) {
        // SM1 (mailbox read by the master): bit 3 "mailbox full"
        let s1 = REG_SM + 8 + 5;
        self.mem[s1] = if self.sm1_full { 0x08 } else { 0 };
        // SM0 is emptied when the request is handled, full while it is held
        self.mem[REG_SM + 5] = if self.sm0_held.is_some() { 0x08 } else { 0 };
    }

    /// The message in SM1 while the master has not read it.
    pub fn sm1_message(&self) -> Option<&[u8]> {
        self.sm1_full.then_some(self.last_sm1.as_slice())
    }

    /// Messages waiting for SM1 behind the one in it (bounded by
    /// [`MAX_PENDING_MAILBOX`]), and whether a request is held in SM0.
    pub fn mailbox_backlog(&self) -> (usize, bool) {
        (self.pending.len(), self.sm0_held.is_some())
    }

    /// Queue a message for SM1 (the answer to a request or the device's
    /// own); false if the queue is full.
    fn send_mailbox(&mut self, msg: Vec<u8>) -> bool {
        if !self.sm1_full {
            self.load_sm1(msg);
            true
        } else if self.pending.len() < MAX_PENDING_MAILBOX {
            self.pending.push_back(msg);
            true
        } else {
            false
        }
    }

    /// Device messages (emergencies) into the queue while there is room.
    fn poll_outgoing(&mut self, app: &mut dyn Application) {
        if self.al_state < AlState::PreOp {
            return;
        }
        while self.pending.len() < MAX_PENDING_MAILBOX {
            match app.outgoing() {
                Some(m) => {
                    self.send_mailbox(m);
                }
                None => break,
            }
        }
        self.publish_sm_status();
    }

    /// System time (local time + offset, register 0x0910), ns.
    pub fn system_time_ns(&self) -> u64 {
        self.time_ns.wrapping_add(self.u64_at(REG_DC_OFFSET))
    }

    /// SYNC0 cycle time if SYNC0 is active, ns.
    pub fn sync0_cycle_ns(&self) -> Option<u32> {
        let act = self.mem[REG_DC_ACTIVATION];
        let cyc = self.u32_at(REG_DC_SYNC0_CYCLE);
        (act & 0x03 == 0x03 && cyc > 0).then_some(cyc)
    }

    fn watchdog_time_ns(&self) -> Option<u64> {
        let div = u64::from(self.u16_at(REG_WD_DIVIDER));
        let n = u64::from(self.u16_at(REG_WD_SM));
        (n > 0).then_some((div + 2) * 40 * n)
    }

    /// Advance the local clock to `t_ns`: run the application at every SYNC0
    /// event up to it and check the SM watchdog.
    pub fn advance_to(&mut self, t_ns: u64, app: &mut dyn Application) {
        if t_ns < self.time_ns {
            return;
        }
        if let Some(cycle) = self.sync0_cycle_ns() {
            let offset = self.u64_at(REG_DC_OFFSET);
            // next SYNC0 in local time
            let start = self.u64_at(REG_DC_START).wrapping_sub(offset);
            let mut next_t = match self.next_sync0_ns {
                Some(n) => n,
                None => {
                    // the first pulse at the start time, or the next whole cycle after now
                    if start >= self.time_ns {
                        start
                    } else {
                        let c = u64::from(cycle);
                        start + (self.time_ns - start).div_ceil(c) * c
                    }
                }
            };
            let c = u64::from(cycle);
            // in INIT and PRE-OP no cycle runs; beyond MAX_SYNC0_PER_ADVANCE
            // due events the oldest are skipped (a SYNC0 cycle of 1 ns made
            // this loop spin for minutes and the process deaf to signals)
            let keep = if self.al_state >= AlState::SafeOp {
                MAX_SYNC0_PER_ADVANCE
            } else {
                0
            };
            if next_t <= t_ns {
                let due = (t_ns - next_t) / c + 1;
                if due > keep {
                    let skip = due - keep;
                    next_t = next_t.saturating_add(skip.saturating_mul(c));
                    if keep > 0 {
                        self.stats.sync0_skipped += skip;
                    }
                }
            }
            while next_t <= t_ns {
                self.time_ns = next_t;
                self.check_watchdog(app);
                self.run_cycle(app);
                next_t += c;
            }
            self.next_sync0_ns = Some(next_t);
        } else {
            self.next_sync0_ns = None;
            self.free_run(t_ns, app);
        }
        self.time_ns = t_ns;
        self.check_watchdog(app);
    }

    fn check_watchdog(&mut self, app: &mut dyn Application) {
        let sm2 = self.sync_manager(2);
        if self.al_state != AlState::Op || !sm2.enabled || sm2.control & 0x40 == 0 {
            return;
        }
        if let Some(wd) = self.watchdog_time_ns() {
            if self.time_ns.saturating_sub(self.last_output_ns) > wd {
                self.watchdog_expired = true;
                self.stats.watchdog_expiries += 1;
                app.watchdog_expired();
                self.al_state = AlState::SafeOp;
                self.al_error = true;
                self.al_code = al_code::SM_WATCHDOG;
                self.publish_al();
                // the inputs show the fault at the master's next read
                let sm3 = self.sync_manager(3);
                let (s, n) = (usize::from(sm3.start), usize::from(sm3.len));
                if sm3.enabled && s + n <= MEMORY_SIZE {
                    let mut inputs = self.mem[s..s + n].to_vec();
                    app.refresh_inputs(&mut inputs);
                    self.mem[s..s + n].copy_from_slice(&inputs);
                }
                self.poll_outgoing(app);
            }
        }
    }

    /// Without SYNC0 and without process data for two of the application's
    /// free-run cycles, the application runs on its own clock (the axis
    /// moves whether or not the master sends): at most
    /// [`MAX_SYNC0_PER_ADVANCE`] cycles per advance, older ones skipped.
    fn free_run(&mut self, t_ns: u64, app: &mut dyn Application) {
        let Some(c) = app.free_run_cycle_ns().map(u64::from).filter(|c| *c > 0) else {
            return;
        };
        if self.al_state < AlState::SafeOp {
            return;
        }
        if self.last_cycle_ns + 2 * c > t_ns {
            return;
        }
        let due = (t_ns - self.last_cycle_ns) / c - 1;
        if due > MAX_SYNC0_PER_ADVANCE {
            self.last_cycle_ns += (due - MAX_SYNC0_PER_ADVANCE) * c;
        }
        while self.last_cycle_ns + 2 * c <= t_ns {
            self.time_ns = self.last_cycle_ns + c;
            self.check_watchdog(app);
            self.fresh_outputs = true; // not a late master: no cycle without new outputs
            self.run_cycle(app);
        }
    }

    fn run_cycle(&mut self, app: &mut dyn Application) {
        if self.al_state < AlState::SafeOp {
            return;
        }
        self.last_cycle_ns = self.time_ns;
        let sm3 = self.sync_manager(3);
        let (s, n) = (usize::from(sm3.start), usize::from(sm3.len));
        if s + n > MEMORY_SIZE {
            return;
        }
        let mut inputs = self.mem[s..s + n].to_vec();
        if self.al_state == AlState::Op && !self.fresh_outputs {
            self.stats.cycles_without_new_outputs += 1;
        }
        self.fresh_outputs = false;
        app.cycle(
            self.time_ns,
            self.al_state == AlState::Op,
            &self.outputs,
            &mut inputs,
        );
        self.mem[s..s + n].copy_from_slice(&inputs);
        self.stats.cycles += 1;
        self.poll_outgoing(app);
    }

    /// Process one frame in place as the device on port 0 of a one-device
    /// ring: every datagram addressed to the device is executed, the working
    /// counters are incremented, the source MAC gets the locally administered
    /// bit (as an ESC sets it when forwarding). Returns false if `frame` is not
    /// an EtherCAT frame (it is then left alone).
    pub fn process_frame(&mut self, frame: &mut [u8], app: &mut dyn Application) -> bool {
        let Some(dgs) = frame::datagrams(frame) else {
            return false;
        };
        self.stats.frames += 1;
        for d in dgs {
            self.stats.datagrams += 1;
            self.datagram(frame, d, app);
        }
        frame[6] |= 0x02;
        if self.cycle_due {
            self.cycle_due = false;
            if self.sync0_cycle_ns().is_none() {
                self.run_cycle(app);
            }
        }
        true
    }

    fn datagram(&mut self, f: &mut [u8], d: Datagram, app: &mut dyn Application) {
        let Some(cmd) = d.cmd else { return };
        let a = d.start + 2;
        let adp = u16::from_le_bytes([f[a], f[a + 1]]);
        let ado = usize::from(u16::from_le_bytes([f[a + 2], f[a + 3]]));
        let mut wkc = u16::from_le_bytes([f[d.wkc()], f[d.wkc() + 1]]);
        let station = self.u16_at(REG_STATION);
        let data = d.data()..d.data() + d.len;
        match cmd {
            Cmd::Nop => {}
            Cmd::Aprd | Cmd::Apwr | Cmd::Aprw | Cmd::Armw => {
                let me = adp == 0;
                f[a..a + 2].copy_from_slice(&adp.wrapping_add(1).to_le_bytes());
                if me {
                    wkc += self.physical(cmd, ado, &mut f[data], app);
                } else if cmd == Cmd::Armw {
                    // another device reads, this one writes
                    wkc += self.physical(Cmd::Apwr, ado, &mut f[data], app);
                }
            }
            Cmd::Fprd | Cmd::Fpwr | Cmd::Fprw | Cmd::Frmw => {
                if adp == station {
                    wkc += self.physical(cmd, ado, &mut f[data], app);
                } else if cmd == Cmd::Frmw {
                    wkc += self.physical(Cmd::Fpwr, ado, &mut f[data], app);
                }
            }
            Cmd::Brd | Cmd::Bwr | Cmd::Brw => {
                f[a..a + 2].copy_from_slice(&adp.wrapping_add(1).to_le_bytes());
                wkc += self.physical(cmd, ado, &mut f[data], app);
            }
            Cmd::Lrd | Cmd::Lwr | Cmd::Lrw => {
                let logical = u32::from_le_bytes(f[a..a + 4].try_into().expect("4 bytes"));
                wkc += self.logical(cmd, logical, &mut f[data], app);
            }
        }
        let w = d.wkc();
        f[w..w + 2].copy_from_slice(&wkc.to_le_bytes());
    }

    /// A physical access at `ado`; returns the working-counter increment.
    fn physical(
        &mut self,
        cmd: Cmd,
        ado: usize,
        data: &mut [u8],
        app: &mut dyn Application,
    ) -> u16 {
        if ado + data.len() > MEMORY_SIZE {
            return 0;
        }
        let mut wkc = 0;
        // read-write commands: the device reads first, then writes what came in
        let incoming = if cmd.writes() {
            Some(data.to_vec())
        } else {
            None
        };
        if cmd.reads() || matches!(cmd, Cmd::Armw | Cmd::Frmw) {
            let emptied = if matches!(cmd, Cmd::Brd | Cmd::Brw) {
                // broadcast reads OR the devices' data into the datagram
                let mut mine = vec![0u8; data.len()];
                let e = self.read(ado, &mut mine);
                data.iter_mut().zip(mine).for_each(|(d, m)| *d |= m);
                e
            } else {
                self.read(ado, data)
            };
            if emptied {
                self.after_sm1_read(app);
            }
            wkc += 1;
        }
        if let Some(incoming) = incoming {
            // a write into a full SM0 (a request held) is not taken
            let sm0 = self.sync_manager(0);
            let (s0, n0) = (usize::from(sm0.start), usize::from(sm0.len));
            let into_held_sm0 = self.sm0_held.is_some()
                && sm0.enabled
                && ado < s0 + n0
                && ado + incoming.len() > s0;
            if !into_held_sm0 {
                self.write(ado, &incoming, app);
                wkc += if cmd.reads() { 2 } else { 1 };
            }
        }
        wkc
    }

    fn logical(
        &mut self,
        cmd: Cmd,
        logical: u32,
        data: &mut [u8],
        app: &mut dyn Application,
    ) -> u16 {
        let mut read_hit = false;
        let mut write_hit = false;
        let incoming = data.to_vec();
        for i in 0..8 {
            let b = REG_FMMU + 16 * i;
            if self.mem[b + 12] & 1 == 0 {
                continue;
            }
            let log_start = u64::from(self.u32_at(b));
            let len = u64::from(self.u16_at(b + 4));
            let phys = usize::from(self.u16_at(b + 8));
            let ty = self.mem[b + 11];
            // overlap of [logical, logical + data.len()) and [log_start,
            // log_start + len), in 64 bits: a mapping that ends past
            // 0xFFFFFFFF must not wrap
            let logical = u64::from(logical);
            let lo = logical.max(log_start);
            let hi = (logical + data.len() as u64).min(log_start + len);
            if lo >= hi {
                continue;
            }
            let d0 = (lo - logical) as usize;
            let p0 = phys + (lo - log_start) as usize;
            let n = (hi - lo) as usize;
            if p0 + n > MEMORY_SIZE {
                continue;
            }
            let sm = self.sms().into_iter().find(|s| {
                s.enabled
                    && usize::from(s.start) <= p0
                    && p0 < usize::from(s.start) + usize::from(s.len)
            });
            if ty & 1 != 0 && cmd.reads() {
                // inputs are valid from SAFE-OP on
                if self.al_state >= AlState::SafeOp && sm.is_some() {
                    self.read(p0, &mut data[d0..d0 + n]);
                    read_hit = true;
                }
            }
            if ty & 2 != 0 && cmd.writes() {
                // outputs are taken in OP only
                if self.al_state == AlState::Op && sm.is_some() {
                    self.write(p0, &incoming[d0..d0 + n], app);
                    write_hit = true;
                }
            }
        }
        let mut wkc = 0;
        if read_hit {
            wkc += 1;
        }
        if write_hit {
            wkc += if cmd == Cmd::Lrw { 2 } else { 1 };
        }
        if cmd == Cmd::Lrw && !write_hit && self.al_state == AlState::SafeOp {
            // SAFE-OP: the frame still clocks an SM-synchronous input cycle
            self.cycle_due = true;
        }
        wkc
    }

    /// Read registers or memory; true if the read emptied SM1.
    fn read(&mut self, ado: usize, data: &mut [u8]) -> bool {
        let n = data.len();
        // live registers
        let st = self.system_time_ns();
        self.set_u64(REG_DC_SYSTEM_TIME, st);
        data.copy_from_slice(&self.mem[ado..ado + n]);
        // reading the last byte of the SM1 mailbox empties it
        let sm1 = self.sync_manager(1);
        if self.sm1_full && sm1.contains_last_byte(ado, n) {
            self.sm1_full = false;
            if let Some(next) = self.pending.pop_front() {
                self.load_sm1(next);
            }
            self.publish_sm_status();
            return true;
        }
        false
    }

    /// After the master read SM1: a request held in SM0 gets its answer
    /// now that there is room, and device messages follow.
    fn after_sm1_read(&mut self, app: &mut dyn Application) {
        if self.pending.len() < MAX_PENDING_MAILBOX {
            if let Some(req) = self.sm0_held.take() {
                self.handle_request(req, app);
            }
        }
        self.poll_outgoing(app);
    }

    fn handle_request(&mut self, req: Vec<u8>, app: &mut dyn Application) {
        self.stats.mailbox_requests += 1;
        if let Some(answer) = app.mailbox(&req, self.al_state) {
            self.send_mailbox(answer);
        }
        self.publish_sm_status();
    }

    fn load_sm1(&mut self, mut answer: Vec<u8>) {
        let sm1 = self.sync_manager(1);
        let s = usize::from(sm1.start);
        answer.resize(usize::from(sm1.len), 0);
        if s + answer.len() <= MEMORY_SIZE {
            self.mem[s..s + answer.len()].copy_from_slice(&answer);
            self.sm1_full = true;
            self.last_sm1 = answer;
        }
    }

    fn write(&mut self, ado: usize, data: &[u8], app: &mut dyn Application) {
        let end = ado + data.len();
        let touches = |a: usize, n: usize| ado < a + n && end > a;
        for (i, b) in data.iter().enumerate() {
            let a = ado + i;
            if Self::writable(a) {
                self.mem[a] = *b;
            }
        }
        if touches(REG_AL_CONTROL, 2) {
            self.al_control(app);
        }
        if touches(REG_SII_CONTROL, 2) {
            self.sii_command();
        }
        if touches(REG_DC_PORT0, 4) {
            // a write to the port-0 receive time latches the receive times
            let t = self.time_ns;
            self.mem[REG_DC_PORT0..REG_DC_PORT0 + 4].copy_from_slice(&(t as u32).to_le_bytes());
            self.mem[REG_DC_PORT0 + 4..REG_DC_PORT0 + 16].fill(0);
            self.set_u64(REG_DC_RECEIVE_TIME, t);
        }
        if touches(REG_DC_ACTIVATION, 1)
            || touches(REG_DC_START, 8)
            || touches(REG_DC_SYNC0_CYCLE, 4)
        {
            self.next_sync0_ns = None;
            self.check_sync0_in_operation(app);
        }
        // SM1 repeat request (activate register bit 1 toggled): the last
        // answer again, acknowledged in the PDI control register bit 1
        let sm1_activate = REG_SM + 8 + 6;
        if touches(sm1_activate, 1) {
            let repeat = self.mem[sm1_activate] & 0x02;
            let ack = REG_SM + 8 + 7;
            if self.mem[ack] & 0x02 != repeat {
                if !self.sm1_full && !self.last_sm1.is_empty() {
                    let last = std::mem::take(&mut self.last_sm1);
                    self.load_sm1(last);
                }
                self.stats.mailbox_repeats += 1;
                self.mem[ack] = (self.mem[ack] & !0x02) | repeat;
                self.publish_sm_status();
            }
        }
        // mailbox request complete?
        let sms = self.sms();
        if sms[0].contains_last_byte(ado, data.len()) && sms[0].control & 0x03 == 0x02 {
            let s = usize::from(sms[0].start);
            let req = self.mem[s..s + usize::from(sms[0].len)].to_vec();
            if self.pending.len() >= MAX_PENDING_MAILBOX {
                self.sm0_held = Some(req);
                self.publish_sm_status();
            } else {
                self.handle_request(req, app);
            }
        }
        // outputs complete?
        if sms[2].contains_last_byte(ado, data.len()) {
            let s = usize::from(sms[2].start);
            self.outputs = self.mem[s..s + usize::from(sms[2].len)].to_vec();
            self.last_output_ns = self.time_ns;
            self.cycle_due = true;
            self.fresh_outputs = true;
        }
    }

    fn writable(a: usize) -> bool {
        match a {
            0x0000..=0x000F => false, // device information
            0x0110..=0x0111 => false, // DL status
            0x0130..=0x0135 => false, // AL status, status code
            0x0440..=0x0443 => false, // watchdog status and counters
            0x0508..=0x050F => false, // SII data (read only here: no EEPROM writes)
            0x0900..=0x091F => false, // DC receive and system times (handled above)
            // SM status and PDI control (the device's side)
            a if (REG_SM..REG_SM + 0x80).contains(&a) && matches!((a - REG_SM) % 8, 5 | 7) => false,
            a => a < MEMORY_SIZE,
        }
    }

    fn sii_command(&mut self) {
        let ctl = self.mem[REG_SII_CONTROL + 1];
        if ctl & 0x01 != 0 {
            // read: 8 bytes from the word address
            let word = self.u32_at(REG_SII_ADDRESS) as usize;
            for i in 0..8 {
                self.mem[REG_SII_DATA + i] = self.sii.get(2 * word + i).copied().unwrap_or(0xFF);
            }
        }
        // command done at once: clear read/write/reload and error bits, keep 8-byte reads
        self.mem[REG_SII_CONTROL + 1] = 0;
        self.mem[REG_SII_CONTROL] = (self.mem[REG_SII_CONTROL] & 0x01) | 0x40;
        // the PDI never owns the EEPROM here
        self.mem[REG_SII_CONFIG + 1] = 0;
    }

    fn al_control(&mut self, app: &mut dyn Application) {
        let ctl = self.mem[REG_AL_CONTROL];
        let ack = ctl & 0x10 != 0;
        if ack {
            self.al_error = false;
            self.al_code = 0;
        }
        let Some(to) = AlState::from_bits(ctl) else {
            let requested = ctl & 0x0F;
            if requested == 3 {
                self.fail(al_code::BOOTSTRAP_NOT_SUPPORTED);
            } else if requested != 0 {
                self.fail(al_code::UNKNOWN_STATE);
            }
            self.publish_al();
            return;
        };
        if self.al_error && !ack && to > self.al_state {
            // an error must be acknowledged before going up
            self.publish_al();
            return;
        }
        let from = self.al_state;
        if to == from {
            self.publish_al();
            return;
        }
        let valid = to < from
            || matches!(
                (from, to),
                (AlState::Init, AlState::PreOp)
                    | (AlState::PreOp, AlState::SafeOp)
                    | (AlState::SafeOp, AlState::Op)
            );
        if !valid {
            self.fail(al_code::INVALID_STATE_CHANGE);
            self.publish_al();
            return;
        }
        let sms = self.sms();
        let check = match (from, to) {
            (AlState::Init, AlState::PreOp) => self.check_mailbox_sms(&sms),
            (AlState::PreOp, AlState::SafeOp) if app.wants_sync0() => match self.sync0_cycle_ns() {
                None => Err(al_code::INVALID_DC_SYNC),
                Some(c) if !app.accepts_sync0_cycle(c) => Err(al_code::DC_SYNC0_CYCLE_TIME),
                Some(_) => Ok(()),
            },
            _ => Ok(()),
        };
        match check.and_then(|_| app.al_change(from, to, &sms)) {
            Ok(()) => {
                self.al_state = to;
                if from < AlState::SafeOp {
                    // free-run cycles count from here
                    self.last_cycle_ns = self.time_ns;
                }
                if to == AlState::Op {
                    self.last_output_ns = self.time_ns;
                    self.watchdog_expired = false;
                }
                if to < AlState::SafeOp {
                    self.outputs.clear();
                }
                if to == AlState::Init {
                    self.pending.clear();
                    self.sm1_full = false;
                    self.sm0_held = None;
                    self.last_sm1.clear();
                    self.publish_sm_status();
                }
                if to >= AlState::PreOp {
                    self.poll_outgoing(app);
                }
            }
            Err(code) => self.fail(code),
        }
        self.publish_al();
    }

    /// The master changed SYNC0 while the application runs on it: a cycle
    /// it does not run with ends OP (SAFE-OP with AL code 0x0036).
    fn check_sync0_in_operation(&mut self, app: &mut dyn Application) {
        if self.al_state < AlState::SafeOp || !app.wants_sync0() {
            return;
        }
        let ok = match self.sync0_cycle_ns() {
            Some(c) => app.accepts_sync0_cycle(c),
            // SYNC0 switched off: the cycle waits (the watchdog guards OP)
            None => true,
        };
        if !ok {
            let from = self.al_state;
            if from == AlState::Op {
                let sms = self.sms();
                let _ = app.al_change(from, AlState::SafeOp, &sms);
                self.al_state = AlState::SafeOp;
            }
            self.fail(al_code::DC_SYNC0_CYCLE_TIME);
            self.publish_al();
        }
    }

    fn fail(&mut self, code: u16) {
        self.al_error = true;
        self.al_code = code;
    }

    fn check_mailbox_sms(&self, sms: &[SyncManager; 4]) -> Result<(), u16> {
        let w = |i: usize| u16::from_le_bytes([self.sii[2 * i], self.sii[2 * i + 1]]);
        // SII words 0x18-0x1B: standard receive (SM0) and send (SM1) mailbox offset and size
        let ok0 = sms[0].enabled && sms[0].start == w(0x18) && sms[0].len == w(0x19);
        let ok1 = sms[1].enabled && sms[1].start == w(0x1A) && sms[1].len == w(0x1B);
        if ok0 && ok1 {
            Ok(())
        } else {
            Err(al_code::INVALID_MAILBOX_CONFIG)
        }
    }
}

#[cfg(test)]
mod standard_tests;
#[cfg(test)]
mod tests;
