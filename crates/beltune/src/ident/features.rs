//! Features of a measured torque -> motor angle FRF that need no model fit:
//! resonance peak, antiresonance dip and the rigid-body (low-frequency)
//! asymptote. They give the start values of the parametric fit (3.34), so no
//! user guess is needed, and an independent check of the fitted model.
//!
//! The FRF of (2.42) falls with `1/w^2`; the features are searched in the
//! compensated magnitude `|G| w^2`, which is `1/J_rigid` far below the
//! antiresonance, has its minimum at `w_z` and its maximum at `w_r`.

use super::etfe::Frf;
use crate::{Error, Result};
use std::f64::consts::PI;

/// What the measured FRF shows by itself.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FrfFeatures {
    /// Resonance (peak of `|G| w^2`), Hz, refined by a parabola through three lines.
    pub resonance_hz: f64,
    /// Antiresonance (dip of `|G| w^2` below the resonance), Hz, refined likewise.
    pub antiresonance_hz: f64,
    /// `|G|` at the resonance line, rad per input unit.
    pub resonance_magnitude: f64,
    /// `|G|` at the antiresonance line, rad per input unit.
    pub antiresonance_magnitude: f64,
    /// Rigid-body inertia `Theta_e + i_t^2 m_c` from the low-frequency
    /// asymptote `|G| ~ 1/(J w^2)`, input unit s^2/rad (kg m^2 for torque in N m).
    pub rigid_inertia: f64,
    /// Number of lines the asymptote was averaged over.
    pub asymptote_lines: usize,
}

/// Find resonance, antiresonance and the low-frequency asymptote among the
/// usable lines of `frf` (a torque -> angle FRF with the integrator).
///
/// The rigid inertia uses the lines below the antiresonance, each corrected
/// by the undamped two-mass shape `|1 - (w/w_z)^2| / |1 - (w/w_r)^2|` (from
/// (2.40)-(2.42)), and takes the median.
///
/// Errors ([`Error::FitFailed`]): fewer than 5 usable lines, no interior
/// maximum (resonance) or no interior minimum below it (antiresonance).
pub fn frf_features(frf: &Frf) -> Result<FrfFeatures> {
    let idx = feature_lines(frf);
    if idx.len() < 5 {
        return Err(Error::FitFailed {
            reason: format!(
                "only {} usable frequency lines (excited and coherent); need at least 5",
                idx.len()
            ),
        });
    }
    let raw: Vec<f64> = idx
        .iter()
        .map(|&i| frf.response[i].norm() * frf.omega_rad_s(i).powi(2))
        .collect();
    // A running median over neighbouring lines: a single noisy line (the
    // encoder's quantization against a weak input) is not a resonance
    // (issue 12: sim-a's "resonance" at 613 Hz next to the PRBS null).
    let comp = running_median(&raw, MEDIAN_HALF_WIDTH);
    // resonance: the largest interior local maximum of |G| w^2
    let peak = (1..idx.len() - 1)
        .filter(|&k| comp[k] > comp[k - 1] && comp[k] >= comp[k + 1])
        .max_by(|&a, &b| comp[a].total_cmp(&comp[b]))
        .ok_or_else(|| Error::FitFailed {
            reason: "no resonance peak inside the usable band".into(),
        })?;
    // antiresonance: the deepest interior local minimum below the resonance;
    // a dip narrower than the running median (two lines on a short PRBS
    // period) survives only on the raw lines, where it must be clearly
    // deeper than its neighbours to count (issue 12: seed 13 plant #23, a
    // sticky, very viscous axis, dip at 14.7 Hz on two lines; seed 14 #378,
    // 24.6 kg on a soft belt, at 7.3 Hz).
    let local_min = |v: &[f64], k: usize| v[k] < v[k - 1] && v[k] <= v[k + 1];
    let dip = (1..peak)
        .filter(|&k| local_min(&comp, k))
        .min_by(|&a, &b| comp[a].total_cmp(&comp[b]))
        .or_else(|| {
            let depth = |k: usize| raw[k] / (0.5 * (raw[k - 1] + raw[k + 1]));
            (1..peak)
                .filter(|&k| local_min(&raw, k) && depth(k) < NARROW_DIP_DEPTH)
                .min_by(|&a, &b| depth(a).total_cmp(&depth(b)))
        })
        .ok_or_else(|| Error::FitFailed {
            reason: "no antiresonance dip below the resonance inside the usable band".into(),
        })?;
    // The antiresonance is low in frequency where the response is strong: its
    // sharp dip is refined on the raw lines next to the smoothed minimum.
    let dip = (dip.saturating_sub(MEDIAN_HALF_WIDTH).max(1)
        ..(dip + MEDIAN_HALF_WIDTH + 1).min(peak))
        .min_by(|&a, &b| raw[a].total_cmp(&raw[b]))
        .unwrap_or(dip);
    let f = |k: usize| frf.freq_hz[idx[k]];
    let resonance_hz = parabolic_vertex(
        [f(peak - 1), f(peak), f(peak + 1)],
        [comp[peak - 1].ln(), comp[peak].ln(), comp[peak + 1].ln()],
    );
    let antiresonance_hz = parabolic_vertex(
        [f(dip - 1), f(dip), f(dip + 1)],
        [raw[dip - 1].ln(), raw[dip].ln(), raw[dip + 1].ln()],
    );

    // rigid-body asymptote from the lines below 0.7 f_z (at least those below f_z)
    let wz = 2.0 * PI * antiresonance_hz;
    let wr = 2.0 * PI * resonance_hz;
    let estimate = |k: usize| {
        let w = frf.omega_rad_s(idx[k]);
        let shape = (1.0 - (w / wz).powi(2)).abs() / (1.0 - (w / wr).powi(2)).abs();
        shape / raw[k]
    };
    let mut low: Vec<f64> = (0..dip)
        .filter(|&k| f(k) < 0.7 * antiresonance_hz)
        .map(estimate)
        .collect();
    if low.is_empty() {
        low = (0..dip).map(estimate).collect();
    }
    if low.is_empty() {
        return Err(Error::FitFailed {
            reason: "no usable line below the antiresonance for the rigid-body asymptote".into(),
        });
    }
    low.sort_by(f64::total_cmp);
    let rigid_inertia = low[low.len() / 2];
    Ok(FrfFeatures {
        resonance_hz,
        antiresonance_hz,
        resonance_magnitude: comp[peak] / frf.omega_rad_s(idx[peak]).powi(2),
        antiresonance_magnitude: frf.response[idx[dip]].norm(),
        rigid_inertia,
        asymptote_lines: low.len(),
    })
}

/// Half width (in lines) of the running median of the compensated magnitude.
const MEDIAN_HALF_WIDTH: usize = 2;

/// A raw line counts as a narrow antiresonance (one the running median
/// erased) only below this fraction of the mean of its two neighbours. The
/// dip lines of seed 13 plant #23 and seed 14 plant #378 lay at 0.41 and
/// 0.47 of it; a single line's relative scatter at coherence 0.9 is about a
/// quarter (one sigma), so a factor of two is not noise.
const NARROW_DIP_DEPTH: f64 = 0.5;

/// Lines whose input power is more than this far below the strongest line
/// are left out of the features: there the response is mostly measurement
/// noise (a PRBS has its spectral null at the clock frequency), dB.
pub const FEATURE_EXCITATION_FLOOR_DB: f64 = -15.0;

/// The usable lines with an input power within [`FEATURE_EXCITATION_FLOOR_DB`]
/// of the strongest usable line.
pub fn feature_lines(frf: &Frf) -> Vec<usize> {
    let idx = frf.usable_indices();
    let max = idx.iter().map(|&i| frf.input_power[i]).fold(0.0, f64::max);
    let floor = max * 10f64.powf(FEATURE_EXCITATION_FLOOR_DB / 10.0);
    idx.into_iter()
        .filter(|&i| frf.input_power[i] >= floor)
        .collect()
}

/// Median of `x[k - h ..= k + h]` (clipped at the ends) for every `k`.
pub(crate) fn running_median(x: &[f64], h: usize) -> Vec<f64> {
    (0..x.len())
        .map(|k| {
            let lo = k.saturating_sub(h);
            let hi = (k + h + 1).min(x.len());
            let mut w: Vec<f64> = x[lo..hi].to_vec();
            w.sort_by(f64::total_cmp);
            w[w.len() / 2]
        })
        .collect()
}

/// Abscissa of the vertex of the parabola through three points; the middle
/// abscissa when the points are collinear or the vertex leaves the interval.
fn parabolic_vertex(x: [f64; 3], y: [f64; 3]) -> f64 {
    let d1 = (y[1] - y[0]) / (x[1] - x[0]);
    let d2 = (y[2] - y[1]) / (x[2] - x[1]);
    let curv = (d2 - d1) / (x[2] - x[0]);
    if curv == 0.0 || !curv.is_finite() {
        return x[1];
    }
    // y' = d1 + curv (2 x - x0 - x1) = 0
    let v = 0.5 * (x[0] + x[1] - d1 / curv);
    if v > x[0] && v < x[2] {
        v
    } else {
        x[1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_vertex_is_exact_for_a_parabola() {
        let p = |x: f64| -(x - 2.3).powi(2) + 4.0;
        let v = parabolic_vertex([2.0, 2.5, 3.5], [p(2.0), p(2.5), p(3.5)]);
        assert!((v - 2.3).abs() < 1e-12);
    }
}
