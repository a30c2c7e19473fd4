//! `beltune plant show` run as a process.

use std::process::Command;

fn beltune(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
        .args(args)
        .output()
        .expect("run beltune")
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = beltune(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

/// Table A.4 (11.2 kg) and Table A.5 (0 kg): the data-sheet rig is within 10 %
/// of the identified resonance/antiresonance.
const DATASHEET_VS_IDENTIFIED: f64 = 0.10;

#[test]
fn egc70_json_has_the_required_fields_and_is_near_the_thesis() {
    for (payload, f_r, f_z) in [(None, 107.11, 19.59), (Some("0"), 134.00, 76.51)] {
        let mut args = vec!["plant", "show", "--json"];
        if let Some(p) = payload {
            args.extend(["--payload", p]);
        }
        let v = json(&args);
        for key in [
            "f_r_hz",
            "f_z_hz",
            "theta_e_kg_m2",
            "m_c_kg",
            "c_n_per_m",
            "i_t_m",
        ] {
            assert!(
                v[key].as_f64().is_some_and(|x| x.is_finite() && x > 0.0),
                "{key}: {v}"
            );
        }
        let got_r = v["f_r_hz"].as_f64().unwrap();
        let got_z = v["f_z_hz"].as_f64().unwrap();
        assert!(
            (got_r / f_r - 1.0).abs() < DATASHEET_VS_IDENTIFIED,
            "{got_r}"
        );
        assert!(
            (got_z / f_z - 1.0).abs() < DATASHEET_VS_IDENTIFIED,
            "{got_z}"
        );
    }
}

#[test]
fn simulation_set_json_matches_table_a11() {
    let v = json(&["plant", "show", "--plant", "sim-a", "--json"]);
    assert!((v["f_r_hz"].as_f64().unwrap() - 133.78).abs() < 0.01);
    assert!((v["f_z_hz"].as_f64().unwrap() - 22.50).abs() < 0.01);
    assert_eq!(v["kind"], "linear");
}

#[test]
fn human_table_by_default() {
    let out = beltune(&["plant", "show"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("resonance f_r") && text.contains("Hz"),
        "{text}"
    );
    assert!(text.contains("position dependency"), "{text}");
}

#[test]
fn toml_file_round_trip_and_errors_are_one_line() {
    let dir = std::env::temp_dir().join(format!("beltune-plant-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let plant = beltune::model::builtin("egc70", Some(3.0)).unwrap();
    let good = dir.join("rig.toml");
    std::fs::write(&good, toml::to_string(&plant).unwrap()).unwrap();
    let v = json(&["plant", "show", "--plant", good.to_str().unwrap(), "--json"]);
    assert_eq!(v["m_c_kg"].as_f64().unwrap(), 3.96);
    let v = json(&[
        "plant",
        "show",
        "--plant",
        good.to_str().unwrap(),
        "--payload",
        "1",
        "--json",
    ]);
    assert_eq!(v["m_c_kg"].as_f64().unwrap(), 1.96);

    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "kind = \"physical\"\nr_m = -1\n").unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec!["plant", "show", "--plant", "egc99"],
        vec!["plant", "show", "--plant", bad.to_str().unwrap()],
        vec!["plant", "show", "--plant", "missing-file.toml"],
        vec!["plant", "show", "--payload", "-3"],
        vec!["plant", "show", "--plant", "sim-b", "--payload", "2"],
    ];
    for args in cases {
        let out = beltune(&args);
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("error: "), "{err}");
    }
    let err = String::from_utf8(beltune(&["plant", "show", "--plant", "missing-file.toml"]).stderr)
        .unwrap();
    assert!(err.contains("missing-file.toml"), "{err}");
    assert_eq!(
        err.matches("os error").count(),
        1,
        "the cause is printed once: {err}"
    );
    let err = String::from_utf8(beltune(&["plant", "show", "--plant", "egc99"]).stderr).unwrap();
    assert!(err.contains("egc99") && err.contains("egc70"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
