//! The summary `beltune commission` prints on stdout: a few lines that fit
//! [`term::WIDTH`] columns, or with `--json` one JSON object.
//!
//! The JSON keys are a stable interface (schema [`SCHEMA`]): keys are added,
//! never renamed or removed, within one schema version. Every quantity is in
//! SI units named by its key's suffix. Top-level keys:
//!
//! | key | meaning |
//! | --- | --- |
//! | `schema` | `"beltune-commission-summary/2"` |
//! | `source` | the plant name or file, the drive, or the recorded CSV |
//! | `status` | `"ok"`, `"not_validated"` (recorded data: no move) or `"limits_not_met"` |
//! | `exit_code` | the status the command exits with (0 or 5) |
//! | `identified` | `f_r_hz`, `f_z_hz`, `theta_e_kg_m2`, `m_c_kg`, `c_n_per_m`, `d_m_n_s_per_m`, `d_c_n_s_per_m`, `dead_time_s`, `fit_rms_db`, `mean_coherence` |
//! | `truth` | simulated plants: `f_r_hz`, `f_z_hz`, `m_c_kg`, `c_n_per_m`; `null` for recorded data |
//! | `controller` | `k_p_nm_s_per_rad`, `k_i_nm_per_rad`, `k_pp_per_s`, `velocity_crossover_hz`, `velocity_phase_margin_deg`, `position_crossover_hz`, `position_phase_margin_deg`, `gain_at_resonance_db` |
//! | `validation` | `start_m`, `target_m` (the move that ran), `max_tracking_error_none_m`, `max_tracking_error_linear_m` (`null` unless run with `--compare-feedforward`), `max_tracking_error_nonlinear_m`, `static_error_nonlinear_m`, `settling_time_nonlinear_s` (or `null`); `null` for recorded data |
//! | `verdict` | the library's verdict, as in `commissioning.json`: `passed`, `validated_on`, `checks` (each `name`, `value`, `limit`, `unit`, `below`, `passed`), `warnings`, `next_step` |
//! | `axis_busy_s` | time the axis was busy (`null` for recorded data) |
//! | `stage_axis_times` | the axis time of each stage in the order they ran, each `stage`, `axis_time_s` (they add up to `axis_busy_s`; empty for recorded data) |
//! | `computation_s`, `wall_time_s` | computing time, elapsed time of the command |
//! | `files` | the files written |
//!
//! For recorded data (`--csv`) the identified masses, stiffness and gains are
//! in the units of the record's input column (N m, or A for a current
//! record); the text form then prints them without units.

//!
//! Everything here is read from the record the run wrote
//! ([`CommissioningRecord`]), so the terminal, `--json`, `commissioning.json`
//! and the report say the same.

use crate::term;
use beltune::commission::validation::Validation;
use beltune::design::DesignSummary;
use beltune::record::commissioning::{AxisRecord, CommissioningRecord, ValidationMove};
use beltune::record::model::IdentifiedModel;
use beltune::sim::Truth;
use beltune::verdict::Verdict;
use serde::Serialize;
use std::f64::consts::PI;
use std::path::PathBuf;

/// The schema name and version of the JSON summary.
pub const SCHEMA: &str = "beltune-commission-summary/2";

/// Columns of the label in front of a summary line.
const LABEL_WIDTH: usize = 10;

/// The identified model, SI units.
#[derive(Clone, Debug, Serialize)]
pub struct IdentifiedSummary {
    /// Resonance (2.44), Hz.
    pub f_r_hz: f64,
    /// Antiresonance (2.45), Hz.
    pub f_z_hz: f64,
    /// Motor-side inertia, kg m^2.
    pub theta_e_kg_m2: f64,
    /// Moving mass, kg.
    pub m_c_kg: f64,
    /// Belt stiffness, N/m.
    pub c_n_per_m: f64,
    /// Motor damping (translational), N s/m.
    pub d_m_n_s_per_m: f64,
    /// Cart damping, N s/m.
    pub d_c_n_s_per_m: f64,
    /// Dead time, s.
    pub dead_time_s: f64,
    /// RMS magnitude error of the fit, dB.
    pub fit_rms_db: f64,
    /// Mean coherence over the fitted lines.
    pub mean_coherence: f64,
}

/// The truth of a simulated plant at the identification position.
#[derive(Clone, Debug, Serialize)]
pub struct TruthSummary {
    /// Resonance, Hz.
    pub f_r_hz: f64,
    /// Antiresonance, Hz.
    pub f_z_hz: f64,
    /// Moving mass, kg.
    pub m_c_kg: f64,
    /// Belt stiffness, N/m.
    pub c_n_per_m: f64,
}

/// The designed controller.
#[derive(Clone, Debug, Serialize)]
pub struct ControllerSummary {
    /// Velocity-loop gain, N m s/rad.
    pub k_p_nm_s_per_rad: f64,
    /// Velocity-loop integral gain, N m/rad.
    pub k_i_nm_per_rad: f64,
    /// Position-loop gain, 1/s.
    pub k_pp_per_s: f64,
    /// Velocity-loop crossover, Hz.
    pub velocity_crossover_hz: f64,
    /// Velocity-loop phase margin, deg.
    pub velocity_phase_margin_deg: f64,
    /// Position-loop crossover, Hz.
    pub position_crossover_hz: f64,
    /// Position-loop phase margin, deg.
    pub position_phase_margin_deg: f64,
    /// Open-loop gain at the resonance, dB.
    pub gain_at_resonance_db: f64,
}

/// The validation move with the three feedforward variants.
#[derive(Clone, Debug, Serialize)]
pub struct ValidationSummary {
    /// Start of the move, m.
    pub start_m: f64,
    /// Target of the move, m.
    pub target_m: f64,
    /// Largest cart error without feedforward, m (`None`: not run).
    pub max_tracking_error_none_m: Option<f64>,
    /// Largest cart error with linear feedforward, m (`None`: not run).
    pub max_tracking_error_linear_m: Option<f64>,
    /// Largest cart error with nonlinear feedforward (the delivered controller), m.
    pub max_tracking_error_nonlinear_m: f64,
    /// Static cart error with nonlinear feedforward, m.
    pub static_error_nonlinear_m: f64,
    /// Settling time with nonlinear feedforward, s (`None`: did not settle).
    pub settling_time_nonlinear_s: Option<f64>,
}

/// The summary of one `beltune commission`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// [`SCHEMA`].
    pub schema: &'static str,
    /// Plant name or file, or the recorded CSV.
    pub source: String,
    /// `ok` or `limits_not_met`.
    pub status: &'static str,
    /// The exit status of the command.
    pub exit_code: i32,
    /// The identified model.
    pub identified: IdentifiedSummary,
    /// The truth (simulated plants only).
    pub truth: Option<TruthSummary>,
    /// The controller.
    pub controller: Option<ControllerSummary>,
    /// The validation (axis runs only).
    pub validation: Option<ValidationSummary>,
    /// The verdict (the library's, as in `commissioning.json`).
    pub verdict: Option<Verdict>,
    /// Time the axis was busy, s.
    pub axis_busy_s: Option<f64>,
    /// The axis time of each stage, in the order they ran.
    pub stage_axis_times: Vec<beltune::commission::stages::StageAxisTime>,
    /// Computing time, s.
    pub computation_s: f64,
    /// Elapsed time of the command, s.
    pub wall_time_s: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// The model and gains are in the units of a record's input column (not
    /// necessarily N m): the text prints them without units.
    #[serde(skip)]
    pub record_units: bool,
}

impl IdentifiedSummary {
    /// From the library's model summary.
    pub fn of(m: &IdentifiedModel) -> Self {
        IdentifiedSummary {
            f_r_hz: m.f_r_hz,
            f_z_hz: m.f_z_hz,
            theta_e_kg_m2: m.theta_e,
            m_c_kg: m.m_c,
            c_n_per_m: m.c,
            d_m_n_s_per_m: m.d_m,
            d_c_n_s_per_m: m.d_c,
            dead_time_s: m.dead_time_s,
            fit_rms_db: m.fit_rms_db,
            mean_coherence: m.mean_coherence,
        }
    }
}

impl TruthSummary {
    /// From the simulator's truth.
    pub fn of(t: &Truth) -> Self {
        TruthSummary {
            f_r_hz: t.f_r_hz,
            f_z_hz: t.f_z_hz,
            m_c_kg: t.m_c,
            c_n_per_m: t.c,
        }
    }
}

impl ControllerSummary {
    /// From the design's summary.
    pub fn of(d: &DesignSummary) -> Self {
        ControllerSummary {
            k_p_nm_s_per_rad: d.k_p,
            k_i_nm_per_rad: d.k_i,
            k_pp_per_s: d.k_pp,
            velocity_crossover_hz: d.omega_c_velocity / (2.0 * PI),
            velocity_phase_margin_deg: d.phase_margin_velocity_deg,
            position_crossover_hz: d.omega_c_position / (2.0 * PI),
            position_phase_margin_deg: d.phase_margin_position_deg,
            gain_at_resonance_db: d.gain_at_resonance_db,
        }
    }
}

impl ValidationSummary {
    /// From the three moves of the move `m` that ran.
    pub fn of(v: &Validation, m: &ValidationMove) -> Self {
        ValidationSummary {
            start_m: m.start_m,
            target_m: m.target_m,
            max_tracking_error_none_m: v.none.as_ref().map(|s| s.max_tracking_error_m),
            max_tracking_error_linear_m: v.linear.as_ref().map(|s| s.max_tracking_error_m),
            max_tracking_error_nonlinear_m: v.nonlinear.max_tracking_error_m,
            static_error_nonlinear_m: v.nonlinear.static_error_m,
            settling_time_nonlinear_s: v.nonlinear.settling_time_s,
        }
    }
}

impl Summary {
    /// The summary of the record a run wrote into `files`, with the elapsed
    /// time of the command.
    pub fn of(record: &CommissioningRecord, files: Vec<PathBuf>, wall_time_s: f64) -> Self {
        let recorded = matches!(record.axis, Some(AxisRecord::Recorded { .. }));
        let verdict = record.verdict.clone();
        let (status, exit) = match &verdict {
            Some(v) if !v.limits_met() => ("limits_not_met", crate::exit::ExitStatus::LimitsNotMet),
            Some(v) if !v.passed => ("not_validated", crate::exit::ExitStatus::Success),
            _ => ("ok", crate::exit::ExitStatus::Success),
        };
        let nan = f64::NAN;
        Summary {
            schema: SCHEMA,
            source: record.plant.clone(),
            status,
            exit_code: exit.code(),
            identified: IdentifiedSummary::of(&record.identified),
            truth: record.truth.as_ref().map(TruthSummary::of),
            controller: record.controller.as_ref().map(ControllerSummary::of),
            validation: match (&record.validation, &record.validation_move) {
                (Some(v), Some(m)) => Some(ValidationSummary::of(v, m)),
                _ => None,
            },
            verdict,
            axis_busy_s: if recorded {
                None
            } else {
                record.experiment_time_s
            },
            stage_axis_times: record.stage_axis_times.clone(),
            computation_s: record.computation_time_s.unwrap_or(nan),
            wall_time_s,
            files,
            record_units: recorded,
        }
    }

    /// The exit status the summary reports.
    pub fn exit_status(&self) -> crate::exit::ExitStatus {
        if self.status == "limits_not_met" {
            crate::exit::ExitStatus::LimitsNotMet
        } else {
            crate::exit::ExitStatus::Success
        }
    }

    /// The summary as pretty JSON.
    pub fn json(&self) -> anyhow::Result<String> {
        Ok(serde_json::to_string_pretty(self)?)
    }

    /// The summary as text lines of at most [`term::width`] columns.
    pub fn lines(&self) -> Vec<String> {
        self.lines_in(term::width())
    }

    /// The summary as text lines of at most `width` columns.
    pub fn lines_in(&self, width: usize) -> Vec<String> {
        let mut out = Vec::new();
        // Every number below has a fixed precision: no float noise to tidy.
        let mut add =
            |label: &str, body: String| out.extend(term::wrap(label, LABEL_WIDTH, &body, width));
        if self.record_units {
            self.record_lines(&mut add);
        } else {
            self.axis_lines(&mut add);
        }
        self.tail_lines(&mut add);
        out
    }

    /// The identified and controller lines of recorded data: values in the
    /// units of the record, printed without units.
    fn record_lines(&self, add: &mut impl FnMut(&str, String)) {
        let id = &self.identified;
        add(
            "identified",
            format!(
                "f_r {:.2} Hz, f_z {:.2} Hz, m_c {:.4e}, c {:.4e} (units of the record), \
                 dead time {:.2} ms, fit {:.2} dB rms, coherence {:.3}",
                id.f_r_hz,
                id.f_z_hz,
                id.m_c_kg,
                id.c_n_per_m,
                id.dead_time_s * 1e3,
                id.fit_rms_db,
                id.mean_coherence
            ),
        );
        let Some(c) = &self.controller else { return };
        add(
            "controller",
            format!(
                "K_P {:.4e}, K_I {:.4e} (units of the record), K_PP {:.2} 1/s; velocity loop \
                 {:.1} Hz / {:.1} deg, position loop {:.1} Hz / {:.1} deg",
                c.k_p_nm_s_per_rad,
                c.k_i_nm_per_rad,
                c.k_pp_per_s,
                c.velocity_crossover_hz,
                c.velocity_phase_margin_deg,
                c.position_crossover_hz,
                c.position_phase_margin_deg
            ),
        );
    }

    /// The identified and controller lines of a run with SI units.
    fn axis_lines(&self, add: &mut impl FnMut(&str, String)) {
        let id = &self.identified;
        let truth = |v: Option<f64>| v.map(|t| format!(" (truth {t:.2})")).unwrap_or_default();
        add(
            "identified",
            format!(
                "f_r {:.2} Hz{}, f_z {:.2} Hz{}, m_c {:.2} kg, c {:.1} kN/m, dead time {:.2} ms, \
                 fit {:.2} dB rms, coherence {:.3}",
                id.f_r_hz,
                truth(self.truth.as_ref().map(|t| t.f_r_hz)),
                id.f_z_hz,
                truth(self.truth.as_ref().map(|t| t.f_z_hz)),
                id.m_c_kg,
                id.c_n_per_m / 1e3,
                id.dead_time_s * 1e3,
                id.fit_rms_db,
                id.mean_coherence
            ),
        );
        let Some(c) = &self.controller else { return };
        add(
            "controller",
            format!(
                "K_P {:.4} N m s/rad, K_I {:.3} N m/rad, K_PP {:.2} 1/s; velocity loop {:.1} Hz / \
                 {:.1} deg, position loop {:.1} Hz / {:.1} deg",
                c.k_p_nm_s_per_rad,
                c.k_i_nm_per_rad,
                c.k_pp_per_s,
                c.velocity_crossover_hz,
                c.velocity_phase_margin_deg,
                c.position_crossover_hz,
                c.position_phase_margin_deg
            ),
        );
    }

    /// Validation, verdict, times and files.
    fn tail_lines(&self, add: &mut impl FnMut(&str, String)) {
        if let Some(v) = &self.validation {
            add(
                "validation",
                format!(
                    "{:.0} -> {:.0} mm, max cart error: {}nonlinear {:.3} mm; static {:.1} um",
                    v.start_m * 1e3,
                    v.target_m * 1e3,
                    match (v.max_tracking_error_none_m, v.max_tracking_error_linear_m) {
                        (Some(n), Some(l)) =>
                            format!("none {:.3} mm, linear {:.3} mm, ", n * 1e3, l * 1e3),
                        _ => String::new(),
                    },
                    v.max_tracking_error_nonlinear_m * 1e3,
                    v.static_error_nonlinear_m * 1e6
                ),
            );
        }
        if let Some(v) = &self.verdict {
            add("verdict", v.text());
            for w in &v.warnings {
                add("warning", format!("{}: {}", w.topic, w.reason));
            }
            add("next step", v.next_step.clone());
        }
        let mut time = Vec::new();
        if let Some(b) = self.axis_busy_s {
            time.push(format!("axis busy {b:.1} s"));
        }
        time.push(format!("computation {:.2} s", self.computation_s));
        time.push(format!("wall time {:.1} s", self.wall_time_s));
        add("time", time.join(", "));
        // the stages that moved the axis (design and fits take no axis time)
        let stages: Vec<String> = self
            .stage_axis_times
            .iter()
            .filter(|t| t.axis_time_s >= 0.05)
            .map(|t| format!("{} {:.1}", t.stage, t.axis_time_s))
            .collect();
        if !stages.is_empty() {
            add("axis time", format!("{} s", stages.join(", ")));
        }
        for f in &self.files {
            add("wrote", f.display().to_string());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use beltune::verdict::{ValidatedOn, Warning};

    /// A recorded-data summary (no move) whose fit is noisy.
    fn noisy_csv_summary() -> Summary {
        Summary {
            schema: SCHEMA,
            source: "rec.csv".into(),
            status: "not_validated",
            exit_code: 0,
            identified: IdentifiedSummary {
                f_r_hz: 31.0,
                f_z_hz: 22.0,
                theta_e_kg_m2: 1e-4,
                m_c_kg: 12.0,
                c_n_per_m: 2e5,
                d_m_n_s_per_m: 40.0,
                d_c_n_s_per_m: 180.0,
                dead_time_s: 1e-3,
                fit_rms_db: 11.2,
                mean_coherence: 0.84,
            },
            truth: None,
            controller: None,
            validation: None,
            verdict: Some(Verdict {
                passed: false,
                validated_on: ValidatedOn::None,
                checks: Vec::new(),
                warnings: vec![
                    Warning {
                        topic: "coherence".into(),
                        reason: "the measured frequency response is noisy (mean coherence 0.84)"
                            .into(),
                    },
                    Warning {
                        topic: "fit residual".into(),
                        reason: "the two-mass model fits the measurement poorly (11.20 dB rms)"
                            .into(),
                    },
                ],
                next_step: "No validation move was run: run a test move.".into(),
            }),
            axis_busy_s: None,
            stage_axis_times: Vec::new(),
            computation_s: 0.5,
            wall_time_s: 0.6,
            files: vec![PathBuf::from("out/commissioning.json")],
            record_units: true,
        }
    }

    /// The terminal says what the report says: the verdict, each warning and
    /// the next step, also for recorded data (`--csv`).
    #[test]
    fn the_terminal_summary_shows_verdict_warnings_and_next_step() {
        let text = noisy_csv_summary().lines_in(term::WIDTH).join("\n");
        for want in [
            "verdict:",
            "warning: coherence: the measured frequency response is noisy",
            "warning: fit residual:",
            "next step: No validation move was run",
        ] {
            assert!(text.contains(want), "`{want}` missing in:\n{text}");
        }
    }

    /// Lines fit the width they are wrapped to (an 80-column terminal gets
    /// lines of at most 80 columns, not the 100 of a pipe).
    #[test]
    fn the_summary_wraps_to_the_terminal_width() {
        let s = noisy_csv_summary();
        for width in [80, term::WIDTH] {
            let lines = s.lines_in(width);
            assert!(
                lines.iter().all(|l| l.chars().count() <= width),
                "{lines:#?}"
            );
            assert!(lines.iter().any(|l| l.chars().count() > width - 20));
        }
        assert!(s.lines_in(80).len() > s.lines_in(100).len());
    }
}
