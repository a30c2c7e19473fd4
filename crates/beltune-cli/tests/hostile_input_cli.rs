//! Hostile and careless input through the command line: bad input, special files, partial
//! failures. One regression test per behaviour (the model-file schema
//! is in `schema_cli.rs`, the server's limits in
//! `serve_limits.rs`), plus the output history.

mod common;

use common::bench::{self, bin, measured};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-i13-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run with a deadline: a hang is a test failure, not a stuck suite.
fn run_within(cmd: &mut Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!(
                "{cmd:?} did not finish within {limit:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Expect bad input (exit status 2), one stderr line with every needle.
fn expect_bad_input(cmd: &mut Command, needles: &[&str]) -> String {
    let o = run_within(cmd, Duration::from_secs(60));
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{cmd:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in {err}");
    }
    err
}

/// The egc70 plant as a TOML file, with `edit` applied to its text.
fn egc70_toml(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let plant = beltune::model::Plant::Physical(beltune::model::rigs::egc70_params(11.2));
    let text = edit(toml::to_string(&plant).unwrap());
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Replace the value of `key = ...` in a TOML text.
fn set_key(text: String, key: &str, value: &str) -> String {
    let prefix = format!("{key} = ");
    let mut found = false;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with(&prefix) {
                found = true;
                format!("{prefix}{value}")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(found, "no key {key} in {text}");
    out.join("\n") + "\n"
}

/// A synthetic motion record for `beltune friction` (linear axis, m and N).
fn motion_csv(dir: &Path, bad_cell: Option<(usize, &str)>) -> PathBuf {
    let mut s = String::from("time_s,pos_m,force_n\n");
    for k in 0..4000 {
        let t = k as f64 / 500.0;
        let w = 2.0 * std::f64::consts::PI * 0.5;
        let x = 0.2 * (w * t).sin();
        let v = 0.2 * w * (w * t).cos();
        let a = -0.2 * w * w * (w * t).sin();
        let f = 13.9 * a + 160.0 * v + 10.0 * v.signum() + 3.0;
        match bad_cell {
            Some((row, cell)) if row == k => s.push_str(&format!("{t},{x},{cell}\n")),
            _ => s.push_str(&format!("{t},{x},{f}\n")),
        }
    }
    let p = dir.join("motion.csv");
    std::fs::write(&p, s).unwrap();
    p
}

/// The recorded-data commissioning of the bench file into `out` (fast: no
/// axis), with the drive's current limit of 3.1 A.
fn commission_recorded(out: Option<&Path>) -> Command {
    let mut c = commission_recorded_without_limit(out);
    c.args(["--torque-limit", "3.1"]);
    c
}

/// [`commission_recorded`] without `--torque-limit`.
fn commission_recorded_without_limit(out: Option<&Path>) -> Command {
    let mut c = bench::on_record("commission");
    c.arg("--quiet");
    if let Some(out) = out {
        c.arg("--out").arg(out);
    }
    c
}

#[test]
fn one_absurd_friction_cell_never_reaches_a_file() {
    let dir = tmpdir("friction-cell");
    for cell in ["1e308", "1e200", "-1e160"] {
        let csv = motion_csv(&dir, Some((1234, cell)));
        let json = dir.join("friction.json");
        let err = expect_bad_input(
            bin()
                .args(["friction", "--csv"])
                .arg(&csv)
                .args([
                    "--time",
                    "time_s",
                    "--torque",
                    "force_n",
                    "--position",
                    "pos_m",
                    "--json",
                ])
                .arg(&json),
            &["torque", "too large"],
        );
        assert!(!err.contains("NaN") && !err.contains("inf"), "{err}");
        assert!(!json.exists(), "{cell}: a result was written");
    }
    // The clean record still fits (J = 13.9 kg within 5 %).
    let csv = motion_csv(&dir, None);
    let o = bin()
        .args(["friction", "--csv"])
        .arg(&csv)
        .args([
            "--time",
            "time_s",
            "--torque",
            "force_n",
            "--position",
            "pos_m",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let inertia: f64 = text
        .split("inertia ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!((inertia - 13.9).abs() / 13.9 < 0.05, "{inertia}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_travel_window_beyond_the_stroke_is_refused() {
    for window in ["-1,2", "0,0.7", "-0.05,0.5"] {
        expect_bad_input(
            bin().args([
                "commission",
                "--quiet",
                &format!("--travel-window={window}"),
            ]),
            &["travel window", "inside the stroke 0..0.6 m"],
        );
    }
}

#[test]
fn sizes_that_would_abort_or_overflow_are_bad_input() {
    let dir = tmpdir("sizes");
    for args in [
        &["commission", "--prbs-order", "24"][..],
        &["commission", "--prbs-order", "32"],
        &["commission", "--prbs-clock-ms", "429496729500"],
        &["commission", "--prbs-clock-ms", "nan"],
        &[
            "commission",
            "--prbs-order",
            "18",
            "--prbs-clock-ms",
            "409.6",
        ],
    ] {
        expect_bad_input(bin().args(args), &["prbs"]);
    }
    let model = dir.join("m.toml");
    std::fs::write(
        &model,
        common::table_a4_model_toml() + "dead_time_s = 1e-3\n",
    )
    .unwrap();
    for ts in ["1e-9", "3e-8", "5e-324", "1"] {
        expect_bad_input(
            bin()
                .args(["design", "--model"])
                .arg(&model)
                .args(["--ts", ts]),
            &["--ts", "sampling time"],
        );
    }
    let csv = measured();
    for (flag, value) in [
        ("--skip-periods", "18446744073709551615"),
        ("--skip-periods", "1001"),
        ("--period-samples", "9223372036854775808"),
        ("--period-samples", "3"),
    ] {
        expect_bad_input(
            bin()
                .args(["identify", "--csv"])
                .arg(&csv)
                .args(["--time", "t_s", "--input", "iq_ref_A"])
                .args(["--output", "theta_motor_rad", flag, value]),
            &[flag],
        );
    }
    // The library itself: a skip count that overflows is "too short".
    let cfg = beltune::ident::EtfeConfig {
        ts_s: 1e-3,
        period_samples: 8,
        skip_periods: usize::MAX,
        ..beltune::ident::EtfeConfig::default()
    };
    let x = vec![0.0; 64];
    assert!(beltune::ident::etfe::etfe(&x, &x, &cfg).is_err());
    let plant = egc70_toml(&dir, "ts.toml", |t| set_key(t, "ts_s", "5e-324"));
    expect_bad_input(
        bin().args(["plant", "show", "--plant"]).arg(&plant),
        &["ts_s", "5e-324"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn no_input_hangs_or_grows_without_bound() {
    let dir = tmpdir("hangs");
    let limit = Duration::from_secs(30);
    for (key, value) in [
        ("d_c_n_s_per_m", "1e308"),
        ("theta_end_pulley_kg_m2", "5e-324"),
        ("c_b_n", "1e300"),
    ] {
        let plant = egc70_toml(&dir, "p.toml", |t| set_key(t, key, value));
        let o = run_within(
            bin()
                .args(["commission", "--quiet", "--out"])
                .arg(dir.join("out"))
                .arg("--plant")
                .arg(&plant),
            limit,
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{key}: {err}");
        assert!(err.contains(key), "{err}");
    }
    // The simulator refuses a plant inside the bounds that would need too
    // many sub-steps, instead of running for hours.
    let mut p = beltune::model::rigs::egc70_params(0.0);
    p.m_cart_kg = 1e-3;
    p.d_c_n_s_per_m = 1e6;
    let e = beltune::sim::SimAxis::new(
        &beltune::model::Plant::Physical(p),
        beltune::sim::SimConfig::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("sub-steps"), "{e}");
    // Devices and FIFOs are refused at once, not read forever.
    let fifo = dir.join("fifo.csv");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid path; mkfifo has no other preconditions.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    for path in [Path::new("/dev/zero"), fifo.as_path()] {
        let mut show = bin();
        show.args(["plant", "show", "--json", "--plant"]).arg(path);
        let mut design = bin();
        design.args(["design", "--model"]).arg(path);
        let mut identify = bin();
        identify
            .args(["identify", "--csv"])
            .arg(path)
            .args(["--time", "t", "--input", "u", "--output", "y"]);
        let mut cmds = [show, design, identify];
        for cmd in &mut cmds {
            let o = run_within(cmd, limit);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{path:?}: {err}");
            assert!(err.contains("not a regular file"), "{err}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `(k_p in commissioning.json, k_p in controller.toml)` of a result folder.
fn gains_of(dir: &Path) -> (f64, f64) {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("commissioning.json")).unwrap())
            .unwrap();
    let toml: toml::Value =
        toml::from_str(&std::fs::read_to_string(dir.join("controller.toml")).unwrap()).unwrap();
    (
        json["controller"]["k_p"].as_f64().unwrap(),
        toml["gains"]["k_p_nm_s_per_rad"].as_float().unwrap(),
    )
}

#[test]
fn a_killed_commissioning_leaves_the_old_or_the_new_set() {
    let dir = tmpdir("kill");
    let out = dir.join("result");
    // The old set: the same record without the dead time (other gains).
    let o = commission_recorded(Some(&out)).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The duration of the replacing run (it also estimates the dead time),
    // then the old set again.
    let t0 = Instant::now();
    let o = commission_recorded(Some(&out))
        .args(["--force", "--actual-torque", "iq_meas_A"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run_time = t0.elapsed();
    let o = commission_recorded(Some(&out))
        .arg("--force")
        .output()
        .unwrap();
    assert!(o.status.success());
    let read_set = || -> Vec<Vec<u8>> {
        ["commissioning.json", "controller.toml", "report.html"]
            .iter()
            .map(|f| std::fs::read(out.join(f)).unwrap())
            .collect()
    };
    let mut old = read_set();
    let (a, b) = gains_of(&out);
    assert_eq!(a, b);
    // Kill the replacing run at instants spread over its whole duration,
    // denser near the end where the files are written.
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut seen_new = false;
    let mut outcomes = [0usize; 2];
    for k in 0..24 {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        let u = (rng % 1000) as f64 / 1000.0;
        // One in three anywhere, the rest around the end, where the files are written.
        let frac = if k % 3 == 0 { u } else { 0.85 + 0.25 * u };
        let mut child = commission_recorded(Some(&out))
            .args(["--force", "--actual-torque", "iq_meas_A"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(run_time.mul_f64(frac));
        let _ = child.kill();
        let _ = child.wait();
        let now = read_set();
        // json and report carry the command line (provenance), so they
        // differ from the old set exactly when the new set is in place; the
        // controller may coincide, but must agree with the json.
        let same: Vec<bool> = now.iter().zip(&old).map(|(n, o)| n == o).collect();
        if same.iter().all(|s| *s) {
            outcomes[0] += 1;
            continue;
        }
        outcomes[1] += 1;
        assert!(!same[0] && !same[2], "kill {k}: a mixed set {same:?}");
        let (a, b) = gains_of(&out);
        assert_eq!(a, b, "kill {k}: json and toml disagree");
        seen_new = true;
        // Back to an old set for the next kill (its json has another
        // computation time, so it is read again).
        let o = commission_recorded(Some(&out))
            .arg("--force")
            .output()
            .unwrap();
        assert!(o.status.success());
        old = read_set();
    }
    // A finished run cleans the temporaries a killed one left beside `out`.
    let o = commission_recorded(Some(&out))
        .arg("--force")
        .output()
        .unwrap();
    assert!(o.status.success());
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    // beside the result: the history database the runs are recorded in
    assert_eq!(
        names,
        ["beltune-history.sqlite", "result"],
        "seen new set: {seen_new}"
    );
    eprintln!(
        "kills leaving the old set: {}, the new set: {}",
        outcomes[0], outcomes[1]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn force_replaces_only_beltunes_files_and_keeps_the_users() {
    // A result folder a user has worked in: sources, a repository, notes and
    // the tuning page's saved sets beside the result.
    let dir = tmpdir("force-keeps");
    let proj = dir.join("proj");
    let o = commission_recorded(Some(&proj)).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let users: [(&str, &str); 5] = [
        ("src/main.c", "int main(void) { return 0; }\n"),
        (".git/HEAD", "ref: refs/heads/main\n"),
        ("notes.txt", "belt re-tensioned on Monday\n"),
        (
            "tuned-20261203T101010Z/controller.toml",
            "# saved by the page\n",
        ),
        ("tuned-20261203T101010Z/commissioning.json", "{}\n"),
    ];
    for (name, text) in users {
        let p = proj.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
    }
    let before = gains_of(&proj);
    // the same record with its dead time estimated: other gains
    let o = commission_recorded(Some(&proj))
        .args(["--force", "--actual-torque", "iq_meas_A"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (name, text) in users {
        assert_eq!(
            std::fs::read_to_string(proj.join(name)).unwrap_or_default(),
            text,
            "{name} was not kept"
        );
    }
    assert_ne!(gains_of(&proj), before, "the result itself was replaced");
    // A user's file under the name of a result file is refused, not replaced,
    // and the folder stays as it was.
    std::fs::remove_file(proj.join("frf.csv")).unwrap();
    let manifest = proj.join(".beltune-manifest");
    let listed = std::fs::read_to_string(&manifest).unwrap();
    std::fs::write(&manifest, listed.replace("frf.csv\n", "")).unwrap();
    std::fs::write(proj.join("frf.csv"), "my own measurement\n").unwrap();
    let err = expect_bad_input(
        commission_recorded(Some(&proj)).arg("--force"),
        &["frf.csv", "move it away"],
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert_eq!(
        std::fs::read_to_string(proj.join("frf.csv")).unwrap(),
        "my own measurement\n"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn outputs_write_through_devices_fifos_and_symlinks() {
    let dir = tmpdir("special");
    let traj = |samples: &Path| {
        let mut c = bin();
        c.args([
            "trajectory",
            "--start",
            "0,0,0",
            "--target",
            "0.1,0,0",
            "--v-max",
            "1",
            "--a-max",
            "10",
            "--j-max",
            "1000",
            "--ts",
            "1e-3",
            "--samples",
        ])
        .arg(samples);
        c
    };
    // A character device stays a device.
    let o = traj(Path::new("/dev/null")).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
    // A symlink stays a symlink, its target gets the samples.
    let target = dir.join("target.csv");
    std::fs::write(&target, "old").unwrap();
    let link = dir.join("link.csv");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let o = traj(&link).output().unwrap();
    assert!(o.status.success());
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(&target)
        .unwrap()
        .starts_with("t_s,position_m"));
    // A FIFO stays a FIFO, its reader gets the samples.
    let fifo = dir.join("fifo");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid path; mkfifo has no other preconditions.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let o = run_within(&mut traj(&fifo), Duration::from_secs(30));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(reader.join().unwrap().starts_with("t_s,position_m"));
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn built_in_plant_names_win_over_folders_of_that_name() {
    let dir = tmpdir("names");
    for name in ["egc70", "sim-c"] {
        std::fs::create_dir_all(dir.join(name)).unwrap();
        let o = bin()
            .current_dir(&dir)
            .args(["plant", "show", "--json", "--plant", name])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["plant"], name);
    }
    // commission resolves the name before it checks the window.
    expect_bad_input(
        bin()
            .current_dir(&dir)
            .args(["commission", "--plant", "egc70", "--travel-window", "-1,2"]),
        &["travel window"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn absurd_plant_values_are_refused_never_printed_as_inf_or_nan() {
    let dir = tmpdir("bounds");
    for (key, value) in [
        ("m_cart_kg", "1e308"),
        ("theta_motor_kg_m2", "1e308"),
        ("payload_kg", "1e9"),
        ("stroke_m", "1e300"),
        ("torque_max_nm", "1e300"),
        ("d_m_n_s_per_m", "1e308"),
    ] {
        let plant = egc70_toml(&dir, "p.toml", |t| set_key(t, key, value));
        for json in [false, true] {
            let mut c = bin();
            c.args(["plant", "show", "--plant"]).arg(&plant);
            if json {
                c.arg("--json");
            }
            let err = expect_bad_input(&mut c, &[key, "plausible"]);
            for bad in ["inf", "NaN", "null"] {
                assert!(!err.contains(bad), "{err}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn values_that_would_be_ignored_are_errors() {
    let dir = tmpdir("ignored");
    // --payload with a plant file is applied (a negative one is refused).
    let plant = egc70_toml(&dir, "p.toml", |t| t);
    expect_bad_input(
        bin()
            .args(["commission", "--payload", "-1", "--plant"])
            .arg(&plant),
        &["payload"],
    );
    expect_bad_input(bin().args(["commission", "--tilt", "720"]), &["--tilt"]);
    expect_bad_input(
        bin().args(["commission", "--tilt", "10", "--plant", "sim-a"]),
        &["--tilt", "physical"],
    );
    expect_bad_input(
        bin().args(["commission", "--torque-limit=-5", "--inertia", "nan"]),
        &["--torque-limit", "--inertia", "recorded data"],
    );
    expect_bad_input(
        commission_recorded_without_limit(Some(&dir.join("out"))).args(["--torque-limit", "1e300"]),
        &["--torque-limit"],
    );
    expect_bad_input(
        commission_recorded(Some(&dir.join("out"))).args(["--seed", "3"]),
        &["--seed", "recorded data"],
    );
    expect_bad_input(
        commission_recorded(Some(&dir.join("out"))).args(["--inertia", "nan"]),
        &["--inertia"],
    );
    assert!(!dir.join("out").exists());
    // an unknown key in a design model (a typo) is named, not ignored
    let model = dir.join("m.toml");
    std::fs::write(&model, common::table_a4_model_toml() + "colomb_nm = 0.1\n").unwrap();
    expect_bad_input(
        bin().args(["design", "--model"]).arg(&model),
        &["m.toml", "unknown key `colomb_nm`"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn negative_numbers_reach_their_own_checks() {
    for args in [
        &[
            "commission",
            "--start-position",
            "-0.005",
            "--travel-window",
            "-1,2",
        ][..],
        &[
            "commission",
            "--dynamics",
            "-0.1",
            "--travel-window",
            "-1,2",
        ],
        &["commission", "--seed", "-1"],
        &["commission", "--excitation-amplitude", "-1"],
    ] {
        let o = bin().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
    // The value is parsed and refused by its own rule.
    let o = bin()
        .args(["commission", "--excitation-amplitude", "-1"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("--excitation-amplitude -1"));
}

#[test]
fn messages_are_one_readable_line() {
    let dir = tmpdir("messages");
    // A folder where a file is expected: the cause once.
    let o = bin()
        .args(["design", "--model"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.matches("directory").count(), 1, "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    // Numbers in exponent form, not 300 digits; no Debug dumps.
    let plant = egc70_toml(&dir, "p.toml", |t| set_key(t, "m_cart_kg", "1e308"));
    let err = expect_bad_input(
        bin().args(["plant", "show", "--plant"]).arg(&plant),
        &["1e308"],
    );
    assert!(err.len() < 300, "{err}");
    assert!(!err.contains("Params {"), "{err}");
    // A header-only CSV says so.
    let csv = dir.join("empty.csv");
    std::fs::write(&csv, "t,u,y\n").unwrap();
    expect_bad_input(
        bin()
            .args(["identify", "--csv"])
            .arg(&csv)
            .args(["--time", "t", "--input", "u", "--output", "y"]),
        &["no data rows"],
    );
    // The tilt in degrees, as given.
    expect_bad_input(
        bin().args(["commission", "--tilt", "720"]),
        &["--tilt 720", "[-90, 90]"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bad values given as flags or file keys are named as the
/// user wrote them (the flag, or the file's own key in its units), never by
/// the library's field names, and no message is a Debug dump.
#[test]
fn messages_name_flags_and_keys_as_written() {
    let dir = tmpdir("words");
    let model = dir.join("m.toml");
    let base = common::table_a4_model_toml();
    std::fs::write(&model, &base).unwrap();
    let current = dir.join("current.toml");
    std::fs::write(
        &current,
        format!("{base}units = \"current\"\ntorque_max_a = -3\n"),
    )
    .unwrap();
    let light = dir.join("light.toml");
    std::fs::write(&light, base.replace("m_c = 13.44", "m_c = 1e-9")).unwrap();
    let motion = motion_csv(&dir, None);
    let design = |extra: &[&str]| {
        let mut c = bin();
        c.args(["design", "--model"]).arg(&model).args(extra);
        c
    };
    let friction = |extra: &[&str]| {
        let mut c = bin();
        c.args(["friction", "--csv"])
            .arg(&motion)
            .args([
                "--time",
                "time_s",
                "--torque",
                "force_n",
                "--position",
                "pos_m",
            ])
            .args(extra);
        c
    };
    let cases: Vec<(Command, Vec<&str>)> = vec![
        (
            design(&["--pm-velocity", "200"]),
            vec!["--pm-velocity 200", "deg"],
        ),
        (design(&["--pm-position", "0"]), vec!["--pm-position 0"]),
        (
            design(&["--filter-attenuation-db", "5"]),
            vec!["--filter-attenuation-db 5", "dB"],
        ),
        (
            design(&["--resonance-suppression-db", "3"]),
            vec!["--resonance-suppression-db 3"],
        ),
        (design(&["--dynamics", "2"]), vec!["--dynamics 2"]),
        (design(&["--ts", "-1"]), vec!["--ts -1", "s"]),
        // before the commissioning moves the axis
        (
            {
                let mut c = bin();
                c.args(["commission", "--quiet", "--pm-velocity", "190"]);
                c
            },
            vec!["--pm-velocity 190"],
        ),
        (
            friction(&["--cutoff-hz", "-1"]),
            vec!["--cutoff-hz -1", "Hz"],
        ),
        (
            friction(&["--min-speed-fraction", "2"]),
            vec!["--min-speed-fraction 2"],
        ),
        (
            {
                let mut c = bin();
                c.args(["design", "--model"]).arg(&current);
                c
            },
            vec!["current.toml", "`torque_max_a` = -3"],
        ),
        (
            {
                let mut c = bin();
                c.args(["design", "--model"]).arg(&light);
                c
            },
            vec!["light.toml", "default sampling time"],
        ),
    ];
    let internal = [
        "pm_velocity_deg",
        "pm_position_deg",
        "resonance_suppression_db",
        "filter_attenuation_db",
        "`dynamics`",
        "cutoff_hz",
        "min_speed_fraction",
        "torque_max_nm",
        "`ts_s`",
        "invalid parameter `",
        "commissioning stopped",
    ];
    for (mut cmd, needles) in cases {
        let err = expect_bad_input(&mut cmd, &needles);
        assert_eq!(err.trim_end().lines().count(), 1, "{cmd:?}: {err}");
        for name in internal {
            assert!(
                !err.contains(name),
                "{cmd:?}: internal name `{name}` in {err}"
            );
        }
        // a Debug dump: `Name { field: ... }` or `Variant("...")`
        let dump = err
            .split_whitespace()
            .zip(err.split_whitespace().skip(1))
            .any(|(a, b)| a.chars().next().is_some_and(|c| c.is_ascii_uppercase()) && b == "{")
            || err.contains("(\"");
        assert!(!dump, "{cmd:?}: Debug dump in {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn inputs_are_never_overwritten_or_confused() {
    let dir = tmpdir("traps");
    let csv = motion_csv(&dir, None);
    let before = std::fs::read(&csv).unwrap();
    expect_bad_input(
        bin()
            .args(["friction", "--csv"])
            .arg(&csv)
            .args(["--time", "time_s", "--torque", "force_n"])
            .args(["--position", "pos_m", "--json"])
            .arg(&csv),
        &["--json", "overwritten"],
    );
    assert_eq!(std::fs::read(&csv).unwrap(), before);
    let data = measured();
    expect_bad_input(
        bin()
            .args(["identify", "--csv"])
            .arg(&data)
            .args(["--time", "t_s", "--input", "iq_ref_A"])
            .args(["--output", "theta_motor_rad", "--json"])
            .arg(&data),
        &["--json", "overwritten"],
    );
    expect_bad_input(
        bin()
            .args(["identify", "--csv"])
            .arg(&data)
            .args(["--time", "t_s", "--input", "iq_ref_A"])
            .args(["--output", "theta_motor_rad", "--actual-torque", "t_s"]),
        &["--actual-torque", "same column"],
    );
    let dup = dir.join("dup.csv");
    std::fs::write(&dup, "t,u,u,y\n0,1,2,3\n0.001,1,2,3\n").unwrap();
    expect_bad_input(
        bin()
            .args(["identify", "--csv"])
            .arg(&dup)
            .args(["--time", "t", "--input", "u", "--output", "y"]),
        &["`u`", "2 times"],
    );
    // commission --out over the folder holding its input.
    let inside = dir.join("rec");
    std::fs::create_dir_all(&inside).unwrap();
    std::fs::copy(&data, inside.join("m.csv.gz")).unwrap();
    let o = bin()
        .args(["commission", "--quiet", "--force", "--csv"])
        .arg(inside.join("m.csv.gz"))
        .args(["--input", "iq_ref_A", "--output", "theta_motor_rad"])
        .args(["--period-samples", "2500", "--torque-limit", "3.1", "--out"])
        .arg(&inside)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("holds the input"));
    assert!(inside.join("m.csv.gz").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn each_run_keeps_its_folder_and_latest_points_at_the_newest() {
    let dir = tmpdir("history");
    let mut cmd = commission_recorded(None);
    let o = cmd.current_dir(&dir).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = commission_recorded(None)
        .args(["--actual-torque", "iq_meas_A"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let root = dir.join("commissioning");
    let mut runs: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "latest")
        .collect();
    runs.sort();
    assert_eq!(runs.len(), 2, "{runs:?}");
    let latest = std::fs::read_link(root.join("latest")).unwrap();
    assert_eq!(latest, Path::new(&runs[1]));
    // The newest run measured the dead time, the first did not.
    let json = |run: &str| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(root.join(run).join("commissioning.json")).unwrap(),
        )
        .unwrap()
    };
    assert_ne!(
        json(&runs[0])["identified"]["dead_time_s"],
        json("latest")["identified"]["dead_time_s"]
    );
    // --out over an existing result needs --force.
    let out = root.join(&runs[0]);
    expect_bad_input(&mut commission_recorded(Some(&out)), &["--force"]);
    let o = commission_recorded(Some(&out))
        .arg("--force")
        .output()
        .unwrap();
    assert!(o.status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn absurd_friction_in_a_design_model_is_refused() {
    let dir = tmpdir("design-friction");
    let model = dir.join("m.toml");
    for (key, value) in [("coulomb_nm", "1e308"), ("viscous_nm_s_per_rad", "1e300")] {
        std::fs::write(
            &model,
            format!(
                "{}dead_time_s = 1e-3\n{key} = {value}\n",
                common::table_a4_model_toml()
            ),
        )
        .unwrap();
        expect_bad_input(
            bin().args(["design", "--model"]).arg(&model),
            &["friction", "plausible"],
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Longest run of digits in `text` (a number printed in full is a run).
fn longest_digit_run(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

#[test]
fn numbers_in_messages_are_short_whatever_the_value() {
    let dir = tmpdir("short-numbers");
    let e = dir.join("e.csv");
    let plant = egc70_toml(&dir, "tiny-stroke.toml", |t| {
        set_key(t, "stroke_m", "5e-324")
    });
    let cases: Vec<Vec<String>> = vec![
        vec![
            "commission",
            "--plant",
            "sim-a",
            "--travel-window",
            "1e308,1e308",
        ],
        vec![
            "commission",
            "--plant",
            "sim-a",
            "--max-tracking-error=-1e308",
        ],
        vec![
            "commission",
            "--plant",
            "sim-a",
            "--max-tracking-error",
            "1e308",
        ],
        vec![
            "commission",
            "--plant",
            "sim-a",
            "--resonance-suppression-db=-1e308",
        ],
        vec![
            "trajectory",
            "--start",
            "0,0,0",
            "--target",
            "0.1,0,0",
            "--v-max",
            "1",
            "--a-max",
            "10",
            "--j-max",
            "100",
            "--j-min=-1e308",
        ],
        vec![
            "excitation",
            "--kind",
            "prbs",
            "--ts",
            "1e-300",
            "--amplitude",
            "1",
            "--out",
        ],
        vec![
            "excitation",
            "--kind",
            "prbs",
            "--ts",
            "1e-4",
            "--amplitude=-5e-324",
            "--out",
        ],
    ]
    .into_iter()
    .map(|c| c.into_iter().map(String::from).collect())
    .collect();
    for mut case in cases {
        if case.last().is_some_and(|a| a == "--out") {
            case.push(e.display().to_string());
        }
        let err = expect_bad_input(bin().args(&case), &[]);
        assert!(
            longest_digit_run(&err) <= 20,
            "{case:?}: a number printed in full: {err}"
        );
        assert!(
            !err.contains("inf") && !err.contains("NaN"),
            "{case:?}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{case:?}: {err}");
    }
    let err = expect_bad_input(
        bin().args(["commission", "--plant"]).arg(&plant),
        &["travel window"],
    );
    assert!(longest_digit_run(&err) <= 20, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_missing_input_file_is_bad_input_in_every_command() {
    let dir = tmpdir("missing-inputs");
    let gone = dir.join("gone");
    let out = dir.join("out.html");
    let g = |name: &str| gone.join(name).display().to_string();
    let o = out.display().to_string();
    let cases: Vec<Vec<String>> = vec![
        vec!["design".into(), "--model".into(), g("model.toml")],
        vec![
            "export".into(),
            "--controller".into(),
            g("controller.toml"),
            "--lang".into(),
            "c".into(),
        ],
        vec!["compare".into(), g("a"), g("b"), "--out".into(), o.clone()],
        vec!["serve".into(), "--commissioning".into(), g("run")],
        vec!["commission".into(), "--plant".into(), g("plant.toml")],
        vec!["health".into(), "--baseline".into(), g("run")],
    ];
    for case in cases {
        let err = expect_bad_input(bin().args(&case), &["gone"]);
        assert_eq!(err.trim().lines().count(), 1, "{case:?}: {err}");
    }
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_non_loopback_bind_is_bad_input_before_anything_listens() {
    expect_bad_input(
        bin().args(["serve", "--bind", "0.0.0.0", "--port", "0"]),
        &["--allow-remote"],
    );
}

#[test]
fn excitation_refuses_what_commission_cannot_analyze() {
    let dir = tmpdir("excitation-limits");
    let out = dir.join("e.csv");
    let run = |extra: &[&str], needles: &[&str]| {
        expect_bad_input(
            bin()
                .args(["excitation", "--ts", "1e-4", "--amplitude", "0.1", "--out"])
                .arg(&out)
                .args(extra),
            needles,
        )
    };
    for n in ["2", "3"] {
        run(&["--kind", "chirp", "--period-samples", n], &["at least 4"]);
    }
    run(&["--kind", "chirp", "--f-end-hz", "6000"], &["Nyquist"]);
    // the order's range as the help states it
    for order in ["1", "21"] {
        run(&["--kind", "prbs", "--order", order], &["2..=20"]);
    }
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_dead_time_the_design_cannot_hold_is_refused_before_anything_simulates() {
    // 1 ms at 1 us sampling is 1000 samples of dead time: the design holds
    // 256. It used to simulate for over a minute and 390 MB first.
    let dir = tmpdir("dead-time-samples");
    let plant = egc70_toml(&dir, "fast-sampling.toml", |t| set_key(t, "ts_s", "1e-6"));
    let o = run_within(
        bin()
            .args(["commission", "--quiet", "--plant"])
            .arg(&plant)
            .arg("--out")
            .arg(dir.join("out")),
        Duration::from_secs(20),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("dead_time_s") && err.contains("256"), "{err}");
    assert!(!dir.join("out").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_required_flag_missing_from_a_config_file_is_named() {
    let dir = tmpdir("config-required");
    let cfg = dir.join("c.toml");
    std::fs::write(&cfg, "csv = \"rec.csv\"\n").unwrap();
    let o = run_within(
        bin().args(["commission", "--config"]).arg(&cfg),
        Duration::from_secs(20),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--input") && err.contains("--output"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
