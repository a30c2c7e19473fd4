//! Everything that can be checked before the axis moves is checked first: a
//! refusal prints one line and no stage line (no stage ran, so the axis never
//! moved), writes nothing, and leaves an existing result alone.

mod common;

use common::bench::{bin, measured, RECORD_ARGS};
use std::path::{Path, PathBuf};
use std::process::Output;

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-refusal-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The files under `dir`, recursively, with their contents.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(snapshot(&p));
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    out.sort();
    out
}

/// A refusal: status 2, exactly one line on stderr (the error), nothing on stdout.
fn assert_refused_before_any_stage(o: &Output, needle: &str, what: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{what}: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(
        lines.len(),
        1,
        "{what}: a stage ran before the refusal:\n{err}"
    );
    assert!(lines[0].starts_with("error: "), "{what}: {err}");
    assert!(
        lines[0].contains(needle),
        "{what}: `{needle}` not in `{}`",
        lines[0]
    );
    assert!(
        o.stdout.is_empty(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stdout)
    );
}

#[test]
fn a_refusal_prints_no_stage_line_and_writes_nothing() {
    let dir = temp_dir("all");
    // an earlier result, which a refused run must leave exactly as it was
    let result = dir.join("result");
    let o = bin()
        .args(["commission", "--quiet", "--plant", "sim-a", "--out"])
        .arg(&result)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let foreign = dir.join("project");
    std::fs::create_dir_all(foreign.join("src")).unwrap();
    std::fs::write(foreign.join("src/main.c"), "int main(void) { return 0; }\n").unwrap();
    let config = dir.join("bad.toml");
    std::fs::write(&config, "plant = \"egc70\"\nno-such-flag = 1\n").unwrap();
    let before = snapshot(&dir);

    let out = |d: &Path| d.to_str().unwrap().to_string();
    let cases: Vec<(&str, Vec<String>, &str)> = vec![
        (
            "an existing result without --force",
            vec!["--out".into(), out(&result)],
            "--force",
        ),
        (
            "a folder holding something else",
            vec!["--out".into(), out(&foreign), "--force".into()],
            "not empty",
        ),
        (
            "a knob out of range",
            vec![
                "--pm-velocity".into(),
                "200".into(),
                "--out".into(),
                out(&dir.join("a")),
            ],
            "--pm-velocity",
        ),
        (
            "a limit that is no length",
            vec![
                "--max-tracking-error".into(),
                "0".into(),
                "--out".into(),
                out(&dir.join("b")),
            ],
            "--max-tracking-error",
        ),
        (
            "a travel window beyond the stroke",
            vec![
                "--travel-window".into(),
                "0,2".into(),
                "--out".into(),
                out(&dir.join("c")),
            ],
            "travel window",
        ),
        (
            "an unknown key in the config file",
            vec![
                "--config".into(),
                out(&config),
                "--out".into(),
                out(&dir.join("d")),
            ],
            "no-such-flag",
        ),
        (
            "a network interface name longer than Linux allows",
            vec![
                "--ethercat".into(),
                "a".repeat(17),
                "--out".into(),
                out(&dir.join("e")),
            ],
            "interface name",
        ),
    ];
    for (what, args, needle) in cases {
        let o = bin().arg("commission").args(&args).output().unwrap();
        assert_refused_before_any_stage(&o, needle, what);
    }

    // a recording: refused before the fit, on its flags and its header alone
    let csv = measured();
    let o = bin()
        .args(["commission", "--csv"])
        .arg(&csv)
        .args(RECORD_ARGS)
        .args(["--out"])
        .arg(dir.join("f"))
        .output()
        .unwrap();
    assert_refused_before_any_stage(&o, "--torque-limit", "a recording without a torque limit");
    let o = bin()
        .args(["commission", "--csv"])
        .arg(&csv)
        .args(["--input", "no_such_column", "--output", "theta_motor_rad"])
        .args(["--torque-limit", "20", "--out"])
        .arg(dir.join("g"))
        .output()
        .unwrap();
    assert_refused_before_any_stage(&o, "no_such_column", "a recording without the named column");

    assert_eq!(
        snapshot(&dir),
        before,
        "a refused run changed or left files"
    );
    for d in ["a", "b", "c", "d", "e", "f", "g"] {
        assert!(!dir.join(d).exists(), "{d} was written");
    }
    assert!(
        !dir.join("result-safety-stop").exists(),
        "a diagnostic was written"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
