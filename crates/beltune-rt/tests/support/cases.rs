//! Seeded random trajectory requests and the sampled-move check shared by
//! `trajectory_vs_ruckig.rs`, `trajectory_asymmetric.rs` and
//! `discrete_lp_oracle.rs`.

use beltune_rt::trajectory::{Limits, State, Trajectory};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rsruckig::prelude::*;

/// The final state must equal the target to this.
pub const FINAL_STATE_TOL: f64 = 1e-8;
/// Slack on the limits when sampling (the brake uses 2.2e-14 s margins,
/// Ruckig's profile check allows 1e-12 on v and a).
pub const LIMIT_TOL: f64 = 1e-9;

/// One planning request.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    pub start: State,
    pub target: State,
    pub limits: Limits,
}

/// The jerk limits of the random cases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Jerk {
    /// `j_min = -j_max` (what rsruckig can plan).
    Symmetric,
    /// `j_min = -j_max * f` with `f` log-uniform in `[0.1, 10]`.
    Asymmetric,
}

/// Families of [`random_case`]: 0 short rest-to-rest, 1 rest-to-rest over all
/// scales, 2 short moving, 3 moving over all scales, 4-5 a start outside
/// the limits; odd families have asymmetric velocity and acceleration limits.
pub const FAMILIES: usize = 6;

pub fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

pub fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (rng.random_range(lo.ln()..hi.ln())).exp()
}

pub fn random_limits(rng: &mut Xoshiro256PlusPlus, asymmetric: bool, jerk: Jerk) -> Limits {
    let v_max = log_uniform(rng, 0.05, 10.0);
    let a_max = log_uniform(rng, 0.2, 100.0);
    let j_max = log_uniform(rng, 1.0, 2000.0);
    let (v_min, a_min) = if asymmetric {
        (-log_uniform(rng, 0.05, 10.0), -log_uniform(rng, 0.2, 100.0))
    } else {
        (-v_max, -a_max)
    };
    let j_min = match jerk {
        Jerk::Symmetric => -j_max,
        Jerk::Asymmetric => -j_max * log_uniform(rng, 0.1, 10.0),
    };
    Limits {
        v_max,
        v_min,
        a_max,
        a_min,
        j_max,
        j_min,
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
    }
}

/// A state strictly inside the limits from which (and towards which)
/// ramping the acceleration to zero with either jerk keeps the velocity
/// inside: admissible as a start (no brake) and as a target, also with the
/// time reversed.
pub fn admissible_state(
    rng: &mut Xoshiro256PlusPlus,
    l: &Limits,
    position: f64,
    moving: bool,
) -> State {
    if !moving {
        return State::at_rest(position);
    }
    let j_small = l.j_max.min(-l.j_min);
    loop {
        let v = rng.random_range(l.v_min..l.v_max);
        let a = rng.random_range(l.a_min..l.a_max);
        let dv = a * a / (2.0 * j_small);
        if v + dv <= l.v_max && v - dv >= l.v_min {
            return State {
                position,
                velocity: v,
                acceleration: a,
            };
        }
    }
}

/// A random request of `family` (see [`FAMILIES`]).
pub fn random_case(rng: &mut Xoshiro256PlusPlus, family: usize, jerk: Jerk) -> Case {
    let asymmetric = family % 2 == 1;
    let limits = random_limits(rng, asymmetric, jerk);
    let p0 = rng.random_range(-1.0..1.0);
    let (distance, start_moving, target_moving) = match family {
        // Short moves from rest to rest (limits rarely reached).
        0 => (log_uniform(rng, 1e-6, 1e-2), false, false),
        // Rest to rest over all scales: none, a, v, a and v limits reached.
        1 => (log_uniform(rng, 1e-4, 100.0), false, false),
        // Moving start and target, short.
        2 => (log_uniform(rng, 1e-5, 0.1), true, true),
        // Moving start and target over all scales.
        3 => (log_uniform(rng, 1e-3, 100.0), true, true),
        // Start violating a limit (see below), target at rest or moving.
        _ => (log_uniform(rng, 1e-3, 50.0), true, rng.random_bool(0.5)),
    };
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let mut start = admissible_state(rng, &limits, p0, start_moving);
    let target = admissible_state(rng, &limits, p0 + sign * distance, target_moving);
    if family >= 4 {
        // Push the start outside: velocity, acceleration, or both.
        let factor = rng.random_range(1.01..2.5);
        match rng.random_range(0..3) {
            0 => {
                start.velocity = if rng.random_bool(0.5) {
                    limits.v_max * factor
                } else {
                    limits.v_min * factor
                }
            }
            1 => {
                start.acceleration = if rng.random_bool(0.5) {
                    limits.a_max * factor
                } else {
                    limits.a_min * factor
                }
            }
            _ => {
                start.velocity = limits.v_max * factor * sign;
                start.acceleration = limits.a_max * rng.random_range(0.5..2.0) * sign;
            }
        }
    }
    Case {
        start,
        target,
        limits,
    }
}

/// rsruckig's duration (it needs `j_min = -j_max`), or `None` when it
/// rejects the request.
pub fn reference_duration(c: &Case) -> Option<f64> {
    assert_eq!(
        c.limits.j_min, -c.limits.j_max,
        "rsruckig needs symmetric jerk limits"
    );
    let mut otg = Ruckig::<1, ThrowErrorHandler>::new(None, 1e-4);
    let mut input = InputParameter::new(None);
    input.current_position[0] = c.start.position;
    input.current_velocity[0] = c.start.velocity;
    input.current_acceleration[0] = c.start.acceleration;
    input.target_position[0] = c.target.position;
    input.target_velocity[0] = c.target.velocity;
    input.target_acceleration[0] = c.target.acceleration;
    input.max_velocity[0] = c.limits.v_max;
    input.max_acceleration[0] = c.limits.a_max;
    input.max_jerk[0] = c.limits.j_max;
    input.min_velocity = Some(DataArrayOrVec::Stack([c.limits.v_min]));
    input.min_acceleration = Some(DataArrayOrVec::Stack([c.limits.a_min]));
    let mut traj = rsruckig::trajectory::Trajectory::new(None);
    match otg.calculate(&input, &mut traj) {
        Ok(RuckigResult::Working) => Some(traj.get_duration()),
        _ => None,
    }
}

/// The move ends in the target; sampled, the jerk stays in `[j_min, j_max]`,
/// the acceleration inside its limits after the brake pre-phase and the
/// velocity inside once it has come back inside; the analytic position range
/// encloses every sample.
pub fn check_samples(c: &Case, traj: &Trajectory) {
    let l = &c.limits;
    let end = traj.sample(traj.duration_s());
    // Beyond 10^6 m, 1e-14 of the largest position (f64 resolution).
    let range = traj.position_range();
    let p_tol = FINAL_STATE_TOL.max(1e-14 * range.lowest.abs().max(range.highest.abs()));
    assert!(
        (end.position - c.target.position).abs() < p_tol
            && (end.velocity - c.target.velocity).abs() < FINAL_STATE_TOL
            && (end.acceleration - c.target.acceleration).abs() < FINAL_STATE_TOL,
        "{c:?}: ends in {end:?}"
    );
    let n = 200;
    let t_brake = traj.brake_duration_s();
    let mut velocity_inside = false;
    let mut lowest = f64::INFINITY;
    let mut highest = f64::NEG_INFINITY;
    let a_tol = LIMIT_TOL * (1.0 + l.a_max.max(-l.a_min));
    for k in 0..=n {
        let t = traj.duration_s() * k as f64 / n as f64;
        let s = traj.sample(t);
        lowest = lowest.min(s.position);
        highest = highest.max(s.position);
        assert!(
            s.jerk <= l.j_max * (1.0 + 1e-12) && s.jerk >= l.j_min * (1.0 + 1e-12),
            "{c:?}: jerk {} at t = {t}",
            s.jerk
        );
        if t < t_brake {
            continue;
        }
        assert!(
            s.acceleration <= l.a_max + a_tol && s.acceleration >= l.a_min - a_tol,
            "{c:?}: a = {} at t = {t} after the brake",
            s.acceleration
        );
        let v_inside = s.velocity <= l.v_max + LIMIT_TOL && s.velocity >= l.v_min - LIMIT_TOL;
        if velocity_inside {
            assert!(
                v_inside,
                "{c:?}: v = {} left the limits at t = {t}",
                s.velocity
            );
        }
        velocity_inside |= v_inside;
    }
    assert!(velocity_inside, "{c:?}: velocity never came back inside");
    // Rounding of the position integration grows with the distance covered.
    let tol =
        1e-12 * (1.0 + lowest.abs().max(highest.abs()) + traj.duration_s() * l.v_max.max(-l.v_min));
    assert!(
        range.lowest <= lowest + tol && range.highest >= highest - tol,
        "{c:?}: range {range:?} vs sampled {lowest} .. {highest}, brake {t_brake}, {:?}",
        traj.phases()
    );
}
