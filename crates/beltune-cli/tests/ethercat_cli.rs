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
use common::drive::DriveProcess;
use std::path::PathBuf;
use std::process::Command;

mod common;

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
/// wire test of `beltune-ethercat` injects exactly one late answer. The
/// drive offers distributed clocks as it does by default; the master's
/// default is SM-synchronous (one drive cycle per frame, so that the result
/// does not depend on the host's scheduling; with SYNC0 this host misses
/// cycles, see docs/ethercat.md), and the default commissioning meets the
/// thesis' limits over the wire (< 1 mm, < 100 um: the verdict, exit 0).
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
        &["--start-position", &START_M.to_string()],
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
    assert!(stderr.contains("SM-synchronous"), "the default: {stderr}");
    // the controller in the drive: written, read back, its own loops (CSP)
    // run the validation move within the thesis' limits
    let flat = stderr.split_whitespace().collect::<Vec<_>>().join(" ");
    let csp = flat
        .split_once("closed by the drive (CSP): ")
        .unwrap_or_else(|| panic!("the drive's loops: {flat}"))
        .1;
    let number_after = |text: &str, key: &str| -> f64 {
        let rest = text
            .split_once(key)
            .unwrap_or_else(|| panic!("`{key}` in {text}"))
            .1;
        rest.split_whitespace().next().unwrap().parse().unwrap()
    };
    let csp_error_mm = number_after(csp, "max cart error ");
    let csp_static_um = number_after(csp, "static ");
    eprintln!("wire, the drive's loops: {csp_error_mm:.3} mm, {csp_static_um:.1} um");
    assert!(
        flat.contains("parameters written by SDO and read back"),
        "{flat}"
    );
    assert!(
        csp_error_mm < MAX_TRACKING_ERROR_M * 1e3,
        "CSP: {csp_error_mm} mm"
    );
    assert!(
        csp_static_um < STATIC_ERROR_M * 1e6,
        "CSP: {csp_static_um} um"
    );
    assert!(
        stderr.contains("cycle jitter rms"),
        "jitter measured: {stderr}"
    );
    assert!(
        stderr.contains("bus down: drive in AL state INIT"),
        "bus down: {stderr}"
    );
    assert!(
        drive_log.contains("0 watchdog expiries; AL INIT, status code 0x0000"),
        "the drive left in INIT without an error: {drive_log}"
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

/// Ctrl-C during a commissioning over the wire: the run stops at the next
/// exchange, the drive is quick-stopped and switched off, the bus is brought
/// down to INIT (the drive's watchdog never fires, no AL error stays
/// latched), and the command ends with the safety-stop status and one line.
#[test]
fn ctrl_c_leaves_the_drive_switched_off_in_init_without_a_watchdog_error() {
    let net = match Netns::create("int") {
        Ok(n) => n,
        Err(e) => {
            eprintln!("SKIPPED: network namespace with a veth pair unavailable here ({e})");
            return;
        }
    };
    let out_dir = temp_dir("ethercat-ctrl-c");
    let mut drive = DriveProcess::spawn(
        &net,
        std::env::temp_dir().join(format!("beltune-vd-int-{}.log", std::process::id())),
        &["--start-position", &START_M.to_string(), "--no-dc"],
    )
    .unwrap_or_else(|e| panic!("virtual drive: {e}"));
    let log = std::env::temp_dir().join(format!("beltune-int-{}.log", std::process::id()));
    let mut child = beltune()
        .args([
            "commission",
            "--ethercat",
            &net.master_if,
            "--cycle-us",
            "1000",
        ])
        .args(["--frame-timeout-ms", "20", "--start-position"])
        .arg(START_M.to_string())
        .arg("--out")
        .arg(&out_dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::fs::File::create(&log).unwrap())
        .spawn()
        .unwrap();
    // wait until the axis is moving (a stage line after "take axis")
    let started = std::time::Instant::now();
    while !std::fs::read_to_string(&log)
        .unwrap_or_default()
        .contains("take axis")
    {
        assert!(
            started.elapsed() < std::time::Duration::from_secs(120),
            "no stage line: {}",
            std::fs::read_to_string(&log).unwrap_or_default()
        );
        if let Ok(Some(s)) = child.try_wait() {
            panic!(
                "ended early ({s}): {}",
                std::fs::read_to_string(&log).unwrap_or_default()
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    let status = child.wait().unwrap();
    let stderr = std::fs::read_to_string(&log).unwrap_or_default();
    let _ = std::fs::remove_file(&log);
    let drive_log = drive.stop();
    eprintln!("{stderr}\ndrive: {drive_log}");
    assert_eq!(status.code(), Some(3), "safety stop status: {stderr}");
    let last = stderr.trim_end().lines().last().unwrap_or("");
    assert!(last.contains("stopped by the operator"), "{last}");
    assert!(
        stderr.contains("bus down: drive in AL state INIT"),
        "{stderr}"
    );
    assert!(
        drive_log.contains("0 watchdog expiries; AL INIT, status code 0x0000"),
        "{drive_log}"
    );
    assert!(!out_dir.join("commissioning.json").exists(), "no result");
    let diagnostic = PathBuf::from(format!("{}-safety-stop", out_dir.display()));
    assert!(
        diagnostic.join("safety-stop.json").is_file(),
        "the diagnostic"
    );
    let _ = std::fs::remove_dir_all(&out_dir);
    let _ = std::fs::remove_dir_all(&diagnostic);
}

#[test]
fn a_bad_drive_profile_is_refused_before_the_bus_is_opened() {
    let dir = temp_dir("drive-profile");
    std::fs::create_dir_all(&dir).unwrap();
    let profile = dir.join("drive.toml");
    std::fs::write(
        &profile,
        "name = \"x\"\nvendor_id = 1\nproduct_code = 2\nmode = 8\n[[parameter]]\nquantity = \"k_pp\"\nindex = 0x2000\nsub = 1\ntype = \"REAL32\"\n",
    )
    .unwrap();
    let out = beltune()
        .args([
            "commission",
            "--ethercat",
            "nosuchif0",
            "--quiet",
            "--drive-profile",
        ])
        .arg(&profile)
        .args(["--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let _ = std::fs::remove_dir_all(&dir);
    // bad input (2), about the profile, not the interface: checked first
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--drive-profile") && stderr.contains("unknown quantity `k_pp`"),
        "{stderr}"
    );
}
