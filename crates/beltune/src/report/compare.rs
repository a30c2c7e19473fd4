//! `beltune compare A B`: two result folders side by side: both measured
//! FRFs and fits, the loops and the validation moves overlaid, and the change
//! of every parameter in percent. Reads the folders with the one folder
//! reader ([`ResultFolder::read`]); the data files are optional (a folder
//! without them shows the table only).

use super::folder::ResultFolder;
use super::plot_data;
use crate::ident::FitModel;
use crate::record::commissioning::CommissioningRecord;
use crate::report::{BodeCurve, BodePlot, FrequencyMarker, MovePlot, Report, Table};
use crate::Result;
use std::path::Path;

/// Change from `a` to `b` in percent of `a` (`None` when `a` is 0 or missing).
pub fn change_percent(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if a != 0.0 => Some((b - a) / a.abs() * 100.0),
        _ => None,
    }
}

/// The comparison's summary line: the resonance and antiresonance of A and
/// B, Hz (`None` where a record has no finite value; such a value, and a
/// change against 0 Hz, is "unknown", never `NaN` or `inf`).
fn compare_summary(
    na: &str,
    nb: &str,
    f_r_hz: [Option<f64>; 2],
    f_z_hz: [Option<f64>; 2],
) -> String {
    let hz = |f: Option<f64>| f.map_or("unknown".to_string(), |f| format!("{f:.2} Hz"));
    let change = |[a, b]: [Option<f64>; 2]| {
        change_percent(a, b).map_or(String::new(), |c| format!(" ({c:+.1} %)"))
    };
    if f_r_hz.iter().chain(&f_z_hz).all(Option::is_none) {
        return format!("{na} against {nb}.");
    }
    format!(
        "{na} against {nb}. The resonance moved from {} to {}{}; the antiresonance from {} to {}{}.",
        hz(f_r_hz[0]),
        hz(f_r_hz[1]),
        change(f_r_hz),
        hz(f_z_hz[0]),
        hz(f_z_hz[1]),
        change(f_z_hz),
    )
}

/// A quantity of a record, in SI units (`None` where the record lacks it).
type Quantity = fn(&CommissioningRecord) -> Option<f64>;

/// The rows of the parameter table: (name, unit, quantity, scale to unit).
const ROWS: [(&str, &str, Quantity, f64); 20] = [
    ("resonance f_r", "Hz", |r| Some(r.identified.f_r_hz), 1.0),
    (
        "antiresonance f_z",
        "Hz",
        |r| Some(r.identified.f_z_hz),
        1.0,
    ),
    (
        "motor inertia Theta_e",
        "kg mm^2",
        |r| Some(r.identified.theta_e),
        1e6,
    ),
    ("moving mass m_c", "kg", |r| Some(r.identified.m_c), 1.0),
    ("belt stiffness c", "kN/m", |r| Some(r.identified.c), 1e-3),
    (
        "motor damping d_m",
        "N s/m",
        |r| Some(r.identified.d_m),
        1.0,
    ),
    ("cart damping d_c", "N s/m", |r| Some(r.identified.d_c), 1.0),
    (
        "dead time t_T",
        "ms",
        |r| Some(r.identified.dead_time_s),
        1e3,
    ),
    (
        "fit residual",
        "dB rms",
        |r| Some(r.identified.fit_rms_db),
        1.0,
    ),
    (
        "mean coherence",
        "",
        |r| Some(r.identified.mean_coherence),
        1.0,
    ),
    (
        "viscous friction d_v",
        "mN m s/rad",
        |r| r.friction.as_ref().map(|f| f.viscous_nm_s_per_rad),
        1e3,
    ),
    (
        "Coulomb friction tau_c",
        "N m",
        |r| r.friction.as_ref().map(|f| f.coulomb_nm),
        1.0,
    ),
    ("K_P", "N m s/rad", |r| r.controller.map(|c| c.k_p), 1.0),
    ("K_I", "N m/rad", |r| r.controller.map(|c| c.k_i), 1.0),
    ("K_PP", "1/s", |r| r.controller.map(|c| c.k_pp), 1.0),
    (
        "velocity crossover f_c",
        "Hz",
        |r| r.controller.map(|c| c.omega_c_velocity),
        1.0 / (2.0 * std::f64::consts::PI),
    ),
    (
        "velocity phase margin",
        "deg",
        |r| r.controller.map(|c| c.phase_margin_velocity_deg),
        1.0,
    ),
    (
        "position phase margin",
        "deg",
        |r| r.controller.map(|c| c.phase_margin_position_deg),
        1.0,
    ),
    (
        "max tracking error (nonlinear feedforward)",
        "mm",
        |r| delivered(r).map(|m| m.max_tracking_error_m),
        1e3,
    ),
    (
        "static error (nonlinear feedforward)",
        "um",
        |r| delivered(r).map(|m| m.static_error_m),
        1e6,
    ),
];

/// The delivered controller's move: the commissioning's (nonlinear
/// feedforward), or the simulated move of a set saved by the tuning page.
fn delivered(r: &CommissioningRecord) -> Option<&crate::commission::validation::MoveSummary> {
    r.delivered_move().or(r
        .tuning
        .as_ref()
        .and_then(|t| t.simulated_validation.as_ref()))
}

/// The parameter-change table of two commissionings.
pub fn parameter_changes(a: &CommissioningRecord, b: &CommissioningRecord) -> Table {
    let cell = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
    let rows = ROWS
        .iter()
        .map(|(name, unit, quantity, scale)| {
            let finite = |x: Option<f64>| x.filter(|v| v.is_finite()).map(|v| v * scale);
            let va = finite(quantity(a));
            let vb = finite(quantity(b));
            vec![
                name.to_string(),
                unit.to_string(),
                cell(va),
                cell(vb),
                change_percent(va, vb).map_or("-".to_string(), |c| format!("{c:+.2} %")),
            ]
        })
        .collect();
    Table {
        title: "Parameter changes (B against A)".into(),
        header: ["quantity", "unit", "A", "B", "change"]
            .map(String::from)
            .to_vec(),
        rows,
    }
}

/// Palette index of run A and of run B: the same in every plot.
const COLOR_A: usize = 0;
/// See [`COLOR_A`].
const COLOR_B: usize = 1;

fn labelled(mut c: BodeCurve, label: String, dots: bool, dashed: bool) -> BodeCurve {
    c.color_index = Some(if label.starts_with('B') {
        COLOR_B
    } else {
        COLOR_A
    });
    c.label = label;
    c.dots = dots;
    c.dashed = dashed;
    c
}

/// One run of a comparison: where it is, what it ran on, its verdict.
fn run_rows(a: &ResultFolder, b: &ResultFolder) -> Table {
    let payload = |c: &ResultFolder| -> String {
        let simulated = match &c.record.axis {
            Some(crate::record::commissioning::AxisRecord::Simulated { payload_kg, .. }) => {
                *payload_kg
            }
            _ => None,
        };
        simulated.map_or("-".to_string(), |p| format!("{p:.1} kg"))
    };
    let verdict = |c: &ResultFolder| -> String {
        c.record
            .verdict
            .as_ref()
            .map_or("-".to_string(), |v| v.text())
    };
    let kind = |c: &ResultFolder| -> String {
        if c.record.tuning.is_some() {
            "saved by the tuning page (simulated move)".into()
        } else {
            match &c.record.axis {
                Some(crate::record::commissioning::AxisRecord::Simulated { .. }) => {
                    "commissioning of a simulated axis".into()
                }
                Some(crate::record::commissioning::AxisRecord::Recorded { .. }) => {
                    "commissioning from a recording".into()
                }
                Some(_) => "commissioning on a drive".into(),
                None => "commissioning".into(),
            }
        }
    };
    let created = |c: &ResultFolder| -> String {
        match &c.record.tuning {
            Some(t) => t.provenance.created_utc.clone(),
            None => c
                .record
                .provenance
                .as_ref()
                .map_or("-".to_string(), |p| p.created_utc.clone()),
        }
    };
    let row = |name: &str, f: &dyn Fn(&ResultFolder) -> String| vec![name.to_string(), f(a), f(b)];
    Table {
        title: "The two runs".into(),
        header: ["", "A", "B"].map(String::from).to_vec(),
        rows: vec![
            row("folder", &|c| c.dir.display().to_string()),
            row("axis", &|c| c.record.plant.clone()),
            row("kind", &kind),
            row("payload", &payload),
            row("verdict", &verdict),
            row("created (UTC)", &created),
        ],
    }
}

/// The comparison report of folders `a` and `b`.
pub fn compare_report(a: &Path, b: &Path) -> Result<Report> {
    let ca = ResultFolder::read(a)?;
    let cb = ResultFolder::read(b)?;
    let name = |c: &ResultFolder, tag: &str| {
        let plant = if c.record.plant.is_empty() {
            "axis"
        } else {
            c.record.plant.as_str()
        };
        format!("{tag}: {} ({plant})", c.dir.display())
    };
    let (na, nb) = (name(&ca, "A"), name(&cb, "B"));
    let table = parameter_changes(&ca.record, &cb.record);
    let f_r = |c: &ResultFolder| Some(c.record.identified.f_r_hz).filter(|f| f.is_finite());
    let f_ra = f_r(&ca);
    let f_rb = f_r(&cb);
    let mut markers = Vec::new();
    for (tag, f) in [("A", f_ra), ("B", f_rb)] {
        if let Some(f) = f {
            markers.push(FrequencyMarker {
                label: format!("f_r {tag} {}", super::bode::hz_text(f)),
                freq_hz: f,
            });
        }
    }
    // both FRFs with their fits
    let mut frf_curves = Vec::new();
    for (tag, c) in [("A", &ca), ("B", &cb)] {
        if let Some(lines) = &c.data.frf {
            let id = &c.record.identified;
            let tf = FitModel::WithBeltDamping.tf(&id.params());
            let p = plot_data::frf_display(lines, &tf, id.dead_time_s, vec![])?;
            let used = |v: &[f64]| -> Vec<f64> {
                v.iter()
                    .zip(&p.usable)
                    .map(|(x, u)| if *u { *x } else { f64::NAN })
                    .collect()
            };
            let measured = BodeCurve {
                label: String::new(),
                freq_hz: p.measured.freq_hz.clone(),
                magnitude_db: used(&p.measured.magnitude_db),
                phase_deg: used(&p.measured.phase_deg),
                ..BodeCurve::default()
            };
            frf_curves.push(labelled(measured, format!("{tag} measured"), true, false));
            frf_curves.push(labelled(
                p.model,
                format!("{tag} fitted model"),
                false,
                tag == "B",
            ));
        }
    }
    let mut overlays = Vec::new();
    if !frf_curves.is_empty() {
        overlays.push(BodePlot {
            title: "Measured frequency responses and fits, A and B".into(),
            curves: frf_curves,
            markers: markers.clone(),
            ..BodePlot::default()
        });
    }
    if let (Some(la), Some(lb)) = (&ca.data.loops, &cb.data.loops) {
        overlays.push(BodePlot {
            title: "Velocity open loops, A and B".into(),
            curves: vec![
                labelled(la.velocity_open_loop.clone(), "A".into(), false, false),
                labelled(lb.velocity_open_loop.clone(), "B".into(), false, true),
            ],
            markers: markers.clone(),
            magnitude_lines_db: vec![0.0],
            phase_lines_deg: vec![-180.0],
            ..BodePlot::default()
        });
        overlays.push(BodePlot {
            title: "Closed position loops, A and B, magnitude".into(),
            curves: vec![
                labelled(la.position_closed_loop.clone(), "A".into(), false, false),
                labelled(lb.position_closed_loop.clone(), "B".into(), false, true),
            ],
            magnitude_lines_db: vec![0.0, -3.0],
            magnitude_only: true,
            ..BodePlot::default()
        });
    }
    let mut moves = Vec::new();
    for (tag, c) in [("A", &ca), ("B", &cb)] {
        // the delivered controller's move: nonlinear feedforward, or the only one
        let delivered = c
            .data
            .moves
            .iter()
            .find(|m| m.label == "nonlinear feedforward")
            .or(c.data.moves.last());
        if let Some(m) = delivered {
            moves.push(MovePlot {
                label: format!("{tag}: {}", m.label),
                // the motor-side panel needs data: the judged error again
                motor_error_m: m.cart_error_m.clone(),
                ..m.clone()
            });
        }
    }
    let summary = compare_summary(
        &na,
        &nb,
        [f_ra, f_rb],
        [&ca, &cb].map(|c| Some(c.record.identified.f_z_hz).filter(|f| f.is_finite())),
    );
    Ok(Report {
        title: "beltune comparison of two commissionings".into(),
        summary,
        tables: vec![run_rows(&ca, &cb), table],
        overlays,
        moves,
        provenance: Some(crate::record::provenance::Provenance::of_this_process(None)),
        ..Report::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn change_is_relative_to_a() {
        assert_eq!(change_percent(Some(100.0), Some(90.0)), Some(-10.0));
        assert_eq!(change_percent(Some(0.0), Some(1.0)), None);
        assert_eq!(change_percent(None, Some(1.0)), None);

        let record = |m_c: f64| {
            let p = crate::model::TwoMassParams::thesis_table_a4();
            let text = serde_json::json!({"identified": {
                "theta_e": p.theta_e, "m_c": m_c, "c": p.c, "d_m": p.d_m, "d_c": p.d_c, "i_t": p.i_t
            }})
            .to_string();
            CommissioningRecord::parse(&text, "test").unwrap()
        };
        let t = parameter_changes(&record(10.0), &record(12.5));
        assert_eq!(t.rows[3][4], "+25.00 %", "{:?}", t.rows[3]);
        assert_eq!(t.rows[12][4], "-", "missing controller");
    }

    #[test]
    fn a_folder_without_a_commissioning_is_an_error_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("beltune-compare-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = compare_report(&dir, &dir).unwrap_err().to_string();
        assert!(e.contains("commissioning.json"), "{e}");
        std::fs::write(dir.join("commissioning.json"), "{\"plant\": 1}").unwrap();
        let e = compare_report(&dir, &dir).unwrap_err().to_string();
        assert!(e.contains("identified"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_summary_never_prints_nan_or_inf() {
        let s = compare_summary("A", "B", [Some(0.0), Some(50.0)], [None, Some(20.0)]);
        assert!(!s.contains("NaN") && !s.contains("inf"), "{s}");
        assert!(s.contains("from unknown to 20.00 Hz"), "{s}");
        let s = compare_summary(
            "A",
            "B",
            [Some(100.0), Some(90.0)],
            [Some(50.0), Some(50.0)],
        );
        assert!(s.contains("100.00 Hz to 90.00 Hz (-10.0 %)"), "{s}");
    }
}
