//! The belt stiffness along the stroke (stages 5b and 5c): where the
//! validation move ends and near where it starts, so that the setpoint leads
//! the cart by the belt's stretch where it really is.

use crate::record::model::FrictionResult;
use serde::{Deserialize, Serialize};

/// The belt stiffness where the validation move ends, and how it changes
/// along the stroke: the static belt stretch the motor setpoint
/// leads by (`tau_hold / (i_t c)`) is that of the stiffness where the cart
/// rests, and the replacement stiffness (2.26) changes along the stroke (by
/// a factor two over a 0.5 m move on a soft belt). Its compliance `1 / c`
/// is exactly quadratic in the cart position for (2.26)
/// ([`beltune_rt::control::BeltProfile`]); with the stiffness measured at
/// three positions the quadratic is known, with two its slope.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetStiffness {
    /// Cart position the stiffness holds for, m.
    pub position_m: f64,
    /// Replacement belt stiffness `c` there, N/m.
    pub c_n_per_m: f64,
    /// Antiresonance `f_z` measured there, Hz.
    pub f_z_hz: f64,
    /// Whether it was measured by its own experiment at `position_m`;
    /// `false`: the identification position is close enough and its fit's
    /// `c` is used.
    pub measured: bool,
    /// Slope of the compliance `1 / c` along the stroke at `position_m`,
    /// 1/N (0: one stiffness for the whole stroke, as in older files).
    #[serde(default)]
    pub compliance_slope_per_n: f64,
    /// Half the compliance's second derivative, 1/(N m) (0: at most linear).
    #[serde(default)]
    pub compliance_curvature_per_n_m: f64,
}

/// Cart speed over which the setpoint's lead for the cart's Coulomb
/// friction ramps in and out (quadratically), m/s
/// ([`beltune_rt::control::BeltProfile::coulomb_velocity_m_s`]). The lead
/// `K F_c` retreats at `2 K F_c |a| / v_c^2` times the speed at the end of a
/// move; with the Table A.8 jerk (40 m/s^3, `|a| <= sqrt(2 j v)`) and a
/// 0.15 mm lead that stays below the speed, so the motor setpoint does not
/// reverse. A wider ramp left slow moves' carts short: inside it the belt
/// carries less than the kinetic friction (0.05 m/s left a heavy
/// cart on a slow reduced move 0.25 mm short; 0.02 m/s passed the 15
/// plants that missed 100 um with the wider or a linear ramp but one).
pub const CART_COULOMB_VELOCITY_M_S: f64 = 0.02;

impl TargetStiffness {
    /// One stiffness for the whole stroke.
    pub fn constant(position_m: f64, c_n_per_m: f64, f_z_hz: f64, measured: bool) -> Self {
        TargetStiffness {
            position_m,
            c_n_per_m,
            f_z_hz,
            measured,
            compliance_slope_per_n: 0.0,
            compliance_curvature_per_n_m: 0.0,
        }
    }

    /// The compliance alone as the setpoint conversion's belt model
    /// (positions as this record's; no mass, force or friction).
    fn compliance(&self) -> beltune_rt::control::BeltProfile<f64> {
        beltune_rt::control::BeltProfile {
            reference_m: self.position_m,
            compliance_m_per_n: 1.0 / self.c_n_per_m,
            compliance_slope_per_n: self.compliance_slope_per_n,
            compliance_curvature_per_n_m: self.compliance_curvature_per_n_m,
            ..Default::default()
        }
    }

    /// The belt compliance `1 / c` at cart position `xi_m`, m/N.
    pub fn compliance_at(&self, xi_m: f64) -> f64 {
        self.compliance().compliance_at(xi_m)
    }

    /// The belt stiffness at cart position `xi_m`, N/m.
    pub fn stiffness_at(&self, xi_m: f64) -> f64 {
        1.0 / self.compliance_at(xi_m)
    }

    /// The setpoint conversion's belt model for the moving mass `m_c_kg`
    /// and the force the belt carries at rest `static_force_n` (the
    /// holding torque over `i_t`), with positions measured from
    /// `origin_m` (the cart position at motor angle 0), and the cart's
    /// friction of `friction` (its stretch is led too, the Coulomb share
    /// ramped in over [`CART_COULOMB_VELOCITY_M_S`]).
    pub fn belt_profile(
        &self,
        m_c_kg: f64,
        static_force_n: f64,
        origin_m: f64,
        friction: &FrictionResult,
    ) -> beltune_rt::control::BeltProfile<f64> {
        beltune_rt::control::BeltProfile {
            m_c_kg,
            reference_m: self.position_m - origin_m,
            static_force_n,
            cart_viscous_n_s_per_m: friction.cart_viscous_n_s_per_m,
            cart_coulomb_n: friction.cart_coulomb_n,
            coulomb_velocity_m_s: CART_COULOMB_VELOCITY_M_S,
            ..self.compliance()
        }
    }

    /// The compliance through this point and the stiffness measured at
    /// `others` (cart position m, stiffness N/m; at most two, each at least
    /// `min_distance_m` from the others): linear through two points,
    /// quadratic through three. `None` when the result is not a belt over
    /// `window_m`: a compliance that is not positive, or that is not
    /// concave (a quadratic (2.26) opens downward) somewhere in the window.
    pub fn through(
        &self,
        others: &[(f64, f64)],
        window_m: (f64, f64),
        min_distance_m: f64,
    ) -> Option<TargetStiffness> {
        let mut pts = vec![(self.position_m, 1.0 / self.c_n_per_m)];
        for &(x, c) in others {
            if !(x.is_finite() && c.is_finite() && c > 0.0) {
                continue;
            }
            if pts.iter().all(|p| (p.0 - x).abs() >= min_distance_m) {
                pts.push((x, 1.0 / c));
            }
        }
        let r = self.position_m;
        let (slope, curvature) = match pts.len() {
            1 => (0.0, 0.0),
            2 => ((pts[1].1 - pts[0].1) / (pts[1].0 - pts[0].0), 0.0),
            _ => {
                // Newton's divided differences about the reference
                let (x0, y0) = pts[0];
                let (x1, y1) = pts[1];
                let (x2, y2) = pts[2];
                let d01 = (y1 - y0) / (x1 - x0);
                let d12 = (y2 - y1) / (x2 - x1);
                let k2 = (d12 - d01) / (x2 - x0);
                // slope at r = x0: d01 + k2 (x0 - x1)
                (d01 + k2 * (r - x1), k2)
            }
        };
        let out = TargetStiffness {
            compliance_slope_per_n: slope,
            compliance_curvature_per_n_m: curvature,
            ..*self
        };
        let (lo, hi) = window_m;
        let positive = [lo, hi, 0.5 * (lo + hi)]
            .iter()
            .all(|&x| out.compliance_at(x).is_finite() && out.compliance_at(x) > 0.0);
        (positive && curvature <= 0.0 && slope.is_finite()).then_some(out)
    }
}
