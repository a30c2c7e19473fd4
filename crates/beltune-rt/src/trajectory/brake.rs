//! The brake pre-phase: bring a start state that violates (or will
//! inevitably violate) the velocity or acceleration limits back inside them
//! with at most two constant-jerk segments, before the seven phases P1-P7.
//!
//! Ported from Ruckig's `BrakeProfile::get_position_brake_trajectory`
//! (via rsruckig 3.0.1).
//! Copyright (c) 2021 Lars Berscheid (Ruckig), Petri Koskinen (rsruckig);
//! MIT License, full notice in `trajectory/mod.rs`.

use super::math::integrate;
// In `cfg(test)` builds std is linked and its inherent `f64` methods shadow
// these `libm` ones, so the import is then unused.
#[cfg_attr(test, allow(unused_imports))]
use super::math::F64Math;

/// Small time added/subtracted so that the brake ends strictly inside the limits.
const EPS: f64 = 2.2e-14;

#[inline]
fn v_at_t(v0: f64, a0: f64, j: f64, t: f64) -> f64 {
    v0 + t * (a0 + j * t / 2.0)
}

/// Velocity (m/s) once the acceleration `a0` has been ramped to zero with jerk `j`.
#[inline]
pub(crate) fn v_at_a_zero(v0: f64, a0: f64, j: f64) -> f64 {
    v0 + (a0 * a0) / (2.0 * j)
}

/// Up to two constant-jerk segments before P1; `duration == 0` when the start
/// state is admissible.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct BrakePhase {
    /// Total duration of the brake pre-phase in s.
    pub duration: f64,
    /// Segment durations in s.
    pub t: [f64; 2],
    /// Segment jerks in m/s^3.
    pub j: [f64; 2],
    /// Acceleration at the start of each segment in m/s^2.
    pub a: [f64; 2],
    /// Velocity at the start of each segment in m/s.
    pub v: [f64; 2],
    /// Position at the start of each segment in m.
    pub p: [f64; 2],
}

impl BrakePhase {
    /// `j_pull` is the jerk that pulls the acceleration back, with the sign
    /// convention of the reference (`j[0] = -j_pull`): `-j_min` for a start
    /// above the limits, `-j_max` below. `j_back` is the jerk that later
    /// returns the acceleration to zero, in the same convention (`j_max`
    /// above, `j_min` below); with symmetric jerk `j_back = j_pull`.
    #[allow(clippy::too_many_arguments)]
    fn acceleration_brake(
        &mut self,
        v0: f64,
        a0: f64,
        v_max: f64,
        v_min: f64,
        a_max: f64,
        a_min: f64,
        j_pull: f64,
        j_back: f64,
    ) {
        self.j[0] = -j_pull;

        let t_to_a_max = (a0 - a_max) / j_pull;
        let t_to_a_zero = a0 / j_pull;

        let v_at_a_max = v_at_t(v0, a0, -j_pull, t_to_a_max);
        let v_at_a_zero = v_at_t(v0, a0, -j_pull, t_to_a_zero);

        if (v_at_a_zero > v_max && j_pull > 0.0) || (v_at_a_zero < v_max && j_pull < 0.0) {
            self.velocity_brake(v0, a0, v_max, v_min, a_min, j_pull, j_back);
        } else if (v_at_a_max < v_min && j_pull > 0.0) || (v_at_a_max > v_min && j_pull < 0.0) {
            let t_to_v_min = -(v_at_a_max - v_min) / a_max;
            let t_to_v_max = -a_max / (2.0 * j_pull) - (v_at_a_max - v_max) / a_max;

            self.t[0] = t_to_a_max + EPS;
            self.t[1] = t_to_v_min.min((t_to_v_max - EPS).max(0.0));
        } else {
            self.t[0] = t_to_a_max + EPS;
        }
    }

    /// Jerks as in [`Self::acceleration_brake`].
    #[allow(clippy::too_many_arguments)]
    fn velocity_brake(
        &mut self,
        v0: f64,
        a0: f64,
        v_max: f64,
        v_min: f64,
        a_min: f64,
        j_pull: f64,
        j_back: f64,
    ) {
        self.j[0] = -j_pull;
        let t_to_a_min = (a0 - a_min) / j_pull;
        let t_to_v_max =
            a0 / j_pull + (a0 * a0 + 2.0 * j_pull * (v0 - v_max)).sqrt() / j_pull.abs();
        // Pull for t, then return the acceleration to zero with `j_back`,
        // ending at v_min: `(j_pull/2) t^2 - a0 t + (v_min - v0 + a0^2/(2 j_back))
        // / (1 + j_pull/j_back) = 0`; with `j_back = j_pull` this is the
        // reference's `a0/j + sqrt(a0^2/2 + j (v0 - v_min))/|j|`.
        let t_to_v_min = if j_back == j_pull {
            a0 / j_pull + (a0 * a0 / 2.0 + j_pull * (v0 - v_min)).sqrt() / j_pull.abs()
        } else {
            let c = (v_min - v0 + a0 * a0 / (2.0 * j_back)) / (1.0 + j_pull / j_back);
            a0 / j_pull + (a0 * a0 - 2.0 * j_pull * c).sqrt() / j_pull.abs()
        };
        let t_min_to_v_max = t_to_v_max.min(t_to_v_min);

        if t_to_a_min < t_min_to_v_max {
            let v_at_a_min = v_at_t(v0, a0, -j_pull, t_to_a_min);
            let t_to_v_max_with_constant = -(v_at_a_min - v_max) / a_min;
            let t_to_v_min_with_constant = a_min / (2.0 * j_back) - (v_at_a_min - v_min) / a_min;

            self.t[0] = (t_to_a_min - EPS).max(0.0);
            self.t[1] = t_to_v_max_with_constant
                .min(t_to_v_min_with_constant)
                .max(0.0);
        } else {
            self.t[0] = (t_min_to_v_max - EPS).max(0.0);
        }
    }

    /// Plan the brake segments for a start `(v0, a0)` and the limits
    /// (`j_min < 0 < j_max`); all limits must be non-zero (checked by the
    /// caller). With `j_min = -j_max` this is exactly the reference's brake.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn plan(
        v0: f64,
        a0: f64,
        v_max: f64,
        v_min: f64,
        a_max: f64,
        a_min: f64,
        j_max: f64,
        j_min: f64,
    ) -> Self {
        let mut b = Self::default();
        if a0 > a_max {
            b.acceleration_brake(v0, a0, v_max, v_min, a_max, a_min, -j_min, j_max);
        } else if a0 < a_min {
            b.acceleration_brake(v0, a0, v_min, v_max, a_min, a_max, -j_max, j_min);
        } else if (v0 > v_max && v_at_a_zero(v0, a0, -j_max) > v_min)
            || (a0 > 0.0 && v_at_a_zero(v0, a0, -j_min) > v_max)
        {
            b.velocity_brake(v0, a0, v_max, v_min, a_min, -j_min, j_max);
        } else if (v0 < v_min && v_at_a_zero(v0, a0, -j_min) < v_max)
            || (a0 < 0.0 && v_at_a_zero(v0, a0, -j_max) < v_min)
        {
            b.velocity_brake(v0, a0, v_min, v_max, a_max, -j_max, j_min);
        }
        b
    }

    /// Record the start state of each segment and advance `(p, v, a)` to the
    /// end of the brake pre-phase.
    pub(crate) fn finalize(&mut self, p: &mut f64, v: &mut f64, a: &mut f64) {
        if self.t[0] <= 0.0 && self.t[1] <= 0.0 {
            self.duration = 0.0;
            return;
        }
        self.duration = 0.0;
        for i in 0..2 {
            if i == 1 && self.t[1] <= 0.0 {
                break;
            }
            self.duration += self.t[i];
            self.p[i] = *p;
            self.v[i] = *v;
            self.a[i] = *a;
            let k = integrate(self.t[i], *p, *v, *a, self.j[i]);
            *p = k.position;
            *v = k.velocity;
            *a = k.acceleration;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Slack for the `EPS` margins of the brake and rounding.
    const LIMIT_TOL: f64 = 1e-9;

    #[test]
    fn admissible_start_needs_no_brake() {
        let b = BrakePhase::plan(0.5, 1.0, 5.0, -5.0, 45.0, -45.0, 40.0, -40.0);
        assert_eq!(b.t, [0.0, 0.0]);
    }

    #[test]
    fn brake_ends_inside_the_limits() {
        // Too fast and too strongly accelerating (v > v_max, a > a_max), with
        // symmetric jerk and with the jerk downwards 3x weaker or stronger.
        let (v_max, v_min, a_max, a_min, j_max) = (5.0, -4.0, 45.0, -30.0, 40.0);
        for j_min in [-j_max, -j_max / 3.0, -3.0 * j_max] {
            for &(v0, a0) in &[
                (7.0, 0.0),
                (4.0, 60.0),
                (-8.0, -10.0),
                (0.0, -70.0),
                (4.9, 20.0),
            ] {
                let mut b = BrakePhase::plan(v0, a0, v_max, v_min, a_max, a_min, j_max, j_min);
                let (mut p, mut v, mut a) = (0.0, v0, a0);
                b.finalize(&mut p, &mut v, &mut a);
                assert!(b.duration > 0.0, "start ({v0}, {a0}) needs a brake");
                assert!(a <= a_max + LIMIT_TOL && a >= a_min - LIMIT_TOL, "a = {a}");
                for j in b.j {
                    assert!(j == 0.0 || j == j_max || j == j_min, "jerk {j}");
                }
                // The brake may end with v still outside, but then returning
                // so that ramping a to 0 (with +j_max from a < 0, with j_min
                // from a > 0) ends inside.
                let v_up = v_at_a_zero(v, a, -j_max); // a < 0 ramped up
                let v_down = v_at_a_zero(v, a, -j_min); // a > 0 ramped down
                if v > v_max + LIMIT_TOL {
                    assert!(a < 0.0 && v_up <= v_max + LIMIT_TOL, "v = {v}, a = {a}");
                }
                if v < v_min - LIMIT_TOL {
                    assert!(a > 0.0 && v_down >= v_min - LIMIT_TOL, "v = {v}, a = {a}");
                }
                if a > 0.0 && v <= v_max {
                    assert!(v_down <= v_max + LIMIT_TOL, "({v0}, {a0}), j_min {j_min}");
                } else if a < 0.0 && v >= v_min {
                    assert!(v_up >= v_min - LIMIT_TOL, "({v0}, {a0}), j_min {j_min}");
                }
            }
        }
    }
}
