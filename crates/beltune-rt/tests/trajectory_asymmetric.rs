//! Asymmetric jerk limits (`j_min != -j_max`), which the reference rsruckig
//! cannot plan. The general solver is checked on seeded random cases by
//! properties that hold for the true time-optimal move and that a wrong
//! family, a lost root or a wrong jerk in one phase would break:
//!
//! * the move ends in the target and respects every limit when sampled;
//! * mirror symmetry: reversing the position axis (and swapping every
//!   minimum with the negated maximum) gives the same duration;
//! * time reversal: the move from the target back to the start, with the
//!   velocities negated, `v` limits mirrored and the jerk limits swapped
//!   (`j_max' = -j_min`, `j_min' = -j_max`), takes the same time -- a different
//!   family answers it;
//! * bracketing by the symmetric planner (rsruckig-verified): the feasible
//!   moves include those of `+-min(j_max, -j_min)` and are included in those
//!   of `+-max(..)`, so the duration lies between the two symmetric ones;
//! * continuity: as `j_min -> -j_max` the duration tends to Ruckig's.
//!
//! Time optimality itself is checked against a discretized linear program in
//! `discrete_lp_oracle.rs`.

use beltune_rt::trajectory::{Limits, State, Trajectory};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Durations of mirrored / time-reversed moves agree to this (relative):
/// both are computed from roots found to machine precision.
const DURATION_REL_TOL: f64 = 1e-9;
/// Absolute floor for (near-)zero durations, s.
const DURATION_ABS_FLOOR: f64 = 1e-12;
/// The final state must equal the target to this (issue 3).
const FINAL_STATE_TOL: f64 = 1e-8;
/// Slack on the limits when sampling (the profile check allows 1e-12 on v
/// and a; the brake keeps 2.2e-14 s margins).
const LIMIT_TOL: f64 = 1e-9;
/// Cases per family; 5 families.
const CASES_PER_FAMILY: usize = 2_000;

#[derive(Clone, Copy, Debug)]
struct Case {
    start: State,
    target: State,
    limits: Limits,
}

fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (rng.random_range(lo.ln()..hi.ln())).exp()
}

fn random_limits(rng: &mut Xoshiro256PlusPlus) -> Limits {
    let j_max = log_uniform(rng, 1.0, 2000.0);
    Limits {
        v_max: log_uniform(rng, 0.05, 10.0),
        v_min: -log_uniform(rng, 0.05, 10.0),
        a_max: log_uniform(rng, 0.2, 100.0),
        a_min: -log_uniform(rng, 0.2, 100.0),
        j_max,
        // From a tenth to ten times j_max.
        j_min: -j_max * log_uniform(rng, 0.1, 10.0),
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
    }
}

/// A state strictly inside the limits from which (and towards which) ramping
/// the acceleration to zero with either jerk keeps the velocity inside:
/// admissible as a start without brake and as a target, also time-reversed.
fn admissible_state(
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

fn random_case(rng: &mut Xoshiro256PlusPlus, family: usize) -> Case {
    let limits = random_limits(rng);
    let p0 = rng.random_range(-1.0..1.0);
    let (distance, start_moving, target_moving) = match family {
        // Short moves from rest to rest (limits rarely reached).
        0 => (log_uniform(rng, 1e-6, 1e-2), false, false),
        // Rest to rest over all scales: none, a, v, a and v limits reached.
        1 => (log_uniform(rng, 1e-4, 100.0), false, false),
        // Moving start and target, short.
        2 => (log_uniform(rng, 1e-5, 0.1), true, true),
        // Moving start and target over all scales.
        _ => (log_uniform(rng, 1e-3, 100.0), true, true),
    };
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let start = admissible_state(rng, &limits, p0, start_moving);
    let target = admissible_state(rng, &limits, p0 + sign * distance, target_moving);
    Case {
        start,
        target,
        limits,
    }
}

/// A start that violates a limit (brake pre-phase), target inside.
fn braking_case(rng: &mut Xoshiro256PlusPlus) -> Case {
    let mut c = random_case(rng, 3);
    let l = c.limits;
    let factor = rng.random_range(1.01..2.5);
    match rng.random_range(0..3) {
        0 => {
            c.start.velocity = if rng.random_bool(0.5) {
                l.v_max
            } else {
                l.v_min
            } * factor
        }
        1 => {
            c.start.acceleration = if rng.random_bool(0.5) {
                l.a_max
            } else {
                l.a_min
            } * factor
        }
        _ => {
            let s = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            c.start.velocity = l.v_max * factor * s;
            c.start.acceleration = l.a_max * rng.random_range(0.5..2.0) * s;
        }
    }
    c
}

fn plan(c: &Case) -> Trajectory {
    Trajectory::plan(&c.start, &c.target, &c.limits)
        .unwrap_or_else(|e| panic!("{c:?}: not planned: {e}"))
}

fn assert_same_duration(a: f64, b: f64, what: &str, c: &Case) {
    assert!(
        (a - b).abs() <= DURATION_REL_TOL * a.max(b) + DURATION_ABS_FLOOR,
        "{what}: {a} vs {b} for {c:?}"
    );
}

/// Ends in the target; jerk within `[j_min, j_max]` throughout; acceleration
/// inside after the brake, velocity inside once it has come back.
fn check_samples(c: &Case, traj: &Trajectory) {
    let l = &c.limits;
    let end = traj.sample(traj.duration_s());
    assert!(
        (end.position - c.target.position).abs() < FINAL_STATE_TOL
            && (end.velocity - c.target.velocity).abs() < FINAL_STATE_TOL
            && (end.acceleration - c.target.acceleration).abs() < FINAL_STATE_TOL,
        "{c:?}: ends in {end:?}"
    );
    let n = 300;
    let t_brake = traj.brake_duration_s();
    let mut velocity_inside = false;
    let a_tol = LIMIT_TOL * (1.0 + l.a_max.max(-l.a_min));
    for k in 0..=n {
        let t = traj.duration_s() * k as f64 / n as f64;
        let s = traj.sample(t);
        assert!(
            s.jerk <= l.j_max * (1.0 + 1e-12) && s.jerk >= l.j_min * (1.0 + 1e-12),
            "{c:?}: jerk {} at {t}",
            s.jerk
        );
        if t < t_brake {
            continue;
        }
        assert!(
            s.acceleration <= l.a_max + a_tol && s.acceleration >= l.a_min - a_tol,
            "{c:?}: a = {} at {t}",
            s.acceleration
        );
        let inside = s.velocity <= l.v_max + LIMIT_TOL && s.velocity >= l.v_min - LIMIT_TOL;
        if velocity_inside {
            assert!(inside, "{c:?}: v = {} left the limits at {t}", s.velocity);
        }
        velocity_inside |= inside;
    }
    assert!(velocity_inside, "{c:?}: velocity never came back inside");
}

fn mirrored(c: &Case) -> Case {
    let m = |s: State| State {
        position: -s.position,
        velocity: -s.velocity,
        acceleration: -s.acceleration,
    };
    let l = c.limits;
    Case {
        start: m(c.start),
        target: m(c.target),
        limits: Limits {
            v_max: -l.v_min,
            v_min: -l.v_max,
            a_max: -l.a_min,
            a_min: -l.a_max,
            j_max: -l.j_min,
            j_min: -l.j_max,
            ..l
        },
    }
}

fn time_reversed(c: &Case) -> Case {
    let r = |s: State| State {
        velocity: -s.velocity,
        ..s
    };
    let l = c.limits;
    Case {
        start: r(c.target),
        target: r(c.start),
        limits: Limits {
            v_max: -l.v_min,
            v_min: -l.v_max,
            j_max: -l.j_min,
            j_min: -l.j_max,
            ..l
        },
    }
}

fn symmetric(c: &Case, j: f64) -> Case {
    Case {
        limits: Limits {
            j_max: j,
            j_min: -j,
            ..c.limits
        },
        ..*c
    }
}

#[test]
fn asymmetric_jerk_moves_are_exact_mirror_and_time_reversal_invariant_and_bracketed() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0xA5_1E_E7);
    let mut reached = [0usize; 3];
    let mut slow_jerk_phases = 0;
    for family in 0..4 {
        for _ in 0..CASES_PER_FAMILY {
            let c = random_case(&mut rng, family);
            let traj = plan(&c);
            let t = traj.duration_s();
            check_samples(&c, &traj);

            let mirror = plan(&mirrored(&c));
            assert_same_duration(t, mirror.duration_s(), "mirror", &c);
            let reverse = plan(&time_reversed(&c));
            assert_same_duration(t, reverse.duration_s(), "time reversal", &c);

            let (j_lo, j_hi) = (
                c.limits.j_max.min(-c.limits.j_min),
                c.limits.j_max.max(-c.limits.j_min),
            );
            let slow = plan(&symmetric(&c, j_lo)).duration_s();
            let fast = plan(&symmetric(&c, j_hi)).duration_s();
            let slack = DURATION_REL_TOL * slow + DURATION_ABS_FLOOR;
            assert!(
                t <= slow + slack && t >= fast - slack,
                "{c:?}: {t} outside [{fast}, {slow}]"
            );

            let ph = traj.phases();
            for (n, k) in reached.iter_mut().zip([1, 3, 5]) {
                if ph.durations_s[k] > 1e-9 {
                    *n += 1;
                }
            }
            if ph.jerks_m_s3.contains(&c.limits.j_min) {
                slow_jerk_phases += 1;
            }
        }
    }
    println!("limits held in P2/P4/P6: {reached:?}; profiles using j_min: {slow_jerk_phases}");
    assert!(
        reached.iter().all(|&n| n >= 500),
        "limit coverage {reached:?}"
    );
}

#[test]
fn braking_starts_come_back_inside_with_the_asymmetric_jerks() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0xB8_A4E);
    let mut braked = 0;
    for _ in 0..CASES_PER_FAMILY {
        let c = braking_case(&mut rng);
        let traj = plan(&c);
        check_samples(&c, &traj);
        let mirror = plan(&mirrored(&c));
        assert_same_duration(traj.duration_s(), mirror.duration_s(), "mirror", &c);
        if traj.brake_duration_s() > 0.0 {
            braked += 1;
            let ph = traj.phases();
            for j in ph.brake_jerks_m_s3 {
                assert!(
                    j == 0.0 || j == c.limits.j_max || j == c.limits.j_min,
                    "{c:?}: brake jerk {j}"
                );
            }
        }
    }
    assert!(braked > CASES_PER_FAMILY / 2, "only {braked} braked");
}

#[test]
fn duration_is_continuous_as_the_jerk_limits_become_symmetric() {
    // Relative change of the duration per relative change of j_min stays
    // O(1); 1e-7 in j_min moves the duration by well under 1e-6.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    for i in 0..2_000 {
        let mut c = random_case(&mut rng, i % 4);
        c.limits.j_min = -c.limits.j_max;
        let ruckig = plan(&c).duration_s();
        for factor in [1.0 - 1e-7, 1.0 + 1e-7] {
            c.limits.j_min = -c.limits.j_max * factor;
            let general = plan(&c).duration_s();
            assert!(
                (general - ruckig).abs() <= 1e-6 * ruckig + DURATION_ABS_FLOOR,
                "{c:?}: {general} vs Ruckig {ruckig}"
            );
        }
    }
}

#[test]
fn invalid_jerk_limits_are_errors() {
    let start = State::at_rest(0.0);
    let target = State::at_rest(0.5);
    for j_min in [0.0, 5.0, f64::NAN, f64::NEG_INFINITY] {
        let limits = Limits {
            j_min,
            ..Limits::default()
        };
        let err = Trajectory::plan(&start, &target, &limits).unwrap_err();
        assert!(err.to_string().contains("j_min"), "{err}");
    }
}
