//! The three output files of a commissioning run: `commissioning.json` (all
//! numbers), `controller.toml` (what a drive needs) and `report.html` (what a
//! person reads). Building them is pure computation; writing is
//! [`write_outputs`], which writes each file atomically and only after all
//! three were built, so a failed run leaves nothing half-written.

use super::commission::{cascade_from_design, Commissioning};
use super::recorded::RecordedCommissioning;
use super::result::{FrictionResult, IdentifiedModel, Truth, Validation};
use crate::design::{ControllerDesign, DesignSummary, Prefilter};
use crate::ident::{Frf, TwoMassFit};
use crate::lti::C64;
use crate::report::{
    BodeCurve, BodePlot, FrequencyMarker, FrfPlot, FrictionPlot, MovePlot, ParameterRow, Report,
};
use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;
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

/// `commissioning.json` and the report for a commissioning from recorded data
/// (`source` names the record). The JSON's `experiment_time_s` is the record's duration.
pub fn recorded_outputs(run: &RecordedCommissioning, source: &str) -> (CommissioningJson, Report) {
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
    let fit = &run.identification.fit;
    let (controller, open_loops) = design_plots(&run.design, fit);
    let mut parameters = model_and_controller_rows(&run.identified, &run.design);
    if let Some(f) = &run.friction {
        parameters.extend([
            row(
                "viscous friction d_v",
                "(torque unit) s/rad",
                None,
                f.viscous_nm_s_per_rad,
                None,
                5,
            ),
            row(
                "Coulomb friction tau_c",
                "(torque unit)",
                None,
                f.coulomb_nm,
                None,
                5,
            ),
            row(
                "constant offset",
                "(torque unit)",
                None,
                f.holding_torque_nm,
                None,
                5,
            ),
        ]);
    }
    let id = &run.identified;
    let report = Report {
        title: format!("beltune commissioning report: {source}"),
        summary: format!(
            "From recorded data ({source}, {:.1} s): resonance {:.2} Hz, antiresonance {:.2} Hz, fit {:.2} dB rms. \
             Controller: K_P {:.4e}, K_I {:.4e}, K_PP {:.3}. No validation move: the stages that need the axis were skipped.",
            run.record_time_s, id.f_r_hz, id.f_z_hz, id.fit_rms_db, run.design.k_p, run.design.k_i, run.design.k_pp
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
