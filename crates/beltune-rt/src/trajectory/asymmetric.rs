//! Time-optimal profiles for asymmetric jerk limits (`j_min != -j_max`), which
//! Ruckig's closed forms (`step1.rs`) do not cover.
//!
//! The structure of a time-optimal profile does not depend on the jerk limits
//! being symmetric: by Pontryagin's principle the jerk is at a bound (`j_max`
//! or `j_min`) except on arcs where a state limit is held (acceleration in P2
//! or P6, velocity in P4), and between such arcs the switching function is a
//! quadratic in time, so there are at most two switches. That gives the same
//! seven phases as Figure 6.11; for the "up" direction the jerks are
//! `[j_max, 0, j_min, 0, j_min, 0, j_max]` and a [`Shape`] fixes them by
//! the peak acceleration `a_peak` (end of P1), the holds P2/P6, the cruise P4
//! at `v_max` (where `a = 0`) and the low acceleration `a_low` (end of P5).
//! The "down" direction is the same problem mirrored (`p, v, a -> -p, -v, -a`,
//! limits swapped).
//!
//! With `k = 1/(2 j_max) - 1/(2 j_min) > 0`, summing the velocity gained in
//! each phase, `(a_end^2 - a_start^2) / (2 j)` for a jerk phase and `a t` for
//! a hold, gives for the whole profile
//!
//! `k (a_peak^2 - a_low^2) + a_peak t2 + a_low t6 = v_f - v_0 + (a_0^2 - a_f^2) / (2 j_max)`  (= R)
//!
//! and the families follow:
//!
//! * **velocity limit reached** (P4 > 0): P1-P3 bring `(v_0, a_0)` to
//!   `(v_max, 0)`: `k a_peak^2 + a_peak t2 = v_max - v_0 + a_0^2/(2 j_max)`,
//!   with `a_peak = a_max` and `t2 > 0` when the square root exceeds `a_max`;
//!   P5-P7 likewise from `(v_max, 0)` to `(v_f, a_f)`; P4 is what is left of
//!   the distance divided by `v_max`. Closed form.
//! * **velocity limit not reached** (P4 = 0, P3 and P5 merge): two unknowns
//!   among `a_peak`/`t2` and `a_low`/`t6` for the velocity and position
//!   conditions. The velocity condition expresses one through the other
//!   (as a square root when neither acceleration limit is held), and the
//!   position condition becomes one polynomial equation (degree at most 6),
//!   built by integrating the phases in polynomial arithmetic (`poly.rs`).
//!
//! Every root gives a candidate that is integrated and checked (durations
//! `>= 0`, acceleration and velocity limits, target reached); the shortest
//! valid candidate of both directions is the time-optimal profile. With
//! `j_min = -j_max` this reproduces Ruckig's durations (tested against
//! `rsruckig`); for asymmetric jerk it is checked against a discretized
//! linear program (`tests/discrete_lp_oracle.rs`) and for invariances
//! (`tests/trajectory_asymmetric.rs`).

use core::ops::{Add, Mul, Sub};

use super::math::integrate;
// In `cfg(test)` builds std is linked and its inherent `f64` methods shadow
// these `libm` ones, so the import is then unused.
#[cfg_attr(test, allow(unused_imports))]
use super::math::F64Math;
use super::poly::{real_roots, Poly, Surd};
// The target precision, limit slack and longest profile of Ruckig's check;
// `A_EPS` here is relative to `1 + |a|`.
use super::profile::{
    Direction, Profile, A_EPS, A_PRECISION, P_PRECISION, T_MAX, V_EPS, V_PRECISION,
};

/// A phase duration computed from a root may come out negative by rounding;
/// up to this fraction of the whole profile it is taken as zero (the target
/// check afterwards decides whether the profile is still exact).
const T_REL_TOL: f64 = 1e-9;
/// Position precision relative to the largest position of the move, for
/// moves beyond 10^6 m (see [`build`]).
const P_REL_PRECISION: f64 = 1e-14;
/// Search intervals for the unknown accelerations are widened by this
/// fraction of `a_max - a_min` so that roots on their ends are not lost.
const A_REL_WIDEN: f64 = 1e-9;
/// Integrated phase-end accelerations this close (relative to `1 + |a|`)
/// to the designed ones are taken as the designed ones.
const A_SNAP: f64 = 1e-12;
/// Rounding of velocities relative to `1 +` [`Problem::v_scale`]: the slack
/// of the velocity limits, and how close the integrated velocity at the start
/// of a cruise must be to `v_max` to be taken as `v_max`. (A brake pre-phase
/// through 10^4 m/s leaves the start state accurate to about 1e-11 m/s.)
const V_ROUND: f64 = 1e-12;

/// The boundary value problem after the brake pre-phase: start, target and
/// limits (m, m/s, m/s^2, m/s^3).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Problem {
    pub p0: f64,
    pub v0: f64,
    pub a0: f64,
    pub pf: f64,
    pub vf: f64,
    pub af: f64,
    pub v_max: f64,
    pub v_min: f64,
    pub a_max: f64,
    pub a_min: f64,
    pub j_max: f64,
    pub j_min: f64,
    /// Largest speed of the move including the brake pre-phase (m/s): the
    /// scale of the rounding in the velocities.
    pub v_scale: f64,
}

impl Problem {
    /// The same problem seen with the position axis reversed.
    fn mirrored(&self) -> Self {
        Self {
            p0: -self.p0,
            v0: -self.v0,
            a0: -self.a0,
            pf: -self.pf,
            vf: -self.vf,
            af: -self.af,
            v_max: -self.v_min,
            v_min: -self.v_max,
            a_max: -self.a_min,
            a_min: -self.a_max,
            j_max: -self.j_min,
            j_min: -self.j_max,
            v_scale: self.v_scale,
        }
    }

    /// Velocity rounding tolerance, m/s (see [`V_ROUND`]).
    fn v_round(&self) -> f64 {
        V_ROUND * (1.0 + self.v_scale.max(self.v_max).max(-self.v_min))
    }

    /// `k = 1/(2 j_max) - 1/(2 j_min)`, s^3/m.
    fn k(&self) -> f64 {
        0.5 / self.j_max - 0.5 / self.j_min
    }

    /// `R = v_f - v_0 + (a_0^2 - a_f^2) / (2 j_max)`, m/s.
    fn r(&self) -> f64 {
        self.vf - self.v0 + (self.a0 * self.a0 - self.af * self.af) * 0.5 / self.j_max
    }

    /// Widening of the acceleration search intervals, m/s^2.
    fn a_widen(&self) -> f64 {
        A_REL_WIDEN * (self.a_max - self.a_min)
    }
}

/// Numbers the phase kinematics can be computed in: `f64` for a profile,
/// [`Surd`] for the polynomial equations of a family.
trait Algebra: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    /// The constant `v` in the algebra of `self`.
    fn constant(&self, v: f64) -> Self;
    /// `self * k`.
    fn times(&self, k: f64) -> Self;
}

impl Algebra for f64 {
    fn constant(&self, v: f64) -> f64 {
        v
    }
    fn times(&self, k: f64) -> f64 {
        self * k
    }
}

impl Algebra for Poly {
    fn constant(&self, v: f64) -> Poly {
        Poly::constant(v)
    }
    fn times(&self, k: f64) -> Poly {
        self.scale(k)
    }
}

impl Algebra for Surd {
    fn constant(&self, v: f64) -> Surd {
        Surd::constant(v, self.q)
    }
    fn times(&self, k: f64) -> Surd {
        self.scale(k)
    }
}

/// An "up" profile: P1 jerk `j_max` to `a_peak`, P2 hold `a_peak` for
/// `hold0`, P3 jerk `j_min` to `a_mid`, P4 hold for `cruise`, P5 jerk `j_min`
/// to `a_low`, P6 hold `a_low` for `hold1`, P7 jerk `j_max` to `a_f`.
/// Accelerations in m/s^2, times in s.
#[derive(Clone, Copy, Debug)]
struct Shape<T> {
    a_peak: T,
    hold0: T,
    a_mid: T,
    cruise: T,
    a_low: T,
    hold1: T,
}

impl<T: Algebra> Shape<T> {
    /// Durations of P1..P7 (s).
    fn durations(&self, pb: &Problem) -> [T; 7] {
        let a0 = self.a_peak.constant(pb.a0);
        let af = self.a_peak.constant(pb.af);
        [
            (self.a_peak - a0).times(1.0 / pb.j_max),
            self.hold0,
            (self.a_mid - self.a_peak).times(1.0 / pb.j_min),
            self.cruise,
            (self.a_low - self.a_mid).times(1.0 / pb.j_min),
            self.hold1,
            (af - self.a_low).times(1.0 / pb.j_max),
        ]
    }

    /// Position at the end of P7 (m).
    fn end_position(&self, pb: &Problem) -> T {
        let zero = self.a_peak.constant(0.0);
        let t = self.durations(pb);
        let mut p = zero.constant(pb.p0);
        let mut v = zero.constant(pb.v0);
        let mut a = zero.constant(pb.a0);
        for (ti, j) in t.into_iter().zip(up_jerks(pb)) {
            // Same closed form as `math::integrate`.
            p = p + ti * (v + ti * (a.times(0.5) + ti.times(j / 6.0)));
            v = v + ti * (a + ti.times(j / 2.0));
            a = a + ti.times(j);
        }
        p
    }
}

/// Jerks of P1..P7 of an "up" profile (m/s^3).
fn up_jerks(pb: &Problem) -> [f64; 7] {
    [pb.j_max, 0.0, pb.j_min, 0.0, pb.j_min, 0.0, pb.j_max]
}

/// Where P3 ends when P3 and P5 merge (no cruise): at `a = 0` if the merged
/// phase crosses it, so that P3 is the deceleration towards the velocity
/// extremum as in the velocity family.
fn split(a_peak: f64, a_low: f64) -> f64 {
    if a_low <= 0.0 && 0.0 <= a_peak {
        0.0
    } else {
        a_peak
    }
}

/// Integrate the shape into a profile and check it; `None` when a duration
/// is negative, a limit is exceeded or the target is missed.
fn build(pb: &Problem, s: &Shape<f64>) -> Option<Profile> {
    let mut t = s.durations(pb);
    let total: f64 = t.iter().map(|x| x.abs()).sum();
    if !total.is_finite() || total > T_MAX {
        return None;
    }
    for ti in &mut t {
        if *ti < -T_REL_TOL * total {
            return None;
        }
        *ti = ti.max(0.0);
    }
    let jerks = up_jerks(pb);
    let mut pr = Profile {
        pf: pb.pf,
        vf: pb.vf,
        af: pb.af,
        direction: Direction::Up,
        ..Profile::default()
    };
    pr.t = t;
    pr.p[0] = pb.p0;
    pr.v[0] = pb.v0;
    pr.a[0] = pb.a0;
    // The accelerations the phases are designed to end at: integration
    // rounds them (a P3 ending at 1e-15 instead of 0 drifts the velocity
    // of a long cruise out of its limit), so ends within rounding snap to them.
    let designed = [
        s.a_peak, s.a_peak, s.a_mid, s.a_mid, s.a_low, s.a_low, pb.af,
    ];
    let mut sum = 0.0;
    for i in 0..7 {
        sum += t[i];
        pr.t_sum[i] = sum;
        pr.j[i] = if t[i] > 0.0 { jerks[i] } else { 0.0 };
        let k = integrate(t[i], pr.p[i], pr.v[i], pr.a[i], pr.j[i]);
        pr.p[i + 1] = k.position;
        pr.v[i + 1] = k.velocity;
        if i == 2 && s.cruise > 0.0 {
            // P4 cruises at v_max by design; a rounding error of P1-P3 would
            // be multiplied by the cruise time (1e-13 m/s over 1e5 s).
            if (k.velocity - pb.v_max).abs() <= pb.v_round() {
                pr.v[3] = pb.v_max;
            }
        }
        let snap = A_SNAP * (1.0 + designed[i].abs());
        pr.a[i + 1] = if (k.acceleration - designed[i]).abs() <= snap {
            designed[i]
        } else {
            k.acceleration
        };
    }
    let a_tol = A_EPS * (1.0 + pb.a_max.max(-pb.a_min));
    if pr.a[1..7]
        .iter()
        .any(|&a| a > pb.a_max + a_tol || a < pb.a_min - a_tol)
    {
        return None;
    }
    // As in Ruckig's check, P1 and P2 are exempt: after a brake pre-phase the
    // velocity may still be outside its limits there, coming back inside.
    let v_slack = V_EPS.max(pb.v_round());
    let v_ok = |v: f64| v <= pb.v_max + v_slack && v >= pb.v_min - v_slack;
    if !pr.v[3..7].iter().all(|&v| v_ok(v)) {
        return None;
    }
    for i in 2..7 {
        if pr.j[i] != 0.0 && pr.a[i] * pr.a[i + 1] < 0.0 {
            // Velocity extremum where the acceleration crosses zero.
            if !v_ok(pr.v[i] - pr.a[i] * pr.a[i] / (2.0 * pr.j[i])) {
                return None;
            }
        }
    }
    // Beyond 10^6 m the absolute precision of f64 itself (1e-10 m) nears
    // the required 1e-8 m: there the position must match to 1e-14 of the
    // largest position the move passes (a brake pre-phase from far outside
    // the limits with a weak jerk can run for an hour).
    let p_scale = pr.p.iter().fold(0.0_f64, |m, p| m.max(p.abs()));
    let p_precision = P_PRECISION.max(P_REL_PRECISION * p_scale);
    let reached = (pr.p[7] - pb.pf).abs() < p_precision
        && (pr.v[7] - pb.vf).abs() < V_PRECISION
        && (pr.a[7] - pb.af).abs() < A_PRECISION;
    reached.then_some(pr)
}

/// The velocity family: P4 cruises at `v_max`. Closed form.
fn velocity_family(pb: &Problem, emit: &mut impl FnMut(&Shape<f64>)) {
    let k = pb.k();
    let d1 = pb.v_max - pb.v0 + pb.a0 * pb.a0 * 0.5 / pb.j_max;
    let d2 = pb.v_max - pb.vf + pb.af * pb.af * 0.5 / pb.j_max;
    if d1 < -pb.v_round() || d2 < -pb.v_round() {
        return;
    }
    let peak = (d1.max(0.0) / k).sqrt();
    let (a_peak, hold0) = if peak > pb.a_max {
        (pb.a_max, (d1 - k * pb.a_max * pb.a_max) / pb.a_max)
    } else {
        // A start exactly on the brake's boundary gives `peak = a0` up to
        // rounding; below `a0` P1 would be negative (an overshoot beyond
        // rounding fails the velocity check of the profile).
        (peak.max(pb.a0), 0.0)
    };
    let low = -(d2.max(0.0) / k).sqrt();
    let (a_low, hold1) = if low < pb.a_min {
        (pb.a_min, (k * pb.a_min * pb.a_min - d2) / pb.a_min)
    } else {
        (low.min(pb.af), 0.0)
    };
    let mut shape = Shape {
        a_peak,
        hold0,
        a_mid: 0.0,
        cruise: 0.0,
        a_low,
        hold1,
    };
    shape.cruise = (pb.pf - shape.end_position(pb)) / pb.v_max;
    emit(&shape);
}

/// Value of a component of a polynomial [`Shape`] at the unknown `x` (and
/// `y`, for the family that has one).
trait At {
    fn at(&self, x: f64, y: f64) -> f64;
}

impl At for Poly {
    fn at(&self, x: f64, _y: f64) -> f64 {
        self.eval(x)
    }
}

impl At for Surd {
    fn at(&self, x: f64, y: f64) -> f64 {
        self.a.eval(x) + y * self.b.eval(x)
    }
}

impl<T: At> Shape<T> {
    /// The profile shape at `x` (and `y`), P3 ending where [`split`] says.
    fn at(&self, x: f64, y: f64) -> Shape<f64> {
        let a_peak = self.a_peak.at(x, y);
        let a_low = self.a_low.at(x, y);
        Shape {
            a_peak,
            hold0: self.hold0.at(x, y),
            a_mid: split(a_peak, a_low),
            cruise: self.cruise.at(x, y),
            a_low,
            hold1: self.hold1.at(x, y),
        }
    }
}

/// A family without cruise: its shape as polynomials in the unknown `x`
/// (P3 and P5 merged: `a_mid = a_peak`) and the interval `x` is searched in.
struct Family<T> {
    shape: Shape<T>,
    lo: f64,
    hi: f64,
}

/// Neither acceleration limit held: `x = a_peak`, `y = a_low` with
/// `y^2 = x^2 - R/k` from the velocity condition.
fn neither_held(pb: &Problem) -> Family<Surd> {
    let q = Poly::x() * Poly::x() - Poly::constant(pb.r() / pb.k());
    let x = Surd::poly(Poly::x(), q);
    let zero = Surd::constant(0.0, q);
    Family {
        shape: Shape {
            a_peak: x,
            hold0: zero,
            a_mid: x,
            cruise: zero,
            a_low: Surd::y(q),
            hold1: zero,
        },
        lo: pb.a0 - pb.a_widen(),
        hi: pb.a_max + pb.a_widen(),
    }
}

/// `a_max` held in P2: `x = a_low`, `t2 = (R - k (a_max^2 - x^2)) / a_max`.
fn a_max_held(pb: &Problem) -> Family<Poly> {
    let (k, x, c) = (pb.k(), Poly::x(), Poly::constant);
    let hold0 = (x * x).times(k / pb.a_max) + c((pb.r() - k * pb.a_max * pb.a_max) / pb.a_max);
    Family {
        shape: Shape {
            a_peak: c(pb.a_max),
            hold0,
            a_mid: c(pb.a_max),
            cruise: c(0.0),
            a_low: x,
            hold1: c(0.0),
        },
        lo: pb.a_min - pb.a_widen(),
        hi: pb.a_max.min(pb.af) + pb.a_widen(),
    }
}

/// `a_min` held in P6: `x = a_peak`, `t6 = (R - k (x^2 - a_min^2)) / a_min`.
fn a_min_held(pb: &Problem) -> Family<Poly> {
    let (k, x, c) = (pb.k(), Poly::x(), Poly::constant);
    let hold1 = (x * x).times(-k / pb.a_min) + c((pb.r() + k * pb.a_min * pb.a_min) / pb.a_min);
    Family {
        shape: Shape {
            a_peak: x,
            hold0: c(0.0),
            a_mid: x,
            cruise: c(0.0),
            a_low: c(pb.a_min),
            hold1,
        },
        lo: pb.a0.max(pb.a_min) - pb.a_widen(),
        hi: pb.a_max + pb.a_widen(),
    }
}

/// Both held: `x = t2`, `t6 = (R - k (a_max^2 - a_min^2) - a_max x) / a_min`;
/// `t6 >= 0` needs `a_max x >= R - k (a_max^2 - a_min^2)`.
fn both_held(pb: &Problem) -> Family<Poly> {
    let (x, c) = (Poly::x(), Poly::constant);
    let rest = pb.r() - pb.k() * (pb.a_max * pb.a_max - pb.a_min * pb.a_min);
    let lo = (rest / pb.a_max).max(0.0);
    Family {
        shape: Shape {
            a_peak: c(pb.a_max),
            hold0: x,
            a_mid: c(pb.a_max),
            cruise: c(0.0),
            a_low: c(pb.a_min),
            hold1: x.times(-pb.a_max / pb.a_min) + c(rest / pb.a_min),
        },
        lo,
        hi: lo + T_MAX,
    }
}

/// The families without cruise: every root of their position condition is
/// a candidate.
fn position_families(pb: &Problem, emit: &mut impl FnMut(&Shape<f64>)) {
    let fam = neither_held(pb);
    let f = fam.shape.end_position(pb).plus(-pb.pf).eliminate_y();
    let q = fam.shape.a_low.q;
    let widen = pb.a_widen();
    for &x in real_roots(&f, fam.lo, fam.hi).as_slice() {
        let qx = q.eval(x);
        if qx < -widen * widen {
            continue;
        }
        let root = qx.max(0.0).sqrt();
        for y in [root, -root] {
            emit(&fam.shape.at(x, y));
        }
    }
    for fam in [a_max_held(pb), a_min_held(pb), both_held(pb)] {
        let f = fam.shape.end_position(pb) - Poly::constant(pb.pf);
        for &x in real_roots(&f, fam.lo, fam.hi).as_slice() {
            emit(&fam.shape.at(x, 0.0));
        }
    }
}

/// The shortest valid profile of the "up" direction of `pb`, if any.
fn best_up(pb: &Problem) -> Option<Profile> {
    let mut best: Option<Profile> = None;
    let mut consider = |s: &Shape<f64>| {
        if let Some(p) = build(pb, s) {
            if best.is_none_or(|b| p.t_sum[6] < b.t_sum[6]) {
                best = Some(p);
            }
        }
    };
    velocity_family(pb, &mut consider);
    position_families(pb, &mut consider);
    best
}

/// Mirror a profile of the mirrored problem back.
fn unmirror(mut p: Profile) -> Profile {
    for x in p.j.iter_mut() {
        *x = -*x;
    }
    for arr in [&mut p.a, &mut p.v, &mut p.p] {
        for x in arr.iter_mut() {
            *x = -*x;
        }
    }
    p.pf = -p.pf;
    p.vf = -p.vf;
    p.af = -p.af;
    p.direction = Direction::Down;
    p
}

/// The time-optimal profile from the (braked) start of `pb` to its target,
/// or `None` if no candidate passes the check (the brake pre-phase is left
/// at its default; the caller sets it).
pub(crate) fn time_optimal_profile(pb: &Problem) -> Option<Profile> {
    let up = best_up(pb);
    let down = best_up(&pb.mirrored()).map(unmirror);
    match (up, down) {
        (Some(u), Some(d)) => Some(if d.t_sum[6] < u.t_sum[6] { d } else { u }),
        (u, d) => u.or(d),
    }
}

#[cfg(test)]
mod tests;
