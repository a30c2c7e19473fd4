//! The ESC against hand-built frames: working counters of ETG.1000.4 table 11
//! ff., the SII read protocol, the AL state machine and its error codes, the
//! mailbox hand-shake, FMMU mapping, SYNC0 and the watchdog.

use super::frame::{self, Cmd};
use super::sii::{Identity, SiiContent, SiiSyncManager};
use super::*;

pub(super) const SRC: [u8; 6] = [0x10; 6];

#[derive(Default)]
pub(super) struct App {
    pub(super) cycles: Vec<(u64, bool, Vec<u8>)>,
    pub(super) watchdog: bool,
    pub(super) sync0: bool,
    pub(super) mailbox: Vec<Vec<u8>>,
}

impl Application for App {
    fn al_change(
        &mut self,
        _from: AlState,
        _to: AlState,
        _sms: &[SyncManager; 4],
    ) -> Result<(), u16> {
        Ok(())
    }
    fn mailbox(&mut self, request: &[u8], _state: AlState) -> Option<Vec<u8>> {
        self.mailbox.push(request.to_vec());
        Some(vec![0xAB; 8])
    }
    fn cycle(&mut self, t_ns: u64, op: bool, outputs: &[u8], inputs: &mut [u8]) {
        self.cycles.push((t_ns, op, outputs.to_vec()));
        for (i, b) in inputs.iter_mut().enumerate() {
            *b = i as u8 + 0x40;
        }
    }
    fn watchdog_expired(&mut self) {
        self.watchdog = true;
    }
    fn wants_sync0(&self) -> bool {
        self.sync0
    }
}

pub(super) fn esc() -> Esc {
    Esc::new(sii::build(&SiiContent {
        identity: Identity {
            vendor_id: 0x1234_5678,
            product_code: 2,
            revision: 3,
            serial: 4,
        },
        name: "test".into(),
        mailbox: (0x1000, 64, 0x1040, 64),
        sync_managers: vec![
            SiiSyncManager {
                start: 0x1000,
                len: 64,
                control: 0x26,
                ty: 1,
            },
            SiiSyncManager {
                start: 0x1040,
                len: 64,
                control: 0x22,
                ty: 2,
            },
        ],
        fmmus: vec![1, 2],
        rx_pdos: vec![],
        tx_pdos: vec![],
    }))
}

/// Send one datagram; returns (data, working counter, address field).
pub(super) fn send(
    esc: &mut Esc,
    app: &mut App,
    cmd: Cmd,
    addr: u32,
    data: &[u8],
) -> (Vec<u8>, u16, u32) {
    let mut f = frame::build(SRC, &[(cmd, addr, data)]);
    assert!(esc.process_frame(&mut f, app));
    assert_eq!(f[6], 0x12, "source MAC with the locally administered bit");
    let d = frame::datagrams(&f).unwrap()[0];
    let a = u32::from_le_bytes(f[d.start + 2..d.start + 6].try_into().unwrap());
    let w = u16::from_le_bytes([f[d.wkc()], f[d.wkc() + 1]]);
    (f[d.data()..d.data() + d.len].to_vec(), w, a)
}

pub(super) fn fp(station: u16, reg: u16) -> u32 {
    u32::from(station) | (u32::from(reg) << 16)
}

pub(super) fn sm(start: u16, len: u16, control: u8, enable: u8) -> Vec<u8> {
    let mut v = start.to_le_bytes().to_vec();
    v.extend_from_slice(&len.to_le_bytes());
    v.extend_from_slice(&[control, 0, enable, 0]);
    v
}

pub(super) fn to_preop(e: &mut Esc, a: &mut App) {
    send(
        e,
        a,
        Cmd::Fpwr,
        fp(0x1001, 0x0800),
        &sm(0x1000, 64, 0x26, 1),
    );
    send(
        e,
        a,
        Cmd::Fpwr,
        fp(0x1001, 0x0808),
        &sm(0x1040, 64, 0x22, 1),
    );
    send(e, a, Cmd::Fpwr, fp(0x1001, 0x0120), &[2, 0]);
    assert_eq!(e.al_state(), AlState::PreOp);
}

#[test]
fn working_counters_follow_the_standard() {
    let (mut e, mut a) = (esc(), App::default());
    // BRD of the type register: one device answers, +1
    let (d, w, adp) = send(&mut e, &mut a, Cmd::Brd, 0, &[0]);
    assert_eq!((d[0], w, adp & 0xFFFF), (0x11, 1, 1));
    // APWR to position 0 sets the station address, +1; the ADP is incremented
    let (_, w, adp) = send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    assert_eq!((w, adp & 0xFFFF), (1, 1));
    // APRD to position 1 is for a device behind this one: no answer here
    let (_, w, _) = send(&mut e, &mut a, Cmd::Aprd, 1 | (0x0010 << 16), &[0, 0]);
    assert_eq!(w, 0);
    // FPRD with the station address reads it back
    let (d, w, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0010), &[0, 0]);
    assert_eq!((u16::from_le_bytes([d[0], d[1]]), w), (0x1001, 1));
    // another station address: not addressed
    let (_, w, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1002, 0x0010), &[0, 0]);
    assert_eq!(w, 0);
    // FPRW reads the old value and writes the new one: +3
    let (d, w, _) = send(
        &mut e,
        &mut a,
        Cmd::Fprw,
        fp(0x1001, 0x0012),
        &0xBEEFu16.to_le_bytes(),
    );
    assert_eq!((d, w), (vec![0, 0], 3));
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0012), &[0, 0]);
    assert_eq!(d, 0xBEEFu16.to_le_bytes());
    // read-only registers keep their value under a write (still counted)
    let (_, w, _) = send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0000), &[0x99]);
    assert_eq!(w, 1);
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0000), &[0]);
    assert_eq!(d, [0x11]);
    // several datagrams in one frame, each with its own counter
    let mut f = frame::build(
        SRC,
        &[
            (Cmd::Brd, 0, &[0]),
            (Cmd::Fprd, fp(0x1001, 0x0010), &[0, 0]),
            (Cmd::Nop, 0, &[0]),
        ],
    );
    e.process_frame(&mut f, &mut a);
    let wk: Vec<u16> = frame::datagrams(&f)
        .unwrap()
        .iter()
        .map(|d| u16::from_le_bytes([f[d.wkc()], f[d.wkc() + 1]]))
        .collect();
    assert_eq!(wk, [1, 1, 0]);
    // not an EtherCAT frame: untouched
    let mut ip = frame::build(SRC, &[(Cmd::Brd, 0, &[0])]);
    ip[12] = 0x08;
    ip[13] = 0x00;
    let copy = ip.clone();
    assert!(!e.process_frame(&mut ip, &mut a));
    assert_eq!(ip, copy);
}

#[test]
fn the_sii_is_read_through_the_eeprom_interface() {
    let (mut e, mut a) = (esc(), App::default());
    send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    // request a read of word 0x08 (vendor ID, product code) as ethercrab does: control + address
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0502),
        &[0x00, 0x01, 0x08, 0x00, 0x00, 0x00],
    );
    let (ctl, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0502), &[0, 0]);
    assert_eq!(ctl[1] & 0x80, 0, "not busy");
    assert_eq!(ctl[0] & 0x40, 0x40, "8-byte reads");
    let (d, w, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0508), &[0; 8]);
    assert_eq!(w, 1);
    assert_eq!(u32::from_le_bytes(d[0..4].try_into().unwrap()), 0x1234_5678);
    assert_eq!(u32::from_le_bytes(d[4..8].try_into().unwrap()), 2);
    // word 0x40: the first category (strings, type 10)
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0502),
        &[0x00, 0x01, 0x40, 0x00, 0x00, 0x00],
    );
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0508), &[0; 8]);
    assert_eq!(u16::from_le_bytes([d[0], d[1]]), 10);
    assert_eq!(&d[5..8], b"\x04te");
}

#[test]
fn the_al_state_machine_checks_its_transitions() {
    let (mut e, mut a) = (esc(), App::default());
    send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    // INIT -> OP directly is not allowed
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[8, 0]);
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0130), &[0; 6]);
    assert_eq!(d[0], 0x11, "INIT with the error bit");
    assert_eq!(
        u16::from_le_bytes([d[4], d[5]]),
        al_code::INVALID_STATE_CHANGE
    );
    // PRE-OP without mailbox sync managers: invalid mailbox configuration
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[0x12, 0]);
    assert_eq!(e.al_state(), AlState::Init);
    assert_eq!(e.al_status_code(), al_code::INVALID_MAILBOX_CONFIG);
    // with them (acknowledging the error)
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0800),
        &sm(0x1000, 64, 0x26, 1),
    );
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0808),
        &sm(0x1040, 64, 0x22, 1),
    );
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[0x12, 0]);
    assert_eq!((e.al_state(), e.al_status_code()), (AlState::PreOp, 0));
    // an application that wants SYNC0 refuses SAFE-OP without it
    a.sync0 = true;
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[4, 0]);
    assert_eq!(
        (e.al_state(), e.al_status_code()),
        (AlState::PreOp, al_code::INVALID_DC_SYNC)
    );
    // bootstrap is not supported; going down is always allowed
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[0x13, 0]);
    assert_eq!(e.al_status_code(), al_code::BOOTSTRAP_NOT_SUPPORTED);
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[0x11, 0]);
    assert_eq!((e.al_state(), e.al_status_code()), (AlState::Init, 0));
}

#[test]
fn a_mailbox_request_is_answered_once_through_sm1() {
    let (mut e, mut a) = (esc(), App::default());
    send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    to_preop(&mut e, &mut a);
    let status = |e: &mut Esc, a: &mut App| send(e, a, Cmd::Fprd, fp(0x1001, 0x080D), &[0]).0[0];
    assert_eq!(status(&mut e, &mut a) & 0x08, 0, "SM1 empty");
    // a partial write is not a request yet
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x1000), &[1; 32]);
    assert!(a.mailbox.is_empty());
    // writing up to the last byte hands it over
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x1020), &[2; 32]);
    assert_eq!(a.mailbox.len(), 1);
    assert_eq!(
        &a.mailbox[0][..33],
        &[[1u8; 32].as_slice(), &[2]].concat()[..]
    );
    assert_eq!(status(&mut e, &mut a) & 0x08, 0x08, "SM1 full");
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x1040), &[0; 64]);
    assert_eq!(&d[..8], &[0xAB; 8]);
    assert_eq!(
        status(&mut e, &mut a) & 0x08,
        0,
        "read to the end: empty again"
    );
}

#[test]
fn process_data_goes_through_the_fmmus_with_state_dependent_counters() {
    let (mut e, mut a) = (esc(), App::default());
    send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    to_preop(&mut e, &mut a);
    // SM2 outputs 3 bytes at 0x1100 (watchdog on), SM3 inputs 4 bytes at 0x1180
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0810),
        &sm(0x1100, 3, 0x64, 1),
    );
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0818),
        &sm(0x1180, 4, 0x20, 1),
    );
    // FMMU0: logical 0x10000+4..+7 -> outputs (write); FMMU1: logical 0x10000..+4 -> inputs (read)
    let fmmu = |log: u32, len: u16, phys: u16, ty: u8| {
        let mut v = log.to_le_bytes().to_vec();
        v.extend_from_slice(&len.to_le_bytes());
        v.extend_from_slice(&[0, 7]);
        v.extend_from_slice(&phys.to_le_bytes());
        v.extend_from_slice(&[0, ty, 1, 0, 0, 0]);
        v
    };
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0600),
        &fmmu(0x10004, 3, 0x1100, 2),
    );
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0610),
        &fmmu(0x10000, 4, 0x1180, 1),
    );
    let pd = [0, 0, 0, 0, 7, 8, 9];
    // PRE-OP: no process data
    let (_, w, _) = send(&mut e, &mut a, Cmd::Lrw, 0x10000, &pd);
    assert_eq!(w, 0);
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[4, 0]);
    assert_eq!(e.al_state(), AlState::SafeOp);
    // SAFE-OP: inputs (+1), outputs ignored; the frame clocks an SM-synchronous cycle
    let (d, w, _) = send(&mut e, &mut a, Cmd::Lrw, 0x10000, &pd);
    assert_eq!(w, 1);
    assert_eq!(&d[4..], &[7, 8, 9], "outputs pass unchanged");
    assert_eq!(a.cycles.len(), 1);
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[8, 0]);
    assert_eq!(e.al_state(), AlState::Op);
    // OP: LRW +3, the inputs of the last cycle come back, the outputs reach the application
    let (d, w, _) = send(&mut e, &mut a, Cmd::Lrw, 0x10000, &pd);
    assert_eq!(w, 3);
    assert_eq!(&d[..4], &[0x40, 0x41, 0x42, 0x43]);
    assert_eq!(a.cycles.last().unwrap(), &(0, true, vec![7, 8, 9]));
    // LRD +1, LWR +1
    assert_eq!(send(&mut e, &mut a, Cmd::Lrd, 0x10000, &[0; 4]).1, 1);
    assert_eq!(send(&mut e, &mut a, Cmd::Lwr, 0x10004, &[1, 2, 3]).1, 1);
    // a logical range outside the FMMUs: nothing
    assert_eq!(send(&mut e, &mut a, Cmd::Lrw, 0x20000, &pd).1, 0);
    // watchdog: 100 ms without outputs -> SAFE-OP, error 0x001B, the application told
    e.advance_to(50_000_000, &mut a);
    assert_eq!(e.al_state(), AlState::Op);
    e.advance_to(100_000_001, &mut a);
    assert!(a.watchdog);
    assert_eq!(
        (e.al_state(), e.al_status_code()),
        (AlState::SafeOp, al_code::SM_WATCHDOG)
    );
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0440), &[0]);
    assert_eq!(d[0] & 1, 0, "watchdog status: expired");
}

#[test]
fn sync0_runs_the_application_once_per_period_in_system_time() {
    let (mut e, mut a) = (esc(), App::default());
    send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    to_preop(&mut e, &mut a);
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0818),
        &sm(0x1180, 4, 0x20, 1),
    );
    e.advance_to(5_000, &mut a);
    // latch receive times with a write to 0x0900, read the receive time
    send(&mut e, &mut a, Cmd::Bwr, 0x0900 << 16, &[0; 4]);
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0918), &[0; 8]);
    assert_eq!(u64::from_le_bytes(d.try_into().unwrap()), 5_000);
    // system time offset +1 ms: system time = local + offset
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0920),
        &1_000_000u64.to_le_bytes(),
    );
    let (d, w, _) = send(&mut e, &mut a, Cmd::Frmw, fp(0x1001, 0x0910), &[0; 8]);
    assert_eq!(
        (u64::from_le_bytes(d.try_into().unwrap()), w),
        (1_005_000, 1)
    );
    // SYNC0 every 250 us from system time 1.1 ms (local 0.1 ms)
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0990),
        &1_100_000u64.to_le_bytes(),
    );
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x09A0),
        &250_000u32.to_le_bytes(),
    );
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0981), &[3]);
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[4, 0]);
    assert_eq!(e.al_state(), AlState::SafeOp);
    e.advance_to(1_000_000, &mut a);
    let times: Vec<u64> = a.cycles.iter().map(|c| c.0).collect();
    assert_eq!(times, [100_000, 350_000, 600_000, 850_000]);
}
