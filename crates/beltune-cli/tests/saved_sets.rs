//! What `beltune serve` simulates and saves for a loaded commissioning folder
//! (issues 15 and 16): the move runs on the plant the commissioning ran on
//! (recorded in `commissioning.json` as `axis`), Save writes the report
//! sections the commissioning's report has (or says why one is absent), and
//! a folder commissioned in current units stays in current units.

mod common;

use beltune_cli::serve::api::Knobs;
use beltune_cli::serve::library::{load_commissioning, LibraryTuner};
use beltune_cli::serve::tuner::Tuner;
use common::bench;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The page's simulated move and the commissioning's validation move run the
/// same plant, controller and trajectory through the same library function;
/// they differ only in the noise realization and in the state the earlier
/// stages leave the simulated axis in (measured: 0.6405 vs 0.6398 mm before the
/// design rule and the Coulomb hold of main a9fc2f4; 0.5528 vs 0.5258 mm, 5.1 %,
/// after them: the part of that left to the axis state is not yet explained).
const SAME_MOVE_REL_TOL: f64 = 0.06;
/// ... or this much absolute, m: the report's move starts where the
/// commissioning's creep to the start left the cart at rest (within its static
/// error band, up to tens of um), the page's from exact rest; with max errors
/// near 0.2 mm (since the design rule, the Coulomb hold and the aligned record)
/// that start alone moves the max error by a few tens of um.
const SAME_MOVE_ABS_TOL_M: f64 = 50e-6;

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-saved-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(cmd: &mut std::process::Command) {
    let o = cmd.output().unwrap();
    assert!(
        o.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn json_of(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The files of a Save with the default knobs, by name.
fn save(tuner: &LibraryTuner) -> HashMap<String, String> {
    tuner
        .save_set(&Knobs::default())
        .unwrap()
        .into_iter()
        .map(|f| (f.name, String::from_utf8(f.bytes).unwrap()))
        .collect()
}

/// Every key of a JSON tree, with its path.
fn keys(v: &serde_json::Value, at: &str, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                out.push(format!("{at}{k}"));
                keys(x, &format!("{at}{k}."), out);
            }
        }
        serde_json::Value::Array(xs) => xs.iter().for_each(|x| keys(x, at, out)),
        _ => {}
    }
}

#[test]
fn a_loaded_egc70_folder_simulates_on_its_plant_and_saves_every_section() {
    let dir = tmpdir("egc70");
    let out = dir.join("run");
    run(bench::bin()
        .args(["commission", "--quiet", "--out"])
        .arg(&out));
    let json = json_of(&out.join("commissioning.json"));
    // what the commissioning ran on
    let axis = &json["axis"];
    assert_eq!(axis["kind"], "simulated", "{axis}");
    assert_eq!(axis["name"], "egc70");
    assert_eq!(axis["payload_kg"].as_f64(), Some(11.2));
    assert_eq!(axis["plant"]["kind"], "physical");
    assert_eq!(axis["plant"]["payload_kg"].as_f64(), Some(11.2));

    let tuner = LibraryTuner::new(load_commissioning(&out).unwrap()).unwrap();
    let r = tuner.tune(&Knobs::default()).unwrap();
    let m = r.validation_move.expect("a simulated move");
    assert!(m.plant.contains("egc70"), "{}", m.plant);
    assert_eq!(m.payload_kg, 11.2);
    let report_mm = json["validation"]["nonlinear"]["max_tracking_error_m"]
        .as_f64()
        .unwrap()
        * 1e3;
    let page_mm = m.max_error_m * 1e3;
    assert!(
        (page_mm - report_mm).abs()
            <= (SAME_MOVE_REL_TOL * report_mm).max(SAME_MOVE_ABS_TOL_M * 1e3),
        "page {page_mm} mm vs report {report_mm} mm"
    );

    let files = save(&tuner);
    for f in ["excitation.csv", "friction.csv", "frf.csv", "moves.csv"] {
        assert!(files.contains_key(f), "{f} not saved: {:?}", files.keys());
    }
    let html = &files["report.html"];
    let original = std::fs::read_to_string(out.join("report.html")).unwrap();
    for section in ["<figure id=\"excitation\">", "<figure id=\"friction\">"] {
        assert!(
            original.contains(section),
            "commissioning report lacks {section}"
        );
        assert!(html.contains(section), "saved report lacks {section}");
    }
    assert!(!html.contains("Sections not in this report"));

    // A saved set is a result folder: its moves.csv has a header naming
    // every column of every row, and `compare BASE BASE/tuned-...` reads it.
    let saved = beltune_cli::serve::library::write_saved_set(
        &out,
        &tuner.save_set(&Knobs::default()).unwrap(),
    )
    .unwrap();
    let moves = std::fs::read_to_string(saved.dir.join("moves.csv")).unwrap();
    let mut lines = moves.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert!(header.len() >= 4, "{header:?}");
    for (i, line) in lines.enumerate() {
        assert_eq!(
            line.split(',').count(),
            header.len(),
            "moves.csv row {i} does not match its header {header:?}"
        );
    }
    let cmp = dir.join("compare.html");
    run(bench::bin()
        .arg("compare")
        .arg(&out)
        .arg(&saved.dir)
        .arg("--out")
        .arg(&cmp));
    let page = std::fs::read_to_string(&cmp).unwrap();
    assert!(page.contains("<svg"), "the comparison has no plots");
    // the compare page says what the two runs are and how each was judged,
    // and has no empty sections
    assert!(page.contains("<h2>The two runs</h2>"), "no runs table");
    assert!(
        page.contains("payload</td><td>11.2 kg"),
        "A's payload missing"
    );
    assert!(
        page.contains("PASS (simulated move)"),
        "B's verdict missing"
    );
    assert!(
        page.contains("saved by the tuning page"),
        "B's kind missing"
    );
    assert!(!page.contains("<td>none</td>"), "a `seed none` row");
    assert!(!page.contains("<pre id=\"log\"></pre>"), "an empty log");
    assert!(
        !page.contains("<h2>Parameters</h2>"),
        "an empty parameters table"
    );
    // the saved set's own (simulated) move is compared, not left blank
    let row = page
        .split("<tr>")
        .find(|r| r.contains("max tracking error (nonlinear feedforward)"))
        .expect("the max tracking error row");
    assert!(!row.contains("<td>-</td>"), "{row}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_folder_in_current_units_saves_in_current_units() {
    let dir = tmpdir("current");
    let out = dir.join("run");
    run(bench::on_record("commission")
        .args([
            "--quiet",
            "--current-units",
            "--torque-limit",
            "15.3",
            "--out",
        ])
        .arg(&out));
    let json = json_of(&out.join("commissioning.json"));
    assert_eq!(json["axis"]["kind"], "recorded", "{}", json["axis"]);

    let tuner = LibraryTuner::new(load_commissioning(&out).unwrap()).unwrap();
    let files = save(&tuner);
    let torque_suffixes = ["_nm", "_nm_s_per_rad", "_nm_per_rad", "_kg_m2"];
    let toml: toml::Value = toml::from_str(&files["controller.toml"]).unwrap();
    assert_eq!(toml["units"].as_str(), Some("current"));
    assert_eq!(toml["torque_max_a"].as_float(), Some(15.3));
    let mut all = Vec::new();
    keys(&serde_json::to_value(&toml).unwrap(), "", &mut all);
    keys(
        &serde_json::from_str(&files["commissioning.json"]).unwrap(),
        "json:",
        &mut all,
    );
    let torque_keys: Vec<&String> = all
        .iter()
        .filter(|k| torque_suffixes.iter().any(|s| k.ends_with(s)))
        .collect();
    assert!(
        torque_keys.is_empty(),
        "torque units in a current-units set: {torque_keys:?}"
    );
    // minijinja escapes `/` in text
    let html = &files["report.html"].replace("&#x2f;", "/");
    assert!(html.contains("A s/rad"), "K_P not in A s/rad");
    for torque_unit in ["N m s/rad", "N m/rad", "N m)", "N m<"] {
        let at = html.find(torque_unit);
        assert!(
            at.is_none(),
            "torque unit `{torque_unit}` in the saved report: {}",
            &html[at.unwrap().saturating_sub(300)..at.unwrap() + 50]
        );
    }
    // the sections a recorded folder cannot have are named, with the reason
    assert!(html.contains("Sections not in this report"));
    assert!(html.contains("excitation.csv") && html.contains("friction.csv"));
    std::fs::remove_dir_all(&dir).unwrap();
}
