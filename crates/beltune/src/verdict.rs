//! The one verdict of a commissioning: is the delivered controller good
//! enough to load into the drive? Computed once, here, from the validation
//! move of the delivered controller (nonlinear feedforward), the drive's
//! torque limit and the margins the design guarantees over the
//! identification's uncertainty. Every output reads it from here:
//! `commissioning.json` (`verdict`), the exit status of `beltune commission`
//! (5 when a check fails), its terminal summary and `--json`, `report.html`,
//! the tuning page and its saved sets.
//!
//! | check | passes when | default limit |
//! | --- | --- | --- |
//! | `max_tracking_error` | largest cart tracking error of the move `<` limit | 1 mm (thesis chapter 5) |
//! | `static_error` | static cart error after the move `<` limit | 100 um (thesis chapter 5) |
//! | `settling` | the error stays inside the settling band before the record ends | the record after the move (1 s) |
//! | `saturation` | largest torque command of the move `<` the torque limit | the drive's torque limit |
//! | `guaranteed_phase_margin` | velocity-loop phase margin over the identification's uncertainty `>=` limit | 30 deg |
//!
//! Warnings (coherence, fit residual, margins short of the requested ones, a
//! thin gain margin) do not fail the verdict; they say what to look at.
//! Without a validation move (recorded data) the verdict is "not
//! validated": the design's own checks still apply, the move's cannot.

use crate::commission::validation::MoveSummary;
use crate::design::robust::GuaranteedMargins;
use crate::design::ControllerDesign;
use crate::record::model::IdentifiedModel;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Thesis chapter 5: largest cart tracking error of the validation move, m.
pub const MAX_TRACKING_ERROR_M: f64 = 1e-3;
/// Thesis chapter 5: static positioning error after the move, m.
pub const MAX_STATIC_ERROR_M: f64 = 100e-6;
/// Smallest velocity-loop phase margin the commissioning accepts over the
/// identification's uncertainty, deg.
pub const MIN_GUARANTEED_PHASE_MARGIN_DEG: f64 = 30.0;
/// Mean coherence of the fitted lines below which the FRF is called noisy.
pub const MIN_MEAN_COHERENCE: f64 = 0.9;
/// RMS magnitude residual of the fit above which the model is called poor, dB
/// (the thesis fits reach about 1 dB).
pub const MAX_FIT_RMS_DB: f64 = 3.0;
/// Phase margin short of the requested one that earns a warning, deg.
pub const MARGIN_SHORTFALL_DEG: f64 = 1.0;
/// Velocity-loop gain margin below which a warning is given, dB.
pub const MIN_GAIN_MARGIN_DB: f64 = 6.0;
/// A torque command within this fraction of the limit counts as saturated.
const SATURATION_TOLERANCE: f64 = 1e-6;

/// The limits a commissioning is judged against (the thesis' by default).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Largest cart tracking error of the validation move, m.
    pub max_tracking_error_m: f64,
    /// Largest static cart error after the move, m.
    pub max_static_error_m: f64,
    /// Smallest velocity-loop phase margin guaranteed over the
    /// identification's uncertainty, deg.
    pub min_guaranteed_phase_margin_deg: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_tracking_error_m: MAX_TRACKING_ERROR_M,
            max_static_error_m: MAX_STATIC_ERROR_M,
            min_guaranteed_phase_margin_deg: MIN_GUARANTEED_PHASE_MARGIN_DEG,
        }
    }
}

impl Limits {
    /// Error unless the lengths are positive and finite and the margin lies in 0..90 deg.
    pub fn validate(&self) -> Result<()> {
        crate::error::require_positive("max tracking error [m]", self.max_tracking_error_m)?;
        crate::error::require_positive("max static error [m]", self.max_static_error_m)?;
        let pm = self.min_guaranteed_phase_margin_deg;
        if !(pm.is_finite() && (0.0..90.0).contains(&pm)) {
            return Err(Error::invalid(
                "min guaranteed phase margin [deg]",
                pm,
                "must lie in 0 ..< 90 deg",
            ));
        }
        Ok(())
    }
}

/// What a check judges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CheckName {
    /// Largest cart tracking error of the validation move.
    MaxTrackingError,
    /// Static cart error after the move.
    StaticError,
    /// The error settles inside the band before the record ends.
    Settling,
    /// The move stays below the torque limit.
    Saturation,
    /// Velocity-loop phase margin over the identification's uncertainty.
    GuaranteedPhaseMargin,
}

/// One judged quantity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// What is judged.
    pub name: CheckName,
    /// The measured value in [`Self::unit`] (`null`: not measured, e.g. a
    /// cart that never settled).
    pub value: Option<f64>,
    /// The limit in [`Self::unit`].
    pub limit: f64,
    /// The unit of value and limit: `m`, `s`, `N m` (`A` for a record in
    /// current units) or `deg`.
    pub unit: String,
    /// Whether the value must stay below the limit (`true`) or reach it (`false`).
    pub below: bool,
    /// Whether the check passed (a missing or non-finite value fails).
    pub passed: bool,
}

/// Something to look at, with its reason.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// Short topic ("coherence", "fit residual", "margins").
    pub topic: String,
    /// Why it is a warning, in words a technician can act on.
    pub reason: String,
}

/// What the move checks were judged on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ValidatedOn {
    /// A validation move on the axis (simulated plant or real drive).
    Axis,
    /// A move simulated on a model (the tuning page's saved sets).
    Simulation,
    /// No move (recorded data).
    #[default]
    None,
}

/// The verdict: every check, the warnings and the next step. (The default
/// is an empty verdict that judged nothing.)
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    /// A move was judged and every check passed.
    pub passed: bool,
    /// What the move checks were judged on.
    pub validated_on: ValidatedOn,
    /// The checks, in the order of the module table.
    pub checks: Vec<Check>,
    /// Warnings with their reason.
    pub warnings: Vec<Warning>,
    /// What to do next, in words.
    pub next_step: String,
}

/// The validation move a verdict judges.
#[derive(Clone, Copy, Debug)]
pub struct MoveInput<'a> {
    /// The move with the delivered controller (nonlinear feedforward).
    pub summary: &'a MoveSummary,
    /// Time recorded after the trajectory ended, s: the error must settle within it.
    pub record_after_move_s: f64,
    /// The drive's torque limit, N m.
    pub torque_max_nm: f64,
    /// Whether it ran on the axis or on a model.
    pub on: ValidatedOn,
}

/// What a verdict is judged on.
#[derive(Clone, Copy, Debug)]
pub struct VerdictInput<'a> {
    /// The limits.
    pub limits: &'a Limits,
    /// The validation move (`None`: recorded data, no move).
    pub validation: Option<MoveInput<'a>>,
    /// The margins the design guarantees over the identification's uncertainty.
    pub guaranteed: Option<&'a GuaranteedMargins>,
    /// The delivered design (requested and achieved margins).
    pub design: &'a ControllerDesign,
    /// The identified model (coherence and fit residual), if known.
    pub identified: Option<&'a IdentifiedModel>,
    /// The controller file the next step names.
    pub controller_file: &'a str,
}

/// `x < limit`; false for NaN.
fn below(x: f64, limit: f64) -> bool {
    x.partial_cmp(&limit) == Some(std::cmp::Ordering::Less)
}

/// `x >= limit`; false for NaN.
fn at_least(x: f64, limit: f64) -> bool {
    matches!(
        x.partial_cmp(&limit),
        Some(std::cmp::Ordering::Greater | std::cmp::Ordering::Equal)
    )
}

fn check(name: CheckName, value: Option<f64>, limit: f64, unit: &str, is_below: bool) -> Check {
    let passed = value.is_some_and(|v| {
        if is_below {
            below(v, limit)
        } else {
            at_least(v, limit)
        }
    });
    Check {
        name,
        value: value.filter(|v| v.is_finite()),
        limit,
        unit: unit.into(),
        below: is_below,
        passed,
    }
}

/// Judge a commissioning.
pub fn judge(input: &VerdictInput) -> Verdict {
    let l = input.limits;
    let mut checks = Vec::new();
    if let Some(m) = &input.validation {
        let s = m.summary;
        checks.push(check(
            CheckName::MaxTrackingError,
            Some(s.max_tracking_error_m),
            l.max_tracking_error_m,
            "m",
            true,
        ));
        checks.push(check(
            CheckName::StaticError,
            Some(s.static_error_m),
            l.max_static_error_m,
            "m",
            true,
        ));
        checks.push(check(
            CheckName::Settling,
            s.settling_time_s,
            m.record_after_move_s,
            "s",
            true,
        ));
        // a record in current units judges a current against the current limit
        let torque_unit = input
            .identified
            .map_or("N m", |id| crate::units::labels(id.units).torque);
        let mut saturation = check(
            CheckName::Saturation,
            Some(s.max_torque_nm),
            m.torque_max_nm,
            torque_unit,
            true,
        );
        saturation.passed = below(
            s.max_torque_nm,
            m.torque_max_nm * (1.0 - SATURATION_TOLERANCE),
        );
        checks.push(saturation);
    }
    if let Some(g) = input.guaranteed {
        checks.push(check(
            CheckName::GuaranteedPhaseMargin,
            Some(g.velocity_phase_margin_deg),
            l.min_guaranteed_phase_margin_deg,
            "deg",
            false,
        ));
    }
    let warnings = warnings(input);
    let validated_on = input.validation.map_or(ValidatedOn::None, |m| m.on);
    let all = checks.iter().all(|c| c.passed);
    let passed = all && validated_on != ValidatedOn::None;
    let file = input.controller_file;
    let next_step = match (all, validated_on) {
        (true, ValidatedOn::Axis) => format!(
            "Enter the gains and the filter of {file} into the drive (the report's drive \
             settings table lists them as a drive menu shows them; `beltune export --controller \
             {file} --lang c` writes them for firmware), then repeat the validation move on the \
             drive before production."
        ),
        (true, ValidatedOn::Simulation) => format!(
            "The move was simulated, not run: commission the axis with this design before \
             loading {file} for production."
        ),
        (true, ValidatedOn::None) => format!(
            "No validation move was run: load {file} into the drive at reduced torque limit and \
             run a test move before production."
        ),
        (false, _) => format!(
            "Do not load {file} for production: it misses its limits. Check the mechanics \
             (belt tension, loose payload), then commission again, or open `beltune serve` on \
             this folder and lower the dynamics."
        ),
    };
    Verdict {
        passed,
        validated_on,
        checks,
        warnings,
        next_step,
    }
}

fn warnings(input: &VerdictInput) -> Vec<Warning> {
    let mut out = Vec::new();
    let mut warn = |topic: &str, reason: String| {
        out.push(Warning {
            topic: topic.into(),
            reason,
        })
    };
    if let Some(id) = input.identified {
        let c = id.mean_coherence;
        if c.is_finite() && !at_least(c, MIN_MEAN_COHERENCE) {
            warn(
                "coherence",
                format!(
                    "the measured frequency response is noisy (mean coherence {c:.2}, below \
                     {MIN_MEAN_COHERENCE}): increase the excitation amplitude or the number of \
                     averaged periods"
                ),
            );
        }
        let r = id.fit_rms_db;
        if r.is_finite() && !at_least(MAX_FIT_RMS_DB, r) {
            warn(
                "fit residual",
                format!(
                    "the two-mass model fits the measurement poorly ({r:.2} dB rms, above \
                     {MAX_FIT_RMS_DB} dB): the axis may have a second resonance or strong \
                     friction; compare the curves below"
                ),
            );
        }
    }
    let d = input.design;
    for (loop_name, want, got) in [
        (
            "velocity",
            d.knobs.pm_velocity_deg,
            d.velocity_margins.phase_margin_deg,
        ),
        (
            "position",
            d.knobs.pm_position_deg,
            d.position_margins.phase_margin_deg,
        ),
    ] {
        if !at_least(got, want - MARGIN_SHORTFALL_DEG) {
            warn(
                "margins",
                format!(
                    "{loop_name} loop phase margin {got:.1} deg is short of the requested \
                     {want:.1} deg"
                ),
            );
        }
    }
    let gm = d.velocity_margins.gain_margin_db;
    if !at_least(gm, MIN_GAIN_MARGIN_DB) {
        warn(
            "margins",
            format!(
                "velocity loop gain margin {gm:.1} dB is below {MIN_GAIN_MARGIN_DB} dB: a small \
                 change of the load can make the loop oscillate"
            ),
        );
    }
    out
}

impl CheckName {
    /// How a person reads it: "max cart error", "static error", ...
    pub fn label(self) -> &'static str {
        match self {
            CheckName::MaxTrackingError => "max cart error",
            CheckName::StaticError => "static error",
            CheckName::Settling => "settling time",
            CheckName::Saturation => "peak torque",
            CheckName::GuaranteedPhaseMargin => "guaranteed phase margin",
        }
    }

    /// What it is, in a sentence fragment for the report.
    pub fn description(self) -> &'static str {
        match self {
            CheckName::MaxTrackingError => "max cart tracking error during the move",
            CheckName::StaticError => "static error after the move",
            CheckName::Settling => "time to settle within the static limit after the move",
            CheckName::Saturation => "largest torque command of the move (torque limit)",
            CheckName::GuaranteedPhaseMargin => {
                "velocity-loop phase margin over the identification's uncertainty"
            }
        }
    }
}

/// A value of a check in display units: (scale from SI, unit, decimals).
fn display_unit(c: &Check) -> (f64, &'static str, usize) {
    match c.unit.as_str() {
        "m" if c.limit < 1e-3 => (1e6, "um", 1),
        "m" => (1e3, "mm", 3),
        "s" => (1.0, "s", 3),
        "N m" => (1.0, "N m", 3),
        "A" => (1.0, "A", 3),
        _ => (1.0, "deg", 1),
    }
}

/// A number without trailing zeros (`1`, `0.5`, `100`).
fn tidy(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

impl Check {
    /// The measured value in display units ("0.042", "3.0"; "none" when not measured).
    pub fn value_text(&self) -> String {
        let (scale, _, digits) = display_unit(self);
        match self.value {
            Some(v) => format!("{:.digits$}", v * scale),
            None => "none".into(),
        }
    }

    /// The limit in display units, without trailing zeros.
    pub fn limit_text(&self) -> String {
        tidy(self.limit * display_unit(self).0)
    }

    /// The display unit (`mm`, `um`, `s`, `N m`, `A`, `deg`).
    pub fn display_unit(&self) -> &'static str {
        display_unit(self).1
    }

    /// The relation the value must keep to the limit: `<` or `>=`.
    pub fn relation(&self) -> &'static str {
        if self.below {
            "<"
        } else {
            ">="
        }
    }

    /// `max cart error 0.042 mm < 1 mm`; a failed check shows the relation that
    /// does not hold reversed (`1.200 mm >= 1 mm`, `12.0 deg < 30 deg`).
    pub fn text(&self) -> String {
        let unit = self.display_unit();
        let op = match (self.passed, self.below) {
            (true, b) => {
                if b {
                    "<"
                } else {
                    ">="
                }
            }
            (false, true) => ">=",
            (false, false) => "<",
        };
        match (self.name, self.value) {
            (CheckName::Settling, None) => format!(
                "the cart did not settle within the {} s recorded after the move",
                self.limit_text()
            ),
            _ => format!(
                "{} {} {unit} {op} {} {unit}",
                self.name.label(),
                self.value_text(),
                self.limit_text()
            ),
        }
    }
}

impl Verdict {
    /// Every check passed (a verdict without a move may still have all its checks passed).
    pub fn limits_met(&self) -> bool {
        self.checks.iter().all(|c| c.passed)
    }

    /// `PASS`, `FAIL` or `NOT VALIDATED`.
    pub fn word(&self) -> &'static str {
        if !self.limits_met() {
            "FAIL"
        } else if self.passed && self.validated_on == ValidatedOn::Simulation {
            "PASS (simulated move)"
        } else if self.passed {
            "PASS"
        } else {
            "NOT VALIDATED"
        }
    }

    /// `PASS: max cart error 0.042 mm < 1 mm, ...` with every check.
    pub fn text(&self) -> String {
        let checks: Vec<String> = self.checks.iter().map(Check::text).collect();
        if checks.is_empty() {
            self.word().to_string()
        } else {
            format!("{}: {}", self.word(), checks.join(", "))
        }
    }

    /// The checks that failed, as text.
    pub fn failures(&self) -> Vec<String> {
        self.checks
            .iter()
            .filter(|c| !c.passed)
            .map(Check::text)
            .collect()
    }

    /// The check of `name`, if it was judged.
    pub fn check(&self, name: CheckName) -> Option<&Check> {
        self.checks.iter().find(|c| c.name == name)
    }
}

#[cfg(test)]
mod tests;
