//! Where the tuning page's design model comes from: a commissioning folder
//! (`commissioning.json`, written by `beltune commission`) or the built-in axis.

use anyhow::Context;
use beltune::model::TwoMassParams;
use serde::Deserialize;
use std::path::Path;

use super::api::{DefaultAttenuation, DesignResponse, EffectiveKnobs, Knobs};
use super::tuner::{ModelSummary, TuneError, Tuner};

/// File read from `--commissioning DIR`.
pub const COMMISSIONING_FILE: &str = "commissioning.json";

/// Identified two-mass model in `commissioning.json` (extra keys are ignored).
#[derive(Debug, Clone, Deserialize)]
pub struct IdentifiedModel {
    /// Motor-side inertia, kg m^2.
    pub theta_e: f64,
    /// Cart mass incl. payload, kg.
    pub m_c: f64,
    /// Belt stiffness, N/m.
    pub c: f64,
    /// Belt damping, N s/m (optional, 0 when absent).
    #[serde(default)]
    pub d: f64,
    /// Motor damping (translational equivalent), N s/m.
    pub d_m: f64,
    /// Cart damping, N s/m.
    pub d_c: f64,
    /// Transmission r / i_g, m/rad.
    pub i_t: f64,
    /// Current-loop dead time, s.
    pub dead_time_s: f64,
}

/// Friction identified from constant-velocity runs (thesis 3.6), as seen at the motor.
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct FrictionTotals {
    /// Viscous friction d_v, N m s/rad.
    pub viscous: f64,
    /// Coulomb friction tau_c, N m.
    pub coulomb: f64,
}

/// The parts of `commissioning.json` the tuning page needs.
#[derive(Debug, Clone, Deserialize)]
pub struct CommissioningFile {
    /// Identified model.
    pub identified: IdentifiedModel,
    /// Identified friction (optional).
    #[serde(default)]
    pub friction: Option<FrictionTotals>,
}

/// The model the page designs for.
#[derive(Debug, Clone)]
pub struct DesignModel {
    /// Human-readable origin.
    pub source: String,
    /// Linear two-mass model.
    pub params: TwoMassParams,
    /// Current-loop dead time, s.
    pub dead_time_s: f64,
    /// Friction for the feedforward, if known.
    pub friction: Option<FrictionTotals>,
}

/// Read `dir/commissioning.json`; every failure names the file.
pub fn load_commissioning(dir: &Path) -> anyhow::Result<DesignModel> {
    let path = dir.join(COMMISSIONING_FILE);
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let file: CommissioningFile =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let id = file.identified;
    let params = TwoMassParams {
        theta_e: id.theta_e,
        m_c: id.m_c,
        c: id.c,
        d: id.d,
        d_m: id.d_m,
        d_c: id.d_c,
        i_t: id.i_t,
    };
    params
        .validate()
        .with_context(|| format!("{}: identified model", path.display()))?;
    beltune::error::require_positive("dead_time_s [s]", id.dead_time_s)
        .with_context(|| format!("{}: identified model", path.display()))?;
    if let Some(f) = file.friction {
        beltune::error::require_non_negative("friction.viscous [N m s/rad]", f.viscous)
            .and_then(|_| beltune::error::require_non_negative("friction.coulomb [N m]", f.coulomb))
            .with_context(|| format!("{}: friction", path.display()))?;
    }
    Ok(DesignModel {
        source: format!("commissioning {}", dir.display()),
        params,
        dead_time_s: id.dead_time_s,
        friction: file.friction,
    })
}

/// The [`Tuner`] backed by the beltune library: `beltune::design` for the
/// controller and `beltune::procedure::validation` for the simulated move.
pub struct LibraryTuner {
    model: DesignModel,
}

impl LibraryTuner {
    /// Tuner for `model`.
    pub fn new(model: DesignModel) -> anyhow::Result<Self> {
        anyhow::bail!(
            "the controller design (beltune::design) is not merged yet; cannot tune {}",
            model.source
        )
    }

    /// Tuner for the built-in egc70 axis.
    pub fn builtin() -> anyhow::Result<Self> {
        anyhow::bail!("the built-in plants (beltune::model::rigs) are not merged yet")
    }
}

impl Tuner for LibraryTuner {
    fn model(&self) -> ModelSummary {
        ModelSummary {
            source: self.model.source.clone(),
            f_r_hz: self.model.params.f_r_hz(),
            f_z_hz: self.model.params.f_z_hz(),
            nominal_payload_kg: 0.0,
        }
    }
    fn defaults(&self) -> EffectiveKnobs {
        unimplemented!()
    }
    fn default_attenuation(&self) -> DefaultAttenuation {
        unimplemented!()
    }
    fn tune(&self, _knobs: &Knobs) -> Result<DesignResponse, TuneError> {
        unimplemented!()
    }
    fn controller_toml(&self, _knobs: &Knobs) -> Result<String, TuneError> {
        unimplemented!()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("beltune-serve-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn reads_identified_model_and_ignores_extras() {
        let dir = temp_dir("ok");
        let json = r#"{"identified": {"theta_e": 7.173e-5, "m_c": 13.44, "c": 203740.0,
            "d_m": 33.17, "d_c": 226.42, "i_t": 0.012414, "dead_time_s": 0.001, "fit_rms_db": 0.4},
            "friction": {"viscous": 0.00253, "coulomb": 0.125}, "design": {"k_p": 1}}"#;
        std::fs::write(dir.join(COMMISSIONING_FILE), json).unwrap();
        let m = load_commissioning(&dir).unwrap();
        assert_eq!(m.params.m_c, 13.44);
        assert_eq!(m.params.d, 0.0);
        assert_eq!(m.dead_time_s, 0.001);
        assert_eq!(m.friction.unwrap().coulomb, 0.125);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn non_physical_or_missing_model_is_an_error_naming_the_file() {
        let dir = temp_dir("bad");
        let e = load_commissioning(&dir).unwrap_err();
        assert!(format!("{e:#}").contains(COMMISSIONING_FILE), "{e:#}");
        let json = r#"{"identified": {"theta_e": -1, "m_c": 13.44, "c": 203740.0,
            "d_m": 33.17, "d_c": 226.42, "i_t": 0.012414, "dead_time_s": 0.001}}"#;
        std::fs::write(dir.join(COMMISSIONING_FILE), json).unwrap();
        let e = format!("{:#}", load_commissioning(&dir).unwrap_err());
        assert!(e.contains("theta_e"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
