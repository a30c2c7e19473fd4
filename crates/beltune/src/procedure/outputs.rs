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
    pub torque_max_nm: f64,
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
    torque_max_nm: f64,
) -> Result<String> {
    let cfg = cascade_from_design(des, torque_max_nm, friction.holding_torque_nm)?;
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
        torque_max_nm,
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
            viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
            coulomb_nm: friction.coulomb_nm,
            linear_viscous_nm_s_per_rad: friction.linear_viscous_nm_s_per_rad,
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

/// The files of one commissioning result, in the order they are listed.
pub const OUTPUT_FILES: [&str; 3] = ["commissioning.json", "controller.toml", "report.html"];

/// Name of the symlink to the newest run in a history folder.
pub const LATEST_LINK: &str = "latest";

/// Where a commissioning run writes its result.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputTarget {
    /// A new timestamped folder `root/YYYY-MM-DDTHHMMSSZ` per run, with the
    /// symlink `root/latest` pointing at the newest.
    History {
        /// The history folder (`commissioning` by default).
        root: PathBuf,
    },
    /// Exactly this folder: new or empty; one holding a result (a
    /// `commissioning.json`) only with `force`, and then the whole set is
    /// replaced. A folder with other files is never replaced.
    Exact {
        /// The folder.
        dir: PathBuf,
        /// Replace an existing result.
        force: bool,
    },
}

/// Write the three files into `dir` as one set: [`crate::io::write_folder_atomic`]
/// replaces the folder as a whole (new, empty or an existing result), so
/// the files change together or not at all. Returns their paths.
pub fn write_outputs(
    dir: &Path,
    json: &CommissioningJson,
    controller_toml: &str,
    report_html: &str,
) -> Result<Vec<PathBuf>> {
    write_texts(dir, &json_text(json)?, controller_toml, report_html, &[])
}

/// Write the result to `target` (see [`OutputTarget`]); returns the paths.
pub fn write_outputs_to(
    target: &OutputTarget,
    json: &CommissioningJson,
    controller_toml: &str,
    report_html: &str,
) -> Result<Vec<PathBuf>> {
    write_texts_to(target, &json_text(json)?, controller_toml, report_html, &[])
}

/// [`write_outputs_to`] with the report's data files (`frf.csv`, ... as
/// (name, text)) in the same set: all files appear together or not at all.
pub fn write_outputs_with_data(
    target: &OutputTarget,
    json: &CommissioningJson,
    controller_toml: &str,
    report_html: &str,
    data_files: &[(String, String)],
) -> Result<Vec<PathBuf>> {
    write_texts_to(
        target,
        &json_text(json)?,
        controller_toml,
        report_html,
        data_files,
    )
}

fn json_text(json: &CommissioningJson) -> Result<String> {
    serde_json::to_string_pretty(json).map_err(|e| Error::Report {
        reason: format!("commissioning.json: {e}"),
    })
}

fn write_texts(
    dir: &Path,
    json_text: &str,
    controller_toml: &str,
    report_html: &str,
    data_files: &[(String, String)],
) -> Result<Vec<PathBuf>> {
    check_finite_text("controller.toml", controller_toml)?;
    crate::io::clean_stale_temporaries(&output_parent(dir));
    let mut files: Vec<(&str, &[u8])> = vec![
        (OUTPUT_FILES[0], json_text.as_bytes()),
        (OUTPUT_FILES[1], controller_toml.as_bytes()),
        (OUTPUT_FILES[2], report_html.as_bytes()),
    ];
    files.extend(data_files.iter().map(|(n, t)| (n.as_str(), t.as_bytes())));
    crate::io::write_folder_atomic(dir, &files)
}

fn write_texts_to(
    target: &OutputTarget,
    json_text: &str,
    controller_toml: &str,
    report_html: &str,
    data_files: &[(String, String)],
) -> Result<Vec<PathBuf>> {
    match target {
        OutputTarget::Exact { dir, force } => {
            check_exact_target(dir, *force)?;
            write_texts(dir, json_text, controller_toml, report_html, data_files)
        }
        OutputTarget::History { root } => {
            std::fs::create_dir_all(root).map_err(|source| Error::Io {
                path: root.clone(),
                source,
            })?;
            crate::io::clean_stale_temporaries(root);
            let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
                .to_string()
                .replace(':', "");
            let mut name = stamp.clone();
            let mut k = 1;
            while std::fs::symlink_metadata(root.join(&name)).is_ok() {
                k += 1;
                name = format!("{stamp}-{k}");
            }
            let files = write_texts(
                &root.join(&name),
                json_text,
                controller_toml,
                report_html,
                data_files,
            )?;
            point_latest(root, &name)?;
            Ok(files)
        }
    }
}

/// The folder beside which the temporary of `dir` lives.
fn output_parent(dir: &Path) -> PathBuf {
    match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// `--out DIR` without `--force` must be new or empty; with it, a folder that
/// holds a result. A folder with other contents is refused either way.
fn check_exact_target(dir: &Path, force: bool) -> Result<()> {
    let err = |message: String| Error::Parse {
        path: dir.display().to_string(),
        message,
    };
    let entries: Vec<String> = match std::fs::read_dir(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => {
            return Err(err(format!(
                "cannot use as output folder: {}",
                crate::io::describe(&e)
            )))
        }
        Ok(d) => d
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect(),
    };
    if entries.is_empty() {
        return Ok(());
    }
    if !entries.iter().any(|e| e == OUTPUT_FILES[0]) {
        return Err(err(
            "the output folder is not empty and holds no commissioning result; \
             choose a new or empty folder"
                .into(),
        ));
    }
    if !force {
        return Err(err(
            "the output folder already holds a commissioning result; pass --force to \
             replace it, or leave out --out to keep every run under commissioning/"
                .into(),
        ));
    }
    Ok(())
}

/// Point `root/latest` at `name`: a new symlink renamed over the old one.
fn point_latest(root: &Path, name: &str) -> Result<()> {
    let link = root.join(LATEST_LINK);
    if std::fs::symlink_metadata(&link).is_ok_and(|m| !m.file_type().is_symlink()) {
        return Err(Error::Parse {
            path: link.display().to_string(),
            message: "is not a symlink; remove it so that it can point at the newest run".into(),
        });
    }
    let tmp = root.join(crate::io::temporary_name(LATEST_LINK));
    let io = |source| Error::Io {
        path: link.clone(),
        source,
    };
    std::os::unix::fs::symlink(name, &tmp).map_err(io)?;
    std::fs::rename(&tmp, &link).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e)
    })?;
    crate::io::sync_dir(root);
    Ok(())
}

/// Nothing non-finite reaches a file: `inf`/`nan` in a TOML text is an error.
fn check_finite_text(name: &str, text: &str) -> Result<()> {
    let bad = text.lines().find(|l| {
        let v = l.split_once('=').map_or("", |(_, v)| v);
        v.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.'))
            .any(|w| matches!(w, "inf" | "nan" | "NaN"))
    });
    match bad {
        Some(line) => Err(Error::Report {
            reason: format!(
                "{name}: refusing to write a non-finite value: `{}`",
                line.trim()
            ),
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod output_tests {
    use super::*;

    const JSON: &str = "{}";

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("beltune-out-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn history_keeps_every_run_and_latest_points_at_the_newest_issue_16_4() {
        let root = temp("history").join("commissioning");
        let target = OutputTarget::History { root: root.clone() };
        let a = write_texts_to(&target, JSON, "a = 1\n", "<p>1</p>", &[]).unwrap();
        let b = write_texts_to(&target, JSON, "a = 2\n", "<p>2</p>", &[]).unwrap();
        assert_ne!(a[0].parent(), b[0].parent());
        assert_eq!(std::fs::read_to_string(&a[1]).unwrap(), "a = 1\n");
        let latest = root.join(LATEST_LINK);
        assert_eq!(
            std::fs::read_to_string(latest.join("controller.toml")).unwrap(),
            "a = 2\n"
        );
        // Two runs and the link, no temporaries.
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 3);
        std::fs::remove_dir_all(root.parent().unwrap()).unwrap();
    }

    #[test]
    fn exact_output_needs_force_over_a_result_and_refuses_foreign_folders_issue_16_4() {
        let dir = temp("exact");
        let out = dir.join("out");
        let exact = |force| OutputTarget::Exact {
            dir: out.clone(),
            force,
        };
        write_texts_to(&exact(false), JSON, "a = 1\n", "", &[]).unwrap();
        let e = write_texts_to(&exact(false), JSON, "a = 2\n", "", &[]).unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        write_texts_to(&exact(true), JSON, "a = 2\n", "", &[]).unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("controller.toml")).unwrap(),
            "a = 2\n"
        );
        let foreign = dir.join("foreign");
        std::fs::create_dir_all(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
        let target = OutputTarget::Exact {
            dir: foreign.clone(),
            force: true,
        };
        let e = write_texts_to(&target, JSON, "a = 1\n", "", &[]).unwrap_err();
        assert!(e.to_string().contains("not empty"), "{e}");
        assert!(foreign.join("notes.txt").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_non_finite_controller_is_never_written_issue_13_2() {
        let dir = temp("finite");
        let out = dir.join("out");
        for bad in [
            "k_p = inf\n",
            "k_p = -inf\n",
            "k_p = nan\n",
            "sos = [1.0, nan]\n",
        ] {
            let e = write_texts(&out, JSON, bad, "", &[]).unwrap_err();
            assert!(e.to_string().contains("non-finite"), "{bad}: {e}");
        }
        assert!(!out.exists());
        write_texts(&out, JSON, "kind = \"notch\"\nk = 1e300\n", "", &[]).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
