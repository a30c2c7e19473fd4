//! PI velocity controller (thesis 4.2.2, (4.5)-(4.9)).
//!
//! Open loop `L = G_PI G_pre G_dt G_tau_phi G_R` with `G_PI = K_P + K_I / s` (4.6),
//! the prefilter in series with the PI controller, the exact dead time
//! `G_dt = e^{-s t_T}` (3.25), the model (2.42) and the velocity filter
//! `G_R = s / (T_R s + 1)` (6.1). Conditions: `|L(j w_r)| = A_sup` (4.7),
//! `|L(j w_c)| = 1` (4.8), `arg L(j w_c) = -pi + PM` (4.9).
//!
//! Solution from the model alone: for a candidate crossover `w_c`, (4.8) and (4.9)
//! fix the complex value `G_PI(j w_c) = e^{j(-pi + PM)} / G_omega(j w_c)`, which is
//! linear in the gains: `K_P = Re`, `K_I = -w_c Im`. The remaining scalar equation
//! (4.7) in `w_c` is bracketed on a log grid below `w_r` (only where both gains are
//! positive) and refined by bisection. Every root is then checked on the full
//! frequency grid: the loop must have exactly one gain crossover, at `w_c`.

use super::{DesignInput, Prefilter};
use crate::lti::freq::dead_time;
use crate::lti::margins::{margins, phase_margin_deg_of, StabilityMargins};
use crate::lti::{db, log_grid, Tf, C64};
use crate::{Error, Result};

/// Relative tolerance of the crossover found by bisection of (4.7).
const W_C_REL_TOL: f64 = 1e-13;
/// Candidate crossovers scanned between `w_r / 1e4` and `w_r`.
const N_CANDIDATES: usize = 3000;

/// The fixed part of the velocity loop `G_omega = G_pre G_dt G_tau_phi G_R` (4.5).
#[derive(Clone, Debug, PartialEq)]
pub struct VelocityPlant {
    /// `G_pre(s)`.
    pub prefilter: Tf,
    /// `G_tau_phi(s)`, (2.42), rad/(N m).
    pub plant: Tf,
    /// `t_T` in s.
    pub dead_time_s: f64,
    /// `T_R` in s.
    pub t_r_s: f64,
}

impl VelocityPlant {
    /// From the design input and the designed prefilter.
    pub fn new(input: &DesignInput, prefilter: &Prefilter) -> Self {
        VelocityPlant {
            prefilter: prefilter.tf(),
            plant: input.model.tf_rigid_flexible(),
            dead_time_s: input.dead_time_s,
            t_r_s: input.t_r_s,
        }
    }

    /// Velocity filter `G_R(j w) = j w / (T_R j w + 1)` (6.1).
    pub fn velocity_filter(&self, w_rad_s: f64) -> C64 {
        let s = C64::new(0.0, w_rad_s);
        s / (self.t_r_s * s + 1.0)
    }

    /// Torque command to motor angle through prefilter and dead time,
    /// `G_pre G_dt G_tau_phi` (the forward path of (4.10) without the controller).
    pub fn forward(&self, w_rad_s: f64) -> C64 {
        self.prefilter.freq_response(w_rad_s)
            * dead_time(w_rad_s, self.dead_time_s)
            * self.plant.freq_response(w_rad_s)
    }

    /// `G_omega(j w)` (4.5).
    pub fn g_omega(&self, w_rad_s: f64) -> C64 {
        self.forward(w_rad_s) * self.velocity_filter(w_rad_s)
    }
}

/// PI gains (4.6).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PiGains {
    /// `K_P`, N m s/rad.
    pub k_p: f64,
    /// `K_I`, N m/rad.
    pub k_i: f64,
}

impl PiGains {
    /// `G_PI(j w) = K_P + K_I / (j w)`.
    pub fn freq_response(&self, w_rad_s: f64) -> C64 {
        C64::new(self.k_p, -self.k_i / w_rad_s)
    }

    /// The gains that put the crossover at `w_c` with phase margin `pm_deg`
    /// ((4.8) and (4.9)) for a loop whose fixed part is `g_omega_at_wc` there.
    pub fn for_crossover(g_omega_at_wc: C64, w_c_rad_s: f64, pm_deg: f64) -> Self {
        let target = C64::from_polar(1.0, (pm_deg - 180.0).to_radians());
        let c = target / g_omega_at_wc;
        PiGains {
            k_p: c.re,
            k_i: -w_c_rad_s * c.im,
        }
    }
}

/// Which second condition fixed the PI gains (the first is always the phase margin (4.9)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityRule {
    /// The thesis' (4.7): `|L(j w_r)| = A_sup`.
    ResonanceSuppression,
    /// Fallback when the loop is phase-limited (dead time, prefilter lag): at every
    /// crossover that the phase margin admits, `|L(j w_r)|` already stays below
    /// `A_sup`, so (4.7) holds as the inequality it stands for ("smaller than this
    /// factor", 4.2.2) and cannot fix a gain. The crossover is then chosen to
    /// maximize the integral gain `K_I` (low-frequency disturbance rejection), the
    /// criterion of Astrom and Hagglund's MIGO design; towards the upper end of the
    /// admissible crossovers `K_I -> 0` (a P controller), towards the lower end the
    /// loop gets slow, so the maximum is interior.
    MaxIntegralGain,
}

/// Result of the PI design.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VelocityDesign {
    /// The gains.
    pub gains: PiGains,
    /// Margins of the continuous open loop (4.5)-(4.6) on the design grid.
    pub margins: StabilityMargins,
    /// `|L(j w_r)|` in dB (the achieved `A_sup` of (4.7)).
    pub gain_at_resonance_db: f64,
    /// Which condition fixed the gains together with the phase margin.
    pub rule: VelocityRule,
}

/// Solve (4.7)-(4.9) for `K_P`, `K_I`. `grid` is the verification grid (ascending,
/// rad/s) that must extend well beyond `omega_r_rad_s`.
pub fn design_pi(
    plant: &VelocityPlant,
    omega_r_rad_s: f64,
    pm_deg: f64,
    a_sup_db: f64,
    grid: &[f64],
) -> Result<VelocityDesign> {
    if !(pm_deg > 0.0 && pm_deg < 180.0) {
        return Err(Error::invalid(
            "pm_velocity_deg",
            pm_deg,
            "the velocity phase margin must lie in (0, 180) degrees",
        ));
    }
    if !(a_sup_db.is_finite() && a_sup_db < 0.0) {
        return Err(Error::invalid(
            "resonance_suppression_db",
            a_sup_db,
            "the resonance suppression A_sup must be finite and < 0 dB",
        ));
    }
    let g_r = plant.g_omega(omega_r_rad_s);
    if !(g_r.norm().is_finite() && g_r.norm() > 0.0) {
        return Err(Error::Infeasible {
            reason: format!(
                "the model's gain at the resonance ({:.2} Hz) is not finite because the model has no damping: the resonance suppression (the open-loop gain at the resonance, thesis eq. 4.7) cannot be set; identify the axis again or give it damping",
                omega_r_rad_s / (2.0 * std::f64::consts::PI)
            ),
        });
    }
    // (4.7) residual in dB for the gains that satisfy (4.8)/(4.9) at w_c; None where a gain is <= 0.
    let residual = |w_c: f64| -> Option<(f64, PiGains)> {
        let g = PiGains::for_crossover(plant.g_omega(w_c), w_c, pm_deg);
        if g.k_p > 0.0 && g.k_i > 0.0 && g.k_p.is_finite() && g.k_i.is_finite() {
            let at_r = db((g.freq_response(omega_r_rad_s) * g_r).norm());
            Some((at_r - a_sup_db, g))
        } else {
            None
        }
    };
    let candidates = log_grid(
        omega_r_rad_s * 1e-4,
        omega_r_rad_s * (1.0 - 1e-9),
        N_CANDIDATES,
    )?;
    // Contiguous runs of candidates with positive gains: (w_c, residual, K_I).
    let mut runs: Vec<Vec<(f64, f64, f64)>> = Vec::new();
    let mut open = false;
    for &w in &candidates {
        match residual(w) {
            Some((r, g)) => {
                if !open {
                    runs.push(Vec::new());
                    open = true;
                }
                if let Some(run) = runs.last_mut() {
                    run.push((w, r, g.k_i));
                }
            }
            None => open = false,
        }
    }
    if runs.is_empty() {
        return Err(Error::Infeasible {
            reason: format!(
                "a phase margin of {pm_deg} deg cannot be reached with positive PI gains at any crossover below the resonance {omega_r_rad_s:.1} rad/s"
            ),
        });
    }
    let verify =
        |w_c: f64, rule: VelocityRule| -> Result<std::result::Result<VelocityDesign, String>> {
            let Some((_, gains)) = residual(w_c) else {
                return Ok(Err(format!("no positive gains at {w_c:.2} rad/s")));
            };
            let l = |w: f64| gains.freq_response(w) * plant.g_omega(w);
            let m = margins(l, grid)?;
            if m.gain_crossover_count != 1 || (m.crossover_rad_s / w_c - 1.0).abs() > 1e-6 {
                return Ok(Err(format!(
                    "crossover {w_c:.2} rad/s gives {} gain crossovers",
                    m.gain_crossover_count
                )));
            }
            Ok(Ok(VelocityDesign {
                gains,
                margins: m,
                gain_at_resonance_db: db(l(omega_r_rad_s).norm()),
                rule,
            }))
        };
    // (4.7): sign changes of the residual inside each run, refined and verified.
    let mut rejected = Vec::new();
    let mut accepted: Option<VelocityDesign> = None;
    for run in &runs {
        for pair in run.windows(2) {
            let ((w0, r0, _), (w1, r1, _)) = (pair[0], pair[1]);
            if (r0 > 0.0) != (r1 > 0.0) {
                let w_c = bisect_residual(&residual, w0, r0, w1);
                match verify(w_c, VelocityRule::ResonanceSuppression)? {
                    // Several valid solutions: keep the highest bandwidth.
                    Ok(d) => {
                        if accepted.is_none_or(|a| a.margins.crossover_rad_s < w_c) {
                            accepted = Some(d);
                        }
                    }
                    Err(why) => rejected.push(why),
                }
            }
        }
    }
    if let Some(d) = accepted {
        return Ok(d);
    }
    // Phase-limited fallback: runs where |L(j w_r)| < A_sup throughout; maximize K_I.
    let mut best: Option<VelocityDesign> = None;
    for run in runs
        .iter()
        .filter(|run| run.iter().all(|(_, r, _)| *r < 0.0))
    {
        let w_c = argmax_integral_gain(run, &residual);
        match verify(w_c, VelocityRule::MaxIntegralGain)? {
            Ok(d) => {
                if best.is_none_or(|b| b.gains.k_i < d.gains.k_i) {
                    best = Some(d);
                }
            }
            Err(why) => rejected.push(why),
        }
    }
    if let Some(d) = best {
        return Ok(d);
    }
    let (lo_db, hi_db) = runs
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, r, _)| {
            (lo.min(r + a_sup_db), hi.max(r + a_sup_db))
        });
    Err(Error::Infeasible {
        reason: format!(
            "with a phase margin of {pm_deg} deg no PI design has a unique crossover and a gain at the resonance of at most A_sup = {a_sup_db} dB (gain at the resonance over the admissible crossovers: {lo_db:.2} to {hi_db:.2} dB{}{})",
            if rejected.is_empty() { "" } else { "; " },
            rejected.join("; ")
        ),
    })
}

/// The crossover in `run` (candidates with positive gains) that maximizes `K_I`,
/// refined by golden-section search in `log w_c` between the neighbours of the best
/// candidate ([`VelocityRule::MaxIntegralGain`]).
fn argmax_integral_gain(
    run: &[(f64, f64, f64)],
    residual: &impl Fn(f64) -> Option<(f64, PiGains)>,
) -> f64 {
    let best = run
        .iter()
        .enumerate()
        .max_by(|a, b| a.1 .2.total_cmp(&b.1 .2))
        .map(|(i, _)| i)
        .unwrap_or(0);
    let k_i = |w: f64| residual(w).map(|(_, g)| g.k_i).unwrap_or(f64::NEG_INFINITY);
    let (mut a, mut b) = (
        run[best.saturating_sub(1)].0.ln(),
        run[(best + 1).min(run.len() - 1)].0.ln(),
    );
    let phi = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..100 {
        if b - a < W_C_REL_TOL {
            break;
        }
        let c = b - phi * (b - a);
        let d = a + phi * (b - a);
        if k_i(c.exp()) > k_i(d.exp()) {
            b = d;
        } else {
            a = c;
        }
    }
    (0.5 * (a + b)).exp()
}

fn bisect_residual(
    residual: &impl Fn(f64) -> Option<(f64, PiGains)>,
    mut lo: f64,
    mut r_lo: f64,
    mut hi: f64,
) -> f64 {
    for _ in 0..200 {
        if hi / lo - 1.0 <= W_C_REL_TOL {
            break;
        }
        let mid = (lo * hi).sqrt();
        let Some((r, _)) = residual(mid) else { break };
        if (r > 0.0) == (r_lo > 0.0) {
            lo = mid;
            r_lo = r;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

/// Phase margin of the loop at `w` (helper for reports): `180 + arg L(j w)`.
pub fn phase_margin_at(gains: &PiGains, plant: &VelocityPlant, w_rad_s: f64) -> f64 {
    phase_margin_deg_of(gains.freq_response(w_rad_s) * plant.g_omega(w_rad_s))
}
