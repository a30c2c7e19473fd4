//! Whether a commissioning met its own limits (issue 12; the report's verdict
//! box is [`super::verdict`]): a commissioning
//! that ends with a controller but misses the thesis' accuracy, saturates the
//! drive, never settles, or cannot guarantee its margins against the
//! identification's uncertainty says so, in the library result
//! ([`Verdict::meets_limits`]) and in the CLI's exit status 5.

use super::result::MoveSummary;
use crate::design::ControllerDesign;
use crate::lti::margins::margins;
use crate::model::TwoMassParams;
use crate::Result;
use serde::{Deserialize, Serialize};

/// Thesis chapter 5: largest cart tracking error with nonlinear feedforward, m.
pub const MAX_TRACKING_ERROR_M: f64 = 1e-3;
/// Thesis chapter 5: static positioning error, m.
pub const MAX_STATIC_ERROR_M: f64 = 100e-6;
/// Smallest velocity-loop phase margin the commissioning accepts over the
/// identification's uncertainty, deg.
pub const MIN_GUARANTEED_PHASE_MARGIN_DEG: f64 = 30.0;
/// Width of the uncertainty box in standard deviations of the fit.
pub const UNCERTAINTY_SIGMAS: f64 = 2.0;

/// The margins of the delivered velocity and position loops on the worst model
/// of the identification's uncertainty box: `m_c` and `c` each at `+-2 sigma`,
/// and the motor and cart damping `d_m`, `d_c` either as given (the fit's,
/// bounded by the measured viscous friction) or half of that (the viscous
/// friction's own uncertainty).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GuaranteedMargins {
    /// Smallest velocity-loop phase margin over the box, deg.
    pub velocity_phase_margin_deg: f64,
    /// Smallest velocity-loop gain margin over the box, dB.
    pub velocity_gain_margin_db: f64,
    /// Smallest position-loop phase margin over the box, deg.
    pub position_phase_margin_deg: f64,
    /// Models of the box evaluated.
    pub models: usize,
}

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

/// The margins of a controller on a plant other than its design model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarginsOn {
    /// Velocity-loop phase margin, deg: over every gain crossover the
    /// smallest angular distance of `L` from -180 deg (a lightly damped
    /// resonance crosses 0 dB too, at any phase); negative when the sampled
    /// closed loop is unstable.
    pub velocity_phase_margin_deg: f64,
    /// Velocity-loop gain margin, dB.
    pub velocity_gain_margin_db: f64,
    /// Position-loop phase margin, deg (same rule).
    pub position_phase_margin_deg: f64,
    /// Whether both sampled closed loops are stable (poles inside the unit circle).
    pub stable: bool,
}

/// Smallest angular distance of `L(j w_c)` from -180 deg over the gain
/// crossovers `w_c` of `l` on `grid`, deg (NaN without a crossover).
fn nyquist_phase_margin_deg(l: impl Fn(f64) -> crate::lti::C64, grid: &[f64]) -> Result<f64> {
    let crossings = crate::lti::margins::gain_crossovers(&l, grid)?;
    Ok(crossings
        .iter()
        .map(|&w| {
            let a = l(w).arg().to_degrees() + 180.0;
            let d = a.rem_euclid(360.0);
            d.min(360.0 - d)
        })
        .fold(f64::NAN, f64::min))
}

/// Margins of `design`'s controller (prefilter, PI, P gains, sampled
/// controller) on `model` instead of the model it was designed on.
pub fn margins_on(design: &ControllerDesign, model: &TwoMassParams) -> Result<MarginsOn> {
    let mut other = design.clone();
    other.input.model = *model;
    let grid = crate::design::verification_grid(&other.input)?;
    let pm_v = nyquist_phase_margin_deg(|w| other.velocity_open_loop(w), &grid)?;
    let pm_p = nyquist_phase_margin_deg(|w| other.position_open_loop(w), &grid)?;
    let gm_v = margins(|w| other.velocity_open_loop(w), &grid)
        .map(|m| m.gain_margin_db)
        .unwrap_or(f64::NAN);
    let stable = crate::design::sampled::DiscreteLoops::new(&other.discrete, &other.input)
        .and_then(|l| crate::design::sampled::check_stability(&l))
        .is_ok();
    let sign = if stable { 1.0 } else { -1.0 };
    Ok(MarginsOn {
        velocity_phase_margin_deg: sign * pm_v,
        velocity_gain_margin_db: gm_v,
        position_phase_margin_deg: sign * pm_p,
        stable,
    })
}

/// The guaranteed margins of `design` over the box around `model` with
/// one-sigma uncertainties `m_c_sigma_kg`, `c_sigma_n_per_m` (NaN: 5 %).
pub fn guaranteed_margins(
    design: &ControllerDesign,
    model: &TwoMassParams,
    m_c_sigma_kg: f64,
    c_sigma_n_per_m: f64,
) -> Result<GuaranteedMargins> {
    let sm = if m_c_sigma_kg.is_finite() {
        m_c_sigma_kg
    } else {
        0.05 * model.m_c
    };
    let sc = if c_sigma_n_per_m.is_finite() {
        c_sigma_n_per_m
    } else {
        0.05 * model.c
    };
    let k = UNCERTAINTY_SIGMAS;
    let mut out = GuaranteedMargins {
        velocity_phase_margin_deg: f64::INFINITY,
        velocity_gain_margin_db: f64::INFINITY,
        position_phase_margin_deg: f64::INFINITY,
        models: 0,
    };
    for dm in [-1.0, 0.0, 1.0] {
        for dc in [-1.0, 0.0, 1.0] {
            for damped in [true, false] {
                let mut m = *model;
                m.m_c = (model.m_c + dm * k * sm).max(0.2 * model.m_c);
                m.c = (model.c + dc * k * sc).max(0.2 * model.c);
                if !damped {
                    m.d_m *= 0.5;
                    m.d_c *= 0.5;
                }
                let on = margins_on(design, &m)?;
                let (pm_v, gm_v, pm_p) = (
                    on.velocity_phase_margin_deg,
                    on.velocity_gain_margin_db,
                    on.position_phase_margin_deg,
                );
                let worse = |a: f64, b: f64| {
                    if a.is_nan() || b.is_nan() {
                        f64::NAN
                    } else {
                        a.min(b)
                    }
                };
                out.velocity_phase_margin_deg = worse(out.velocity_phase_margin_deg, pm_v);
                out.velocity_gain_margin_db = worse(out.velocity_gain_margin_db, gm_v);
                out.position_phase_margin_deg = worse(out.position_phase_margin_deg, pm_p);
                out.models += 1;
            }
        }
    }
    Ok(out)
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
