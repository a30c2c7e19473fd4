//! The design rule for lightly damped axes: margins that hold on the
//! axis, not only on the identified model.
//!
//! Two facts of a belt axis identified with a small excitation drive this rule:
//!
//! 1. **Friction is not damping.** The FRF's fitted `d_m`, `d_c` lump the
//!    Coulomb friction the excitation meets into viscous damping. For egc70 the
//!    fit's rigid-body damping `i_t^2 (d_m + d_c)` is 0.035 N m s/rad, the
//!    constant-velocity runs measure 0.004 (thesis 3.6): the fitted plant has a
//!    pole at 3 Hz where the axis integrates. A PI designed on it for 60 deg
//!    keeps about 38 deg on the axis. [`design_model`] gives the design model
//!    the rigid-body damping the friction runs measured and keeps the
//!    resonance damping the FRF shows, as belt damping `d` (which is where the
//!    axis has it).
//! 2. **The resonance damping is uncertain too**, and where the thesis'
//!    (4.7) has no root the loop is phase-limited by the prefilter's lag, not
//!    by the resonance. [`robust_design`] therefore treats the prefilter as a
//!    design variable: Butterworth cut-offs from well above to below the
//!    antiresonance and notches of growing depth, each designed with the
//!    thesis' conditions (4.7)-(4.9) on the design model, each checked over
//!    the identification's uncertainty box
//!    ([`guaranteed_margins`]: `m_c`, `c` at
//!    +-2 sigma, the damping as identified and halved). The fastest velocity
//!    loop whose guaranteed margins reach [`GUARANTEED_PHASE_MARGIN_DEG`]
//!    wins; if none does, the one with the largest guaranteed margin (and the
//!    verdict says so).
//!
//! The choice is principled in the sense of Astrom and Hagglund's robust
//! loop shaping: the bandwidth is maximized subject to a robustness
//! constraint that holds over the model set the identification supports,
//! rather than on its nominal model only.

use super::VelocityPlant;
use super::{design, ControllerDesign, DesignInput, DesignKnobs, Dynamics, PrefilterKind};
use crate::lti::C64;
use crate::model::stroke::StrokeVariation;
use crate::model::TwoMassParams;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Velocity-loop phase margin the robust design guarantees over the
/// uncertainty box, deg (>= 45 deg on the axis).
pub const GUARANTEED_PHASE_MARGIN_DEG: f64 = 45.0;
/// Position-loop phase margin the robust design guarantees over the box, deg
/// (a position loop below 60 deg overshoots its target: the thesis asks 80
/// nominally).
pub const GUARANTEED_POSITION_PHASE_MARGIN_DEG: f64 = 60.0;

/// How many degrees of phase margin a dB of gain margin weighs when no
/// candidate meets the guarantee and the most robust one is kept (6 dB of
/// gain margin against 45 deg of phase margin: about 7.5 deg per dB).
const DEG_PER_DB: f64 = 7.5;

/// Prefilter candidates besides the configured one: (kind, attenuation at the
/// antiresonance in dB). The Butterworth cut-off of (4.4) runs from 3.8 `w_z`
/// (-0.02 dB) down to 0.3 `w_z` (-20 dB); the notch depth from shallow to deep.
const CANDIDATES: [(PrefilterKind, f64); 17] = [
    (PrefilterKind::Butterworth, -0.02),
    (PrefilterKind::Butterworth, -0.05),
    (PrefilterKind::Butterworth, -0.1),
    (PrefilterKind::Butterworth, -0.2),
    (PrefilterKind::Butterworth, -0.5),
    (PrefilterKind::Butterworth, -1.0),
    (PrefilterKind::Butterworth, -2.0),
    (PrefilterKind::Butterworth, -3.0),
    (PrefilterKind::Butterworth, -4.5),
    (PrefilterKind::Butterworth, -6.0),
    (PrefilterKind::Butterworth, -9.0),
    (PrefilterKind::Butterworth, -12.0),
    (PrefilterKind::Notch, -3.0),
    (PrefilterKind::Notch, -6.0),
    (PrefilterKind::Notch, -9.0),
    (PrefilterKind::Notch, -12.0),
    (PrefilterKind::Notch, -20.0),
];

/// The design model of an identified axis (see the module docs): `fit` with
/// its motor and cart damping scaled (in the fit's ratio) so that the
/// rigid-body damping `i_t^2 (d_m + d_c)` equals the measured viscous
/// friction `viscous_nm_s_per_rad` (N m s/rad at the motor, (3.36)), and the
/// belt damping `d` chosen so that the resonance keeps the fit's damping
/// `a3` (2.38g) ([`TwoMassParams::resonance_damping`]). Without a usable
/// measurement (non-finite or negative) the fit is returned unchanged.
pub fn design_model(fit: &TwoMassParams, viscous_nm_s_per_rad: f64) -> TwoMassParams {
    if !(viscous_nm_s_per_rad.is_finite() && viscous_nm_s_per_rad >= 0.0) {
        return *fit;
    }
    let it2 = fit.i_t * fit.i_t;
    let rigid = fit.rigid_damping();
    let (d_m, d_c) = if rigid > 0.0 {
        let s = viscous_nm_s_per_rad / rigid;
        (fit.d_m * s, fit.d_c * s)
    } else {
        (0.0, viscous_nm_s_per_rad / it2)
    };
    let scaled = TwoMassParams {
        d_m,
        d_c,
        d: 0.0,
        ..*fit
    };
    let missing = fit.resonance_damping() - scaled.resonance_damping();
    TwoMassParams {
        d: (missing / (it2 * fit.m_c + fit.theta_e)).max(0.0),
        ..scaled
    }
}

/// The robust design's result.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustDesign {
    /// The chosen design (on the design model).
    pub design: ControllerDesign,
    /// Its margins over the uncertainty box.
    pub guaranteed: GuaranteedMargins,
    /// Whether the guaranteed margins reach the guarantee of the knobs'
    /// dynamics ([`GUARANTEED_PHASE_MARGIN_DEG`] and
    /// [`GUARANTEED_POSITION_PHASE_MARGIN_DEG`] at standard).
    pub meets_guarantee: bool,
    /// Designs that exist among the candidates.
    pub candidates_designed: usize,
    /// Designs whose margins were checked over the box before one met the
    /// guarantee (the others rank lower and were not needed).
    pub candidates_checked: usize,
}

/// The ladder of nominal (velocity, position) phase margins every prefilter
/// candidate is designed with, deg, from the thesis' 70/85 (conservative
/// one-knob setting) down to 35/50. The thesis' 60 / 80 deg are nominal
/// targets on a model the identification knows only to within its
/// uncertainty; the constraint that matters is the guarantee over that
/// uncertainty ([`Dynamics`]), and every degree of nominal margin above it
/// costs integral gain. The ladder does not depend on the knobs, so a
/// lower guarantee admits a superset of the designs a higher one admits.
const NOMINAL_MARGIN_LADDER_DEG: [(f64, f64); 8] = [
    (70.0, 85.0),
    (65.0, 82.0),
    (60.0, 80.0),
    (55.0, 72.0),
    (50.0, 65.0),
    (45.0, 60.0),
    (40.0, 55.0),
    (35.0, 50.0),
];

/// Integral stiffness of the cascade, `K_I K_PP`: at low frequency the cascade answers a motor-angle error `e` (rad)
/// with the torque `K_I K_PP e / s` (N m), so `K_I K_PP` (N m/(rad s)) is the
/// rate at which a standing error builds torque. It ranks the designs: the
/// low-frequency load-disturbance rejection of the cascade (Astrom and
/// Hagglund's MIGO criterion, maximize the integral gain subject to a
/// robustness constraint, applied to the cascade), which sets how fast the
/// torque that overcomes the friction left at standstill builds up (the
/// static error of thesis chapter 5).
fn integral_stiffness(d: &ControllerDesign) -> f64 {
    d.k_i * d.k_pp
}

/// Step of the one-knob setting the robust rule resolves: `x` is rounded to
/// a multiple of it ([`robust_design`] walks the settings from 0 up in these
/// steps).
pub const DYNAMICS_STEP: f64 = 0.05;

/// The robust design at `knobs.dynamics`: over the candidates (prefilters x
/// [`NOMINAL_MARGIN_LADDER_DEG`]) whose margins over the uncertainty box
/// (`m_c_sigma_kg`, `c_sigma_n_per_m`: one-sigma uncertainties of the fit;
/// [`guaranteed_margins`]) reach the guarantee of the setting
/// ([`Dynamics::guaranteed_velocity_phase_margin_deg`],
/// [`Dynamics::guaranteed_position_phase_margin_deg`]; 45/60 deg standard),
/// the one with the largest integral stiffness `K_I K_PP` that is at least
/// as fast, in both loops, as the design of the next slower setting.
///
/// The settings are walked from 0 (conservative) up to `x` (rounded to
/// [`DYNAMICS_STEP`]): each step's design is the previous step's if nothing
/// faster qualifies, so the velocity and the position crossover never fall
/// as `x` rises (by construction; a lower guarantee admits a superset of
/// the candidates). `input` carries the design model ([`design_model`]); of
/// `knobs` the configured prefilter is one more candidate and `dynamics` is
/// used; every candidate has the thesis' `A_sup` of -10 dB (the candidates
/// must not depend on the setting). A rung of the ladder
/// below a guarantee cannot meet it (the nominal model is in the box) and is
/// not considered for it. If no candidate meets a setting's guarantee, the
/// one with the largest guaranteed margin is kept for it with
/// [`RobustDesign::meets_guarantee`] false.
pub fn robust_design(
    input: &DesignInput,
    knobs: &DesignKnobs,
    m_c_sigma_kg: f64,
    c_sigma_n_per_m: f64,
    stroke: Option<&StrokeVariation>,
) -> Result<RobustDesign> {
    let steps = (knobs.dynamics.value() / DYNAMICS_STEP).round() as usize;
    let setting = |k: usize| Dynamics::new((k as f64 * DYNAMICS_STEP).min(1.0));
    let target = setting(steps)?;
    let (g_v_min, g_p_min) = (
        target.guaranteed_velocity_phase_margin_deg(),
        target.guaranteed_position_phase_margin_deg(),
    );
    let mut prefilters = vec![(knobs.prefilter, knobs.filter_attenuation_db)];
    prefilters.extend(CANDIDATES.iter().map(|&(kind, att)| (kind, Some(att))));
    let mut designs = Vec::new();
    let mut last_error = None;
    for &(pm_v, pm_p) in NOMINAL_MARGIN_LADDER_DEG
        .iter()
        .filter(|(v, p)| *v >= g_v_min && *p >= g_p_min)
    {
        for &(kind, att) in &prefilters {
            let k = DesignKnobs {
                prefilter: kind,
                filter_attenuation_db: att,
                pm_velocity_deg: pm_v,
                pm_position_deg: pm_p,
                // the same candidates for every setting: the thesis' A_sup
                resonance_suppression_db: DesignKnobs::default().resonance_suppression_db,
                ..*knobs
            };
            match design(input, &k) {
                Ok(d) => designs.push(d),
                Err(e) => last_error = Some(e),
            }
        }
    }
    if designs.is_empty() {
        return Err(last_error.unwrap_or_else(|| Error::Infeasible {
            reason: "no controller design exists for the identified model".into(),
        }));
    }
    let designed = designs.len();
    // Best first; the box is checked lazily, once per candidate.
    designs.sort_by(|a, b| integral_stiffness(b).total_cmp(&integral_stiffness(a)));
    let mut box_margins: Vec<Option<Option<GuaranteedMargins>>> = vec![None; designed];
    let mut checked = 0;
    let mut floor: Option<(f64, f64)> = None;
    let mut chosen: Option<(usize, bool)> = None;
    for k in 0..=steps {
        let level = setting(k)?;
        let (g_v, g_p, g_gm) = (
            level.guaranteed_velocity_phase_margin_deg(),
            level.guaranteed_position_phase_margin_deg(),
            level.guaranteed_velocity_gain_margin_db(),
        );
        // how far the worst margin is from its guarantee (a dB of gain
        // margin weighs as DEG_PER_DB degrees of phase margin)
        let worst = |g: &GuaranteedMargins| {
            (g.velocity_phase_margin_deg - g_v)
                .min(g.position_phase_margin_deg - g_p)
                .min((g.velocity_gain_margin_db - g_gm) * DEG_PER_DB)
        };
        let mut pick: Option<(usize, bool)> = None;
        let mut fallback: Option<(usize, f64)> = None;
        for (i, d) in designs.iter().enumerate() {
            let admissible = d.knobs.pm_velocity_deg >= g_v
                && d.knobs.pm_position_deg >= g_p
                && floor.is_none_or(|(fv, fp)| {
                    d.velocity_margins.crossover_rad_s >= fv
                        && d.position_margins.crossover_rad_s >= fp
                });
            if !admissible {
                continue;
            }
            let g = match &box_margins[i] {
                Some(g) => *g,
                None => {
                    checked += 1;
                    let g = match guaranteed_margins(
                        d,
                        &input.model,
                        m_c_sigma_kg,
                        c_sigma_n_per_m,
                        stroke,
                    ) {
                        Ok(g) if !g.velocity_phase_margin_deg.is_nan() => Some(g),
                        Ok(_) => None,
                        Err(e) => {
                            last_error = Some(e);
                            None
                        }
                    };
                    box_margins[i] = Some(g);
                    g
                }
            };
            let Some(g) = g else { continue };
            if g.meets(level) {
                pick = Some((i, true));
                break;
            }
            if fallback.is_none_or(|(_, w)| worst(&g) > w) {
                fallback = Some((i, worst(&g)));
            }
        }
        let Some((i, meets)) = pick.or(fallback.map(|(i, _)| (i, false))) else {
            return Err(last_error.unwrap_or_else(|| Error::Infeasible {
                reason:
                    "no controller design has finite margins over the identification's uncertainty"
                        .into(),
            }));
        };
        let d = &designs[i];
        floor = Some((
            d.velocity_margins.crossover_rad_s,
            d.position_margins.crossover_rad_s,
        ));
        chosen = Some((i, meets));
    }
    let (i, meets) = chosen.expect("at least setting 0 is walked");
    let guaranteed = box_margins[i]
        .flatten()
        .expect("the chosen design was checked");
    let mut design = designs.swap_remove(i);
    design.knobs.dynamics = knobs.dynamics;
    Ok(RobustDesign {
        design,
        guaranteed,
        meets_guarantee: meets,
        candidates_designed: designed,
        candidates_checked: checked,
    })
}

/// Which rule turns an identified model into a controller.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DesignRule {
    /// [`robust_design`] on the [`design_model`] (the commissioning's default):
    /// prefilter and nominal margins chosen for the guarantee.
    #[default]
    Robust,
    /// The thesis' conditions (4.1)-(4.14) with exactly the given knobs, on
    /// the [`design_model`] (an expert's choice; the guarantee is evaluated).
    Knobs,
    /// The thesis' design with the given knobs on the fit as identified
    /// (friction lumped into damping), for comparison.
    Thesis,
}

/// The design for an identified model: `input.model` is the fit as
/// identified, `viscous_nm_s_per_rad` the viscous friction the
/// constant-velocity runs measured (`None` before or without them: 0, the
/// conservative pure integrator), `m_c_sigma_kg`, `c_sigma_n_per_m` the fit's
/// one-sigma uncertainties (NaN: 5 %). The commissioning, `beltune design`
/// and the tuning page all call this, so they agree for the same model.
pub fn design_identified(
    input: &DesignInput,
    viscous_nm_s_per_rad: Option<f64>,
    m_c_sigma_kg: f64,
    c_sigma_n_per_m: f64,
    stroke: Option<&StrokeVariation>,
    knobs: &DesignKnobs,
    rule: DesignRule,
) -> Result<RobustDesign> {
    let model = design_model(&input.model, viscous_nm_s_per_rad.unwrap_or(0.0));
    let on_model = DesignInput { model, ..*input };
    let d = match rule {
        DesignRule::Robust => {
            return robust_design(&on_model, knobs, m_c_sigma_kg, c_sigma_n_per_m, stroke)
        }
        DesignRule::Knobs => design(&on_model, knobs)?,
        DesignRule::Thesis => design(input, knobs)?,
    };
    let guaranteed = guaranteed_margins(&d, &model, m_c_sigma_kg, c_sigma_n_per_m, stroke)?;
    Ok(RobustDesign {
        meets_guarantee: guaranteed.meets(knobs.dynamics),
        design: d,
        guaranteed,
        candidates_designed: 1,
        candidates_checked: 1,
    })
}

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

/// The velocity and position open loops of `design`'s controller on `model`,
/// evaluated once per point of `grid` (rad/s).
fn open_loops_on(
    design: &ControllerDesign,
    model: &TwoMassParams,
    grid: &[f64],
) -> (Vec<C64>, Vec<C64>) {
    let input = DesignInput {
        model: *model,
        ..design.input
    };
    let plant = VelocityPlant::new(&input, &design.prefilter);
    let gains = design.pi_gains();
    grid.iter()
        .map(|&w| {
            let fwd = gains.freq_response(w) * plant.forward(w);
            let l_v = fwd * plant.velocity_filter(w);
            (l_v, design.k_pp * fwd / (1.0 + l_v))
        })
        .unzip()
}

/// Smallest angular distance of `L(j w_c)` from -180 deg over every gain
/// crossover `w_c` of the sampled response `l` (deg; NaN without a crossover
/// or with a non-finite point). A crossover between two grid points is placed
/// by linear interpolation of `ln |L|`, its phase interpolated alike.
pub(crate) fn nyquist_phase_margin_deg(l: &[C64]) -> f64 {
    let mut pm = f64::NAN;
    for pair in l.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (la, lb) = (a.norm().ln(), b.norm().ln());
        if !(la.is_finite() && lb.is_finite()) {
            return f64::NAN;
        }
        if (la > 0.0) != (lb > 0.0) {
            let t = la / (la - lb);
            let arg = a.arg() + t * (b / a).arg();
            let d = (arg.to_degrees() + 180.0).rem_euclid(360.0);
            pm = pm.min(d.min(360.0 - d));
        }
    }
    pm
}

/// Smallest gain margin of the sampled response `l`, dB: `-20 log10 |L|`
/// where `L` crosses the negative real axis (`+inf` where it never does).
pub(crate) fn gain_margin_db(l: &[C64]) -> f64 {
    let mut gm = f64::INFINITY;
    for pair in l.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if (a.im > 0.0) != (b.im > 0.0) && (a.re < 0.0 || b.re < 0.0) {
            let t = a.im / (a.im - b.im);
            let at = a + (b - a) * t;
            if at.re < 0.0 {
                gm = gm.min(-crate::lti::db(at.norm()));
            }
        }
    }
    gm
}

/// Margins of `design`'s controller (prefilter, PI, P gains, sampled
/// controller) on `model` instead of the model it was designed on.
pub fn margins_on(design: &ControllerDesign, model: &TwoMassParams) -> Result<MarginsOn> {
    let input = DesignInput {
        model: *model,
        ..design.input
    };
    let grid = crate::design::verification_grid(&input)?;
    let (l_v, l_p) = open_loops_on(design, model, &grid);
    let pm_v = nyquist_phase_margin_deg(&l_v);
    let pm_p = nyquist_phase_margin_deg(&l_p);
    let gm_v = gain_margin_db(&l_v);
    let stable = crate::design::sampled::DiscreteLoops::new(&design.discrete, &input)
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

impl GuaranteedMargins {
    /// Whether these margins reach [`GUARANTEED_PHASE_MARGIN_DEG`] (velocity)
    /// and [`GUARANTEED_POSITION_PHASE_MARGIN_DEG`] (position); false for NaN.
    pub fn meets_guarantee(&self) -> bool {
        self.meets(Dynamics::STANDARD)
    }

    /// Whether these margins reach the guarantee of `dynamics`; false for NaN.
    pub fn meets(&self, dynamics: Dynamics) -> bool {
        self.velocity_phase_margin_deg >= dynamics.guaranteed_velocity_phase_margin_deg()
            && self.position_phase_margin_deg >= dynamics.guaranteed_position_phase_margin_deg()
            && self.velocity_gain_margin_db >= dynamics.guaranteed_velocity_gain_margin_db()
    }
}

/// The guaranteed margins of `design` over the box around `model` with
/// one-sigma uncertainties `m_c_sigma_kg`, `c_sigma_n_per_m` (NaN: 5 %),
/// and, where `stroke` is known, on `model` carried to either end of the
/// stroke ([`StrokeVariation::at_ends`]), with its damping as given and
/// halved: the controller identified at one position runs at all of them.
pub fn guaranteed_margins(
    design: &ControllerDesign,
    model: &TwoMassParams,
    m_c_sigma_kg: f64,
    c_sigma_n_per_m: f64,
    stroke: Option<&StrokeVariation>,
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
    let halved = |m: TwoMassParams| TwoMassParams {
        d_m: 0.5 * m.d_m,
        d_c: 0.5 * m.d_c,
        d: 0.5 * m.d,
        ..m
    };
    let mut models = Vec::with_capacity(22);
    for dm in [-1.0, 0.0, 1.0] {
        for dc in [-1.0, 0.0, 1.0] {
            let m = TwoMassParams {
                m_c: (model.m_c + dm * k * sm).max(0.2 * model.m_c),
                c: (model.c + dc * k * sc).max(0.2 * model.c),
                ..*model
            };
            models.extend([m, halved(m)]);
        }
    }
    if let Some(v) = stroke {
        for m in v.at_ends(model) {
            models.extend([m, halved(m)]);
        }
    }
    let mut out = GuaranteedMargins {
        velocity_phase_margin_deg: f64::INFINITY,
        velocity_gain_margin_db: f64::INFINITY,
        position_phase_margin_deg: f64::INFINITY,
        models: 0,
    };
    let worse = |a: f64, b: f64| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.min(b)
        }
    };
    for m in &models {
        let on = margins_on(design, m)?;
        out.velocity_phase_margin_deg =
            worse(out.velocity_phase_margin_deg, on.velocity_phase_margin_deg);
        out.velocity_gain_margin_db =
            worse(out.velocity_gain_margin_db, on.velocity_gain_margin_db);
        out.position_phase_margin_deg =
            worse(out.position_phase_margin_deg, on.position_phase_margin_deg);
        out.models += 1;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Margins on the fit only: the design model's rigid-body
    /// damping is the measured viscous friction, its resonance damping the
    /// fit's, and the split is exact.
    #[test]
    fn the_design_model_separates_friction_from_resonance_damping() {
        let fit = TwoMassParams {
            d: 0.0,
            ..TwoMassParams::thesis_table_a4()
        };
        let viscous = 0.1 * fit.rigid_damping();
        let m = design_model(&fit, viscous);
        assert!((m.rigid_damping() / viscous - 1.0).abs() < 1e-12, "{m:?}");
        assert!((m.resonance_damping() / fit.resonance_damping() - 1.0).abs() < 1e-12);
        assert!((m.d_m / m.d_c - fit.d_m / fit.d_c).abs() < 1e-9);
        assert!(m.d > 0.0);
        // More viscous friction than the fit's damping: no negative belt damping.
        let m = design_model(&fit, 3.0 * fit.rigid_damping());
        assert_eq!(m.d, 0.0);
        assert_eq!(design_model(&fit, f64::NAN), fit);
    }

    /// The root cause: on egc70 the thesis design on the fit keeps
    /// far less than its 60 deg on the axis' true linearization, the robust
    /// design on the design model keeps at least the guaranteed margin. The
    /// "fit" here is the egc70 commissioning's identified model (rounded), the
    /// measured viscous friction the friction runs' value; the truth is the
    /// simulator's linearization with its belt damping.
    #[test]
    fn the_robust_design_keeps_its_margins_on_the_true_egc70() {
        let plant = crate::model::rigs::egc70_params(11.2);
        let truth = plant.linearize(0.5).unwrap();
        let fit = TwoMassParams {
            d: 0.0,
            d_m: 40.7,
            d_c: 185.7,
            m_c: 12.38,
            c: 217.5e3,
            ..truth
        };
        let on_truth =
            |d: &ControllerDesign| margins_on(d, &truth).unwrap().velocity_phase_margin_deg;
        let thesis = design(&DesignInput::new(fit, 1e-3), &DesignKnobs::default()).unwrap();
        assert!(on_truth(&thesis) < 45.0, "{}", on_truth(&thesis));
        let input = DesignInput::new(design_model(&fit, 4.06e-3), 1e-3);
        let r = robust_design(&input, &DesignKnobs::default(), 0.31, 3.8e3, None).unwrap();
        assert!(r.meets_guarantee, "{r:?}");
        let pm = on_truth(&r.design);
        assert!(pm >= GUARANTEED_PHASE_MARGIN_DEG, "{pm} {r:?}");
        // And it is not bought with a slow loop: its integral stiffness
        // (the static-error driver) is no lower than the thesis design's.
        assert!(
            integral_stiffness(&r.design) >= integral_stiffness(&thesis),
            "{} vs {}",
            integral_stiffness(&r.design),
            integral_stiffness(&thesis)
        );
    }
}
