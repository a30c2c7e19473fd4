//! EtherCAT on the command line: `beltune commission --ethercat IFACE`
//! against `beltune virtual-drive` (a child process inside a network
//! namespace, on the other end of a veth pair; both created and always
//! removed by the test, skipped with a message where namespaces, veth pairs or
//! real-time scheduling are unavailable), and the one-line errors without a
//! raw socket.

use beltune::commission::NoProgress;
use beltune::commission::{commission, CommissioningConfig, DataSheet};
use beltune::model::rigs::{self, Plant};
use beltune::sim::{SimAxis, SimConfig};
use beltune_ethercat::netns::Netns;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Duration;

fn beltune() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
}

/// Identified resonance and antiresonance within 2 % of the truth.
const FREQUENCY_TOLERANCE: f64 = 0.02;
/// Thesis chapter 5: static positioning error.
const STATIC_ERROR_M: f64 = 100e-6;
/// The dynamic error over the wire against the direct simulation at the same
/// 1 ms cycle: one cycle of bus transport delay, as in-process ...
const WIRE_ERROR_FACTOR: f64 = 1.25;
/// ... plus this much, m: since the record is aligned both errors
/// are near 0.15 mm, where the start at rest within the static error band
/// alone moves them by a few tens of um.
const WIRE_ERROR_ABS_M: f64 = 50e-6;
/// Thesis chapter 5: the dynamic cart error limit, m.
const MAX_TRACKING_ERROR_M: f64 = 1e-3;
const START_M: f64 = 0.05;

/// `beltune virtual-drive` as a child process inside the namespace, its
/// stderr in a file (no pipe to fill); stopped with SIGTERM (killed if it
/// does not stop) and reaped on drop, also when the test panics.
struct DriveProcess {
    child: std::process::Child,
    log: PathBuf,
}

impl DriveProcess {
    fn spawn(net: &Netns, log: PathBuf, extra: &[&str]) -> Result<DriveProcess, String> {
        let err = std::fs::File::create(&log).map_err(|e| e.to_string())?;
        let child = net
            .command(env!("CARGO_BIN_EXE_beltune"))
            .args(["virtual-drive", "--interface", &net.drive_if])
            .args(["--start-position", &START_M.to_string(), "--seed", "1"])
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

    fn stderr(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// SIGTERM, wait for the exit; its stderr.
    fn stop(&mut self) -> String {
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

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The full commissioning over a veth pair, `beltune commission
/// --ethercat` against `beltune virtual-drive` run as a real child process
/// of the test inside the namespace. An earlier version ran the drive on a
/// thread of the test because the child "lost frames after 100-2000 cycles":
/// the cause was in the master, not in the child. One answer later than the
/// frame timeout (a scheduling gap of the drive or the master on this busy
/// host) made ethercrab's TX/RX task return `ReceiveFrame`; passing that on
/// aborted the exchange in flight, whose own answer then came after it had
/// been given up, and so on: no exchange succeeded any more. The raw-socket
/// transport now drops such a late answer (one lost frame, bridged); the
/// wire test of `beltune-ethercat` injects exactly one late answer. Here the
/// drive runs SM-synchronous (`--no-dc`): one drive cycle per frame, so that
/// the result does not depend on the host's scheduling; with distributed
/// clocks this host misses SYNC0 cycles (counted on both sides, see the
/// README).
#[test]
fn a_late_answer_no_longer_loses_every_later_frame_with_the_drive_as_a_child_process() {
    let net = match Netns::create("cli") {
        Ok(n) => n,
        Err(e) => {
            eprintln!("SKIPPED: network namespace with a veth pair unavailable here ({e})");
            return;
        }
    };
    let out_dir = temp_dir("ethercat");
    let mut drive = DriveProcess::spawn(
        &net,
        std::env::temp_dir().join(format!("beltune-vd-{}.log", std::process::id())),
        &["--no-dc"],
    )
    .unwrap_or_else(|e| panic!("virtual drive: {e}"));
    let out = beltune()
        .args([
            "commission",
            "--ethercat",
            &net.master_if,
            "--cycle-us",
            "1000",
        ])
        // a real drive answers within microseconds, a process on a shared
        // host sometimes within milliseconds
        .args(["--frame-timeout-ms", "20"])
        // the verdict judges the move over a bus with late
        // frames: this test checks the wire path, not the thesis' 1 mm
        // (exit status 5 otherwise)
        .args([
            "--max-tracking-error",
            "0.01",
            "--max-static-error",
            "0.001",
        ])
        .args(["--start-position", &START_M.to_string(), "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let drive_log = drive.stop();
    eprintln!("drive: {}", drive_log.trim());
    assert!(
        out.status.success(),
        "commission over the wire failed: {stderr}\ndrive: {drive_log}"
    );
    assert!(
        stderr.contains("no distributed clocks"),
        "SM-synchronous: {stderr}"
    );
    assert!(
        drive_log.contains("stopped:"),
        "the drive stopped on SIGTERM: {drive_log}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("commissioning.json")).unwrap())
            .unwrap();
    assert!(out_dir.join("controller.toml").is_file() && out_dir.join("report.html").is_file());
    assert!(
        json.get("truth").is_none(),
        "no simulator truth claimed for a real bus"
    );
    let plant = rigs::builtin("egc70", None).unwrap();
    let pos = json["identification_position_m"].as_f64().unwrap();
    let truth = plant.linearize(pos).unwrap();
    let f_r = json["identified"]["f_r_hz"].as_f64().unwrap();
    let f_z = json["identified"]["f_z_hz"].as_f64().unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    eprintln!(
        "wire: f_r {f_r:.2} ({:.2}), f_z {f_z:.2} ({:.2})",
        truth.f_r_hz(),
        truth.f_z_hz()
    );
    assert!(
        rel(f_r, truth.f_r_hz()) < FREQUENCY_TOLERANCE,
        "f_r {f_r} vs {}",
        truth.f_r_hz()
    );
    assert!(
        rel(f_z, truth.f_z_hz()) < FREQUENCY_TOLERANCE,
        "f_z {f_z} vs {}",
        truth.f_z_hz()
    );
    let nl = &json["validation"]["nonlinear"];
    let max_err = nl["max_tracking_error_m"].as_f64().unwrap();
    let static_err = nl["static_error_m"].as_f64().unwrap();
    // the direct simulation at the same cycle
    let mut p1 = plant.clone();
    if let Plant::Physical(p) = &mut p1 {
        p.ts_s = 1e-3;
    }
    let mut axis = SimAxis::new(
        &p1,
        SimConfig {
            seed: 1,
            initial_cart_position_m: Some(START_M),
            ..SimConfig::default()
        },
    )
    .unwrap();
    let ds = DataSheet::for_plant(&p1, START_M, None);
    let direct = commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap();
    let d = direct.validation.nonlinear.max_tracking_error_m;
    eprintln!(
        "wire: max cart error {:.3} mm (direct {:.3} mm), static {:.1} um",
        max_err * 1e3,
        d * 1e3,
        static_err * 1e6
    );
    assert!(
        static_err < STATIC_ERROR_M,
        "static error {:.1} um",
        static_err * 1e6
    );
    assert!(
        max_err < MAX_TRACKING_ERROR_M && max_err < WIRE_ERROR_FACTOR * d + WIRE_ERROR_ABS_M,
        "max cart error {:.3} mm, direct {:.3} mm",
        max_err * 1e3,
        d * 1e3
    );
    let _ = std::fs::remove_dir_all(&out_dir);
}

/// `beltune health --ethercat` against `beltune virtual-drive` (a child
/// process in the namespace, SM-synchronous): a commissioning over the wire
/// is the baseline, the health check over the same wire finds the same axis
/// (every quantity within its limits: exit status 0) in at most 5 s of axis
/// time.
#[test]
fn a_health_check_runs_over_the_wire() {
    let net = match Netns::create("health") {
        Ok(n) => n,
        Err(e) => {
            eprintln!("SKIPPED: network namespace with a veth pair unavailable here ({e})");
            return;
        }
    };
    let dir = temp_dir("ethercat-health");
    std::fs::create_dir_all(&dir).unwrap();
    let mut drive = DriveProcess::spawn(
        &net,
        std::env::temp_dir().join(format!("beltune-vd-health-{}.log", std::process::id())),
        &["--no-dc"],
    )
    .unwrap_or_else(|e| panic!("virtual drive: {e}"));
    let wire = [
        "--ethercat",
        net.master_if.as_str(),
        "--cycle-us",
        "1000",
        "--frame-timeout-ms",
        "20",
        "--start-position",
        "0.05",
        "--quiet",
    ];
    let base = dir.join("base");
    let out = beltune()
        .arg("commission")
        .args(wire)
        .args([
            "--max-tracking-error",
            "0.01",
            "--max-static-error",
            "0.001",
        ])
        .arg("--out")
        .arg(&base)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "commission over the wire: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // the axis homed again and parked at 50 mm: a drive powered up anew
    // (the master counts the position from where it finds the drive)
    drive.stop();
    let mut drive = DriveProcess::spawn(
        &net,
        std::env::temp_dir().join(format!("beltune-vd-health2-{}.log", std::process::id())),
        &["--no-dc"],
    )
    .unwrap_or_else(|e| panic!("virtual drive: {e}"));
    let out = beltune()
        .arg("health")
        .args(wire)
        .arg("--baseline")
        .arg(&base)
        .arg("--json")
        .arg("--out")
        .arg(dir.join("health"))
        .output()
        .unwrap();
    let drive_log = drive.stop();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "health over the wire: {stdout}{}\ndrive: {drive_log}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(j["status"], "ok");
    assert!(j["experiment_time_s"].as_f64().unwrap() <= 5.0);
    assert!(dir.join("beltune-history.sqlite").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_interface_is_one_line_and_no_outputs() {
    let out_dir = temp_dir("ethercat-missing");
    let out = beltune()
        .args(["commission", "--ethercat", "nosuchif0", "--quiet", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("nosuchif0"), "{stderr}");
    assert!(!out_dir.exists(), "no outputs");
}

#[test]
fn without_the_rights_for_a_raw_socket_it_says_so_in_one_line() {
    // run as `nobody` where we can switch users (as root); otherwise we are unprivileged already
    let is_root = unsafe { libc::geteuid() } == 0;
    let mut cmd = if is_root {
        let mut c = Command::new("setpriv");
        c.args([
            "--reuid=65534",
            "--regid=65534",
            "--clear-groups",
            "--inh-caps=-all",
            env!("CARGO_BIN_EXE_beltune"),
        ]);
        c
    } else {
        beltune()
    };
    let out = match cmd
        .args([
            "commission",
            "--ethercat",
            "lo",
            "--quiet",
            "--out",
            "/nonexistent/beltune-no-rights",
        ])
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            eprintln!("SKIPPED: cannot run unprivileged here ({e})");
            return;
        }
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if stderr.contains("setpriv:") {
        eprintln!(
            "SKIPPED: setpriv cannot drop privileges here ({})",
            stderr.trim()
        );
        return;
    }
    assert!(!out.status.success());
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("raw sockets need root or CAP_NET_RAW"),
        "{stderr}"
    );
}
