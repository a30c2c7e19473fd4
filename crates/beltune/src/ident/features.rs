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
    frf_features_in(frf, None)
}

/// [`frf_features`] with the antiresonance searched inside `band_hz`
/// (`[lowest, highest]`, Hz; the data sheet's range) where given: a dip
/// outside the range the axis' physics allows is not its antiresonance. A
/// heavy motor on a light cart (inertia ratio 0.23, resonance 1.1 times the
/// antiresonance at 133-203 Hz) showed no dip deep enough near its
/// resonance, and a dip the friction shaped near 8 Hz was taken instead
/// (start `m_c` 1.3 kg, `c` 3.7 kN/m; the fit ran to its edge). Inside the
/// band a shallow dip counts when it is the one next to the resonance: with
/// `f_r / f_z` near 1 (2.47) the peak over the dip,
/// `kappa^2 / (4 zeta_z zeta_r (1 + kappa))`, is about 1. Where the band
/// holds no dip, the search falls back to the whole band below the resonance.
pub fn frf_features_in(frf: &Frf, band_hz: Option<[f64; 2]>) -> Result<FrfFeatures> {
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
    // (sim-a's "resonance" at 613 Hz next to the PRBS null).
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
    // deeper than its neighbours to count (seed 13 plant #23, a
    // sticky, very viscous axis, dip at 14.7 Hz on two lines; seed 14 #378,
    // 24.6 kg on a soft belt, at 7.3 Hz).
    let local_min = |v: &[f64], k: usize| v[k] < v[k - 1] && v[k] <= v[k + 1];
    // A dip at the foot of the resonance is a wiggle of its flank, not an
    // antiresonance: (2.42) puts |G| w^2 at w_z far below its peak (issue 12:
    // seed 14 #994, a 2 % wiggle 2 Hz below a broad 86 Hz peak).
    let deep = |k: usize| comp[k] < DIP_BELOW_PEAK * comp[peak];
    let in_band =
        |k: usize| band_hz.is_none_or(|[lo, hi]| (lo..=hi).contains(&frf.freq_hz[idx[k]]));
    let depth = |k: usize| raw[k] / (0.5 * (raw[k - 1] + raw[k + 1]));
    let deepest = |inside: &dyn Fn(usize) -> bool| {
        (1..peak)
            .filter(|&k| local_min(&comp, k) && deep(k) && inside(k))
            .min_by(|&a, &b| comp[a].total_cmp(&comp[b]))
            .or_else(|| {
                (1..peak)
                    .filter(|&k| {
                        local_min(&raw, k) && depth(k) < NARROW_DIP_DEPTH && deep(k) && inside(k)
                    })
                    .min_by(|&a, &b| depth(a).total_cmp(&depth(b)))
            })
    };
    let dip = deepest(&in_band)
        .or_else(|| {
            // inside the data sheet's range a shallow dip counts when it is
            // the one next to the resonance (a resonance 1.1 times its
            // antiresonance leaves no room for a deep one)
            band_hz?;
            (1..peak)
                .rev()
                .find(|&k| local_min(&comp, k))
                .filter(|&k| in_band(k))
        })
        // the range may be wrong: a clear dip anywhere below the resonance
        .or_else(|| band_hz.and_then(|_| deepest(&|_| true)));
    let f = |k: usize| frf.freq_hz[idx[k]];
    let (dip, antiresonance_hz) = match dip {
        Some(dip) => {
            // The antiresonance is low in frequency where the response is
            // strong: its sharp dip is refined on the raw lines next to the
            // smoothed minimum.
            let dip = (dip.saturating_sub(MEDIAN_HALF_WIDTH).max(1)
                ..(dip + MEDIAN_HALF_WIDTH + 1).min(peak))
                .min_by(|&a, &b| raw[a].total_cmp(&raw[b]))
                .unwrap_or(dip);
            let hz = parabolic_vertex(
                [f(dip - 1), f(dip), f(dip + 1)],
                [raw[dip - 1].ln(), raw[dip].ln(), raw[dip + 1].ln()],
            );
            (dip, hz)
        }
        None => {
            let hz = flank_antiresonance_hz(frf, &idx, &raw, f(peak)).ok_or_else(|| {
                Error::FitFailed {
                    reason: "no antiresonance dip below the resonance inside the usable band"
                        .into(),
                }
            })?;
            let nearest = (1..peak)
                .min_by(|&a, &b| (f(a) - hz).abs().total_cmp(&(f(b) - hz).abs()))
                .unwrap_or(1);
            (nearest, hz)
        }
    };
    let resonance_hz = parabolic_vertex(
        [f(peak - 1), f(peak), f(peak + 1)],
        [comp[peak - 1].ln(), comp[peak].ln(), comp[peak + 1].ln()],
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
    let asymptote_lines = low.len();
    let rigid_inertia = median(low.into_iter());
    Ok(FrfFeatures {
        resonance_hz,
        antiresonance_hz,
        resonance_magnitude: comp[peak] / frf.omega_rad_s(idx[peak]).powi(2),
        antiresonance_magnitude: frf.response[idx[dip]].norm(),
        rigid_inertia,
        asymptote_lines,
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

/// A local minimum of `|G| w^2` counts as the antiresonance only below this
/// fraction of the resonance peak. Undamped, (2.42) puts it at zero; with
/// modal damping `zeta_z`, `zeta_r` the peak over the dip is
/// `kappa^2 / (4 zeta_z zeta_r (1 + kappa))` (inertia ratio `kappa`, (2.46)),
/// 3.7 for egc70's empty cart (`kappa` about 2) at damping 0.3 on both modes
/// and 8 at 0.2; the factor of 2 asked here fails only at `kappa` near 2
/// with damping above 0.4. The flank wiggle of seed 14 #994 lay at 0.98.
const DIP_BELOW_PEAK: f64 = 0.5;

/// The flank of the resonance the antiresonance is read from when the FRF
/// shows no dip, as fractions of the resonance frequency: far enough above a
/// low antiresonance that friction does not distort the lines, far enough
/// below the resonance that its damping does not (seed 14 #994: the lines of
/// 0.15-0.5 f_r gave 10.0 Hz, of 0.1-0.5 9.8 Hz, of 0.15-0.4 9.8 Hz).
const FLANK_BAND: (f64, f64) = (0.15, 0.5);

/// The band above the resonance `|G| w^2` gives `1/Theta_e` in (fractions
/// of the resonance frequency); the resonance's damping is negligible there.
const HIGH_BAND: (f64, f64) = (2.0, 5.0);

/// Fewest lines in each of [`FLANK_BAND`] and [`HIGH_BAND`] for the flank
/// estimate.
const FLANK_MIN_LINES: usize = 3;

/// The antiresonance of an FRF that shows no dip below its resonance, read
/// from the resonance's rising flank, Hz; `None` where the band lacks lines.
///
/// A heavy cart on a soft belt with much Coulomb friction puts the
/// antiresonance at a few Hz, where the cart sticks for part of each PRBS
/// period and friction, not the belt, shapes the lines (seed 14
/// #994, 24 kg, Coulomb x2.9, its dip 0.7 of its neighbours, level with the
/// friction's scatter). Above the dip the undamped two-mass shape of (2.42),
/// written with `w_r` and `Theta_e` (`J = Theta_e (w_r/w_z)^2`), is
/// `|G| w^2 = (w^2 - w_z^2) / (Theta_e |w_r^2 - w^2|)`, linear in
/// `(1/Theta_e, w_z^2)`: the lines far above the resonance give `Theta_e`
/// (for a given `w_z`), the lines of the flank give `w_z^2` (for a given
/// `Theta_e`); a few alternations of both medians converge (they are nearly
/// decoupled: `w_z^2` is a small correction above the resonance).
fn flank_antiresonance_hz(frf: &Frf, idx: &[usize], raw: &[f64], resonance_hz: f64) -> Option<f64> {
    let in_band = |band: (f64, f64)| -> Vec<(f64, f64)> {
        idx.iter()
            .zip(raw)
            .filter(|(&i, _)| {
                let r = frf.freq_hz[i] / resonance_hz;
                r > band.0 && r < band.1
            })
            .map(|(&i, &m)| (frf.omega_rad_s(i).powi(2), m))
            .collect()
    };
    let (flank, high) = (in_band(FLANK_BAND), in_band(HIGH_BAND));
    if flank.len() < FLANK_MIN_LINES || high.len() < FLANK_MIN_LINES {
        return None;
    }
    let wr2 = (2.0 * PI * resonance_hz).powi(2);
    let mut wz2 = 0.0;
    for _ in 0..FLANK_ITERATIONS {
        let theta_e = median(high.iter().map(|&(w2, m)| (w2 - wz2) / (m * (w2 - wr2))));
        wz2 = median(flank.iter().map(|&(w2, m)| w2 - m * theta_e * (wr2 - w2)));
        if wz2.is_nan() || wz2 <= 0.0 {
            return None;
        }
    }
    Some(wz2.sqrt() / (2.0 * PI))
}

/// Alternations of the flank estimate; the second already agrees with the
/// fifth to 0.1 % on seed 14 #994.
const FLANK_ITERATIONS: usize = 5;

/// Median of a non-empty sequence (the upper one of an even count).
fn median(x: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = x.collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

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
            median(x[lo..hi].iter().copied())
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
    use crate::model::TwoMassParams;

    #[test]
    fn parabola_vertex_is_exact_for_a_parabola() {
        let p = |x: f64| -(x - 2.3).powi(2) + 4.0;
        let v = parabolic_vertex([2.0, 2.5, 3.5], [p(2.0), p(2.5), p(3.5)]);
        assert!((v - 2.3).abs() < 1e-12);
    }

    /// An FRF of the analytic two-mass model (2.42) on the PRBS line grid
    /// (1.2236 Hz to 530 Hz), its lines below `fill_below_hz` replaced by a
    /// level rising from a third of the rigid-body one, scattered by 10 %
    /// line to line (a sticking cart: friction, not the belt, shapes them;
    /// #994's lines below its dip lay at 0.4-0.7 of `1/J`, rising).
    fn distorted_frf(p: &TwoMassParams, fill_below_hz: f64) -> Frf {
        let tf = p.tf_torque_to_motor_angle();
        let freq_hz: Vec<f64> = (1..=433).map(|k| k as f64 * 1.2236).collect();
        let level = 0.3 / p.rigid_inertia();
        let response = freq_hz
            .iter()
            .enumerate()
            .map(|(k, &f)| {
                let w = 2.0 * PI * f;
                let g = tf.freq_response(w);
                if f < fill_below_hz {
                    let scatter = if k % 2 == 0 { 1.1 } else { 0.9 };
                    g / g.norm() * level * (1.0 + 3.0 * f / fill_below_hz) * scatter / (w * w)
                } else {
                    g
                }
            })
            .collect();
        let n = freq_hz.len();
        Frf {
            freq_hz,
            response,
            coherence: vec![1.0; n],
            line_status: vec![super::super::etfe::LineStatus::Usable; n],
            input_power: vec![1.0; n],
            ts_s: 1e-4,
            n_periods: 4,
        }
    }

    /// A heavy motor on a light cart (the zoo's heavy-motor-light-cart:
    /// `Theta_e` 200.7 kg mm^2, 0.3 kg, inertia ratio 0.23, f_z 120 Hz, the
    /// resonance 1.11 times higher) with the belt damping of a real belt:
    /// its dip is shallow, while friction carves a deep one near 8 Hz. Without
    /// a range the deep one is taken (the fit then ran to its edge); inside
    /// the data sheet's range (-35 % / +10 % of 120-185 Hz) the true one is
    /// found within 10 % (a start value, as the flank's: the damped dip lies
    /// a little below `f_z`; the fit then lands the zoo axis' f_z 0.5 % off).
    #[test]
    fn the_antiresonance_is_searched_where_the_data_sheet_allows_it() {
        let p = TwoMassParams {
            theta_e: 200.73e-6,
            m_c: 0.3,
            c: 0.3 * (2.0 * PI * 120.0_f64).powi(2),
            d: 22.0,
            d_m: 1.0,
            d_c: 1.0,
            i_t: 0.0124141,
        };
        assert!((p.inertia_ratio() - 0.23).abs() < 0.01);
        let mut frf = distorted_frf(&p, 0.0);
        for (f, g) in frf.freq_hz.iter().zip(frf.response.iter_mut()) {
            if (*f - 8.0).abs() < 2.0 {
                *g *= 0.3;
            }
        }
        let anywhere = frf_features(&frf).unwrap();
        assert!(anywhere.antiresonance_hz < 20.0, "{anywhere:?}");
        let band = [0.65 * 120.0, 1.1 * 185.0];
        let inside = frf_features_in(&frf, Some(band)).unwrap();
        assert!(
            (inside.antiresonance_hz / p.f_z_hz() - 1.0).abs() < 0.10,
            "f_z {:.2} Hz, true {:.2} Hz",
            inside.antiresonance_hz,
            p.f_z_hz()
        );
        assert!((inside.resonance_hz / p.f_r_hz() - 1.0).abs() < 0.03);
    }

    /// A data sheet that is wrong about the stiffness (its range above the
    /// true antiresonance) does not hide a clear dip: the search falls back
    /// to the whole band below the resonance.
    #[test]
    fn a_clear_dip_outside_a_wrong_data_sheet_range_is_still_found() {
        let p = TwoMassParams::thesis_table_a4();
        let frf = distorted_frf(&p, 0.0);
        let fz = p.f_z_hz();
        let f = frf_features_in(&frf, Some([1.5 * fz, 2.5 * fz])).unwrap();
        assert!(
            (f.antiresonance_hz / fz - 1.0).abs() < 0.03,
            "{f:?} vs {fz}"
        );
    }

    /// Seed 14 #994 (24 kg on a soft belt, Coulomb x2.9): friction
    /// hid the antiresonance and a wiggle on the resonance's flank was taken
    /// for it, which started the fit at a tenth of the cart mass (the
    /// wiggle, a median artefact of a noisy flat top, is refused by
    /// `DIP_BELOW_PEAK`; the study test of #994 covers it). Here an analytic
    /// plant of the same shape (f_z 11 Hz, f_r 82 Hz) loses its dip to a
    /// friction-like fill; the features must read f_z from the flank within
    /// 10 % (measured 4.5 %; the fit refines it: #994 commissions with f_z
    /// 0.7 % and m_c 1.6 % off). Without the flank estimate: "no
    /// antiresonance dip".
    #[test]
    fn a_hidden_antiresonance_is_read_from_the_resonance_flank() {
        let p = TwoMassParams {
            theta_e: 71.7e-6,
            m_c: 25.0,
            c: 1.2e5,
            d: 0.0,
            d_m: 3.0,
            d_c: 200.0,
            i_t: 0.0124,
        };
        let (fz, fr) = (p.f_z_hz(), p.f_r_hz());
        assert!(
            (fz - 11.0).abs() < 0.2 && (fr - 81.5).abs() < 1.0,
            "{fz} {fr}"
        );
        let feat = frf_features(&distorted_frf(&p, 1.5 * fz)).unwrap();
        assert!((feat.resonance_hz / fr - 1.0).abs() < 0.03, "{feat:?}");
        assert!(
            (feat.antiresonance_hz / fz - 1.0).abs() < FLANK_TOL,
            "f_z {:.2} Hz, true {fz:.2} Hz",
            feat.antiresonance_hz
        );
    }

    /// Tolerance of the flank estimate of f_z (relative): the undamped shape
    /// it inverts is off by the modal damping on the flank.
    const FLANK_TOL: f64 = 0.1;

    /// The same grid without distortion: the dip itself is found (the flank
    /// is a fallback), within the 2 % of the f_z target.
    #[test]
    fn an_undistorted_antiresonance_is_found_at_its_dip() {
        let p = TwoMassParams::thesis_table_a4();
        let frf = distorted_frf(&p, 0.0);
        let clean = frf_features(&frf).unwrap();
        assert!(
            (clean.antiresonance_hz / p.f_z_hz() - 1.0).abs() < 0.02,
            "{clean:?}"
        );
    }
}
