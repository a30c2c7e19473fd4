//! The three output files of a commissioning run: `commissioning.json` (all
//! numbers), `controller.toml` (what a drive needs) and `report.html` (what a
//! person reads). Building them is pure computation; writing is
//! [`write_outputs`], which writes each file atomically and only after all
//! three were built, so a failed run leaves nothing half-written.

use super::commission::Commissioning;
use super::controller_file::ControllerFile;
use super::recorded::RecordedCommissioning;
use super::result::{FrictionResult, IdentifiedModel, Truth, Validation};
use crate::design::{ControllerDesign, DesignSummary, DriveForm, SCHEMA_VERSION};
use crate::ident::{Frf, ModelUnits, TwoMassFit};
use crate::lti::C64;
use crate::provenance::Provenance;
use crate::report::{
    BodeCurve, BodePlot, FrequencyMarker, FrfPlot, FrictionPlot, MovePlot, ParameterRow, Report,
};
use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// `commissioning.json` (schema [`SCHEMA_VERSION`], docs/schema.md): an
/// identified-model record ([`crate::design::ModelFile`]) with the controller,
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
    /// Where the FRF was measured, m (`null` for recorded data).
    pub identification_position_m: Option<f64>,
    /// For a simulated plant: the true values at the identification position.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Truth>,
    /// The stage log.
    pub log: Vec<String>,
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

/// `controller.toml` for a design, friction (with the holding torque) and torque
/// limit, in `units`: [`ControllerFile::from_design`] as text.
pub fn controller_toml(
    des: &ControllerDesign,
    friction: &FrictionResult,
    torque_max_nm: f64,
    units: ModelUnits,
    provenance: Provenance,
) -> Result<String> {
    ControllerFile::from_design(des, friction, torque_max_nm, units, provenance)?.to_toml()
}

/// `commissioning.json` for a run.
pub fn commissioning_json(
    run: &Commissioning,
    plant: &str,
    truth: Option<Truth>,
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
        friction: Some(run.friction.clone()),
        controller: run.design.summary(),
        drive_form: DriveForm::of(&run.design),
        validation: Some(run.validation.clone()),
        experiment_time_s: run.experiment_time_s,
        computation_time_s: run.computation_time_s,
        excitation_amplitude_nm: Some(run.excitation_amplitude_nm),
        identification_position_m: Some(run.identification_position_m),
        truth,
        log: run.log.clone(),
    }
}

fn hz(w_rad_s: f64) -> f64 {
    w_rad_s / (2.0 * PI)
}

/// `p` shifted by whole turns to within 180 deg of the previous point.
fn unwrap_deg(mut p: f64, prev: Option<f64>) -> f64 {
    if let Some(q) = prev {
        p -= 360.0 * ((p - q) / 360.0).round();
    }
    p
}

fn curve(label: &str, freq_hz: &[f64], h: impl Fn(f64) -> C64) -> BodeCurve {
    let mut phase_deg = Vec::with_capacity(freq_hz.len());
    let mut prev: Option<f64> = None;
    let mut magnitude_db = Vec::with_capacity(freq_hz.len());
    for f in freq_hz {
        let v = h(2.0 * PI * f);
        magnitude_db.push(20.0 * v.norm().log10());
        let p = unwrap_deg(v.arg().to_degrees(), prev);
        prev = Some(p);
        phase_deg.push(p);
    }
    BodeCurve {
        label: label.into(),
        freq_hz: freq_hz.to_vec(),
        magnitude_db,
        phase_deg,
    }
}

fn log_grid_hz(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect()
}

fn fmt(x: f64, digits: usize) -> String {
    format!("{x:.digits$}")
}

/// Decimate a trace to at most `n` points for plotting.
fn decimate(x: &[f64], n: usize) -> Vec<f64> {
    let step = x.len().div_ceil(n.max(1)).max(1);
    x.iter().step_by(step).copied().collect()
}

/// The measured FRF (all lines) with coherence and the fitted model with dead time.
pub fn identification_plot(frf: &Frf, fit: &TwoMassFit, dead_time_s: f64) -> FrfPlot {
    let lines: Vec<usize> = (1..frf.freq_hz.len()).collect();
    let mut prev: Option<f64> = None;
    let phase_deg = lines
        .iter()
        .map(|&i| {
            let p = unwrap_deg(frf.response[i].arg().to_degrees(), prev);
            prev = Some(p);
            p
        })
        .collect();
    let measured = BodeCurve {
        label: "measured (torque command -> motor angle)".into(),
        freq_hz: lines.iter().map(|&i| frf.freq_hz[i]).collect(),
        magnitude_db: lines
            .iter()
            .map(|&i| 20.0 * frf.response[i].norm().log10())
            .collect(),
        phase_deg,
    };
    let f_lo = measured.freq_hz.first().copied().unwrap_or(1.0);
    let f_hi = measured.freq_hz.last().copied().unwrap_or(1000.0);
    let grid = log_grid_hz(f_lo, f_hi, 400);
    let tf = fit.model.tf(&fit.params);
    let model = curve("fitted model with dead time", &grid, |w| {
        tf.freq_response(w) * C64::from_polar(1.0, -w * dead_time_s)
    });
    FrfPlot {
        usable: lines.iter().map(|&i| frf.is_usable(i)).collect(),
        coherence: lines.iter().map(|&i| frf.coherence[i]).collect(),
        measured,
        model,
        markers: resonance_markers(fit),
    }
}

fn resonance_markers(fit: &TwoMassFit) -> Vec<FrequencyMarker> {
    vec![
        FrequencyMarker {
            label: format!("f_z {:.1} Hz", fit.f_z_hz),
            freq_hz: fit.f_z_hz,
        },
        FrequencyMarker {
            label: format!("f_r {:.1} Hz", fit.f_r_hz),
            freq_hz: fit.f_r_hz,
        },
    ]
}

/// The controller and the two open loops with crossovers and margins marked.
pub fn design_plots(des: &ControllerDesign, fit: &TwoMassFit) -> (BodePlot, Vec<BodePlot>) {
    let grid = log_grid_hz(0.1, 1000.0, 500);
    let controller = BodePlot {
        title: "Controller G_pre G_PI (velocity error -> torque)".into(),
        curves: vec![curve("G_pre G_PI", &grid, |w| {
            des.prefilter.tf().freq_response(w) * C64::new(des.k_p, -des.k_i / w)
        })],
        markers: resonance_markers(fit),
    };
    let vm = &des.velocity_margins;
    let pm = &des.position_margins;
    let open_loops = vec![
        BodePlot {
            title: format!(
                "Velocity open loop: crossover {:.1} Hz, phase margin {:.1} deg, gain margin {:.1} dB, {:.1} dB at f_r",
                hz(vm.crossover_rad_s),
                vm.phase_margin_deg,
                vm.gain_margin_db,
                des.gain_at_resonance_db
            ),
            curves: vec![curve("L velocity", &grid, |w| des.velocity_open_loop(w))],
            markers: vec![
                FrequencyMarker {
                    label: format!("w_c {:.1} Hz", hz(vm.crossover_rad_s)),
                    freq_hz: hz(vm.crossover_rad_s),
                },
                FrequencyMarker {
                    label: format!("f_r {:.1} Hz", fit.f_r_hz),
                    freq_hz: fit.f_r_hz,
                },
            ],
        },
        BodePlot {
            title: format!(
                "Position open loop: crossover {:.2} Hz, phase margin {:.1} deg",
                hz(pm.crossover_rad_s),
                pm.phase_margin_deg
            ),
            curves: vec![curve("L position", &grid, |w| des.position_open_loop(w))],
            markers: vec![FrequencyMarker {
                label: format!("w_c {:.2} Hz", hz(pm.crossover_rad_s)),
                freq_hz: hz(pm.crossover_rad_s),
            }],
        },
    ];
    (controller, open_loops)
}

fn row(
    name: &str,
    unit: &str,
    before: Option<f64>,
    after: f64,
    truth: Option<f64>,
    d: usize,
) -> ParameterRow {
    ParameterRow {
        name: name.into(),
        unit: unit.into(),
        before: before.map(|b| fmt(b, d)),
        after: fmt(after, d),
        truth: truth.map(|t| fmt(t, d)),
    }
}

/// Rows of the model and the controller (before/truth columns empty).
fn model_and_controller_rows(id: &IdentifiedModel, des: &ControllerDesign) -> Vec<ParameterRow> {
    let vm = &des.velocity_margins;
    let pm = &des.position_margins;
    vec![
        row("resonance f_r", "Hz", None, id.f_r_hz, None, 2),
        row("antiresonance f_z", "Hz", None, id.f_z_hz, None, 2),
        row(
            "motor inertia Theta_e",
            "kg mm^2",
            None,
            id.theta_e * 1e6,
            None,
            2,
        ),
        row("moving mass m_c", "kg", None, id.m_c, None, 2),
        row("belt stiffness c", "kN/m", None, id.c / 1e3, None, 1),
        row("motor damping d_m", "N s/m", None, id.d_m, None, 2),
        row("cart damping d_c", "N s/m", None, id.d_c, None, 2),
        row("dead time t_T", "ms", None, id.dead_time_s * 1e3, None, 2),
        row("K_P", "N m s/rad", None, des.k_p, None, 4),
        row("K_I", "N m/rad", None, des.k_i, None, 3),
        row("K_PP", "1/s", None, des.k_pp, None, 3),
        row(
            "velocity phase margin",
            "deg",
            None,
            vm.phase_margin_deg,
            None,
            2,
        ),
        row(
            "position phase margin",
            "deg",
            None,
            pm.phase_margin_deg,
            None,
            2,
        ),
        row(
            "gain at resonance",
            "dB",
            None,
            des.gain_at_resonance_db,
            None,
            2,
        ),
    ]
}

/// The report for a run. `before` is the data-sheet model (if any), `truth` the simulation truth.
pub fn build_report(
    run: &Commissioning,
    plant: &str,
    before: Option<&crate::model::TwoMassParams>,
    truth: Option<&Truth>,
) -> Report {
    let fit = &run.fit;
    let des = &run.design;
    let frf_plot = identification_plot(&run.frf, fit, run.dead_time.seconds);
    let (controller, open_loops) = design_plots(des, fit);
    let friction = FrictionPlot {
        velocity_rad_s: run
            .friction_points
            .iter()
            .map(|p| p.velocity_rad_s)
            .collect(),
        torque_nm: run
            .friction_points
            .iter()
            .map(|p| p.mean_torque_nm)
            .collect(),
        viscous_nm_s_per_rad: run.friction.viscous_nm_s_per_rad,
        coulomb_nm: run.friction.coulomb_nm,
    };
    let labels = [
        "no feedforward",
        "linear feedforward",
        "nonlinear feedforward",
    ];
    let moves = run
        .moves
        .iter()
        .zip(labels)
        .map(|(m, label)| MovePlot {
            label: label.into(),
            time_s: decimate(&m.record.time_s, 1500),
            desired_m: decimate(&m.record.desired_m, 1500),
            cart_error_m: decimate(&m.cart_error_m, 1500),
            motor_error_m: decimate(&m.motor_error_m, 1500),
            torque_nm: decimate(
                &m.record
                    .samples
                    .iter()
                    .map(|s| s.torque_command_nm)
                    .collect::<Vec<_>>(),
                1500,
            ),
        })
        .collect();
    let validation_rows = run
        .moves
        .iter()
        .zip(labels)
        .map(|(m, label)| {
            [
                label.to_string(),
                format!("{:.3} mm", m.summary.max_tracking_error_m * 1e3),
                format!("{:.1} um", m.summary.static_error_m * 1e6),
                match m.summary.settling_time_s {
                    Some(t) => format!("{t:.3} s"),
                    None => format!(
                        "not within {:.0} um",
                        super::validation::SETTLING_BAND_M * 1e6
                    ),
                },
            ]
        })
        .collect();
    let id = &run.identified;
    let mut parameters = model_and_controller_rows(id, des);
    // before / truth columns of the model rows
    let columns: [(Option<f64>, Option<f64>); 5] = [
        (before.map(|b| b.f_r_hz()), truth.map(|t| t.f_r_hz)),
        (before.map(|b| b.f_z_hz()), truth.map(|t| t.f_z_hz)),
        (
            before.map(|b| b.theta_e * 1e6),
            truth.map(|t| t.theta_e * 1e6),
        ),
        (before.map(|b| b.m_c), truth.map(|t| t.m_c)),
        (before.map(|b| b.c / 1e3), truth.map(|t| t.c / 1e3)),
    ];
    for (r, (b, t)) in parameters.iter_mut().zip(columns) {
        let d = if r.unit == "kN/m" { 1 } else { 2 };
        r.before = b.map(|v| fmt(v, d));
        r.truth = t.map(|v| fmt(v, d));
    }
    parameters[7].truth = truth.map(|t| fmt(t.dead_time_s * 1e3, 2));
    let f = &run.friction;
    parameters.splice(
        8..8,
        [
            row(
                "viscous friction d_v",
                "mN m s/rad",
                None,
                f.viscous_nm_s_per_rad * 1e3,
                truth.map(|t| t.viscous_nm_s_per_rad * 1e3),
                3,
            ),
            row(
                "Coulomb friction tau_c",
                "N m",
                None,
                f.coulomb_nm,
                truth.map(|t| t.coulomb_nm),
                4,
            ),
            row(
                "holding torque",
                "N m",
                None,
                run.holding_torque_nm,
                None,
                4,
            ),
        ],
    );
    let nl = &run.validation.nonlinear;
    let summary = format!(
        "{plant}: resonance {:.1} Hz, antiresonance {:.1} Hz, fit {:.2} dB rms. Controller: K_P {:.4}, K_I {:.3}, K_PP {:.2}. \
         With nonlinear feedforward the 0 -> 500 mm move tracks within {:.3} mm and ends {:.1} um from the target. \
         The axis was busy for {:.1} s; computing took {:.2} s.",
        id.f_r_hz,
        id.f_z_hz,
        id.fit_rms_db,
        des.k_p,
        des.k_i,
        des.k_pp,
        nl.max_tracking_error_m * 1e3,
        nl.static_error_m * 1e6,
        run.experiment_time_s,
        run.computation_time_s
    );
    Report {
        title: format!("beltune commissioning report: {plant}"),
        summary,
        log: run.log.clone(),
        frf: Some(frf_plot),
        controller: Some(controller),
        open_loops,
        friction: Some(friction),
        moves,
        parameters,
        validation_rows,
    }
}

/// A number with `sig` significant digits (scientific outside 1e-3..1e5).
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
) -> (CommissioningJson, Report) {
    let mut identified = run.identified.clone();
    identified.torque_max_nm = Some(torque_max_nm);
    let json = CommissioningJson {
        schema_version: SCHEMA_VERSION,
        provenance,
        plant: source.to_string(),
        identified,
        friction: run.friction.clone(),
        controller: run.design.summary(),
        drive_form: DriveForm::of(&run.design),
        validation: None,
        experiment_time_s: run.record_time_s,
        computation_time_s: run.computation_time_s,
        excitation_amplitude_nm: None,
        identification_position_m: None,
        truth: None,
        log: run.log.clone(),
    };
    let fit = &run.identification.fit;
    let (controller, open_loops) = design_plots(&run.design, fit);
    let mut run_with_limit = run.clone();
    run_with_limit.identified.torque_max_nm = Some(torque_max_nm);
    let parameters = recorded_rows(&run_with_limit);
    let id = &run.identified;
    let l = crate::units::labels(id.units);
    let report = Report {
        title: format!("beltune commissioning report: {source}"),
        summary: format!(
            "From recorded data ({source}, {:.1} s): resonance {:.2} Hz, antiresonance {:.2} Hz, fit {:.2} dB rms. \
             Controller: K_P {} {}, K_I {} {}, K_PP {:.3} 1/s. No validation move: the stages that need the axis were skipped.",
            run.record_time_s, id.f_r_hz, id.f_z_hz, id.fit_rms_db,
            sig(run.design.k_p, 5), l.torque_per_velocity, sig(run.design.k_i, 5), l.torque_per_angle, run.design.k_pp
        ),
        log: run.log.clone(),
        frf: Some(identification_plot(
            &run.identification.frf,
            fit,
            id.dead_time_s,
        )),
        controller: Some(controller),
        open_loops,
        friction: None,
        moves: Vec::new(),
        parameters,
        validation_rows: Vec::new(),
    };
    (json, report)
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
    write_texts(dir, &json_text(json)?, controller_toml, report_html)
}

/// Write the result to `target` (see [`OutputTarget`]); returns the paths.
pub fn write_outputs_to(
    target: &OutputTarget,
    json: &CommissioningJson,
    controller_toml: &str,
    report_html: &str,
) -> Result<Vec<PathBuf>> {
    write_texts_to(target, &json_text(json)?, controller_toml, report_html)
}

fn json_text(json: &CommissioningJson) -> Result<String> {
    json.to_json_text()
}

fn write_texts(
    dir: &Path,
    json_text: &str,
    controller_toml: &str,
    report_html: &str,
) -> Result<Vec<PathBuf>> {
    check_finite_text("controller.toml", controller_toml)?;
    crate::io::clean_stale_temporaries(&output_parent(dir));
    crate::io::write_folder_atomic(
        dir,
        &[
            (OUTPUT_FILES[0], json_text.as_bytes()),
            (OUTPUT_FILES[1], controller_toml.as_bytes()),
            (OUTPUT_FILES[2], report_html.as_bytes()),
        ],
    )
}

fn write_texts_to(
    target: &OutputTarget,
    json_text: &str,
    controller_toml: &str,
    report_html: &str,
) -> Result<Vec<PathBuf>> {
    match target {
        OutputTarget::Exact { dir, force } => {
            check_exact_target(dir, *force)?;
            write_texts(dir, json_text, controller_toml, report_html)
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
            let files = write_texts(&root.join(&name), json_text, controller_toml, report_html)?;
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
        let a = write_texts_to(&target, JSON, "a = 1\n", "<p>1</p>").unwrap();
        let b = write_texts_to(&target, JSON, "a = 2\n", "<p>2</p>").unwrap();
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
        write_texts_to(&exact(false), JSON, "a = 1\n", "").unwrap();
        let e = write_texts_to(&exact(false), JSON, "a = 2\n", "").unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        write_texts_to(&exact(true), JSON, "a = 2\n", "").unwrap();
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
        let e = write_texts_to(&target, JSON, "a = 1\n", "").unwrap_err();
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
            let e = write_texts(&out, JSON, bad, "").unwrap_err();
            assert!(e.to_string().contains("non-finite"), "{bad}: {e}");
        }
        assert!(!out.exists());
        write_texts(&out, JSON, "kind = \"notch\"\nk = 1e300\n", "").unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
