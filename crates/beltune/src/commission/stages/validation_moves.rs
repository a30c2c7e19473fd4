//! Stage 8: the validation move (thesis chapter 5, Table A.8) with nonlinear
//! feedforward (the delivered controller), and on request
//! ([`CommissioningConfig::compare_feedforward`]) first with no and linear
//! feedforward for the comparison, each from the same start; the unmeasured
//! return to the start runs under the positioning controller.

use super::super::motion::{FollowingError, TrackOptions};
use super::super::validation::{
    run_move, validation_controller, validation_track_options, FeedforwardVariant, VariantMove,
};
use super::super::{positioning_limits, CommissioningConfig, DataSheet};
use super::Stages;
use crate::commission::validation::Validation;
use crate::ident::fit::TwoMassFit;
use crate::record::model::FrictionResult;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// What stage 8 hands on.
pub struct ValidationMoves {
    /// The moves that ran, in order: none and linear feedforward where
    /// asked for, then nonlinear (the delivered controller's, always last).
    pub moves: Vec<VariantMove>,
    /// Their summaries.
    pub validation: Validation,
    /// The move actually run (Table A.8's, or the fastest the axis can do).
    pub planned: PlannedMove,
}

/// Fraction of the torque limit the validation move may use for
/// acceleration, gravity and friction together (the rest is the feedback's).
pub const MOVE_TORQUE_FRACTION: f64 = 0.9;
/// Distance the validation start keeps from the window's lower edge, m.
const START_CLEARANCE_M: f64 = 0.01;
/// Distance the validation target keeps from the window's upper edge, m
/// (Table A.8: 0.5 m target in a window up to 0.57 m).
const TARGET_CLEARANCE_M: f64 = 0.07;

/// The validation move fitted to the axis: Table A.8's limits
/// where the axis can do them, else the fastest move it can do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlannedMove {
    /// Start, m.
    pub start_m: f64,
    /// Target, m.
    pub target_m: f64,
    /// The trajectory limits used.
    pub limits: Limits,
    /// Largest acceleration the torque budget allows, m/s^2.
    pub acceleration_capability_m_s2: f64,
    /// Whether the move is slower than Table A.8's (the axis cannot do it).
    pub reduced: bool,
}

/// Where the validation move of `spec` ends inside the travel window of
/// `ds`, m: its target, at most [`TARGET_CLEARANCE_M`] below the window's
/// upper edge. Known before any experiment, so that the belt stiffness can be
/// measured there ([`super::identification::stiffness_at`]).
pub fn validation_target_m(spec: &super::super::validation::MoveSpec, ds: &DataSheet) -> f64 {
    spec.target_m.min(ds.travel_max_m - TARGET_CLEARANCE_M)
}

/// The validation move for an axis with rigid inertia `inertia_kg_m2`,
/// transmission `i_t_m`, friction `friction` (at the motor), holding torque
/// `holding_nm`, torque limit `torque_max_nm` and worst stop deceleration
/// `stop_deceleration_m_s2`, inside the travel window of `ds`.
#[allow(clippy::too_many_arguments)]
pub fn plan_validation_move(
    spec: &super::super::validation::MoveSpec,
    ds: &DataSheet,
    inertia_kg_m2: f64,
    i_t_m: f64,
    friction: &FrictionResult,
    holding_nm: f64,
    torque_max_nm: f64,
    stop_deceleration_m_s2: f64,
) -> Result<PlannedMove> {
    let start = spec.start_m.max(ds.travel_min_m + START_CLEARANCE_M);
    let target = validation_target_m(spec, ds);
    if (target - start).partial_cmp(&0.05) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::Infeasible {
            reason: format!(
                "the travel window [{:.0}, {:.0}] mm leaves no room for a validation move",
                ds.travel_min_m * 1e3,
                ds.travel_max_m * 1e3
            ),
        });
    }
    let mut limits = Limits {
        position_min: ds.travel_min_m,
        position_max: ds.travel_max_m,
        ..spec.limits
    };
    // Torque left after gravity and Coulomb friction; viscous friction at
    // the move's top speed and the acceleration share it.
    let budget =
        MOVE_TORQUE_FRACTION * torque_max_nm - holding_nm.abs() - friction.coulomb_nm.abs();
    if budget.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::Infeasible {
            reason: format!(
                "gravity and friction take {:.3} N m of the torque limit {torque_max_nm:.3} N m: the axis cannot accelerate",
                holding_nm.abs() + friction.coulomb_nm.abs()
            ),
        });
    }
    let viscous = friction.viscous_nm_s_per_rad.max(0.0);
    let mut reduced = false;
    let mut probe = Trajectory::plan(&State::at_rest(start), &State::at_rest(target), &limits)?;
    let v_peak = peak_velocity(&probe);
    // At most half the budget for viscous friction: cap the speed.
    if viscous * v_peak / i_t_m > 0.5 * budget {
        let v_cap = 0.5 * budget * i_t_m / viscous;
        limits.v_max = v_cap;
        limits.v_min = -v_cap;
        probe = Trajectory::plan(&State::at_rest(start), &State::at_rest(target), &limits)?;
        reduced = true;
    }
    let v_peak = peak_velocity(&probe);
    let a_peak = peak_acceleration(&probe);
    let a_cap =
        ((budget - viscous * v_peak / i_t_m) * i_t_m / inertia_kg_m2).min(stop_deceleration_m_s2);
    if a_peak > a_cap {
        // The fastest move: the largest acceleration the torque allows, the
        // jerk scaled with it (Table A.8's ratio).
        let scale = a_cap / a_peak;
        limits.a_max = a_cap;
        limits.a_min = -a_cap;
        limits.j_max = spec.limits.j_max * scale;
        limits.j_min = spec.limits.j_min * scale;
        reduced = true;
    }
    Ok(PlannedMove {
        start_m: start,
        target_m: target,
        limits,
        acceleration_capability_m_s2: a_cap,
        reduced,
    })
}

/// Limits of the unmeasured return to the validation start inside the
/// window of `ds`: the validation move's `planned` limits, at most those of
/// the positioning moves the positioning controller ran in stages 2-5, with
/// the acceleration at most half the stop deceleration
/// `stop_deceleration_m_s2` (so that the look-ahead, which assumes the
/// stop's deceleration after a reaction time, never trips on the return's
/// own braking).
///
/// Travel stops of feasible plants: at the validation move's
/// 1.1 m/s the slow bootstrap loop, without Coulomb feedforward, lagged a
/// light cart with high friction by 30 mm and its integrator, wound up
/// against the friction, carried the cart 18 mm past the approach point,
/// 15 mm inside the window, to 3 mm outside the start: the look-ahead
/// stopped it.
pub fn return_limits(planned: &Limits, ds: &DataSheet, stop_deceleration_m_s2: f64) -> Limits {
    let positioning = positioning_limits(ds);
    let a = planned
        .a_max
        .min(positioning.a_max)
        .min(0.5 * stop_deceleration_m_s2);
    let v = planned.v_max.min(positioning.v_max);
    let j = planned.j_max.min(positioning.j_max);
    Limits {
        v_max: v,
        v_min: -v,
        a_max: a,
        a_min: -a,
        j_max: j,
        j_min: -j,
        position_min: ds.travel_min_m,
        position_max: ds.travel_max_m,
    }
}

fn peak_velocity(t: &Trajectory) -> f64 {
    sampled(t).map(|s| s.velocity.abs()).fold(0.0, f64::max)
}

fn peak_acceleration(t: &Trajectory) -> f64 {
    sampled(t).map(|s| s.acceleration.abs()).fold(0.0, f64::max)
}

fn sampled(t: &Trajectory) -> impl Iterator<Item = beltune_rt::trajectory::Sample> + '_ {
    let d = t.duration_s();
    (0..=400).map(move |k| t.sample(d * k as f64 / 400.0))
}

/// Stage 8: the three validation moves with `feedback` plus each feedforward
/// variant built from the fit (belt stretch), the rigid inertia
/// `feedforward_inertia_kg_m2` (the friction runs' or the fit's, which also
/// sizes the move's acceleration) and the friction of stage 7, the belt
/// stretch with the compliance along the stroke `belt` measured in stages
/// 5b/5c (dynamic and static under the holding torque). The unmeasured
/// return to the start runs under `positioning` (the bootstrap controller
/// with the holding torque, the one of the positioning moves of stages 2-5).
#[allow(clippy::too_many_arguments)]
pub fn validation_moves(
    st: &mut Stages,
    feedback: &CascadeConfig<f64>,
    positioning: &CascadeConfig<f64>,
    fit: &TwoMassFit,
    feedforward_inertia_kg_m2: f64,
    friction: &FrictionResult,
    preview: usize,
    holding_nm: f64,
    belt: &crate::commission::stiffness::TargetStiffness,
    datasheet: &DataSheet,
    cfg: &CommissioningConfig,
) -> Result<ValidationMoves> {
    let ts = st.runner.info().ts_s;
    let p = fit.params;
    let m_e = feedforward_inertia_kg_m2;
    let opts = validation_track_options(
        &p,
        preview,
        holding_nm,
        belt,
        friction,
        st.runner.origin_m(),
    );
    let variants: &[FeedforwardVariant] = if cfg.compare_feedforward {
        &FeedforwardVariant::ALL
    } else {
        &[FeedforwardVariant::Nonlinear]
    };
    let move_samples = ((cfg.validation.settle_s + 1.5) / ts) as u64 * variants.len() as u64;
    st.start("validation moves", move_samples);
    let mut moves: Vec<VariantMove> = Vec::with_capacity(variants.len());
    let planned = plan_validation_move(
        &cfg.validation,
        datasheet,
        m_e,
        p.i_t,
        friction,
        holding_nm,
        st.runner.supervisor().limits().torque_max_nm,
        st.runner
            .supervisor()
            .capability()
            .worst_deceleration_m_s2(),
    )?;
    let spec = super::super::validation::MoveSpec {
        start_m: planned.start_m,
        target_m: planned.target_m,
        limits: planned.limits,
        ..cfg.validation
    };
    // The unmeasured return to the start runs under the positioning
    // controller (the bootstrap cascade of stages 2-5, which moved the axis
    // safely before) with the move's limits within the positioning limits
    // it ran under there, braking with at most half the stop deceleration,
    // to a point 15 mm
    // inside the window from which it creeps to the start
    // ([`super::super::validation::run_move`]). Under the designed
    // feedback without feedforward, a loop that is poorly damped on the real
    // axis overshot and hunted at the torque limit on the way back, and the
    // look-ahead stopped it 80 mm before the window's edge.
    let worst_stop = st
        .runner
        .supervisor()
        .capability()
        .worst_deceleration_m_s2();
    let return_limits = return_limits(&planned.limits, datasheet, worst_stop);
    for &variant in variants {
        // the same controller the tuning page simulates
        let c = validation_controller(
            feedback,
            m_e,
            p.i_t,
            friction,
            belt.stiffness_at(planned.target_m),
            variant,
        );
        // The following-error limit guards the delivered controller (the
        // nonlinear feedforward). The comparison variants lag by design: a
        // slow loop without torque feedforward trailed the Table A.8 move by
        // 53 mm on plant #248 of the robustness study (position loop 1.3 Hz), which
        // stopped the whole commissioning. They track in closed loop with
        // their error recorded, not limited; the closed loop's travel
        // look-ahead, the torque and the velocity limits still guard them.
        let variant_opts = TrackOptions {
            following_error: if variant == FeedforwardVariant::Nonlinear {
                FollowingError::Limited
            } else {
                FollowingError::Recorded
            },
            ..opts
        };
        // Return to the start within the return limits (it is not measured).
        let result = run_move(
            st.runner,
            positioning,
            &return_limits,
            &c,
            variant_opts,
            &spec,
        )?;
        moves.push(VariantMove { variant, result });
    }
    let summary_of = |v: FeedforwardVariant| {
        moves
            .iter()
            .find(|m| m.variant == v)
            .map(|m| m.result.summary.clone())
    };
    let validation = Validation {
        none: summary_of(FeedforwardVariant::None),
        linear: summary_of(FeedforwardVariant::Linear),
        nonlinear: summary_of(FeedforwardVariant::Nonlinear).ok_or_else(|| Error::TooShort {
            what: "validation moves".into(),
            needed: 1,
            got: 0,
        })?,
    };
    let compared = match (&validation.none, &validation.linear) {
        (Some(n), Some(l)) => format!(
            "none {:.3} mm, linear {:.3} mm, ",
            n.max_tracking_error_m * 1e3,
            l.max_tracking_error_m * 1e3
        ),
        _ => String::new(),
    };
    let approach = spec
        .approach(&opts.belt_stretch, st.runner.origin_m())
        .map_or(String::new(), |a| {
            format!(
                ", the last {:.2} mm crept at {:.0} mm/s",
                a.distance_m * 1e3,
                a.speed_m_s * 1e3
            )
        });
    let line = format!(
        "{}{approach}; max cart error: {compared}nonlinear {:.3} mm; static (nonlinear) {:.1} um",
        if planned.reduced {
            format!(
                "the fastest move the axis can do {:.0} -> {:.0} mm (v <= {:.2} m/s, a <= {:.2} m/s^2; Table A.8's is beyond its torque)",
                planned.start_m * 1e3,
                planned.target_m * 1e3,
                planned.limits.v_max,
                planned.limits.a_max
            )
        } else {
            format!(
                "Table A.8 move {:.0} -> {:.0} mm",
                planned.start_m * 1e3,
                planned.target_m * 1e3
            )
        },
        validation.nonlinear.max_tracking_error_m * 1e3,
        validation.nonlinear.static_error_m * 1e6
    );
    st.finish("validation", line);
    Ok(ValidationMoves {
        moves,
        validation,
        planned,
    })
}
