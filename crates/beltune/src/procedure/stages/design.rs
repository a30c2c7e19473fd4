//! Stage 6: the controller design (thesis chapter 4) on the identified model,
//! and the real-time cascade that takes over the axis from the bootstrap
//! controller.

use super::super::commission::{cascade_from_design, CommissioningConfig};
use super::Stages;
use crate::design::{design, ControllerDesign, DesignInput};
use crate::ident::fit::TwoMassFit;
use crate::Result;
use beltune_rt::control::CascadeConfig;

/// What stage 6 hands on.
pub struct DesignStage {
    /// The design (no friction feedforward yet: stage 7 measures it).
    pub design: ControllerDesign,
    /// The feedback cascade (no feedforward, holding torque as offset).
    pub feedback: CascadeConfig<f64>,
}

/// Stage 6: design on `fit` with the dead time `dead_time_s`; the feedback
/// cascade becomes the runner's stop controller.
pub fn design_stage(
    st: &mut Stages,
    fit: &TwoMassFit,
    dead_time_s: f64,
    torque_max_nm: f64,
    holding_nm: f64,
    cfg: &CommissioningConfig,
) -> Result<DesignStage> {
    st.start("controller design", 0);
    let ts = st.runner.info().ts_s;
    let input = DesignInput {
        model: fit.params,
        dead_time_s,
        t_r_s: cfg.t_r_s,
        ts_s: ts,
        friction: None,
    };
    let des = st.compute(|| design(&input, &cfg.knobs))?;
    let feedback = cascade_from_design(&des, torque_max_nm, holding_nm)?;
    st.runner.set_stop_controller(feedback);
    let line = format!(
        "K_P {:.4} N m s/rad, K_I {:.3} N m/rad, K_PP {:.2} 1/s; velocity loop {:.1} Hz / {:.1} deg, position loop {:.1} Hz / {:.1} deg, {:.2} dB at w_r",
        des.k_p,
        des.k_i,
        des.k_pp,
        des.velocity_margins.crossover_rad_s / (2.0 * std::f64::consts::PI),
        des.velocity_margins.phase_margin_deg,
        des.position_margins.crossover_rad_s / (2.0 * std::f64::consts::PI),
        des.position_margins.phase_margin_deg,
        des.gain_at_resonance_db
    );
    st.finish("design", line);
    Ok(DesignStage {
        design: des,
        feedback,
    })
}

/// Guaranteed velocity phase margin the robust redesign aims for, deg.
pub const ROBUST_PHASE_MARGIN_DEG: f64 = 35.0;

/// The prefilters the robust redesign tries besides the configured one:
/// stronger Butterworth attenuation and notches of growing width at the
/// resonance (attenuation at the antiresonance, dB).
const ROBUST_PREFILTERS: [(crate::design::PrefilterKind, f64); 5] = [
    (crate::design::PrefilterKind::Butterworth, -6.0),
    (crate::design::PrefilterKind::Notch, -6.0),
    (crate::design::PrefilterKind::Notch, -12.0),
    (crate::design::PrefilterKind::Notch, -20.0),
    (crate::design::PrefilterKind::Butterworth, -12.0),
];

/// The design rule for lightly damped axes (issue 12). On the model whose
/// damping is bounded by the measured friction ([`bound_damping`]) the thesis'
/// (4.7) `|L(j w_r)| = A_sup` only has a root at a crossover of 1-2 Hz: the
/// undamped resonance peak stands far above the rigid-body line, and the PI
/// alone must push it under `A_sup`. The principled remedy is to take the
/// peak down with the prefilter instead: each candidate (the first design, the
/// configured prefilter on the bounded model, stronger Butterworth
/// attenuation, notches at `w_r` of growing width) is designed with the
/// thesis' conditions (4.7)-(4.9) on the bounded model, its margins are
/// checked over the identification's uncertainty box
/// ([`crate::procedure::acceptance::guaranteed_margins`]), and the fastest
/// velocity loop that keeps [`ROBUST_PHASE_MARGIN_DEG`] there wins; if none
/// does, the one with the largest guaranteed margin.
pub fn robust_design(
    first: &ControllerDesign,
    bounded: &crate::model::TwoMassParams,
    m_c_sigma_kg: f64,
    c_sigma_n_per_m: f64,
    knobs: &crate::design::DesignKnobs,
) -> Result<(
    ControllerDesign,
    crate::procedure::acceptance::GuaranteedMargins,
    String,
)> {
    use crate::procedure::acceptance::guaranteed_margins;
    let mut tried = Vec::new();
    let input = DesignInput {
        model: *bounded,
        ..first.input
    };
    let mut candidates = vec![first.clone()];
    let mut variants = vec![*knobs];
    for (kind, att) in ROBUST_PREFILTERS {
        variants.push(crate::design::DesignKnobs {
            prefilter: kind,
            filter_attenuation_db: Some(att),
            ..*knobs
        });
    }
    for k in variants {
        if let Ok(d) = design(&input, &k) {
            candidates.push(d);
        }
    }
    let mut best: Option<(
        ControllerDesign,
        crate::procedure::acceptance::GuaranteedMargins,
    )> = None;
    for d in candidates {
        let Ok(g) = guaranteed_margins(&d, bounded, m_c_sigma_kg, c_sigma_n_per_m) else {
            continue;
        };
        tried.push(format!(
            "{:?} {:.0} dB {:.1} Hz {:.0} deg",
            d.knobs.prefilter,
            d.knobs.attenuation_db(),
            d.velocity_margins.crossover_rad_s / (2.0 * std::f64::consts::PI),
            g.velocity_phase_margin_deg
        ));
        let ok = |g: &crate::procedure::acceptance::GuaranteedMargins| {
            g.velocity_phase_margin_deg >= ROBUST_PHASE_MARGIN_DEG
                && g.position_phase_margin_deg >= ROBUST_PHASE_MARGIN_DEG
        };
        let better = match &best {
            None => true,
            Some((b, bg)) => match (ok(&g), ok(bg)) {
                (true, false) => true,
                (false, true) => false,
                (true, true) => {
                    d.velocity_margins.crossover_rad_s > b.velocity_margins.crossover_rad_s
                }
                (false, false) => g.velocity_phase_margin_deg > bg.velocity_phase_margin_deg,
            },
        };
        if better {
            best = Some((d, g));
        }
    }
    let (d, g) = best.ok_or_else(|| crate::Error::Infeasible {
        reason: "no controller design exists for the identified model".into(),
    })?;
    Ok((d, g, tried.join(", ")))
}

/// The identified model with its motor and cart damping `d_m`, `d_c`
/// bounded by the viscous friction the constant-velocity runs measured
/// (`viscous_nm_s_per_rad` at the motor, (3.36)): the rigid-body damping
/// `i_t^2 (d_m + d_c)` of the model may not exceed it, both scaled alike; the
/// belt's own damping `d` is kept. An FRF measured with a small excitation
/// shows Coulomb friction as damping (issue 12: the design then meets its
/// margins on a model far better damped than the axis).
pub fn bound_damping(
    model: &crate::model::TwoMassParams,
    viscous_nm_s_per_rad: f64,
) -> crate::model::TwoMassParams {
    let rigid = model.i_t * model.i_t * (model.d_m + model.d_c);
    if !(viscous_nm_s_per_rad.is_finite() && viscous_nm_s_per_rad >= 0.0)
        || rigid <= viscous_nm_s_per_rad
    {
        return *model;
    }
    let scale = viscous_nm_s_per_rad / rigid;
    crate::model::TwoMassParams {
        d_m: model.d_m * scale,
        d_c: model.d_c * scale,
        ..*model
    }
}

#[cfg(test)]
mod tests {
    use super::bound_damping;

    /// Issue 12 (margins on the fit only): the model's rigid-body damping is
    /// capped at the measured viscous friction, the belt damping untouched.
    #[test]
    fn identified_damping_is_bounded_by_the_measured_viscous_friction_issue_12() {
        let m = crate::model::rigs::sim_a();
        let rigid = m.i_t * m.i_t * (m.d_m + m.d_c);
        let b = bound_damping(&m, 0.25 * rigid);
        assert!((b.i_t * b.i_t * (b.d_m + b.d_c) - 0.25 * rigid).abs() < 1e-12 * rigid);
        assert!((b.d_m / b.d_c - m.d_m / m.d_c).abs() < 1e-12);
        assert_eq!(b.d, m.d);
        assert_eq!(bound_damping(&m, 2.0 * rigid), m);
        assert_eq!(bound_damping(&m, f64::NAN), m);
    }
}
