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
//! goes to "fault" with error code 0x8130 (communication: life guard error);
//! the inputs show it at the master's next read, and a CoE emergency
//! (error code, error register 0x1001) goes into the mailbox, as for every
//! fault (and one with code 0 when a fault reset clears it).
//!
//! The process data is the object dictionary's: each cycle the mapped
//! outputs are written into their objects and the mapped inputs read from
//! theirs, so any mapping of the mappable objects works, and an object not
//! mapped keeps what an SDO wrote (0x6060 written by SDO selects the mode
//! for an RxPDO without it). The objects behind the inputs are current from
//! power-up on (0x6041 reads "switch on disabled" in PRE-OP).

use crate::cia402::{self, Command, State, MODE_CSP, MODE_CST};
use crate::esc::{al_code, coe, AlState, Application, Esc, SyncManager};
use crate::objects::{self, ObjectValues, ERROR_REGISTER, TORQUE_OFFSET};
use crate::od::Dictionary;
use crate::pdo::{self, Layout};
use crate::scaling::Scaling;
use crate::Error;
use beltune::axis::Axis as _;
use beltune::model::rigs::Plant;
use beltune::sim::{SimAxis, SimConfig};
use beltune_rt::control::{CascadeController, MotionSample, Setpoint};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;

pub use crate::objects::{IDENTITY, NAME};

/// Error code for the SM watchdog (CiA 301: life guard error or heartbeat error).
pub const ERROR_WATCHDOG: u16 = 0x8130;
/// Error code when the bus leaves OP with the power stage on (CiA 301: communication).
pub const ERROR_COMMUNICATION: u16 = 0x8100;

/// Default length of each mailbox sync manager, bytes (SM0 at 0x1000 and
/// SM1 at 0x1080 leave room for at most 128).
pub const MAILBOX_LEN: u16 = 128;
/// Shortest mailbox the drive accepts, bytes (a segmented SDO needs 16).
pub const MAILBOX_MIN: u16 = 32;
/// Emergencies kept for the mailbox at most (older ones are dropped).
const MAX_EMERGENCIES: usize = 8;

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
    /// Output and input layouts of the assigned mapping (from SAFE-OP on).
    layouts: Option<(Layout, Layout)>,
    faults: Arc<Faults>,
    cfg: DriveConfig,
    load_nm_per_inc: u32,
    last_torque_nm: f64,
    cycles: u64,
    quick_stop_damping: f64,
    sdo: coe::SdoServer,
    /// The latest values behind the inputs.
    position_inc: i32,
    velocity_inc_s: i32,
    torque_permille: i16,
    load_position_inc: Option<i32>,
    emergencies: std::collections::VecDeque<Vec<u8>>,
    emergency_counter: u8,
    /// The dictionary as it is at power-up (the ESI's default values).
    power_up: Dictionary,
    /// Motor encoder counts of the last cycle.
    motor_counts: i64,
    /// The drive's own loops in CSP, with their preview in cycles.
    loops: Option<(CascadeController<f32>, usize)>,
    /// CSP setpoints of the last `preview + 1` cycles, oldest first.
    csp_setpoints: std::collections::VecDeque<MotionSample<f64>>,
    csp_last_velocity_rad_s: f64,
    following_error_inc: i32,
}

/// Error code when the loop parameters do not make a controller (CiA 402:
/// parameter error).
pub const ERROR_PARAMETER: u16 = 0x6320;

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
        let od = objects::dictionary(&ObjectValues {
            scaling,
            cycle_ns,
            load_nm_per_inc,
        });
        let sii = crate::esc::sii::build(&objects::sii_content(&od, cfg.mailbox_bytes));
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
        let initial_position = cfg.initial_position_inc;
        let mut firmware = Firmware {
            od,
            sim,
            scaling,
            cycle_ns,
            // transitions 0 and 1 (self-test, initialisation) are done at power-up
            state: State::SwitchOnDisabled,
            prev_cw: 0,
            mode_display: 0,
            error_code: 0,
            layouts: None,
            faults: Arc::new(Faults::default()),
            cfg,
            load_nm_per_inc,
            last_torque_nm: 0.0,
            cycles: 0,
            quick_stop_damping,
            sdo: coe::SdoServer::new(),
            position_inc: initial_position,
            velocity_inc_s: 0,
            torque_permille: 0,
            load_position_inc: None,
            emergencies: Default::default(),
            emergency_counter: 0,
            power_up: Dictionary::new(),
            motor_counts: 0,
            loops: None,
            csp_setpoints: Default::default(),
            csp_last_velocity_rad_s: 0.0,
            following_error_inc: 0,
        };
        firmware.load_position_inc = firmware.load_increments(firmware.sim.cart_position_m());
        firmware.publish();
        firmware.power_up = firmware.od.clone();
        let mut esc = Esc::new(sii);
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

    /// The drive's ESI file (ETG.2000 XML), from the dictionary and the SII
    /// it serves.
    pub fn esi(&self) -> String {
        let od = &self.firmware.power_up;
        let sii = objects::sii_content(od, self.firmware.cfg.mailbox_bytes);
        crate::esi::esi(od, &sii, self.firmware.cycle_ns)
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

    /// The mode of operation the drive runs (0x6061).
    pub fn mode_display(&self) -> i8 {
        self.mode_display
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

    /// The object dictionary.
    pub fn objects(&self) -> &Dictionary {
        &self.od
    }

    fn fault(&mut self, code: u16) {
        if !matches!(self.state, State::Fault | State::FaultReactionActive) {
            self.state = State::FaultReactionActive;
            self.error_code = code;
            self.emergency(code);
        }
    }

    /// Queue a CoE emergency for `code` (0: error reset), with the error
    /// register 0x1001 it sets: generic error, plus "communication" for the
    /// 0x81xx codes.
    fn emergency(&mut self, code: u16) {
        let register = match code {
            0 => 0,
            0x8100..=0x81FF => 0x11,
            _ => 0x01,
        };
        self.od.set(ERROR_REGISTER, 0, &[register]);
        if self.emergencies.len() >= MAX_EMERGENCIES {
            self.emergencies.pop_front();
        }
        self.emergency_counter = self.emergency_counter % 7 + 1;
        self.emergencies.push_back(coe::emergency(
            self.emergency_counter,
            code,
            register,
            [0; 5],
        ));
    }

    fn sync_mode_dc(&self) -> bool {
        self.od.get_uint(0x1C32, 1) == Some(2)
    }

    fn load_increments(&self, cart_m: f64) -> Option<i32> {
        cart_m.is_finite().then(|| {
            (cart_m * 1e9 / f64::from(self.load_nm_per_inc))
                .round()
                .clamp(i32::MIN as f64, i32::MAX as f64) as i32
        })
    }

    fn statusword(&self) -> u16 {
        let mut sw = self.state.statusword_bits() | cia402::SW_REMOTE;
        if !matches!(
            self.state,
            State::SwitchOnDisabled | State::NotReadyToSwitchOn | State::Fault
        ) {
            sw |= cia402::SW_VOLTAGE_ENABLED;
        }
        if self.state == State::OperationEnabled
            && (self.mode_display == MODE_CST || self.mode_display == MODE_CSP)
        {
            sw |= cia402::SW_FOLLOWS_TARGET;
        }
        sw
    }

    /// Enter CSP: the loops from the manufacturer objects, started
    /// bumplessly at the present angle. Error code if they make no controller.
    fn start_loops(&mut self) -> Result<(), u16> {
        let od = &self.od;
        let (c, preview) =
            crate::loops::config_from(self.cfg.cycle_s, |i, s| od.get(i, s).map(<[u8]>::to_vec))
                .ok_or(ERROR_PARAMETER)?;
        let mut ctrl = CascadeController::new(c.cast::<f32>()).map_err(|_| ERROR_PARAMETER)?;
        let phi = self.motor_angle_rad();
        ctrl.reset_to(phi as f32);
        self.loops = Some((ctrl, preview));
        self.csp_setpoints.clear();
        let hold = MotionSample {
            angle_rad: phi,
            velocity_rad_s: 0.0,
            acceleration_rad_s2: 0.0,
        };
        self.csp_setpoints
            .extend(std::iter::repeat_n(hold, preview + 1));
        self.csp_last_velocity_rad_s = 0.0;
        Ok(())
    }

    fn motor_angle_rad(&self) -> f64 {
        self.motor_counts as f64 * self.sim.info().motor_rad_per_count
    }

    /// One cycle of the drive's loops: the setpoint of this cycle (target
    /// position 0x607A and velocity offset 0x60B1, increments; acceleration
    /// from the velocity's change) is the feedforward's preview, the one
    /// `preview` cycles before is the loops' (the master sends the
    /// trajectory `n_T` cycles ahead); the torque command, N m.
    fn loops_torque(&mut self) -> f64 {
        let q = self.sim.info().motor_rad_per_count;
        let phi = self.motor_angle_rad();
        let target = self
            .od
            .get_uint(crate::objects::TARGET_POSITION, 0)
            .unwrap_or(0) as u32 as i32;
        let velocity = self
            .od
            .get_uint(crate::objects::VELOCITY_OFFSET, 0)
            .unwrap_or(0) as u32 as i32;
        let omega = f64::from(velocity) * q;
        let ahead = MotionSample {
            angle_rad: phi + f64::from(target.wrapping_sub(self.position_inc)) * q,
            velocity_rad_s: omega,
            acceleration_rad_s2: (omega - self.csp_last_velocity_rad_s) / self.cfg.cycle_s,
        };
        self.csp_last_velocity_rad_s = omega;
        let Some((ctrl, preview)) = self.loops.as_mut() else {
            return 0.0;
        };
        self.csp_setpoints.push_back(ahead);
        while self.csp_setpoints.len() > *preview + 1 {
            self.csp_setpoints.pop_front();
        }
        let now = self.csp_setpoints.front().copied().unwrap_or(ahead);
        let f = |m: MotionSample<f64>| MotionSample {
            angle_rad: m.angle_rad as f32,
            velocity_rad_s: m.velocity_rad_s as f32,
            acceleration_rad_s2: m.acceleration_rad_s2 as f32,
        };
        let out = ctrl.step(&Setpoint::with_preview(f(now), f(ahead)), phi as f32);
        self.following_error_inc = ((now.angle_rad - phi) / q)
            .round()
            .clamp(i32::MIN as f64, i32::MAX as f64) as i32;
        f64::from(out.torque_nm)
    }

    /// The objects behind the inputs, from the drive's present state.
    fn publish(&mut self) {
        let sw = self.statusword();
        self.od.set(cia402::STATUSWORD, 0, &sw.to_le_bytes());
        self.od
            .set(cia402::ERROR_CODE, 0, &self.error_code.to_le_bytes());
        self.od.set(
            cia402::MODES_OF_OPERATION_DISPLAY,
            0,
            &[self.mode_display as u8],
        );
        self.od
            .set(pdo::POSITION_ACTUAL, 0, &self.position_inc.to_le_bytes());
        self.od
            .set(pdo::VELOCITY_ACTUAL, 0, &self.velocity_inc_s.to_le_bytes());
        self.od
            .set(pdo::TORQUE_ACTUAL, 0, &self.torque_permille.to_le_bytes());
        self.od.set(
            crate::objects::FOLLOWING_ERROR,
            0,
            &self.following_error_inc.to_le_bytes(),
        );
        if let Some(l) = self.load_position_inc {
            self.od
                .set(pdo::ADDITIONAL_POSITION_ACTUAL, 1, &l.to_le_bytes());
        }
    }

    /// Copy the mapped inputs' objects into the SM3 image.
    fn pack_inputs(&self, inputs: &mut [u8]) {
        let Some((_, inp)) = &self.layouts else {
            return;
        };
        for e in inp.entries() {
            let (Some((o, n)), Some(v)) = (
                inp.find(e.index, e.sub_index),
                self.od.get(e.index, e.sub_index),
            ) else {
                continue;
            };
            if let Some(dst) = inputs.get_mut(o..o + n) {
                let k = n.min(v.len());
                dst[..k].copy_from_slice(&v[..k]);
            }
        }
    }

    /// Write the mapped outputs into their objects (`op`), or zeros (the
    /// outputs are not valid outside OP).
    fn unpack_outputs(&mut self, outputs: &[u8], op: bool) {
        let Some((out, _)) = self.layouts.clone() else {
            return;
        };
        for e in out.entries() {
            let Some((o, n)) = out.find(e.index, e.sub_index) else {
                continue;
            };
            let zero = vec![0u8; n];
            let v = if op {
                outputs.get(o..o + n).unwrap_or(&zero)
            } else {
                &zero
            };
            self.od.set(e.index, e.sub_index, v);
        }
    }

    fn od_i16(&self, index: u16) -> i16 {
        self.od.get_uint(index, 0).unwrap_or(0) as u16 as i16
    }
}

impl Application for Firmware {
    fn al_change(&mut self, from: AlState, to: AlState, sms: &[SyncManager; 4]) -> Result<(), u16> {
        if from == AlState::PreOp && to == AlState::SafeOp {
            let out = Layout::new(&self.od.assigned_mapping(pdo::SM2_ASSIGN))
                .map_err(|_| al_code::INVALID_OUTPUT_CONFIG)?;
            let inp = Layout::new(&self.od.assigned_mapping(pdo::SM3_ASSIGN))
                .map_err(|_| al_code::INVALID_INPUT_CONFIG)?;
            let (sm2, sm3) = (objects::SM2_START, objects::SM3_START);
            let sm_ok = |sm: &SyncManager, start: u16, len: usize| {
                if len == 0 {
                    !sm.enabled || sm.len == 0
                } else {
                    sm.enabled && sm.start == start && usize::from(sm.len) == len
                }
            };
            if !sm_ok(&sms[2], sm2, out.len()) {
                return Err(al_code::INVALID_OUTPUT_CONFIG);
            }
            if !sm_ok(&sms[3], sm3, inp.len()) {
                return Err(al_code::INVALID_INPUT_CONFIG);
            }
            self.layouts = Some((out, inp));
        }
        if to < AlState::SafeOp {
            self.layouts = None;
        }
        if from == AlState::Op && self.state.torque_enabled() {
            self.fault(ERROR_COMMUNICATION);
            self.publish();
        }
        Ok(())
    }

    fn mailbox(&mut self, request: &[u8], state: AlState) -> Option<Vec<u8>> {
        let capacity = usize::from(self.cfg.mailbox_bytes);
        self.sdo.handle(request, &mut self.od, state, capacity)
    }

    fn outgoing(&mut self) -> Option<Vec<u8>> {
        self.sdo
            .follow_up()
            .or_else(|| self.emergencies.pop_front())
    }

    fn wants_sync0(&self) -> bool {
        self.sync_mode_dc()
    }

    fn free_run_cycle_ns(&self) -> Option<u32> {
        // with the power stage off the axis coasts (and is measured) whether
        // or not the master sends; with torque the cycle follows the master
        (!self.state.torque_enabled()).then_some(self.cycle_ns)
    }

    fn accepts_sync0_cycle(&self, cycle_ns: u32) -> bool {
        // the drive runs its loops at its own cycle only
        cycle_ns == self.cycle_ns
    }

    fn watchdog_expired(&mut self) {
        self.fault(ERROR_WATCHDOG);
        // the fault reaction (remove the torque) is done at once: "fault"
        // (transition 14) without waiting for a cycle, which may not come
        // without SYNC0
        self.state = State::Fault;
        self.last_torque_nm = 0.0;
        self.publish();
    }

    fn refresh_inputs(&mut self, inputs: &mut [u8]) {
        self.publish();
        self.pack_inputs(inputs);
    }

    fn cycle(&mut self, _t_ns: u64, op: bool, outputs: &[u8], inputs: &mut [u8]) {
        self.cycles += 1;
        if self.layouts.is_none() {
            return;
        }
        self.unpack_outputs(outputs, op);
        let cw = self.od.get_uint(cia402::CONTROLWORD, 0).unwrap_or(0) as u16;
        let mode = self.od.get_uint(cia402::MODES_OF_OPERATION, 0).unwrap_or(0) as u8 as i8;
        let target =
            i32::from(self.od_i16(pdo::TARGET_TORQUE)) + i32::from(self.od_i16(TORQUE_OFFSET));
        let target = target.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
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
            self.emergency(0);
        }
        self.prev_cw = cw;
        let enabled_now = self.state == State::OperationEnabled;
        if mode == MODE_CST || mode == MODE_CSP {
            // the cyclic synchronous modes switch at any time (CiA 402);
            // CSP starts its loops when it is entered with the power on
            let entering = mode == MODE_CSP
                && enabled_now
                && (self.mode_display != MODE_CSP || before != State::OperationEnabled);
            if entering {
                if let Err(code) = self.start_loops() {
                    self.fault(code);
                }
            }
            self.mode_display = mode;
        } else if !self.state.torque_enabled() {
            self.mode_display = mode.max(0);
        }
        let omega = self.sim.motor_velocity_rad_s();
        let lim = self.scaling.torque_limit_nm();
        let torque = match self.state {
            State::OperationEnabled if self.mode_display == MODE_CST => {
                self.scaling.permille_to_nm(target).clamp(-lim, lim)
            }
            State::OperationEnabled if self.mode_display == MODE_CSP => {
                self.loops_torque().clamp(-lim, lim)
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
        self.motor_counts = m.motor_counts;
        let q = self.sim.info().motor_rad_per_count;
        self.position_inc =
            i64::from(self.cfg.initial_position_inc).wrapping_add(m.motor_counts) as i32;
        self.velocity_inc_s = (self.sim.motor_velocity_rad_s() / q)
            .round()
            .clamp(i32::MIN as f64, i32::MAX as f64) as i32;
        self.load_position_inc = m.cart_position_m.and_then(|x| self.load_increments(x));
        self.torque_permille = self.scaling.nm_to_permille(m.torque_actual_nm);
        self.publish();
        self.pack_inputs(inputs);
    }
}
