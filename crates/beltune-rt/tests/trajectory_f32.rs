//! The single-precision path of the trajectory generator
//! (`Trajectory::to_f32`, `TrajectoryF32::sample`) against the f64 plan it
//! comes from (`Trajectory::sample`), sampled at the same instants, on the
//! thesis' validation move and on seeded random moves with brake
//! pre-phases and asymmetric limits.
//!
//! Tolerance (from f32's resolution, not from a run): the f32 sampler rounds
//! each segment's start time to f32 (half an ulp of the duration `T`), forms
//! the time into the segment (another half ulp), and evaluates the cubic
//! from the start state rounded to f32 in a handful of f32 operations (at
//! most 8 ulp of the largest position). So the position may be off by
//! `|v|max ulp(T) + 8 ulp(|p|max)`, the velocity by `|a|max ulp(T) + 8
//! ulp(|v|max)`, the acceleration by `|j|max ulp(T) + 8 ulp(|a|max)`; the
//! jerk is exact where both sample the same segment. Near a switching
//! instant (within `ulp(T)`) the two may sample neighbouring segments;
//! the state is continuous there, so the same bounds hold for position,
//! velocity and acceleration, and the jerk is not compared.

use beltune_rt::trajectory::{Limits, State, Trajectory};

/// One ulp of `|x|` as f32, s or m or m/s.
fn ulp32(x: f64) -> f64 {
    let x = (x.abs() as f32).max(f32::MIN_POSITIVE);
    f64::from(f32::from_bits(x.to_bits() + 1) - x)
}

struct Worst {
    position_m: f64,
    velocity_m_s: f64,
    acceleration_m_s2: f64,
}

/// Samples `traj` every `ts` s (and past its end) in f64 and f32 at the same
/// instants; asserts the bounds of the module docs and returns the largest
/// errors relative to them.
fn compare(traj: &Trajectory, ts: f64) -> Worst {
    let f = traj.to_f32();
    let duration = traj.duration_s();
    let n = ((duration + 0.05) / ts) as usize + 1;
    let (mut p_max, mut v_max, mut a_max, mut j_max) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    for k in 0..n {
        let s = traj.sample(k as f64 * ts);
        p_max = p_max.max(s.position.abs());
        v_max = v_max.max(s.velocity.abs());
        a_max = a_max.max(s.acceleration.abs());
        j_max = j_max.max(s.jerk.abs());
    }
    let ut = ulp32(duration + 0.05);
    let tol_p = v_max * ut + 8.0 * ulp32(p_max);
    let tol_v = a_max * ut + 8.0 * ulp32(v_max);
    let tol_a = j_max * ut + 8.0 * ulp32(a_max);
    let mut worst = Worst {
        position_m: 0.0,
        velocity_m_s: 0.0,
        acceleration_m_s2: 0.0,
    };
    for k in 0..n {
        let t32 = (k as f64 * ts) as f32;
        let want = traj.sample(f64::from(t32));
        let got = f.sample(t32);
        let dp = (f64::from(got.position) - want.position).abs();
        let dv = (f64::from(got.velocity) - want.velocity).abs();
        let da = (f64::from(got.acceleration) - want.acceleration).abs();
        assert!(
            dp <= tol_p && dv <= tol_v && da <= tol_a,
            "t = {t32} s: position {dp:e} (tol {tol_p:e}), velocity {dv:e} (tol {tol_v:e}), \
             acceleration {da:e} (tol {tol_a:e})"
        );
        worst.position_m = worst.position_m.max(dp / tol_p);
        worst.velocity_m_s = worst.velocity_m_s.max(dv / tol_v);
        worst.acceleration_m_s2 = worst.acceleration_m_s2.max(da / tol_a);
    }
    assert_eq!(f.duration_s(), duration as f32);
    worst
}

/// Thesis chapter 5: 0 -> 0.5 m with the limits of Table A.8, at 10 kHz.
#[test]
fn f32_samples_of_the_validation_move_follow_the_f64_plan() {
    let limits = Limits {
        position_min: -0.01,
        position_max: 0.57,
        ..Limits::default()
    };
    let traj = Trajectory::plan(&State::at_rest(0.0), &State::at_rest(0.5), &limits).unwrap();
    let w = compare(&traj, 1e-4);
    println!(
        "validation move: largest f32 error / tolerance: position {:.2}, velocity {:.2}, acceleration {:.2}",
        w.position_m, w.velocity_m_s, w.acceleration_m_s2
    );
    // the end state itself: the target to f32's resolution
    let end = traj.to_f32().sample(10.0);
    assert_eq!(end.position, 0.5);
    assert_eq!(end.velocity, 0.0);
    assert_eq!(end.acceleration, 0.0);
    // before the start: the start state
    assert_eq!(traj.to_f32().sample(f32::NAN).position, 0.0);
}

/// 2,000 seeded moves: random start states (some outside the velocity or
/// acceleration limits, so with a brake pre-phase), targets and limits,
/// symmetric and asymmetric jerk.
#[test]
fn f32_samples_of_seeded_moves_follow_the_f64_plan() {
    let mut state = 0x5EED_F032_u64;
    let mut draw = |lo: f64, hi: f64| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    let (mut planned, mut braked) = (0, 0);
    let mut worst: f64 = 0.0;
    for case in 0..2000 {
        let v = draw(0.2, 3.0);
        let a = draw(1.0, 30.0);
        let j = draw(10.0, 500.0);
        let limits = Limits {
            v_max: v,
            v_min: -v * draw(0.5, 1.0),
            a_max: a,
            a_min: -a * draw(0.5, 1.0),
            j_max: j,
            j_min: if case % 2 == 0 {
                -j
            } else {
                -j * draw(0.5, 1.0)
            },
            position_min: f64::NEG_INFINITY,
            position_max: f64::INFINITY,
        };
        let start = State {
            position: draw(-1.0, 1.0),
            velocity: draw(-1.3, 1.3) * v,
            acceleration: draw(-1.3, 1.3) * a,
        };
        let target = State::at_rest(draw(-1.0, 1.0));
        let Ok(traj) = Trajectory::plan(&start, &target, &limits) else {
            continue;
        };
        planned += 1;
        if traj.brake_duration_s() > 0.0 {
            braked += 1;
        }
        let w = compare(&traj, 1e-4);
        worst = worst
            .max(w.position_m)
            .max(w.velocity_m_s)
            .max(w.acceleration_m_s2);
    }
    println!("{planned} moves ({braked} with a brake pre-phase): largest f32 error / tolerance {worst:.2}");
    assert!(
        planned > 1900 && braked > 100,
        "{planned} planned, {braked} braked"
    );
}
