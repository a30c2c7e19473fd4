//! `health.json`: a health check as a file (schema [`SCHEMA_VERSION`],
//! docs/health.md): who ran it, on which axis, against which baseline, what
//! it measured, each quantity against the baseline, the verdict and the log.
//! One type, [`HealthRecord`], written by [`HealthRecord::to_json_text`] and
//! read by [`HealthRecord::parse`].

use super::commissioning::AxisRecord;
use super::provenance::Provenance;

use crate::health::HealthCheck;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// The file of a health check's result folder.
pub const HEALTH_FILE: &str = "health.json";

/// `health.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HealthRecord {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Who wrote it.
    pub provenance: Provenance,
    /// The axis' name (`--axis`, else the baseline's plant).
    pub axis: String,
    /// What the check ran on.
    pub axis_record: AxisRecord,
    /// The baseline's result folder.
    pub baseline_dir: String,
    /// When the baseline was commissioned (UTC), if it says.
    pub baseline_created_utc: Option<String>,
    /// The check.
    pub check: HealthCheck,
    /// The recommendations, worst first.
    pub recommendations: Vec<String>,
}

impl HealthRecord {
    /// The JSON text.
    pub fn to_json_text(&self) -> Result<String> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| Error::Report {
            reason: format!("{HEALTH_FILE}: {e}"),
        })?;
        text.push('\n');
        Ok(text)
    }

    /// Parse the text of a `health.json`; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        serde_json::from_str(text).map_err(|e| Error::Parse {
            path: origin.to_string(),
            message: format!("not a health check written by `beltune health`: {e}"),
        })
    }

    /// Read and parse `path` (at most [`crate::io::MAX_TEXT_BYTES`]).
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = crate::io::read_to_string_capped(path, crate::io::MAX_TEXT_BYTES)?;
        Self::parse(&text, &path.display().to_string())
    }
}
