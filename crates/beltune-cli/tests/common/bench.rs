//! The bench recording shipped in the repository and the arguments that
//! describe it, shared by every test that runs the CLI on recorded data.

use std::path::PathBuf;
use std::process::Command;

/// The `beltune` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beltune"))
}

/// `data/twomass-bench/multisine-a.csv.gz`: 20 periods of 2500 samples, motor
/// current `iq_ref_A` in, motor angle `theta_motor_rad` out.
pub fn measured() -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/twomass-bench/multisine-a.csv.gz");
    assert!(
        p.exists(),
        "measured data missing: {} (it ships in the repository, data/twomass-bench)",
        p.display()
    );
    p
}

/// The columns and period of [`measured`].
pub const RECORD_ARGS: [&str; 6] = [
    "--input",
    "iq_ref_A",
    "--output",
    "theta_motor_rad",
    "--period-samples",
    "2500",
];

/// `beltune SUBCOMMAND --csv <bench record> <RECORD_ARGS>` (`identify` or
/// `commission`), ready for more arguments.
pub fn on_record(subcommand: &str) -> Command {
    let mut c = bin();
    c.args([subcommand, "--csv"])
        .arg(measured())
        .args(RECORD_ARGS);
    c
}
