//! `beltune trajectory` end to end: the thesis move of Table A.8, the sample
//! file, and one-line errors for invalid requests.

use std::path::PathBuf;
use std::process::{Command, Output};

/// Relative tolerance on the closed-form duration (rounding only).
const DURATION_REL_TOL: f64 = 1e-9;
/// The last sample must be at the target (final states within 1e-8).
const FINAL_STATE_TOL: f64 = 1e-8;

fn beltune(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
        .args(args)
        .output()
        .expect("run beltune")
}

const THESIS_MOVE: [&str; 11] = [
    "trajectory",
    "--start",
    "0,0,0",
    "--target",
    "0.5,0,0",
    "--v-max",
    "5",
    "--a-max",
    "45",
    "--j-max",
    "40",
];

/// 0 -> 0.5 m with j 40, a 45, v 5 reaches neither a nor v limit:
/// four jerk phases of (d / 2j)^(1/3) each.
fn thesis_duration() -> f64 {
    4.0 * (0.5_f64 / 80.0).cbrt()
}

/// Run `beltune` with `args` (which end in `--json`) and parse its output.
fn json_of(args: &[&str]) -> serde_json::Value {
    let out = beltune(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

#[test]
fn json_has_duration_and_seven_phases() {
    let mut args = THESIS_MOVE.to_vec();
    args.extend(["--position-limits", "-0.01,0.57", "--json"]);
    let v = json_of(&args);
    let duration = v["duration_s"].as_f64().unwrap();
    let expected = thesis_duration();
    assert!(
        (duration - expected).abs() <= DURATION_REL_TOL * expected,
        "{duration}"
    );
    let phases = v["phase_durations_s"].as_array().unwrap();
    assert_eq!(phases.len(), 7);
    let sum: f64 = phases.iter().map(|p| p.as_f64().unwrap()).sum();
    assert!((sum - duration).abs() < 1e-12);
}

/// Asymmetric jerk `+J1 = 40`, `-J2 = -20` m/s^3, the same 0.5 m: jerk
/// phases `+J1` for tau, `-J2` for `2 J1 tau / J2`, `+J1` for tau (the
/// velocity condition makes the peak and low acceleration equal in size), and
/// integrating them gives `d = tau^3 (J1/3 + J1^2/J2 + 2 J1^3 / (3 J2^2))`;
/// here 200 tau^3 = 0.5, T = 6 tau = 0.8143 s (peak 5.4 m/s^2, 1.1 m/s).
#[test]
fn asymmetric_jerk_matches_the_closed_form() {
    let mut args = THESIS_MOVE.to_vec();
    args.extend(["--j-min", "-20", "--json"]);
    let v = json_of(&args);
    let (j1, j2, d) = (40.0_f64, 20.0_f64, 0.5_f64);
    let tau = (d / (j1 / 3.0 + j1 * j1 / j2 + 2.0 * j1.powi(3) / (3.0 * j2 * j2))).cbrt();
    let expected = 2.0 * tau + 2.0 * j1 * tau / j2;
    let duration = v["duration_s"].as_f64().unwrap();
    assert!(
        (duration - expected).abs() <= DURATION_REL_TOL * expected,
        "{duration} vs {expected}"
    );
    let jerks: Vec<f64> = v["phase_jerks_m_s3"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j.as_f64().unwrap())
        .collect();
    assert!(jerks.iter().all(|&j| j == 0.0 || j == 40.0 || j == -20.0));
    assert!(jerks.contains(&-20.0), "{jerks:?}");
}

#[test]
fn table_output_lists_the_phases() {
    let out = beltune(&THESIS_MOVE);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("duration: 0.7368"), "{text}");
    for p in ["P1", "P2", "P3", "P4", "P5", "P6", "P7"] {
        assert!(
            text.lines().any(|l| l.starts_with(p)),
            "{p} missing in {text}"
        );
    }
}

#[test]
fn samples_file_ends_at_the_target() {
    let path: PathBuf =
        std::env::temp_dir().join(format!("beltune-traj-{}.csv", std::process::id()));
    let mut args = THESIS_MOVE.to_vec();
    let p = path.to_str().unwrap().to_owned();
    args.extend(["--samples", &p, "--ts", "0.001"]);
    let out = beltune(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_file(&path).ok();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(csv.starts_with("t_s,position_m,velocity_m_s,acceleration_m_s2,jerk_m_s3\n"));
    // k = 0 ..= ceil(T / ts)
    assert_eq!(rows.len(), (thesis_duration() / 0.001).ceil() as usize + 1);
    assert_eq!(rows[0][1], 0.0);
    let last = rows.last().unwrap();
    assert!((last[1] - 0.5).abs() < FINAL_STATE_TOL && last[2].abs() < FINAL_STATE_TOL);
    // Sampled every ts.
    assert!((rows[1][0] - 0.001).abs() < 1e-15);
}

/// `status`: the exit status (beltune_cli::exit: 2 bad input, 4 infeasible).
fn assert_one_line_error(args: &[&str], needle: &str, status: i32) {
    let out = beltune(args);
    assert_eq!(out.status.code(), Some(status), "{args:?}");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: ") && err.contains(needle), "{err}");
}

#[test]
fn invalid_requests_print_one_line_and_fail() {
    let mut negative_jerk = THESIS_MOVE.to_vec();
    negative_jerk[10] = "-40";
    // The flag as typed, not the core's field name.
    assert_one_line_error(&negative_jerk, "--j-max", 2);

    let mut positive_j_min = THESIS_MOVE.to_vec();
    positive_j_min.extend(["--j-min", "5"]);
    assert_one_line_error(&positive_j_min, "--j-min", 2);

    let mut outside = THESIS_MOVE.to_vec();
    outside[4] = "0.7,0,0";
    outside.extend(["--position-limits", "-0.01,0.57"]);
    assert_one_line_error(&outside, "outside the position limits", 2);

    // Stopping from 2 m/s at -0.2 m towards -1 m overshoots the -0.25 m limit.
    let mut overshoot = THESIS_MOVE.to_vec();
    overshoot[2] = "-0.2,-2,0";
    overshoot.extend(["--position-limits", "-0.25,0.57"]);
    assert_one_line_error(&overshoot, "leaves the position limits", 4);

    let mut bad_state = THESIS_MOVE.to_vec();
    bad_state[2] = "0,0";
    let out = beltune(&bad_state);
    assert!(!out.status.success());
}
