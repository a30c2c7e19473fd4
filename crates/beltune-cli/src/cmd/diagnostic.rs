//! The diagnostic a safety stop leaves behind: `safety-stop.json` (what was
//! running, which limit, the values, the stop) and `safety-stop.csv` (the
//! last second of samples before the violation), written atomically as one
//! folder next to where the results would have gone ([`folder`]): without
//! `--out`, `commissioning/<UTC time>-safety-stop/` beside the runs (the
//! `latest` link keeps pointing at the newest result); with `--out DIR`, the
//! sibling `DIR-safety-stop/`, so that `DIR` stays as it was and the same
//! command runs again once the cause is fixed (a later result in `DIR`
//! removes the then stale sibling).
//!
//! JSON keys (schema [`SCHEMA`], stable like the summary's): `schema`,
//! `stage`, `reason`, `limit` (`travel`, `travel_ahead`, `velocity`,
//! `torque`, `following_error`, `non_finite`), `violation` (the values, SI),
//! `limits` (the supervisor's `travel_min_m`, `travel_max_m`,
//! `torque_max_nm`, `velocity_max_m_s`, `following_error_max_m`), `time_s`,
//! `position_m`, `velocity_m_s`, `torque_command_nm`, `following_error_m`,
//! `stop_position_m`, `stop_error`, `samples_file`, `samples`,
//! `provenance`.

use crate::progress::StopCapture;
use beltune::procedure::outputs::OutputTarget;
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

/// Suffix of a diagnostic folder.
pub const FOLDER_SUFFIX: &str = "-safety-stop";

/// The folder of a stop's diagnostic for `target` (a new name in a history).
pub fn folder(target: &OutputTarget) -> PathBuf {
    match target {
        OutputTarget::Exact { dir, .. } => sibling(dir),
        OutputTarget::History { root } => {
            let stamp = beltune::provenance::Provenance::now(Vec::new(), None)
                .created_utc
                .replace(':', "");
            let mut name = format!("{stamp}{FOLDER_SUFFIX}");
            let mut k = 1;
            while std::fs::symlink_metadata(root.join(&name)).is_ok() {
                k += 1;
                name = format!("{stamp}-{k}{FOLDER_SUFFIX}");
            }
            root.join(name)
        }
    }
}

/// `DIR-safety-stop` beside `DIR`.
fn sibling(dir: &Path) -> PathBuf {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "commissioning".into());
    dir.with_file_name(format!("{name}{FOLDER_SUFFIX}"))
}

/// After a result was written to `--out DIR`: remove the diagnostic of an
/// earlier stop beside it (only a folder holding just the diagnostic files).
pub fn remove_stale(target: &OutputTarget) -> anyhow::Result<()> {
    let OutputTarget::Exact { dir, .. } = target else {
        return Ok(());
    };
    let stale = sibling(dir);
    let Ok(entries) = std::fs::read_dir(&stale) else {
        return Ok(());
    };
    let names: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if names.iter().all(|n| n == JSON_FILE || n == CSV_FILE) {
        std::fs::remove_dir_all(&stale)
            .map_err(|e| anyhow::anyhow!("removing the stale {}: {e}", stale.display()))?;
    }
    Ok(())
}

/// Write both files as one folder ([`folder`] of `target`, replaced as a
/// whole); returns their paths, the description first. `reason` is the
/// one-line message of the stop.
pub fn write(
    target: &OutputTarget,
    stop: &StopCapture,
    reason: &str,
    seed: Option<u64>,
) -> anyhow::Result<Vec<PathBuf>> {
    let dir = folder(target);
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
    let mut text = serde_json::to_string_pretty(&description)?;
    text.push('\n');
    let csv = samples_csv(&r.history);
    Ok(beltune::io::write_folder_atomic(
        &dir,
        &[(JSON_FILE, text.as_bytes()), (CSV_FILE, csv.as_bytes())],
    )?)
}
