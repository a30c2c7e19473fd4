//! The trajectory generator against the reference implementation `rsruckig`
//! (dev-dependency only) on seeded random cases, with Ruckig's closed forms
//! (the default for symmetric jerk) and with the general solver used for
//! asymmetric jerk, plus the thesis case of Table A.8 against a closed-form
//! duration.

mod support;

use beltune_rt::trajectory::{Limits, Planner, State, Trajectory};
use beltune_rt::Error;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use support::cases::{
    check_samples, random_case, reference_duration, Jerk, FAMILIES, FINAL_STATE_TOL,
};

/// Durations must equal the reference's to this relative tolerance.
const DURATION_REL_TOL: f64 = 1e-9;
/// Absolute floor for (near-)zero durations, s.
const DURATION_ABS_FLOOR: f64 = 1e-12;
/// Cases per family; 6 families -> 12,000 cases.
const CASES_PER_FAMILY: usize = 2_000;

/// Plan the 12,000 seeded cases with `plan` ([`Trajectory::plan`], a reused
/// [`Planner`] or the general solver) and compare with rsruckig.
fn compare_with_reference(
    mut plan: impl FnMut(&State, &State, &Limits) -> Result<Trajectory, Error>,
) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0xBE17_70E5);
    let mut compared = 0;
    let mut reference_failed = 0;
    let mut ours_succeeded_where_reference_failed = 0;
    let mut braked = 0;
    let mut worst_rel = 0.0_f64;
    // Coverage: cases whose profile holds a limit in P2 (acceleration),
    // P4 (velocity), P6 (deceleration).
    let mut reached = [0usize; 3];
    for family in 0..FAMILIES {
        for _ in 0..CASES_PER_FAMILY {
            let c = random_case(&mut rng, family, Jerk::Symmetric);
            let ours = plan(&c.start, &c.target, &c.limits);
            let Some(t_ref) = reference_duration(&c) else {
                // Allowed either way; counted (so far these are all starts
                // with |a0| far beyond the limits and a small j_max).
                reference_failed += 1;
                if ours.is_ok() {
                    ours_succeeded_where_reference_failed += 1;
                }
                continue;
            };
            let traj = ours.unwrap_or_else(|e| {
                panic!("{c:?}: reference succeeded ({t_ref} s), we failed: {e}")
            });
            let err = (traj.duration_s() - t_ref).abs();
            assert!(
                err <= DURATION_REL_TOL * t_ref + DURATION_ABS_FLOOR,
                "{c:?}: duration {} vs reference {t_ref}",
                traj.duration_s()
            );
            if t_ref > 0.0 {
                worst_rel = worst_rel.max(err / t_ref);
            }
            if traj.brake_duration_s() > 0.0 {
                braked += 1;
            }
            let ph = traj.phases();
            for (n, k) in reached.iter_mut().zip([1, 3, 5]) {
                if ph.durations_s[k] > 1e-9 {
                    *n += 1;
                }
            }
            check_samples(&c, &traj);
            compared += 1;
        }
    }
    println!(
        "compared {compared}, reference failed {reference_failed} \
         (we succeeded in {ours_succeeded_where_reference_failed} of them), braked {braked}, \
         reached a/v/a limits in P2/P4/P6 {reached:?}, worst relative duration error {worst_rel:e}"
    );
    assert!(
        reached.iter().all(|&n| n >= 500),
        "limit coverage {reached:?}"
    );
    assert!(compared >= 10_000, "only {compared} cases compared");
    assert!(
        braked >= 1_000,
        "only {braked} cases exercised the brake pre-phase"
    );
}

#[test]
fn durations_equal_rsruckig_on_12000_random_cases() {
    compare_with_reference(Trajectory::plan);
}

/// One [`Planner`] reused for all 12,000 cases: its scratch profiles are not
/// re-initialized between plans, so a stale value read anywhere would show as
/// a duration differing from rsruckig's or a phase differing from a fresh
/// planner's.
#[test]
fn reused_planner_equals_rsruckig_and_fresh_plans() {
    let mut planner = Planner::default();
    compare_with_reference(|start, target, limits| {
        let reused = planner.plan(start, target, limits);
        let fresh = Trajectory::plan(start, target, limits);
        match (&reused, &fresh) {
            (Ok(r), Ok(f)) => {
                assert_eq!(r.duration_s().to_bits(), f.duration_s().to_bits());
                assert_eq!(r.phases(), f.phases());
            }
            (Err(r), Err(f)) => assert_eq!(r, f),
            _ => panic!("reused {reused:?} vs fresh {fresh:?}"),
        }
        reused
    });
}

/// The general solver for asymmetric jerk (`asymmetric.rs`), run on the same
/// symmetric cases: its polynomial families must reproduce Ruckig's closed
/// forms, brake pre-phase included.
#[test]
fn general_solver_equals_rsruckig_on_12000_random_cases() {
    compare_with_reference(Trajectory::plan_with_general_solver);
}

#[test]
fn position_limits_are_enforced() {
    // Same moves with position limits: success with the same duration when
    // the unconstrained move stays inside, PositionLimitsViolated otherwise.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let (mut inside, mut violated) = (0, 0);
    for i in 0..2_000 {
        let mut c = random_case(&mut rng, 2 + i % 4, Jerk::Symmetric);
        let Ok(free) = Trajectory::plan(&c.start, &c.target, &c.limits) else {
            continue;
        };
        let range = free.position_range();
        let lo = c.start.position.min(c.target.position);
        let hi = c.start.position.max(c.target.position);
        c.limits.position_min = lo - rng.random_range(0.0..(lo - range.lowest).max(1e-6) * 2.0);
        c.limits.position_max = hi + rng.random_range(0.0..(range.highest - hi).max(1e-6) * 2.0);
        let fits = range.lowest >= c.limits.position_min - 1e-8
            && range.highest <= c.limits.position_max + 1e-8;
        match Trajectory::plan(&c.start, &c.target, &c.limits) {
            Ok(t) => {
                assert!(fits, "{c:?}");
                assert_eq!(t.duration_s(), free.duration_s());
                inside += 1;
            }
            Err(Error::PositionLimitsViolated { lowest, highest }) => {
                assert!(!fits, "{c:?}");
                assert!(lowest < c.limits.position_min || highest > c.limits.position_max);
                violated += 1;
            }
            Err(e) => panic!("{c:?}: unexpected {e}"),
        }
    }
    assert!(
        inside > 200 && violated > 200,
        "inside {inside}, violated {violated}"
    );
}

#[test]
fn thesis_case_table_a8_matches_closed_form() {
    // Thesis 6.3 / Table A.8: 0 -> 0.5 m, j_max 40 m/s^3, a_max 45 m/s^2,
    // v_max 5 m/s, position limits -0.01 .. 0.57 m.
    let limits = Limits {
        position_min: -0.01,
        position_max: 0.57,
        ..Limits::symmetric(5.0, 45.0, 40.0)
    };
    let (d, j): (f64, f64) = (0.5, 40.0);
    // Neither limit is reached: the four jerk phases P1, P3, P5, P7 have equal
    // length T with d = 2 j T^3, so the duration is 4 (d / (2 j))^(1/3);
    // peak acceleration j T and velocity j T^2 stay below 45 and 5.
    let t_phase = (d / (2.0 * j)).cbrt();
    assert!(j * t_phase < 45.0 && j * t_phase * t_phase < 5.0);
    let expected = 4.0 * t_phase; // 0.7368 s
    let traj = Trajectory::plan(&State::at_rest(0.0), &State::at_rest(d), &limits).unwrap();
    assert!((traj.duration_s() - expected).abs() <= DURATION_REL_TOL * expected);
    let ph = traj.phases();
    // P3 and P5 share the jerk -j_max: the reference merges them into P3.
    let merged = [t_phase, 0.0, 2.0 * t_phase, 0.0, 0.0, 0.0, t_phase];
    for (got, want) in ph.durations_s.iter().zip(merged) {
        assert!((got - want).abs() < 1e-9, "{:?}", ph.durations_s);
    }
    let end = traj.sample(traj.duration_s());
    assert!((end.position - d).abs() < FINAL_STATE_TOL);
    let r = traj.position_range();
    assert!(r.lowest >= -1e-12 && r.highest <= d + FINAL_STATE_TOL);
}

#[test]
fn extreme_finite_inputs_never_panic() {
    // Magnitudes from 1e-200 to 1e200 in every field: the planner must return
    // a typed error or a finite plan whose end is the target, never panic.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(99);
    let any = |rng: &mut Xoshiro256PlusPlus| {
        let m = 10f64.powf(rng.random_range(-200.0..200.0));
        if rng.random_bool(0.5) {
            m
        } else {
            -m
        }
    };
    let mut planned = 0;
    let mut planned_asymmetric = 0;
    for _ in 0..5_000 {
        let start = State {
            position: any(&mut rng),
            velocity: any(&mut rng),
            acceleration: any(&mut rng),
        };
        let mut limits = Limits {
            v_max: any(&mut rng).abs(),
            v_min: -any(&mut rng).abs(),
            a_max: any(&mut rng).abs(),
            a_min: -any(&mut rng).abs(),
            j_max: any(&mut rng).abs(),
            j_min: f64::NAN,
            position_min: f64::NEG_INFINITY,
            position_max: f64::INFINITY,
        };
        // Half symmetric jerk (Ruckig's closed forms), half asymmetric (the
        // general solver).
        limits.j_min = if rng.random_bool(0.5) {
            -limits.j_max
        } else {
            -any(&mut rng).abs()
        };
        // Half the targets admissible (inside the velocity limits, at a = 0).
        let target = if rng.random_bool(0.5) {
            State {
                position: any(&mut rng),
                velocity: limits.v_max * rng.random_range(0.0..1.0),
                acceleration: 0.0,
            }
        } else {
            State {
                position: any(&mut rng),
                velocity: any(&mut rng),
                acceleration: any(&mut rng),
            }
        };
        if let Ok(traj) = Trajectory::plan(&start, &target, &limits) {
            assert!(traj.duration_s().is_finite() && traj.duration_s() >= 0.0);
            let s = traj.sample(traj.duration_s() * 0.5);
            assert!(s.position.is_finite() && s.velocity.is_finite());
            planned += 1;
            if limits.j_min != -limits.j_max {
                planned_asymmetric += 1;
            }
        }
    }
    println!(
        "extreme inputs: {planned} of 5000 planned, {planned_asymmetric} with asymmetric jerk"
    );
    assert!(
        planned > 20,
        "only {planned} extreme requests were plannable"
    );
}
