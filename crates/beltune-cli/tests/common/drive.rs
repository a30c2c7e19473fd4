//! `beltune virtual-drive` as a child process of a test, inside the
//! network namespace of a [`Netns`] (the EtherCAT wire tests).

use beltune_ethercat::netns::Netns;
use std::path::PathBuf;
use std::process::Stdio;
use std::time::Duration;

/// `beltune virtual-drive` as a child process inside the namespace, its
/// stderr in a file (no pipe to fill); stopped with SIGTERM (killed if it
/// does not stop) and reaped on drop, also when the test panics.
pub struct DriveProcess {
    /// The child (`ip netns exec` execs the drive in place: its pid).
    pub child: std::process::Child,
    log: PathBuf,
}

impl DriveProcess {
    /// Start it with `extra` arguments; ready once it has said so.
    pub fn spawn(net: &Netns, log: PathBuf, extra: &[&str]) -> Result<DriveProcess, String> {
        let err = std::fs::File::create(&log).map_err(|e| e.to_string())?;
        let child = net
            .command(env!("CARGO_BIN_EXE_beltune"))
            .args(["virtual-drive", "--interface", &net.drive_if])
            .args(["--seed", "1"])
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(err)
            .spawn()
            .map_err(|e| format!("spawn: {e}"))?;
        let mut d = DriveProcess { child, log };
        // ready once it has said so (its socket is bound by then)
        for _ in 0..200 {
            if d.stderr().contains("Ctrl-C stops") {
                return Ok(d);
            }
            if let Ok(Some(status)) = d.child.try_wait() {
                return Err(format!("the drive exited ({status}): {}", d.stderr()));
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        Err(format!("the drive did not start: {}", d.stderr()))
    }

    /// What it wrote on stderr so far.
    pub fn stderr(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// SIGTERM, wait for the exit; its stderr.
    pub fn stop(&mut self) -> String {
        // SAFETY: signalling our own child by its pid (`ip netns exec` execs in place).
        unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGTERM) };
        for _ in 0..250 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return self.stderr();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.stderr()
    }
}

impl Drop for DriveProcess {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
        let _ = std::fs::remove_file(&self.log);
    }
}
