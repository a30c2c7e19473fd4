//! The diagnostic a safety stop leaves behind: `safety-stop.json` (what was
//! running, which limit, the values, the stop) and `safety-stop.csv` (the
//! last second of samples before the violation), both written atomically
//! into the folder where the results would have gone.
//!
//! JSON keys (schema [`SCHEMA`], stable like the summary's): `schema`,
//! `stage`, `reason`, `limit` (`travel`, `travel_ahead`, `velocity`,
//! `torque`, `following_error`, `non_finite`), `violation` (the values, SI),
//! `limits` (the supervisor's `travel_min_m`, `travel_max_m`,
//! `torque_max_nm`, `velocity_max_m_s`, `following_error_max_m`), `time_s`,
//! `position_m`, `velocity_m_s`, `torque_command_nm`, `following_error_m`,
//! `stop_position_m`, `stop_error`, `samples_file`, `samples`,
//! `provenance`.

use super::util::write_atomic;
use crate::progress::StopCapture;
use beltune::procedure::runner::HistorySample;
use beltune::procedure::Violation;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The schema name and version of `safety-stop.json`.
pub const SCHEMA: &str = "beltune-safety-stop/1";
/// File name of the description.
pub const JSON_FILE: &str = "safety-stop.json";
/// File name of the samples.
pub const CSV_FILE: &str = "safety-stop.csv";
/// Columns of the samples file, SI units (an empty cell: not measured).
pub const CSV_COLUMNS: [&str; 8] = [
    "t_s",
    "torque_command_nm",
    "torque_actual_nm",
    "motor_angle_rad",
    "position_m",
    "cart_position_m",
    "velocity_m_s",
    "following_error_m",
];

#[derive(Serialize)]
struct Description<'a> {
    schema: &'static str,
    stage: &'a str,
    reason: &'a str,
    limit: &'static str,
    violation: &'a Violation,
    limits: &'a beltune::procedure::SafetyLimits,
    time_s: f64,
    position_m: f64,
    velocity_m_s: f64,
    torque_command_nm: f64,
    following_error_m: Option<f64>,
    stop_position_m: Option<f64>,
    stop_error: Option<&'a str>,
    samples_file: &'static str,
    samples: usize,
    provenance: beltune::provenance::Provenance,
}

/// The short name of the violated limit.
pub fn limit_name(v: &Violation) -> &'static str {
    match v {
        Violation::Travel { .. } => "travel",
        Violation::TravelAhead { .. } => "travel_ahead",
        Violation::Velocity { .. } => "velocity",
        Violation::Torque { .. } => "torque",
        Violation::FollowingError { .. } => "following_error",
        Violation::NonFinite => "non_finite",
    }
}

/// The samples as CSV with a header row ([`CSV_COLUMNS`]).
pub fn samples_csv(history: &[HistorySample]) -> String {
    let mut out = CSV_COLUMNS.join(",");
    out.push('\n');
    let opt = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
    for h in history {
        let s = &h.sample;
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{}",
            h.time_s,
            s.torque_command_nm,
            s.torque_actual_nm,
            s.motor_angle_rad,
            s.position_m,
            opt(s.cart_position_m),
            h.velocity_m_s,
            opt(h.following_error_m)
        );
    }
    out
}

/// Remove the diagnostic of an earlier stop from `dir` (after results were
/// written there: a folder must not hold fresh results beside a stale stop).
pub fn remove_stale(dir: &Path) -> anyhow::Result<()> {
    for name in [JSON_FILE, CSV_FILE] {
        let p = dir.join(name);
        match std::fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => anyhow::bail!("removing the stale {}: {e}", p.display()),
        }
    }
    Ok(())
}

/// Write both files into `dir` (created if needed); returns their paths,
/// the description first. `reason` is the one-line message of the stop.
pub fn write(
    dir: &Path,
    stop: &StopCapture,
    reason: &str,
    seed: Option<u64>,
) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("creating {}: {e}", dir.display()))?;
    let r = &stop.record;
    let description = Description {
        schema: SCHEMA,
        stage: &stop.stage,
        reason,
        limit: limit_name(&r.violation),
        violation: &r.violation,
        limits: &r.limits,
        time_s: r.time_s,
        position_m: r.position_m,
        velocity_m_s: r.velocity_m_s,
        torque_command_nm: r.torque_command_nm,
        following_error_m: r.following_error_m,
        stop_position_m: r.stop_position_m,
        stop_error: r.stop_error.as_deref(),
        samples_file: CSV_FILE,
        samples: r.history.len(),
        provenance: beltune::provenance::Provenance::of_this_process(seed),
    };
    // The samples first: the description that names them appears only when they are there.
    let csv = dir.join(CSV_FILE);
    write_atomic(&csv, samples_csv(&r.history).as_bytes())?;
    let json = dir.join(JSON_FILE);
    let mut text = serde_json::to_string_pretty(&description)?;
    text.push('\n');
    write_atomic(&json, text.as_bytes())?;
    Ok(vec![json, csv])
}
