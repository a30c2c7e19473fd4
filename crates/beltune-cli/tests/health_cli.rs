//! `beltune health` and `beltune history` on the command line: a healthy
//! check and an aged one against a commissioning (exit statuses 0 and 5,
//! the result folder, the recommendation in words), the history of both in
//! the default database beside the results and as a page with the trends,
//! a recording instead of an axis (`--csv`), and refusals in one line that
//! write nothing.

use beltune::model::builtin;
use beltune::sim::{SimAxis, SimConfig};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn beltune(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-health-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A commissioning of egc70 in `dir/base`.
fn commissioned(dir: &Path) {
    let o = beltune(dir, &["commission", "--quiet", "--out", "base"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

#[test]
fn a_healthy_and_an_aged_axis_are_told_apart_and_both_go_into_the_history() {
    let dir = scratch("axis");
    commissioned(&dir);
    // healthy
    let o = beltune(
        &dir,
        &["health", "--baseline", "base", "--quiet", "--out", "h1"],
    );
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}{}", text(&o.stderr));
    assert!(out.starts_with("health of egc70: OK"), "{out}");
    assert!(dir.join("h1/health.json").is_file() && dir.join("h1/report.html").is_file());
    // health.json reads back as it was written
    let rec = beltune::record::health::HealthRecord::load(&dir.join("h1/health.json")).unwrap();
    assert_eq!(rec.axis, "egc70");
    assert_eq!(rec.check.comparisons.len(), 12);
    // 18 % of the belt stiffness lost: act, with the recommendation in words
    let o = beltune(
        &dir,
        &[
            "health",
            "--baseline",
            "base",
            "--quiet",
            "--json",
            "--belt-stiffness-loss",
            "0.18",
            "--axis",
            "egc70",
            "--out",
            "h2",
        ],
    );
    assert_eq!(o.status.code(), Some(5), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["status"], "act");
    let recs: Vec<String> = j["recommendations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap().to_string())
        .collect();
    assert!(
        recs[0].starts_with("belt stiffness, cart far from the motor -1")
            && recs[0].ends_with("re-tension the belt to its data-sheet value, then re-commission"),
        "{recs:?}"
    );
    let stderr = text(&o.stderr);
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.starts_with("error: the health check finished: act:"),
        "{stderr}"
    );
    // the default history beside the results: the commissioning and both checks
    let db = dir.join("beltune-history.sqlite");
    assert!(db.is_file());
    let o = beltune(&dir, &["history", "--json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let runs: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let kinds: Vec<&str> = runs
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["commissioning", "health", "health"]);
    let statuses: Vec<&str> = runs
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["status"].as_str().unwrap())
        .collect();
    assert_eq!(statuses, ["pass", "ok", "act"]);
    // the page: a trend per quantity with the limits
    let o = beltune(
        &dir,
        &["history", "--axis", "egc70", "--html", "trend.html"],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let page = std::fs::read_to_string(dir.join("trend.html")).unwrap();
    assert!(
        page.contains("id=\"trend-0\"") && page.contains("belt stiffness, cart far from the motor")
    );
    assert!(page.contains("<svg") && !page.contains("<script"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A recorded excitation instead of the axis: an open-loop PRBS on the
/// simulated egc70 at the baseline's identification position, written as
/// a CSV (time, torque, motor angle), is the commissioned axis.
#[test]
fn a_recording_is_checked_against_the_commissioning() {
    let dir = scratch("csv");
    commissioned(&dir);
    let base: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("base/commissioning.json")).unwrap())
            .unwrap();
    let at = base["identification_position_m"].as_f64().unwrap();
    let amplitude = base["excitation_amplitude_nm"].as_f64().unwrap();
    let plant = builtin("egc70", None).unwrap();
    let mut axis = SimAxis::new(
        &plant,
        SimConfig {
            initial_cart_position_m: Some(at),
            ..SimConfig::default()
        },
    )
    .unwrap();
    let ts = plant.info().ts_s;
    let q = plant.info().motor_rad_per_count;
    let mut prbs = beltune_rt::prbs::Prbs::new(9, 16, amplitude).unwrap();
    let n = 3 * prbs.period_samples() as usize;
    let mut csv = String::from("t_s,tau_nm,phi_rad\n");
    for k in 0..n {
        let tau = prbs.step();
        let m = axis.step(tau);
        csv.push_str(&format!(
            "{},{tau},{}\n",
            (k + 1) as f64 * ts,
            m.motor_counts as f64 * q
        ));
    }
    std::fs::write(dir.join("rec.csv"), csv).unwrap();
    let o = beltune(
        &dir,
        &[
            "health",
            "--baseline",
            "base",
            "--csv",
            "rec.csv",
            "--input",
            "tau_nm",
            "--output",
            "phi_rad",
            "--period-samples",
            "8176",
            "--quiet",
            "--json",
            "--out",
            "h",
        ],
    );
    assert!(
        o.status.code() == Some(0),
        "{}{}",
        text(&o.stdout),
        text(&o.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let keys: Vec<&str> = j["quantities"]
        .as_array()
        .unwrap()
        .iter()
        .map(|q| q["quantity"].as_str().unwrap())
        .collect();
    assert_eq!(
        keys,
        [
            "stiffness_far",
            "resonance_far",
            "antiresonance_far",
            "moving_mass",
            "resonance_damping"
        ]
    );
    let rec = beltune::record::health::HealthRecord::load(&dir.join("h/health.json")).unwrap();
    assert!(rec.check.measured.far.as_ref().unwrap().position_m.is_nan());
    let c = &j["quantities"][0];
    eprintln!("recording: stiffness {}", c["change"]);
    // the thesis' FRF fit of the recording against the commissioning's
    // friction-aware model of the same axis at the same position
    assert!(c["change"].as_f64().unwrap().abs() < 0.05, "{c}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad input is refused in one line with status 2 before anything runs,
/// and nothing is written (no result folder, no history database).
#[test]
fn bad_health_input_is_one_line_and_writes_nothing() {
    let dir = scratch("refusals");
    commissioned(&dir);
    std::fs::remove_file(dir.join("beltune-history.sqlite")).unwrap();
    let cases: [(&[&str], &str); 6] = [
        (
            &["health", "--baseline", "nowhere"],
            "no commissioning.json",
        ),
        (
            &[
                "health",
                "--baseline",
                "base",
                "--limit",
                "stiffness_far=0.1,0.2",
            ],
            "lower limit",
        ),
        (
            &[
                "health",
                "--baseline",
                "base",
                "--limit",
                "stiffness=-0.1,0.2",
            ],
            "QUANTITY=LOWER,UPPER",
        ),
        (
            &[
                "health",
                "--baseline",
                "base",
                "--belt-stiffness-loss",
                "1.5",
            ],
            "wear.belt_stiffness_loss",
        ),
        (
            &["health", "--baseline", "base", "--db", "missing/h.sqlite"],
            "does not exist",
        ),
        (
            &[
                "health",
                "--baseline",
                "base",
                "--csv",
                "x.csv",
                "--input",
                "a",
                "--output",
                "b",
                "--seed",
                "3",
            ],
            "--seed",
        ),
    ];
    for (args, why) in cases {
        let o = beltune(&dir, args);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(why), "{args:?}: {err}");
        assert!(!dir.join("health").exists(), "{args:?} wrote a result");
        assert!(
            !dir.join("beltune-history.sqlite").exists(),
            "{args:?} wrote a history"
        );
    }
    let o = beltune(&dir, &["history"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("no history database"));
    let _ = std::fs::remove_dir_all(&dir);
}
