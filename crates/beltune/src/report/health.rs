//! The pages of the health of an axis, made with the report's one page
//! ([`super::render_html`]) and SVG engine ([`super::plot`]): a health
//! check's `report.html` ([`health_report`], written with `health.json` as
//! one set by [`HealthSet`]), and the history of the runs with each
//! quantity's trend and its limits ([`history_report`]).

use super::data::{Report, Table, TrendPlot};
use crate::health::Quantity;
use crate::history::{RunKind, RunRow};
use crate::record::folder::OutputTarget;
use crate::record::health::{HealthRecord, HEALTH_FILE};
use crate::record::REPORT_FILE;
use crate::Result;
use std::path::PathBuf;

/// A value and its uncertainty with four significant digits.
fn pm(value: f64, sigma: f64) -> String {
    if sigma.is_finite() {
        format!("{value:.4e} +- {sigma:.1e}")
    } else {
        format!("{value:.4e}")
    }
}

/// The limits of a change as text.
fn limits_text(lower: Option<f64>, upper: Option<f64>, relative: bool) -> String {
    let f = |x: f64| {
        if relative {
            format!("{:+.1} %", 100.0 * x)
        } else {
            format!("{x:+.3}")
        }
    };
    match (lower, upper) {
        (Some(l), Some(u)) => format!("{} .. {}", f(l), f(u)),
        (Some(l), None) => format!("above {}", f(l)),
        (None, Some(u)) => format!("below {}", f(u)),
        (None, None) => "none".into(),
    }
}

/// The summary line of a health check.
pub fn health_summary(rec: &HealthRecord) -> String {
    let c = &rec.check;
    let head = format!(
        "health of {}: {} ({} quantities against the commissioning in {}; axis busy {:.2} s)",
        rec.axis,
        c.status.word(),
        c.comparisons.len(),
        rec.baseline_dir,
        c.experiment_time_s
    );
    if rec.recommendations.is_empty() {
        format!("{head}. Every quantity is within its limits.")
    } else {
        format!("{head}. {}", rec.recommendations.join(". "))
    }
}

/// The report of a health check.
pub fn health_report(rec: &HealthRecord) -> Report {
    let c = &rec.check;
    let mut tables = vec![Table {
        title: "Each quantity against the baseline".into(),
        header: [
            "quantity", "unit", "at / mm", "baseline", "measured", "change", "limits", "verdict",
        ]
        .map(String::from)
        .to_vec(),
        rows: c
            .comparisons
            .iter()
            .map(|q| {
                vec![
                    q.quantity.description().to_string(),
                    q.quantity.unit().to_string(),
                    q.position_m
                        .map(|x| format!("{:.1}", x * 1e3))
                        .unwrap_or_default(),
                    pm(q.baseline.value, q.baseline.sigma),
                    pm(q.measured.value, q.measured.sigma),
                    q.change_text(),
                    limits_text(q.limit.lower, q.limit.upper, q.limit.relative),
                    q.status.word().to_string(),
                ]
            })
            .collect(),
    }];
    if !rec.recommendations.is_empty() {
        tables.insert(
            0,
            Table {
                title: "Recommendations".into(),
                header: vec!["what to do".into()],
                rows: rec
                    .recommendations
                    .iter()
                    .map(|r| vec![r.clone()])
                    .collect(),
            },
        );
    }
    let m = &c.measured;
    tables.push(Table {
        title: "Excitation blocks".into(),
        header: [
            "block",
            "at / mm",
            "A_PRBS / N m",
            "f_r / Hz",
            "f_z / Hz",
            "c / (kN/m)",
            "m_c / kg",
            "fit",
        ]
        .map(String::from)
        .to_vec(),
        rows: [
            ("far", m.far.as_ref()),
            ("far, half amplitude", m.far_half.as_ref()),
            ("near", m.near.as_ref()),
        ]
        .into_iter()
        .filter_map(|(name, f)| {
            f.map(|f| {
                vec![
                    name.to_string(),
                    format!("{:.1}", f.position_m * 1e3),
                    format!("{:.3}", f.amplitude_nm),
                    format!("{:.2}", f.f_r_hz()),
                    format!("{:.2}", f.f_z_hz()),
                    format!("{:.1}", f.params.c / 1e3),
                    format!(
                        "{:.2}{}",
                        f.params.m_c,
                        if f.mass_held { " (held)" } else { "" }
                    ),
                    format!("{:?}", f.method),
                ]
            })
        })
        .chain(m.failures.iter().map(|f| {
            let mut row = vec![String::new(); 8];
            row[0] = format!("not fitted: {f}");
            row
        }))
        .collect(),
    });
    tables.push(Table {
        title: "Friction runs".into(),
        header: [
            "from / mm",
            "to / mm",
            "motor velocity / (rad/s)",
            "mean torque / N m",
            "standard error / N m",
        ]
        .map(String::from)
        .to_vec(),
        rows: m
            .runs
            .iter()
            .map(|r| {
                vec![
                    format!("{:.1}", r.from_m * 1e3),
                    format!("{:.1}", r.to_m * 1e3),
                    format!("{:.2}", r.velocity_rad_s),
                    format!("{:.4}", r.mean_torque_nm),
                    format!("{:.1e}", r.sigma_nm),
                ]
            })
            .collect(),
    });
    Report {
        title: format!("beltune health report: {}", rec.axis),
        summary: health_summary(rec),
        log: c.log.clone(),
        provenance: Some(rec.provenance.clone()),
        tables,
        ..Default::default()
    }
}

/// A health check's folder: `health.json` and `report.html`, written together.
pub struct HealthSet {
    /// `health.json`.
    pub record: HealthRecord,
    /// `report.html`, as data.
    pub report: Report,
}

impl HealthSet {
    /// The set of `record`.
    pub fn of(record: HealthRecord) -> HealthSet {
        let report = health_report(&record);
        HealthSet { record, report }
    }

    /// The files as (name, contents).
    pub fn files(&self) -> Result<Vec<(String, Vec<u8>)>> {
        Ok(vec![
            (
                HEALTH_FILE.to_string(),
                self.record.to_json_text()?.into_bytes(),
            ),
            (
                REPORT_FILE.to_string(),
                super::render_html(&self.report)?.into_bytes(),
            ),
        ])
    }

    /// Write the set to `target`, all files together or none.
    pub fn write(&self, target: &OutputTarget) -> Result<Vec<PathBuf>> {
        target.write(&self.files()?)
    }
}

/// The history page: the runs, and per axis each quantity's trend with the
/// latest health check's baseline and limits.
pub fn history_report(title: &str, runs: &[RunRow]) -> Report {
    let table = Table {
        title: "Runs".into(),
        header: [
            "run",
            "axis",
            "kind",
            "created (UTC)",
            "verdict",
            "folder",
            "recommendations",
        ]
        .map(String::from)
        .to_vec(),
        rows: runs
            .iter()
            .map(|r| {
                vec![
                    r.id.to_string(),
                    r.run.axis.clone(),
                    r.run.kind.key().to_string(),
                    r.run.created_utc.clone(),
                    r.run.status.clone(),
                    r.run.result_dir.clone().unwrap_or_default(),
                    match r.run.recommendations.as_slice() {
                        [] => String::new(),
                        [one] => one.clone(),
                        [first, rest @ ..] => format!("{first} (and {} more)", rest.len()),
                    },
                ]
            })
            .collect(),
    };
    let mut axes: Vec<&str> = runs.iter().map(|r| r.run.axis.as_str()).collect();
    axes.sort();
    axes.dedup();
    let mut trends = Vec::new();
    for axis in &axes {
        let of_axis: Vec<&RunRow> = runs.iter().filter(|r| r.run.axis == *axis).collect();
        for q in Quantity::ALL {
            if let Some(t) = trend(axis, q, &of_axis) {
                trends.push(t);
            }
        }
    }
    let acting = runs
        .iter()
        .filter(|r| r.run.kind == RunKind::Health && r.run.status == "act")
        .count();
    Report {
        title: title.to_string(),
        summary: format!(
            "{} runs of {} axes; {} health checks ask for action",
            runs.len(),
            axes.len(),
            acting
        ),
        tables: vec![table],
        trends,
        ..Default::default()
    }
}

/// The trend of `q` over `runs` of one axis (`None` where no run has it).
fn trend(axis: &str, q: Quantity, runs: &[&RunRow]) -> Option<TrendPlot> {
    let mut t = TrendPlot {
        title: format!("{axis}: {} / {}", q.description(), q.unit()),
        unit: q.unit().to_string(),
        ..Default::default()
    };
    let mut latest = None;
    for (k, r) in runs.iter().enumerate() {
        let Some(row) = r.run.quantities.iter().find(|x| x.name == q.key()) else {
            continue;
        };
        let x = (k + 1) as f64;
        match r.run.kind {
            RunKind::Commissioning => {
                t.commissioning_run.push(x);
                t.commissioning_value.push(row.value);
            }
            RunKind::Health => {
                t.health_run.push(x);
                t.health_value.push(row.value);
                t.health_sigma.push(row.sigma);
                latest = Some(row);
            }
        }
    }
    if t.commissioning_run.is_empty() && t.health_run.is_empty() {
        return None;
    }
    if let Some(row) = latest {
        if row.baseline.is_finite() {
            t.baseline = Some(row.baseline);
            let relative = row.limit_relative.unwrap_or(true);
            for (label, l) in [("lower", row.limit_lower), ("upper", row.limit_upper)] {
                if l.is_finite() {
                    let v = if relative {
                        row.baseline * (1.0 + l)
                    } else {
                        row.baseline + l
                    };
                    t.limits.push((label.to_string(), v));
                }
            }
        }
    }

    Some(t)
}
