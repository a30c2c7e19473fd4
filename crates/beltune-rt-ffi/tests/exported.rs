//! The Rust export compiles and builds the configuration the loader builds;
//! the Rust and C exports carry the same values to the last digit printed.
//! tests/data/controller.rs is `beltune export --lang rust` of
//! tests/data/controller.toml (regenerate with `BELTUNE_BLESS=1`).

use beltune::record::controller::ControllerFile;
use beltune::record::export::{c_header, parse_values, rust_module, values, Value};
use std::path::Path;

#[allow(dead_code)]
mod exported {
    include!("data/controller.rs");
}

fn fixture() -> ControllerFile {
    ControllerFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/controller.toml"))
        .unwrap()
}

#[test]
fn rust_export_is_current_and_equals_the_loaded_configuration() {
    let file = fixture();
    let text = rust_module(&file);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/controller.rs");
    if std::env::var_os("BELTUNE_BLESS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        text,
        "tests/data/controller.rs is stale: BELTUNE_BLESS=1 cargo test -p beltune-rt-ffi --test exported"
    );
    assert_eq!(exported::CASCADE, file.cascade_config().unwrap());
    let conv = beltune_rt::control::SetpointConversion::new(
        exported::I_T_M_PER_RAD,
        exported::BELT_STRETCH,
    )
    .unwrap();
    assert_eq!(conv, file.setpoint_conversion().unwrap());
    assert_eq!(exported::PREVIEW_SAMPLES, file.feedforward.preview_samples);
}

#[test]
fn rust_and_c_exports_agree_to_the_last_digit() {
    let file = fixture();
    let (r, c) = (
        parse_values(&rust_module(&file)),
        parse_values(&c_header(&file)),
    );
    assert_eq!(r, c);
    let vals = values(&file);
    assert_eq!(r.len(), vals.len());
    // every literal reads back to the exact value of the file
    for ((name, lit), (vname, v)) in r.iter().zip(&vals) {
        assert_eq!(name, vname);
        match v {
            Value::Real(x) => {
                assert_eq!(lit.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{name}")
            }
            Value::Count(n) => assert_eq!(lit.parse::<usize>().unwrap(), *n, "{name}"),
            Value::Flag(b) => assert_eq!(lit.parse::<bool>().unwrap(), *b, "{name}"),
        }
    }
    assert!(r.iter().any(|(n, _)| n == "k_p_nm_s_per_rad"));
}
