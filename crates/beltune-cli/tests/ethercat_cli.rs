//! Issue 14 on the command line: `beltune commission --ethercat IFACE`
//! against `beltune virtual-drive` on the other end of a veth pair whose drive
//! end lives in its own network namespace (created and always removed by the
//! test; skipped with a message where namespaces or veth pairs are
//! unavailable), and the one-line errors without a raw socket.

use beltune::model::rigs::{self, Plant};
use beltune::procedure::commission::{commission, CommissioningConfig, DataSheet};
use beltune::procedure::NoProgress;
use beltune::sim::{SimAxis, SimConfig};
use beltune_ethercat::drive::{DriveConfig, VirtualDrive};
use std::path::PathBuf;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

fn beltune() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
}

/// Issue 14: identified resonance and antiresonance within 2 % of the truth.
const FREQUENCY_TOLERANCE: f64 = 0.02;
/// Thesis chapter 5: static positioning error.
const STATIC_ERROR_M: f64 = 100e-6;
/// The dynamic error over the wire against the direct simulation at the same
/// 1 ms cycle (which itself misses the thesis' 1 mm at 1 kHz): one cycle of
/// bus transport delay, as in-process.
const WIRE_ERROR_FACTOR: f64 = 1.25;
const START_M: f64 = 0.05;

fn ip(args: &[&str]) -> Result<(), String> {
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

/// A namespace holding one end of a veth pair; removed on drop (also on panic).
struct Netns {
    ns: String,
    master_if: String,
    drive_if: String,
}

impl Netns {
    fn create() -> Result<Netns, String> {
        let id = std::process::id() % 100_000;
        let n = Netns {
            ns: format!("bt-cli-{id}"),
            master_if: format!("btcm{id}"),
            drive_if: format!("btcd{id}"),
        };
        ip(&["netns", "add", &n.ns])?;
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
}

impl Drop for Netns {
    fn drop(&mut self) {
        let _ = ip(&["link", "del", &self.master_if]);
        let _ = ip(&["netns", "del", &self.ns]);
    }
}

/// Stops the drive thread when the test ends (also on panic).
struct StopOnDrop(Arc<AtomicBool>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn commissioning_over_a_veth_pair_against_the_virtual_drive() {
    let net = match Netns::create() {
        Ok(n) => n,
        Err(e) => {
            eprintln!("SKIPPED: network namespace with a veth pair unavailable here ({e})");
            return;
        }
    };
    // the virtual drive on a thread that enters the namespace (SM-synchronous,
    // no DC: one drive cycle per frame, so that the result does not depend on
    // the scheduling of a shared test machine)
    let stop = Arc::new(AtomicBool::new(false));
    let (ns, drive_if, stop2) = (net.ns.clone(), net.drive_if.clone(), Arc::clone(&stop));
    let server = std::thread::spawn(move || -> Result<u64, String> {
        let f = std::fs::File::open(format!("/run/netns/{ns}")).map_err(|e| e.to_string())?;
        use std::os::fd::AsRawFd;
        // SAFETY: setns on a namespace descriptor we hold; this thread only.
        if unsafe { libc::setns(f.as_raw_fd(), libc::CLONE_NEWNET) } != 0 {
            return Err(std::io::Error::last_os_error().to_string());
        }
        let plant = rigs::builtin("egc70", None).unwrap();
        let cfg = DriveConfig {
            sim: SimConfig {
                seed: 1,
                initial_cart_position_m: Some(START_M),
                ..SimConfig::default()
            },
            distributed_clocks: false,
            ..DriveConfig::default()
        };
        let mut drive = VirtualDrive::new(&plant, cfg).map_err(|e| e.to_string())?;
        let stats = beltune_ethercat::serve::serve(&drive_if, &mut drive, &stop2)
            .map_err(|e| e.to_string())?;
        Ok(stats.frames)
    });
    let _stop = StopOnDrop(Arc::clone(&stop));
    std::thread::sleep(std::time::Duration::from_millis(200));
    let out_dir = temp_dir("ethercat");
    let out = beltune()
        .args([
            "commission",
            "--ethercat",
            &net.master_if,
            "--cycle-us",
            "1000",
        ])
        // the drive is a process on the same shared (2-core, busy) machine:
        // its answers can come tens of ms late, which a real drive never does
        .args(["--frame-timeout-ms", "100"])
        // the verdict (issue 16) judges the motor-side move of a drive without
        // load-side encoder, over a bus with late frames: this test checks the
        // wire path, not the thesis' 1 mm (exit status 5 otherwise)
        .args([
            "--max-tracking-error",
            "0.01",
            "--max-static-error",
            "0.001",
        ])
        .args(["--start-position", &START_M.to_string(), "--quiet", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    stop.store(true, Ordering::Relaxed);
    let frames = server.join().unwrap().unwrap();
    assert!(
        out.status.success(),
        "commission over the wire failed: {stderr} ({frames} frames)"
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
        max_err < WIRE_ERROR_FACTOR * d,
        "max cart error {:.3} mm, direct {:.3} mm",
        max_err * 1e3,
        d * 1e3
    );
    let _ = std::fs::remove_dir_all(&out_dir);
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
