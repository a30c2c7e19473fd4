//! The virtual drive plugged into ethercrab's `PduTx`/`PduRx` in the same
//! process: every frame ethercrab queues is handed to the drive's ESC at once
//! and its answer back to ethercrab; the drive's clock is simulated and
//! advances by one bus cycle per exchange (and by 1 us per frame, so that
//! distributed-clock receive times differ), so a commissioning runs as fast
//! as the machine computes and is repeatable.

use super::{Clock, Transport};
use crate::drive::{Faults, VirtualDrive};
use core::task::{Context, Poll};
use ethercrab::{PduRx, PduTx};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Simulated time per frame, ns.
const FRAME_TIME_NS: u64 = 1000;

/// The in-process bus with one virtual drive.
pub struct InProcess<'sto> {
    tx: PduTx<'sto>,
    rx: PduRx<'sto>,
    drive: VirtualDrive,
    clock: Arc<AtomicU64>,
    faults: Arc<Faults>,
    buf: Vec<u8>,
    /// When the current cycle started (simulated), ns.
    cycle_start_ns: u64,
    frames: u64,
    dropped: u64,
}

impl<'sto> InProcess<'sto> {
    /// A bus with `drive`, simulated time from 1 s (a drive that has been on for a while).
    pub fn new(tx: PduTx<'sto>, rx: PduRx<'sto>, drive: VirtualDrive) -> Self {
        let faults = drive.faults();
        let t0 = 1_000_000_000;
        InProcess {
            tx,
            rx,
            drive,
            clock: Arc::new(AtomicU64::new(t0)),
            faults,
            buf: Vec::with_capacity(1514),
            cycle_start_ns: t0,
            frames: 0,
            dropped: 0,
        }
    }

    /// The drive.
    pub fn drive(&self) -> &VirtualDrive {
        &self.drive
    }

    /// The drive, mutable.
    pub fn drive_mut(&mut self) -> &mut VirtualDrive {
        &mut self.drive
    }

    /// Simulated time, ns.
    pub fn now_ns(&self) -> u64 {
        self.clock.load(Ordering::Relaxed)
    }

    /// Frames exchanged and frames dropped by fault injection.
    pub fn frame_counts(&self) -> (u64, u64) {
        (self.frames, self.dropped)
    }

    fn tick(&mut self, dt_ns: u64) {
        let t = self.clock.fetch_add(dt_ns, Ordering::Relaxed) + dt_ns;
        self.drive.advance_to(t);
    }
}

impl Transport for InProcess<'_> {
    fn poll_io(&mut self, cx: &mut Context<'_>) -> Poll<Result<(), ethercrab::error::Error>> {
        self.tx.replace_waker(cx.waker());
        while let Some(frame) = self.tx.next_sendable_frame() {
            let buf = &mut self.buf;
            let sent = frame.send_blocking(|bytes| {
                buf.clear();
                buf.extend_from_slice(bytes);
                Ok(bytes.len())
            });
            if let Err(e) = sent {
                return Poll::Ready(Err(e));
            }
            self.frames += 1;
            self.tick(FRAME_TIME_NS);
            let cycles = self.drive.firmware.cycles();
            if self.faults.take(&self.faults.drop_requests, cycles) {
                // lost on the way to the drive: it sees nothing, no answer comes
                self.dropped += 1;
                continue;
            }
            let mut frame_buf = std::mem::take(&mut self.buf);
            let processed = self.drive.process_frame(&mut frame_buf);
            let drop = self.faults.take(&self.faults.drop_frames, cycles);
            if processed && !drop {
                if let Err(e) = self.rx.receive_frame(&frame_buf) {
                    self.buf = frame_buf;
                    return Poll::Ready(Err(e));
                }
            } else if drop {
                self.dropped += 1;
            }
            self.buf = frame_buf;
        }
        Poll::Pending
    }

    fn end_of_cycle(&mut self, cycle_ns: u64, _dc_wait: Option<std::time::Duration>) {
        // the rest of the cycle after the frames of this one
        let next = self.cycle_start_ns + cycle_ns;
        let now = self.now_ns();
        if next > now {
            self.tick(next - now);
            self.cycle_start_ns = next;
        } else {
            self.cycle_start_ns = now;
        }
    }

    fn real_time(&self) -> bool {
        false
    }

    fn clock(&self) -> Clock {
        Clock::Simulated(Arc::clone(&self.clock))
    }
}
