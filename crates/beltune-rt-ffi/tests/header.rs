//! The committed C header `include/beltune_rt.h` is what cbindgen generates
//! from `src/lib.rs` with `cbindgen.toml` (regenerate with `BELTUNE_BLESS=1`).

use std::path::Path;

#[test]
fn committed_header_is_cbindgens_output() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen runs")
        .write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = dir.join("include/beltune_rt.h");
    if std::env::var_os("BELTUNE_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "include/beltune_rt.h is stale: run BELTUNE_BLESS=1 cargo test -p beltune-rt-ffi --test header"
    );
    for f in [
        "bt_cascade_init",
        "bt_cascade_step",
        "bt_trajectory_plan",
        "bt_setpoint_convert",
    ] {
        assert!(generated.contains(f), "{f} missing from the header");
    }
}
