//! The report of a commissioning (issue 16), built from the shared plot data
//! of [`super::plot_data`]: verdict first, then parameters, validation, the
//! measured FRF, the identification experiment, controller, open loops with
//! margins, closed loops and sensitivities, before/after overlays, friction and
//! the moves; the data files beside it; the provenance.

use super::plot_data::{
    csv_text, decimate, frf_csv, frf_display, frf_lines, loop_data, loops_csv, resonance_markers,
    with_gains, LoopData, EXCITATION_CSV, FRF_CSV, FRICTION_CSV, LOOPS_CSV, MOVES_CSV,
    TRACE_POINTS,
};
use super::verdict_old::{verdict, Verdict, VerdictInput};
use crate::commission::recorded::RecordedCommissioning;
use crate::commission::result::{IdentifiedModel, MoveSummary, Truth};
use crate::commission::validation::{FeedforwardVariant, MoveResult, SETTLING_BAND_M};
use crate::commission::Commissioning;
use crate::design::ControllerDesign;
use crate::record::provenance::Provenance;
use crate::report::{
    BodeCurve, BodePlot, ExcitationPlot, FrequencyMarker, FrictionPlot, MarginPoint, MovePlot,
    Panel, ParameterRow, Report,
};
use crate::Result;
use std::f64::consts::PI;

/// The controller file the verdict's next step names.
pub const CONTROLLER_FILE: &str = "controller.toml";

fn hz(w_rad_s: f64) -> f64 {
    w_rad_s / (2.0 * PI)
}

fn fmt(x: f64, digits: usize) -> String {
    format!("{x:.digits$}")
}

/// `y(x)` interpolated linearly in `log10 x`.
fn at(c: &BodeCurve, f: f64, phase: bool) -> f64 {
    let y = if phase { &c.phase_deg } else { &c.magnitude_db };
    match c.freq_hz.iter().position(|v| *v >= f) {
        None => y.last().copied().unwrap_or(f64::NAN),
        Some(0) => y.first().copied().unwrap_or(f64::NAN),
        Some(i) => {
            let (a, b) = (c.freq_hz[i - 1].log10(), c.freq_hz[i].log10());
            let t = (f.log10() - a) / (b - a);
            y[i - 1] + t * (y[i] - y[i - 1])
        }
    }
}

/// The -180 deg line (plus whole turns) that the phase margin at `f_c` refers to.
fn minus_180_near(c: &BodeCurve, f_c_hz: f64, pm_deg: f64) -> f64 {
    let reference = at(c, f_c_hz, true) - pm_deg;
    -180.0 + 360.0 * ((reference + 180.0) / 360.0).round()
}

/// An open-loop Bode plot with 0 dB / -180 deg lines, the crossover marker and
/// the phase- and gain-margin points.
fn open_loop_plot(
    title: String,
    curve: &BodeCurve,
    m: &crate::lti::StabilityMargins,
    extra_markers: Vec<FrequencyMarker>,
) -> BodePlot {
    let f_c = hz(m.crossover_rad_s);
    let line = minus_180_near(curve, f_c, m.phase_margin_deg);
    let mut points = vec![MarginPoint {
        label: format!("PM {:.1} deg", m.phase_margin_deg),
        freq_hz: f_c,
        value: line + m.phase_margin_deg,
        panel: Panel::Phase,
    }];
    if m.gain_margin_db.is_finite() && m.phase_crossover_rad_s.is_finite() {
        points.push(MarginPoint {
            label: format!("GM {:.1} dB", m.gain_margin_db),
            freq_hz: hz(m.phase_crossover_rad_s),
            value: -m.gain_margin_db,
            panel: Panel::Magnitude,
        });
    }
    let mut markers = vec![FrequencyMarker {
        label: format!("f_c {}", hz_text(f_c)),
        freq_hz: f_c,
    }];
    markers.extend(extra_markers);
    BodePlot {
        title,
        curves: vec![curve.clone()],
        markers,
        magnitude_lines_db: vec![0.0],
        phase_lines_deg: vec![line],
        points,
        magnitude_only: false,
    }
}

/// "7.63 Hz", "0.52 Hz", "111 Hz".
pub fn hz_text(f: f64) -> String {
    if f >= 100.0 {
        format!("{f:.0} Hz")
    } else if f >= 1.0 {
        format!("{f:.1} Hz")
    } else {
        format!("{f:.2} Hz")
    }
}

/// Controller, open loops, closed loops and sensitivities of a design, from
/// [`loop_data`] (the same numbers the tuning page shows).
pub struct LoopPlots {
    /// The loop data the plots are drawn from.
    pub data: LoopData,
    /// `G_pre G_PI`.
    pub controller: BodePlot,
    /// Velocity and position open loops.
    pub open_loops: Vec<BodePlot>,
    /// Closed loops and sensitivities (magnitude).
    pub closed_loops: Vec<BodePlot>,
}

/// The loop plots of `des` with resonance markers at `f_z_hz`, `f_r_hz`.
pub fn loop_plots(des: &ControllerDesign, f_z_hz: f64, f_r_hz: f64) -> Result<LoopPlots> {
    let data = loop_data(des)?;
    let vm = &des.velocity_margins;
    let pm = &des.position_margins;
    let f_r = FrequencyMarker {
        label: format!("f_r {}", hz_text(f_r_hz)),
        freq_hz: f_r_hz,
    };
    let controller = BodePlot {
        title: "Controller G_pre G_PI (velocity error -> torque)".into(),
        curves: vec![data.controller.clone()],
        markers: resonance_markers(f_z_hz, f_r_hz),
        ..BodePlot::default()
    };
    let open_loops = vec![
        open_loop_plot(
            format!(
                "Velocity open loop: crossover {}, phase margin {:.1} deg, gain margin {:.1} dB, {:.1} dB at f_r",
                hz_text(hz(vm.crossover_rad_s)),
                vm.phase_margin_deg,
                vm.gain_margin_db,
                des.gain_at_resonance_db
            ),
            &data.velocity_open_loop,
            vm,
            vec![f_r.clone()],
        ),
        open_loop_plot(
            format!(
                "Position open loop: crossover {}, phase margin {:.1} deg",
                hz_text(hz(pm.crossover_rad_s)),
                pm.phase_margin_deg
            ),
            &data.position_open_loop,
            pm,
            vec![],
        ),
    ];
    let closed_loops = vec![
        BodePlot {
            title: "Closed loops (reference -> output), magnitude".into(),
            curves: vec![
                data.velocity_closed_loop.clone(),
                data.position_closed_loop.clone(),
            ],
            markers: vec![f_r.clone()],
            magnitude_lines_db: vec![0.0, -3.0],
            magnitude_only: true,
            ..BodePlot::default()
        },
        BodePlot {
            title: "Sensitivity 1/(1+L) (disturbance -> error), magnitude; 6 dB is the usual limit"
                .into(),
            curves: vec![
                data.velocity_sensitivity.clone(),
                data.position_sensitivity.clone(),
            ],
            markers: vec![f_r],
            magnitude_lines_db: vec![0.0, 6.0],
            magnitude_only: true,
            ..BodePlot::default()
        },
    ];
    Ok(LoopPlots {
        data,
        controller,
        open_loops,
        closed_loops,
    })
}

/// The bootstrap controller (before) against the designed one (after), both
/// on the identified model: velocity open loops.
fn bootstrap_overlay(run: &Commissioning) -> Result<BodePlot> {
    let ds = &run.datasheet;
    let torque_max = ds.torque_max_nm;
    let boot = crate::commission::bootstrap::bootstrap_controller(
        ds.rigid_inertia(),
        ds.i_t_m,
        run.design.input.ts_s,
        torque_max,
    )?;
    let g = boot.gains;
    let before = with_gains(
        &run.design,
        g.k_pp_per_s,
        g.k_p_nm_s_per_rad,
        g.k_i_nm_per_rad,
    );
    let grid = super::plot_data::loop_grid_hz(&run.design)?;
    let b = super::plot_data::loop_data_on(&before, &grid)?;
    let a = loop_data(&run.design)?;
    let mut before_curve = b.velocity_open_loop;
    before_curve.label = "before: bootstrap gains (data-sheet inertia, no prefilter)".into();
    before_curve.dashed = true;
    let mut after_curve = a.velocity_open_loop;
    after_curve.label = "after: designed controller".into();
    Ok(BodePlot {
        title: "Before / after: velocity open loop on the identified model".into(),
        curves: vec![before_curve, after_curve],
        markers: vec![FrequencyMarker {
            label: format!("f_r {}", hz_text(run.identified.f_r_hz)),
            freq_hz: run.identified.f_r_hz,
        }],
        magnitude_lines_db: vec![0.0],
        phase_lines_deg: vec![-180.0],
        ..BodePlot::default()
    })
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
        value: Some(after),
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
            "velocity crossover f_c",
            "Hz",
            None,
            hz(vm.crossover_rad_s),
            None,
            2,
        ),
        row(
            "velocity phase margin",
            "deg",
            None,
            vm.phase_margin_deg,
            None,
            2,
        ),
        row(
            "position crossover f_c",
            "Hz",
            None,
            hz(pm.crossover_rad_s),
            None,
            3,
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

/// The controller as a drive menu shows it ([`crate::design::DriveForm`]):
/// speed-loop gain, integral time in ms, position gain in 1/s and (m/min)/mm,
/// filter, velocity filter, sampling time; K_P in the unit of `units`.
pub fn drive_form_table(
    des: &ControllerDesign,
    units: crate::ident::ModelUnits,
) -> crate::report::Table {
    let f = crate::design::DriveForm::of(des);
    let opt = |v: Option<f64>, d: usize| v.map_or("-".to_string(), |x| format!("{x:.d$}"));
    let row = |name: &str, unit: &str, v: String| vec![name.to_string(), unit.to_string(), v];
    crate::report::Table {
        title: "Drive settings (the gains as a drive menu shows them)".into(),
        header: ["setting", "unit", "value"].map(String::from).to_vec(),
        rows: vec![
            row(
                "speed controller gain K_P",
                crate::units::labels(units).torque_per_velocity,
                format!("{:.4}", f.velocity_gain_nm_s_per_rad),
            ),
            row(
                "speed controller integral time T_n",
                "ms",
                opt(f.integral_time_ms, 2),
            ),
            row(
                "position controller gain K_v",
                "1/s",
                format!("{:.3}", f.position_gain_per_s),
            ),
            row(
                "position controller gain K_v",
                "(m/min)/mm",
                format!("{:.4}", f.position_gain_m_per_min_per_mm),
            ),
            row("speed setpoint filter", "", f.filter_kind.clone()),
            row("filter frequency", "Hz", opt(f.filter_frequency_hz, 2)),
            row("filter damping", "", opt(f.filter_damping, 3)),
            row(
                "speed actual value filter T_R",
                "ms",
                format!("{:.2}", f.velocity_filter_time_ms),
            ),
            row("sampling time", "ms", format!("{:.3}", f.ts_ms)),
        ],
    }
}

/// The verdict input of a design with an optional validation summary.
pub fn verdict_input(
    id: Option<&IdentifiedModel>,
    des: &ControllerDesign,
    nonlinear: Option<&MoveSummary>,
) -> VerdictInput {
    VerdictInput {
        max_tracking_error_m: nonlinear.map(|m| m.max_tracking_error_m),
        static_error_m: nonlinear.map(|m| m.static_error_m),
        mean_coherence: id.map(|i| i.mean_coherence),
        fit_rms_db: id.map(|i| i.fit_rms_db),
        velocity_phase_margin_deg: (
            des.knobs.pm_velocity_deg,
            des.velocity_margins.phase_margin_deg,
        ),
        position_phase_margin_deg: (
            des.knobs.pm_position_deg,
            des.position_margins.phase_margin_deg,
        ),
        velocity_gain_margin_db: des.velocity_margins.gain_margin_db,
        controller_file: CONTROLLER_FILE.into(),
    }
}

/// The verdict of a commissioning (judged on the move with nonlinear feedforward).
pub fn verdict_of(run: &Commissioning) -> Verdict {
    verdict(&verdict_input(
        Some(&run.identified),
        &run.design,
        Some(&run.validation.nonlinear),
    ))
}

/// A move as plotted (decimated to [`TRACE_POINTS`]).
pub fn move_plot(m: &MoveResult, label: &str) -> MovePlot {
    MovePlot {
        label: label.into(),
        time_s: decimate(&m.record.time_s, TRACE_POINTS),
        desired_m: decimate(&m.record.desired_m, TRACE_POINTS),
        cart_error_m: decimate(&m.cart_error_m, TRACE_POINTS),
        motor_error_m: decimate(&m.motor_error_m, TRACE_POINTS),
        torque_nm: decimate(
            &m.record
                .samples
                .iter()
                .map(|s| s.torque_command_nm)
                .collect::<Vec<_>>(),
            TRACE_POINTS,
        ),
    }
}

/// A row of the validation table.
pub fn validation_row(label: &str, s: &MoveSummary) -> [String; 4] {
    [
        label.to_string(),
        format!("{:.3} mm", s.max_tracking_error_m * 1e3),
        format!("{:.1} um", s.static_error_m * 1e6),
        match s.settling_time_s {
            Some(t) => format!("{t:.3} s"),
            None => format!("not within {:.0} um", SETTLING_BAND_M * 1e6),
        },
    ]
}

/// Min/max envelope of `y` in at most `n / 2` buckets (a PRBS stays a band,
/// not an alias), with the matching times.
fn envelope(t: &[f64], y: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let len = t.len().min(y.len());
    let buckets = (n / 2).max(1);
    let step = len.div_ceil(buckets).max(1);
    let (mut to, mut yo) = (Vec::new(), Vec::new());
    for start in (0..len).step_by(step) {
        let end = (start + step).min(len);
        let slice = &y[start..end];
        let (imin, imax) = slice.iter().enumerate().fold((0, 0), |(a, b), (i, v)| {
            (
                if *v < slice[a] { i } else { a },
                if *v > slice[b] { i } else { b },
            )
        });
        let (first, second) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        for k in [first, second] {
            to.push(t[start + k]);
            yo.push(slice[k]);
        }
    }
    (to, yo)
}

/// The report for a run. `before` is the data-sheet model (if any), `truth`
/// the simulation truth, `provenance` the run's stamp.
pub fn build_report(
    run: &Commissioning,
    plant: &str,
    before: Option<&crate::model::TwoMassParams>,
    truth: Option<&Truth>,
    provenance: Option<&Provenance>,
) -> Result<Report> {
    let fit = &run.fit;
    let des = &run.design;
    let tf = fit.model.tf(&fit.params);
    let lines = frf_lines(&run.frf, &tf, run.dead_time.seconds)?;
    let frf_plot = frf_display(
        &lines,
        &tf,
        run.dead_time.seconds,
        resonance_markers(fit.f_z_hz, fit.f_r_hz),
    )?;
    let loops = loop_plots(des, fit.f_z_hz, fit.f_r_hz)?;
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
    let variants = FeedforwardVariant::ALL;
    let moves = run
        .moves
        .iter()
        .zip(variants)
        .map(|(m, v)| move_plot(m, v.label()))
        .collect();
    let validation_rows = run
        .moves
        .iter()
        .zip(variants)
        .map(|(m, v)| validation_row(v.label(), &m.summary))
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
            // issue 12: the static belt stretch the setpoint leads by uses it
            row(
                &format!(
                    "belt stiffness c at the validation target ({:.0} mm{})",
                    run.target_stiffness.position_m * 1e3,
                    if run.target_stiffness.measured {
                        ", measured there"
                    } else {
                        ", identification position"
                    }
                ),
                "kN/m",
                None,
                run.target_stiffness.c_n_per_m / 1e3,
                None,
                1,
            ),
        ],
    );
    let nl = &run.validation.nonlinear;
    let summary = format!(
        "{plant}: resonance {:.1} Hz, antiresonance {:.1} Hz, fit {:.2} dB rms. Controller: K_P {:.4} N m s/rad, \
         K_I {:.3} N m/rad, K_PP {:.2} 1/s. With nonlinear feedforward the validation move to {:.0} mm tracks within \
         {:.3} mm and ends {:.1} um from the target. The axis was busy for {:.1} s; computing took {:.2} s.",
        id.f_r_hz,
        id.f_z_hz,
        id.fit_rms_db,
        des.k_p,
        des.k_i,
        des.k_pp,
        run.moves[2].record.desired_m.last().copied().unwrap_or(0.0) * 1e3,
        nl.max_tracking_error_m * 1e3,
        nl.static_error_m * 1e6,
        run.experiment_time_s,
        run.computation_time_s
    );
    let ex = &run.excitation;
    let (t_tau, tau) = envelope(&ex.time_s, &ex.torque_command_nm, 2 * TRACE_POINTS);
    let (t_pos, pos) = envelope(&ex.time_s, &ex.position_m, 2 * TRACE_POINTS);
    let excitation = ExcitationPlot {
        time_s: t_tau,
        torque_nm: tau,
        position_time_s: t_pos,
        position_m: pos,
        torque_limit_nm: ex.torque_max_nm,
        travel_min_m: ex.travel_min_m,
        travel_max_m: ex.travel_max_m,
    };
    Ok(Report {
        title: format!("beltune commissioning report: {plant}"),
        summary,
        log: run.log.clone(),
        frf: Some(frf_plot),
        controller: Some(loops.controller),
        open_loops: loops.open_loops,
        closed_loops: loops.closed_loops,
        overlays: vec![bootstrap_overlay(run)?],
        friction: Some(friction),
        moves,
        parameters,
        validation_rows,
        verdict: Some(verdict_of(run)),
        provenance: provenance.cloned(),
        excitation: Some(excitation),
        data_files: data_file_notes(true),
        tables: vec![drive_form_table(des, crate::ident::ModelUnits::Torque)],
    })
}

fn data_file_notes(with_moves: bool) -> Vec<(String, String)> {
    let mut v = vec![
        (
            FRF_CSV.to_string(),
            "every measured line of the FRF (the plot shows it decimated) with the fitted model"
                .to_string(),
        ),
        (
            LOOPS_CSV.to_string(),
            "the open and closed loops, sensitivities and controller on the plot grid".to_string(),
        ),
    ];
    if with_moves {
        v.push((
            MOVES_CSV.to_string(),
            "the validation moves (desired position, errors, torque) as plotted".to_string(),
        ));
        v.push((
            EXCITATION_CSV.to_string(),
            "the identification experiment (torque, position) as plotted, with its limits"
                .to_string(),
        ));
        v.push((
            FRICTION_CSV.to_string(),
            "the constant-velocity friction runs (velocity, mean torque)".to_string(),
        ));
    }
    v
}

/// `moves.csv`: the three validation moves as plotted.
pub fn moves_csv(moves: &[MovePlot]) -> String {
    let Some(first) = moves.first() else {
        return String::new();
    };
    let n = moves.iter().map(|m| m.time_s.len()).min().unwrap_or(0);
    let names: Vec<String> = moves
        .iter()
        .flat_map(|m| {
            let key = m.label.replace(' ', "_");
            [format!("error_{key}_m"), format!("torque_{key}_nm")]
        })
        .collect();
    let errors: Vec<&[f64]> = moves
        .iter()
        .map(|m| {
            if m.cart_error_m.len() >= n {
                &m.cart_error_m[..n]
            } else {
                &m.motor_error_m[..n.min(m.motor_error_m.len())]
            }
        })
        .collect();
    let mut cols: Vec<(&str, &[f64])> = vec![
        ("time_s", &first.time_s[..n]),
        (
            "desired_m",
            &first.desired_m[..n.min(first.desired_m.len())],
        ),
    ];
    for (i, m) in moves.iter().enumerate() {
        cols.push((&names[2 * i], errors[i]));
        cols.push((&names[2 * i + 1], &m.torque_nm[..n.min(m.torque_nm.len())]));
    }
    super::plot_data::csv_text(&cols)
}

/// The data files beside the report of a run: (file name, text).
pub fn data_files(run: &Commissioning, report: &Report) -> Result<Vec<(String, String)>> {
    let fit = &run.fit;
    let tf = fit.model.tf(&fit.params);
    let lines = frf_lines(&run.frf, &tf, run.dead_time.seconds)?;
    let mut files = vec![
        (FRF_CSV.into(), frf_csv(&lines)),
        (LOOPS_CSV.into(), loops_csv(&loop_data(&run.design)?)),
        (MOVES_CSV.into(), moves_csv(&report.moves)),
    ];
    if let Some(e) = &report.excitation {
        files.push((EXCITATION_CSV.into(), excitation_csv(e)));
    }
    if let Some(f) = &report.friction {
        files.push((FRICTION_CSV.into(), friction_csv(f)));
    }
    Ok(files)
}

/// Columns of `excitation.csv`: the trace as plotted (envelope), and the
/// torque limit and travel window drawn with it (the same on every row).
const EXCITATION_COLUMNS: [&str; 6] = [
    "time_s",
    "torque_nm",
    "position_m",
    "torque_limit_nm",
    "travel_min_m",
    "travel_max_m",
];

/// `excitation.csv`: the identification experiment as the report plots it.
pub fn excitation_csv(e: &ExcitationPlot) -> String {
    let n = e.time_s.len();
    let same = |v: f64| vec![v; n];
    // the torque and position envelopes share their time base (same samples, same buckets)
    let position: Vec<f64> = if e.position_time_s == e.time_s {
        e.position_m.clone()
    } else {
        e.time_s
            .iter()
            .map(|t| {
                let k = e.position_time_s.partition_point(|x| x < t);
                e.position_m
                    .get(k.min(e.position_m.len().saturating_sub(1)))
                    .copied()
                    .unwrap_or(f64::NAN)
            })
            .collect()
    };
    csv_text(&[
        (EXCITATION_COLUMNS[0], &e.time_s),
        (EXCITATION_COLUMNS[1], &e.torque_nm),
        (EXCITATION_COLUMNS[2], &position),
        (EXCITATION_COLUMNS[3], &same(e.torque_limit_nm)),
        (EXCITATION_COLUMNS[4], &same(e.travel_min_m)),
        (EXCITATION_COLUMNS[5], &same(e.travel_max_m)),
    ])
}

/// Read `excitation.csv` back.
pub fn read_excitation_csv(path: &std::path::Path) -> Result<ExcitationPlot> {
    let cols = crate::ident::read_csv_columns(path, &EXCITATION_COLUMNS)?;
    let col = |n: &str| -> Vec<f64> { cols.column(n).map(|c| c.to_vec()).unwrap_or_default() };
    let first = |n: &str| col(n).first().copied().unwrap_or(f64::NAN);
    let time_s = col("time_s");
    Ok(ExcitationPlot {
        position_time_s: time_s.clone(),
        time_s,
        torque_nm: col("torque_nm"),
        position_m: col("position_m"),
        torque_limit_nm: first("torque_limit_nm"),
        travel_min_m: first("travel_min_m"),
        travel_max_m: first("travel_max_m"),
    })
}

/// `friction.csv`: each constant-velocity run of the friction stage.
pub fn friction_csv(f: &FrictionPlot) -> String {
    csv_text(&[
        ("velocity_rad_s", &f.velocity_rad_s),
        ("mean_torque_nm", &f.torque_nm),
    ])
}

/// Read `friction.csv` back; the fitted curve is `viscous_nm_s_per_rad`,
/// `coulomb_nm` (from `commissioning.json`).
pub fn read_friction_csv(
    path: &std::path::Path,
    viscous_nm_s_per_rad: f64,
    coulomb_nm: f64,
) -> Result<FrictionPlot> {
    let names = ["velocity_rad_s", "mean_torque_nm"];
    let cols = crate::ident::read_csv_columns(path, &names)?;
    let col = |n: &str| -> Vec<f64> { cols.column(n).map(|c| c.to_vec()).unwrap_or_default() };
    Ok(FrictionPlot {
        velocity_rad_s: col("velocity_rad_s"),
        torque_nm: col("mean_torque_nm"),
        viscous_nm_s_per_rad,
        coulomb_nm,
    })
}

/// The report of a commissioning from recorded data (`source` names the record).
pub fn recorded_report(
    run: &RecordedCommissioning,
    source: &str,
    provenance: Option<&Provenance>,
) -> Result<Report> {
    let fit = &run.identification.fit;
    let id = &run.identified;
    let tf = fit.model.tf(&fit.params);
    let lines = frf_lines(&run.identification.frf, &tf, id.dead_time_s)?;
    let frf = frf_display(
        &lines,
        &tf,
        id.dead_time_s,
        resonance_markers(fit.f_z_hz, fit.f_r_hz),
    )?;
    let loops = loop_plots(&run.design, fit.f_z_hz, fit.f_r_hz)?;
    let mut parameters = model_and_controller_rows(id, &run.design);
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
    Ok(Report {
        title: format!("beltune commissioning report: {source}"),
        summary: format!(
            "From recorded data ({source}, {:.1} s): resonance {:.2} Hz, antiresonance {:.2} Hz, fit {:.2} dB rms. \
             Controller: K_P {:.4e}, K_I {:.4e}, K_PP {:.3}. No validation move: the stages that need the axis were skipped.",
            run.record_time_s, id.f_r_hz, id.f_z_hz, id.fit_rms_db, run.design.k_p, run.design.k_i, run.design.k_pp
        ),
        log: run.log.clone(),
        frf: Some(frf),
        controller: Some(loops.controller),
        open_loops: loops.open_loops,
        closed_loops: loops.closed_loops,
        verdict: Some(verdict(&verdict_input(Some(id), &run.design, None))),
        provenance: provenance.cloned(),
        data_files: data_file_notes(false),
        // (no drive table: a record in current units has other gain units)
        ..Report::default()
    })
}

/// The data files beside the report of a recorded commissioning.
pub fn recorded_data_files(run: &RecordedCommissioning) -> Result<Vec<(String, String)>> {
    let fit = &run.identification.fit;
    let tf = fit.model.tf(&fit.params);
    let lines = frf_lines(&run.identification.frf, &tf, run.identified.dead_time_s)?;
    Ok(vec![
        (FRF_CSV.into(), frf_csv(&lines)),
        (LOOPS_CSV.into(), loops_csv(&loop_data(&run.design)?)),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_keeps_the_extremes_of_every_bucket() {
        let t: Vec<f64> = (0..1000).map(|k| k as f64).collect();
        let y: Vec<f64> = (0..1000)
            .map(|k| if k % 7 == 0 { 1.0 } else { -1.0 })
            .collect();
        let (to, yo) = envelope(&t, &y, 20);
        assert_eq!(to.len(), yo.len());
        assert!(to.len() <= 22);
        assert!(yo.contains(&1.0) && yo.contains(&-1.0));
        assert!(to.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn hz_text_never_says_omega() {
        assert_eq!(hz_text(7.634), "7.6 Hz");
        assert_eq!(hz_text(0.523), "0.52 Hz");
        assert_eq!(hz_text(110.8), "111 Hz");
    }
}
