//! The virtual drive on a network interface: a raw `AF_PACKET` socket bound
//! to EtherType 0x88A4 on one interface; every EtherCAT frame that arrives is
//! processed by the drive and sent back (as the last device of a line sends
//! the frame back to the master), and the drive's clock follows the host's
//! monotonic clock so that SYNC0 cycles and the watchdog run in real time.

use crate::drive::VirtualDrive;
use crate::esc::frame::ETHERTYPE;
use crate::master::wire::socket_error;
use crate::Error;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a serving session did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ServeStats {
    /// Frames answered.
    pub frames: u64,
    /// Drive cycles run.
    pub cycles: u64,
    /// Watchdog expiries.
    pub watchdog_expiries: u64,
    /// SYNC0 cycles in OP that found no new outputs (the master's frame
    /// came after the SYNC0 it was meant for: the drive applied the previous
    /// torque once more, as a real drive does).
    pub cycles_without_new_outputs: u64,
    /// AL state when serving stopped.
    pub al_state: crate::esc::AlState,
    /// Whether an AL error was latched then.
    pub al_error: bool,
    /// AL status code then.
    pub al_status_code: u16,
}

/// Nanoseconds of the monotonic clock.
pub fn monotonic_ns() -> u64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t) };
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

struct Socket(libc::c_int);

impl Drop for Socket {
    fn drop(&mut self) {
        // SAFETY: the descriptor is ours and closed once.
        unsafe { libc::close(self.0) };
    }
}

fn open(interface: &str) -> Result<Socket, Error> {
    let err = |e: std::io::Error| socket_error(interface, &e);
    let name = std::ffi::CString::new(interface).map_err(|_| Error::Config {
        name: "interface",
        reason: format!("`{interface}` contains a NUL byte"),
    })?;
    // SAFETY: plain libc calls with checked results.
    unsafe {
        let ifindex = libc::if_nametoindex(name.as_ptr());
        if ifindex == 0 {
            return Err(err(std::io::Error::last_os_error()));
        }
        let proto = (ETHERTYPE).to_be() as libc::c_int;
        let fd = libc::socket(libc::AF_PACKET, libc::SOCK_RAW, proto);
        if fd < 0 {
            return Err(err(std::io::Error::last_os_error()));
        }
        let s = Socket(fd);
        let mut addr: libc::sockaddr_ll = std::mem::zeroed();
        addr.sll_family = libc::AF_PACKET as u16;
        addr.sll_protocol = (ETHERTYPE).to_be();
        addr.sll_ifindex = ifindex as i32;
        if libc::bind(
            fd,
            &addr as *const _ as *const libc::sockaddr,
            std::mem::size_of::<libc::sockaddr_ll>() as u32,
        ) < 0
        {
            return Err(err(std::io::Error::last_os_error()));
        }
        // wake at least every 200 us for the drive's clock
        let tv = libc::timeval {
            tv_sec: 0,
            tv_usec: 200,
        };
        libc::setsockopt(
            fd,
            libc::SOL_SOCKET,
            libc::SO_RCVTIMEO,
            &tv as *const _ as *const libc::c_void,
            std::mem::size_of::<libc::timeval>() as u32,
        );
        Ok(s)
    }
}

/// Answer EtherCAT frames on `interface` until `stop` is set. A one-line
/// error if the socket cannot be opened (e.g. without CAP_NET_RAW).
pub fn serve(
    interface: &str,
    drive: &mut VirtualDrive,
    stop: &AtomicBool,
) -> Result<ServeStats, Error> {
    let sock = open(interface)?;
    let mut buf = vec![0u8; 2048];
    let mut frames = 0;
    let t0 = monotonic_ns();
    // the drive's local clock starts at 1 s (it has been on for a while)
    let local = |now: u64| now - t0 + 1_000_000_000;
    let mut held: Option<Vec<u8>> = None;
    while !stop.load(Ordering::Relaxed) {
        let mut from: libc::sockaddr_ll = unsafe { std::mem::zeroed() };
        let mut len = std::mem::size_of::<libc::sockaddr_ll>() as libc::socklen_t;
        // SAFETY: buf and from are ours, sizes given.
        let n = unsafe {
            libc::recvfrom(
                sock.0,
                buf.as_mut_ptr() as *mut libc::c_void,
                buf.len(),
                0,
                &mut from as *mut _ as *mut libc::sockaddr,
                &mut len,
            )
        };
        drive.advance_to(local(monotonic_ns()));
        if n <= 0 {
            continue;
        }
        if from.sll_pkttype == libc::PACKET_OUTGOING {
            continue;
        }
        let frame = &mut buf[..n as usize];
        // frames already processed by a device (locally administered source) are not for us
        if frame.len() < 14 || frame[6] & 0x02 != 0 {
            continue;
        }
        let cycles = drive.firmware.cycles();
        let faults = drive.faults();
        if faults.take(&faults.drop_requests, cycles) {
            continue;
        }
        if drive.process_frame(frame) {
            frames += 1;
            let drop = faults.take(&faults.drop_frames, cycles);
            if drop {
                continue;
            }
            let send = |bytes: &[u8]| {
                // SAFETY: sending a buffer we own on our socket to the interface it came from.
                unsafe {
                    libc::sendto(
                        sock.0,
                        bytes.as_ptr() as *const libc::c_void,
                        bytes.len(),
                        0,
                        &from as *const _ as *const libc::sockaddr,
                        len,
                    );
                }
            };
            // a held-back answer goes out late, before the answer to this frame
            if let Some(old) = held.take() {
                send(&old);
            }
            if faults.take(&faults.late_answers, cycles) {
                held = Some(frame.to_vec());
                continue;
            }
            send(frame);
        }
    }
    let s = drive.esc.stats();
    Ok(ServeStats {
        frames,
        cycles: s.cycles,
        watchdog_expiries: s.watchdog_expiries,
        cycles_without_new_outputs: s.cycles_without_new_outputs,
        al_state: drive.esc.al_state(),
        al_error: drive.esc.al_error(),
        al_status_code: drive.esc.al_status_code(),
    })
}
