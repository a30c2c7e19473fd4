//! The seam between the web server and the library: a [`Tuner`] takes validated
//! knobs and returns everything the page shows. The server knows nothing about
//! the controller design or the simulator beyond this trait.

use super::api::{
    CommissionedNumbers, DefaultAttenuation, DesignResponse, EffectiveKnobs, FrfOverlay, Knobs,
};

/// Why a tuning request produced no design.
#[derive(Debug, Clone, PartialEq)]
pub enum TuneError {
    /// The knobs ask for something the plant cannot do (HTTP 422, reason shown).
    Infeasible(String),
    /// Anything else (HTTP 500).
    Internal(String),
}

impl std::fmt::Display for TuneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TuneError::Infeasible(r) => write!(f, "{r}"),
            TuneError::Internal(r) => write!(f, "internal error: {r}"),
        }
    }
}

/// Design model summary shown in the page header.
#[derive(Debug, Clone)]
pub struct ModelSummary {
    /// Where the model comes from.
    pub source: String,
    /// Resonance frequency, Hz.
    pub f_r_hz: f64,
    /// Antiresonance frequency, Hz.
    pub f_z_hz: f64,
    /// Payload the design model assumes, kg.
    pub nominal_payload_kg: f64,
    /// The measured FRF and its fit, when known.
    pub measured_frf: Option<FrfOverlay>,
    /// The commissioning's own validation numbers, when known.
    pub commissioned: Option<CommissionedNumbers>,
    /// The result's verdict as text (`PASS: ...`), when it has one.
    pub commissioned_verdict: Option<String>,
}

/// One file of a saved set: name and contents.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedFile {
    /// File name (no directory).
    pub name: String,
    /// Contents.
    pub bytes: Vec<u8>,
}

/// Runs the controller design and the simulated move for a set of knobs.
pub trait Tuner: Send + Sync + 'static {
    /// The design model.
    fn model(&self) -> ModelSummary;
    /// The knobs' defaults (= the design library's defaults).
    fn defaults(&self) -> EffectiveKnobs;
    /// Default prefilter attenuation per kind, dB.
    fn default_attenuation(&self) -> DefaultAttenuation;
    /// Design, evaluate and simulate.
    fn tune(&self, knobs: &Knobs) -> Result<DesignResponse, TuneError>;
    /// The design for `knobs` as the text of `controller.toml`.
    fn controller_toml(&self, knobs: &Knobs) -> Result<String, TuneError>;
    /// Everything Save writes, as one consistent set: `controller.toml` first,
    /// then (when the tuner can make them) `commissioning.json`, `report.html`
    /// and the data files, all for the same design. Default: `controller.toml` only.
    fn save_set(&self, knobs: &Knobs) -> Result<Vec<SavedFile>, TuneError> {
        Ok(vec![SavedFile {
            name: super::CONTROLLER_FILE.to_string(),
            bytes: self.controller_toml(knobs)?.into_bytes(),
        }])
    }
}
