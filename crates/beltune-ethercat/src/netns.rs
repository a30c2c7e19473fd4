//! Test support (feature `test-util`): a network namespace holding one end
//! of a veth pair, for the wire tests of this crate and of the CLI. The
//! namespace and the pair are removed on drop (also when a test panics);
//! [`Netns::create`] fails with a message where `ip`, namespaces or veth
//! pairs are unavailable (no root / CAP_NET_ADMIN), so that a test can skip.

use std::process::Command;

/// A namespace with the drive end of a veth pair; the master end stays in
/// the caller's namespace.
#[derive(Debug)]
pub struct Netns {
    /// Name of the namespace (`/run/netns/NAME`).
    pub ns: String,
    /// The veth end in the caller's namespace (the master's interface).
    pub master_if: String,
    /// The veth end inside the namespace (the drive's interface).
    pub drive_if: String,
}

/// Run `ip ARGS`; its stderr as the error.
pub fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("ip: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

impl Netns {
    /// Create namespace `bt-TAG-PID` and the pair `btmTAGPID` / `btdTAGPID`
    /// (interface names stay within 15 characters for tags of up to 4).
    pub fn create(tag: &str) -> Result<Netns, String> {
        let id = std::process::id() % 100_000;
        let n = Netns {
            ns: format!("bt-{tag}-{id}"),
            master_if: format!("btm{tag}{id}"),
            drive_if: format!("btd{tag}{id}"),
        };
        if n.master_if.len() > 15 {
            return Err(format!("tag `{tag}` makes the interface name too long"));
        }
        ip(&["netns", "add", &n.ns])?;
        // from here on, Drop cleans up
        ip(&[
            "link",
            "add",
            &n.master_if,
            "type",
            "veth",
            "peer",
            "name",
            &n.drive_if,
        ])?;
        ip(&["link", "set", &n.drive_if, "netns", &n.ns])?;
        ip(&["link", "set", &n.master_if, "up"])?;
        ip(&["-n", &n.ns, "link", "set", &n.drive_if, "up"])?;
        Ok(n)
    }

    /// Move the calling thread into the namespace (the rest of the process stays).
    pub fn enter(&self) -> Result<(), String> {
        enter(&self.ns)
    }

    /// A command that runs `program` inside the namespace (`ip netns exec`).
    pub fn command(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut c = Command::new("ip");
        c.args(["netns", "exec", &self.ns]).arg(program);
        c
    }
}

/// Move the calling thread into the network namespace `ns` (for a thread
/// that must not own the [`Netns`], whose drop cleans up).
pub fn enter(ns: &str) -> Result<(), String> {
    use std::os::fd::AsRawFd;
    let f = std::fs::File::open(format!("/run/netns/{ns}"))
        .map_err(|e| format!("open netns {ns}: {e}"))?;
    // SAFETY: setns on a namespace descriptor we hold; affects this thread only.
    if unsafe { libc::setns(f.as_raw_fd(), libc::CLONE_NEWNET) } != 0 {
        return Err(format!("setns: {}", std::io::Error::last_os_error()));
    }
    Ok(())
}

impl Drop for Netns {
    fn drop(&mut self) {
        // deleting one end removes the pair; the namespace goes with its name
        let _ = ip(&["link", "del", &self.master_if]);
        let _ = ip(&["netns", "del", &self.ns]);
    }
}
