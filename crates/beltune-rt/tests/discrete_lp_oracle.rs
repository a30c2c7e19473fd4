//! The discretized LP oracle (`tests/support/discrete_lp.rs`): its self-test
//! against the reference `rsruckig` on symmetric jerk limits and against a
//! closed form on asymmetric ones, then the planner's asymmetric-jerk
//! durations, which no reference covers, against it.

mod support;

use beltune_rt::trajectory::{Limits, State, Trajectory};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::time::Instant;
use support::cases::{self, log_uniform, random_limits, Jerk};
use support::discrete_lp::{
    feasible, feasible_profile, lp_retries, lp_stats, shortest_duration, Bounds, VelocityCheck,
};

#[derive(Clone, Copy, Debug)]
struct Case {
    start: [f64; 3],
    target: [f64; 3],
    bounds: Bounds,
}

/// rsruckig's duration for the case, or `None` when it rejects it.
fn reference_duration(c: &Case) -> Option<f64> {
    cases::reference_duration(&cases::Case {
        start: state(c.start),
        target: state(c.target),
        limits: limits(&c.bounds),
    })
}

/// `[p, v, a]` as the planner's state.
fn state(s: [f64; 3]) -> State {
    State {
        position: s[0],
        velocity: s[1],
        acceleration: s[2],
    }
}

/// The planner's limits for the oracle's bounds (no position limits).
fn limits(b: &Bounds) -> Limits {
    Limits {
        v_max: b.v_max,
        v_min: b.v_min,
        a_max: b.a_max,
        a_min: b.a_min,
        j_max: b.j_max,
        j_min: b.j_min,
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
    }
}

/// The oracle's bounds for the planner's limits.
fn bounds(l: &Limits) -> Bounds {
    Bounds {
        v_max: l.v_max,
        v_min: l.v_min,
        a_max: l.a_max,
        a_min: l.a_min,
        j_max: l.j_max,
        j_min: l.j_min,
    }
}

fn random_bounds(rng: &mut Xoshiro256PlusPlus, asymmetric: bool, jerk: Jerk) -> Bounds {
    bounds(&random_limits(rng, asymmetric, jerk))
}

/// `[p, v, a]` strictly inside the limits, admissible as start and target
/// (ramping the acceleration to zero keeps the velocity inside).
fn admissible_state(rng: &mut Xoshiro256PlusPlus, b: &Bounds, p: f64, moving: bool) -> [f64; 3] {
    if !moving {
        return [p, 0.0, 0.0];
    }
    loop {
        let v = rng.random_range(0.9 * b.v_min..0.9 * b.v_max);
        let a = rng.random_range(0.9 * b.a_min..0.9 * b.a_max);
        let dv = a * a / (2.0 * b.j_max.min(-b.j_min));
        if v + dv <= 0.95 * b.v_max && v - dv >= 0.95 * b.v_min {
            return [p, v, a];
        }
    }
}

/// Families: 0 short rest-to-rest (no limit reached), 1 long rest-to-rest
/// (a and v limits reached), 2 moving start and target, 3 asymmetric v/a
/// limits rest-to-rest, 4 asymmetric v/a limits moving.
fn random_case(rng: &mut Xoshiro256PlusPlus, family: usize, jerk: Jerk) -> Case {
    let bounds = random_bounds(rng, family >= 3, jerk);
    let p0 = rng.random_range(-1.0..1.0);
    // Distances relative to the natural length scale v_max^2 / a_max.
    let scale = bounds.v_max * bounds.v_max / bounds.a_max;
    let (distance, moving) = match family {
        0 => (scale * log_uniform(rng, 1e-4, 1e-2), false),
        1 => (scale * log_uniform(rng, 2.0, 30.0), false),
        2 => (scale * log_uniform(rng, 1e-2, 10.0), true),
        3 => (scale * log_uniform(rng, 1e-2, 30.0), false),
        _ => (scale * log_uniform(rng, 1e-2, 10.0), true),
    };
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let start = admissible_state(rng, &bounds, p0, moving);
    let target = admissible_state(rng, &bounds, p0 + sign * distance, moving);
    Case {
        start,
        target,
        bounds,
    }
}

const FAMILIES: usize = 5;
const CASES_PER_FAMILY: usize = 8;

fn cases() -> Vec<(Case, f64)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x1b_0ac1e);
    let mut out = Vec::new();
    for family in 0..FAMILIES {
        let mut n = 0;
        while n < CASES_PER_FAMILY {
            let c = random_case(&mut rng, family, Jerk::Symmetric);
            if let Some(t) = reference_duration(&c) {
                if t > 0.0 {
                    out.push((c, t));
                    n += 1;
                }
            }
        }
    }
    out
}

/// Measurement (run with `--ignored --nocapture`): the LP optimum over the
/// reference duration for several grid sizes.
#[test]
#[ignore = "measurement, about 4 minutes"]
fn measure_gap_to_rsruckig() {
    let ns: Vec<usize> = std::env::var("LP_NS")
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or(vec![100, 200, 400]);
    for n in ns {
        for check in [VelocityCheck::GridPointsOnly, VelocityCheck::Conservative] {
            let (s0, e0) = lp_stats();
            let r0 = lp_retries();
            let started = Instant::now();
            let mut lowest = f64::INFINITY;
            let mut highest = f64::NEG_INFINITY;
            let mut worst = 0;
            for (i, (c, t_ref)) in cases().into_iter().enumerate() {
                // Feasibility need not be monotone in T (blocked intervals of
                // moving targets): bracket with the first feasible factor.
                let first = [1.0, 1.001, 1.003, 1.01, 1.03, 1.1, 1.3]
                    .into_iter()
                    .find(|f| feasible(c.start, c.target, &c.bounds, f * t_ref, n, check));
                let t = first
                    .and_then(|f| {
                        shortest_duration(
                            c.start,
                            c.target,
                            &c.bounds,
                            (0.9 * t_ref, f * t_ref),
                            n,
                            check,
                            1e-4,
                        )
                    })
                    .unwrap_or(f64::INFINITY);
                let gap = t / t_ref - 1.0;
                lowest = lowest.min(gap);
                if gap > highest {
                    highest = gap;
                    worst = i;
                }
            }
            let (s1, e1) = lp_stats();
            println!(
                "N = {n:3} {check:?}: T_lp / T_ref - 1 in [{lowest:+.3e}, {highest:+.3e}] (worst case {worst}), \
                 {} solves, {} retried, {} errors, {:.2} ms per solve",
                s1 - s0,
                lp_retries() - r0,
                e1 - e0,
                started.elapsed().as_secs_f64() * 1e3 / (s1 - s0) as f64
            );
        }
    }
}

/// Grid size of the checks (see `DELTA`).
const N: usize = 200;
/// Relative margin around the reference duration.
///
/// Measured with `measure_gap_to_rsruckig` on these 40 cases: the shortest
/// LP duration over rsruckig's, `T_lp / T_ref - 1`, is never below 0 (to the
/// bisection tolerance 1e-4) and at worst
///
/// | N   | GridPointsOnly | Conservative | ms per LP solve |
/// | --- | -------------- | ------------ | --------------- |
/// | 100 | 7.7e-2         | 7.9e-2       | 10 - 13         |
/// | 200 | 8.6e-3         | 8.6e-3       | 40 - 50         |
/// | 400 | 3.0e-3         | 3.0e-3       | 170 - 220       |
///
/// (test profile, opt-level 2, 2 shared cores; the worst cases are a long
/// move and a moving start whose acceleration must come back from far
/// outside a tiny `a_max`). N = 200 with DELTA = 0.02 leaves 2.3 times the
/// worst measured gap on the upper side and the full 2 % on the lower side,
/// at about 3 s for the whole test; N = 100 would need DELTA >= 0.1, N = 400
/// costs 4 times as much per solve.
const DELTA: f64 = 0.02;

/// The lower side needs no discretization margin: the LP optimum was never
/// below the reference (measured minimum of `T_lp / T_ref - 1` is 0 to the
/// bisection tolerance 1e-4), so "no grid move 0.2 % shorter" is what a
/// suboptimal planner would fail.
const DELTA_SHORTER: f64 = 2e-3;

#[test]
fn oracle_brackets_rsruckig_on_40_symmetric_cases() {
    let cases = cases();
    let (s0, e0) = lp_stats();
    let started = Instant::now();
    for (i, (c, t_ref)) in cases.iter().enumerate() {
        assert!(
            feasible(
                c.start,
                c.target,
                &c.bounds,
                t_ref * (1.0 + DELTA),
                N,
                VelocityCheck::Conservative
            ),
            "case {i}: not feasible at T_ref (1 + DELTA), T_ref = {t_ref}: {c:?}"
        );
        assert!(
            !feasible(
                c.start,
                c.target,
                &c.bounds,
                t_ref * (1.0 - DELTA_SHORTER),
                N,
                VelocityCheck::GridPointsOnly
            ),
            "case {i}: feasible at T_ref (1 - DELTA_SHORTER), T_ref = {t_ref}: {c:?}"
        );
    }
    let (s1, e1) = lp_stats();
    println!(
        "{} cases, N = {N}: {} LP solves, {} solver errors, {:.1} ms per solve",
        cases.len(),
        s1 - s0,
        e1 - e0,
        started.elapsed().as_secs_f64() * 1e3 / (s1 - s0) as f64
    );
    // A solver error reads as "infeasible" and would pass the lower check.
    assert_eq!(
        e1, e0,
        "LP solver errors (DISCRETE_LP_VERBOSE=1 prints them)"
    );
}

/// The Conservative claim, checked: the jerk profile of a Conservative LP
/// point, integrated exactly and sampled 16 times per interval, keeps the
/// velocity and acceleration inside and ends at the target.
#[test]
fn conservative_profiles_stay_inside_between_grid_points() {
    for (i, (c, t_ref)) in cases().iter().enumerate() {
        let t = t_ref * (1.0 + DELTA);
        let jerks = feasible_profile(
            c.start,
            c.target,
            &c.bounds,
            t,
            N,
            VelocityCheck::Conservative,
        )
        .unwrap_or_else(|| panic!("case {i}: infeasible"));
        let b = &c.bounds;
        let dt = t / N as f64;
        let v_tol = 1e-7 * b.v_max.max(-b.v_min);
        let a_tol = 1e-7 * b.a_max.max(-b.a_min);
        let [mut p, mut v, mut a] = c.start;
        for &j in &jerks {
            assert!(j >= b.j_min * (1.0 + 1e-9) && j <= b.j_max * (1.0 + 1e-9));
            for m in 1..=16 {
                let s = dt * m as f64 / 16.0;
                let vs = v + a * s + j * s * s / 2.0;
                let as_ = a + j * s;
                assert!(
                    vs <= b.v_max + v_tol && vs >= b.v_min - v_tol,
                    "case {i}: v = {vs} outside [{}, {}]",
                    b.v_min,
                    b.v_max
                );
                assert!(
                    as_ <= b.a_max + a_tol && as_ >= b.a_min - a_tol,
                    "case {i}: a = {as_}"
                );
            }
            p += v * dt + a * dt * dt / 2.0 + j * dt * dt * dt / 6.0;
            v += a * dt + j * dt * dt / 2.0;
            a += j * dt;
        }
        let scale_p = 1e-7 * (1.0 + (c.target[0] - c.start[0]).abs());
        assert!(
            (p - c.target[0]).abs() <= scale_p
                && (v - c.target[1]).abs() <= v_tol
                && (a - c.target[2]).abs() <= a_tol,
            "case {i}: ends at [{p}, {v}, {a}], target {:?}",
            c.target
        );
    }
}

/// Time-optimal rest-to-rest move over `distance > 0` with jerk in
/// `[-j2, j1]`, no velocity or acceleration limit reached.
///
/// By Pontryagin's principle the jerk is bang-bang with at most two switches
/// (its switching function is a quadratic polynomial in time), so the profile
/// is `+j1` for `t1`, `-j2` for `t2`, `+j1` for `t3`. With `r = j1 / j2`:
/// `a(T) = 0` gives `t2 = r (t1 + t3)`; the acceleration is then two
/// triangles of areas `j1 t1^2 (1 + r) / 2` and `-j1 t3^2 (1 + r) / 2`, so
/// `v(T) = 0` gives `t1 = t3 = t`, `t2 = 2 r t`. The acceleration is odd about
/// `T / 2 = t (1 + r)`, the velocity even, so the distance is twice the
/// position at `T / 2`: `D = j1 t^3 (1 + r)(1 + 2 r) / 3`. Hence
/// `t = (3 D / (j1 (1 + r)(1 + 2 r)))^(1/3)`, `T = 2 t (1 + r)`, peak
/// acceleration `+-j1 t`, peak velocity `j1 t^2 (1 + r) / 2`.
/// (Check: `r = 1` gives the classic `D = 2 j t^3`, `T = 4 t`.)
fn asymmetric_jerk_rest_to_rest(distance: f64, j1: f64, j2: f64) -> (f64, f64, f64) {
    let r = j1 / j2;
    let t = (3.0 * distance / (j1 * (1.0 + r) * (1.0 + 2.0 * r))).cbrt();
    (2.0 * t * (1.0 + r), j1 * t, j1 * t * t * (1.0 + r) / 2.0)
}

#[test]
fn oracle_brackets_closed_form_with_asymmetric_jerk() {
    // Ratios whose switch times fall between grid points.
    for (j1, j2) in [(70.0, 200.0), (290.0, 100.0), (100.0, 100.0)] {
        let distance = 1e-3;
        let b = Bounds {
            v_max: 1.0,
            v_min: -1.0,
            a_max: 10.0,
            a_min: -10.0,
            j_max: j1,
            j_min: -j2,
        };
        let (t_opt, a_peak, v_peak) = asymmetric_jerk_rest_to_rest(distance, j1, j2);
        assert!(a_peak < b.a_max && v_peak < b.v_max, "limits reached");
        let start = [0.2, 0.0, 0.0];
        let target = [0.2 + distance, 0.0, 0.0];
        let upper = feasible(
            start,
            target,
            &b,
            t_opt * (1.0 + DELTA),
            N,
            VelocityCheck::Conservative,
        );
        let lower = feasible(
            start,
            target,
            &b,
            t_opt * (1.0 - DELTA_SHORTER),
            N,
            VelocityCheck::GridPointsOnly,
        );
        let t_lp = shortest_duration(
            start,
            target,
            &b,
            (0.9 * t_opt, 1.2 * t_opt),
            N,
            VelocityCheck::GridPointsOnly,
            1e-4,
        );
        println!(
            "j_max {j1}, j_min -{j2}: T* = {t_opt:.6} s, GridPointsOnly LP optimum / T* - 1 = {:?}",
            t_lp.map(|t| t / t_opt - 1.0)
        );
        assert!(upper && !lower, "j_max {j1}, j_min -{j2}: T* = {t_opt}");
    }
}

/// The planner with asymmetric jerk, where no reference exists, against the
/// oracle on cases drawn like the 40 above but with `j_min = -j_max f`,
/// `f` in `[0.1, 10]`: a grid move of `T (1 + DELTA)` exists, none of
/// `T (1 - DELTA_SHORTER)`. The self-tests above establish that the oracle
/// brackets true optima so at this grid size; a planner slower than optimal
/// by more than `DELTA_SHORTER` plus the grid's gap (at most 0.9 % measured)
/// fails here.
#[test]
fn planner_is_time_optimal_with_asymmetric_jerk() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0xA5_0AC1E);
    let (s0, e0) = lp_stats();
    let mut finer = 0;
    for i in 0..FAMILIES * CASES_PER_FAMILY {
        let c = random_case(&mut rng, i % FAMILIES, Jerk::Asymmetric);
        let b = &c.bounds;
        let t = Trajectory::plan(&state(c.start), &state(c.target), &limits(b))
            .unwrap_or_else(|e| panic!("case {i}: {e}: {c:?}"))
            .duration_s();
        // Jerk phases much shorter than T / N need a finer grid.
        let grid = |n: usize| {
            feasible(
                c.start,
                c.target,
                b,
                t * (1.0 + DELTA),
                n,
                VelocityCheck::Conservative,
            )
        };
        let n = [N, 2 * N, 4 * N]
            .into_iter()
            .find(|&n| grid(n))
            .unwrap_or_else(|| panic!("case {i}: no grid move of T (1 + DELTA), T = {t}: {c:?}"));
        if n > N {
            finer += 1;
        }
        assert!(
            !feasible(
                c.start,
                c.target,
                b,
                t * (1.0 - DELTA_SHORTER),
                n,
                VelocityCheck::GridPointsOnly
            ),
            "case {i}: a grid move of T (1 - DELTA_SHORTER) exists on {n} intervals, T = {t}: {c:?}"
        );
    }
    let (_, e1) = lp_stats();
    assert_eq!(e1, e0, "LP solver errors");
    println!(
        "{} LP solves, {finer} cases needed a finer grid",
        lp_stats().0 - s0
    );
}
