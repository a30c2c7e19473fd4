//! The master on a network interface: ethercrab's raw-socket TX/RX future
//! (Linux `AF_PACKET`, EtherType 0x88A4) polled together with each exchange,
//! and cycles paced by the monotonic clock.

use super::{Clock, CycleJitter, Transport};
use crate::Error;
use core::future::Future;
use core::pin::Pin;
use core::task::{Context, Poll};
use ethercrab::{PduRx, PduTx};
use std::time::{Duration, Instant};

type TxRx<'sto> = Pin<
    Box<dyn Future<Output = Result<(PduTx<'sto>, PduRx<'sto>), ethercrab::error::Error>> + 'sto>,
>;

/// A raw socket on an interface.
pub struct RawSocket<'sto> {
    task: TxRx<'sto>,
    next_cycle: Option<Instant>,
    stray_frames: u64,
    last_start: Option<Instant>,
    jitter: CycleJitter,
    /// Pace the cycles in real time (a real drive needs it; a test against
    /// an SM-synchronous virtual drive may run unpaced).
    pub paced: bool,
}

/// The one-line error for a socket that cannot be opened.
pub fn socket_error(interface: &str, e: &std::io::Error) -> Error {
    let hint = if e.kind() == std::io::ErrorKind::PermissionDenied
        || e.raw_os_error() == Some(libc::EPERM)
    {
        " (raw sockets need root or CAP_NET_RAW)"
    } else {
        ""
    };
    Error::Socket {
        interface: interface.to_string(),
        message: e.to_string(),
        hint,
    }
}

impl<'sto> RawSocket<'sto> {
    /// Open `interface`; a one-line error without the rights for a raw socket.
    pub fn open(interface: &str, tx: PduTx<'sto>, rx: PduRx<'sto>) -> Result<Self, Error> {
        let task = ethercrab::std::tx_rx_task(interface, tx, rx)
            .map_err(|e| socket_error(interface, &e))?;
        Ok(RawSocket {
            task: Box::pin(task),
            next_cycle: None,
            stray_frames: 0,
            last_start: None,
            jitter: CycleJitter::default(),
            paced: true,
        })
    }
}

impl RawSocket<'_> {
    /// Answers that came after their frame had timed out (dropped).
    pub fn stray_frames(&self) -> u64 {
        self.stray_frames
    }
}

impl Transport for RawSocket<'_> {
    fn poll_io(&mut self, cx: &mut Context<'_>) -> Poll<Result<(), ethercrab::error::Error>> {
        loop {
            match self.task.as_mut().poll(cx) {
                // An answer to a frame that already timed out (the drive or the
                // host was late): ethercrab's TX/RX task reports it as
                // `ReceiveFrame` and returns. Passing that on aborted the
                // exchange in flight, whose answer then came after it had been
                // given up and aborted the next one, and so on: once one answer
                // was late, no exchange succeeded any more ("lost
                // frames after 100-2000 cycles"). The late answer is dropped
                // and the task (re-entrant: it keeps its queues) polled again.
                Poll::Ready(Err(ethercrab::error::Error::ReceiveFrame)) => {
                    self.stray_frames += 1;
                }
                Poll::Ready(Ok(_)) => return Poll::Ready(Err(ethercrab::error::Error::SendFrame)),
                Poll::Ready(Err(e)) => return Poll::Ready(Err(e)),
                Poll::Pending => return Poll::Pending,
            }
        }
    }

    fn end_of_cycle(&mut self, cycle_ns: u64, dc_wait: Option<Duration>) {
        if !self.paced {
            return;
        }
        let now = Instant::now();
        let cycle = Duration::from_nanos(cycle_ns);
        let next = match (dc_wait, self.next_cycle) {
            // distributed clocks: the next SYNC0 plus the shift, from the drive's time
            (Some(w), _) if w <= 2 * cycle => now + w,
            (_, Some(t)) if t + cycle > now => t + cycle,
            _ => now + cycle,
        };
        // sleep most of the way, spin the rest (sleep overshoots by tens of us)
        let margin = Duration::from_micros(80);
        if next > now + margin {
            std::thread::sleep(next - now - margin);
        }
        while Instant::now() < next {
            std::hint::spin_loop();
        }
        self.next_cycle = Some(next);
        // the next exchange starts now: its period from the one before
        let start = Instant::now();
        if let Some(prev) = self.last_start.replace(start) {
            self.jitter
                .add((start - prev).as_secs_f64(), cycle.as_secs_f64());
        }
    }

    fn jitter(&self) -> Option<CycleJitter> {
        Some(self.jitter)
    }

    fn real_time(&self) -> bool {
        true
    }

    fn clock(&self) -> Clock {
        Clock::Monotonic
    }
}
