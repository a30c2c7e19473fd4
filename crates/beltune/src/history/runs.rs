//! What a run stores in the history: the run (axis, kind, time, status,
//! folders, the record as JSON) and one row per quantity, under the keys of
//! [`crate::health::Quantity`] so that commissioning and health runs make
//! one trend per quantity.

use super::{Column, HistoryDb, Value, Writer};
use crate::health::{Comparison, HealthCheck, Quantity};
use crate::record::commissioning::CommissioningRecord;
use crate::Result;
use serde::{Deserialize, Serialize};

/// Which kind of run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunKind {
    /// `beltune commission`.
    Commissioning,
    /// `beltune health`.
    Health,
}

impl RunKind {
    /// The stored word.
    pub fn key(self) -> &'static str {
        match self {
            RunKind::Commissioning => "commissioning",
            RunKind::Health => "health",
        }
    }
}

/// One quantity of a run (units in [`Self::unit`]; relative changes and
/// limits are fractions).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuantityRow {
    /// [`Quantity::key`].
    pub name: String,
    /// SI unit of the value.
    pub unit: String,
    /// The value.
    pub value: f64,
    /// Its one-sigma uncertainty (NaN: unknown).
    pub sigma: f64,
    /// The baseline it was compared with (health runs).
    pub baseline: f64,
    /// Its uncertainty.
    pub baseline_sigma: f64,
    /// The change (relative or absolute as the limit).
    pub change: f64,
    /// Its uncertainty.
    pub change_sigma: f64,
    /// The lower limit of the change (NaN: none).
    pub limit_lower: f64,
    /// The upper limit of the change (NaN: none).
    pub limit_upper: f64,
    /// Whether the change and the limits are fractions of the baseline.
    pub limit_relative: Option<bool>,
    /// `ok`, `watch` or `act` (health runs).
    pub status: Option<String>,
    /// Where it was measured, m.
    pub position_m: f64,
}

impl QuantityRow {
    /// A measured value without a comparison.
    pub fn value(q: Quantity, value: f64, sigma: f64, position_m: f64) -> QuantityRow {
        let nan = f64::NAN;
        QuantityRow {
            name: q.key().to_string(),
            unit: q.unit().to_string(),
            value,
            sigma,
            baseline: nan,
            baseline_sigma: nan,
            change: nan,
            change_sigma: nan,
            limit_lower: nan,
            limit_upper: nan,
            limit_relative: None,
            status: None,
            position_m,
        }
    }

    /// A health check's comparison.
    pub fn of_comparison(c: &Comparison) -> QuantityRow {
        QuantityRow {
            baseline: c.baseline.value,
            baseline_sigma: c.baseline.sigma,
            change: c.change,
            change_sigma: c.change_sigma,
            limit_lower: c.limit.lower.unwrap_or(f64::NAN),
            limit_upper: c.limit.upper.unwrap_or(f64::NAN),
            limit_relative: Some(c.limit.relative),
            status: Some(
                serde_json::to_value(c.status)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default(),
            ),
            ..QuantityRow::value(
                c.quantity,
                c.measured.value,
                c.measured.sigma,
                c.position_m.unwrap_or(f64::NAN),
            )
        }
    }
}

/// A run to record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NewRun {
    /// The axis' name.
    pub axis: String,
    /// Which kind.
    pub kind: RunKind,
    /// When it ran (RFC 3339, UTC).
    pub created_utc: String,
    /// Its verdict: `pass`/`fail` (commissioning), `ok`/`watch`/`act` (health).
    pub status: String,
    /// Its result folder.
    pub result_dir: Option<String>,
    /// The baseline's folder (health runs).
    pub baseline_dir: Option<String>,
    /// Who wrote it.
    pub beltune_version: String,
    /// How long the axis was busy, s.
    pub experiment_time_s: f64,
    /// The run's record as JSON (`commissioning.json`, `health.json`).
    pub record_json: String,
    /// Its recommendations (health runs).
    pub recommendations: Vec<String>,
    /// Its quantities.
    pub quantities: Vec<QuantityRow>,
}

impl NewRun {
    /// A commissioning: the quantities a health check compares with, where
    /// it measured them (the stiffness near the start from its profile at
    /// the start-side position `near_m`, if given).
    pub fn of_commissioning(
        axis: &str,
        record: &CommissioningRecord,
        result_dir: Option<String>,
        near_m: Option<f64>,
    ) -> Result<NewRun> {
        let id = &record.identified;
        let c_rel = id.c_sigma / id.c;
        let (fr, fz) =
            crate::health::baseline::resonances(&id.params(), c_rel, id.m_c_sigma / id.m_c);
        let at = record.identification_position_m.unwrap_or(id.position_m);
        let mut q = vec![
            QuantityRow::value(Quantity::StiffnessFar, id.c, id.c_sigma, at),
            QuantityRow::value(Quantity::ResonanceFar, fr.value, fr.sigma, at),
            QuantityRow::value(Quantity::AntiresonanceFar, fz.value, fz.sigma, at),
            QuantityRow::value(Quantity::MovingMass, id.m_c, id.m_c_sigma, f64::NAN),
        ];
        if let (Some(profile), Some(x)) = (&record.target_stiffness, near_m) {
            let c = profile.stiffness_at(x);
            let p = crate::model::TwoMassParams { c, ..id.params() };
            let (fr, fz) = crate::health::baseline::resonances(&p, c_rel, id.m_c_sigma / id.m_c);
            q.push(QuantityRow::value(Quantity::StiffnessNear, c, c * c_rel, x));
            q.push(QuantityRow::value(
                Quantity::ResonanceNear,
                fr.value,
                fr.sigma,
                x,
            ));
            q.push(QuantityRow::value(
                Quantity::AntiresonanceNear,
                fz.value,
                fz.sigma,
                x,
            ));
        }
        if let Some(p) = record.frf_fit {
            q.push(QuantityRow::value(
                Quantity::ResonanceDamping,
                p.resonance_damping_ratio(),
                f64::NAN,
                at,
            ));
        }
        if let Some(f) = &record.friction {
            let nan = f64::NAN;
            q.push(QuantityRow::value(
                Quantity::CoulombFriction,
                f.coulomb_nm,
                nan,
                nan,
            ));
            q.push(QuantityRow::value(
                Quantity::ViscousFriction,
                f.viscous_nm_s_per_rad,
                nan,
                nan,
            ));
            q.push(QuantityRow::value(
                Quantity::HoldingTorque,
                f.holding_torque_nm,
                nan,
                nan,
            ));
        }
        let passed = record.verdict.as_ref().is_some_and(|v| v.passed);
        let provenance = record.provenance.as_ref();
        Ok(NewRun {
            axis: axis.to_string(),
            kind: RunKind::Commissioning,
            created_utc: provenance.map_or_else(super::now_utc, |p| p.created_utc.clone()),
            status: if passed { "pass" } else { "fail" }.to_string(),
            result_dir,
            baseline_dir: None,
            beltune_version: provenance.map_or_else(
                || env!("CARGO_PKG_VERSION").to_string(),
                |p| p.beltune_version.clone(),
            ),
            experiment_time_s: record.experiment_time_s.unwrap_or(f64::NAN),
            record_json: record.to_json_text()?,
            recommendations: Vec::new(),
            quantities: q,
        })
    }

    /// A health check of `axis` against the baseline in `baseline_dir`.
    pub fn of_health(
        axis: &str,
        check: &HealthCheck,
        record_json: String,
        result_dir: Option<String>,
        baseline_dir: String,
    ) -> NewRun {
        NewRun {
            axis: axis.to_string(),
            kind: RunKind::Health,
            created_utc: super::now_utc(),
            status: serde_json::to_value(check.status)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default(),
            result_dir,
            baseline_dir: Some(baseline_dir),
            beltune_version: env!("CARGO_PKG_VERSION").to_string(),
            experiment_time_s: check.experiment_time_s,
            record_json,
            recommendations: check.recommendations(),
            quantities: check
                .comparisons
                .iter()
                .map(QuantityRow::of_comparison)
                .collect(),
        }
    }
}

/// A recorded run as read back.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRow {
    /// Its number.
    pub id: i64,
    /// The run as recorded (the record's JSON is left out: see
    /// [`NewRun::record_json`]).
    #[serde(flatten)]
    pub run: NewRun,
}

fn opt_text(s: &Option<String>) -> Value {
    Value::Text(s.clone())
}

fn opt_real(x: f64) -> Value {
    Value::real(x)
}

/// Insert `run` (module docs) within the transaction of `w`.
pub(crate) fn insert_run(w: &mut Writer<'_>, run: &NewRun) -> Result<i64> {
    w.execute(
        "INSERT INTO axes (name, created_utc) VALUES ($1, $2) ON CONFLICT (name) DO NOTHING",
        &[Value::text(&run.axis), Value::text(&run.created_utc)],
    )?;
    let rows = w.query(
        "INSERT INTO runs (axis, kind, created_utc, status, result_dir, baseline_dir, beltune_version, experiment_time_s, record, recommendations) \
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10) RETURNING id",
        &[
            Value::text(&run.axis),
            Value::text(run.kind.key()),
            Value::text(&run.created_utc),
            Value::text(&run.status),
            opt_text(&run.result_dir),
            opt_text(&run.baseline_dir),
            Value::text(&run.beltune_version),
            opt_real(run.experiment_time_s),
            Value::text(&run.record_json),
            Value::text(serde_json::to_string(&run.recommendations).unwrap_or_else(|_| "[]".into())),
        ],
        &[Column::Int],
    )?;
    let id = rows
        .first()
        .and_then(|r| r[0].as_i64())
        .ok_or_else(|| crate::Error::Database {
            location: String::new(),
            reason: "the new run got no number".into(),
        })?;
    for q in &run.quantities {
        w.execute(
            "INSERT INTO quantities (run_id, name, unit, value, sigma, baseline, baseline_sigma, change, change_sigma, limit_lower, limit_upper, limit_relative, status, position_m) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14)",
            &[
                Value::Int(Some(id)),
                Value::text(&q.name),
                Value::text(&q.unit),
                opt_real(q.value),
                opt_real(q.sigma),
                opt_real(q.baseline),
                opt_real(q.baseline_sigma),
                opt_real(q.change),
                opt_real(q.change_sigma),
                opt_real(q.limit_lower),
                opt_real(q.limit_upper),
                Value::Int(q.limit_relative.map(i64::from)),
                opt_text(&q.status),
                opt_real(q.position_m),
            ],
        )?;
    }
    Ok(id)
}

/// The runs of `axis` (or all), oldest first, with their quantities.
pub(crate) fn read_runs(db: &mut HistoryDb, axis: Option<&str>) -> Result<Vec<RunRow>> {
    use Column::*;
    let cols = [Int, Text, Text, Text, Text, Text, Text, Text, Real, Text];
    let select = "SELECT id, axis, kind, created_utc, status, result_dir, baseline_dir, beltune_version, experiment_time_s, recommendations FROM runs";
    let rows = match axis {
        Some(a) => db.query(
            &format!("{select} WHERE axis = $1 ORDER BY id"),
            &[Value::text(a)],
            &cols,
        )?,
        None => db.query(&format!("{select} ORDER BY id"), &[], &cols)?,
    };
    let qcols = [
        Int, Text, Text, Real, Real, Real, Real, Real, Real, Real, Real, Int, Text, Real,
    ];
    let qselect = "SELECT run_id, name, unit, value, sigma, baseline, baseline_sigma, change, change_sigma, limit_lower, limit_upper, limit_relative, status, position_m FROM quantities";
    let qrows = match axis {
        Some(a) => db.query(
            &format!("{qselect} WHERE run_id IN (SELECT id FROM runs WHERE axis = $1) ORDER BY run_id, name"),
            &[Value::text(a)],
            &qcols,
        )?,
        None => db.query(&format!("{qselect} ORDER BY run_id, name"), &[], &qcols)?,
    };
    let text = |v: &Value| v.as_str().unwrap_or_default().to_string();
    let mut out: Vec<RunRow> = rows
        .iter()
        .map(|r| RunRow {
            id: r[0].as_i64().unwrap_or_default(),
            run: NewRun {
                axis: text(&r[1]),
                kind: if r[2].as_str() == Some("health") {
                    RunKind::Health
                } else {
                    RunKind::Commissioning
                },
                created_utc: text(&r[3]),
                status: text(&r[4]),
                result_dir: r[5].as_str().map(str::to_string),
                baseline_dir: r[6].as_str().map(str::to_string),
                beltune_version: text(&r[7]),
                experiment_time_s: r[8].as_f64(),
                record_json: String::new(),
                recommendations: r[9]
                    .as_str()
                    .and_then(|s| serde_json::from_str(s).ok())
                    .unwrap_or_default(),
                quantities: Vec::new(),
            },
        })
        .collect();
    for q in qrows {
        let id = q[0].as_i64().unwrap_or_default();
        if let Some(run) = out.iter_mut().find(|r| r.id == id) {
            run.run.quantities.push(QuantityRow {
                name: text(&q[1]),
                unit: text(&q[2]),
                value: q[3].as_f64(),
                sigma: q[4].as_f64(),
                baseline: q[5].as_f64(),
                baseline_sigma: q[6].as_f64(),
                change: q[7].as_f64(),
                change_sigma: q[8].as_f64(),
                limit_lower: q[9].as_f64(),
                limit_upper: q[10].as_f64(),
                limit_relative: q[11].as_i64().map(|x| x != 0),
                status: q[12].as_str().map(str::to_string),
                position_m: q[13].as_f64(),
            });
        }
    }
    Ok(out)
}
