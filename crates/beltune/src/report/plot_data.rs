//! The plot data of a commissioning, computed once here and used by the
//! report, the tuning page (`beltune serve`) and `beltune compare`: the loops
//! of a design on one frequency grid, the measured FRF with its phase
//! unwrapped against the fitted model and decimated for display. The data
//! files that hold them are [`super::data_files`].

use crate::design::ControllerDesign;
use crate::ident::Frf;
use crate::lti::freq::unwrap_near as unwrap_near_deg;
use crate::lti::{bode, feedback, log_grid, BodePoint, Tf, C64};
use crate::report::{BodeCurve, FrequencyMarker, FrfPlot};
use crate::Result;
use std::f64::consts::PI;

/// Points of the loop plots (log-spaced): enough to draw the resonance; the
/// margins come from the design's own fine grid, not from these points.
pub const LOOP_PLOT_POINTS: usize = 400;
/// Decades of the loop plot grid below the lowest of the antiresonance and the
/// two crossovers.
pub const LOOP_PLOT_DECADES_BELOW: f64 = 2.0;
/// The loop plot grid ends at this multiple of the highest of resonance and
/// velocity crossover (or at the Nyquist frequency, if lower): beyond it the
/// dead time only turns the phase by whole turns and hides the margins.
pub const LOOP_PLOT_TOP_FACTOR: f64 = 4.0;
/// Largest number of points of the measured FRF drawn (log-spaced bins, the
/// lines of a bin averaged); the full data goes to `frf.csv`.
pub const FRF_DISPLAY_POINTS: usize = 250;
/// Points of the fitted model curve in the FRF plot.
pub const FRF_MODEL_POINTS: usize = 400;
/// Largest number of samples of a time trace drawn.
pub const TRACE_POINTS: usize = 1500;

/// The loops of a design on one frequency grid (Hz).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LoopData {
    /// Frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Velocity open loop `L` (4.5)-(4.6).
    pub velocity_open_loop: BodeCurve,
    /// Closed velocity loop `L / (1 + L)`.
    pub velocity_closed_loop: BodeCurve,
    /// Sensitivity of the velocity loop `1 / (1 + L)`.
    pub velocity_sensitivity: BodeCurve,
    /// Position open loop `K_PP G_w,cl`.
    pub position_open_loop: BodeCurve,
    /// Closed position loop.
    pub position_closed_loop: BodeCurve,
    /// Sensitivity of the position loop.
    pub position_sensitivity: BodeCurve,
    /// Controller `G_pre G_PI`: velocity error -> torque.
    pub controller: BodeCurve,
}

/// The frequency grid of the loop plots, Hz: [`LOOP_PLOT_DECADES_BELOW`]
/// decades below the lowest of antiresonance and crossovers up to
/// [`LOOP_PLOT_TOP_FACTOR`] times the resonance (at most Nyquist),
/// [`LOOP_PLOT_POINTS`] log-spaced points.
pub fn loop_grid_hz(des: &ControllerDesign) -> Result<Vec<f64>> {
    let lowest = des
        .omega_z_rad_s
        .min(des.velocity_margins.crossover_rad_s)
        .min(des.position_margins.crossover_rad_s);
    let highest = des.omega_r_rad_s.max(des.velocity_margins.crossover_rad_s);
    let nyquist = PI / des.input.ts_s;
    let w_max = if highest.is_finite() && highest > 0.0 {
        (LOOP_PLOT_TOP_FACTOR * highest).min(nyquist)
    } else {
        nyquist
    };
    let w_min = lowest * 10f64.powf(-LOOP_PLOT_DECADES_BELOW);
    let w_min = if w_min.is_finite() && w_min > 0.0 && w_min < w_max {
        w_min
    } else {
        w_max * 1e-5
    };
    Ok(log_grid(w_min, w_max, LOOP_PLOT_POINTS)?
        .into_iter()
        .map(|w| w / (2.0 * PI))
        .collect())
}

fn to_curve(label: &str, points: &[BodePoint]) -> BodeCurve {
    BodeCurve {
        label: label.into(),
        freq_hz: points.iter().map(|p| p.omega_rad_s / (2.0 * PI)).collect(),
        magnitude_db: points.iter().map(|p| p.magnitude_db).collect(),
        phase_deg: points.iter().map(|p| p.phase_deg).collect(),
        ..BodeCurve::default()
    }
}

/// The loops of `des` on [`loop_grid_hz`].
pub fn loop_data(des: &ControllerDesign) -> Result<LoopData> {
    loop_data_on(des, &loop_grid_hz(des)?)
}

/// The loops of `des` on `grid_hz` (ascending, Hz).
pub fn loop_data_on(des: &ControllerDesign, grid_hz: &[f64]) -> Result<LoopData> {
    let w: Vec<f64> = grid_hz.iter().map(|f| 2.0 * PI * f).collect();
    let l_v = |w: f64| des.velocity_open_loop(w);
    let l_p = |w: f64| des.position_open_loop(w);
    let sens = |l: C64| C64::new(1.0, 0.0) / (C64::new(1.0, 0.0) + l);
    let pre = des.prefilter.tf();
    Ok(LoopData {
        freq_hz: grid_hz.to_vec(),
        velocity_open_loop: to_curve("velocity open loop", &bode(l_v, &w)?),
        velocity_closed_loop: to_curve("velocity closed loop", &bode(|w| feedback(l_v(w)), &w)?),
        velocity_sensitivity: to_curve("velocity sensitivity", &bode(|w| sens(l_v(w)), &w)?),
        position_open_loop: to_curve("position open loop", &bode(l_p, &w)?),
        position_closed_loop: to_curve("position closed loop", &bode(|w| feedback(l_p(w)), &w)?),
        position_sensitivity: to_curve("position sensitivity", &bode(|w| sens(l_p(w)), &w)?),
        controller: to_curve(
            "G_pre G_PI",
            &bode(
                |w| pre.freq_response(w) * C64::new(des.k_p, -des.k_i / w),
                &w,
            )?,
        ),
    })
}

/// `des` with other gains and no prefilter (e.g. the bootstrap controller on the
/// identified model, for a before/after overlay).
pub fn with_gains(des: &ControllerDesign, k_pp: f64, k_p: f64, k_i: f64) -> ControllerDesign {
    ControllerDesign {
        k_pp,
        k_p,
        k_i,
        prefilter: crate::design::Prefilter::None,
        ..des.clone()
    }
}

/// Phase of `tf e^{-j w t_T}` along `grid_hz`, unwrapped, shifted by whole
/// turns so that the first point lies in (-360, 0] deg (a plant with an
/// integrator starts near -180 deg, not +180).
fn model_bode(tf: &Tf, dead_time_s: f64, grid_hz: &[f64]) -> Result<Vec<BodePoint>> {
    let w: Vec<f64> = grid_hz.iter().map(|f| 2.0 * PI * f).collect();
    let mut pts = bode(
        |w| tf.freq_response(w) * C64::from_polar(1.0, -w * dead_time_s),
        &w,
    )?;
    if let Some(first) = pts.first().map(|p| p.phase_deg) {
        let shift = -360.0 * (first / 360.0).ceil();
        for p in &mut pts {
            p.phase_deg += shift;
        }
    }
    Ok(pts)
}

/// Linear interpolation of `y(x)` in `log10 x` (clamped at the ends).
fn interp_log(x: &[f64], y: &[f64], at: f64) -> f64 {
    match x.iter().position(|v| *v >= at) {
        None => y.last().copied().unwrap_or(f64::NAN),
        Some(0) => y.first().copied().unwrap_or(f64::NAN),
        Some(i) => {
            let (a, b) = (x[i - 1].log10(), x[i].log10());
            let t = if b > a {
                (at.log10() - a) / (b - a)
            } else {
                0.0
            };
            y[i - 1] + t * (y[i] - y[i - 1])
        }
    }
}

/// The measured FRF (every line but DC) as plain numbers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrfLines {
    /// Frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Magnitude, dB.
    pub magnitude_db: Vec<f64>,
    /// Phase, deg: each line within 180 deg of the fitted model at its
    /// frequency (so excluded noisy lines cannot run away by whole turns).
    pub phase_deg: Vec<f64>,
    /// Magnitude-squared coherence, 0..1.
    pub coherence: Vec<f64>,
    /// `true` where the fit used the line.
    pub used_by_fit: Vec<bool>,
    /// The fitted model with dead time at the same frequencies, dB.
    pub model_magnitude_db: Vec<f64>,
    /// The fitted model with dead time at the same frequencies, deg.
    pub model_phase_deg: Vec<f64>,
}

/// The lines of `frf` with their phase unwrapped against the fitted model
/// `tf` with dead time (the model is continuous; a measured line is placed
/// within 180 deg of it). Thesis figure 3.7 shows the same comparison.
pub fn frf_lines(frf: &Frf, tf: &Tf, dead_time_s: f64) -> Result<FrfLines> {
    let idx: Vec<usize> = (1..frf.freq_hz.len())
        .filter(|&i| frf.freq_hz[i] > 0.0 && frf.response[i].norm() > 0.0)
        .collect();
    let freq_hz: Vec<f64> = idx.iter().map(|&i| frf.freq_hz[i]).collect();
    if freq_hz.is_empty() {
        return Ok(FrfLines::default());
    }
    let model = model_bode(tf, dead_time_s, &freq_hz)?;
    let phase_deg = idx
        .iter()
        .zip(&model)
        .map(|(&i, m)| unwrap_near_deg(frf.response[i].arg().to_degrees(), m.phase_deg))
        .collect();
    Ok(FrfLines {
        magnitude_db: idx.iter().map(|&i| frf.magnitude_db(i)).collect(),
        phase_deg,
        coherence: idx.iter().map(|&i| frf.coherence[i]).collect(),
        used_by_fit: idx.iter().map(|&i| frf.is_usable(i)).collect(),
        model_magnitude_db: model.iter().map(|p| p.magnitude_db).collect(),
        model_phase_deg: model.iter().map(|p| p.phase_deg).collect(),
        freq_hz,
    })
}

/// Decimate measured lines for display: [`FRF_DISPLAY_POINTS`] log-spaced
/// bins; the used lines of a bin are averaged (complex mean) into one point,
/// the excluded ones into another. Bins holding one line keep it exactly.
pub fn frf_display(
    lines: &FrfLines,
    tf: &Tf,
    dead_time_s: f64,
    markers: Vec<FrequencyMarker>,
) -> Result<FrfPlot> {
    let mut plot = FrfPlot {
        markers,
        ..FrfPlot::default()
    };
    plot.measured.label = "measured".into();
    plot.model.label = "fitted model with dead time".into();
    // Lines above the highest used line are outside the excited band (the
    // PRBS has no power there): left out of the plot, kept in `frf.csv`.
    let f_top = lines
        .freq_hz
        .iter()
        .zip(&lines.used_by_fit)
        .filter(|(_, u)| **u)
        .map(|(f, _)| *f)
        .fold(f64::NAN, f64::max);
    let n = if f_top.is_finite() {
        lines.freq_hz.iter().take_while(|f| **f <= f_top).count()
    } else {
        lines.freq_hz.len()
    };
    let (Some(&f_lo), Some(&f_hi)) = (lines.freq_hz.first(), lines.freq_hz[..n].last()) else {
        return Ok(plot);
    };
    let grid = if f_hi > f_lo {
        log_grid(f_lo, f_hi, FRF_MODEL_POINTS)?
    } else {
        vec![f_lo]
    };
    let model = model_bode(tf, dead_time_s, &grid)?;
    plot.model = to_curve("fitted model with dead time", &model);
    let model_phase: Vec<f64> = model.iter().map(|p| p.phase_deg).collect();
    let ratio = (f_hi / f_lo).max(1.0 + 1e-9);
    let n_bins = FRF_DISPLAY_POINTS / 2;
    let bin_of = |f: f64| -> usize {
        (((f / f_lo).ln() / ratio.ln()) * n_bins as f64)
            .floor()
            .clamp(0.0, (n_bins - 1) as f64) as usize
    };
    let mut i = 0;
    while i < n {
        let b = bin_of(lines.freq_hz[i]);
        let mut j = i;
        while j < n && bin_of(lines.freq_hz[j]) == b {
            j += 1;
        }
        for used in [true, false] {
            let members: Vec<usize> = (i..j).filter(|&k| lines.used_by_fit[k] == used).collect();
            if members.is_empty() {
                continue;
            }
            let (f, h, coh) = if members.len() == 1 {
                let k = members[0];
                let h = C64::from_polar(
                    10f64.powf(lines.magnitude_db[k] / 20.0),
                    lines.phase_deg[k].to_radians(),
                );
                (lines.freq_hz[k], h, lines.coherence[k])
            } else {
                let m = members.len() as f64;
                let f = (members.iter().map(|&k| lines.freq_hz[k].ln()).sum::<f64>() / m).exp();
                let h = members
                    .iter()
                    .map(|&k| {
                        C64::from_polar(
                            10f64.powf(lines.magnitude_db[k] / 20.0),
                            lines.phase_deg[k].to_radians(),
                        )
                    })
                    .sum::<C64>()
                    / m;
                let coh = members.iter().map(|&k| lines.coherence[k]).sum::<f64>() / m;
                (f, h, coh)
            };
            if h.norm() == 0.0 || !h.norm().is_finite() {
                continue;
            }
            let reference = interp_log(&grid, &model_phase, f);
            plot.measured.freq_hz.push(f);
            plot.measured.magnitude_db.push(20.0 * h.norm().log10());
            plot.measured
                .phase_deg
                .push(unwrap_near_deg(h.arg().to_degrees(), reference));
            plot.coherence.push(coh);
            plot.usable.push(used);
        }
        i = j;
    }
    Ok(plot)
}

/// Resonance and antiresonance markers (Hz labels).
pub fn resonance_markers(f_z_hz: f64, f_r_hz: f64) -> Vec<FrequencyMarker> {
    vec![
        FrequencyMarker {
            label: format!("f_z {f_z_hz:.1} Hz"),
            freq_hz: f_z_hz,
        },
        FrequencyMarker {
            label: format!("f_r {f_r_hz:.1} Hz"),
            freq_hz: f_r_hz,
        },
    ]
}

/// Every `k`-th value so that at most `n` remain.
pub fn decimate(x: &[f64], n: usize) -> Vec<f64> {
    let step = x.len().div_ceil(n.max(1)).max(1);
    x.iter().step_by(step).copied().collect()
}

impl LoopData {
    /// The curves in the order of [`super::data_files::LOOP_CURVES`].
    pub fn curves(&self) -> [&BodeCurve; 7] {
        [
            &self.velocity_open_loop,
            &self.velocity_closed_loop,
            &self.velocity_sensitivity,
            &self.position_open_loop,
            &self.position_closed_loop,
            &self.position_sensitivity,
            &self.controller,
        ]
    }

    /// The curves, mutable, in the same order.
    pub fn curves_mut(&mut self) -> [&mut BodeCurve; 7] {
        [
            &mut self.velocity_open_loop,
            &mut self.velocity_closed_loop,
            &mut self.velocity_sensitivity,
            &mut self.position_open_loop,
            &mut self.position_closed_loop,
            &mut self.position_sensitivity,
            &mut self.controller,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ident::LineStatus;

    /// A double integrator with dead time, measured with one wild excluded line:
    /// every line stays within 180 deg of the model and the model starts in (-360, 0].
    #[test]
    fn excluded_lines_stay_near_the_model() {
        let tf = Tf::from_descending(&[1.0], &[1.0, 0.0, 0.0]);
        let t = 1e-3;
        let freq_hz: Vec<f64> = (0..2000).map(|i| i as f64 * 0.25).collect();
        let mut response: Vec<C64> = freq_hz
            .iter()
            .map(|f| {
                let w = 2.0 * PI * f;
                tf.freq_response(w.max(1e-9)) * C64::from_polar(1.0, -w * t)
            })
            .collect();
        response[700] *= C64::from_polar(1.0, 2.9); // noisy line
        let mut line_status = vec![LineStatus::Usable; freq_hz.len()];
        line_status[700] = LineStatus::LowCoherence;
        let frf = Frf {
            coherence: vec![1.0; freq_hz.len()],
            input_power: vec![1.0; freq_hz.len()],
            freq_hz,
            response,
            line_status,
            ts_s: 1e-4,
            n_periods: 2,
        };
        let lines = frf_lines(&frf, &tf, t).unwrap();
        assert!(lines.model_phase_deg[0] <= 0.0 && lines.model_phase_deg[0] > -360.0);
        for (p, m) in lines.phase_deg.iter().zip(&lines.model_phase_deg) {
            assert!((p - m).abs() <= 180.0 + 1e-9, "{p} vs {m}");
        }
        // closed form: -180 - 360 f t deg
        let k = 1000;
        let expect = -180.0 - 360.0 * lines.freq_hz[k] * t;
        assert!((lines.phase_deg[k] - expect).abs() < 1e-6);
        let plot = frf_display(&lines, &tf, t, vec![]).unwrap();
        assert!(plot.measured.freq_hz.len() <= FRF_DISPLAY_POINTS);
        assert!(plot.usable.iter().any(|u| !u));
        let text = super::super::data_files::frf_csv(&lines);
        let dir = std::env::temp_dir().join(format!("beltune-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(super::super::data_files::FRF_CSV);
        std::fs::write(&p, text).unwrap();
        let back = super::super::data_files::read_frf_csv(&p).unwrap();
        assert_eq!(back, lines);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
