//! Real-time scheduling for the bus thread of a master or a virtual drive
//! on a Linux PC: `SCHED_FIFO` with `SCHED_RESET_ON_FORK`, so that threads
//! and processes started from it (the commissioning's computation, which
//! runs beside the hold controller) fall back to normal scheduling and never
//! compete with the bus at real-time priority. Without it, a busy host
//! (compilers on both cores) deschedules the bus thread for milliseconds and
//! frames miss their cycle; see the README's EtherCAT section.

use crate::Error;

/// Put the calling thread under `SCHED_FIFO` at `priority` (1..=99); a
/// one-line error without the rights (root or CAP_SYS_NICE).
pub fn set_realtime_priority(priority: u8) -> Result<(), Error> {
    if !(1..=99).contains(&priority) {
        return Err(Error::Config {
            name: "real-time priority",
            reason: format!("{priority} is outside 1 ..= 99"),
        });
    }
    let param = libc::sched_param {
        sched_priority: i32::from(priority),
    };
    // SAFETY: plain libc call on the calling thread (pid 0) with a parameter we own.
    let r = unsafe {
        libc::sched_setscheduler(0, libc::SCHED_FIFO | libc::SCHED_RESET_ON_FORK, &param)
    };
    if r != 0 {
        let e = std::io::Error::last_os_error();
        return Err(Error::Config {
            name: "real-time priority",
            reason: format!("SCHED_FIFO {priority}: {e} (needs root or CAP_SYS_NICE)"),
        });
    }
    Ok(())
}

/// Put the calling thread back under normal scheduling (`SCHED_OTHER`),
/// e.g. once the bus is closed and only files are written.
pub fn set_normal() {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: plain libc call on the calling thread; dropping a priority needs no rights.
    unsafe { libc::sched_setscheduler(0, libc::SCHED_OTHER, &param) };
}

/// The calling thread's scheduling policy and priority (`SCHED_FIFO` = 1).
pub fn current_policy() -> (i32, i32) {
    let mut param = libc::sched_param { sched_priority: 0 };
    // SAFETY: plain libc calls on the calling thread.
    unsafe {
        let policy = libc::sched_getscheduler(0);
        libc::sched_getparam(0, &mut param);
        (policy & !libc::SCHED_RESET_ON_FORK, param.sched_priority)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_priority_outside_the_range_is_a_config_error() {
        for p in [0u8, 100, 255] {
            assert!(matches!(
                set_realtime_priority(p),
                Err(Error::Config { .. })
            ));
        }
    }

    #[test]
    fn threads_started_from_a_real_time_thread_run_normally() {
        // on a thread of its own: the test harness' threads stay as they are
        let r = std::thread::spawn(|| {
            if let Err(e) = set_realtime_priority(10) {
                return Err(e.to_string());
            }
            let me = current_policy();
            let child = std::thread::spawn(current_policy).join().unwrap();
            set_normal();
            assert_eq!(current_policy(), (libc::SCHED_OTHER, 0), "back to normal");
            Ok((me, child))
        })
        .join()
        .unwrap();
        match r {
            Ok((me, child)) => {
                assert_eq!(me, (libc::SCHED_FIFO, 10));
                assert_eq!(child, (libc::SCHED_OTHER, 0), "reset on fork");
            }
            Err(e) => {
                assert!(e.contains("CAP_SYS_NICE"), "{e}");
                eprintln!("SKIPPED: no real-time scheduling here ({e})");
            }
        }
    }
}
