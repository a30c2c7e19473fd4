//! The three output files of a commissioning run: `commissioning.json` (all
//! numbers), `controller.toml` (what a drive needs) and `report.html` (what a
//! person reads). Building them is pure computation; writing is
//! [`write_outputs`], which writes each file atomically and only after all
//! three were built, so a failed run leaves nothing half-written.

use super::controller::ControllerFile;
use super::SCHEMA_VERSION;
use crate::commission::recorded::RecordedCommissioning;
use crate::commission::result::{
    FrictionResult, IdentifiedModel, TargetStiffness, Truth, Validation,
};
use crate::commission::Commissioning;
use crate::design::{ControllerDesign, DesignSummary, DriveForm};
use crate::ident::ModelUnits;
use crate::record::provenance::Provenance;
use crate::report::{ParameterRow, Report};
use crate::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `commissioning.json` (schema [`SCHEMA_VERSION`], docs/schema.md): an
/// identified-model record ([`super::model::ModelFile`]) with the controller,
/// the validation and the log.
#[derive(Clone, Debug, Serialize)]
pub struct CommissioningJson {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Who wrote it: beltune version, date, command line, seed.
    pub provenance: Provenance,
    /// Name of the axis (built-in plant name or file).
    pub plant: String,
    /// The identified model (with sampling time, torque limit and units).
    pub identified: IdentifiedModel,
    /// Friction (`null` when it could not be measured).
    pub friction: Option<FrictionResult>,
    /// Controller: gains, prefilter, achieved margins.
    pub controller: DesignSummary,
    /// The controller in drive-menu form (`T_n`, `K_v`, filter frequency and damping).
    pub drive_form: DriveForm,
    /// The three validation moves (`null` for recorded data: no axis to move).
    pub validation: Option<Validation>,
    /// How long the axis was busy, s.
    pub experiment_time_s: f64,
    /// Computation time (FFT, fit, design), s.
    pub computation_time_s: f64,
    /// PRBS amplitude used, N m (`null` for recorded data).
    pub excitation_amplitude_nm: Option<f64>,
    /// Where the model was measured: the mean motor-side position over the
    /// compared periods of the excitation, m (`null` for recorded data).
    pub identification_position_m: Option<f64>,
    /// The belt stiffness where the validation move ends, which the static
    /// belt stretch of `controller.toml` uses (`null` for recorded data).
    pub target_stiffness: Option<TargetStiffness>,
    /// The thesis' fit of the FRF's magnitude (3.5), beside the model in
    /// `identified` when that is the friction-aware fit (absent for
    /// recorded data, where `identified` is the FRF fit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frf_fit: Option<crate::model::TwoMassParams>,
    /// The friction-aware fit of the nonlinear model (2.30) (issue 12):
    /// parameters, Coulomb friction of motor and cart, residuals; absent
    /// where it failed or for recorded data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_aware: Option<crate::ident::NonlinearFit>,
    /// For a simulated plant: the true values at the identification position.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Truth>,
    /// What the commissioning ran on: a simulated plant (its parameters, so
    /// that the tuning page simulates on the same plant as the report), a
    /// recorded file or a real drive (no simulator truth).
    pub axis: AxisRecord,
    /// The stage log.
    pub log: Vec<String>,
}

/// What a commissioning ran on (`commissioning.json` key `axis`, docs/schema.md).
/// Absent in files written before it was added: readers then know only the
/// identified model.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AxisRecord {
    /// A simulated axis.
    Simulated {
        /// The plant's name (built-in) or file, as given.
        name: String,
        /// Payload on the cart, kg (`null`: a linear set, which has none).
        payload_kg: Option<f64>,
        /// Cart position at the start, m.
        start_position_m: f64,
        /// Noise seed of the simulation.
        seed: u64,
        /// Every parameter of the simulated plant (payload and tilt included).
        plant: Box<crate::model::rigs::Plant>,
    },
    /// Recorded data (CSV): no simulator truth.
    Recorded {
        /// The record's file.
        source: String,
    },
    /// A real drive (EtherCAT): no simulator truth.
    Ethercat {
        /// The interface and SubDevice.
        source: String,
    },
}

impl AxisRecord {
    /// The record of a simulated `plant` named `name`.
    pub fn simulated(
        name: &str,
        plant: &crate::model::rigs::Plant,
        start_position_m: f64,
        seed: u64,
    ) -> Self {
        let payload_kg = match plant {
            crate::model::rigs::Plant::Physical(p) => Some(p.payload_kg),
            crate::model::rigs::Plant::Linear(_) => None,
        };
        AxisRecord::Simulated {
            name: name.to_string(),
            payload_kg,
            start_position_m,
            seed,
            plant: Box::new(plant.clone()),
        }
    }
}

impl CommissioningJson {
    /// The JSON text; in current units the unit suffixes of the keys are the
    /// current spelling ([`crate::units::relabel_keys`]).
    pub fn to_json_text(&self) -> Result<String> {
        let err = |e: serde_json::Error| Error::Report {
            reason: format!("commissioning.json: {e}"),
        };
        let mut v = serde_json::to_value(self).map_err(err)?;
        if self.identified.units == ModelUnits::Current {
            crate::units::relabel_keys(&mut v, &crate::units::current_key);
        }
        let mut text = serde_json::to_string_pretty(&v).map_err(err)?;
        text.push('\n');
        Ok(text)
    }
}

/// `controller.toml` for a design, friction (with the holding torque), the
/// belt stiffness at the validation target (the static stretch) and torque
/// limit, in `units`: [`ControllerFile::from_design`] as text.
pub fn controller_toml(
    des: &ControllerDesign,
    friction: &FrictionResult,
    target_stiffness: Option<&TargetStiffness>,
    torque_max_nm: f64,
    units: ModelUnits,
    provenance: Provenance,
) -> Result<String> {
    ControllerFile::from_design(
        des,
        friction,
        target_stiffness,
        torque_max_nm,
        units,
        provenance,
    )?
    .to_toml()
}

/// `commissioning.json` for a run.
pub fn commissioning_json(
    run: &Commissioning,
    plant: &str,
    truth: Option<Truth>,
    axis: AxisRecord,
    provenance: Provenance,
) -> CommissioningJson {
    let mut identified = run.identified.clone();
    identified.ts_s = Some(run.design.input.ts_s);
    identified.torque_max_nm = Some(run.datasheet.torque_max_nm);
    identified.t_r_s = run.design.input.t_r_s;
    CommissioningJson {
        schema_version: SCHEMA_VERSION,
        provenance,
        plant: plant.to_string(),
        identified,
        frf_fit: Some(run.frf_fit.params),
        friction_aware: run.nonlinear.clone(),
        friction: Some(run.friction.clone()),
        controller: run.design.summary(),
        drive_form: DriveForm::of(&run.design),
        validation: Some(run.validation.clone()),
        experiment_time_s: run.experiment_time_s,
        computation_time_s: run.computation_time_s,
        excitation_amplitude_nm: Some(run.excitation_amplitude_nm),
        identification_position_m: Some(run.identification_position_m),
        target_stiffness: Some(run.target_stiffness),
        truth,
        axis,
        log: run.log.clone(),
    }
}

pub use crate::report::build::{build_report, data_files, recorded_data_files};

fn sig(x: f64, sig: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..5).contains(&e) {
        let d = (sig as i32 - 1 - e).max(0) as usize;
        format!("{x:.d$}")
    } else {
        format!("{x:.*e}", sig - 1)
    }
}

/// Model, friction and controller rows of a recorded commissioning, in the
/// record's units (no scaled SI units: a current record has no kg).
fn recorded_rows(run: &RecordedCommissioning) -> Vec<ParameterRow> {
    let id = &run.identified;
    let des = &run.design;
    let l = crate::units::labels(id.units);
    let r = |name: &str, unit: &str, v: f64| ParameterRow {
        name: name.into(),
        unit: unit.into(),
        before: None,
        after: sig(v, 5),
        truth: None,
        value: Some(v),
    };
    let form = DriveForm::of(des);
    let mut rows = vec![
        r("resonance f_r", "Hz", id.f_r_hz),
        r("antiresonance f_z", "Hz", id.f_z_hz),
        r("motor inertia Theta_e", l.inertia, id.theta_e),
        r("moving mass m_c", l.mass, id.m_c),
        r("belt stiffness c", l.stiffness, id.c),
        r("motor damping d_m", l.damping, id.d_m),
        r("cart damping d_c", l.damping, id.d_c),
        r("transmission i_t", "m/rad", id.i_t),
        r(
            if id.dead_time_measured {
                "dead time t_T"
            } else {
                "dead time t_T (assumed, not measured)"
            },
            "ms",
            id.dead_time_s * 1e3,
        ),
    ];
    if let Some(f) = &run.friction {
        rows.extend([
            r(
                "viscous friction d_v",
                l.torque_per_velocity,
                f.viscous_nm_s_per_rad,
            ),
            r("Coulomb friction tau_c", l.torque, f.coulomb_nm),
            r("constant offset", l.torque, f.holding_torque_nm),
        ]);
    }
    if let Some(t) = id.torque_max_nm {
        rows.push(r("torque limit", l.torque, t));
    }
    rows.extend([
        r("K_P", l.torque_per_velocity, des.k_p),
        r("K_I", l.torque_per_angle, des.k_i),
        r("K_PP", "1/s", des.k_pp),
    ]);
    if let Some(tn) = form.integral_time_ms {
        rows.push(r("integral time T_n = K_P/K_I", "ms", tn));
    }
    rows.extend([
        r(
            "velocity phase margin",
            "deg",
            des.velocity_margins.phase_margin_deg,
        ),
        r(
            "position phase margin",
            "deg",
            des.position_margins.phase_margin_deg,
        ),
        r("gain at resonance", "dB", des.gain_at_resonance_db),
    ]);
    rows
}

/// `commissioning.json` and the report for a commissioning from recorded data
/// (`source` names the record, `torque_max_nm` is the drive's torque limit in
/// the record's unit). The JSON's `experiment_time_s` is the record's duration.
pub fn recorded_outputs(
    run: &RecordedCommissioning,
    source: &str,
    torque_max_nm: f64,
    provenance: Provenance,
) -> Result<(CommissioningJson, Report)> {
    let mut identified = run.identified.clone();
    identified.torque_max_nm = Some(torque_max_nm);
    let json = CommissioningJson {
        schema_version: SCHEMA_VERSION,
        provenance,
        plant: source.to_string(),
        identified,
        frf_fit: None,
        friction_aware: None,
        friction: run.friction.clone(),
        controller: run.design.summary(),
        drive_form: DriveForm::of(&run.design),
        validation: None,
        experiment_time_s: run.record_time_s,
        computation_time_s: run.computation_time_s,
        excitation_amplitude_nm: None,
        identification_position_m: None,
        target_stiffness: None,
        truth: None,
        axis: AxisRecord::Recorded {
            source: source.to_string(),
        },
        log: run.log.clone(),
    };
    let mut run_with_limit = run.clone();
    run_with_limit.identified.torque_max_nm = Some(torque_max_nm);
    let id = &run.identified;
    let l = crate::units::labels(id.units);
    let mut report = crate::report::build::recorded_report(run, source, Some(&json.provenance))?;
    report.parameters = recorded_rows(&run_with_limit);
    report.summary = format!(
        "From recorded data ({source}, {:.1} s): resonance {:.2} Hz, antiresonance {:.2} Hz, fit {:.2} dB rms. \
         Controller: K_P {} {}, K_I {} {}, K_PP {:.3} 1/s. No validation move: the stages that need the axis were skipped.",
        run.record_time_s,
        id.f_r_hz,
        id.f_z_hz,
        id.fit_rms_db,
        sig(run.design.k_p, 5),
        l.torque_per_velocity,
        sig(run.design.k_i, 5),
        l.torque_per_angle,
        run.design.k_pp
    );
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
    json.to_json_text()
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
