//! Whether a commissioning met its own limits (issue 12; the report's verdict
//! box is [`crate::report::verdict_old`]): a commissioning
//! that ends with a controller but misses the thesis' accuracy, saturates the
//! drive, never settles, or cannot guarantee its margins against the
//! identification's uncertainty says so, in the library result
//! ([`Verdict::meets_limits`]) and in the CLI's exit status 5.

use crate::commission::result::MoveSummary;
pub use crate::design::robust::{
    guaranteed_margins, margins_on, GuaranteedMargins, MarginsOn, UNCERTAINTY_SIGMAS,
};
use serde::{Deserialize, Serialize};

/// Thesis chapter 5: largest cart tracking error with nonlinear feedforward, m.
pub const MAX_TRACKING_ERROR_M: f64 = 1e-3;
/// Thesis chapter 5: static positioning error, m.
pub const MAX_STATIC_ERROR_M: f64 = 100e-6;
/// Smallest velocity-loop phase margin the commissioning accepts over the
/// identification's uncertainty, deg.
pub const MIN_GUARANTEED_PHASE_MARGIN_DEG: f64 = 30.0;
/// The outcome of a commissioning against its own limits.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    /// Every limit met.
    pub meets_limits: bool,
    /// One sentence per limit missed (empty when all are met).
    pub failures: Vec<String>,
    /// What the commissioning cannot guarantee although the move met its
    /// limits (a thin margin over the identification's uncertainty).
    pub warnings: Vec<String>,
    /// The margins the commissioning guarantees over the uncertainty.
    pub guaranteed: GuaranteedMargins,
    /// The validation used a slower move than Table A.8 (the axis cannot do it).
    pub reduced_move: bool,
}

/// `x < limit`, false for NaN.
fn below(x: f64, limit: f64) -> bool {
    x.partial_cmp(&limit) == Some(std::cmp::Ordering::Less)
}

/// Judge a finished commissioning: the nonlinear-feedforward move against the
/// thesis' limits, saturation against `torque_max_nm`, the guaranteed margins.
pub fn judge(
    nonlinear: &MoveSummary,
    torque_max_nm: f64,
    guaranteed: GuaranteedMargins,
    reduced_move: bool,
) -> Verdict {
    let mut failures = Vec::new();
    if !below(nonlinear.max_tracking_error_m, MAX_TRACKING_ERROR_M) {
        failures.push(format!(
            "max cart error {:.3} mm is not below {:.1} mm",
            nonlinear.max_tracking_error_m * 1e3,
            MAX_TRACKING_ERROR_M * 1e3
        ));
    }
    if !below(nonlinear.static_error_m, MAX_STATIC_ERROR_M) {
        failures.push(format!(
            "static error {:.1} um is not below {:.0} um",
            nonlinear.static_error_m * 1e6,
            MAX_STATIC_ERROR_M * 1e6
        ));
    }
    if nonlinear.settling_time_s.is_none() {
        failures.push("the cart did not settle within the record".into());
    }
    if nonlinear.max_torque_nm >= torque_max_nm * (1.0 - 1e-6) {
        failures.push(format!(
            "the move saturated the drive at its torque limit {torque_max_nm:.3} N m"
        ));
    }
    let mut warnings = Vec::new();
    if below(
        guaranteed.velocity_phase_margin_deg,
        MIN_GUARANTEED_PHASE_MARGIN_DEG,
    ) || guaranteed.velocity_phase_margin_deg.is_nan()
    {
        warnings.push(format!(
            "the velocity loop's phase margin over the identification's uncertainty is {:.1} deg, below {:.0} deg",
            guaranteed.velocity_phase_margin_deg, MIN_GUARANTEED_PHASE_MARGIN_DEG
        ));
    }
    Verdict {
        meets_limits: failures.is_empty(),
        failures,
        warnings,
        guaranteed,
        reduced_move,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn good() -> MoveSummary {
        MoveSummary {
            max_tracking_error_m: 0.4e-3,
            static_error_m: 20e-6,
            settling_time_s: Some(0.1),
            max_motor_error_m: 1e-3,
            max_torque_nm: 1.5,
        }
    }

    fn margins_ok() -> GuaranteedMargins {
        GuaranteedMargins {
            velocity_phase_margin_deg: 50.0,
            velocity_gain_margin_db: 8.0,
            position_phase_margin_deg: 70.0,
            models: 18,
        }
    }

    /// Issue 12 ("silent bad successes"): a saturated move, a hunting axis
    /// that never settles, or a large error is a failed verdict, not a success.
    #[test]
    fn a_commissioning_that_misses_its_limits_says_so_issue_12() {
        assert!(judge(&good(), 3.1, margins_ok(), false).meets_limits);
        let saturated = MoveSummary {
            max_torque_nm: 3.1,
            ..good()
        };
        let v = judge(&saturated, 3.1, margins_ok(), false);
        assert!(
            !v.meets_limits && v.failures[0].contains("saturated"),
            "{v:?}"
        );
        let hunting = MoveSummary {
            settling_time_s: None,
            static_error_m: 300e-6,
            ..good()
        };
        let v = judge(&hunting, 3.1, margins_ok(), false);
        assert_eq!(v.failures.len(), 2, "{v:?}");
        let nan = MoveSummary {
            max_tracking_error_m: f64::NAN,
            ..good()
        };
        assert!(!judge(&nan, 3.1, margins_ok(), false).meets_limits);
        let thin = GuaranteedMargins {
            velocity_phase_margin_deg: 12.0,
            ..margins_ok()
        };
        let v = judge(&good(), 3.1, thin, false);
        assert!(v.meets_limits && v.warnings.len() == 1, "{v:?}");
    }
}
