//! Stage 6: the controller design (thesis chapter 4) on the identified model,
//! and the real-time cascade that takes over the axis from the bootstrap
//! controller.

use super::super::{cascade_from_design, CommissioningConfig};
use super::Stages;
use crate::design::robust::{design_identified, RobustDesign};
use crate::design::{ControllerDesign, DesignInput};
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
/// cascade becomes the runner's stop controller. Before the friction runs the
/// viscous friction is unknown; the design model then has none (a pure
/// integrator at low frequency, the conservative phase) and the resonance
/// damping of the fit ([`crate::design::robust::design_model`]).
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
    let des = st.compute(|| design_rule(&input, cfg, fit, None))?.design;
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
/// [`CommissioningConfig::design_rule`].
pub fn design_rule(
    input: &DesignInput,
    cfg: &CommissioningConfig,
    fit: &TwoMassFit,
    viscous_nm_s_per_rad: Option<f64>,
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
        &cfg.knobs,
        rule,
    )
}
