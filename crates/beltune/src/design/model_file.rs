//! The identified model as a file: TOML written by hand, or the JSON that
//! `beltune identify` writes (same top-level keys; extra keys are ignored).
//!
//! ```toml
//! theta_e = 71.73e-6   # kg m^2
//! m_c = 13.44          # kg
//! c = 203.74e3         # N/m
//! d_m = 33.17          # N s/m (translational equivalent)
//! d_c = 226.42         # N s/m
//! i_t = 0.0124141      # m/rad
//! dead_time_s = 1e-3
//! t_r_s = 2e-3         # optional, default 2 ms
//! d = 0.0              # optional belt damping, N s/m
//! viscous = 2.53e-3    # optional friction, N m s/rad
//! coulomb = 0.125      # optional friction, N m
//! ```

use super::{DesignInput, FrictionParams, DEFAULT_TS_S, DEFAULT_T_R_S};
use crate::model::TwoMassParams;
use crate::{Error, Result};
use std::path::Path;

/// Identified model plus the loop data the design needs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ModelFile {
    /// `Theta_e`, kg m^2.
    pub theta_e: f64,
    /// `m_c`, kg.
    pub m_c: f64,
    /// `c`, N/m.
    pub c: f64,
    /// `d_m`, N s/m.
    pub d_m: f64,
    /// `d_c`, N s/m.
    pub d_c: f64,
    /// `i_t`, m/rad.
    pub i_t: f64,
    /// Belt damping `d`, N s/m (optional, default 0).
    #[serde(default)]
    pub d: f64,
    /// Dead time `t_T`, s.
    pub dead_time_s: f64,
    /// Velocity filter `T_R`, s (optional, default 2 ms).
    #[serde(default = "default_t_r")]
    pub t_r_s: f64,
    /// Viscous friction `d_v~`, N m s/rad (optional).
    #[serde(default, alias = "viscous")]
    pub viscous_nm_s_per_rad: Option<f64>,
    /// Coulomb friction `tau_c~`, N m (optional).
    #[serde(default, alias = "coulomb")]
    pub coulomb_nm: Option<f64>,
}

fn default_t_r() -> f64 {
    DEFAULT_T_R_S
}

impl ModelFile {
    /// Parse JSON (if the text starts with `{`) or TOML; `origin` names the source in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let parsed: std::result::Result<ModelFile, String> = if text.trim_start().starts_with('{') {
            serde_json::from_str(text).map_err(|e| e.to_string())
        } else {
            toml::from_str(text).map_err(|e| e.to_string().replace('\n', " "))
        };
        let m = parsed.map_err(|message| Error::Parse {
            path: origin.to_string(),
            message,
        })?;
        m.design_input(DEFAULT_TS_S)?.validate()?;
        Ok(m)
    }

    /// Read and parse a file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::io::read_to_string_capped(path, crate::io::MAX_TEXT_BYTES)?;
        ModelFile::parse(&text, &path.display().to_string())
    }

    /// The two-mass parameters.
    pub fn params(&self) -> TwoMassParams {
        TwoMassParams {
            theta_e: self.theta_e,
            m_c: self.m_c,
            c: self.c,
            d: self.d,
            d_m: self.d_m,
            d_c: self.d_c,
            i_t: self.i_t,
        }
    }

    /// The design input at sampling time `ts_s` (not validated).
    pub fn design_input(&self, ts_s: f64) -> Result<DesignInput> {
        let friction = if self.viscous_nm_s_per_rad.is_some() || self.coulomb_nm.is_some() {
            let f = FrictionParams {
                viscous_nm_s_per_rad: self.viscous_nm_s_per_rad.unwrap_or(0.0),
                coulomb_nm: self.coulomb_nm.unwrap_or(0.0),
            };
            f.validate()?;
            Some(f)
        } else {
            None
        };
        Ok(DesignInput {
            model: self.params(),
            dead_time_s: self.dead_time_s,
            t_r_s: self.t_r_s,
            ts_s,
            friction,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOML: &str = "theta_e = 71.73e-6\nm_c = 13.44\nc = 203.74e3\nd_m = 33.17\nd_c = 226.42\ni_t = 0.0124141\ndead_time_s = 1e-3\nviscous = 2.53e-3\ncoulomb = 0.125\n";

    #[test]
    fn toml_and_identify_json_with_extras() {
        let m = ModelFile::parse(TOML, "a.toml").unwrap();
        assert_eq!(m.t_r_s, 2e-3);
        assert_eq!(m.d, 0.0);
        let inp = m.design_input(1e-4).unwrap();
        assert_eq!(inp.friction.unwrap().coulomb_nm, 0.125);
        let json = r#"{"theta_e": 71.73e-6, "m_c": 13.44, "c": 203740.0, "d_m": 33.17, "d_c": 226.42,
            "i_t": 0.0124141, "dead_time_s": 0.001, "f_r_hz": 107.1, "fit": {"cost": 0.1}, "frf": [1, 2]}"#;
        let j = ModelFile::parse(json, "m.json").unwrap();
        assert_eq!(j.m_c, 13.44);
        assert!(j.design_input(1e-4).unwrap().friction.is_none());
    }

    #[test]
    fn bad_files_are_errors() {
        assert!(ModelFile::parse("theta_e = 1", "x.toml").is_err());
        let neg = TOML.replace("m_c = 13.44", "m_c = -1");
        let e = ModelFile::parse(&neg, "x.toml").unwrap_err();
        assert!(e.to_string().contains("m_c"), "{e}");
        assert!(ModelFile::parse("{", "x.json").is_err());
        assert!(ModelFile::load(Path::new("/nonexistent/model.toml")).is_err());
    }
}
