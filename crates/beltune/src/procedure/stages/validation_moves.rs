//! Stage 8: the validation move (thesis chapter 5, Table A.8) with no, linear
//! and nonlinear feedforward, each from the same start; the unmeasured return
//! to the start runs under the feedback cascade.

use super::super::commission::{CommissioningConfig, DataSheet};
use super::super::result::{FrictionResult, Validation};
use super::super::validation::{
    run_move, validation_controller, validation_track_options, FeedforwardVariant, MoveResult,
};
use super::Stages;
use crate::ident::fit::TwoMassFit;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::Limits;

/// What stage 8 hands on.
pub struct ValidationMoves {
    /// The three moves: none, linear, nonlinear feedforward.
    pub moves: [MoveResult; 3],
    /// Their summaries.
    pub validation: Validation,
}

/// Stage 8: the three validation moves with `feedback` plus each feedforward
/// variant built from the fit and the friction of stage 7.
#[allow(clippy::too_many_arguments)]
pub fn validation_moves(
    st: &mut Stages,
    feedback: &CascadeConfig<f64>,
    fit: &TwoMassFit,
    friction: &FrictionResult,
    preview: usize,
    holding_nm: f64,
    datasheet: &DataSheet,
    cfg: &CommissioningConfig,
) -> Result<ValidationMoves> {
    let ts = st.runner.info().ts_s;
    let p = fit.params;
    let m_e = p.rigid_inertia();
    let opts = validation_track_options(&p, preview, holding_nm);
    let move_samples =
        ((cfg.validation.settle_s + 1.5) / ts) as u64 * FeedforwardVariant::ALL.len() as u64;
    st.start("validation moves", move_samples);
    let mut moves: Vec<MoveResult> = Vec::with_capacity(3);
    let return_limits = Limits {
        position_min: datasheet.travel_min_m,
        position_max: datasheet.travel_max_m,
        ..cfg.validation.limits
    };
    for variant in FeedforwardVariant::ALL {
        // the same controller the tuning page simulates (issue 16)
        let c = validation_controller(feedback, m_e, friction, variant);
        // Return to the start with the thesis' own limits (it is not measured).
        moves.push(run_move(
            st.runner,
            feedback,
            &return_limits,
            &c,
            opts,
            &cfg.validation,
        )?);
    }
    let validation = Validation {
        none: moves[0].summary.clone(),
        linear: moves[1].summary.clone(),
        nonlinear: moves[2].summary.clone(),
    };
    let line = format!(
        "max cart error: none {:.3} mm, linear {:.3} mm, nonlinear {:.3} mm; static (nonlinear) {:.1} um",
        validation.none.max_tracking_error_m * 1e3,
        validation.linear.max_tracking_error_m * 1e3,
        validation.nonlinear.max_tracking_error_m * 1e3,
        validation.nonlinear.static_error_m * 1e6
    );
    st.finish("validation", line);
    let moves: [MoveResult; 3] = moves.try_into().map_err(|_| Error::TooShort {
        what: "validation moves".into(),
        needed: 3,
        got: 0,
    })?;
    Ok(ValidationMoves { moves, validation })
}
