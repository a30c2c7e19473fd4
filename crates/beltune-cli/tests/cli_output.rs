//! Item 5: the command line. Every exit status produced by the
//! situation it documents, the diagnostic file after a safety stop, output
//! that fits 100 columns without float noise, `--quiet` keeping the summary,
//! `--json` with its documented keys, `--config`, `plant template`,
//! completions and the man page.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The width every line of the command's output fits in.
const WIDTH: usize = 100;

fn beltune() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_beltune"));
    // The help layout must not depend on the terminal of whoever runs the tests.
    c.env_remove("COLUMNS");
    c
}

fn run(args: &[&str]) -> Output {
    beltune().args(args).output().unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-cli16-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn code(o: &Output) -> i32 {
    o.status.code().unwrap_or(-1)
}

fn commission(out: &Path, extra: &[&str]) -> Output {
    beltune()
        .arg("commission")
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect(),
        Err(_) => Vec::new(),
    };
    v.sort();
    v
}

/// A decimal with more than 12 significant digits: the print of a value like
/// `0.05 - 1e-17` (issue 16 saw `0.04999999999999999`).
fn float_noise(s: &str) -> Option<String> {
    s.split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .find(|t| {
            let significant = t.trim_start_matches(['0', '.']);
            t.contains('.') && significant.chars().filter(|c| c.is_ascii_digit()).count() > 12
        })
        .map(str::to_string)
}

fn assert_fits(what: &str, s: &str) {
    for line in s.lines() {
        assert!(
            line.chars().count() <= WIDTH,
            "{what}: {} columns: {line}",
            line.chars().count()
        );
    }
    assert_eq!(float_noise(s), None, "{what}: float noise in {s}");
}

fn keys(v: &serde_json::Value) -> BTreeSet<String> {
    v.as_object()
        .unwrap_or_else(|| panic!("not an object: {v}"))
        .keys()
        .cloned()
        .collect()
}

fn set(items: &[&str]) -> BTreeSet<String> {
    items.iter().map(|s| s.to_string()).collect()
}

/// Status 0; stage lines (stderr) and the summary (stdout) fit 100 columns
/// and print no float noise; `--quiet` hides the stage lines, keeps the summary.
#[test]
fn success_is_0_and_every_line_fits_100_columns() {
    let dir = temp_dir("ok");
    let o = commission(&dir.join("out"), &[]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert_fits("summary", &out);
    assert_fits("stage lines", &err);
    // The identification stage line was 190 columns: now wrapped,
    // continuation lines indented under the start of the text.
    let id = err
        .lines()
        .position(|l| l.contains("identification (open loop): "))
        .expect("identification stage line");
    assert!(err
        .lines()
        .nth(id + 1)
        .unwrap()
        .starts_with(&" ".repeat(30)));
    for label in [
        "identified:",
        "controller:",
        "validation:",
        "verdict: PASS",
        "wrote:",
    ] {
        assert!(out.contains(label), "summary lacks {label}: {out}");
    }

    let o = commission(&dir.join("quiet"), &["--quiet"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    assert_eq!(text(&o.stderr), "", "--quiet prints no stage lines");
    let quiet = text(&o.stdout);
    assert!(
        quiet.contains("verdict: PASS") && quiet.contains("wrote:"),
        "{quiet}"
    );
    // Same seed, same summary apart from the times and the folder.
    let strip = |s: &str| {
        s.lines()
            .filter(|l| !l.contains("time:") && !l.contains("wrote:"))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&quiet), strip(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--json`: one JSON object on stdout with exactly the documented keys, and
/// the same numbers as `commissioning.json` of the same run.
#[test]
fn json_summary_has_the_documented_keys_and_the_run_s_numbers() {
    let dir = temp_dir("json");
    let out = dir.join("out");
    let o = commission(&out, &["--json"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("stdout is one JSON object");
    assert_eq!(
        keys(&s),
        set(&[
            "schema",
            "source",
            "status",
            "exit_code",
            "identified",
            "truth",
            "controller",
            "validation",
            "verdict",
            "axis_busy_s",
            "stage_axis_times",
            "computation_s",
            "wall_time_s",
            "files",
        ])
    );
    assert_eq!(s["schema"], "beltune-commission-summary/2");
    // the axis time per stage adds up to the axis' busy time (issue 31)
    let stages = s["stage_axis_times"].as_array().unwrap();
    assert!(stages.len() >= 8, "{stages:?}");
    let sum: f64 = stages
        .iter()
        .map(|t| {
            assert_eq!(keys(t), set(&["stage", "axis_time_s"]));
            t["axis_time_s"].as_f64().unwrap()
        })
        .sum();
    assert!((sum - s["axis_busy_s"].as_f64().unwrap()).abs() < 1e-6);
    // the comparison moves run only with --compare-feedforward
    assert!(s["validation"]["max_tracking_error_none_m"].is_null());
    assert!(s["validation"]["max_tracking_error_linear_m"].is_null());
    assert_eq!(s["status"], "ok");
    assert_eq!(s["exit_code"], 0);
    assert_eq!(
        keys(&s["identified"]),
        set(&[
            "f_r_hz",
            "f_z_hz",
            "theta_e_kg_m2",
            "m_c_kg",
            "c_n_per_m",
            "d_m_n_s_per_m",
            "d_c_n_s_per_m",
            "dead_time_s",
            "fit_rms_db",
            "mean_coherence",
        ])
    );
    assert_eq!(
        keys(&s["truth"]),
        set(&["f_r_hz", "f_z_hz", "m_c_kg", "c_n_per_m"])
    );
    assert_eq!(
        keys(&s["controller"]),
        set(&[
            "k_p_nm_s_per_rad",
            "k_i_nm_per_rad",
            "k_pp_per_s",
            "velocity_crossover_hz",
            "velocity_phase_margin_deg",
            "position_crossover_hz",
            "position_phase_margin_deg",
            "gain_at_resonance_db",
        ])
    );
    assert_eq!(
        keys(&s["validation"]),
        set(&[
            "start_m",
            "target_m",
            "max_tracking_error_none_m",
            "max_tracking_error_linear_m",
            "max_tracking_error_nonlinear_m",
            "static_error_nonlinear_m",
            "settling_time_nonlinear_s",
        ])
    );
    assert_eq!(
        keys(&s["verdict"]),
        set(&["passed", "validated_on", "checks", "warnings", "next_step"])
    );
    for c in s["verdict"]["checks"].as_array().unwrap() {
        assert_eq!(
            keys(c),
            set(&["name", "value", "limit", "unit", "below", "passed"])
        );
    }
    // The same run's commissioning.json (written by the library's outputs).
    let full: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("commissioning.json")).unwrap())
            .unwrap();
    assert_eq!(s["identified"]["f_r_hz"], full["identified"]["f_r_hz"]);
    assert_eq!(s["identified"]["c_n_per_m"], full["identified"]["c"]);
    assert_eq!(
        s["controller"]["k_p_nm_s_per_rad"],
        full["controller"]["k_p"]
    );
    assert_eq!(
        s["validation"]["max_tracking_error_nonlinear_m"],
        full["validation"]["nonlinear"]["max_tracking_error_m"]
    );
    assert_eq!(
        s["verdict"]["checks"][0]["value"],
        full["validation"]["nonlinear"]["max_tracking_error_m"]
    );
    assert_eq!(s["verdict"]["checks"][0]["limit"], 1e-3);
    assert_eq!(s["verdict"]["checks"][1]["limit"], 1e-4);
    // one verdict: the summary's is the record's
    assert_eq!(s["verdict"], full["verdict"]);
    let files: Vec<PathBuf> = s["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| PathBuf::from(f.as_str().unwrap()))
        .collect();
    // the three result files and the report's data files (frf, loops, moves,
    // excitation, friction)
    assert_eq!(files.len(), 8);
    assert!(files.iter().all(|f| f.is_file()), "{files:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Status 1: an error that is neither bad input nor about the axis (an
/// output that cannot be written: the device is full). A missing input file
/// is bad input (2).
#[test]
fn an_unwritable_output_is_1_and_a_missing_input_2() {
    let dir = temp_dir("io");
    let o = Command::new(env!("CARGO_BIN_EXE_beltune"))
        .args([
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
            "--samples",
            "/dev/full",
        ])
        .output()
        .unwrap();
    assert_eq!(code(&o), 1, "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("/dev/full"), "{err}");
    let missing = dir.join("no-such-axis.toml");
    let o = commission(
        &dir.join("out"),
        &["--quiet", "--plant", missing.to_str().unwrap()],
    );
    assert_eq!(code(&o), 2, "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("no-such-axis.toml"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Status 2: an unknown flag, a malformed value, a value out of range, a
/// bad config file; the out-of-range value prints without float noise.
#[test]
fn bad_input_is_2() {
    for args in [
        &["commission", "--no-such-flag"][..],
        &["commission", "--payload", "abc"],
        &["plant", "show", "--payload", "-3"],
        &["completions", "tcsh"],
        &[
            "commission",
            "--quiet",
            "--travel-window",
            "0.01,0.06",
            "--start-position",
            "0.02",
        ],
    ] {
        let o = run(args);
        assert_eq!(code(&o), 2, "{args:?}: {}", text(&o.stderr));
    }
    // 0.06 - 0.01 is 0.049999999999999996 in f64; the message says 0.05.
    let o = run(&[
        "commission",
        "--quiet",
        "--travel-window",
        "0.01,0.06",
        "--start-position",
        "0.02",
    ]);
    let err = text(&o.stderr);
    assert!(err.contains("= 0.05:"), "{err}");
    assert_eq!(float_noise(&err), None, "{err}");
}

/// Status 3: a following-error limit of 1 um stops the axis in its first
/// closed-loop move; the diagnostic tells the stage, the limit and the values
/// and holds the samples up to the stop.
#[test]
fn a_forced_safety_stop_is_3_and_leaves_a_diagnostic() {
    let dir = temp_dir("stop");
    let out = dir.join("out");
    let o = commission(&out, &["--quiet", "--following-error-max", "1e-6"]);
    assert_eq!(code(&o), 3, "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    assert!(
        err.contains("safety stop") && err.contains("safety-stop.json"),
        "{err}"
    );
    assert_eq!(text(&o.stdout), "", "no summary after a stop");
    // `--out DIR` stays untouched (the same command can run again); the
    // diagnostic is the folder beside it.
    assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
    let diag = dir.join("out-safety-stop");
    assert_eq!(
        files_in(&diag),
        [".beltune-manifest", "safety-stop.csv", "safety-stop.json"]
    );
    let d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(diag.join("safety-stop.json")).unwrap())
            .unwrap();
    assert_eq!(d["schema"], "beltune-safety-stop/1");
    assert_eq!(d["limit"], "following_error");
    let stage = d["stage"].as_str().unwrap();
    assert!(err.contains(&format!("stage `{stage}`")), "{err}");
    assert_eq!(d["limits"]["following_error_max_m"], 1e-6);
    let e = d["violation"]["FollowingError"]["error_m"]
        .as_f64()
        .unwrap();
    assert!(e.abs() > 1e-6, "the violation exceeds the limit: {e}");
    assert_eq!(d["following_error_m"].as_f64(), Some(e));
    assert!(d["stop_position_m"].is_number() && d["stop_error"].is_null());
    assert_eq!(d["samples_file"], "safety-stop.csv");
    assert_eq!(d["provenance"]["seed"], 1);
    check_samples(&diag, &d);
    // The same command without the tight limit runs into the same folder and
    // removes the then stale diagnostic beside it.
    let o = commission(&out, &["--quiet"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    assert_eq!(
        files_in(&out),
        [
            ".beltune-manifest",
            "commissioning.json",
            "controller.toml",
            "excitation.csv",
            "frf.csv",
            "friction.csv",
            "loops.csv",
            "moves.csv",
            "report.html"
        ]
    );
    assert!(!diag.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The samples file: the header, as many rows as the description says, at
/// the axis' 100 us, contiguous, ending at the sample the stop was judged
/// on; and at most one second of them.
fn check_samples(diag: &Path, d: &serde_json::Value) {
    let csv = std::fs::read_to_string(diag.join("safety-stop.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t_s,torque_command_nm,torque_actual_nm,motor_angle_rad,position_m,cart_position_m,velocity_m_s,following_error_m"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|c| {
                    if c.is_empty() {
                        f64::NAN
                    } else {
                        c.parse().unwrap()
                    }
                })
                .collect()
        })
        .collect();
    assert_eq!(rows.len() as u64, d["samples"].as_u64().unwrap());
    // egc70 samples at 100 us: one second is 10,000 samples.
    let ts = 100e-6;
    assert!(
        rows.len() <= 10_000 && !rows.is_empty(),
        "{} rows",
        rows.len()
    );
    for w in rows.windows(2) {
        assert!(
            (w[1][0] - w[0][0] - ts).abs() < 1e-9,
            "{} -> {}",
            w[0][0],
            w[1][0]
        );
    }
    let last = rows.last().unwrap();
    assert_eq!(last[0], d["time_s"].as_f64().unwrap());
    assert_eq!(last[4], d["position_m"].as_f64().unwrap());
    let first = rows[0][0];
    assert!(d["time_s"].as_f64().unwrap() - first < 1.0);
}

/// Status 3 after more than a second (egc70 with a 3 mm following-error
/// limit stops in the move to the worst-case position at 2.3 s): exactly the
/// last second is kept. (Until issue 12 this was a travel stop during the
/// open-loop excitation in a narrow window; the excitation's guard band now
/// ends such an excitation and refuses the window with status 4 instead.)
#[test]
fn a_late_safety_stop_keeps_exactly_the_last_second() {
    let dir = temp_dir("late-stop");
    let out = dir.join("out");
    let o = commission(
        &out,
        &[
            "--plant",
            "egc70",
            "--following-error-max",
            "0.003",
            "--quiet",
        ],
    );
    assert_eq!(code(&o), 3, "{}", text(&o.stderr));
    let d: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("out-safety-stop").join("safety-stop.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(d["limit"], "following_error");
    assert_eq!(d["stage"], "move to worst-case position");
    assert!(d["time_s"].as_f64().unwrap() > 1.0);
    assert_eq!(d["samples"], 10_000);
    check_samples(&dir.join("out-safety-stop"), &d);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Status 4: a resonance suppression of -80 dB has no PI design; nothing is written.
#[test]
fn an_infeasible_design_is_4() {
    let dir = temp_dir("infeasible");
    let out = dir.join("out");
    let o = commission(&out, &["--quiet", "--resonance-suppression-db", "-80"]);
    assert_eq!(code(&o), 4, "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("infeasible"),
        "{}",
        text(&o.stderr)
    );
    assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Status 5: egc70 commissions, but its validation move (about 0.18 mm) misses
/// a technician's own limit of 0.05 mm: the results are written, the summary
/// says so, the command says which limit. (`sim-c` used to miss the thesis'
/// 1 mm; since issue 12 it validates with the fastest move it can do.)
#[test]
fn limits_not_met_is_5_with_the_results_written() {
    let dir = temp_dir("limits");
    let out = dir.join("out");
    let o = commission(
        &out,
        // 10 um: below what egc70 reaches (0.042 mm since issue 12)
        &["--quiet", "--json", "--max-tracking-error", "0.00001"],
    );
    assert_eq!(code(&o), 5, "{}", text(&o.stderr));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["status"], "limits_not_met");
    assert_eq!(s["exit_code"], 5);
    assert_eq!(s["verdict"]["passed"], false);
    let c = &s["verdict"]["checks"][0];
    assert_eq!(c["name"], "max_tracking_error");
    assert_eq!(c["passed"], false);
    assert!(c["value"].as_f64().unwrap() >= 1e-5);
    assert_eq!(
        c["value"],
        s["validation"]["max_tracking_error_nonlinear_m"]
    );
    let err = text(&o.stderr);
    assert!(
        err.contains("misses its limits") && err.contains("max cart error"),
        "{err}"
    );
    assert_eq!(
        files_in(&out),
        [
            ".beltune-manifest",
            "commissioning.json",
            "controller.toml",
            "excitation.csv",
            "frf.csv",
            "friction.csv",
            "loops.csv",
            "moves.csv",
            "report.html"
        ]
    );
    // The same run passes once the limit is what it achieved (a technician's own limit).
    let achieved = c["value"].as_f64().unwrap() * 1.01;
    let o = commission(
        &dir.join("out2"),
        &["--quiet", "--max-tracking-error", &achieved.to_string()],
    );
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Status 141: the reader of stdout went away before the summary came
/// (`beltune ... | true`, as a shell reports it with pipefail).
#[test]
fn a_closed_stdout_is_141() {
    if !Path::new("/bin/bash").is_file() {
        eprintln!("skipped: /bin/bash not found");
        return;
    }
    let dir = temp_dir("pipe");
    let script = format!(
        "set -o pipefail; '{}' commission --quiet --json --out '{}' | true",
        env!("CARGO_BIN_EXE_beltune"),
        dir.join("out").display()
    );
    let o = Command::new("/bin/bash")
        .args(["-c", &script])
        .output()
        .unwrap();
    assert_eq!(code(&o), 141, "{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("panicked"), "{}", text(&o.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--config FILE.toml`: the file's flags apply, the command line overrides
/// them, and an unknown key is bad input naming the key.
#[test]
fn config_file_flags_apply_and_the_command_line_overrides_them() {
    let dir = temp_dir("config");
    let cfg = dir.join("axis.toml");
    std::fs::write(
        &cfg,
        "# a commissioning of the empty cart\npayload = 0.0\nseed = 3\nquiet = true\njson = true\n\
         travel_window = [-0.01, 0.57]\nmax-tracking-error = 0.001\n",
    )
    .unwrap();
    let summary = |o: &Output| -> serde_json::Value {
        assert_eq!(code(o), 0, "{}", text(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let cfg_s = cfg.to_str().unwrap();
    let from_file = summary(&commission(&dir.join("a"), &["--config", cfg_s]));
    let typed = summary(&commission(
        &dir.join("b"),
        &[
            "--payload",
            "0",
            "--seed",
            "3",
            "--quiet",
            "--json",
            "--travel-window",
            "-0.01,0.57",
        ],
    ));
    // Deterministic (same seed, same flags): the same identification.
    assert_eq!(from_file["identified"], typed["identified"]);
    assert_eq!(from_file["truth"]["m_c_kg"], typed["truth"]["m_c_kg"]);
    // The command line wins over the file.
    let overridden = summary(&commission(
        &dir.join("c"),
        &["--config", cfg_s, "--payload", "5"],
    ));
    // the same as typing everything with 5 kg (the truth is the two-mass
    // equivalent of the three-mass plant: 5 kg on the cart add a little less
    // than 5 kg to it)
    let typed5 = summary(&commission(
        &dir.join("c5"),
        &[
            "--payload",
            "5",
            "--seed",
            "3",
            "--quiet",
            "--json",
            "--travel-window",
            "-0.01,0.57",
        ],
    ));
    assert_eq!(overridden["truth"], typed5["truth"]);
    assert_eq!(overridden["identified"], typed5["identified"]);
    let m0 = from_file["truth"]["m_c_kg"].as_f64().unwrap();
    let m5 = overridden["truth"]["m_c_kg"].as_f64().unwrap();
    assert!(
        m5 - m0 > 4.0 && m5 - m0 <= 5.0 + 1e-9,
        "payload 5 kg on top: {m0} -> {m5}"
    );

    std::fs::write(&cfg, "payload = 0.0\npaylaod = 3.0\n").unwrap();
    let o = commission(&dir.join("d"), &["--config", cfg_s]);
    assert_eq!(code(&o), 2);
    let err = text(&o.stderr);
    assert!(
        err.contains("unknown key `paylaod`") && err.contains("axis.toml"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    std::fs::write(&cfg, "payload = \"heavy\"\n").unwrap();
    let o = commission(&dir.join("e"), &["--config", cfg_s]);
    assert_eq!(code(&o), 2);
    assert!(text(&o.stderr).contains("axis.toml"), "{}", text(&o.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `beltune plant template` writes a file that `--plant FILE` takes as it is:
/// `plant show` gives the built-in's numbers and a commissioning runs on it.
#[test]
fn plant_template_is_accepted_unchanged() {
    let dir = temp_dir("template");
    let file = dir.join("axis.toml");
    let o = run(&["plant", "template", "--out", file.to_str().unwrap()]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let t = std::fs::read_to_string(&file).unwrap();
    assert!(
        t.lines().filter(|l| l.starts_with("# ")).count() > 30,
        "annotated: {t}"
    );
    assert_fits("template", &t);
    // stdout gives the same file
    assert_eq!(text(&run(&["plant", "template"]).stdout), t);
    let show = |plant: &str| -> serde_json::Value {
        let o = run(&["plant", "show", "--plant", plant, "--json"]);
        assert_eq!(code(&o), 0, "{}", text(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let (a, b) = (show(file.to_str().unwrap()), show("egc70"));
    for key in [
        "f_r_hz",
        "f_z_hz",
        "theta_e_kg_m2",
        "m_c_kg",
        "c_n_per_m",
        "rigid_inertia_kg_m2",
    ] {
        let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
        // 12 significant digits in the file
        assert!((x - y).abs() <= 1e-10 * y.abs(), "{key}: {x} vs {y}");
    }
    let o = commission(
        &dir.join("out"),
        &["--plant", file.to_str().unwrap(), "--quiet"],
    );
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    // A linear set too.
    let lin = dir.join("sim-b.toml");
    let o = run(&[
        "plant",
        "template",
        "--plant",
        "sim-b",
        "--out",
        lin.to_str().unwrap(),
    ]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let (a, b) = (show(lin.to_str().unwrap()), show("sim-b"));
    let (x, y) = (a["f_r_hz"].as_f64().unwrap(), b["f_r_hz"].as_f64().unwrap());
    assert!((x - y).abs() <= 1e-10 * y, "{x} vs {y}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The help of every command and subcommand fits 100 columns.
#[test]
fn every_help_fits_100_columns() {
    fn visit(path: Vec<String>, seen: &mut Vec<String>) {
        let mut args = path.clone();
        args.push("--help".into());
        let o = beltune().args(&args).output().unwrap();
        assert_eq!(code(&o), 0, "{args:?}");
        let h = text(&o.stdout);
        assert_fits(&format!("beltune {}", path.join(" ")), &h);
        seen.push(path.join(" "));
        // The names listed under "Commands:", up to the next blank line.
        let subs: Vec<String> = h
            .lines()
            .skip_while(|l| *l != "Commands:")
            .skip(1)
            .take_while(|l| !l.trim().is_empty())
            // a name starts at column 2; wrapped descriptions are indented further
            .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
            .filter_map(|l| l.split_whitespace().next())
            .filter(|n| *n != "help")
            .map(str::to_string)
            .collect();
        for sub in subs {
            let mut p = path.clone();
            p.push(sub);
            visit(p, seen);
        }
    }
    let mut seen = Vec::new();
    visit(Vec::new(), &mut seen);
    for s in [
        "commission",
        "plant template",
        "completions",
        "man",
        "trajectory",
    ] {
        assert!(seen.iter().any(|x| x == s), "{s} not visited: {seen:?}");
    }
}

/// `--help`: headings, examples, the exit statuses; every line fits 100 columns.
#[test]
fn help_has_headings_examples_and_exit_statuses() {
    let o = run(&["--help"]);
    assert_eq!(code(&o), 0);
    let root = text(&o.stdout);
    assert_fits("beltune --help", &root);
    for s in [
        "Examples:",
        "Exit status:",
        "completions",
        "man",
        "beltune plant template",
    ] {
        assert!(root.contains(s), "{s}: {root}");
    }
    let o = run(&["commission", "--help"]);
    assert_eq!(code(&o), 0);
    let h = text(&o.stdout);
    assert_fits("beltune commission --help", &h);
    for s in [
        "Plant:",
        "Safety:",
        "Design:",
        "Excitation:",
        "Validation limits:",
        "Recorded data (--csv):",
        "Output:",
        "Examples:",
        "Exit status:",
    ] {
        assert!(h.contains(s), "{s}: {h}");
    }
    for code in ["0 ", "1 ", "2 ", "3 ", "4 ", "5 ", "141 "] {
        assert!(
            h.lines().any(|l| l.trim_start().starts_with(code)),
            "exit status {code}: {h}"
        );
    }
}

/// The README documents every exit status of `help::EXIT_STATUSES` and the
/// summary's JSON keys.
#[test]
fn the_command_reference_documents_the_exit_statuses_and_json_keys() {
    let docs = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/commands.md"),
    )
    .unwrap();
    for (code, _) in beltune_cli::help::EXIT_STATUSES {
        assert!(
            docs.contains(&format!("\n| {code} | ")),
            "docs/commands.md lacks exit status {code}"
        );
    }
    for key in [
        beltune_cli::cmd::summary::SCHEMA,
        "limits_not_met",
        "not_validated",
        "`max_tracking_error_nonlinear_m`",
        "`checks`",
    ] {
        assert!(docs.contains(key), "docs/commands.md lacks {key}");
    }
}

/// `beltune completions SHELL`: bash's script is valid bash and knows the
/// subcommands and flags; the others are produced.
#[test]
fn completions_for_each_shell() {
    let o = run(&["completions", "bash"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let script = text(&o.stdout);
    for s in ["commission", "--travel-window", "template", "completions"] {
        assert!(script.contains(s), "{s}");
    }
    if Path::new("/bin/bash").is_file() {
        let dir = temp_dir("completions");
        let f = dir.join("beltune.bash");
        std::fs::write(&f, &script).unwrap();
        let o = Command::new("/bin/bash")
            .arg("-n")
            .arg(&f)
            .output()
            .unwrap();
        assert!(o.status.success(), "bash -n: {}", text(&o.stderr));
        std::fs::remove_dir_all(&dir).unwrap();
    }
    for shell in ["zsh", "fish", "elvish", "powershell"] {
        let o = run(&["completions", shell]);
        assert_eq!(code(&o), 0, "{shell}");
        assert!(text(&o.stdout).contains("commission"), "{shell}");
    }
}

/// Completions offer the values of `--plant`, `--prefilter` and `--dynamics`
/// (bash lists them in one `compgen -W` word list each).
#[test]
fn completions_offer_plant_prefilter_and_dynamics_values() {
    let o = run(&["completions", "bash"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let script = text(&o.stdout);
    for words in [
        "egc70 sim-a sim-b sim-c",
        "butterworth notch none",
        "conservative standard dynamic",
    ] {
        assert!(script.contains(words), "bash completions lack `{words}`");
    }
    // parsing keeps its own rules: a plant file is still accepted by name
    let o = run(&["plant", "show", "--plant", "no-such-plant.toml"]);
    let err = text(&o.stderr);
    assert!(
        err.contains("no-such-plant.toml") && !err.contains("possible values"),
        "{err}"
    );
}

/// `beltune man`: roff with the exit statuses; it renders with groff without
/// warnings where groff is installed; `--out` writes one page per subcommand.
#[test]
fn man_page_renders() {
    let o = run(&["man"]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let roff = text(&o.stdout);
    assert!(
        roff.starts_with(".ie") || roff.contains(".TH beltune 1"),
        "{}",
        &roff[..200.min(roff.len())]
    );
    assert!(roff.contains(".SH \"EXIT STATUS\""));
    assert!(roff.contains(".SH EXAMPLES"));
    let dir = temp_dir("man");
    let o = run(&["man", "--out", dir.to_str().unwrap()]);
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let pages = files_in(&dir);
    for p in [
        "beltune.1",
        "beltune-commission.1",
        "beltune-plant-template.1",
        "beltune-man.1",
    ] {
        assert!(pages.contains(&p.to_string()), "{p}: {pages:?}");
    }
    let commission = std::fs::read_to_string(dir.join("beltune-commission.1")).unwrap();
    assert!(commission.contains("travel\\-window"), "{commission}");
    let Some(groff) = ["/usr/bin/groff", "/bin/groff"]
        .into_iter()
        .find(|p| Path::new(p).is_file())
    else {
        eprintln!("skipped the rendering: groff not found (apt-get install groff-base)");
        std::fs::remove_dir_all(&dir).unwrap();
        return;
    };
    for page in ["beltune.1", "beltune-commission.1"] {
        // Plain text: old-style output without bold, underline or overstrike.
        let o = Command::new(groff)
            .args(["-man", "-Tutf8", "-ww", "-P-c", "-P-b", "-P-u", "-P-o"])
            .arg(dir.join(page))
            .env("LC_ALL", "C")
            .output()
            .unwrap();
        assert!(o.status.success(), "{page}: {}", text(&o.stderr));
        assert_eq!(text(&o.stderr), "", "{page}: groff warnings");
        // Justified text: compare with the spaces collapsed.
        let shown = text(&o.stdout)
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        assert!(shown.contains("EXIT STATUS"), "{page}: {shown}");
        assert!(shown.contains("safety stop"), "{page}: {shown}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// From recorded data: the JSON summary has the same keys, with the axis-only
/// parts `null`; the text summary fits and gives no SI units to values in the
/// record's units (amperes here).
#[test]
fn recorded_data_summary_has_null_axis_parts() {
    let data =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/twomass-bench/multisine-a.csv.gz");
    let dir = temp_dir("recorded");
    let args = |json: bool, out: &str| {
        let mut c = beltune();
        c.args(["commission", "--quiet", "--csv"]).arg(&data).args([
            "--input",
            "iq_ref_A",
            "--output",
            "theta_motor_rad",
            "--actual-torque",
            "iq_meas_A",
            "--period-samples",
            "2500",
            "--torque-limit",
            "3.1",
            "--out",
        ]);
        c.arg(dir.join(out));
        if json {
            c.arg("--json");
        }
        c.output().unwrap()
    };
    let o = args(true, "a");
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["status"], "not_validated");
    assert_eq!(s["exit_code"], 0);
    assert_eq!(s["verdict"]["validated_on"], "none");
    assert_eq!(s["verdict"]["passed"], false);
    for k in ["truth", "validation", "axis_busy_s"] {
        assert!(s[k].is_null(), "{k}: {}", s[k]);
    }
    assert!(s["identified"]["f_r_hz"].as_f64().unwrap() > 0.0);
    let o = args(false, "b");
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let t = text(&o.stdout);
    assert_fits("recorded summary", &t);
    assert!(
        t.contains("units of the record") && !t.contains(" kg"),
        "{t}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
