//! A discretized linear program as an independent optimality oracle for
//! jerk-limited 1-DOF trajectories, also for asymmetric jerk limits
//! (`j_min != -j_max`), which the reference `rsruckig` cannot check.
//!
//! Self-contained on purpose: it does not use `beltune_rt::trajectory::Limits`.
//!
//! # Discretization (exact for piecewise-constant jerk)
//!
//! The duration `T` is cut into `N` intervals of `dt = T / N`; the jerk `j_k`
//! is constant on interval `k`. With `a_k`, `v_k` the grid values,
//!
//! ```text
//! a_{k+1} = a_k + j_k dt
//! v_{k+1} = v_k + a_k dt + j_k dt^2 / 2
//! p_N     = p_0 + sum_k (v_k dt + a_k dt^2 / 2 + j_k dt^3 / 6)
//! ```
//!
//! hold exactly (with `p_{k+1} = p_k + v_k dt + a_k dt^2 / 2 + j_k dt^3 / 6`).
//! The LP keeps `j_k`, `a_k`, `v_k`, `p_k` as (scaled) variables tied by these
//! sparse equalities; the start and target states are fixed through the
//! bounds of `a_0, v_0, p_0, a_N, v_N, p_N`. The acceleration is piecewise
//! linear, so bounds on the grid values are exact for the continuous
//! acceleration.
//!
//! # Scaling
//!
//! Variables are `u_k = j_k / J`, `alpha_k = a_k / A`, `nu_k = v_k / V` with
//! `J = max(j_max, -j_min)`, `A = max(min(max|a limit|, J T), |a_0|, |a_f|)`,
//! `V = max(min(max|v limit|, A T), |v_0|, |v_f|)`: the accelerations and
//! velocities reachable within `T`, so every variable of a (nearly) feasible
//! point is O(1) whether the limits are reached or not. The recurrences are
//! divided by `A` and `V`, the position one by `V T` (positions relative to
//! `p_0`), which keeps its coefficients `<= 1/N` and `rho_N` O(1).
//!
//! # Velocity between grid points ([`VelocityCheck::Conservative`])
//!
//! On an interval the velocity is a quadratic `v_k + a_k s + j s^2 / 2`,
//! `s` in `[0, dt]`. It has an interior maximum only if `j < 0 < a_k`, at
//! `s* = a_k / |j| <= dt`, of `v_k + a_k s* / 2 <= v_k + a_k dt / 2`; an
//! interior minimum only if `a_k < 0 < j`, of `>= v_k + a_k dt / 2`. So the
//! linear constraints `v_min <= v_k + a_k dt / 2 <= v_max` (with the grid
//! bounds on `v_k`, `v_{k+1}`) keep the whole interval inside: the "margin" is
//! `|a_k| dt / 2`, zero where the acceleration is zero (cruising at a velocity
//! limit costs nothing); a constant margin `min(|j| dt^2 / 8, a dt / 4)` was
//! tried first and cost 3.8 % of the duration at N = 200 on long moves.
//! The first and last intervals touch the fixed
//! start / target state: there the velocity `v0 + a0 s + j s^2 / 2` (backwards
//! `vf - af s + j s^2 / 2`) depends on the one jerk only, and the condition
//! for all `s` in `(0, dt]` is an exact bound on that jerk
//! (`max_jerk_within`). With these every feasible LP point is a continuous
//! profile that respects all limits at all times.
//!
//! [`VelocityCheck::GridPointsOnly`] bounds the grid velocities only: a
//! relaxation of the velocity constraint for piecewise-constant jerk. Note
//! that it is not a proven relaxation of the continuous problem: the jerk is
//! restricted to be constant on the grid, while the time-optimal bang-bang
//! profile switches between grid points. Its optimum converges to the true one
//! as `N` grows; `tests/discrete_lp_oracle.rs` measures how fast.

use microlp::{ComparisonOp, OptimizationDirection, Problem};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Kinematic bounds: `v_min < 0 < v_max`, `a_min < 0 < a_max`,
/// `j_min < 0 < j_max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub v_max: f64,
    pub v_min: f64,
    pub a_max: f64,
    pub a_min: f64,
    pub j_max: f64,
    pub j_min: f64,
}

/// How the velocity bounds are imposed (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VelocityCheck {
    /// Velocity bounded at the grid points only (relaxation: use to show
    /// that a duration is too short).
    GridPointsOnly,
    /// Grid velocities tightened so that the continuous velocity stays
    /// inside (restriction: use to show that a duration is achievable).
    Conservative,
}

static SOLVES: AtomicUsize = AtomicUsize::new(0);
static ERRORS: AtomicUsize = AtomicUsize::new(0);
static RETRIES: AtomicUsize = AtomicUsize::new(0);

/// LP solves so far (calls of [`feasible`] that reached the solver) and how
/// many of them ended in a numerical error or a panic of the solver even
/// after one retry with other variable scales (counted as "infeasible"; the
/// environment variable `DISCRETE_LP_VERBOSE` prints each error).
/// Process-wide: tests running in parallel add up.
pub fn lp_stats() -> (usize, usize) {
    (
        SOLVES.load(Ordering::Relaxed),
        ERRORS.load(Ordering::Relaxed),
    )
}

/// How many solves needed the retry (process-wide, like [`lp_stats`]).
pub fn lp_retries() -> usize {
    RETRIES.load(Ordering::Relaxed)
}

/// Is there a jerk profile, piecewise constant on `intervals` equal intervals
/// of total `duration_s`, with `j` in `[j_min, j_max]`, the acceleration within
/// its bounds and the velocity within its bounds (as `check` says), from
/// `start = [p0, v0, a0]` to exactly `target = [pf, vf, af]`?
///
/// A solver error other than "infeasible" (or a solver panic) is retried once
/// with other variable scales and constraint order; if that fails too it counts as infeasible;
/// [`lp_stats`] and [`lp_retries`] count them.
pub fn feasible(
    start: [f64; 3],
    target: [f64; 3],
    b: &Bounds,
    duration_s: f64,
    intervals: usize,
    check: VelocityCheck,
) -> bool {
    feasible_profile(start, target, b, duration_s, intervals, check).is_some()
}

/// As [`feasible`], but returns the jerks `j_k` (m/s^3, one per interval) of
/// the feasible point the LP found.
pub fn feasible_profile(
    start: [f64; 3],
    target: [f64; 3],
    b: &Bounds,
    duration_s: f64,
    intervals: usize,
    check: VelocityCheck,
) -> Option<Vec<f64>> {
    assert!(intervals >= 2, "need at least two intervals");
    assert!(
        b.v_min < 0.0 && b.v_max > 0.0 && b.a_min < 0.0 && b.a_max > 0.0,
        "{b:?}"
    );
    assert!(b.j_min < 0.0 && b.j_max > 0.0, "{b:?}");
    if duration_s.is_nan() || duration_s <= 0.0 || duration_s.is_infinite() {
        return None;
    }
    let n = intervals;
    let t = duration_s;
    let dt = t / n as f64;
    let [p0, v0, a0] = start;
    let [pf, vf, af] = target;

    let v_bounds = |k: usize| -> (f64, f64) {
        if k == 0 {
            (v0, v0)
        } else if k == n {
            (vf, vf)
        } else {
            (b.v_min, b.v_max)
        }
    };
    // Jerk bounds; in the first and last interval the velocity is a quadratic
    // in the jerk alone (the start / target state is fixed), so Conservative
    // bounds that jerk exactly.
    let mut j_bounds = vec![(b.j_min, b.j_max); n];
    if check == VelocityCheck::Conservative {
        // v0 + a0 s + j s^2/2 <= v_max for s in (0, dt], and >= v_min.
        let first = (
            b.j_min.max(-max_jerk_within(v0 - b.v_min, -a0, dt)),
            b.j_max.min(max_jerk_within(b.v_max - v0, a0, dt)),
        );
        // Backwards from the target: vf - af s + j s^2/2.
        let last = (
            b.j_min.max(-max_jerk_within(vf - b.v_min, af, dt)),
            b.j_max.min(max_jerk_within(b.v_max - vf, -af, dt)),
        );
        j_bounds[0] = first;
        let l = &mut j_bounds[n - 1];
        *l = (l.0.max(last.0), l.1.min(last.1));
        if j_bounds.iter().any(|(lo, hi)| lo > hi) {
            return None;
        }
    }

    // One LP solve (`scale` 1, or other scales and constraint order for the
    // retry: the same feasible set, other numerics): Ok(feasible) or the
    // solver's error.
    let attempt = |scale: f64| -> Result<Option<Vec<f64>>, String> {
        // `scale` changes the jerk and velocity scales in opposite directions:
        // the matrix changes, not only the bounds.
        let j_ref = b.j_max.max(-b.j_min);
        let a_lim = b.a_max.max(-b.a_min);
        let v_lim = b.v_max.max(-b.v_min);
        let a_s = a_lim.min(j_ref * t).max(a0.abs()).max(af.abs());
        let v_s = v_lim.min(a_s * t).max(v0.abs()).max(vf.abs()) / scale;
        let j_s = j_ref * scale;
        // The retry also adds the constraints in the reverse order.
        let order: Vec<usize> = if scale == 1.0 {
            (0..n).collect()
        } else {
            (0..n).rev().collect()
        };
        let mut lp = Problem::new(OptimizationDirection::Minimize);
        let u: Vec<_> = j_bounds
            .iter()
            .map(|&(lo, hi)| lp.add_var(0.0, (lo / j_s, hi / j_s)))
            .collect();
        let alpha: Vec<_> = (0..=n)
            .map(|k| {
                let (lo, hi) = if k == 0 {
                    (a0, a0)
                } else if k == n {
                    (af, af)
                } else {
                    (b.a_min, b.a_max)
                };
                lp.add_var(0.0, (lo / a_s, hi / a_s))
            })
            .collect();
        let nu: Vec<_> = (0..=n)
            .map(|k| {
                let (lo, hi) = v_bounds(k);
                lp.add_var(0.0, (lo / v_s, hi / v_s))
            })
            .collect();

        let c1 = dt * j_s / a_s;
        let c2 = dt * a_s / v_s;
        let c3 = dt * dt * j_s / (2.0 * v_s);
        for &k in &order {
            lp.add_constraint(
                [(alpha[k + 1], 1.0), (alpha[k], -1.0), (u[k], -c1)],
                ComparisonOp::Eq,
                0.0,
            );
            lp.add_constraint(
                [
                    (nu[k + 1], 1.0),
                    (nu[k], -1.0),
                    (alpha[k], -c2),
                    (u[k], -c3),
                ],
                ComparisonOp::Eq,
                0.0,
            );
        }
        if check == VelocityCheck::Conservative {
            // Between grid points of the inner intervals (see the module docs):
            // v_min <= v_k + a_k dt / 2 <= v_max.
            let c = dt * a_s / (2.0 * v_s);
            for k in 1..n - 1 {
                lp.add_constraint(
                    [(nu[k], 1.0), (alpha[k], c)],
                    ComparisonOp::Le,
                    b.v_max / v_s,
                );
                lp.add_constraint(
                    [(nu[k], 1.0), (alpha[k], c)],
                    ComparisonOp::Ge,
                    b.v_min / v_s,
                );
            }
        }
        // Position as a recurrence too (a banded constraint matrix keeps the LU
        // factors sparse; one dense row made the solve ~N^2.5):
        // rho_k = (p_k - p0) / (V T), rho_0 = 0, rho_N = (pf - p0) / (V T).
        let p_s = v_s * t;
        let rho: Vec<_> = (0..=n)
            .map(|k| {
                if k == 0 {
                    lp.add_var(0.0, (0.0, 0.0))
                } else if k == n {
                    let r = (pf - p0) / p_s;
                    lp.add_var(0.0, (r, r))
                } else {
                    lp.add_var(0.0, (f64::NEG_INFINITY, f64::INFINITY))
                }
            })
            .collect();
        let d1 = dt * v_s / p_s;
        let d2 = dt * dt * a_s / (2.0 * p_s);
        let d3 = dt * dt * dt * j_s / (6.0 * p_s);
        for &k in &order {
            lp.add_constraint(
                [
                    (rho[k + 1], 1.0),
                    (rho[k], -1.0),
                    (nu[k], -d1),
                    (alpha[k], -d2),
                    (u[k], -d3),
                ],
                ComparisonOp::Eq,
                0.0,
            );
        }

        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| lp.solve()));
        match outcome {
            Ok(Ok(o)) => Ok(o
                .solution()
                .map(|sol| u.iter().map(|&x| sol.var_value(x) * j_s).collect())),
            Ok(Err(microlp::Error::Infeasible)) => Ok(None),
            Ok(Err(e)) => Err(format!("{e:?}")),
            Err(_) => Err("solver panicked".to_string()),
        }
    };

    let verbose = std::env::var_os("DISCRETE_LP_VERBOSE").is_some();
    SOLVES.fetch_add(1, Ordering::Relaxed);
    match attempt(1.0) {
        Ok(f) => f,
        Err(e) => {
            // Retry once with other scales (e.g. microlp's "Singular matrix").
            RETRIES.fetch_add(1, Ordering::Relaxed);
            let retry = attempt(0.5);
            if verbose {
                eprintln!(
                    "discrete_lp: solver error {e} (T = {t}, N = {n}, {check:?}), retry: {retry:?}"
                );
            }
            retry.unwrap_or_else(|_| {
                ERRORS.fetch_add(1, Ordering::Relaxed);
                None
            })
        }
    }
}

/// The largest jerk `j` with `a s + j s^2 / 2 <= room` for all `s` in
/// `(0, dt]` (the velocity may rise by at most `room` within one interval
/// that starts with acceleration `a`): `min` over `x = 1/s >= 1/dt` of the
/// convex `2 room x^2 - 2 a x`. `-inf` when `room < 0`, or `room = 0 < a`.
fn max_jerk_within(room: f64, a: f64, dt: f64) -> f64 {
    if room < 0.0 {
        return f64::NEG_INFINITY;
    }
    let x_lo = 1.0 / dt;
    if a > 0.0 && a >= 2.0 * room * x_lo {
        // Unconstrained minimum at x = a / (2 room) inside the range.
        if room == 0.0 {
            return f64::NEG_INFINITY;
        }
        -a * a / (2.0 * room)
    } else {
        2.0 * room * x_lo * x_lo - 2.0 * a * x_lo
    }
}

/// Bisection on the duration: the shortest duration in `[lo, hi]` (to the
/// relative tolerance `rel_tol`) at which [`feasible`] holds, or `None` when
/// it does not hold at `hi`. Returns `lo` when it already holds there.
/// Assumes feasibility is monotone in the duration (true for the continuous
/// problem; with a fixed `N` the grid can make it slightly non-monotone, so
/// the result is one feasible duration near the boundary).
pub fn shortest_duration(
    start: [f64; 3],
    target: [f64; 3],
    b: &Bounds,
    (lo, hi): (f64, f64),
    intervals: usize,
    check: VelocityCheck,
    rel_tol: f64,
) -> Option<f64> {
    let ok = |t: f64| feasible(start, target, b, t, intervals, check);
    if !ok(hi) {
        return None;
    }
    if ok(lo) {
        return Some(lo);
    }
    let (mut lo, mut hi) = (lo, hi);
    while hi - lo > rel_tol * hi {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}
