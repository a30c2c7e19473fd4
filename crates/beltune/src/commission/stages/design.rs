//! Stage 6: the controller design (thesis chapter 4) on the identified model,
//! and the real-time cascade that takes over the axis from the bootstrap
//! controller; stage 7b: the delivered design on the friction stage 7
//! measured.

use super::super::{cascade_from_design, CommissioningConfig};
use super::friction::FrictionStage;
use super::Stages;
use crate::design::robust::{design_identified, DesignRule, GuaranteedMargins, RobustDesign};
use crate::design::{ControllerDesign, DesignInput, Feedforward, PrefilterKind};
use crate::ident::fit::{FitModel, TwoMassFit};
use crate::model::stroke::StrokeVariation;
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
/// cascade becomes the runner's stop controller. Before the friction runs the
/// viscous friction is unknown; the design model then has none (a pure
/// integrator at low frequency, the conservative phase) and the resonance
/// damping of the fit ([`crate::design::robust::design_model`]). `stroke`:
/// the model along the stroke (the data sheet's), checked by the robust rule.
#[allow(clippy::too_many_arguments)]
pub fn design_stage(
    st: &mut Stages,
    fit: &TwoMassFit,
    stroke: Option<&StrokeVariation>,
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
    let des = st
        .compute(|| design_rule(&input, cfg, fit, None, stroke))?
        .design;
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

/// The configured design rule on `fit` with the measured viscous friction
/// `viscous_nm_s_per_rad` (N m s/rad at the motor; `None` before the friction
/// runs): [`crate::design::robust::design_identified`] with
/// [`CommissioningConfig::design_rule`], checked along the `stroke`.
pub fn design_rule(
    input: &DesignInput,
    cfg: &CommissioningConfig,
    fit: &TwoMassFit,
    viscous_nm_s_per_rad: Option<f64>,
    stroke: Option<&StrokeVariation>,
) -> Result<RobustDesign> {
    let rule = cfg.design_rule;
    let input = DesignInput {
        model: fit.params,
        ..*input
    };
    design_identified(
        &input,
        viscous_nm_s_per_rad,
        fit.m_c_sigma(),
        fit.c_sigma(),
        stroke,
        &cfg.knobs,
        rule,
    )
}

/// What stage 7b hands on: the controller that is delivered.
pub struct DeliveredDesign {
    /// The design with its feedforward (inertia, viscous and Coulomb friction).
    pub design: ControllerDesign,
    /// The feedback cascade (no feedforward, holding torque as offset).
    pub feedback: CascadeConfig<f64>,
    /// The margins it keeps over the identification's uncertainty.
    pub guaranteed: GuaranteedMargins,
}

/// Stage 7b: the design again, on the damping the friction runs support
/// (the FRF's motor and cart damping `d_m`, `d_c` lump the Coulomb friction
/// the small-signal excitation meets into viscous damping; the runs measure
/// the real viscous part, [`crate::design::robust`]), with the feedforward
/// of the measured friction. Its feedback becomes the runner's stop
/// controller. The feedforward's inertia: the friction-aware fit's rigid
/// inertia (its motor inertia solved: within 2.5 % of the truth on the
/// robustness study's plants); without it, the rigid body the friction runs
/// accelerated (the FRF fit's `m_c` came out up to 38 % heavy on heavy
/// payloads on soft belts; the momentum balance is within 5 % there but up
/// to 16 % light on light carts with high friction), else the FRF fit's.
#[allow(clippy::too_many_arguments)]
pub fn delivered_design(
    st: &mut Stages,
    designed: &ControllerDesign,
    fit: &TwoMassFit,
    stroke: Option<&StrokeVariation>,
    friction: &FrictionStage,
    torque_max_nm: f64,
    holding_nm: f64,
    cfg: &CommissioningConfig,
) -> Result<DeliveredDesign> {
    let fr = &friction.result;
    let robust = st.compute(|| {
        design_rule(
            &designed.input,
            cfg,
            fit,
            Some(fr.viscous_nm_s_per_rad),
            stroke,
        )
    })?;
    let guaranteed = robust.guaranteed;
    let tried = match cfg.design_rule {
        DesignRule::Robust => format!(
            "{} candidate designs, {} checked over the uncertainty{}",
            robust.candidates_designed,
            robust.candidates_checked,
            if robust.meets_guarantee {
                ""
            } else {
                "; none meets the guarantee, the most robust kept"
            }
        ),
        DesignRule::Knobs => "the configured knobs on the design model".into(),
        DesignRule::Thesis => "the thesis design on the fit as identified".into(),
    };
    let designed = robust.design;
    let feedback = cascade_from_design(&designed, torque_max_nm, holding_nm)?;
    st.runner.set_stop_controller(feedback);
    st.start("robust design", 0);
    let line = format!(
        "{} prefilter ({:.1} dB), K_P {:.4} N m s/rad, K_I {:.3} N m/rad, K_PP {:.2} 1/s, velocity loop {:.1} Hz / {:.1} deg nominal; guaranteed over the uncertainty: velocity {:.1} deg, position {:.1} deg (candidates: {tried})",
        match designed.knobs.prefilter {
            PrefilterKind::Butterworth => "Butterworth",
            PrefilterKind::Notch => "notch",
            PrefilterKind::None => "no",
        },
        designed.knobs.attenuation_db(),
        designed.k_p,
        designed.k_i,
        designed.k_pp,
        designed.velocity_margins.crossover_rad_s / (2.0 * std::f64::consts::PI),
        designed.velocity_margins.phase_margin_deg,
        guaranteed.velocity_phase_margin_deg,
        guaranteed.position_phase_margin_deg
    );
    st.finish("robust design", line);
    let input = DesignInput {
        friction: Some(fr.params()),
        ..designed.input
    };
    let p = fit.params;
    let feedforward_inertia = if fit.model == FitModel::Nonlinear {
        p.rigid_inertia()
    } else {
        friction
            .rigid_inertia
            .map(|m| m.inertia_kg_m2)
            .unwrap_or_else(|| p.rigid_inertia())
    };
    let design = ControllerDesign {
        feedforward: Feedforward {
            inertia_kg_m2: feedforward_inertia,
            ..Feedforward::design(&p, input.friction.as_ref())?
        },
        input,
        ..designed
    };
    Ok(DeliveredDesign {
        design,
        feedback,
        guaranteed,
    })
}
