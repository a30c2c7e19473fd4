//! `beltune compare A B` (issue 16): two commissioning folders side by side:
//! both measured FRFs and fits, the loops and the validation moves overlaid,
//! and the change of every parameter in percent. Reads only the files a
//! commissioning writes (`commissioning.json`, `frf.csv`, `loops.csv`,
//! `moves.csv`); the data files are optional (a folder without them shows the
//! table only).

use super::plot_data::{self as plots, FrfLines, LoopData, FRF_CSV, LOOPS_CSV, MOVES_CSV};
use crate::ident::FitModel;
use crate::report::{BodeCurve, BodePlot, FrequencyMarker, MovePlot, Report, Table};
use crate::{Error, Result};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One commissioning folder as read.
#[derive(Clone, Debug)]
pub struct Commissioned {
    /// The folder.
    pub dir: PathBuf,
    /// `commissioning.json`.
    pub json: Value,
    /// `frf.csv`, if present.
    pub frf: Option<FrfLines>,
    /// `loops.csv`, if present.
    pub loops: Option<LoopData>,
    /// `moves.csv`: time and the error of the move with nonlinear feedforward, if present.
    pub nonlinear_move: Option<MovePlot>,
}

/// Read a commissioning folder (typed errors naming the file).
pub fn read_commissioning(dir: &Path) -> Result<Commissioned> {
    let path = dir.join("commissioning.json");
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
        path: path.clone(),
        source,
    })?;
    let json: Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
        path: path.display().to_string(),
        message: format!("not valid JSON: {e}"),
    })?;
    if json.get("identified").and_then(|v| v.as_object()).is_none() {
        return Err(Error::Parse {
            path: path.display().to_string(),
            message: "no `identified` model: not a commissioning written by `beltune commission`"
                .into(),
        });
    }
    let frf = dir
        .join(FRF_CSV)
        .exists()
        .then(|| plots::read_frf_csv(&dir.join(FRF_CSV)))
        .transpose()?;
    let loops = dir
        .join(LOOPS_CSV)
        .exists()
        .then(|| plots::read_loops_csv(&dir.join(LOOPS_CSV)))
        .transpose()?;
    let moves_path = dir.join(MOVES_CSV);
    let nonlinear_move = if moves_path.exists() {
        let names = [
            "time_s",
            "desired_m",
            "error_nonlinear_feedforward_m",
            "torque_nonlinear_feedforward_nm",
        ];
        let cols = crate::ident::read_csv_columns(&moves_path, &names)?;
        let col = |n: &str| cols.column(n).map(|c| c.to_vec()).unwrap_or_default();
        Some(MovePlot {
            label: String::new(),
            time_s: col("time_s"),
            desired_m: col("desired_m"),
            cart_error_m: col("error_nonlinear_feedforward_m"),
            motor_error_m: Vec::new(),
            torque_nm: col("torque_nonlinear_feedforward_nm"),
        })
    } else {
        None
    };
    Ok(Commissioned {
        dir: dir.to_path_buf(),
        json,
        frf,
        loops,
        nonlinear_move,
    })
}

fn number(v: &Value, path: &[&str]) -> Option<f64> {
    let mut cur = v;
    for k in path {
        cur = cur.get(k)?;
    }
    cur.as_f64().filter(|x| x.is_finite())
}

/// Change from `a` to `b` in percent of `a` (`None` when `a` is 0 or missing).
pub fn change_percent(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if a != 0.0 => Some((b - a) / a.abs() * 100.0),
        _ => None,
    }
}

/// The rows of the parameter table: (name, unit, JSON path, scale to unit).
const ROWS: [(&str, &str, &[&str], f64); 20] = [
    ("resonance f_r", "Hz", &["identified", "f_r_hz"], 1.0),
    ("antiresonance f_z", "Hz", &["identified", "f_z_hz"], 1.0),
    (
        "motor inertia Theta_e",
        "kg mm^2",
        &["identified", "theta_e"],
        1e6,
    ),
    ("moving mass m_c", "kg", &["identified", "m_c"], 1.0),
    ("belt stiffness c", "kN/m", &["identified", "c"], 1e-3),
    ("motor damping d_m", "N s/m", &["identified", "d_m"], 1.0),
    ("cart damping d_c", "N s/m", &["identified", "d_c"], 1.0),
    ("dead time t_T", "ms", &["identified", "dead_time_s"], 1e3),
    ("fit residual", "dB rms", &["identified", "fit_rms_db"], 1.0),
    ("mean coherence", "", &["identified", "mean_coherence"], 1.0),
    (
        "viscous friction d_v",
        "mN m s/rad",
        &["friction", "viscous_nm_s_per_rad"],
        1e3,
    ),
    (
        "Coulomb friction tau_c",
        "N m",
        &["friction", "coulomb_nm"],
        1.0,
    ),
    ("K_P", "N m s/rad", &["controller", "k_p"], 1.0),
    ("K_I", "N m/rad", &["controller", "k_i"], 1.0),
    ("K_PP", "1/s", &["controller", "k_pp"], 1.0),
    (
        "velocity crossover f_c",
        "Hz",
        &["controller", "omega_c_velocity"],
        1.0 / (2.0 * std::f64::consts::PI),
    ),
    (
        "velocity phase margin",
        "deg",
        &["controller", "phase_margin_velocity_deg"],
        1.0,
    ),
    (
        "position phase margin",
        "deg",
        &["controller", "phase_margin_position_deg"],
        1.0,
    ),
    (
        "max tracking error (nonlinear feedforward)",
        "mm",
        &["validation", "nonlinear", "max_tracking_error_m"],
        1e3,
    ),
    (
        "static error (nonlinear feedforward)",
        "um",
        &["validation", "nonlinear", "static_error_m"],
        1e6,
    ),
];

/// The parameter-change table of two commissionings.
pub fn parameter_changes(a: &Value, b: &Value) -> Table {
    let cell = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
    let rows = ROWS
        .iter()
        .map(|(name, unit, path, scale)| {
            let va = number(a, path).map(|v| v * scale);
            let vb = number(b, path).map(|v| v * scale);
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

fn model_tf(json: &Value) -> Option<(crate::lti::Tf, f64)> {
    let id: crate::commission::result::IdentifiedModel =
        serde_json::from_value(json.get("identified")?.clone()).ok()?;
    Some((FitModel::WithBeltDamping.tf(&id.params()), id.dead_time_s))
}

fn labelled(mut c: BodeCurve, label: String, dots: bool, dashed: bool) -> BodeCurve {
    c.label = label;
    c.dots = dots;
    c.dashed = dashed;
    c
}

/// The comparison report of folders `a` and `b`.
pub fn compare_report(a: &Path, b: &Path) -> Result<Report> {
    let ca = read_commissioning(a)?;
    let cb = read_commissioning(b)?;
    let name = |c: &Commissioned, tag: &str| {
        let plant = c
            .json
            .get("plant")
            .and_then(|p| p.as_str())
            .unwrap_or("axis");
        format!("{tag}: {} ({plant})", c.dir.display())
    };
    let (na, nb) = (name(&ca, "A"), name(&cb, "B"));
    let table = parameter_changes(&ca.json, &cb.json);
    let f_r = |c: &Commissioned| number(&c.json, &["identified", "f_r_hz"]);
    let f_ra = f_r(&ca);
    let f_rb = f_r(&cb);
    let mut markers = Vec::new();
    for (tag, f) in [("A", f_ra), ("B", f_rb)] {
        if let Some(f) = f {
            markers.push(FrequencyMarker {
                label: format!("f_r {tag} {}", super::build::hz_text(f)),
                freq_hz: f,
            });
        }
    }
    // both FRFs with their fits
    let mut frf_curves = Vec::new();
    for (tag, c) in [("A", &ca), ("B", &cb)] {
        if let (Some(lines), Some((tf, dt))) = (&c.frf, model_tf(&c.json)) {
            let p = plots::frf_display(lines, &tf, dt, vec![])?;
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
    if let (Some(la), Some(lb)) = (&ca.loops, &cb.loops) {
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
        if let Some(m) = &c.nonlinear_move {
            moves.push(MovePlot {
                label: format!("{tag}: nonlinear feedforward"),
                // the motor-side panel needs data: the judged error again
                motor_error_m: m.cart_error_m.clone(),
                ..m.clone()
            });
        }
    }
    let summary = match (f_ra, f_rb) {
        (Some(x), Some(y)) => format!(
            "{na} against {nb}. The resonance moved from {x:.2} Hz to {y:.2} Hz ({:+.1} %); \
             the antiresonance from {:.2} Hz to {:.2} Hz.",
            (y - x) / x * 100.0,
            number(&ca.json, &["identified", "f_z_hz"]).unwrap_or(f64::NAN),
            number(&cb.json, &["identified", "f_z_hz"]).unwrap_or(f64::NAN),
        ),
        _ => format!("{na} against {nb}."),
    };
    Ok(Report {
        title: "beltune comparison of two commissionings".into(),
        summary,
        tables: vec![table],
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
        let a = serde_json::json!({"identified": {"f_r_hz": 100.0}});
        let b = serde_json::json!({"identified": {"f_r_hz": 125.0}});
        let t = parameter_changes(&a, &b);
        assert_eq!(t.rows[0][4], "+25.00 %");
        assert_eq!(t.rows[1][4], "-", "missing value");
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
}
