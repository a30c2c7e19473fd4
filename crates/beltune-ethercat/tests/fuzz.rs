//! The virtual drive under hostile frames, in-process and seeded: random
//! bytes behind the EtherCAT type, valid frames with mutated bytes, sweeps
//! of every register with random data (AL control, sync managers, FMMUs,
//! the SII interface, distributed clocks with SYNC0 cycles down to 1 ns),
//! mailbox requests written without reading the answers, and jumps of the
//! device clock. After each batch the drive must still answer a valid frame
//! with the right working counter, and its mailbox queue must stay within
//! its bound. (The same over the wire, against the process, with memory and
//! SIGTERM checked: `beltune-cli/tests/virtual_drive_cli.rs`.)

use beltune::model::rigs;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive};
use beltune_ethercat::esc::frame::{self, Cmd};
use beltune_ethercat::esc::MAX_PENDING_MAILBOX;

/// xorshift64*: a small seeded generator (no dependency for a fuzz loop).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

const SRC: [u8; 6] = [0x02, 0, 0, 0, 0, 0x10];

/// A frame from hostile choices; every kind the issue names.
fn hostile(r: &mut Rng) -> Vec<u8> {
    match r.below(6) {
        // random bytes behind a valid Ethernet header and EtherType
        0 => {
            let n = 14 + r.below(1500) as usize;
            let mut f = r.bytes(n);
            f[6..12].copy_from_slice(&SRC);
            f[12] = 0x88;
            f[13] = 0xA4;
            f
        }
        // a valid frame with mutated bytes
        1 => {
            let mut f = frame::build(SRC, &[(Cmd::Fprd, 0x0130 << 16, &[0; 4])]);
            for _ in 0..1 + r.below(4) {
                let i = 14 + r.below(f.len() as u64 - 14) as usize;
                f[i] = r.next() as u8;
            }
            f
        }
        // a register sweep: any command, any address, any data
        2 => {
            let cmd = Cmd::from_u8(r.below(15) as u8).unwrap_or(Cmd::Nop);
            let addr = (r.below(0x2000) as u32) << 16;
            let n = 1 + r.below(64) as usize;
            frame::build(SRC, &[(cmd, addr, &r.bytes(n))])
        }
        // state requests, sync managers, FMMUs with random content
        3 => {
            let regs = [
                0x0120u32, 0x0800, 0x0808, 0x0810, 0x0818, 0x0600, 0x0610, 0x0502,
            ];
            let reg = regs[r.below(regs.len() as u64) as usize];
            frame::build(SRC, &[(Cmd::Bwr, reg << 16, &r.bytes(16))])
        }
        // distributed clocks: SYNC0 cycle (down to 1 ns), start, activation
        4 => {
            let cycle = 1 + r.below(2_000_000) as u32;
            frame::build(
                SRC,
                &[
                    (Cmd::Bwr, 0x09A0 << 16, &cycle.to_le_bytes()),
                    (Cmd::Bwr, 0x0990 << 16, &r.next().to_le_bytes()),
                    (Cmd::Bwr, 0x0981 << 16, &[3]),
                    (Cmd::Bwr, 0x0920 << 16, &r.next().to_le_bytes()),
                ],
            )
        }
        // a mailbox request into SM0, never reading SM1
        _ => {
            let mut req = r.bytes(128);
            req[0] = r.below(130) as u8;
            req[1] = 0;
            req[5] = (r.below(16) as u8) | 0x30;
            frame::build(SRC, &[(Cmd::Bwr, 0x1000 << 16, &req)])
        }
    }
}

/// The mailbox set-up and PRE-OP, as a master does, so that the mailbox
/// sequences reach the SDO server.
fn to_preop(d: &mut VirtualDrive) {
    let sm = |start: u16, len: u16, control: u8| {
        let mut v = start.to_le_bytes().to_vec();
        v.extend_from_slice(&len.to_le_bytes());
        v.extend_from_slice(&[control, 0, 1, 0]);
        v
    };
    for (reg, data) in [
        (0x0800u32, sm(0x1000, 128, 0x26)),
        (0x0808, sm(0x1080, 128, 0x22)),
        (0x0120, vec![0x12, 0]),
    ] {
        let mut f = frame::build(SRC, &[(Cmd::Bwr, reg << 16, &data)]);
        d.process_frame(&mut f);
    }
}

fn answers_a_valid_frame(d: &mut VirtualDrive) -> bool {
    let mut f = frame::build(SRC, &[(Cmd::Brd, 0, &[0; 2])]);
    if !d.process_frame(&mut f) {
        return false;
    }
    let g = frame::datagrams(&f).unwrap()[0];
    let wkc = u16::from_le_bytes([f[g.wkc()], f[g.wkc() + 1]]);
    // the ESC type register (0x11) and one device's working counter
    f[g.data()] == 0x11 && wkc == 1
}

#[test]
fn hostile_frames_registers_mailboxes_and_clocks_leave_the_drive_answering_and_bounded() {
    let plant = rigs::builtin("egc70", None).unwrap();
    for seed in [1u64, 2, 3, 4, 5] {
        let mut d = VirtualDrive::new(&plant, DriveConfig::default()).unwrap();
        let mut r = Rng(0x9E37_79B9_7F4A_7C15 ^ seed);
        let mut t = 1_000_000_000u64;
        for batch in 0..400 {
            if batch % 20 == 0 {
                to_preop(&mut d);
            }
            for _ in 0..50 {
                let mut f = hostile(&mut r);
                d.process_frame(&mut f);
            }
            // the clock: small steps, sometimes a jump of seconds
            t += if r.below(10) == 0 {
                r.below(5_000_000_000)
            } else {
                r.below(2_000_000)
            };
            d.advance_to(t);
            assert!(
                answers_a_valid_frame(&mut d),
                "seed {seed}, batch {batch}: no answer"
            );
            let (queued, _) = d.esc.mailbox_backlog();
            assert!(
                queued <= MAX_PENDING_MAILBOX,
                "seed {seed}: {queued} queued"
            );
        }
        eprintln!("seed {seed}: {:?}", d.esc.stats());
        assert!(d.esc.stats().mailbox_requests > 0, "mailbox sequences ran");
    }
}
