//! The verdict of a commissioning (issue 16): pass/fail per limit, warnings
//! with their reason, and the next step. The limits are the thesis' targets for
//! the validation move (chapter 5): a cart tracking error below 1 mm during the
//! move and a static error below 100 um after it.

use serde::Serialize;

/// Largest cart tracking error during the validation move, m (thesis chapter
/// 5: < 1 mm; the same limit the commissioning judges itself by,
/// [`crate::verdict::MAX_TRACKING_ERROR_M`]).
pub const DYNAMIC_ERROR_LIMIT_M: f64 = crate::verdict::MAX_TRACKING_ERROR_M;
/// Largest static error after the validation move, m (thesis chapter 5:
/// < 100 um; [`crate::verdict::MAX_STATIC_ERROR_M`]).
pub const STATIC_ERROR_LIMIT_M: f64 = crate::verdict::MAX_STATIC_ERROR_M;
/// Mean coherence of the fitted lines below which the FRF is called noisy.
pub const MIN_MEAN_COHERENCE: f64 = 0.9;
/// RMS magnitude residual of the fit above which the model is called poor, dB
/// (the thesis fits reach about 1 dB).
pub const MAX_FIT_RMS_DB: f64 = 3.0;
/// Phase margin short of the requested one that earns a warning, deg.
pub const MARGIN_SHORTFALL_DEG: f64 = 1.0;
/// Velocity-loop gain margin below which a warning is given, dB.
pub const MIN_GAIN_MARGIN_DB: f64 = 6.0;

/// One limit and whether it is met.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LimitCheck {
    /// What is checked.
    pub name: String,
    /// Measured value, in `unit`.
    pub value: f64,
    /// The limit, in `unit` (the value must stay below it).
    pub limit: f64,
    /// Unit of `value` and `limit` (display unit: mm, um).
    pub unit: String,
    /// `value < limit`.
    pub passed: bool,
}

/// Something to look at, with its reason.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Warning {
    /// Short topic ("coherence", "fit residual", "margins").
    pub topic: String,
    /// Why it is a warning, in words a technician can act on.
    pub reason: String,
}

/// What the verdict is judged on.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VerdictInput {
    /// Largest cart tracking error of the move with nonlinear feedforward, m
    /// (`None`: no validation move, e.g. recorded data).
    pub max_tracking_error_m: Option<f64>,
    /// Static error after that move, m.
    pub static_error_m: Option<f64>,
    /// Mean coherence over the fitted lines.
    pub mean_coherence: Option<f64>,
    /// RMS magnitude residual of the fit, dB.
    pub fit_rms_db: Option<f64>,
    /// Requested and achieved velocity phase margin, deg.
    pub velocity_phase_margin_deg: (f64, f64),
    /// Requested and achieved position phase margin, deg.
    pub position_phase_margin_deg: (f64, f64),
    /// Velocity-loop gain margin, dB.
    pub velocity_gain_margin_db: f64,
    /// File the drive should load when the verdict is a pass.
    pub controller_file: String,
}

/// The verdict.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verdict {
    /// The limits, each passed or failed.
    pub checks: Vec<LimitCheck>,
    /// Warnings with their reason.
    pub warnings: Vec<Warning>,
    /// Every check passed (and there was at least one).
    pub passed: bool,
    /// What to do next.
    pub next_step: String,
}

/// `x >= lo`; false for NaN (a missing number never passes).
fn at_least(x: f64, lo: f64) -> bool {
    x >= lo
}

/// Judge a commissioning.
pub fn verdict(v: &VerdictInput) -> Verdict {
    let mut checks = Vec::new();
    if let Some(e) = v.max_tracking_error_m {
        checks.push(LimitCheck {
            name: "max cart tracking error during the move".into(),
            value: e * 1e3,
            limit: DYNAMIC_ERROR_LIMIT_M * 1e3,
            unit: "mm".into(),
            passed: e.is_finite() && e < DYNAMIC_ERROR_LIMIT_M,
        });
    }
    if let Some(e) = v.static_error_m {
        checks.push(LimitCheck {
            name: "static error after the move".into(),
            value: e * 1e6,
            limit: STATIC_ERROR_LIMIT_M * 1e6,
            unit: "um".into(),
            passed: e.is_finite() && e < STATIC_ERROR_LIMIT_M,
        });
    }
    let mut warnings = Vec::new();
    if let Some(c) = v
        .mean_coherence
        .filter(|c| !at_least(*c, MIN_MEAN_COHERENCE))
    {
        warnings.push(Warning {
            topic: "coherence".into(),
            reason: format!(
                "the measured frequency response is noisy (mean coherence {c:.2}, below {MIN_MEAN_COHERENCE}): \
                 increase the excitation amplitude or the number of averaged periods"
            ),
        });
    }
    if let Some(r) = v.fit_rms_db.filter(|r| !at_least(MAX_FIT_RMS_DB, *r)) {
        warnings.push(Warning {
            topic: "fit residual".into(),
            reason: format!(
                "the two-mass model fits the measurement poorly ({r:.2} dB rms, above {MAX_FIT_RMS_DB} dB): \
                 the axis may have a second resonance or strong friction; compare the curves below"
            ),
        });
    }
    let (want, got) = v.velocity_phase_margin_deg;
    if !at_least(got, want - MARGIN_SHORTFALL_DEG) {
        warnings.push(Warning {
            topic: "margins".into(),
            reason: format!(
                "velocity loop phase margin {got:.1} deg is short of the requested {want:.1} deg"
            ),
        });
    }
    let (want, got) = v.position_phase_margin_deg;
    if !at_least(got, want - MARGIN_SHORTFALL_DEG) {
        warnings.push(Warning {
            topic: "margins".into(),
            reason: format!(
                "position loop phase margin {got:.1} deg is short of the requested {want:.1} deg"
            ),
        });
    }
    if !at_least(v.velocity_gain_margin_db, MIN_GAIN_MARGIN_DB) {
        warnings.push(Warning {
            topic: "margins".into(),
            reason: format!(
                "velocity loop gain margin {:.1} dB is below {MIN_GAIN_MARGIN_DB} dB: \
                 a small change of the load can make the loop oscillate",
                v.velocity_gain_margin_db
            ),
        });
    }
    let passed = !checks.is_empty() && checks.iter().all(|c| c.passed);
    let next_step = if passed {
        format!("Load {} into the drive.", v.controller_file)
    } else if checks.is_empty() {
        format!(
            "No validation move was run: load {} into the drive at reduced torque limit and run \
             a test move before production.",
            v.controller_file
        )
    } else {
        format!(
            "Do not load {} for production: the move misses the limits. Check the mechanics \
             (belt tension, loose payload), then commission again, or open `beltune serve` on \
             this folder and lower the dynamics.",
            v.controller_file
        )
    };
    Verdict {
        checks,
        warnings,
        passed,
        next_step,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok_input() -> VerdictInput {
        VerdictInput {
            max_tracking_error_m: Some(0.64e-3),
            static_error_m: Some(31e-6),
            mean_coherence: Some(0.99),
            fit_rms_db: Some(1.4),
            velocity_phase_margin_deg: (60.0, 60.0),
            position_phase_margin_deg: (80.0, 80.0),
            velocity_gain_margin_db: 14.2,
            controller_file: "controller.toml".into(),
        }
    }

    #[test]
    fn limits_pass_and_fail_at_the_thesis_values() {
        let v = verdict(&ok_input());
        assert!(v.passed && v.warnings.is_empty(), "{v:?}");
        assert!(v.next_step.contains("controller.toml"));
        let v = verdict(&VerdictInput {
            max_tracking_error_m: Some(1.2e-3),
            ..ok_input()
        });
        assert!(!v.passed && !v.checks[0].passed && v.checks[1].passed);
        assert!(v.next_step.starts_with("Do not load"));
        let v = verdict(&VerdictInput {
            static_error_m: Some(f64::NAN),
            ..ok_input()
        });
        assert!(!v.passed, "NaN never passes");
    }

    #[test]
    fn warnings_name_their_reason() {
        let v = verdict(&VerdictInput {
            mean_coherence: Some(0.5),
            fit_rms_db: Some(5.0),
            velocity_gain_margin_db: 3.0,
            velocity_phase_margin_deg: (60.0, 50.0),
            ..ok_input()
        });
        let topics: Vec<&str> = v.warnings.iter().map(|w| w.topic.as_str()).collect();
        assert_eq!(topics, ["coherence", "fit residual", "margins", "margins"]);
        assert!(v.passed, "warnings alone do not fail the limits");
        let none = verdict(&VerdictInput {
            max_tracking_error_m: None,
            static_error_m: None,
            ..ok_input()
        });
        assert!(!none.passed && none.next_step.starts_with("No validation move"));
    }
}
