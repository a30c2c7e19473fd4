//! Unit tests against closed-form durations of rest-to-rest moves.

use super::*;

/// Relative tolerance for closed-form durations (only rounding differs).
const DURATION_REL_TOL: f64 = 1e-9;

fn plan_rest(d: f64, limits: &Limits) -> Trajectory {
    Trajectory::plan(&State::at_rest(0.0), &State::at_rest(d), limits).expect("plannable")
}

#[test]
fn rest_to_rest_reaching_velocity_and_acceleration_limits() {
    // Rest-to-rest with both limits reached: T = d/v + v/a + a/j
    // (symmetric trapezoidal acceleration profile).
    let (v, a, j, d) = (1.0, 2.0, 10.0, 3.0);
    let traj = plan_rest(d, &Limits::symmetric(v, a, j));
    let expected = d / v + v / a + a / j;
    assert!((traj.duration_s() - expected).abs() <= DURATION_REL_TOL * expected);
    let ph = traj.phases();
    // P1, P3, P5, P7 = a/j; P2, P6 = v/a - a/j; P4 = d/v - v/a - a/j.
    let expected_phases = [
        a / j,
        v / a - a / j,
        a / j,
        d / v - v / a - a / j,
        a / j,
        v / a - a / j,
        a / j,
    ];
    for (got, want) in ph.durations_s.iter().zip(expected_phases) {
        assert!((got - want).abs() < 1e-9, "{got} vs {want}");
    }
}

#[test]
fn rest_to_rest_jerk_only_downward() {
    // Neither a nor v reached: four phases of length (d / (2 j))^(1/3).
    let (j, d) = (40.0, -0.2);
    let traj = plan_rest(d, &Limits::symmetric(5.0, 45.0, j));
    let expected = 4.0 * libm::cbrt(d.abs() / (2.0 * j));
    assert!((traj.duration_s() - expected).abs() <= DURATION_REL_TOL * expected);
    let end = traj.sample(traj.duration_s());
    assert!((end.position - d).abs() < 1e-10);
}

#[test]
fn samples_are_continuous_and_jerk_limited() {
    let limits = Limits {
        v_max: 2.0,
        v_min: -1.0,
        a_max: 8.0,
        a_min: -5.0,
        j_max: 50.0,
        j_min: -50.0,
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
    };
    let start = State {
        position: 0.3,
        velocity: 1.5,
        acceleration: -2.0,
    };
    let target = State {
        position: -0.4,
        velocity: 0.2,
        acceleration: 1.0,
    };
    let traj = Trajectory::plan(&start, &target, &limits).unwrap();
    let ts = 1e-4;
    let n = (traj.duration_s() / ts) as usize + 2;
    let mut prev = traj.sample(0.0);
    assert!((prev.position - start.position).abs() < 1e-12);
    for k in 1..=n {
        let s = traj.sample(k as f64 * ts);
        // Continuity: a step of ts with |j| <= j_max changes a by <= j_max ts.
        assert!((s.acceleration - prev.acceleration).abs() <= limits.j_max * ts * (1.0 + 1e-9));
        assert!(s.jerk.abs() <= limits.j_max);
        assert!(s.velocity <= limits.v_max + 1e-9 && s.velocity >= limits.v_min - 1e-9);
        assert!(s.acceleration <= limits.a_max + 1e-9 && s.acceleration >= limits.a_min - 1e-9);
        prev = s;
    }
    let end = traj.sample(traj.duration_s());
    assert!((end.position - target.position).abs() < 1e-8);
    assert!((end.velocity - target.velocity).abs() < 1e-8);
    assert!((end.acceleration - target.acceleration).abs() < 1e-8);
}

#[test]
fn invalid_requests_are_typed_errors() {
    let l = Limits::symmetric(1.0, 1.0, 1.0);
    let rest = State::at_rest(0.0);
    assert!(matches!(
        Trajectory::plan(&rest, &State::at_rest(f64::NAN), &l),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        Trajectory::plan(&rest, &rest, &Limits::symmetric(1.0, 0.0, 1.0)),
        Err(Error::InvalidParameter { .. })
    ));
    let bounded = Limits {
        position_min: -1.0,
        position_max: 1.0,
        ..l
    };
    assert_eq!(
        Trajectory::plan(&rest, &State::at_rest(2.0), &bounded).unwrap_err(),
        Error::TargetOutsideLimits
    );
    // Start at 0.9 m moving at 1 m/s towards +1 m: stopping overshoots the limit.
    let fast = State {
        position: 0.9,
        velocity: 1.0,
        acceleration: 0.0,
    };
    assert!(matches!(
        Trajectory::plan(&fast, &State::at_rest(0.0), &bounded),
        Err(Error::PositionLimitsViolated { .. })
    ));
    let too_fast_target = State {
        position: 0.0,
        velocity: 2.0,
        acceleration: 0.0,
    };
    assert!(matches!(
        Trajectory::plan(&rest, &too_fast_target, &l),
        Err(Error::Infeasible { .. })
    ));
}

#[test]
fn zero_move_has_zero_duration() {
    let s = State::at_rest(0.25);
    let traj = Trajectory::plan(&s, &s, &Limits::default()).unwrap();
    assert_eq!(traj.duration_s(), 0.0);
    let at = traj.sample(1.0);
    assert_eq!(
        (at.position, at.velocity, at.acceleration),
        (0.25, 0.0, 0.0)
    );
}

#[test]
fn a_start_already_at_the_target_needs_no_move() {
    // Rest and moving, symmetric and asymmetric jerk: zero duration, and the
    // sample at 0 is the start. (Ruckig returns 0 s at rest but plans a
    // 0.64 s loop for the moving state with these limits.)
    for j_min in [-40.0, -20.0] {
        let limits = Limits {
            j_min,
            ..Limits::default()
        };
        for state in [
            State::at_rest(0.3),
            State {
                position: 0.1,
                velocity: 0.5,
                acceleration: 1.0,
            },
        ] {
            let traj = Trajectory::plan(&state, &state, &limits).expect("plannable");
            assert_eq!(traj.duration_s(), 0.0, "{state:?}, j_min {j_min}");
            let s = traj.sample(0.0);
            assert_eq!(
                (s.position, s.velocity, s.acceleration, s.jerk),
                (state.position, state.velocity, state.acceleration, 0.0)
            );
            assert_eq!(traj.end(), state);
            let range = traj.position_range();
            assert_eq!(
                (range.lowest, range.highest),
                (state.position, state.position)
            );
        }
    }
}
