//! Stage 8 (thesis chapter 5): the validation move 0 -> 500 mm with the
//! trajectory limits of Table A.8, with no, linear and nonlinear feedforward,
//! measuring the cart tracking error (simulation truth or a cart encoder) and
//! the motor-side error.

use super::motion::{move_to, track, TrackOptions, TrackRecord};
use super::runner::Runner;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Approach, ApproachConfig, Limits, State, Trajectory};
use serde::{Deserialize, Serialize};

/// Result of one validation move.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MoveSummary {
    /// Largest cart tracking error `|xi_d - xi|` during and after the move, m
    /// (motor-side `|xi_d - i_t phi_m|` when the axis has no cart encoder).
    pub max_tracking_error_m: f64,
    /// Mean `|xi_d - xi|` over the last 100 ms of the record, m.
    pub static_error_m: f64,
    /// Time from the end of the trajectory until the error stays within the
    /// settling band, s; `None` (JSON `null`) if it never settles within the record.
    pub settling_time_s: Option<f64>,
    /// Largest motor-side error `|xi_d - i_t phi_m|`, m.
    pub max_motor_error_m: f64,
    /// Largest torque command magnitude, N m.
    pub max_torque_nm: f64,
}

/// The validation with the three feedforward variants of chapter 5: the
/// delivered controller's move (nonlinear feedforward) always, the two
/// comparison moves only where they were asked for
/// ([`super::CommissioningConfig::compare_feedforward`]; neither is judged
/// nor delivered, and together they kept the axis busy 7-8 s).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// Without feedforward (`null`: not run).
    #[serde(default)]
    pub none: Option<MoveSummary>,
    /// Linear feedforward (inertia and a viscous-only friction fit; `null`: not run).
    #[serde(default)]
    pub linear: Option<MoveSummary>,
    /// Nonlinear feedforward (inertia, viscous and Coulomb): the delivered controller's move.
    pub nonlinear: MoveSummary,
}

/// Band within which the error counts as settled, m: the thesis' static
/// positioning limit (chapter 5, 100 um). A narrower band (it was 50 um)
/// called a cart "not settled" that rests within the static limit it is
/// judged by; hunting beyond the limit still counts as unsettled.
pub const SETTLING_BAND_M: f64 = crate::verdict::MAX_STATIC_ERROR_M;
/// Window at the end of the record over which the static error is averaged, s.
pub const STATIC_WINDOW_S: f64 = 0.1;
/// How long the error of a validation move must stay within
/// [`SETTLING_BAND_M`] after the trajectory (its final approach included)
/// before the record ends, s: the move's settling time
/// ([`MoveSpec::settle_s`]) is then the longest the record runs, not how
/// long it always runs. Four times [`STATIC_WINDOW_S`], over which the
/// static error is averaged, and more than half a period of a position loop
/// down to 1.3 Hz (the slowest of the robustness study's delivered loops,
/// plant #248): a loop still swinging back leaves the band within it. On
/// egc70 the cart is within the band when the final approach ends, and the
/// record ends 0.6 s earlier than with the whole second.
pub const SETTLED_HOLD_S: f64 = 0.4;

/// The return to the validation start stops this far inside the window
/// before it creeps to the start, m.
pub const APPROACH_DISTANCE_M: f64 = 0.015;
/// Speed of the creep to the validation start, m/s.
pub const CREEP_SPEED_M_S: f64 = 0.2;

/// What the final approach creeps beyond twice the cart's friction band,
/// m: the swing a soft position loop leaves the cart at the end of a fast
/// move (up to 0.3 mm on the robustness study's soft, sticky axes), with
/// room, so that the creep starts with the cart behind the target.
pub const FINAL_APPROACH_MARGIN_M: f64 = 1e-3;
/// Speed of the final approach, m/s: slow enough that the cart, dragged
/// by the belt, stops without a swing of its own (`v / w_z`, 20 um at
/// 15 Hz), fast enough that the creep of about 1.3 mm takes 0.7 s. With
/// the margin above the creep lasts long enough for the cascade's
/// integrator to settle the torque.
pub const FINAL_APPROACH_SPEED_M_S: f64 = 2e-3;

/// The final approach of a move to `target_m` (cart coordinates of the
/// runner, origin `origin_m`) for the belt model `belt`: where the setpoint
/// leads the cart's Coulomb friction `F_c` (a [`BeltStretch::Profile`]),
/// the last `2 K(target) F_c +` [`FINAL_APPROACH_MARGIN_M`] at
/// [`FINAL_APPROACH_SPEED_M_S`]; `None` otherwise. The cart rests
/// anywhere in its friction band `+-K F_c` (up to 0.18 mm on the study's
/// soft, sticky axes) depending on how the fast move's end left it; dragged
/// slowly from behind with the lead held, it stops at the target (static
/// error median 19 -> 4 um, p99 71 -> 33 um on the 1000-plant study, seed 12).
///
/// [`BeltStretch::Profile`]: beltune_rt::control::BeltStretch::Profile
pub fn final_approach(
    belt: &beltune_rt::control::BeltStretch<f64>,
    target_m: f64,
    origin_m: f64,
) -> Option<ApproachConfig> {
    let beltune_rt::control::BeltStretch::Profile(p) = belt else {
        return None;
    };
    final_approach_for_band(p.cart_coulomb_n * p.compliance_at(target_m - origin_m))
}

/// The final approach for a cart whose Coulomb friction stretches the belt
/// by `band_m` (`F_c / c` at the target, m): `2 band +`
/// [`FINAL_APPROACH_MARGIN_M`] at [`FINAL_APPROACH_SPEED_M_S`]; `None` for
/// no (or a non-finite) band.
pub fn final_approach_for_band(band_m: f64) -> Option<ApproachConfig> {
    (band_m.is_finite() && band_m > 0.0).then_some(ApproachConfig {
        distance_m: FINAL_APPROACH_MARGIN_M + 2.0 * band_m,
        speed_m_s: FINAL_APPROACH_SPEED_M_S,
    })
}

/// The validation move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveSpec {
    /// Start position, m.
    pub start_m: f64,
    /// Target position, m.
    pub target_m: f64,
    /// Trajectory limits (Table A.8 by default).
    pub limits: Limits,
    /// Time recorded after the trajectory ends, s.
    pub settle_s: f64,
    /// End the move with the slow final approach of
    /// [`final_approach`] where the setpoint leads the cart's Coulomb
    /// friction (the trajectory is then the move and its creep).
    pub final_approach: bool,
}

impl MoveSpec {
    /// The final approach this move ends in for the belt model `belt`
    /// (origin `origin_m`): [`final_approach`] at the target, `None` where
    /// [`Self::final_approach`] is off.
    pub fn approach(
        &self,
        belt: &beltune_rt::control::BeltStretch<f64>,
        origin_m: f64,
    ) -> Option<ApproachConfig> {
        final_approach(belt, self.target_m, origin_m).filter(|_| self.final_approach)
    }
}

impl Default for MoveSpec {
    /// The thesis move 0 -> 0.5 m with Table A.8: j 40 m/s^3, a 45 m/s^2,
    /// v 5 m/s, positions -0.01 .. 0.57 m; 1.0 s recorded after the move.
    fn default() -> Self {
        MoveSpec {
            start_m: 0.0,
            target_m: 0.5,
            limits: table_a8_limits(),
            settle_s: 1.0,
            final_approach: true,
        }
    }
}

/// Table A.8 (`T_A`): the trajectory limits of all thesis experiments.
pub fn table_a8_limits() -> Limits {
    Limits {
        v_max: 5.0,
        v_min: -5.0,
        a_max: 45.0,
        a_min: -45.0,
        j_max: 40.0,
        j_min: -40.0,
        position_min: -0.01,
        position_max: 0.57,
    }
}

/// One validation move that ran on the axis: its feedforward variant and
/// what it recorded.
#[derive(Clone, Debug)]
pub struct VariantMove {
    /// The feedforward variant.
    pub variant: FeedforwardVariant,
    /// The record and its summary.
    pub result: MoveResult,
}

/// A recorded validation move and its summary.
#[derive(Clone, Debug, Default)]
pub struct MoveResult {
    /// The record.
    pub record: TrackRecord,
    /// Cart tracking error `xi_d - xi` per sample (empty without a cart measurement), m.
    pub cart_error_m: Vec<f64>,
    /// Motor-side error `xi_d - i_t phi_m` per sample, m.
    pub motor_error_m: Vec<f64>,
    /// The numbers.
    pub summary: MoveSummary,
}

/// Summarize a recorded move: maximum errors, static error, settling time.
pub fn summarize(record: TrackRecord) -> Result<MoveResult> {
    let n = record.samples.len();
    if n == 0 {
        return Err(Error::TooShort {
            what: "validation move".into(),
            needed: 1,
            got: 0,
        });
    }
    let motor_error_m: Vec<f64> = record
        .desired_m
        .iter()
        .zip(&record.samples)
        .map(|(d, s)| d - s.position_m)
        .collect();
    let cart_error_m: Vec<f64> = if record.samples.iter().all(|s| s.cart_position_m.is_some()) {
        record
            .desired_m
            .iter()
            .zip(&record.samples)
            .map(|(d, s)| d - s.cart_position_m.unwrap_or(f64::NAN))
            .collect()
    } else {
        Vec::new()
    };
    let judged = if cart_error_m.is_empty() {
        &motor_error_m
    } else {
        &cart_error_m
    };
    let max_abs = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let ts = if n > 1 {
        record.time_s[1] - record.time_s[0]
    } else {
        1.0
    };
    let window = ((STATIC_WINDOW_S / ts).round() as usize).clamp(1, n);
    let static_error_m = judged[n - window..].iter().map(|e| e.abs()).sum::<f64>() / window as f64;
    let end = record.trajectory_duration_s;
    // Last sample outside the band; settled from the next one on.
    let last_out = judged.iter().rposition(|e| e.abs() > SETTLING_BAND_M);
    let settling_time_s = match last_out {
        None => Some(0.0),
        Some(i) if i + 1 >= n => None,
        Some(i) => Some((record.time_s[i + 1] - end).max(0.0)),
    };
    let summary = MoveSummary {
        max_tracking_error_m: max_abs(judged),
        static_error_m,
        settling_time_s,
        max_motor_error_m: max_abs(&motor_error_m),
        max_torque_nm: record
            .samples
            .iter()
            .fold(0.0_f64, |m, s| m.max(s.torque_command_nm.abs())),
    };
    Ok(MoveResult {
        record,
        cart_error_m,
        motor_error_m,
        summary,
    })
}

/// Bring the axis to `spec.start_m` with `positioning` (at moderate limits),
/// then run the move with `controller` (ending in its [`final_approach`]
/// unless the spec turns it off) and summarize it.
pub fn run_move(
    runner: &mut Runner,
    positioning: &CascadeConfig<f64>,
    positioning_limits: &Limits,
    controller: &CascadeConfig<f64>,
    opts: TrackOptions,
    spec: &MoveSpec,
) -> Result<MoveResult> {
    if (runner.position_m() - spec.start_m).abs() > 1e-4 {
        // The start is 10 mm from the window's edge and the return
        // runs without feedforward; approach it from inside the window and
        // creep the last part, so that the feedback's overshoot cannot reach
        // the edge.
        let inside = if spec.target_m >= spec.start_m {
            1.0
        } else {
            -1.0
        };
        let approach = spec.start_m + inside * APPROACH_DISTANCE_M;
        if (runner.position_m() - approach).abs() > 1e-4 {
            move_to(runner, positioning, approach, positioning_limits, 0.0)?;
        }
        let creep = Limits {
            v_max: CREEP_SPEED_M_S,
            v_min: -CREEP_SPEED_M_S,
            a_max: positioning_limits.a_max.min(2.0),
            a_min: -positioning_limits.a_max.min(2.0),
            j_max: positioning_limits.j_max.min(40.0),
            j_min: -positioning_limits.j_max.min(40.0),
            ..*positioning_limits
        };
        move_to(runner, positioning, spec.start_m, &creep, 0.02)?;
    }
    // The move starts where the cart rests, not where the motor is: under a
    // static force the belt is stretched, and a trajectory from the motor's
    // position made the setpoint jump by the static stretch at its first
    // sample (0.35 mm on a soft 46 deg axis, the move's largest error).
    let start = cart_at_rest_m(runner.position_m(), runner.origin_m(), &opts.belt_stretch);
    let path = match spec.approach(&opts.belt_stretch, runner.origin_m()) {
        Some(a) => Approach::plan(&State::at_rest(start), spec.target_m, &spec.limits, &a)?,
        None => Approach::direct(Trajectory::plan(
            &State::at_rest(start),
            &State::at_rest(spec.target_m),
            &spec.limits,
        )?),
    };
    let record = track(runner, controller, &path, spec.settle_s, opts)?;
    summarize(record)
}

/// Where the cart rests when the motor holds it at `motor_position_m`
/// (`i_t phi`, m, positions from `origin_m` in the belt model's
/// coordinates): `xi = i_t phi - K(xi) F_s` for the static force of a
/// [`BeltStretch::Profile`](beltune_rt::control::BeltStretch::Profile)
/// (fixed-point iteration; the stretch is a millimetre, `K` changes by a
/// few per cent over it), the motor's position otherwise. Friction may hold
/// the cart anywhere within `K F_c` of it.
pub fn cart_at_rest_m(
    motor_position_m: f64,
    origin_m: f64,
    belt: &beltune_rt::control::BeltStretch<f64>,
) -> f64 {
    match belt {
        beltune_rt::control::BeltStretch::Profile(p) => {
            let mut xi = motor_position_m;
            for _ in 0..4 {
                let k = p.compliance_at(xi - origin_m);
                let next = motor_position_m - k * p.static_force_n;
                if !next.is_finite() {
                    return motor_position_m;
                }
                xi = next;
            }
            xi
        }
        _ => motor_position_m,
    }
}

/// Breakaway threshold of the Coulomb hold at the cart, m (beltune-rt
/// cascade refinement (c)): a fifth of the thesis' static limit, so that the
/// integrator alone finishes the positioning inside it, and at least two
/// counts of the coarsest motor encoder of the robustness study (4x egc70's,
/// 10 um at the cart). Without it an axis that rested after an
/// overshoot or stuck short of its target waited for the integrator to build
/// the breakaway torque, seconds on slow loops (47 of 109 static-error
/// failures of the 1000-plant study).
pub const COULOMB_BREAKAWAY_CART_M: f64 = 20e-6;

/// The breakaway threshold in motor angle for transmission `i_t` (m/rad),
/// rad: [`COULOMB_BREAKAWAY_CART_M`] beyond the stretch of the cart's
/// Coulomb friction `friction.cart_coulomb_n` on the belt of stiffness
/// `c_n_per_m` (N/m) where the move ends. The setpoint leads the motor by
/// that stretch while the cart moves and retreats from it as the cart
/// stops (`beltune_rt::control::BeltProfile`); the motor then rests up to
/// that far beyond its setpoint with the cart at its target, held by its
/// friction. A push inside that band, with the whole Coulomb
/// torque on a motor whose cart stuck, made the motor hunt against the belt
/// and dragged carts that had stopped 20 um from the target 130 um off
/// (8 static-error failures of the 1000-plant study; none beyond it).
pub fn coulomb_breakaway_rad(
    i_t_m_per_rad: f64,
    friction: &crate::record::model::FrictionResult,
    c_n_per_m: f64,
) -> f64 {
    let lead = friction.cart_coulomb_n.max(0.0) / c_n_per_m;
    let lead = if lead.is_finite() { lead } else { 0.0 };
    (COULOMB_BREAKAWAY_CART_M + lead) / i_t_m_per_rad
}

/// The three feedforward variants of the validation (chapter 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeedforwardVariant {
    /// Feedback only.
    None,
    /// Inertia and a viscous-only friction fit.
    Linear,
    /// Inertia, viscous and Coulomb friction (4.16).
    Nonlinear,
}

impl FeedforwardVariant {
    /// The variants in the order the validation runs them.
    pub const ALL: [FeedforwardVariant; 3] = [
        FeedforwardVariant::None,
        FeedforwardVariant::Linear,
        FeedforwardVariant::Nonlinear,
    ];

    /// Label in reports ("no feedforward", ...).
    pub fn label(self) -> &'static str {
        match self {
            FeedforwardVariant::None => "no feedforward",
            FeedforwardVariant::Linear => "linear feedforward",
            FeedforwardVariant::Nonlinear => "nonlinear feedforward",
        }
    }
}

/// The controller of a validation move: `feedback` (the designed cascade with
/// its torque offset, no feedforward) with the variant's feedforward for the
/// rigid inertia `m_e_kg_m2` and `friction`, the desired velocity filtered by
/// `G_R` and the feedforward previewed by the current-loop dead time; the
/// nonlinear variant with the Coulomb breakaway ([`coulomb_breakaway_rad`] for
/// transmission `i_t_m_per_rad` and the belt stiffness `c_n_per_m` where the
/// move ends). Stage 8 of the commissioning and the tuning page's simulated
/// move both use it.
pub fn validation_controller(
    feedback: &CascadeConfig<f64>,
    m_e_kg_m2: f64,
    i_t_m_per_rad: f64,
    friction: &crate::record::model::FrictionResult,
    c_n_per_m: f64,
    variant: FeedforwardVariant,
) -> CascadeConfig<f64> {
    use beltune_rt::control::Feedforward;
    let mut c = *feedback;
    c.feedforward = match variant {
        FeedforwardVariant::None => Feedforward::none(),
        FeedforwardVariant::Linear => {
            Feedforward::linear(m_e_kg_m2, friction.linear_viscous_nm_s_per_rad)
        }
        FeedforwardVariant::Nonlinear => {
            let mut f = Feedforward::nonlinear(
                m_e_kg_m2,
                friction.viscous_nm_s_per_rad,
                friction.coulomb_nm,
            );
            f.params.coulomb_breakaway_rad =
                coulomb_breakaway_rad(i_t_m_per_rad, friction, c_n_per_m);
            f
        }
    };
    c.filter_desired_velocity = true;
    c.feedforward_preview = true;
    c
}

/// The tracking options of a validation move for the design model `p`:
/// feedforward preview by `preview_samples` (the current-loop dead time),
/// belt-stretch compensation `K(xi) (m_c a + F)` with the belt's compliance
/// along the stroke `belt` (stages 5b/5c) and the force `F = tau_hold / i_t`
/// the belt carries under the holding torque `holding_nm`, positions from
/// `origin_m` (the runner's). The stiffness identified at the
/// worst-case position is up to 30 % lower than at the target, and the cart
/// rested that share of the static stretch, up to hundreds of um, short of
/// it; the stiffness along a 0.5 m move changes by a factor two on a soft
/// belt, and one stiffness left the cart up to 0.6 mm off during the
/// acceleration and stepped the static stretch of a tilted axis at the start.
pub fn validation_track_options(
    p: &crate::model::TwoMassParams,
    preview_samples: usize,
    holding_nm: f64,
    belt: &crate::commission::stiffness::TargetStiffness,
    friction: &crate::record::model::FrictionResult,
    origin_m: f64,
) -> TrackOptions {
    TrackOptions {
        preview_samples,
        belt_stretch: beltune_rt::control::BeltStretch::Profile(belt.belt_profile(
            p.m_c,
            holding_nm / p.i_t,
            origin_m,
            friction,
        )),
        following_error: super::motion::FollowingError::Limited,
        end_when_settled: Some(super::motion::SettledEnd {
            band_m: SETTLING_BAND_M,
            hold_s: SETTLED_HOLD_S,
        }),
    }
}

/// Largest deceleration of the supervisor's jerk-limited stop in a simulated
/// validation move, m/s^2 (less when the plant's torque limit and inertia
/// allow less, [`super::safety::StopCapability::from_axis`]).
pub const SIM_STOP_DECELERATION_M_S2: f64 = 20.0;

/// The validation move of design `des` on a fresh simulation of `plant`
/// (noise `seed`), at rest at `spec.start_m`, with the controller and options
/// of stage 8 ([`validation_controller`], [`validation_track_options`]; the
/// simulated plants are horizontal: no holding torque), the belt's
/// compliance along the stroke `belt` (stages 5b/5c; `None`: the model's
/// stiffness everywhere). A following error beyond `following_error_max_m`
/// stops the move (typed error).
#[allow(clippy::too_many_arguments)]
pub fn simulate_validation_move(
    plant: &crate::model::rigs::Plant,
    des: &crate::design::ControllerDesign,
    friction: &crate::record::model::FrictionResult,
    belt: Option<&crate::commission::stiffness::TargetStiffness>,
    variant: FeedforwardVariant,
    spec: &MoveSpec,
    seed: u64,
    following_error_max_m: f64,
) -> Result<MoveResult> {
    use super::{NoProgress, SafetyLimits, SafetySupervisor};
    let info = plant.info();
    let config = crate::sim::SimConfig {
        seed,
        initial_cart_position_m: Some(spec.start_m),
        ..crate::sim::SimConfig::default()
    };
    let mut axis = crate::sim::SimAxis::new(plant, config)?;
    let torque_max = info.torque_max_nm;
    let feedback = super::cascade_from_design(des, torque_max, 0.0)?;
    // The stop is planned and supervised with the deceleration this plant
    // really has (its torque limit on its own rigid inertia, as stage 2 does
    // on the axis), not with the design model's: a payload the design did not
    // assume decelerates slower, and the look-ahead must know it.
    let truth = plant.linearize(spec.start_m)?;
    let capability = super::safety::StopCapability::from_axis(
        torque_max,
        truth.rigid_inertia(),
        truth.i_t,
        0.0,
        plant.friction_totals().coulomb_nm,
    )?;
    let a_stop = capability
        .worst_deceleration_m_s2()
        .min(SIM_STOP_DECELERATION_M_S2);
    let supervisor = SafetySupervisor::with_capability(
        SafetyLimits {
            travel_min_m: spec.limits.position_min,
            travel_max_m: spec.limits.position_max,
            torque_max_nm: torque_max,
            velocity_max_m_s: spec.limits.v_max,
            following_error_max_m,
        },
        capability,
    )?;
    let stop_limits = Limits {
        a_max: a_stop,
        a_min: -a_stop,
        j_max: 20.0 * a_stop,
        j_min: -20.0 * a_stop,
        ..spec.limits
    };
    let mut progress = NoProgress;
    let mut runner = Runner::new(
        &mut axis,
        &mut progress,
        supervisor,
        des.input.model.i_t,
        spec.start_m,
        feedback,
        stop_limits,
    )?;
    let model = des.input.model;
    let belt = belt.copied().unwrap_or_else(|| {
        crate::commission::stiffness::TargetStiffness::constant(
            spec.target_m,
            model.c,
            model.f_z_hz(),
            false,
        )
    });
    let controller = validation_controller(
        &feedback,
        model.rigid_inertia(),
        model.i_t,
        friction,
        belt.stiffness_at(spec.target_m),
        variant,
    );
    let preview = (des.input.dead_time_s / des.input.ts_s).round() as usize;
    let opts = validation_track_options(&model, preview, 0.0, &belt, friction, spec.start_m);
    run_move(
        &mut runner,
        &feedback,
        &spec.limits,
        &controller,
        opts,
        spec,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use beltune_rt::control::{BeltProfile, BeltStretch, CartSample, SetpointConversion};

    /// The validation move starts where the cart rests. The
    /// setpoint conversion at rest at that position must ask for exactly
    /// the motor position that holds it (no jump at the first sample), on a
    /// soft belt whose compliance changes along the stroke, under the static
    /// force of a 46 deg slope (-65 N, 0.3-0.6 mm of stretch).
    #[test]
    fn the_move_starts_where_the_cart_rests() {
        let i_t = 0.0124;
        let profile = BeltProfile {
            m_c_kg: 9.2,
            reference_m: 0.45,
            compliance_m_per_n: 9.5e-6,
            compliance_slope_per_n: 7.5e-6,
            compliance_curvature_per_n_m: -5.8e-6,
            static_force_n: -64.8,
            ..BeltProfile::default()
        };
        let belt = BeltStretch::Profile(profile);
        let conv = SetpointConversion::new(i_t, belt).unwrap();
        let origin = 0.05;
        for motor_m in [0.052, 0.3, 0.55] {
            let xi = cart_at_rest_m(motor_m, origin, &belt);
            let sp = conv.motor_sample(&CartSample {
                position_m: xi - origin,
                ..CartSample::default()
            });
            // the motor position (from the origin) the conversion asks for
            let asked = sp.angle_rad * i_t + origin;
            assert!((asked - motor_m).abs() < 1e-12, "{motor_m}: {asked}");
            // the cart rests ahead of the motor by the stretch F_s K(xi)
            let stretch = -profile.static_force_n * profile.compliance_at(xi - origin);
            assert!(((xi - motor_m) - stretch).abs() < 1e-12);
            assert!(stretch > 2e-4 && stretch < 1e-3, "{stretch}");
        }
        assert_eq!(cart_at_rest_m(0.3, origin, &BeltStretch::Off), 0.3);
    }
}
