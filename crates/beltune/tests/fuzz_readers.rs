//! Property-based fuzzing ("beyond the list"): the CSV, TOML and
//! JSON readers and the design knobs never panic, never hang and never
//! return a non-finite number; every input either gives a finite result or
//! a typed error.
//!
//! Bounded for the test suite: the case counts below keep the targets within
//! about 30 s together in the dev profile (opt-level 2). A longer run:
//! `PROPTEST_CASES=20000 cargo test -p beltune --test fuzz_readers`.

use beltune::design::{design, DesignKnobs, PrefilterKind};
use beltune::ident::read_csv_columns;
use beltune::model::rigs::{egc70_params, load_toml};
use beltune::model::Plant;
use beltune::record::model::ModelFile;
use proptest::prelude::*;
use std::path::PathBuf;

/// `n` cases, or `PROPTEST_CASES` when set (a longer run). The seed is fixed
/// (the suite gives the same verdict on every run; a random seed once found a
/// hang in CI that no local run had met), or `PROPTEST_RNG_SEED` when set.
fn cases(n: u32) -> ProptestConfig {
    let n = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(n);
    let default = ProptestConfig::default();
    let rng_seed = if std::env::var_os("PROPTEST_RNG_SEED").is_some() {
        default.rng_seed
    } else {
        proptest::test_runner::RngSeed::Fixed(13)
    };
    ProptestConfig {
        cases: n,
        rng_seed,
        ..default
    }
}

/// A scratch file unique to this process and test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("beltune-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Numbers that break naive code: extremes, subnormals, signed zeros, NaN.
fn nasty_number() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(-0.0),
        Just(5e-324),
        Just(1e-300),
        Just(1e300),
        Just(1e308),
        Just(-1e308),
        Just(f64::MAX),
        Just(f64::INFINITY),
        Just(f64::NAN),
        Just(1.0),
        Just(-1.0),
        -1e6..1e6f64,
        any::<f64>(),
    ]
}

/// TOML/JSON text of a number (non-finite ones in the spellings the readers see).
fn number_text(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:e}")
    }
}

/// CSV cells: numbers, words, empties, quotes, separators.
fn cell() -> impl Strategy<Value = String> {
    prop_oneof![
        nasty_number().prop_map(|x| format!("{x}")),
        Just(String::new()),
        Just("nan".to_string()),
        Just("1,5".to_string()),
        Just("\"2\"".to_string()),
        Just(" 3 ".to_string()),
        Just("0x10".to_string()),
        "[a-z0-9.eE+-]{0,6}",
    ]
}

fn check_columns(cols: &beltune::ident::CsvColumns) {
    let rows = cols.rows();
    for c in &cols.data {
        assert_eq!(c.len(), rows);
        assert!(c.iter().all(|v| v.is_finite()));
    }
}

proptest! {
    #![proptest_config(cases(3000))]

    /// Arbitrary bytes as a CSV file.
    #[test]
    fn csv_reader_survives_arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let p = scratch("bytes.csv");
        std::fs::write(&p, &bytes).unwrap();
        if let Ok(cols) = read_csv_columns(&p, &["t", "u"]) {
            check_columns(&cols);
        }
    }

    /// Structured CSV with nasty cells, missing and duplicate columns.
    #[test]
    fn csv_reader_survives_nasty_cells(
        header in proptest::collection::vec(prop_oneof![Just("t"), Just("u"), Just("y"), Just("")], 1..5),
        rows in proptest::collection::vec(proptest::collection::vec(cell(), 0..6), 0..40),
    ) {
        let mut text = header.join(",") + "\n";
        for r in &rows {
            text.push_str(&r.join(","));
            text.push('\n');
        }
        let p = scratch("cells.csv");
        std::fs::write(&p, &text).unwrap();
        if let Ok(cols) = read_csv_columns(&p, &["t", "u", "y"]) {
            check_columns(&cols);
            if cols.rows() > 0 {
                let _ = beltune::ident::csv_columns::check_time(&cols, "t", 2);
                let _ = beltune::ident::csv_columns::check_not_constant(&cols, "u");
            }
        }
    }
}

/// The egc70 plant TOML with one key's value replaced by `value`.
fn mutated_plant(key_index: usize, value: &str) -> String {
    let text = toml::to_string(&Plant::Physical(egc70_params(11.2))).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let keyed: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains(" = ") && !lines[i].starts_with("kind"))
        .collect();
    let target = keyed[key_index % keyed.len()];
    lines
        .iter()
        .enumerate()
        .map(|(i, l)| {
            if i == target {
                let key = l.split(" = ").next().unwrap();
                format!("{key} = {value}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(cases(2000))]

    /// A plant file with one value replaced: either a typed error, or a plant
    /// whose derived quantities are finite and whose simulator starts.
    #[test]
    fn plant_toml_reader_gives_finite_plants_or_errors(key in 0usize..64, x in nasty_number(), garbage in "[ -~]{0,12}", use_garbage in any::<bool>()) {
        let value = if use_garbage { garbage } else { number_text(x) };
        let p = scratch("plant.toml");
        std::fs::write(&p, mutated_plant(key, &value)).unwrap();
        if let Ok(plant) = load_toml(&p) {
            let s = plant.summary().expect("a loaded plant has a summary");
            for v in [s.f_r_hz, s.f_z_hz, s.kappa, s.resonance_ratio, s.theta_e_kg_m2, s.m_c_kg, s.c_n_per_m] {
                prop_assert!(v.is_finite() && v > 0.0, "{value}: {v}");
            }
            // The simulator either refuses the plant or starts within its
            // sub-step budget (no hang).
            if let Ok(axis) = beltune::sim::SimAxis::new(&plant, beltune::sim::SimConfig::default()) {
                prop_assert!(axis.substeps() <= beltune::sim::MAX_SUBSTEPS);
            }
        }
    }
}

/// A model file (TOML or JSON) of the bench-like axis with nasty values.
fn model_text(values: &[f64; 8], json: bool) -> String {
    let keys = [
        "theta_e",
        "m_c",
        "c",
        "d_m",
        "d_c",
        "i_t",
        "dead_time_s",
        "coulomb",
    ];
    let a4 = beltune::model::TwoMassParams::thesis_table_a4();
    let base = [
        a4.theta_e, a4.m_c, a4.c, a4.d_m, a4.d_c, a4.i_t, 1e-3, 0.125,
    ];
    let pick = |i: usize| {
        if values[i].is_nan() {
            base[i]
        } else {
            values[i]
        }
    };
    if json {
        let fields: Vec<String> = keys
            .iter()
            .enumerate()
            .map(|(i, k)| {
                let v = pick(i);
                // JSON has no inf: a huge exponent is what a file can say.
                let t = if v.is_infinite() {
                    "1e999".to_string()
                } else {
                    format!("{v:e}")
                };
                format!("\"{k}\": {t}")
            })
            .collect();
        format!("{{{}}}", fields.join(", "))
    } else {
        keys.iter()
            .enumerate()
            .map(|(i, k)| format!("{k} = {}\n", number_text(pick(i))))
            .collect()
    }
}

proptest! {
    #![proptest_config(cases(400))]

    /// Model files: parse errors or models whose design is finite or a typed error.
    #[test]
    fn model_file_reader_and_design_give_finite_results_or_errors(
        values in proptest::array::uniform8(prop_oneof![3 => Just(f64::NAN), 1 => nasty_number()]),
        json in any::<bool>(),
    ) {
        let text = model_text(&values, json);
        if let Ok(m) = ModelFile::parse(&text, "fuzz") {
            if let Ok(input) = m.design_input(Some(beltune::design::DEFAULT_TS_S)) {
                if let Ok(d) = design(&input, &DesignKnobs::default()) {
                    for v in [d.k_p, d.k_i, d.k_pp, d.omega_r_rad_s, d.omega_z_rad_s] {
                        prop_assert!(v.is_finite(), "{text}: {v}");
                    }
                }
            }
        }
    }

    /// Design knobs anywhere (NaN, negative, huge): finite gains or a typed error.
    #[test]
    fn design_knobs_give_finite_designs_or_errors(
        pm_v in nasty_number(),
        pm_p in nasty_number(),
        sup in nasty_number(),
        att in proptest::option::of(nasty_number()),
        kind in prop_oneof![Just(PrefilterKind::Butterworth), Just(PrefilterKind::Notch), Just(PrefilterKind::None)],
        sane in any::<bool>(),
    ) {
        // Half the cases near the defaults, where designs exist.
        let (pm_v, pm_p, sup) = if sane {
            (20.0 + pm_v.abs() % 70.0, 20.0 + pm_p.abs() % 70.0, -(0.5 + sup.abs() % 40.0))
        } else {
            (pm_v, pm_p, sup)
        };
        let knobs = DesignKnobs {
            prefilter: kind,
            pm_velocity_deg: pm_v,
            pm_position_deg: pm_p,
            resonance_suppression_db: sup,
            filter_attenuation_db: att,
            dynamics: Default::default(),
        };
        let m = ModelFile::parse(&model_text(&[f64::NAN; 8], false), "egc70").unwrap();
        let input = m.design_input(Some(beltune::design::DEFAULT_TS_S)).unwrap();
        if let Ok(d) = design(&input, &knobs) {
            for v in [d.k_p, d.k_i, d.k_pp] {
                prop_assert!(v.is_finite() && v > 0.0, "{knobs:?}: {v}");
            }
        }
    }
}
