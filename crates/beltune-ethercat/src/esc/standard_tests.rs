//! Regression tests of the ESC against behaviour a real device has and a
//! real master relies on: the DL status of the last device of a line, the
//! mailbox repeat request, a bounded mailbox queue, FMMUs at the top of
//! the logical address space, SYNC0 cycles the application cannot follow.

use super::frame::Cmd;
use super::tests::{esc, fp, send, sm, to_preop, App};
use super::*;

fn addressed() -> (Esc, App) {
    let (mut e, mut a) = (esc(), App::default());
    send(
        &mut e,
        &mut a,
        Cmd::Apwr,
        0x0010 << 16,
        &0x1001u16.to_le_bytes(),
    );
    (e, a)
}

#[test]
fn the_dl_status_shows_one_open_port_with_a_link_and_a_live_pdi_watchdog() {
    let (mut e, mut a) = addressed();
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0110), &[0, 0]);
    let dl = u16::from_le_bytes([d[0], d[1]]);
    // ETG.1000.4 DL status: bit 1 PDI watchdog reloaded, bits 4-7 the
    // physical links of ports 0-3, bits 8 + 2n / 9 + 2n loop closed /
    // communication on port n
    assert_eq!(dl & 0x0003, 0x0003, "PDI operational, watchdog not expired");
    assert_eq!((dl >> 4) & 0x0F, 0x01, "a link on port 0 only");
    // SOEM counts a port as open when (loop, communication) = (0, 1): only port 0
    let open = (0..4)
        .filter(|n| (dl >> (8 + 2 * n)) & 0x03 == 0x02)
        .count();
    assert_eq!(open, 1, "{dl:#06x}: the last device of a line");
    // ports without a link have their loop closed
    for n in 1..4 {
        assert_eq!((dl >> (8 + 2 * n)) & 0x03, 0x01, "port {n} of {dl:#06x}");
    }
    // 0x0007: ports 0 and 1 MII, 2 and 3 not implemented
    let (d, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0007), &[0]);
    assert_eq!(d[0], 0x0F);
}

fn request(e: &mut Esc, a: &mut App, fill: u8) {
    send(e, a, Cmd::Fpwr, fp(0x1001, 0x1000), &[fill; 64]);
}

fn read_sm1(e: &mut Esc, a: &mut App) -> Vec<u8> {
    send(e, a, Cmd::Fprd, fp(0x1001, 0x1040), &[0; 64]).0
}

fn sm1_full(e: &mut Esc, a: &mut App) -> bool {
    send(e, a, Cmd::Fprd, fp(0x1001, 0x080D), &[0]).0[0] & 0x08 != 0
}

#[test]
fn a_mailbox_repeat_request_brings_the_last_answer_back() {
    let (mut e, mut a) = addressed();
    to_preop(&mut e, &mut a);
    request(&mut e, &mut a, 1);
    let answer = read_sm1(&mut e, &mut a);
    assert_eq!(&answer[..8], &[0xAB; 8]);
    // the answer was lost on its way back: the master toggles the repeat
    // request (SM1 activate 0x080E bit 1), as SOEM's ecx_mbxreceive does by
    // writing 0x080D-0x080E, and waits for the acknowledge in 0x080F bit 1
    let (st, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x080D), &[0, 0]);
    let toggled = u16::from_le_bytes([st[0], st[1]]) ^ 0x0200;
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x080D),
        &toggled.to_le_bytes(),
    );
    let (ack, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x080F), &[0]);
    assert_eq!(ack[0] & 0x02, 0x02, "repeat acknowledged");
    assert!(sm1_full(&mut e, &mut a), "the answer is in SM1 again");
    assert_eq!(read_sm1(&mut e, &mut a), answer);
    assert_eq!(a.mailbox.len(), 1, "the request was not handled twice");
    assert!(e.stats().mailbox_repeats == 1);
    // the SM still works: the status bit is not writable by the master
    assert!(!sm1_full(&mut e, &mut a));
}

#[test]
fn requests_without_reading_sm1_keep_the_mailbox_queue_bounded() {
    let (mut e, mut a) = addressed();
    to_preop(&mut e, &mut a);
    for k in 0..10_000u32 {
        request(&mut e, &mut a, k as u8);
    }
    let (queued, held) = e.mailbox_backlog();
    assert_eq!(queued, MAX_PENDING_MAILBOX);
    assert!(held, "the last request waits in SM0");
    assert_eq!(
        a.mailbox.len(),
        MAX_PENDING_MAILBOX + 1,
        "answered: the one in SM1 and the queue; the one in SM0 waits"
    );
    // a write into the full SM0 is not taken: working counter 0
    let (_, w, _) = send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x1000), &[9; 64]);
    assert_eq!(w, 0);
    let (st, _, _) = send(&mut e, &mut a, Cmd::Fprd, fp(0x1001, 0x0805), &[0]);
    assert_eq!(st[0] & 0x08, 0x08, "SM0 full");
    // reading SM1 makes room: the held request is answered
    read_sm1(&mut e, &mut a);
    assert_eq!(e.mailbox_backlog(), (MAX_PENDING_MAILBOX, false));
    assert_eq!(a.mailbox.len(), MAX_PENDING_MAILBOX + 2, "the held one now");
    let (_, w, _) = send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x1000), &[9; 64]);
    assert_eq!(w, 1, "SM0 takes a request again");
}

#[test]
fn an_fmmu_at_the_top_of_the_logical_space_maps_without_wrapping() {
    let (mut e, mut a) = addressed();
    to_preop(&mut e, &mut a);
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0818),
        &sm(0x1180, 16, 0x20, 1),
    );
    // FMMU0: logical 0xFFFF_FFF0, 16 bytes -> inputs at 0x1180: it ends
    // exactly at 2^32, where 32-bit arithmetic wrapped to 0
    let mut f = 0xFFFF_FFF0u32.to_le_bytes().to_vec();
    f.extend_from_slice(&16u16.to_le_bytes());
    f.extend_from_slice(&[0, 7]);
    f.extend_from_slice(&0x1180u16.to_le_bytes());
    f.extend_from_slice(&[0, 1, 1, 0, 0, 0]);
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0600), &f);
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[4, 0]);
    assert_eq!(e.al_state(), AlState::SafeOp);
    // the application's inputs are 0x40, 0x41, ... after a cycle
    send(&mut e, &mut a, Cmd::Lrw, 0xFFFF_FFF0, &[0; 16]);
    let (d, w, _) = send(&mut e, &mut a, Cmd::Lrd, 0xFFFF_FFF8, &[0; 8]);
    assert_eq!(w, 1);
    assert_eq!(d, (0x48..0x50).collect::<Vec<u8>>());
}

#[test]
fn a_sync0_cycle_of_one_nanosecond_does_not_stall_the_device() {
    let (mut e, mut a) = addressed();
    // in INIT: SYNC0 every 1 ns, activated (issue: the device stopped answering)
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x09A0),
        &1u32.to_le_bytes(),
    );
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0981), &[3]);
    // 1.5 s of device time: 1.5e9 SYNC0 events, none of which runs a cycle
    e.advance_to(1_500_000_000, &mut a);
    assert!(a.cycles.is_empty());
    let (d, w, _) = send(&mut e, &mut a, Cmd::Brd, 0, &[0]);
    assert_eq!((d[0], w), (0x11, 1), "it still answers");
    // in SAFE-OP with an application that takes any cycle: at most
    // MAX_SYNC0_PER_ADVANCE cycles per advance, the rest counted as skipped
    to_preop(&mut e, &mut a);
    send(
        &mut e,
        &mut a,
        Cmd::Fpwr,
        fp(0x1001, 0x0818),
        &sm(0x1180, 4, 0x20, 1),
    );
    a.sync0 = true;
    send(&mut e, &mut a, Cmd::Fpwr, fp(0x1001, 0x0120), &[4, 0]);
    assert_eq!(e.al_state(), AlState::SafeOp);
    e.advance_to(1_600_000_000, &mut a);
    assert_eq!(a.cycles.len() as u64, MAX_SYNC0_PER_ADVANCE);
    assert!(e.stats().sync0_skipped > 99_000_000);
}

/// An application that runs its loops at 1 ms only.
struct OneMs(App);

impl Application for OneMs {
    fn al_change(&mut self, f: AlState, t: AlState, s: &[SyncManager; 4]) -> Result<(), u16> {
        self.0.al_change(f, t, s)
    }
    fn mailbox(&mut self, r: &[u8], s: AlState) -> Option<Vec<u8>> {
        self.0.mailbox(r, s)
    }
    fn cycle(&mut self, t: u64, op: bool, o: &[u8], i: &mut [u8]) {
        self.0.cycle(t, op, o, i)
    }
    fn watchdog_expired(&mut self) {}
    fn wants_sync0(&self) -> bool {
        true
    }
    fn accepts_sync0_cycle(&self, cycle_ns: u32) -> bool {
        cycle_ns == 1_000_000
    }
}

fn to(e: &mut Esc, app: &mut OneMs, cmd: Cmd, addr: u32, data: &[u8]) {
    let mut f = frame::build(super::tests::SRC, &[(cmd, addr, data)]);
    assert!(e.process_frame(&mut f, app));
}

#[test]
fn a_sync0_cycle_other_than_the_applications_is_refused_with_its_al_code() {
    let (mut e, _) = addressed();
    let mut app = OneMs(App::default());
    to_preop(&mut e, &mut app.0);
    let sync0 = |e: &mut Esc, app: &mut OneMs, ns: u32| {
        to(e, app, Cmd::Fpwr, fp(0x1001, 0x09A0), &ns.to_le_bytes());
        to(e, app, Cmd::Fpwr, fp(0x1001, 0x0981), &[3]);
    };
    sync0(&mut e, &mut app, 500_000);
    to(&mut e, &mut app, Cmd::Fpwr, fp(0x1001, 0x0120), &[4, 0]);
    assert_eq!(
        (e.al_state(), e.al_error(), e.al_status_code()),
        (AlState::PreOp, true, al_code::DC_SYNC0_CYCLE_TIME)
    );
    // the application's own cycle is accepted (acknowledging the error)
    sync0(&mut e, &mut app, 1_000_000);
    to(&mut e, &mut app, Cmd::Fpwr, fp(0x1001, 0x0120), &[0x14, 0]);
    assert_eq!((e.al_state(), e.al_error()), (AlState::SafeOp, false));
    // changed to 250 us while running: the error, in SAFE-OP
    sync0(&mut e, &mut app, 250_000);
    assert_eq!(
        (e.al_state(), e.al_error(), e.al_status_code()),
        (AlState::SafeOp, true, al_code::DC_SYNC0_CYCLE_TIME)
    );
}
