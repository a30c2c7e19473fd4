//! The report of a result (verdict first, then parameters, validation, the
//! measured FRF, the identification experiment, controller, open loops with
//! margins, closed loops and sensitivities, before/after overlays, friction and
//! the moves; the data files beside it; the provenance), built by one
//! function, [`build_report`], from the record of the result and the data
//! files: for a run on an axis, a commissioning from a recording and a design
//! saved by the tuning page alike.

use super::bode::{hz, hz_text, loop_plots};
use super::data_files::DataFiles;
use super::plot_data::{
    decimate, frf_display, loop_data, resonance_markers, with_gains, TRACE_POINTS,
};
use crate::commission::validation::{MoveResult, MoveSummary, SETTLING_BAND_M};
use crate::commission::Commissioning;
use crate::design::ControllerDesign;
use crate::ident::ModelUnits;
use crate::lti::Tf;
use crate::model::TwoMassParams;
use crate::record::commissioning::CommissioningRecord;
use crate::report::{
    BodePlot, ExcitationPlot, FrequencyMarker, MovePlot, ParameterRow, Report, Table,
};
use crate::Result;

/// What the result is.
#[derive(Clone, Debug, PartialEq)]
pub enum ReportKind {
    /// A run on an axis (a simulated plant or a real drive).
    Axis,
    /// A commissioning from a recording: no validation move.
    Recorded,
    /// A design saved by the tuning page, judged on a simulated move.
    Tuned {
        /// Where the design model came from.
        source: String,
        /// Payload of the simulated move, kg.
        payload_kg: f64,
        /// What the simulated move ran on.
        move_label: String,
    },
}

/// Everything a report is built from.
pub struct ReportInputs<'a> {
    /// What the result is.
    pub kind: ReportKind,
    /// The record (`commissioning.json`): model, friction, verdict, log, provenance.
    pub record: &'a CommissioningRecord,
    /// The delivered design (loops, gains, drive settings).
    pub design: &'a ControllerDesign,
    /// The fitted model's transfer function torque -> motor angle (without dead time).
    pub model_tf: &'a Tf,
    /// The data files: measured FRF, moves, excitation, friction runs.
    pub data: &'a DataFiles,
    /// The validation moves' numbers, one table row each: (label, summary).
    pub move_rows: &'a [(String, MoveSummary)],
    /// The data-sheet model (the "before" column), if known.
    pub datasheet_model: Option<&'a TwoMassParams>,
    /// Before/after overlays.
    pub overlays: Vec<BodePlot>,
    /// Sections the report cannot show, with the reason: (section, why).
    pub absent: Vec<(String, String)>,
}

fn fmt(x: f64, digits: usize) -> String {
    format!("{x:.digits$}")
}

/// `x` with `sig` significant digits (fixed point where readable).
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

/// Build the report of a result.
pub fn build_report(inp: &ReportInputs) -> Result<Report> {
    let rec = inp.record;
    let id = &rec.identified;
    let des = inp.design;
    let frf = match &inp.data.frf {
        Some(lines) => Some(super::FrfPlot {
            input_unit: crate::units::labels(id.units).torque.into(),
            ..frf_display(
                lines,
                inp.model_tf,
                id.dead_time_s,
                resonance_markers(id.f_z_hz, id.f_r_hz),
            )?
        }),
        None => None,
    };
    let loops = loop_plots(des, id.f_z_hz, id.f_r_hz)?;
    let mut friction = inp.data.friction.clone();
    if let (Some(plot), Some(f)) = (&mut friction, &rec.friction) {
        plot.viscous_nm_s_per_rad = f.viscous_nm_s_per_rad;
        plot.coulomb_nm = f.coulomb_nm;
    }
    let mut tables = vec![
        drive_form_table(des, id.units),
        super::vendor::vendor_table(des, id.units),
    ];
    if !rec.stage_axis_times.is_empty() {
        tables.push(axis_time_table(
            &rec.stage_axis_times,
            rec.experiment_time_s.unwrap_or(f64::NAN),
        ));
    }
    if !inp.absent.is_empty() {
        tables.push(Table {
            title: "Sections not in this report".into(),
            header: vec!["section".into(), "why".into()],
            rows: inp
                .absent
                .iter()
                .map(|(a, b)| vec![a.clone(), b.clone()])
                .collect(),
        });
    }
    Ok(Report {
        title: match &inp.kind {
            ReportKind::Tuned { source, .. } => format!("beltune tuning report: {source}"),
            _ => format!("beltune commissioning report: {}", rec.plant),
        },
        summary: summary(inp),
        log: rec.log.clone(),
        frf,
        controller: Some(loops.controller),
        open_loops: loops.open_loops,
        closed_loops: loops.closed_loops,
        overlays: inp.overlays.clone(),
        friction,
        moves: inp.data.moves.clone(),
        parameters: parameter_rows(rec, des, inp.datasheet_model),
        validation_rows: inp
            .move_rows
            .iter()
            .map(|(label, s)| validation_row(label, s))
            .collect(),
        verdict: rec.verdict.clone(),
        provenance: rec.provenance.clone(),
        excitation: inp.data.excitation.clone(),
        data_files: inp.data.notes(),
        tables,
        trends: Vec::new(),
    })
}

/// The paragraph under the verdict.
fn summary(inp: &ReportInputs) -> String {
    let rec = inp.record;
    let id = &rec.identified;
    let des = inp.design;
    let l = crate::units::labels(id.units);
    match &inp.kind {
        ReportKind::Axis => {
            let nl = rec.delivered_move().cloned().unwrap_or_default();
            let target_mm = rec.validation_move.map_or(f64::NAN, |m| m.target_m * 1e3);
            format!(
                "{}: resonance {:.1} Hz, antiresonance {:.1} Hz, fit {:.2} dB rms. Controller: K_P {:.4} N m s/rad, \
                 K_I {:.3} N m/rad, K_PP {:.2} 1/s. With nonlinear feedforward the validation move to {:.0} mm tracks within \
                 {:.3} mm and ends {:.1} um from the target. The axis was busy for {:.1} s; computing took {:.2} s.",
                rec.plant,
                id.f_r_hz,
                id.f_z_hz,
                id.fit_rms_db,
                des.k_p,
                des.k_i,
                des.k_pp,
                target_mm,
                nl.max_tracking_error_m * 1e3,
                nl.static_error_m * 1e6,
                rec.experiment_time_s.unwrap_or(f64::NAN),
                rec.computation_time_s.unwrap_or(f64::NAN)
            )
        }
        ReportKind::Recorded => format!(
            "From recorded data ({}, {:.1} s{}): resonance {:.2} Hz, antiresonance {:.2} Hz, fit {:.2} dB rms. \
             Controller: K_P {} {}, K_I {} {}, K_PP {:.3} 1/s. No validation move: the stages that need the axis were skipped.",
            rec.plant,
            rec.experiment_time_s.unwrap_or(f64::NAN),
            match &rec.axis {
                Some(crate::record::commissioning::AxisRecord::Recorded {
                    identification: Some(m),
                    ..
                }) => format!("; identified {}", m.words()),
                _ => String::new(),
            },
            id.f_r_hz,
            id.f_z_hz,
            id.fit_rms_db,
            sig(des.k_p, 5),
            l.torque_per_velocity,
            sig(des.k_i, 5),
            l.torque_per_angle,
            des.k_pp
        ),
        ReportKind::Tuned {
            source,
            payload_kg,
            move_label,
        } => format!(
            "Saved by the tuning page. The design model is the one of {source}; the verdict is judged on a \
             simulated validation move with {payload_kg} kg payload ({move_label}), not on the axis. \
             Run `beltune commission` again to validate on the axis."
        ),
    }
}

/// One row of the parameter table, formatted with `digits` decimals (SI
/// display units) or 5 significant digits (current units).
struct Rows {
    units: ModelUnits,
    rows: Vec<ParameterRow>,
}

impl Rows {
    /// A row: `value` in the display unit `unit`; `before`, `truth` in the same unit.
    fn add(
        &mut self,
        name: &str,
        unit: &str,
        value: f64,
        before: Option<f64>,
        truth: Option<f64>,
        digits: usize,
    ) {
        let text = |v: f64| match self.units {
            ModelUnits::Torque => fmt(v, digits),
            ModelUnits::Current => sig(v, 5),
        };
        self.rows.push(ParameterRow {
            name: name.into(),
            unit: unit.into(),
            before: before.map(text),
            after: text(value),
            truth: truth.map(text),
            value: Some(value),
        });
    }
}

/// The parameter table: the model (with the data-sheet model and the
/// simulator's truth beside it where known), friction, the belt stiffness at
/// the validation target, the torque limit, the controller. SI values in
/// readable units (kg mm^2, kN/m, ms); a record in current units in its own
/// units, unscaled.
pub fn parameter_rows(
    rec: &CommissioningRecord,
    des: &ControllerDesign,
    datasheet: Option<&TwoMassParams>,
) -> Vec<ParameterRow> {
    let id = &rec.identified;
    let si = id.units == ModelUnits::Torque;
    let l = crate::units::labels(id.units);
    // (scale, unit) of the model quantities: SI display units or the record's
    let (inertia, mass, stiffness, damping) = if si {
        (
            (1e6, "kg mm^2"),
            (1.0, "kg"),
            (1e-3, "kN/m"),
            (1.0, "N s/m"),
        )
    } else {
        (
            (1.0, l.inertia),
            (1.0, l.mass),
            (1.0, l.stiffness),
            (1.0, l.damping),
        )
    };
    let truth = rec.truth.as_ref();
    let mut r = Rows {
        units: id.units,
        rows: Vec::new(),
    };
    let b = |f: &dyn Fn(&TwoMassParams) -> f64| datasheet.map(f);
    r.add(
        "resonance f_r",
        "Hz",
        id.f_r_hz,
        b(&|p| p.f_r_hz()),
        truth.map(|t| t.f_r_hz),
        2,
    );
    r.add(
        "antiresonance f_z",
        "Hz",
        id.f_z_hz,
        b(&|p| p.f_z_hz()),
        truth.map(|t| t.f_z_hz),
        2,
    );
    r.add(
        "motor inertia Theta_e",
        inertia.1,
        id.theta_e * inertia.0,
        b(&|p| p.theta_e * inertia.0),
        truth.map(|t| t.theta_e * inertia.0),
        2,
    );
    r.add(
        "moving mass m_c",
        mass.1,
        id.m_c * mass.0,
        b(&|p| p.m_c * mass.0),
        truth.map(|t| t.m_c * mass.0),
        2,
    );
    r.add(
        "belt stiffness c",
        stiffness.1,
        id.c * stiffness.0,
        b(&|p| p.c * stiffness.0),
        truth.map(|t| t.c * stiffness.0),
        1,
    );
    r.add(
        "motor damping d_m",
        damping.1,
        id.d_m * damping.0,
        None,
        None,
        2,
    );
    r.add(
        "cart damping d_c",
        damping.1,
        id.d_c * damping.0,
        None,
        None,
        2,
    );
    r.add(
        if id.dead_time_measured {
            "dead time t_T"
        } else {
            "dead time t_T (assumed, not measured)"
        },
        "ms",
        id.dead_time_s * 1e3,
        None,
        truth.map(|t| t.dead_time_s * 1e3),
        2,
    );
    if let Some(f) = &rec.friction {
        let (viscous_scale, viscous_unit) = if si {
            (1e3, "mN m s/rad")
        } else {
            (1.0, l.torque_per_velocity)
        };
        r.add(
            "viscous friction d_v",
            viscous_unit,
            f.viscous_nm_s_per_rad * viscous_scale,
            None,
            truth.map(|t| t.viscous_nm_s_per_rad * viscous_scale),
            3,
        );
        r.add(
            "Coulomb friction tau_c",
            l.torque,
            f.coulomb_nm,
            None,
            truth.map(|t| t.coulomb_nm),
            4,
        );
        r.add(
            "holding torque",
            l.torque,
            f.holding_torque_nm,
            None,
            None,
            4,
        );
    }
    if let Some(t) = &rec.target_stiffness {
        r.add(
            &format!(
                "belt stiffness c at the validation target ({:.0} mm{})",
                t.position_m * 1e3,
                if t.measured {
                    ", measured there"
                } else {
                    ", identification position"
                }
            ),
            stiffness.1,
            t.c_n_per_m * stiffness.0,
            None,
            None,
            1,
        );
    }
    if let Some(t) = id.torque_max_nm {
        r.add("torque limit", l.torque, t, None, None, 3);
    }
    let vm = &des.velocity_margins;
    let pm = &des.position_margins;
    r.add("K_P", l.torque_per_velocity, des.k_p, None, None, 4);
    r.add("K_I", l.torque_per_angle, des.k_i, None, None, 3);
    r.add("K_PP", "1/s", des.k_pp, None, None, 3);
    r.add(
        "velocity crossover f_c",
        "Hz",
        hz(vm.crossover_rad_s),
        None,
        None,
        2,
    );
    r.add(
        "velocity phase margin",
        "deg",
        vm.phase_margin_deg,
        None,
        None,
        2,
    );
    r.add(
        "position crossover f_c",
        "Hz",
        hz(pm.crossover_rad_s),
        None,
        None,
        3,
    );
    r.add(
        "position phase margin",
        "deg",
        pm.phase_margin_deg,
        None,
        None,
        2,
    );
    r.add(
        "gain at resonance",
        "dB",
        des.gain_at_resonance_db,
        None,
        None,
        2,
    );
    r.rows
}

/// The bootstrap controller (before) against the designed one (after), both
/// on the identified model: velocity open loops.
pub fn bootstrap_overlay(run: &Commissioning) -> Result<BodePlot> {
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
            // in series with the speed controller, inside the speed loop: a drive's
            // current (torque) setpoint filter, not a speed setpoint filter (outside the loop)
            row(
                "current setpoint filter (inside the speed loop)",
                "",
                f.filter_kind.clone(),
            ),
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

/// The table of the axis time per stage (the stages that took none, the
/// computations, left out) and the total `total_s`, s.
pub fn axis_time_table(times: &[crate::commission::stages::StageAxisTime], total_s: f64) -> Table {
    let mut rows: Vec<Vec<String>> = times
        .iter()
        .filter(|t| t.axis_time_s > 0.0)
        .map(|t| vec![t.stage.clone(), format!("{:.2} s", t.axis_time_s)])
        .collect();
    rows.push(vec!["total".into(), format!("{total_s:.2} s")]);
    Table {
        title: "Axis time per stage".into(),
        header: vec!["stage".into(), "axis time".into()],
        rows,
    }
}

/// A row of the validation table.
pub fn validation_row(label: &str, s: &MoveSummary) -> [String; 4] {
    [
        label.to_string(),
        format!("{:.3} mm", s.max_tracking_error_m * 1e3),
        format!("{:.1} um", s.static_error_m * 1e6),
        match s.settling_time_s {
            // the error never left the band: say so, a bare "0.000 s" reads as a defect
            Some(t) if t == 0.0 && s.max_tracking_error_m <= SETTLING_BAND_M => format!(
                "0 s (within +-{:.0} um throughout the move)",
                SETTLING_BAND_M * 1e6
            ),
            Some(t) => format!(
                "{t:.3} s after the trajectory ends (to within +-{:.0} um)",
                SETTLING_BAND_M * 1e6
            ),
            None => format!("not within {:.0} um", SETTLING_BAND_M * 1e6),
        },
    ]
}

/// Min/max envelope of `y` in at most `n / 2` buckets (a PRBS stays a band,
/// not an alias), with the matching times.
pub fn envelope(t: &[f64], y: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
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

/// The identification experiment of a run as the report plots it (min/max
/// envelopes of torque and position, with the limits it ran under).
pub fn excitation_plot(run: &Commissioning) -> ExcitationPlot {
    let ex = &run.excitation;
    let (t_tau, tau) = envelope(&ex.time_s, &ex.torque_command_nm, 2 * TRACE_POINTS);
    let (t_pos, pos) = envelope(&ex.time_s, &ex.position_m, 2 * TRACE_POINTS);
    ExcitationPlot {
        time_s: t_tau,
        torque_nm: tau,
        position_time_s: t_pos,
        position_m: pos,
        torque_limit_nm: ex.torque_max_nm,
        travel_min_m: ex.travel_min_m,
        travel_max_m: ex.travel_max_m,
    }
}

/// The moves of a run as plotted, with their labels.
pub fn move_plots(moves: &[(String, &MoveResult)]) -> Vec<MovePlot> {
    moves.iter().map(|(l, m)| move_plot(m, l)).collect()
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

    /// The prefilter sits in series with the speed controller, inside the
    /// speed loop: a drive calls that a current (torque) setpoint filter; a
    /// "speed setpoint filter" would sit outside the loop.
    #[test]
    fn the_drive_table_names_the_prefilter_by_where_it_sits() {
        let input =
            crate::design::DesignInput::new(crate::model::TwoMassParams::thesis_table_a4(), 1e-3);
        let des = crate::design::design(&input, &crate::design::DesignKnobs::default()).unwrap();
        let t = drive_form_table(&des, crate::ident::ModelUnits::default());
        let names: Vec<&str> = t.rows.iter().map(|r| r[0].as_str()).collect();
        assert!(
            names.contains(&"current setpoint filter (inside the speed loop)"),
            "{names:?}"
        );
        assert!(
            !names.iter().any(|n| n.contains("speed setpoint")),
            "{names:?}"
        );
    }

    /// A move whose error never left the settling band says so instead of a
    /// bare "0.000 s"; a real settling time names its reference and band.
    #[test]
    fn the_settling_time_says_what_it_measures() {
        let within = MoveSummary {
            max_tracking_error_m: 42e-6,
            settling_time_s: Some(0.0),
            ..MoveSummary::default()
        };
        assert_eq!(
            validation_row("nonlinear", &within)[3],
            "0 s (within +-100 um throughout the move)"
        );
        let settles = MoveSummary {
            max_tracking_error_m: 7e-3,
            settling_time_s: Some(0.125),
            ..MoveSummary::default()
        };
        assert_eq!(
            validation_row("none", &settles)[3],
            "0.125 s after the trajectory ends (to within +-100 um)"
        );
    }

    #[test]
    fn hz_text_never_says_omega() {
        assert_eq!(hz_text(7.634), "7.6 Hz");
        assert_eq!(hz_text(0.523), "0.52 Hz");
        assert_eq!(hz_text(110.8), "111 Hz");
    }
}
