//! `beltune virtual-drive` under hostile input: its arguments (a folder
//! named like a built-in plant, a negative start position), and a process
//! fuzzed over a veth pair for a bounded time (random and mutated frames,
//! register sweeps, mailbox requests never read back, SYNC0 down to 1 ns):
//! it keeps answering valid frames, its memory stays bounded and SIGTERM
//! ends it. The network part creates and removes its own namespace and
//! skips with a message where that is not possible.

use beltune_ethercat::esc::frame::{self, Cmd};
use beltune_ethercat::netns::Netns;
use common::drive::DriveProcess;
use std::process::Command;
use std::time::{Duration, Instant};

mod common;

fn beltune() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
}

#[test]
fn a_folder_named_like_a_builtin_plant_does_not_shadow_it() {
    let dir = std::env::temp_dir().join(format!("beltune-vd-shadow-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("egc70")).unwrap();
    let out = beltune()
        .current_dir(&dir)
        .args([
            "virtual-drive",
            "--plant",
            "egc70",
            "--interface",
            "nosuchif0",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(!out.status.success());
    // the plant was the built-in one (not the folder: "Is a directory");
    // what fails is the interface, in one line
    let last = stderr.trim_end().lines().last().unwrap_or("");
    assert!(last.contains("nosuchif0"), "{stderr}");
    assert!(stderr.contains("plant egc70"), "{stderr}");
    assert!(!stderr.to_lowercase().contains("directory"), "{stderr}");
}

#[test]
fn a_negative_start_position_is_a_value_not_an_unknown_argument() {
    let out = beltune()
        .args(["virtual-drive", "--interface", "nosuchif0"])
        .args(["--start-position", "-5"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    // a value the drive refuses (outside the stroke): bad input, exit status 2
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("unexpected argument"), "{stderr}");
    assert_eq!(
        stderr
            .trim_end()
            .lines()
            .filter(|l| l.starts_with("error"))
            .count(),
        1,
        "{stderr}"
    );
}

/// A raw socket on the master's end of the pair.
struct Raw(libc::c_int, libc::sockaddr_ll);

impl Raw {
    fn open(interface: &str) -> Result<Raw, String> {
        let name = std::ffi::CString::new(interface).unwrap();
        // SAFETY: plain libc calls with checked results.
        unsafe {
            let ifindex = libc::if_nametoindex(name.as_ptr());
            let proto = 0x88A4u16.to_be() as libc::c_int;
            let fd = libc::socket(libc::AF_PACKET, libc::SOCK_RAW, proto);
            if fd < 0 || ifindex == 0 {
                return Err(std::io::Error::last_os_error().to_string());
            }
            let mut addr: libc::sockaddr_ll = std::mem::zeroed();
            addr.sll_family = libc::AF_PACKET as u16;
            addr.sll_protocol = 0x88A4u16.to_be();
            addr.sll_ifindex = ifindex as i32;
            addr.sll_halen = 6;
            addr.sll_addr[..6].fill(0xFF);
            let size = std::mem::size_of::<libc::sockaddr_ll>() as u32;
            if libc::bind(fd, &addr as *const _ as *const libc::sockaddr, size) < 0 {
                libc::close(fd);
                return Err(std::io::Error::last_os_error().to_string());
            }
            let tv = libc::timeval {
                tv_sec: 0,
                tv_usec: 20_000,
            };
            libc::setsockopt(
                fd,
                libc::SOL_SOCKET,
                libc::SO_RCVTIMEO,
                &tv as *const _ as *const libc::c_void,
                std::mem::size_of::<libc::timeval>() as u32,
            );
            Ok(Raw(fd, addr))
        }
    }

    fn send(&self, f: &[u8]) {
        let size = std::mem::size_of::<libc::sockaddr_ll>() as u32;
        // SAFETY: sending a buffer we own.
        unsafe {
            libc::sendto(
                self.0,
                f.as_ptr() as *const libc::c_void,
                f.len(),
                0,
                &self.1 as *const _ as *const libc::sockaddr,
                size,
            );
        }
    }

    /// The next frame the drive answered (source MAC with the locally
    /// administered bit), within `timeout`.
    fn answer(&self, timeout: Duration) -> Option<Vec<u8>> {
        let t0 = Instant::now();
        let mut buf = vec![0u8; 2048];
        while t0.elapsed() < timeout {
            // SAFETY: receiving into a buffer we own.
            let n =
                unsafe { libc::recv(self.0, buf.as_mut_ptr() as *mut libc::c_void, buf.len(), 0) };
            if n > 14 && buf[6] & 0x02 != 0 {
                return Some(buf[..n as usize].to_vec());
            }
        }
        None
    }
}

impl Drop for Raw {
    fn drop(&mut self) {
        // SAFETY: closing our descriptor once.
        unsafe { libc::close(self.0) };
    }
}

fn rss_kib(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}

/// Resident memory the drive may gain under the fuzz, KiB (its mailbox
/// queue is bounded at 16 answers of 128 bytes; the issue saw 6.5 -> 489 MB).
const RSS_GROWTH_MAX_KIB: u64 = 8 * 1024;
/// Fuzzing time over the wire.
const FUZZ_TIME: Duration = Duration::from_secs(4);

#[test]
fn a_fuzzed_drive_process_keeps_answering_stays_bounded_and_ends_on_sigterm() {
    let net = match Netns::create("fz") {
        Ok(n) => n,
        Err(e) => {
            eprintln!("SKIPPED: network namespace with a veth pair unavailable here ({e})");
            return;
        }
    };
    let log = std::env::temp_dir().join(format!("beltune-vd-fuzz-{}.log", std::process::id()));
    let mut drive = DriveProcess::spawn(&net, log, &[]).unwrap_or_else(|e| panic!("drive: {e}"));
    let sock = match Raw::open(&net.master_if) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("SKIPPED: no raw socket here ({e})");
            return;
        }
    };
    // a master's source address: the locally administered bit (0x02) clear,
    // as the drive sets it in its answers
    let src = [0x10, 0, 0, 0, 0, 0x20];
    let probe = frame::build(src, &[(Cmd::Brd, 0, &[0; 2])]);
    sock.send(&probe);
    assert!(
        sock.answer(Duration::from_secs(2)).is_some(),
        "no answer before the fuzz"
    );
    let pid = drive.child.id();
    let rss0 = rss_kib(pid);
    // the mailbox set up (so that mailbox requests reach the server), then
    // hostile frames of every kind, seeded
    let sm = |start: u16, len: u16, control: u8| {
        let mut v = start.to_le_bytes().to_vec();
        v.extend_from_slice(&len.to_le_bytes());
        v.extend_from_slice(&[control, 0, 1, 0]);
        v
    };
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    let mut rnd = move || {
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    };
    let t0 = Instant::now();
    let (mut sent, mut probes, mut answered) = (0u64, 0u64, 0u64);
    while t0.elapsed() < FUZZ_TIME {
        sock.send(&frame::build(
            src,
            &[(Cmd::Bwr, 0x0800 << 16, &sm(0x1000, 128, 0x26))],
        ));
        sock.send(&frame::build(
            src,
            &[(Cmd::Bwr, 0x0808 << 16, &sm(0x1080, 128, 0x22))],
        ));
        sock.send(&frame::build(src, &[(Cmd::Bwr, 0x0120 << 16, &[0x12, 0])]));
        for _ in 0..200 {
            let r = rnd();
            let f = match r % 5 {
                0 => {
                    let n = 16 + (rnd() % 1400) as usize;
                    let mut f: Vec<u8> = (0..n).map(|_| rnd() as u8).collect();
                    f[..6].fill(0xFF);
                    f[6..12].copy_from_slice(&src);
                    f[12] = 0x88;
                    f[13] = 0xA4;
                    f
                }
                1 => {
                    let mut f = probe.clone();
                    let i = 14 + (rnd() as usize % (f.len() - 14));
                    f[i] = rnd() as u8;
                    f
                }
                2 => {
                    let data: Vec<u8> = (0..1 + rnd() % 32).map(|_| rnd() as u8).collect();
                    let cmd = Cmd::from_u8((rnd() % 15) as u8).unwrap_or(Cmd::Nop);
                    frame::build(src, &[(cmd, ((rnd() % 0x2000) as u32) << 16, &data)])
                }
                3 => {
                    let cycle = 1 + (rnd() % 1000) as u32;
                    frame::build(
                        src,
                        &[
                            (Cmd::Bwr, 0x09A0 << 16, &cycle.to_le_bytes()),
                            (Cmd::Bwr, 0x0981 << 16, &[3]),
                        ],
                    )
                }
                _ => {
                    let mut req: Vec<u8> = (0..128).map(|_| rnd() as u8).collect();
                    req[0] = 10;
                    req[1] = 0;
                    req[5] = 0x03 | ((rnd() as u8 & 7) << 4);
                    req[6] = 0;
                    req[7] = 0x20;
                    frame::build(src, &[(Cmd::Bwr, 0x1000 << 16, &req)])
                }
            };
            sock.send(&f);
            sent += 1;
        }
        // a valid frame in between: answered
        sock.send(&probe);
        probes += 1;
        let deadline = Instant::now() + Duration::from_millis(500);
        while Instant::now() < deadline {
            match sock.answer(deadline - Instant::now()) {
                Some(a) if a.len() >= probe.len() && a[14..16] == probe[14..16] && a[16] == 7 => {
                    answered += 1;
                    break;
                }
                Some(_) => continue,
                None => break,
            }
        }
    }
    let rss1 = rss_kib(pid);
    eprintln!(
        "fuzz: {sent} hostile frames, {answered} of {probes} probes answered, RSS {rss0} -> {rss1} KiB"
    );
    assert!(
        answered + 2 >= probes,
        "valid frames unanswered: {answered} of {probes}"
    );
    assert!(
        rss1 <= rss0 + RSS_GROWTH_MAX_KIB,
        "memory grew {rss0} -> {rss1} KiB"
    );
    let t = Instant::now();
    let log = drive.stop();
    assert!(
        t.elapsed() < Duration::from_secs(5),
        "SIGTERM took {:?}",
        t.elapsed()
    );
    assert!(log.contains("stopped:"), "ended by SIGTERM: {log}");
}
