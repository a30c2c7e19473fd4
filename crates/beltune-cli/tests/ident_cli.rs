//! End-to-end tests of `beltune identify` and `beltune friction` on CSV files.

mod common;

use common::bench::{self, bin, measured};
use std::path::{Path, PathBuf};

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-ident-cli-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `beltune identify` on the bench recording: 20 periods of 2500 samples, the
/// first discarded, free inertia, current units.
fn identify_measured() -> std::process::Command {
    let mut c = bench::on_record("identify");
    c.args([
        "--time",
        "t_s",
        "--skip-periods",
        "1",
        "--free-inertia",
        "--current-units",
    ]);
    c
}

/// Run, expect failure as bad input (exit status 2) with ONE stderr line
/// containing all `needles`.
fn expect_error(args: &[&str], needles: &[&str]) {
    let out = bin().args(args).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in {err}");
    }
}

#[test]
fn identify_measured_bench_writes_model_and_frf() {
    let dir = tmpdir("measured");
    let json = dir.join("model.json");
    let frf = dir.join("frf.csv");
    let out = identify_measured()
        .args(["--actual-torque", "iq_meas_A", "--json"])
        .arg(&json)
        .arg("--frf-csv")
        .arg(&frf)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for key in [
        "f_r_hz",
        "f_z_hz",
        "theta_e",
        "m_c",
        "c",
        "d_m",
        "d_c",
        "fit_rms_db",
        "i_t",
        "dead_time_s",
    ] {
        assert!(
            v["identified"][key].is_number(),
            "{key}: {}",
            v["identified"][key]
        );
    }
    // the fitted modes within 3 % of the measured FRF's peak and dip
    let f_r = v["identified"]["f_r_hz"].as_f64().unwrap();
    let f_z = v["identified"]["f_z_hz"].as_f64().unwrap();
    let peak = v["fit"]["features"]["resonance_hz"].as_f64().unwrap();
    let dip = v["fit"]["features"]["antiresonance_hz"].as_f64().unwrap();
    assert!(
        (f_r / peak - 1.0).abs() < 0.03 && (f_z / dip - 1.0).abs() < 0.03,
        "{v}"
    );
    assert_eq!(v["identified"]["i_t"].as_f64(), Some(1.0));
    assert_eq!(v["identified"]["units"].as_str(), Some("current"));
    assert_eq!(v["schema_version"].as_u64(), Some(1));
    let text = std::fs::read_to_string(&frf).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().contains("coherence"));
    // 2500-sample periods: lines 0..=1250
    assert_eq!(lines.count(), 1251);
    // period detection gives the same result without --period-samples
    let out2 = bin()
        .args(["identify", "--csv"])
        .arg(measured())
        .args([
            "--time",
            "t_s",
            "--input",
            "iq_ref_A",
            "--output",
            "theta_motor_rad",
            "--current-units",
        ])
        .output()
        .unwrap();
    assert!(out2.status.success());
    assert!(String::from_utf8_lossy(&out2.stdout).contains(&format!("f_r = {f_r:.3} Hz")));
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

/// A small periodic record: 4 periods of 16 samples.
fn periodic_csv(bad: impl Fn(usize) -> Option<String>) -> String {
    let mut s = String::from("t,u,y\n");
    for k in 0..64 {
        let u = if (k * 7 % 16) < 8 { 1.0 } else { -1.0 };
        match bad(k) {
            Some(row) => s.push_str(&row),
            None => s.push_str(&format!("{},{},{}\n", k as f64 * 1e-3, u, 0.01 * k as f64)),
        }
    }
    s
}

#[test]
fn identify_bad_csv_files_give_one_line_errors() {
    let dir = tmpdir("bad");
    let base = [
        "identify",
        "--time",
        "t",
        "--input",
        "u",
        "--output",
        "y",
        "--period-samples",
        "16",
        "--csv",
    ];
    let run = |file: &str, needles: &[&str]| {
        let mut a: Vec<&str> = base.to_vec();
        a.push(file);
        expect_error(&a, needles);
    };
    let f = write(&dir, "missing.csv", "t,u\n0,1\n");
    run(&f, &["missing column `y`"]);
    let f = write(
        &dir,
        "text.csv",
        &periodic_csv(|k| (k == 5).then(|| "0.005,abc,0\n".into())),
    );
    run(&f, &["row 7", "`u`", "not a number"]);
    let f = write(
        &dir,
        "nan.csv",
        &periodic_csv(|k| (k == 9).then(|| "0.009,1,inf\n".into())),
    );
    run(&f, &["row 11", "`y`", "not finite"]);
    let f = write(
        &dir,
        "time.csv",
        &periodic_csv(|k| (k == 20).then(|| "0.001,1,0\n".into())),
    );
    run(&f, &["row 22", "`t`", "not increasing"]);
    let short: String = periodic_csv(|_| None)
        .lines()
        .take(40)
        .map(|l| format!("{l}\n"))
        .collect();
    let f = write(&dir, "short.csv", &short);
    run(&f, &["too few samples", "39 data rows"]);
    let constant: String = (0..64).fold(String::from("t,u,y\n"), |s, k| {
        s + &format!("{},0.5,{}\n", k as f64 * 1e-3, k)
    });
    let f = write(&dir, "const.csv", &constant);
    run(&f, &["`u` is constant", "no excitation"]);
    run(
        &dir.join("absent.csv").to_string_lossy(),
        &["absent.csv", "cannot open"],
    );
}

#[test]
fn friction_from_a_recorded_motion() {
    // linear axis, m and N: J = 13.9 kg, d_v = 160 N s/m, f_c = 10 N, offset 3 N, 500 Hz
    let dir = tmpdir("friction");
    let mut s = String::from("time_s,pos_m,force_n\n");
    for k in 0..10000 {
        let t = k as f64 / 500.0;
        let w1 = 2.0 * std::f64::consts::PI * 0.3;
        let w2 = 2.0 * std::f64::consts::PI * 0.7;
        let x = 0.2 * (w1 * t).sin() + 0.05 * (w2 * t).sin();
        let v = 0.2 * w1 * (w1 * t).cos() + 0.05 * w2 * (w2 * t).cos();
        let a = -0.2 * w1 * w1 * (w1 * t).sin() - 0.05 * w2 * w2 * (w2 * t).sin();
        let f = 13.9 * a + 160.0 * v + 10.0 * v.signum() + 3.0;
        s.push_str(&format!("{t},{x},{f}\n"));
    }
    let csv = write(&dir, "motion.csv", &s);
    let json = dir.join("friction.json");
    let out = bin()
        .args([
            "friction",
            "--csv",
            &csv,
            "--time",
            "time_s",
            "--torque",
            "force_n",
            "--position",
            "pos_m",
            "--json",
        ])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    const TOL: f64 = 0.05;
    let get = |k: &str| v[k].as_f64().unwrap();
    assert!((get("viscous") / 160.0 - 1.0).abs() < TOL, "{v}");
    assert!((get("coulomb") / 10.0 - 1.0).abs() < TOL, "{v}");
    assert!((get("inertia") / 13.9 - 1.0).abs() < TOL, "{v}");
    assert!((get("offset") - 3.0).abs() < 0.5, "{v}");
    assert!(get("relative_residual") < 0.05, "{v}");

    let base = [
        "friction",
        "--time",
        "time_s",
        "--torque",
        "force_n",
        "--position",
        "pos_m",
        "--csv",
    ];
    let one_way: String = (0..200).fold(String::from("time_s,pos_m,force_n\n"), |s, k| {
        s + &format!("{},{},1\n", k as f64 * 1e-3, (k * k) as f64 * 1e-6)
    });
    let f = write(&dir, "oneway.csv", &one_way);
    let mut a = base.to_vec();
    a.push(&f);
    expect_error(&a, &["both directions"]);
    let f = write(&dir, "missing.csv", "time_s,pos_m\n0,1\n");
    let mut a = base.to_vec();
    a.push(&f);
    expect_error(&a, &["missing column `force_n`"]);
}

/// `beltune identify ... | head -3` panicked ("failed printing to
/// stdout: Broken pipe"). The reader here closes its end before the command
/// prints anything; the command must end quietly: exit 0 or killed by SIGPIPE,
/// and no panic text on stderr.
#[test]
fn identify_into_a_closed_pipe_ends_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    let mut child = identify_measured()
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes away at once, as `head` does after its lines.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(!err.contains("Broken pipe"), "{err}");
    assert!(
        out.status.success() || out.status.signal() == Some(libc_sigpipe()),
        "{:?}: {err}",
        out.status
    );
}

/// SIGPIPE's number on Linux.
fn libc_sigpipe() -> i32 {
    13
}

/// Data that cannot be fitted (here a record without a resonance:
/// the output is the input, scaled) is bad input, exit status 2, with the
/// reason; not status 1 (an internal failure).
#[test]
fn a_record_that_cannot_be_fitted_is_bad_input() {
    let dir = tmpdir("unfittable");
    // a periodic +-1 sequence of 256 samples (a fixed linear congruential
    // generator), 10 periods, sampled at 10 kHz
    let mut state: u32 = 12345;
    let period: Vec<f64> = (0..256)
        .map(|_| {
            state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
            if state >> 31 == 1 {
                1.0
            } else {
                -1.0
            }
        })
        .collect();
    let mut s = String::from("t_s,u,y\n");
    for k in 0..2560 {
        let u = period[k % 256];
        s.push_str(&format!("{},{u},{}\n", k as f64 * 1e-4, 0.5 * u));
    }
    let f = write(&dir, "flat.csv", &s);
    expect_error(
        &[
            "identify",
            "--csv",
            &f,
            "--time",
            "t_s",
            "--input",
            "u",
            "--output",
            "y",
            "--period-samples",
            "256",
        ],
        &["fit failed", "resonance"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
