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

mod support;

use beltune_rt::trajectory::{Limits, State, Trajectory};
use support::cases::{check_samples, random_case, rng, Case, Jerk, FAMILIES};

/// Durations of mirrored / time-reversed moves agree to this (relative):
/// both are computed from roots found to machine precision.
const DURATION_REL_TOL: f64 = 1e-9;
/// Absolute floor for (near-)zero durations, s.
const DURATION_ABS_FLOOR: f64 = 1e-12;
/// Cases per family.
const CASES_PER_FAMILY: usize = 5_000;

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
    let mut rng = rng(0xA5_1E_E7);
    let mut reached = [0usize; 3];
    let mut slow_jerk_phases = 0;
    for family in 0..FAMILIES - 2 {
        for _ in 0..CASES_PER_FAMILY {
            let c = random_case(&mut rng, family, Jerk::Asymmetric);
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
    let mut rng = rng(0xB8_A4E);
    let mut braked = 0;
    for i in 0..CASES_PER_FAMILY {
        let c = random_case(&mut rng, 4 + i % 2, Jerk::Asymmetric);
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
    let mut rng = rng(5);
    for i in 0..2_000 {
        let mut c = random_case(&mut rng, i % 4, Jerk::Symmetric);
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
