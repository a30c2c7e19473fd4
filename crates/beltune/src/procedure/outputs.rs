//! The three output files of a commissioning run: `commissioning.json` (all
//! numbers), `controller.toml` (what a drive needs) and `report.html` (what a
//! person reads). Building them is pure computation; writing is
//! [`write_outputs`], which writes each file atomically and only after all
//! three were built, so a failed run leaves nothing half-written.

use super::commission::{cascade_from_design, Commissioning};
use super::recorded::RecordedCommissioning;
use super::result::{FrictionResult, IdentifiedModel, Truth, Validation};
use crate::design::{ControllerDesign, DesignSummary, Prefilter};
use crate::report::Report;
use crate::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `commissioning.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CommissioningJson {
    /// Name of the axis (built-in plant name or file).
    pub plant: String,
    /// The identified model.
    pub identified: IdentifiedModel,
    /// Friction (`null` when it could not be measured).
    pub friction: Option<FrictionResult>,
    /// Controller: gains, prefilter, achieved margins.
    pub controller: DesignSummary,
    /// The three validation moves (`null` for recorded data: no axis to move).
    pub validation: Option<Validation>,
    /// How long the axis was busy, s.
    pub experiment_time_s: f64,
    /// Computation time (FFT, fit, design), s.
    pub computation_time_s: f64,
    /// PRBS amplitude used, N m (`null` for recorded data).
    pub excitation_amplitude_nm: Option<f64>,
    /// Where the FRF was measured, m (`null` for recorded data).
    pub identification_position_m: Option<f64>,
    /// For a simulated plant: the true values at the identification position.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Truth>,
    /// The stage log.
    pub log: Vec<String>,
}

/// Sections of `controller.toml`.
#[derive(Clone, Debug, Serialize)]
pub struct ControllerToml {
    /// Sampling time `T_s`, s.
    pub ts_s: f64,
    /// Torque limit, N m.
    pub torque_limit_nm: f64,
    /// Constant torque offset (holding torque), N m.
    pub torque_offset_nm: f64,
    /// Continuous gains.
    pub gains: GainsToml,
    /// Prefilter in the velocity loop.
    pub prefilter: PrefilterToml,
    /// Velocity filter `G_R = s/(T_R s + 1)` (6.1), Tustin.
    pub velocity_filter: FirstOrderToml,
    /// Feedforward (4.16) and its refinements.
    pub feedforward: FeedforwardToml,
}

/// Continuous cascade gains.
#[derive(Clone, Debug, Serialize)]
pub struct GainsToml {
    /// `K_PP`, 1/s.
    pub k_pp_per_s: f64,
    /// `K_P`, N m s/rad.
    pub k_p_nm_s_per_rad: f64,
    /// `K_I`, N m/rad.
    pub k_i_nm_per_rad: f64,
    /// `K_v` (4.17).
    pub k_v: f64,
}

/// Prefilter parameters and its discrete section.
#[derive(Clone, Debug, Serialize)]
pub struct PrefilterToml {
    /// "butterworth", "notch" or "none".
    pub kind: String,
    /// Butterworth cut-off, rad/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega_bw_rad_s: Option<f64>,
    /// Notch centre, rad/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega_r_rad_s: Option<f64>,
    /// Notch width `d_n`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub d_n: Option<f64>,
    /// `H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`: `[b0, b1, b2, a1, a2]`.
    pub sos: [f64; 5],
}

/// A first-order section `[b0, b1, a1]` with its time constant.
#[derive(Clone, Debug, Serialize)]
pub struct FirstOrderToml {
    /// `T_R`, s.
    pub t_r_s: f64,
    /// `H(z) = (b0 + b1 z^-1) / (1 + a1 z^-1)`: `[b0, b1, a1]`.
    pub coeffs: [f64; 3],
}

/// Feedforward parameters.
#[derive(Clone, Debug, Serialize)]
pub struct FeedforwardToml {
    /// `m_e~` (4.15), kg m^2.
    pub inertia_kg_m2: f64,
    /// `d_v~` for nonlinear feedforward, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// `tau_c~`, N m.
    pub coulomb_nm: f64,
    /// Viscous-only coefficient for linear feedforward, N m s/rad.
    pub linear_viscous_nm_s_per_rad: f64,
    /// Feedforward preview (current-loop dead time), samples.
    pub preview_samples: usize,
    /// Belt-stretch compensation `m_c / c`, s^2.
    pub belt_stretch_s2: f64,
    /// Static belt stretch under the holding force, `tau_hold / (i_t c)`, m:
    /// the motor setpoint leads the cart by this much.
    pub static_stretch_m: f64,
    /// Desired velocity through `G_R` before the velocity loop.
    pub filter_desired_velocity: bool,
}

/// `controller.toml` for a design, friction and holding torque.
pub fn controller_toml(
    des: &ControllerDesign,
    friction: &FrictionResult,
    torque_limit_nm: f64,
) -> Result<String> {
    let cfg = cascade_from_design(des, torque_limit_nm, friction.holding_torque_nm)?;
    let s = des.discrete.prefilter;
    let v = cfg.velocity_filter;
    let (kind, omega_bw, omega_r, d_n) = match des.prefilter {
        Prefilter::Butterworth { omega_bw_rad_s } => {
            ("butterworth", Some(omega_bw_rad_s), None, None)
        }
        Prefilter::Notch { omega_r_rad_s, d_n } => ("notch", None, Some(omega_r_rad_s), Some(d_n)),
        Prefilter::None => ("none", None, None, None),
    };
    let model = des.input.model;
    let doc = ControllerToml {
        ts_s: des.input.ts_s,
        torque_limit_nm,
        torque_offset_nm: friction.holding_torque_nm,
        gains: GainsToml {
            k_pp_per_s: des.k_pp,
            k_p_nm_s_per_rad: des.k_p,
            k_i_nm_per_rad: des.k_i,
            k_v: 1.0,
        },
        prefilter: PrefilterToml {
            kind: kind.into(),
            omega_bw_rad_s: omega_bw,
            omega_r_rad_s: omega_r,
            d_n,
            sos: [s.b0, s.b1, s.b2, s.a1, s.a2],
        },
        velocity_filter: FirstOrderToml {
            t_r_s: des.input.t_r_s,
            coeffs: [v.b0, v.b1, v.a1],
        },
        feedforward: FeedforwardToml {
            inertia_kg_m2: model.rigid_inertia(),
            viscous_nm_s_per_rad: friction.viscous,
            coulomb_nm: friction.coulomb,
            linear_viscous_nm_s_per_rad: friction.linear_viscous,
            preview_samples: (des.input.dead_time_s / des.input.ts_s).round() as usize,
            belt_stretch_s2: model.m_c / model.c,
            static_stretch_m: friction.holding_torque_nm / (model.i_t * model.c),
            filter_desired_velocity: true,
        },
    };
    toml::to_string_pretty(&doc).map_err(|e| Error::Report {
        reason: format!("controller.toml: {e}"),
    })
}

/// `commissioning.json` for a run.
pub fn commissioning_json(
    run: &Commissioning,
    plant: &str,
    truth: Option<Truth>,
) -> CommissioningJson {
    CommissioningJson {
        plant: plant.to_string(),
        identified: run.identified.clone(),
        friction: Some(run.friction.clone()),
        controller: run.design.summary(),
        validation: Some(run.validation.clone()),
        experiment_time_s: run.experiment_time_s,
        computation_time_s: run.computation_time_s,
        excitation_amplitude_nm: Some(run.excitation_amplitude_nm),
        identification_position_m: Some(run.identification_position_m),
        truth,
        log: run.log.clone(),
    }
}

pub use super::report_build::{build_report, data_files, recorded_data_files};

/// `commissioning.json` and the report for a commissioning from recorded data
/// (`source` names the record). The JSON's `experiment_time_s` is the record's duration.
pub fn recorded_outputs(
    run: &RecordedCommissioning,
    source: &str,
    provenance: Option<&crate::provenance::Provenance>,
) -> Result<(CommissioningJson, Report)> {
    let json = CommissioningJson {
        plant: source.to_string(),
        identified: run.identified.clone(),
        friction: run.friction.clone(),
        controller: run.design.summary(),
        validation: None,
        experiment_time_s: run.record_time_s,
        computation_time_s: run.computation_time_s,
        excitation_amplitude_nm: None,
        identification_position_m: None,
        truth: None,
        log: run.log.clone(),
    };
    let report = super::report_build::recorded_report(run, source, provenance)?;
    Ok((json, report))
}

/// Write the three files into `dir` (created if needed), each atomically.
/// Returns their paths.
pub fn write_outputs(
    dir: &Path,
    json: &CommissioningJson,
    controller_toml: &str,
    report_html: &str,
) -> Result<Vec<PathBuf>> {
    let json_text = serde_json::to_string_pretty(json).map_err(|e| Error::Report {
        reason: format!("commissioning.json: {e}"),
    })?;
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let files = [
        ("commissioning.json", json_text.as_bytes()),
        ("controller.toml", controller_toml.as_bytes()),
        ("report.html", report_html.as_bytes()),
    ];
    let mut out = Vec::new();
    for (name, bytes) in files {
        let p = dir.join(name);
        crate::io::write_atomic(&p, bytes)?;
        out.push(p);
    }
    Ok(out)
}
