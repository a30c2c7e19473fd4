//! `beltune design` end to end: TOML and identify-style JSON in, JSON out; bad and
//! infeasible requests give one `error:` line and exit code 1.

mod common;

use std::path::PathBuf;
use std::process::Command;

/// Requested-vs-achieved tolerance of the design (deg / dB).
const SPEC_TOL: f64 = 0.01;

/// Table A.4 with a 1 ms dead time, `T_R` 2 ms and Table A.10's friction.
fn a4_toml() -> String {
    common::table_a4_model_toml()
        + "dead_time_s = 1e-3\nt_r_s = 2e-3\nviscous = 2.53e-3\ncoulomb = 0.125\n"
}

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("beltune-design-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
        .arg("design")
        .args(args)
        .output()
        .unwrap()
}

fn field(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("missing `{key}` in {v}"))
}

#[test]
fn toml_model_gives_json_with_the_required_keys() {
    let dir = scratch("toml");
    let model = dir.join("a4.toml");
    std::fs::write(&model, a4_toml()).unwrap();
    for (prefilter, filter_key, expect) in
        [("butterworth", "omega_bw", 123.24), ("notch", "d_n", 4.60)]
    {
        let out_path = dir.join(format!("{prefilter}.json"));
        // Tables A.6/A.7 are the thesis' design on the model as given
        let out = run(&[
            "--thesis-design",
            "--model",
            model.to_str().unwrap(),
            "--prefilter",
            prefilter,
            "--json",
            out_path.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("K_PP"), "{stdout}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out_path).unwrap()).unwrap();
        for key in [
            "k_p",
            "k_i",
            "k_pp",
            "omega_c_velocity",
            "omega_c_position",
            "gain_margin_velocity_db",
        ] {
            assert!(field(&v, key) > 0.0, "{key}");
        }
        // Table A.6/A.7 filter parameters: 0.5 %
        assert!((field(&v, filter_key) / expect - 1.0).abs() < 5e-3);
        assert!((field(&v, "phase_margin_velocity_deg") - 60.0).abs() < SPEC_TOL);
        assert!((field(&v, "gain_at_resonance_db") + 10.0).abs() < SPEC_TOL);
        assert!((field(&v, "phase_margin_position_deg") - 80.0).abs() < SPEC_TOL);
        for key in ["b0", "b1", "b2", "a1", "a2"] {
            assert!(v["discrete"]["prefilter"][key].is_f64(), "{key}");
        }
        for key in ["b0", "b1", "a1"] {
            assert!(v["discrete"]["pi"][key].is_f64());
            assert!(v["discrete"]["velocity_filter"][key].is_f64());
        }
        // friction from the model file reaches the feedforward
        assert_eq!(v["feedforward"]["coulomb_nm"].as_f64(), Some(0.125));
    }
}

#[test]
fn identify_json_and_dynamics_and_expert_knobs() {
    let dir = scratch("json");
    let model = dir.join("model.json");
    std::fs::write(
        &model,
        r#"{"theta_e": 7.173e-5, "m_c": 13.44, "c": 203740.0, "d_m": 33.17, "d_c": 226.42,
            "i_t": 0.012414085561167836, "dead_time_s": 0.001, "t_r_s": 0.002,
            "f_r_hz": 107.1, "fit": {"iterations": 12}}"#,
    )
    .unwrap();
    let read = |extra: &[&str], name: &str| {
        let out_path = dir.join(name);
        let mut args = vec![
            "--model",
            model.to_str().unwrap(),
            "--json",
            out_path.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = run(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(&out_path).unwrap())
            .unwrap()
    };
    // --dynamics orders the robust designs slow to fast; standard is the default
    let cons = read(&["--dynamics", "conservative"], "c.json");
    let stan = read(&["--dynamics", "standard"], "s.json");
    let dynm = read(&["--dynamics", "dynamic"], "d.json");
    let default = read(&[], "default.json");
    for key in ["omega_c_velocity", "omega_c_position"] {
        assert!(field(&stan, key) >= field(&cons, key), "{key}");
        assert!(field(&dynm, key) >= field(&stan, key), "{key}");
    }
    assert!(field(&dynm, "omega_c_velocity") > field(&cons, "omega_c_velocity"));
    for key in ["k_p", "k_i", "k_pp"] {
        assert_eq!(field(&default, key), field(&stan, key), "{key}");
    }
    // expert flags override the one-knob setting
    let mixed = read(
        &[
            "--dynamics",
            "0.5",
            "--pm-velocity",
            "55",
            "--resonance-suppression-db",
            "-12",
            "--pm-position",
            "75",
        ],
        "m.json",
    );
    assert!((field(&mixed, "phase_margin_velocity_deg") - 55.0).abs() < SPEC_TOL);
    assert!((field(&mixed, "gain_at_resonance_db") + 12.0).abs() < SPEC_TOL);
    assert!((field(&mixed, "phase_margin_position_deg") - 75.0).abs() < SPEC_TOL);
}

#[test]
fn bad_and_infeasible_requests_fail_with_one_line() {
    let dir = scratch("bad");
    let model = dir.join("a4.toml");
    std::fs::write(&model, a4_toml()).unwrap();
    let broken = dir.join("broken.toml");
    std::fs::write(&broken, a4_toml().replace("m_c = 13.44", "m_c = -2")).unwrap();
    let m = model.to_str().unwrap();
    // Exit statuses (beltune_cli::exit): 4 infeasible, 2 bad input, 1 I/O.
    let cases: Vec<(Vec<&str>, i32)> = vec![
        (vec!["--model", m, "--pm-position", "95"], 4),
        (vec!["--model", m, "--resonance-suppression-db", "-150"], 2),
        (vec!["--model", m, "--prefilter", "chebyshev"], 2),
        (vec!["--model", m, "--dynamics", "turbo"], 2),
        (vec!["--model", m, "--filter-attenuation-db", "2"], 2),
        (vec!["--model", m, "--ts", "0.01"], 2),
        (vec!["--model", broken.to_str().unwrap()], 2),
        (vec!["--model", "/nonexistent/model.toml"], 2),
    ];
    for (args, status) in cases {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(status), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.starts_with("error: ") && err.trim_end().lines().count() == 1,
            "{args:?}: {err}"
        );
    }
}
