//! The identified-model record (schema [`SCHEMA_VERSION`], docs/schema.md): what
//! `beltune identify --json` and `beltune commission` (`commissioning.json`)
//! write, and what `beltune design --model`, `beltune serve` and the export read.
//!
//! A record is a JSON or TOML document with `schema_version`, `provenance`,
//! `identified` ([`IdentifiedModel`]) and `friction` ([`FrictionResult`]);
//! `commissioning.json` is such a document with more sections. A hand-written
//! model may also be flat (the keys of [`IdentifiedModel`] at the top, with
//! optional `viscous_nm_s_per_rad` / `coulomb_nm`), as files before schema 1 were:
//!
//! ```toml
//! theta_e = 71.73e-6   # kg m^2
//! m_c = 13.44          # kg
//! c = 203.74e3         # N/m
//! d_m = 33.17          # N s/m (translational equivalent)
//! d_c = 226.42         # N s/m
//! i_t = 0.0124141      # m/rad
//! dead_time_s = 1e-3   # optional: 1 ms (thesis 3.30) assumed when absent or null
//! t_r_s = 2e-3         # optional, default 2 ms
//! d = 0.0              # optional belt damping, N s/m
//! viscous_nm_s_per_rad = 2.53e-3  # optional friction (old key: viscous)
//! coulomb_nm = 0.125              # optional friction (old key: coulomb)
//! ```
//!
//! With `units = "current"` every N m of a unit reads A (the input was a motor
//! current and the torque constant is unknown): see [`crate::units`].

use crate::design::{DesignInput, FrictionParams, DEFAULT_TS_S, DEFAULT_T_R_S};
use crate::ident::{Frf, ModelUnits, TwoMassFit};
use crate::model::TwoMassParams;
use crate::record::provenance::Provenance;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

use super::SCHEMA_VERSION;

/// Dead time assumed when it was not measured (no actual-torque column), s
/// (thesis (3.30): 10 samples of 100 us).
pub const DEFAULT_DEAD_TIME_S: f64 = 1e-3;

/// The identified two-mass model (thesis Table A.4 layout), the loop data the
/// design needs and the quality of the fit. In the record's units ([`Self::units`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawModel")]
pub struct IdentifiedModel {
    /// Unit system of the record: `torque` (SI) or `current` (every N m reads A).
    pub units: ModelUnits,
    /// Resonance frequency (2.44), Hz (recomputed from the parameters on reading).
    pub f_r_hz: f64,
    /// Antiresonance frequency (2.45), Hz (recomputed from the parameters on reading).
    pub f_z_hz: f64,
    /// Motor-side inertia `Theta_e`, kg m^2.
    pub theta_e: f64,
    /// Moving mass `m_c`, kg.
    pub m_c: f64,
    /// Belt stiffness `c`, N/m.
    pub c: f64,
    /// Belt damping `d`, N s/m (0 in the fitted model (2.42)).
    pub d: f64,
    /// Motor damping (translational equivalent) `d_m`, N s/m.
    pub d_m: f64,
    /// Cart damping `d_c`, N s/m.
    pub d_c: f64,
    /// Transmission `i_t`, m/rad.
    pub i_t: f64,
    /// Current-loop dead time `t_T` (3.30) the design uses, s.
    pub dead_time_s: f64,
    /// `false` when the dead time was not measured and [`DEFAULT_DEAD_TIME_S`]
    /// is assumed (written as `dead_time_s = null` before schema 1).
    pub dead_time_measured: bool,
    /// Velocity filter time constant `T_R`, s.
    pub t_r_s: f64,
    /// Sampling time of the record (and of the drive), s; `None` if unknown.
    pub ts_s: Option<f64>,
    /// Torque limit of the drive, N m (A in current units); `None` if unknown.
    pub torque_max_nm: Option<f64>,
    /// RMS error of the magnitude fit (3.33), dB (NaN / `null`: unknown).
    pub fit_rms_db: f64,
    /// One-sigma uncertainty of `m_c`, kg (NaN / `null`: unknown).
    pub m_c_sigma: f64,
    /// One-sigma uncertainty of `c`, N/m (NaN / `null`: unknown).
    pub c_sigma: f64,
    /// Mean magnitude-squared coherence over the lines used by the fit (NaN / `null`: unknown).
    pub mean_coherence: f64,
    /// Number of FRF lines used by the fit (0: unknown).
    pub lines_used: usize,
    /// Cart position at which the FRF was measured, m (NaN / `null`: unknown, e.g. recorded data).
    pub position_m: f64,
    /// How the parameters were identified (`frf_fit` when absent).
    pub method: IdentificationMethod,
    /// Coulomb friction of the motor side the friction-aware fit found, N m
    /// (`null`: not identified).
    pub motor_coulomb_nm: Option<f64>,
    /// Coulomb friction of the cart the friction-aware fit found, N
    /// (`null`: not identified).
    pub cart_coulomb_n: Option<f64>,
    /// How the model changes from [`Self::position_m`] to the ends of the
    /// stroke, from the data sheet's physics ([`crate::model::stroke`]);
    /// absent: unknown (recorded data, a linear set), the design is checked
    /// at the identification position only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stroke_variation: Option<crate::model::stroke::StrokeVariation>,
}

/// Which identification gave the parameters of an [`IdentifiedModel`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IdentificationMethod {
    /// The thesis' fit of the linear model (2.42) to the FRF's magnitude (3.33).
    #[default]
    FrfFit,
    /// The nonlinear model (2.30) with the Coulomb friction of the motor and
    /// of the cart, fitted to the time record ([`crate::ident::nonlinear`]).
    FrictionAware,
}

/// What a file may hold: every field optional or with an old spelling.
#[derive(Deserialize)]
struct RawModel {
    #[serde(default)]
    units: ModelUnits,
    theta_e: f64,
    m_c: f64,
    c: f64,
    #[serde(default)]
    d: f64,
    d_m: f64,
    d_c: f64,
    i_t: f64,
    #[serde(default)]
    dead_time_s: Option<f64>,
    #[serde(default)]
    dead_time_measured: Option<bool>,
    #[serde(default)]
    t_r_s: Option<f64>,
    #[serde(default, alias = "sample_time_s")]
    ts_s: Option<f64>,
    #[serde(default, alias = "torque_limit_nm")]
    torque_max_nm: Option<f64>,
    #[serde(default)]
    fit_rms_db: Option<f64>,
    #[serde(default)]
    m_c_sigma: Option<f64>,
    #[serde(default)]
    c_sigma: Option<f64>,
    #[serde(default)]
    mean_coherence: Option<f64>,
    #[serde(default, alias = "n_lines")]
    lines_used: Option<usize>,
    #[serde(default)]
    position_m: Option<f64>,
    #[serde(default)]
    method: IdentificationMethod,
    #[serde(default)]
    motor_coulomb_nm: Option<f64>,
    #[serde(default)]
    cart_coulomb_n: Option<f64>,
    #[serde(default)]
    stroke_variation: Option<crate::model::stroke::StrokeVariation>,
}

impl TryFrom<RawModel> for IdentifiedModel {
    type Error = String;
    fn try_from(r: RawModel) -> std::result::Result<Self, String> {
        let params = TwoMassParams {
            theta_e: r.theta_e,
            m_c: r.m_c,
            c: r.c,
            d: r.d,
            d_m: r.d_m,
            d_c: r.d_c,
            i_t: r.i_t,
        };
        params.validate().map_err(|e| e.to_string())?;
        if let Some(v) = &r.stroke_variation {
            v.validate().map_err(|e| e.to_string())?;
        }
        let measured = r.dead_time_measured.unwrap_or(r.dead_time_s.is_some());
        let nan = f64::NAN;
        Ok(IdentifiedModel {
            units: r.units,
            f_r_hz: params.f_r_hz(),
            f_z_hz: params.f_z_hz(),
            theta_e: r.theta_e,
            m_c: r.m_c,
            c: r.c,
            d: r.d,
            d_m: r.d_m,
            d_c: r.d_c,
            i_t: r.i_t,
            dead_time_s: r.dead_time_s.unwrap_or(DEFAULT_DEAD_TIME_S),
            dead_time_measured: measured,
            t_r_s: r.t_r_s.unwrap_or(DEFAULT_T_R_S),
            ts_s: r.ts_s,
            torque_max_nm: r.torque_max_nm,
            fit_rms_db: r.fit_rms_db.unwrap_or(nan),
            m_c_sigma: r.m_c_sigma.unwrap_or(nan),
            c_sigma: r.c_sigma.unwrap_or(nan),
            mean_coherence: r.mean_coherence.unwrap_or(nan),
            lines_used: r.lines_used.unwrap_or(0),
            position_m: r.position_m.unwrap_or(nan),
            method: r.method,
            motor_coulomb_nm: r.motor_coulomb_nm.filter(|x| x.is_finite()),
            cart_coulomb_n: r.cart_coulomb_n.filter(|x| x.is_finite()),
            stroke_variation: r.stroke_variation,
        })
    }
}

impl IdentifiedModel {
    /// The summary of a fit on `frf`, with the dead time used and the cart
    /// position of the measurement (NaN when unknown, e.g. recorded data).
    /// Sampling time and torque limit are unknown here (`None`): the caller sets them.
    pub fn from_fit(fit: &TwoMassFit, frf: &Frf, dead_time_s: f64, position_m: f64) -> Self {
        let used = frf.usable_indices();
        let mean_coherence = if used.is_empty() {
            0.0
        } else {
            used.iter().map(|&i| frf.coherence[i]).sum::<f64>() / used.len() as f64
        };
        let p = fit.params;
        IdentifiedModel {
            units: fit.units,
            f_r_hz: fit.f_r_hz,
            f_z_hz: fit.f_z_hz,
            theta_e: p.theta_e,
            m_c: p.m_c,
            c: p.c,
            d: p.d,
            d_m: p.d_m,
            d_c: p.d_c,
            i_t: p.i_t,
            dead_time_s,
            dead_time_measured: true,
            t_r_s: DEFAULT_T_R_S,
            ts_s: None,
            torque_max_nm: None,
            fit_rms_db: fit.fit_rms_db,
            m_c_sigma: fit.m_c_sigma(),
            c_sigma: fit.c_sigma(),
            mean_coherence,
            lines_used: fit.n_lines,
            position_m,
            method: IdentificationMethod::FrfFit,
            motor_coulomb_nm: None,
            cart_coulomb_n: None,
            stroke_variation: None,
        }
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
}

/// Friction seen at the motor (3.36), N m based (A in current units).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "RawFriction")]
pub struct FrictionResult {
    /// Viscous coefficient `d_v~`, N m s/rad (key `viscous` before schema 1).
    pub viscous_nm_s_per_rad: f64,
    /// Coulomb torque `tau_c~`, N m (key `coulomb` before schema 1).
    pub coulomb_nm: f64,
    /// Viscous-only fit (the "linear" feedforward), N m s/rad (key
    /// `linear_viscous` before schema 1; `viscous_nm_s_per_rad` when absent).
    pub linear_viscous_nm_s_per_rad: f64,
    /// Relative residual of the (3.36) fit (0 when not given).
    pub relative_residual: f64,
    /// Holding torque (gravity on a tilted axis, or the record's constant
    /// offset), N m (0 when not given).
    pub holding_torque_nm: f64,
    /// The cart's share of the Coulomb friction, `F_c` in N (current units:
    /// A m/rad), from the friction-aware model (`beltune::ident::nonlinear`);
    /// 0 when unknown. Part of [`Self::coulomb_nm`], not in addition to it:
    /// the setpoint conversion leads the motor by the belt stretch it causes.
    pub cart_coulomb_n: f64,
    /// The cart's viscous friction `d_c`, N s/m, from the friction-aware
    /// model; 0 when unknown (as [`Self::cart_coulomb_n`]).
    pub cart_viscous_n_s_per_m: f64,
}

/// What a file's `friction` may hold (old spellings, optional parts).
#[derive(Deserialize)]
struct RawFriction {
    #[serde(alias = "viscous")]
    viscous_nm_s_per_rad: f64,
    #[serde(alias = "coulomb")]
    coulomb_nm: f64,
    #[serde(default, alias = "linear_viscous")]
    linear_viscous_nm_s_per_rad: Option<f64>,
    #[serde(default)]
    relative_residual: f64,
    #[serde(default)]
    holding_torque_nm: f64,
    #[serde(default)]
    cart_coulomb_n: f64,
    #[serde(default)]
    cart_viscous_n_s_per_m: f64,
}

impl From<RawFriction> for FrictionResult {
    fn from(r: RawFriction) -> Self {
        FrictionResult {
            viscous_nm_s_per_rad: r.viscous_nm_s_per_rad,
            coulomb_nm: r.coulomb_nm,
            linear_viscous_nm_s_per_rad: r
                .linear_viscous_nm_s_per_rad
                .unwrap_or(r.viscous_nm_s_per_rad),
            relative_residual: r.relative_residual,
            holding_torque_nm: r.holding_torque_nm,
            cart_coulomb_n: r.cart_coulomb_n,
            cart_viscous_n_s_per_m: r.cart_viscous_n_s_per_m,
        }
    }
}

impl FrictionResult {
    /// The friction parameters of the design (feedforward (4.16)).
    pub fn params(&self) -> FrictionParams {
        FrictionParams {
            viscous_nm_s_per_rad: self.viscous_nm_s_per_rad,
            coulomb_nm: self.coulomb_nm,
        }
    }
}

/// An identified-model record: the part of `commissioning.json` (or of the
/// `identify --json` file) that a design needs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelFile {
    /// [`SCHEMA_VERSION`] of the file (0: a file from before schema 1).
    pub schema_version: u32,
    /// Who wrote it (absent in hand-written and old files).
    pub provenance: Option<Provenance>,
    /// The model.
    pub identified: IdentifiedModel,
    /// Friction, if identified.
    pub friction: Option<FrictionResult>,
}

/// The document form (`commissioning.json`, `identify --json`); other keys are ignored.
#[derive(Deserialize)]
struct Document {
    #[serde(default)]
    schema_version: u32,
    #[serde(default)]
    provenance: Option<Provenance>,
    identified: IdentifiedModel,
    #[serde(default)]
    friction: Option<FrictionResult>,
}

/// The flat form (hand-written, or `identify --json` before schema 1).
#[derive(Deserialize)]
struct FlatFriction {
    #[serde(default, alias = "viscous")]
    viscous_nm_s_per_rad: Option<f64>,
    #[serde(default, alias = "coulomb")]
    coulomb_nm: Option<f64>,
}

/// Keys of the model itself (flat form, or the `identified` table), with their
/// old spellings and the recomputed frequencies a written record carries.
const MODEL_KEYS: &[&str] = &[
    "units",
    "f_r_hz",
    "f_z_hz",
    "theta_e",
    "m_c",
    "c",
    "d",
    "d_m",
    "d_c",
    "i_t",
    "dead_time_s",
    "dead_time_measured",
    "t_r_s",
    "ts_s",
    "sample_time_s",
    "torque_max_nm",
    "torque_limit_nm",
    "fit_rms_db",
    "m_c_sigma",
    "c_sigma",
    "mean_coherence",
    "lines_used",
    "n_lines",
    "position_m",
    "method",
    "motor_coulomb_nm",
    "cart_coulomb_n",
];
/// Keys of a `friction` table (and the flat form's friction), with old spellings.
const FRICTION_KEYS: &[&str] = &[
    "viscous_nm_s_per_rad",
    "viscous",
    "coulomb_nm",
    "coulomb",
    "linear_viscous_nm_s_per_rad",
    "linear_viscous",
    "relative_residual",
    "holding_torque_nm",
    "cart_coulomb_n",
    "stroke_variation",
    "cart_viscous_n_s_per_m",
];
/// Top-level keys of the document form.
const DOCUMENT_KEYS: &[&str] = &["schema_version", "provenance", "identified", "friction"];

/// A hand-written (TOML) model may hold only the keys beltune reads: a key it
/// does not know (a typo such as `colomb_nm`, or a unit beltune does not use)
/// would otherwise be silently ignored. JSON records
/// (`identify --json`, `commissioning.json`) carry more sections and are not
/// checked. In current units a key may carry the current suffix (`_a`).
fn check_known_keys(v: &serde_json::Value) -> std::result::Result<(), String> {
    let current =
        |m: &serde_json::Value| m.get("units").and_then(|u| u.as_str()) == Some("current");
    let known = |key: &str, list: &[&str], current: bool| {
        list.contains(&key)
            || (current
                && crate::units::torque_key(key).is_some_and(|k| list.contains(&k.as_str())))
    };
    let check = |table: &serde_json::Value, list: &[&str], current: bool, prefix: &str| {
        let Some(map) = table.as_object() else {
            return Ok(());
        };
        match map.keys().find(|k| !known(k, list, current)) {
            Some(k) => Err(format!(
                "unknown key `{prefix}{k}`: not a key of the identified-model file \
                 (docs/schema.md lists them)"
            )),
            None => Ok(()),
        }
    };
    if let Some(id) = v.get("identified") {
        let cur = current(id);
        check(v, DOCUMENT_KEYS, cur, "")?;
        check(id, MODEL_KEYS, cur, "identified.")?;
        if let Some(f) = v.get("friction") {
            check(f, FRICTION_KEYS, cur, "friction.")?;
        }
        Ok(())
    } else {
        let flat: Vec<&str> = MODEL_KEYS.iter().chain(FRICTION_KEYS).copied().collect();
        check(v, &flat, current(v), "")
    }
}

impl ModelFile {
    /// A schema-[`SCHEMA_VERSION`] record.
    pub fn new(
        identified: IdentifiedModel,
        friction: Option<FrictionResult>,
        provenance: Provenance,
    ) -> Self {
        ModelFile {
            schema_version: SCHEMA_VERSION,
            provenance: Some(provenance),
            identified,
            friction,
        }
    }

    /// Parse JSON (if the text starts with `{`) or TOML; `origin` names the
    /// source in errors. The model and friction are validated.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let perr = |message: String| Error::Parse {
            path: origin.to_string(),
            message,
        };
        let value: serde_json::Value = if text.trim_start().starts_with('{') {
            serde_json::from_str(text).map_err(|e| perr(e.to_string()))?
        } else {
            let t: toml::Value =
                toml::from_str(text).map_err(|e| perr(e.to_string().replace('\n', " ")))?;
            serde_json::to_value(t).map_err(|e| perr(e.to_string()))?
        };
        let mut value = value;
        if !text.trim_start().starts_with('{') {
            check_known_keys(&value).map_err(perr)?;
        }
        let units_of =
            |v: &serde_json::Value| v.get("units").and_then(|u| u.as_str()) == Some("current");
        if value.get("identified").is_some_and(units_of) || units_of(&value) {
            crate::units::relabel_keys(&mut value, &crate::units::torque_key);
        }
        let file = if value.get("identified").is_some() {
            let d: Document = serde_json::from_value(value).map_err(|e| perr(e.to_string()))?;
            if d.schema_version > SCHEMA_VERSION {
                return Err(perr(format!(
                    "schema_version {} is newer than this beltune reads ({SCHEMA_VERSION})",
                    d.schema_version
                )));
            }
            ModelFile {
                schema_version: d.schema_version,
                provenance: d.provenance,
                identified: d.identified,
                friction: d.friction,
            }
        } else {
            let f: FlatFriction =
                serde_json::from_value(value.clone()).map_err(|e| perr(e.to_string()))?;
            let identified: IdentifiedModel =
                serde_json::from_value(value).map_err(|e| perr(e.to_string()))?;
            let friction =
                (f.viscous_nm_s_per_rad.is_some() || f.coulomb_nm.is_some()).then(|| {
                    let v = f.viscous_nm_s_per_rad.unwrap_or(0.0);
                    FrictionResult {
                        viscous_nm_s_per_rad: v,
                        coulomb_nm: f.coulomb_nm.unwrap_or(0.0),
                        linear_viscous_nm_s_per_rad: v,
                        relative_residual: 0.0,
                        holding_torque_nm: 0.0,
                        cart_coulomb_n: 0.0,
                        cart_viscous_n_s_per_m: 0.0,
                    }
                });
            ModelFile {
                schema_version: 0,
                provenance: None,
                identified,
                friction,
            }
        };
        let checked = (|| -> Result<()> {
            file.design_input(None)?.validate()?;
            if let Some(t) = file.identified.torque_max_nm {
                crate::model::params::check_torque_limit("torque_max_nm", t)?;
            }
            if let Some(ts) = file.identified.ts_s {
                crate::model::params::check_sample_time(ts)?;
            }
            Ok(())
        })();
        // The file's name and its own spelling of the key (current units:
        // `torque_max_a`), not the library's.
        checked.map_err(|e| match e {
            Error::InvalidParameter {
                name,
                value,
                reason,
            } => {
                let value = crate::error::short_number(value);
                let key = match file.identified.units {
                    ModelUnits::Current => crate::units::current_key(&name).unwrap_or(name),
                    ModelUnits::Torque => name,
                };
                perr(if key == "ts_s" && file.identified.ts_s.is_none() {
                    format!("at the default sampling time {value} s: {reason}")
                } else {
                    format!("`{key}` = {value}: {reason}")
                })
            }
            e => e,
        })?;
        Ok(file)
    }

    /// Read and parse a file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::io::read_to_string_capped(path, crate::io::MAX_TEXT_BYTES)?;
        ModelFile::parse(&text, &path.display().to_string())
    }

    /// The two-mass parameters.
    pub fn params(&self) -> TwoMassParams {
        self.identified.params()
    }

    /// The sampling time a design uses: `ts_s`, else the record's, else 100 us.
    pub fn design_ts_s(&self, ts_s: Option<f64>) -> f64 {
        ts_s.or(self.identified.ts_s).unwrap_or(DEFAULT_TS_S)
    }

    /// The design input at sampling time `ts_s` (see [`Self::design_ts_s`]; not validated).
    pub fn design_input(&self, ts_s: Option<f64>) -> Result<DesignInput> {
        let friction = match &self.friction {
            Some(f) => {
                let p = f.params();
                p.validate()?;
                Some(p)
            }
            None => None,
        };
        Ok(DesignInput {
            model: self.params(),
            dead_time_s: self.identified.dead_time_s,
            t_r_s: self.identified.t_r_s,
            ts_s: self.design_ts_s(ts_s),
            friction,
        })
    }

    /// The design for this model at sampling time `ts_s` with `rule`
    /// ([`crate::design::robust::design_identified`]): the measured viscous
    /// friction and the fit's uncertainties come from the file, so a
    /// `commissioning.json` gives the commissioning's own controller.
    pub fn design(
        &self,
        ts_s: Option<f64>,
        knobs: &crate::design::DesignKnobs,
        rule: crate::design::robust::DesignRule,
    ) -> Result<crate::design::robust::RobustDesign> {
        let input = self.design_input(ts_s)?;
        crate::design::robust::design_identified(
            &input,
            input.friction.map(|f| f.viscous_nm_s_per_rad),
            self.identified.m_c_sigma,
            self.identified.c_sigma,
            self.identified.stroke_variation.as_ref(),
            knobs,
            rule,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOML: &str = "theta_e = 71.73e-6\nm_c = 13.44\nc = 203.74e3\nd_m = 33.17\nd_c = 226.42\ni_t = 0.0124141\ndead_time_s = 1e-3\nviscous = 2.53e-3\ncoulomb = 0.125\n";

    /// A model file's stroke variation is read back and used by the design;
    /// an absurd ratio is refused naming its key (never a 1e308 model).
    #[test]
    fn a_stroke_variation_is_read_checked_and_designed_with() {
        let ends = |c: &str| {
            format!(
                "[stroke_variation]\nreference_position_m = 0.5\n\
                 [[stroke_variation.ends]]\nposition_m = 0.0\nm_c_ratio = 0.9\nc_ratio = {c}\nd_ratio = 1.0\n\
                 [[stroke_variation.ends]]\nposition_m = 0.6\nm_c_ratio = 1.0\nc_ratio = 0.95\nd_ratio = 1.0\n"
            )
        };
        let m = ModelFile::parse(&format!("{TOML}{}", ends("2.0")), "a.toml").unwrap();
        let v = m.identified.stroke_variation.unwrap();
        assert_eq!(v.ends[0].c_ratio, 2.0);
        let with = m
            .design(Some(1e-4), &Default::default(), Default::default())
            .unwrap();
        let without = ModelFile::parse(TOML, "a.toml")
            .unwrap()
            .design(Some(1e-4), &Default::default(), Default::default())
            .unwrap();
        // four more models checked: each end, as identified and halved
        assert_eq!(with.guaranteed.models, without.guaranteed.models + 4);
        let err = ModelFile::parse(&format!("{TOML}{}", ends("1e308")), "a.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("c_ratio"), "{err}");
    }

    #[test]
    fn toml_and_old_identify_json_with_extras() {
        let m = ModelFile::parse(TOML, "a.toml").unwrap();
        assert_eq!(m.schema_version, 0);
        assert_eq!(m.identified.t_r_s, crate::design::DEFAULT_T_R_S);
        assert_eq!(m.identified.d, 0.0);
        let inp = m.design_input(Some(1e-4)).unwrap();
        assert_eq!(inp.friction.unwrap().coulomb_nm, 0.125);
        // (2.44) recomputed from the parameters, not taken from the file
        assert!((m.identified.f_r_hz - m.params().f_r_hz()).abs() < 1e-12);
        let json = r#"{"theta_e": 71.73e-6, "m_c": 13.44, "c": 203740.0, "d_m": 33.17, "d_c": 226.42,
            "i_t": 0.0124141, "dead_time_s": 0.001, "f_r_hz": 107.1, "fit": {"cost": 0.1}, "frf": [1, 2],
            "sample_time_s": 2e-4}"#;
        let j = ModelFile::parse(json, "m.json").unwrap();
        assert_eq!(j.identified.m_c, 13.44);
        assert_eq!(j.design_ts_s(None), 2e-4);
        assert!(j.design_input(None).unwrap().friction.is_none());
    }

    #[test]
    fn unmeasured_dead_time_is_assumed_and_marked() {
        let t = TOML.replace("dead_time_s = 1e-3\n", "");
        let m = ModelFile::parse(&t, "a.toml").unwrap();
        assert_eq!(m.identified.dead_time_s, DEFAULT_DEAD_TIME_S);
        assert!(!m.identified.dead_time_measured);
        let j = r#"{"theta_e": 7e-5, "m_c": 13.4, "c": 2e5, "d_m": 33, "d_c": 226, "i_t": 0.0124, "dead_time_s": null}"#;
        let m = ModelFile::parse(j, "m.json").unwrap();
        assert!(!m.identified.dead_time_measured);
    }

    #[test]
    fn document_round_trip_json_and_toml() {
        let flat = ModelFile::parse(TOML, "a.toml").unwrap();
        let mut id = flat.identified.clone();
        id.ts_s = Some(1e-4);
        id.torque_max_nm = Some(3.1);
        id.units = ModelUnits::Current;
        let doc = ModelFile::new(id, flat.friction.clone(), Provenance::now(vec![], Some(3)));
        let json = serde_json::to_string_pretty(&doc).unwrap();
        let back = ModelFile::parse(&json, "m.json").unwrap();
        // NaN fields (unknown) come back as NaN: compare the rest
        assert_eq!(back.identified.units, ModelUnits::Current);
        assert_eq!(back.identified.torque_max_nm, Some(3.1));
        assert_eq!(back.friction, doc.friction);
        assert_eq!(back.provenance, doc.provenance);
        assert_eq!(back.schema_version, SCHEMA_VERSION);
        assert_eq!(back.params(), doc.params());
        let toml_text = toml::to_string(&doc).unwrap();
        let back = ModelFile::parse(&toml_text, "m.toml").unwrap();
        assert_eq!(back.params(), doc.params());
        assert_eq!(back.identified.ts_s, Some(1e-4));
    }

    /// A commissioning.json from before schema 1 (old friction keys, NaN
    /// uncertainties written as null) is read; a recorded one without friction too.
    #[test]
    fn commissioning_json_before_schema_1_is_read() {
        let old = r#"{"plant": "egc70", "identified": {"f_r_hz": 110.8, "f_z_hz": 21.1,
            "theta_e": 7.173e-5, "m_c": 12.38, "c": 217452.6, "d_m": 40.7, "d_c": 185.7,
            "i_t": 0.012414, "dead_time_s": 0.001, "fit_rms_db": 1.37, "m_c_sigma": null,
            "c_sigma": null, "mean_coherence": 0.99, "lines_used": 300, "position_m": null},
            "friction": {"viscous": 0.00406, "coulomb": 0.1097, "linear_viscous": 0.00847,
            "relative_residual": 0.02, "holding_torque_nm": 0.0001},
            "controller": {"k_p": 0.1139}, "validation": null, "log": []}"#;
        let m = ModelFile::parse(old, "commissioning.json").unwrap();
        assert_eq!(m.schema_version, 0);
        let f = m.friction.as_ref().unwrap();
        assert_eq!(f.linear_viscous_nm_s_per_rad, 0.00847);
        assert_eq!(f.coulomb_nm, 0.1097);
        assert!(m.identified.m_c_sigma.is_nan() && m.identified.position_m.is_nan());
        assert!(m.identified.dead_time_measured);
        let inp = m.design_input(None).unwrap();
        assert_eq!(inp.ts_s, DEFAULT_TS_S);
        assert_eq!(inp.friction.unwrap().viscous_nm_s_per_rad, 0.00406);
        // linear_viscous absent: the viscous coefficient
        let short = old.replace(r#", "linear_viscous": 0.00847"#, "");
        let m = ModelFile::parse(&short, "c.json").unwrap();
        assert_eq!(m.friction.unwrap().linear_viscous_nm_s_per_rad, 0.00406);
    }

    /// A TOML model with a key beltune does not read is an error naming the
    /// key; JSON records with more sections (`commissioning.json`) still load.
    #[test]
    fn unknown_keys_in_a_toml_model_are_errors() {
        for (text, key) in [
            (TOML.to_string() + "colomb_nm = 0.1\n", "colomb_nm"),
            (
                TOML.replace("m_c = 13.44", "m_cart = 13.44\nm_c = 13.44"),
                "m_cart",
            ),
        ] {
            let e = ModelFile::parse(&text, "x.toml").unwrap_err().to_string();
            assert!(e.contains(&format!("`{key}`")), "{e}");
        }
        let flat = ModelFile::parse(TOML, "a.toml").unwrap();
        let doc = ModelFile::new(
            flat.identified,
            flat.friction,
            Provenance::now(vec![], None),
        );
        let good = toml::to_string(&doc).unwrap();
        ModelFile::parse(&good, "d.toml").unwrap();
        let bad = good.replace("[identified]\n", "[identified]\nstiffness = 1.0\n");
        let e = ModelFile::parse(&bad, "d.toml").unwrap_err().to_string();
        assert!(e.contains("`identified.stiffness`"), "{e}");
        let bad = good.replace("[friction]\n", "[friction]\nstiction_nm = 1.0\n");
        let e = ModelFile::parse(&bad, "d.toml").unwrap_err().to_string();
        assert!(e.contains("`friction.stiction_nm`"), "{e}");
        let bad = format!("comment = \"x\"\n{good}");
        assert!(ModelFile::parse(&bad, "d.toml")
            .unwrap_err()
            .to_string()
            .contains("`comment`"));
        // in current units the current spelling of a torque key is known
        let cur = TOML.to_string() + "units = \"current\"\ntorque_max_a = 15.0\n";
        assert_eq!(
            ModelFile::parse(&cur, "c.toml")
                .unwrap()
                .identified
                .torque_max_nm,
            Some(15.0)
        );
    }

    #[test]
    fn bad_files_are_errors() {
        assert!(ModelFile::parse("theta_e = 1", "x.toml").is_err());
        let neg = TOML.replace("m_c = 13.44", "m_c = -1");
        let e = ModelFile::parse(&neg, "x.toml").unwrap_err();
        assert!(e.to_string().contains("m_c"), "{e}");
        assert!(ModelFile::parse("{", "x.json").is_err());
        assert!(ModelFile::load(Path::new("/nonexistent/model.toml")).is_err());
        let newer = r#"{"schema_version": 99, "identified": {"theta_e": 7e-5, "m_c": 13.4, "c": 2e5, "d_m": 33, "d_c": 226, "i_t": 0.0124}}"#;
        let e = ModelFile::parse(newer, "n.json").unwrap_err();
        assert!(e.to_string().contains("newer"), "{e}");
        let lim = TOML.to_string() + "torque_max_nm = -3\n";
        let e = ModelFile::parse(&lim, "x.toml").unwrap_err().to_string();
        assert!(e.starts_with("x.toml: `torque_max_nm` = -3"), "{e}");
        // the file's own spelling of the key in current units
        let lim = TOML.to_string() + "units = \"current\"\ntorque_max_a = -3\n";
        let e = ModelFile::parse(&lim, "x.toml").unwrap_err().to_string();
        assert!(
            e.contains("`torque_max_a` = -3") && !e.contains("_nm"),
            "{e}"
        );
    }
}
