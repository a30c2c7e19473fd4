//! Model-based input shaping: the jerk-limited trajectory convolved with a
//! shaper designed from the identified mode where the cart stops, stretched
//! or compressed in time so that the shaped move takes a given duration
//! within the same velocity, acceleration and jerk limits.
//!
//! A shaper's impulses are positive and sum to one, so the shaped
//! trajectory's velocity, acceleration and jerk are convex combinations of
//! the base trajectory's and stay within its limits; the base trajectory is
//! the time-optimal one of limits `(v/s, a/s^2, j/s^3)` for a time scale
//! `s >= 1` (exactly `s` times slower, [`scaled_trajectory`]).

use super::shaper::{Shaper, ShaperKind};
use crate::{Error, Result};
use beltune_rt::trajectory::{Limits, Sample, State, Trajectory};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A lightly damped mode of the cart on its belt.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// Undamped natural frequency, Hz.
    pub freq_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
}

impl Mode {
    /// The cart's mode on a belt of stiffness `c_n_per_m` with damping
    /// `d_n_s_per_m` and cart mass `m_c_kg` with the motor held (the
    /// antiresonance `f_z` of thesis (2.33)).
    pub fn cart_on_belt(c_n_per_m: f64, d_n_s_per_m: f64, m_c_kg: f64) -> Result<Mode> {
        crate::error::require_positive("c [N/m]", c_n_per_m)?;
        crate::error::require_positive("m_c [kg]", m_c_kg)?;
        crate::error::require_non_negative("d [N s/m]", d_n_s_per_m)?;
        let w = (c_n_per_m / m_c_kg).sqrt();
        let zeta = d_n_s_per_m / (2.0 * (c_n_per_m * m_c_kg).sqrt());
        Ok(Mode {
            freq_hz: w / (2.0 * PI),
            damping_ratio: zeta.min(0.9),
        })
    }
}

/// A base trajectory followed by a shaper: the desired cart motion
/// `sum_i A_i x(t - T_i)`.
#[derive(Clone, Debug)]
pub struct ShapedTrajectory {
    /// The base (unshaped) trajectory.
    pub base: Trajectory,
    /// The shaper (the identity for none).
    pub shaper: Shaper,
}

impl ShapedTrajectory {
    /// The desired cart state at `t_s` (m, m/s, m/s^2, m/s^3).
    pub fn sample(&self, t_s: f64) -> Sample {
        let mut out = Sample {
            position: 0.0,
            velocity: 0.0,
            acceleration: 0.0,
            jerk: 0.0,
        };
        for (a, t) in self.shaper.amplitudes.iter().zip(&self.shaper.times_s) {
            let s = self.base.sample(t_s - t);
            out.position += a * s.position;
            out.velocity += a * s.velocity;
            out.acceleration += a * s.acceleration;
            out.jerk += a * s.jerk;
        }
        out
    }

    /// Duration: the base's plus the shaper's, s.
    pub fn duration_s(&self) -> f64 {
        self.base.duration_s() + self.shaper.duration_s()
    }
}

/// The rest-to-rest trajectory from `start_m` to `target_m` that takes
/// `duration_s` with limits `limits` scaled in time: an error when even the
/// limits themselves take longer. Exact up to the planner's rounding (the
/// time-optimal profile of `(v/s, a/s^2, j/s^3)` is the original one slowed
/// by `s` where the position window does not bind; a secant iteration
/// finishes the rest).
pub fn scaled_trajectory(
    start_m: f64,
    target_m: f64,
    limits: &Limits,
    duration_s: f64,
) -> Result<Trajectory> {
    let plan = |s: f64| -> Result<Trajectory> {
        let l = Limits {
            v_max: limits.v_max / s,
            v_min: limits.v_min / s,
            a_max: limits.a_max / (s * s),
            a_min: limits.a_min / (s * s),
            j_max: limits.j_max / (s * s * s),
            j_min: limits.j_min / (s * s * s),
            ..*limits
        };
        Ok(Trajectory::plan(
            &State::at_rest(start_m),
            &State::at_rest(target_m),
            &l,
        )?)
    };
    let fastest = plan(1.0)?;
    let d0 = fastest.duration_s();
    if !(duration_s.is_finite() && duration_s >= d0 * (1.0 - 1e-9)) {
        return Err(Error::invalid(
            "move duration_s",
            duration_s,
            format!("the limits need at least {d0:.4} s for this move"),
        ));
    }
    let mut s = (duration_s / d0).max(1.0);
    let mut t = plan(s)?;
    for _ in 0..8 {
        let d = t.duration_s();
        if (d - duration_s).abs() <= 1e-9 * duration_s {
            break;
        }
        s *= duration_s / d;
        t = plan(s.max(1.0))?;
    }
    Ok(t)
}

/// Residual vibration amplitude of `mode` left by a rest-to-rest base
/// trajectory `base` (m): the mode driven by the commanded acceleration,
/// `|integral a(t) e^(-zeta w (T - t)) e^(j w_d t) dt| / w_d` at its end `T`
/// (trapezoids at `dt_s`).
pub fn base_residual_m(base: &Trajectory, mode: &Mode, dt_s: f64) -> f64 {
    let w = 2.0 * PI * mode.freq_hz;
    let z = mode.damping_ratio;
    let wd = w * (1.0 - z * z).max(1e-12).sqrt();
    let t_end = base.duration_s();
    let n = ((t_end / dt_s).ceil() as usize).max(1);
    let h = t_end / n as f64;
    let (mut re, mut im) = (0.0, 0.0);
    for k in 0..=n {
        let t = k as f64 * h;
        let weight = if k == 0 || k == n { 0.5 } else { 1.0 };
        let g = weight * base.sample(t).acceleration * (-z * w * (t_end - t)).exp();
        re += g * (wd * t).cos();
        im += g * (wd * t).sin();
    }
    h * (re * re + im * im).sqrt() / wd
}

/// What the model-based shaping chose for one move.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapingChoice {
    /// Shaper family.
    pub kind: ShaperKind,
    /// Its design frequency, Hz.
    pub freq_hz: f64,
    /// Its design damping ratio.
    pub damping_ratio: f64,
    /// The impulses.
    pub shaper: Shaper,
    /// Predicted worst residual amplitude over the band, m.
    pub predicted_residual_m: f64,
}

/// The shaper for a move from `start_m` to `target_m` of total duration
/// `duration_s` within `limits`, whose mode where the cart stops lies
/// anywhere in `modes` (e.g. the payload range's ends, the model's
/// uncertainty): over the families ZV, MZV, ZVD, EI, 2- and 3-hump EI and
/// design frequencies across the modes' band, the one whose predicted worst
/// residual (the shaper's residual ratio times the residual of the base
/// trajectory it leaves time for, [`base_residual_m`]) is least. No shaping
/// is a candidate too. Where candidates leave at most `negligible_m` of the
/// mode, the shortest of them is taken (none first): the time a shaper
/// does not need goes to a gentler base trajectory, whose smaller
/// following error and friction lead are what then remain.
pub fn choose_shaper(
    start_m: f64,
    target_m: f64,
    limits: &Limits,
    duration_s: f64,
    modes: &[Mode],
    negligible_m: f64,
) -> Result<ShapingChoice> {
    if modes.is_empty() {
        return Err(Error::NoExcitation {
            what: "no mode to shape for".into(),
        });
    }
    let f_lo = modes.iter().map(|m| m.freq_hz).fold(f64::MAX, f64::min);
    let f_hi = modes.iter().map(|m| m.freq_hz).fold(0.0, f64::max);
    let zeta = modes.iter().map(|m| m.damping_ratio).sum::<f64>() / modes.len() as f64;
    let d_min =
        Trajectory::plan(&State::at_rest(start_m), &State::at_rest(target_m), limits)?.duration_s();
    // the band's modes (ends and 5 points between) the prediction checks
    let mut checks: Vec<Mode> = modes.to_vec();
    for i in 1..6 {
        let f = f_lo + (f_hi - f_lo) * i as f64 / 6.0;
        checks.push(Mode {
            freq_hz: f,
            damping_ratio: zeta,
        });
    }
    let dt = (1.0 / f_hi / 40.0).min(1e-3);
    let predict = |shaper: &Shaper| -> Result<f64> {
        let base = scaled_trajectory(start_m, target_m, limits, duration_s - shaper.duration_s())?;
        let mut worst: f64 = 0.0;
        for m in &checks {
            let r = base_residual_m(&base, m, dt)
                * shaper.residual_vibration(m.freq_hz, m.damping_ratio);
            worst = worst.max(r);
        }
        Ok(worst)
    };
    let design_damping = zeta.min(0.19);
    let mut best = ShapingChoice {
        kind: ShaperKind::Zv,
        freq_hz: 0.0,
        damping_ratio: 0.0,
        shaper: Shaper::none(),
        predicted_residual_m: predict(&Shaper::none())?,
    };
    for kind in ShaperKind::ALL {
        for i in 0..=24 {
            let f = f_lo * 0.7 + (f_hi * 1.3 - f_lo * 0.7) * i as f64 / 24.0;
            let shaper = kind.design(f, design_damping)?;
            if shaper.duration_s() > duration_s - d_min {
                continue;
            }
            let r = predict(&shaper)?;
            let best_negligible = best.predicted_residual_m <= negligible_m;
            let better = if best_negligible {
                r <= negligible_m && shaper.duration_s() < best.shaper.duration_s()
            } else {
                r < best.predicted_residual_m
            };
            if better {
                best = ShapingChoice {
                    kind,
                    freq_hz: f,
                    damping_ratio: design_damping,
                    shaper,
                    predicted_residual_m: r,
                };
            }
        }
    }
    Ok(best)
}
