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
//! The same diagnostic ends a failed exchange with the axis (lost frames, a
//! drive fault, a watchdog: the drive was told to quick stop): `limit` is
//! then `axis` and `violation` names the failure.
//!
//! JSON keys (schema [`SCHEMA`], stable like the summary's): `schema`,
//! `stage`, `reason`, `limit` (`travel`, `travel_ahead`, `velocity`,
//! `torque`, `following_error`, `non_finite`, `axis`), `violation` (the
//! values, SI; for `axis`: `{"Axis": {"error", "message", "error_code",
//! "quick_stop"}}` with `error` one of `timeout`, `working_counter`,
//! `drive_fault`, `not_operational`),
//! `limits` (the supervisor's `travel_min_m`, `travel_max_m`,
//! `torque_max_nm`, `velocity_max_m_s`, `following_error_max_m`), `time_s`,
//! `position_m`, `velocity_m_s`, `torque_command_nm`, `following_error_m`,
//! `stop_position_m`, `stop_error`, `samples_file`, `samples`,
//! `provenance`.

use crate::progress::{StopCapture, StopCause};
use beltune::axis::AxisError;
use beltune::commission::runner::HistorySample;
use beltune::commission::Violation;
use beltune::record::folder::OutputTarget;
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

/// The `violation` of the description: a violated limit, or the failed exchange.
#[derive(Serialize)]
enum Cause<'a> {
    Axis(AxisFailure),
    #[serde(untagged)]
    Limit(&'a Violation),
}

#[derive(Serialize)]
struct AxisFailure {
    error: &'static str,
    message: String,
    /// CiA 402 error code of a drive fault (0x603F).
    error_code: Option<u16>,
    /// Why the quick stop failed too, if it did.
    quick_stop: Option<String>,
}

/// The short name of a failed exchange.
pub fn axis_error_name(e: &AxisError) -> &'static str {
    match e {
        AxisError::Timeout { .. } => "timeout",
        AxisError::WorkingCounter { .. } => "working_counter",
        AxisError::DriveFault { .. } => "drive_fault",
        AxisError::NotOperational => "not_operational",
        AxisError::Interrupted => "interrupted",
    }
}

#[derive(Serialize)]
struct Description<'a> {
    schema: &'static str,
    stage: &'a str,
    reason: &'a str,
    limit: &'static str,
    violation: Cause<'a>,
    limits: &'a beltune::commission::SafetyLimits,
    time_s: f64,
    position_m: f64,
    velocity_m_s: f64,
    torque_command_nm: f64,
    following_error_m: Option<f64>,
    stop_position_m: Option<f64>,
    stop_error: Option<&'a str>,
    samples_file: &'static str,
    samples: usize,
    provenance: beltune::record::provenance::Provenance,
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
            let stamp = beltune::record::provenance::Provenance::now(Vec::new(), None)
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
    if names
        .iter()
        .all(|n| n == JSON_FILE || n == CSV_FILE || n == beltune::io::MANIFEST_FILE)
    {
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
    let provenance = beltune::record::provenance::Provenance::of_this_process(seed);
    let (description, history) = match &stop.cause {
        StopCause::Limit(r) => (
            Description {
                schema: SCHEMA,
                stage: &stop.stage,
                reason,
                limit: limit_name(&r.violation),
                violation: Cause::Limit(&r.violation),
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
                provenance,
            },
            &r.history,
        ),
        StopCause::Axis(r) => (
            Description {
                schema: SCHEMA,
                stage: &stop.stage,
                reason,
                limit: "axis",
                violation: Cause::Axis(AxisFailure {
                    error: axis_error_name(&r.error),
                    message: r.error.to_string(),
                    error_code: match r.error {
                        AxisError::DriveFault { error_code } => Some(error_code),
                        _ => None,
                    },
                    quick_stop: r.quick_stop.map(|e| e.to_string()),
                }),
                limits: &r.limits,
                time_s: r.time_s,
                position_m: r.position_m,
                velocity_m_s: r.velocity_m_s,
                torque_command_nm: r.torque_command_nm,
                following_error_m: r.following_error_m,
                // the drive stopped the axis on its own: where, the host cannot say
                stop_position_m: None,
                stop_error: None,
                samples_file: CSV_FILE,
                samples: r.history.len(),
                provenance,
            },
            &r.history,
        ),
    };
    let mut text = serde_json::to_string_pretty(&description)?;
    text.push('\n');
    let csv = samples_csv(history);
    Ok(beltune::io::write_folder_atomic(
        &dir,
        &[(JSON_FILE, text.as_bytes()), (CSV_FILE, csv.as_bytes())],
        &[JSON_FILE, CSV_FILE],
    )?)
}
