//! The file formats through the command line: one identified-model schema from
//! `identify` and `commission` into `design`, the export and the excitation;
//! units carried through for a record in current units.

use beltune::record::controller::ControllerFile;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn beltune() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-schema-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn bench() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/twomass-bench/multisine-a.csv.gz")
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "status {:?}: {}{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn read_json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// `design --json` of a model file.
fn design(model: &Path, json: &Path) -> (String, serde_json::Value) {
    let out = ok(&beltune()
        .args(["design", "--model"])
        .arg(model)
        .arg("--json")
        .arg(json)
        .output()
        .unwrap());
    (out, read_json(json))
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Same inputs (model, dead time, T_R, T_s, friction, default knobs) give the
/// same design; JSON floats round-trip exactly, so only the last bits of the
/// design's own iterations may differ.
const SAME_DESIGN_TOL: f64 = 1e-9;

#[test]
fn commission_then_design_from_commissioning_json_and_export() {
    let dir = temp_dir("sim");
    let out = dir.join("out");
    ok(&beltune()
        .args(["commission", "--quiet", "--seed", "3", "--out"])
        .arg(&out)
        .output()
        .unwrap());
    let cj = read_json(&out.join("commissioning.json"));
    assert_eq!(cj["schema_version"].as_u64(), Some(1));
    let prov = &cj["provenance"];
    assert_eq!(prov["seed"].as_u64(), Some(3));
    assert_eq!(
        prov["beltune_version"].as_str(),
        Some(env!("CARGO_PKG_VERSION"))
    );
    assert!(
        prov["command_line"][1].as_str() == Some("commission"),
        "{prov}"
    );
    assert!(prov["created_utc"].as_str().unwrap().ends_with('Z'));
    let id = &cj["identified"];
    assert_eq!(id["units"].as_str(), Some("torque"));
    assert_eq!(id["ts_s"].as_f64(), Some(1e-4));
    assert_eq!(id["torque_max_nm"].as_f64(), Some(3.1));
    assert!(cj["drive_form"]["integral_time_ms"].as_f64().unwrap() > 0.0);

    // commission -> design --model commissioning.json: the same controller
    let (_, d) = design(&out.join("commissioning.json"), &dir.join("design.json"));
    for key in ["k_p", "k_i", "k_pp"] {
        let (a, b) = (
            d[key].as_f64().unwrap(),
            cj["controller"][key].as_f64().unwrap(),
        );
        assert!(
            rel(a, b) < SAME_DESIGN_TOL,
            "{key}: design {a}, commission {b}"
        );
    }

    // controller.toml: schema, provenance, everything CascadeConfig needs
    let toml_path = out.join("controller.toml");
    let file = ControllerFile::load(&toml_path).unwrap();
    assert_eq!(file.provenance.seed, Some(3));
    let cfg = file.cascade_config().unwrap();
    assert_eq!(
        cfg.gains.k_p_nm_s_per_rad,
        cj["controller"]["k_p"].as_f64().unwrap()
    );
    assert_eq!(cfg.torque_max_nm, 3.1);
    assert!(cfg.feedforward_preview && cfg.filter_desired_velocity);

    // the export reads it; Rust and C carry the same values
    let rust = ok(&beltune()
        .args(["export", "--lang", "rust", "--controller"])
        .arg(&toml_path)
        .output()
        .unwrap());
    let c = ok(&beltune()
        .args(["export", "--lang", "c", "--controller"])
        .arg(&toml_path)
        .output()
        .unwrap());
    let (r, c) = (
        beltune::record::export::parse_values(&rust),
        beltune::record::export::parse_values(&c),
    );
    assert!(r.len() > 30 && r == c, "{r:?}\n{c:?}");
    // single precision: the f32 nearest each value, the same in C (`float`) and Rust
    let rust32 = ok(&beltune()
        .args([
            "export",
            "--lang",
            "rust",
            "--precision",
            "f32",
            "--controller",
        ])
        .arg(&toml_path)
        .output()
        .unwrap());
    assert!(rust32.contains("CascadeConfig<f32>"));
    let r32 = beltune::record::export::parse_values(&rust32);
    assert_eq!(r32.len(), r.len());
    for ((n32, l32), (n, l)) in r32.iter().zip(&r) {
        assert_eq!(n32, n);
        if let (Ok(x32), Ok(x)) = (l32.parse::<f32>(), l.parse::<f64>()) {
            assert_eq!(x32.to_bits(), (x as f32).to_bits(), "{n}");
        }
    }
    let c32 = ok(&beltune()
        .args([
            "export",
            "--lang",
            "c",
            "--precision",
            "f32",
            "--controller",
        ])
        .arg(&toml_path)
        .output()
        .unwrap());
    assert!(c32.contains("static const BtCascadeConfigF32 BELTUNE_CASCADE"));
    assert_eq!(beltune::record::export::parse_values(&c32), r32);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 11: `identify --json` without an actual-torque column wrote
/// `"dead_time_s": null`, which `design --model` rejected.
#[test]
fn identify_json_without_dead_time_feeds_design() {
    let dir = temp_dir("identify");
    let base = [
        "--time",
        "t_s",
        "--input",
        "iq_ref_A",
        "--output",
        "theta_motor_rad",
        "--period-samples",
        "2500",
        "--current-units",
        "--torque-limit",
        "20",
    ];
    for (name, extra) in [
        ("no-dead-time", vec![]),
        ("dead-time", vec!["--actual-torque", "iq_meas_A"]),
    ] {
        let model = dir.join(format!("{name}.json"));
        ok(&beltune()
            .args(["identify", "--csv"])
            .arg(bench())
            .args(base)
            .args(&extra)
            .arg("--json")
            .arg(&model)
            .output()
            .unwrap());
        let m = read_json(&model);
        let measured = !extra.is_empty();
        assert_eq!(m["schema_version"].as_u64(), Some(1));
        assert_eq!(
            m["identified"]["dead_time_measured"].as_bool(),
            Some(measured),
            "{m}"
        );
        assert_eq!(m["identified"]["torque_max_a"].as_f64(), Some(20.0), "{m}");
        assert_eq!(m["identified"]["ts_s"].as_f64(), Some(4e-4), "{m}");
        let (text, d) = design(&model, &dir.join(format!("{name}-design.json")));
        assert_eq!(text.contains("not measured"), !measured, "{text}");
        assert!(text.contains("A s/rad") && !text.contains("N m"), "{text}");
        assert!(d["k_p"].as_f64().unwrap() > 0.0);
        // the design runs at the record's sampling time
        assert_eq!(d["ts_s"].as_f64(), Some(4e-4));
    }
    // the old flat file with "dead_time_s": null is read too (1 ms assumed)
    let old = dir.join("old.json");
    std::fs::write(
        &old,
        r#"{"theta_e": 0.00985, "m_c": 0.0049, "c": 564.1, "d": 0, "d_m": 0.001, "d_c": 0.002,
            "i_t": 1.0, "dead_time_s": null, "sample_time_s": 4e-4, "units": "current"}"#,
    )
    .unwrap();
    let (text, _) = design(&old, &dir.join("old-design.json"));
    assert!(text.contains("not measured; 1 ms assumed"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every key suffix that claims a torque unit.
const TORQUE_SUFFIXES: [&str; 7] = [
    "_nm",
    "_nm_s_per_rad",
    "_nm_per_rad",
    "_kg_m2",
    "_kg",
    "_n_per_m",
    "_n_s_per_m",
];

fn keys(v: &serde_json::Value, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                out.push(k.clone());
                keys(x, out);
            }
        }
        serde_json::Value::Array(xs) => xs.iter().for_each(|x| keys(x, out)),
        _ => {}
    }
}

#[test]
fn commission_csv_in_current_units_labels_every_unit_as_current() {
    let dir = temp_dir("current");
    let out = dir.join("out");
    let args = [
        "--input",
        "iq_ref_A",
        "--output",
        "theta_motor_rad",
        "--actual-torque",
        "iq_meas_A",
        "--period-samples",
        "2500",
        "--current-units",
        "--quiet",
    ];
    // the torque limit is required: the record's peak (15.3 A) is not a limit
    let o = beltune()
        .args(["commission", "--csv"])
        .arg(bench())
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--torque-limit") && err.contains(" A "),
        "{err}"
    );
    assert!(!out.exists());

    ok(&beltune()
        .args(["commission", "--csv"])
        .arg(bench())
        .args(args)
        .args(["--torque-limit", "20", "--out"])
        .arg(&out)
        .output()
        .unwrap());
    // JSON: no key claims a torque unit; the limit is the given one, in A
    let cj = read_json(&out.join("commissioning.json"));
    let mut ks = Vec::new();
    keys(&cj, &mut ks);
    for k in &ks {
        assert!(!TORQUE_SUFFIXES.iter().any(|s| k.ends_with(s)), "key `{k}`");
    }
    assert_eq!(cj["identified"]["units"].as_str(), Some("current"));
    assert_eq!(cj["identified"]["torque_max_a"].as_f64(), Some(20.0));
    assert!(
        cj["drive_form"]["velocity_gain_a_s_per_rad"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    // TOML: labelled in A, keys in A, and it loads with the limit in A
    let toml = std::fs::read_to_string(out.join("controller.toml")).unwrap();
    for bad in ["_nm", "kg", "N m"] {
        assert!(!toml.contains(bad), "`{bad}` in controller.toml:\n{toml}");
    }
    assert!(
        toml.contains("torque_max_a = 20.0") && toml.contains("K_P in A s/rad"),
        "{toml}"
    );
    let file = ControllerFile::load(&out.join("controller.toml")).unwrap();
    assert_eq!(file.cascade_config().unwrap().torque_max_nm, 20.0);
    // report: every unit of the parameter table is a current unit or carries no torque
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // the drive-family table (family, parameter, unit, value) after the others
    let (html, vendor) = html
        .split_once("Drive parameters per drive family")
        .expect("the report has the drive-family table");
    let vendor_units: Vec<String> = vendor
        .split("<tr><td>")
        .skip(1)
        .filter_map(|row| {
            let cell = row.split("</td><td>").nth(2)?;
            Some(cell.replace("&#x2f;", "/").replace("&#x5e;", "^"))
        })
        .collect();
    assert!(vendor_units.len() >= 9, "{vendor_units:?}");
    for u in &vendor_units {
        assert!(
            ["Hz", "ms", "1/s", "1000/min", ""].contains(&u.as_str())
                || (u.starts_with('A') && !u.contains('N') && !u.contains("kg")),
            "unit `{u}` in the drive-family table"
        );
    }
    let units: Vec<String> = html
        .split("<tr><td>")
        .skip(1)
        .filter_map(|row| {
            let cell = row.split("</td><td>").nth(1)?;
            Some(cell.replace("&#x2f;", "/").replace("&#x5e;", "^"))
        })
        .collect();
    assert!(units.len() >= 12, "{units:?}");
    // (the drive-settings table: position gain in (m/min)/mm, the filter's kind without unit)
    let plain = ["Hz", "ms", "deg", "dB", "1/s", "m/rad", "(m/min)/mm", ""];
    for u in &units {
        assert!(
            plain.contains(&u.as_str())
                || (u.starts_with('A') && !u.contains('N') && !u.contains("kg")),
            "unit `{u}` in the report"
        );
    }
    for want in ["A s^2/rad", "A s/rad", "A/rad", "A"] {
        assert!(units.iter().any(|u| u == want), "{want} missing: {units:?}");
    }
    assert!(!html.contains("N m s&#x2f;rad") && !html.contains("kg mm"));
    // and it designs again from its own commissioning.json, in A
    let (text, _) = design(&out.join("commissioning.json"), &dir.join("d.json"));
    assert!(text.contains("A s/rad"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The keys of `commissioning.json` and `controller.toml` come in
/// the order of their structs (the identity of the file first, then the model,
/// the controller, the data), not alphabetically.
#[test]
fn files_keep_their_documented_key_order() {
    let dir = temp_dir("order");
    let out = dir.join("run");
    ok(&beltune()
        .args(["commission", "--quiet", "--csv"])
        .arg(bench())
        .args([
            "--input",
            "iq_ref_A",
            "--output",
            "theta_motor_rad",
            "--period-samples",
            "2500",
            "--torque-limit",
            "15.3",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap());
    let text = std::fs::read_to_string(out.join("commissioning.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let top: Vec<&str> = json
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    assert_eq!(
        top[..6],
        [
            "schema_version",
            "provenance",
            "plant",
            "identified",
            "friction",
            "controller"
        ],
        "{top:?}"
    );
    let id: Vec<&str> = json["identified"]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    assert_eq!(
        id[..5],
        ["units", "f_r_hz", "f_z_hz", "theta_e", "m_c"],
        "{id:?}"
    );
    // the text itself, not only the parsed map (which could reorder)
    let at = |k: &str| text.find(&format!("\"{k}\"")).unwrap();
    assert!(at("schema_version") < at("provenance") && at("identified") < at("controller"));

    let toml = std::fs::read_to_string(out.join("controller.toml")).unwrap();
    let lines: Vec<&str> = toml
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .collect();
    let key = |l: &str| l.split(" = ").next().unwrap().to_string();
    assert_eq!(
        lines[..4].iter().map(|l| key(l)).collect::<Vec<_>>(),
        ["schema_version", "units", "ts_s", "torque_max_nm"],
        "{toml}"
    );
    let sections: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with('['))
        .collect();
    assert_eq!(
        sections,
        [
            "[provenance]",
            "[gains]",
            "[prefilter]",
            "[velocity_filter]",
            "[feedforward]",
            "[setpoint]",
            "[drive_form]"
        ]
    );
    let gains = &toml[toml.find("[gains]").unwrap()..];
    assert!(gains.find("k_pp_per_s").unwrap() < gains.find("k_p_nm_s_per_rad").unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}
