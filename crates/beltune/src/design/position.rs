//! P position controller (thesis 4.3, (4.10)-(4.14)).
//!
//! The plant of the position loop is the closed velocity loop from the velocity
//! reference to the motor angle, with the prefilter inside it:
//! `G_w,cl = G_PI G_pre G_dt G_tau_phi / (1 + G_PI G_pre G_dt G_tau_phi G_R)` (4.10).
//! A P controller cannot shift the phase, so the crossover `w_c,phi` is fixed by
//! `arg G_w,cl(j w_c,phi) = -pi + PM` (4.13): the first frequency (from low
//! frequencies, where `G_w,cl` integrates, -90 deg) where the unwrapped phase
//! reaches that value. Then `K_PP = 1 / |G_w,cl(j w_c,phi)|` (4.14; the thesis
//! writes `K_P` there, a typo: the gain determined is the position gain `K_PP`).

use super::velocity::{PiGains, VelocityPlant};
use crate::lti::freq::unwrap_near;
use crate::lti::margins::{margins, StabilityMargins};
use crate::lti::C64;
use crate::{Error, Result};

/// `G_w,cl(j w)` (4.10), rad per rad/s.
pub fn closed_velocity_loop(gains: &PiGains, plant: &VelocityPlant, w_rad_s: f64) -> C64 {
    let fwd = gains.freq_response(w_rad_s) * plant.forward(w_rad_s);
    fwd / (1.0 + fwd * plant.velocity_filter(w_rad_s))
}

/// Result of the P design.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PositionDesign {
    /// `K_PP`, 1/s (rad/s of velocity reference per rad of position error).
    pub k_pp: f64,
    /// Margins of the continuous position open loop `K_PP G_w,cl`.
    pub margins: StabilityMargins,
}

/// Solve (4.13)/(4.14) for `K_PP` on `grid` (ascending, rad/s).
pub fn design_p(
    gains: &PiGains,
    plant: &VelocityPlant,
    pm_deg: f64,
    grid: &[f64],
) -> Result<PositionDesign> {
    if !(pm_deg > 0.0 && pm_deg < 180.0) {
        return Err(Error::invalid(
            "pm_position_deg",
            pm_deg,
            "the position phase margin must lie in (0, 180) degrees",
        ));
    }
    let g = |w: f64| closed_velocity_loop(gains, plant, w);
    let target = pm_deg - 180.0;
    // unwrapped phase along the grid, starting near -90 deg
    let mut prev_w = grid[0];
    let mut prev_phase = unwrap_near(g(prev_w).arg().to_degrees(), -90.0);
    if prev_phase <= target {
        return Err(Error::Infeasible {
            reason: format!(
                "the closed velocity loop integrates ({prev_phase:.1} deg at {prev_w:.3} rad/s), so a P position controller reaches at most 90 deg phase margin; {pm_deg} deg is out of reach"
            ),
        });
    }
    let mut bracket = None;
    for &w in &grid[1..] {
        let h = g(w);
        if !(h.re.is_finite() && h.im.is_finite()) {
            return Err(Error::NonFinite {
                what: format!("closed velocity loop at {w} rad/s"),
                index: 0,
            });
        }
        let phase = unwrap_near(h.arg().to_degrees(), prev_phase);
        if phase <= target {
            bracket = Some((prev_w, prev_phase, w));
            break;
        }
        prev_w = w;
        prev_phase = phase;
    }
    let Some((mut lo, lo_phase, mut hi)) = bracket else {
        return Err(Error::Infeasible {
            reason: format!(
                "the phase of the closed velocity loop never reaches {target} deg (position phase margin {pm_deg} deg) below {:.0} rad/s",
                grid[grid.len() - 1]
            ),
        });
    };
    let phase_at = |w: f64| unwrap_near(g(w).arg().to_degrees(), lo_phase);
    for _ in 0..200 {
        if hi / lo - 1.0 <= 1e-13 {
            break;
        }
        let mid = (lo * hi).sqrt();
        if phase_at(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let w_c = (lo * hi).sqrt();
    let k_pp = 1.0 / g(w_c).norm();
    let m = margins(|w| k_pp * g(w), grid)?;
    if m.gain_crossover_count != 1 || (m.crossover_rad_s / w_c - 1.0).abs() > 1e-6 {
        return Err(Error::Infeasible {
            reason: format!(
                "the position gain K_PP = {k_pp:.4} 1/s (chosen for the requested position phase margin, thesis eq. 4.14) gives {} gain crossovers of the position loop, expected one at {:.2} Hz: lower the position phase margin or the velocity loop dynamics",
                m.gain_crossover_count,
                w_c / (2.0 * std::f64::consts::PI)
            ),
        });
    }
    Ok(PositionDesign { k_pp, margins: m })
}
