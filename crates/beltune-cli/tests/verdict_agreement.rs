//! One verdict everywhere: for every condition that fails a commissioning
//! (tracking error, static error, settling, saturation, guaranteed margin),
//! the exit status, the terminal summary, `--json`, `commissioning.json`,
//! `report.html`, the tuning page on that folder and its saved set all say
//! the same. The verdict is computed once (`beltune::verdict`); these tests
//! catch an output that judges on its own.

mod common;

use beltune::commission::{judge_run, Commissioning, CommissioningConfig};
use beltune::record::commissioning::{AxisRecord, Origin};
use beltune::record::folder::OutputTarget;
use beltune::record::provenance::Provenance;
use beltune::report::folder::{ResultFolder, ResultSet};
use beltune::sim::Truth;
use beltune::verdict::{CheckName, Limits, Verdict};
use beltune_cli::cmd::summary::Summary;
use beltune_cli::exit::ExitStatus;
use beltune_cli::serve::api::Knobs;
use beltune_cli::serve::library::{builtin_commissioning, load_commissioning, LibraryTuner};
use beltune_cli::serve::tuner::Tuner;
use std::path::{Path, PathBuf};

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-verdict-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The verdict word and each check's result as `report.html` shows them.
fn report_verdict(dir: &Path) -> (String, Vec<(String, bool)>) {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let at = html.find("id=\"verdict-result\"").expect("a verdict box");
    let word = html[at..]
        .split('>')
        .nth(1)
        .unwrap()
        .split('<')
        .next()
        .unwrap()
        .to_string();
    let checks = html
        .split("<tr data-check=\"")
        .skip(1)
        .map(|row| {
            let name = row.split('"').next().unwrap().to_string();
            let result = row.split("</tr>").next().unwrap();
            (name, result.contains("class=\"pass\">pass<"))
        })
        .collect();
    (word, checks)
}

/// Every output of the folder `dir` agrees with `verdict`.
fn assert_every_output_agrees(dir: &Path, verdict: &Verdict, what: &str) {
    // commissioning.json, read back by the one folder reader
    let folder = ResultFolder::read(dir).unwrap();
    assert_eq!(
        folder.record.verdict.as_ref(),
        Some(verdict),
        "{what}: commissioning.json"
    );
    // the summary the command prints (text and --json) and its exit status
    let summary = Summary::of(&folder.record, Vec::new(), 0.0);
    let expected = if verdict.limits_met() {
        ExitStatus::Success
    } else {
        ExitStatus::LimitsNotMet
    };
    assert_eq!(summary.exit_status(), expected, "{what}: exit status");
    let text = summary.lines().join("\n");
    assert!(
        text.contains(&format!("verdict: {}", verdict.word())),
        "{what}: terminal says\n{text}"
    );
    for failure in verdict.failures() {
        let first_words: String = failure
            .split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ");
        assert!(
            text.contains(&first_words),
            "{what}: `{failure}` not in\n{text}"
        );
    }
    let json: serde_json::Value = serde_json::from_str(&summary.json().unwrap()).unwrap();
    assert_eq!(
        json["verdict"],
        serde_json::to_value(verdict).unwrap(),
        "{what}: --json"
    );
    // report.html
    let (word, checks) = report_verdict(dir);
    assert_eq!(word, verdict.word(), "{what}: report.html");
    let expected: Vec<(String, bool)> = verdict
        .checks
        .iter()
        .map(|c| {
            let name = serde_json::to_value(c.name).unwrap();
            (name.as_str().unwrap().to_string(), c.passed)
        })
        .collect();
    assert_eq!(checks, expected, "{what}: report.html checks");
    // the tuning page on the folder
    let tuner = LibraryTuner::new(load_commissioning(dir).unwrap()).unwrap();
    assert_eq!(
        tuner.model().commissioned_verdict,
        Some(verdict.text()),
        "{what}: tuning page"
    );
}

/// What breaks one check of a run.
type Breaks = dyn Fn(&mut Commissioning);

/// The result set of `run` written into `dir`.
fn write_run(
    run: &beltune::commission::Commissioning,
    plant: &beltune::model::rigs::Plant,
    dir: &Path,
) {
    let origin = Origin {
        name: "egc70".into(),
        axis: AxisRecord::simulated("egc70", plant, 0.05, 1),
        truth: Some(Truth::of_plant(plant, run.identification_position_m).unwrap()),
        provenance: Provenance::now(vec!["test".into()], Some(1)),
    };
    ResultSet::of_run(run, &origin)
        .unwrap()
        .write(&OutputTarget::Exact {
            dir: dir.to_path_buf(),
            force: false,
        })
        .unwrap();
}

#[test]
fn each_failing_condition_is_said_the_same_by_every_output() {
    let (plant, run) = builtin_commissioning().unwrap();
    let cfg = CommissioningConfig::default();
    assert!(run.verdict.passed, "{:?}", run.verdict);
    let dir = temp_dir("conditions");
    write_run(&run, &plant, &dir.join("pass"));
    assert_every_output_agrees(&dir.join("pass"), &run.verdict, "the passing run");
    let conditions: [(CheckName, &Breaks); 5] = [
        (CheckName::MaxTrackingError, &|r| {
            r.validation.nonlinear.max_tracking_error_m = 2e-3
        }),
        (CheckName::StaticError, &|r| {
            r.validation.nonlinear.static_error_m = 250e-6
        }),
        (CheckName::Settling, &|r| {
            r.validation.nonlinear.settling_time_s = None
        }),
        (CheckName::Saturation, &|r| {
            r.validation.nonlinear.max_torque_nm = r.torque_max_nm
        }),
        (CheckName::GuaranteedPhaseMargin, &|r| {
            r.guaranteed.velocity_phase_margin_deg = 12.0
        }),
    ];
    for (name, fail) in conditions {
        let mut failing = run.clone();
        fail(&mut failing);
        failing.verdict = judge_run(&failing, &cfg);
        let failed: Vec<CheckName> = failing
            .verdict
            .checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| c.name)
            .collect();
        assert_eq!(failed, [name], "{:?}", failing.verdict);
        let out = dir.join(format!("{name:?}"));
        write_run(&failing, &plant, &out);
        assert_every_output_agrees(&out, &failing.verdict, &format!("{name:?}"));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The issue's own example: a tracking limit below what the axis reaches is
/// exit 5, FAIL in the summary, `--json`, `commissioning.json` and the
/// report, and the tuning page on the folder says FAIL too; a set the page
/// saves says of itself what its report says.
#[test]
fn a_tight_tracking_limit_fails_every_output_of_the_command() {
    let dir = temp_dir("command");
    let out = dir.join("out");
    let o = common::bench::bin()
        .args([
            "commission",
            "--json",
            "--max-tracking-error",
            "0.00002",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(5),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["status"], "limits_not_met");
    let folder = ResultFolder::read(&out).unwrap();
    let verdict = folder.record.verdict.clone().unwrap();
    assert_eq!(json["verdict"], serde_json::to_value(&verdict).unwrap());
    assert_eq!(verdict.word(), "FAIL");
    assert_eq!(
        verdict.failures().len(),
        1,
        "only the tracking limit: {:?}",
        verdict.failures()
    );
    assert!(
        folder
            .record
            .log
            .iter()
            .any(|l| l.starts_with("verdict: FAIL")),
        "the log says it too"
    );
    assert_every_output_agrees(&out, &verdict, "--max-tracking-error 0.00002");
    // the stage lines on stderr, the one-line error last
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.trim_end()
            .lines()
            .last()
            .unwrap()
            .contains("misses its limits"),
        "{err}"
    );
    // the page's saved set: its record and its report agree with each other
    let tuner = LibraryTuner::new(load_commissioning(&out).unwrap()).unwrap();
    let set = tuner.tuned_set(&Knobs::default()).unwrap();
    let saved = dir.join("saved");
    set.write(&OutputTarget::Exact {
        dir: saved.clone(),
        force: false,
    })
    .unwrap();
    let saved_verdict = set.verdict().unwrap().clone();
    assert_eq!(
        saved_verdict.validated_on,
        beltune::verdict::ValidatedOn::Simulation
    );
    // the saved set is judged with the thesis limits on its simulated move
    assert_eq!(Limits::default().max_tracking_error_m, 1e-3);
    assert_every_output_agrees(&saved, &saved_verdict, "the saved set");
    std::fs::remove_dir_all(&dir).unwrap();
}
