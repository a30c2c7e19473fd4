//! A seven-phase jerk-limited profile (Figure 6.11: P1-P7 with jerk
//! `+-j_max` or 0 in each phase: Ruckig's step 1, symmetric jerk) and its
//! admissibility check; the general solver (`asymmetric.rs`) fills the same
//! struct with `j_max`, `j_min` or 0.
//!
//! Ported from Ruckig's `Profile::check` (via rsruckig 3.0.1).
//! Copyright (c) 2021 Lars Berscheid (Ruckig), Petri Koskinen (rsruckig);
//! MIT License, full notice in `trajectory/mod.rs`.

use super::brake::BrakePhase;
use super::math::integrate;
// In `cfg(test)` builds std is linked and its inherent `f64` methods shadow
// these `libm` ones, so the import is then unused.
#[cfg_attr(test, allow(unused_imports))]
use super::math::F64Math;

/// Slack on the velocity limits (m/s).
pub(crate) const V_EPS: f64 = 1e-12;
/// Slack on the acceleration limits (m/s^2).
pub(crate) const A_EPS: f64 = 1e-12;

/// Final position must match the target to this (m).
pub(crate) const P_PRECISION: f64 = 1e-8;
/// Final velocity must match the target to this (m/s).
pub(crate) const V_PRECISION: f64 = 1e-8;
/// Final acceleration must match the target to this (m/s^2).
pub(crate) const A_PRECISION: f64 = 1e-10;

/// Longest admissible profile (s).
pub(crate) const T_MAX: f64 = 1e12;

/// Which limits a profile family reaches: `Acc0` = acceleration limit held in
/// P2, `Acc1` = in P6, `Vel` = velocity limit held in P4.
#[derive(Debug, Default, PartialEq, Eq, Clone, Copy)]
pub(crate) enum ReachedLimits {
    Vel,
    Acc0,
    Acc1,
    Acc0Acc1,
    Acc1Vel,
    #[default]
    None,
}

/// Direction of the move (which of `v_max`/`v_min` bounds the cruise).
#[derive(Debug, Default, PartialEq, Eq, Clone, Copy)]
pub(crate) enum Direction {
    #[default]
    Up,
    Down,
}

/// Jerk sign pattern over P1, P3, P5, P7: every time-optimal profile of
/// step 1 is up-down-down-up (`+j, -j, -j, +j`).
#[derive(Debug, Default, PartialEq, Eq, Clone, Copy)]
pub(crate) enum ControlSigns {
    #[default]
    UpDownDownUp,
}

/// Lowest and highest position of a profile (m) and when they occur (s).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PositionBounds {
    pub min: f64,
    pub max: f64,
}

/// Phase durations, jerks and the boundary states of each phase.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Profile {
    /// Duration of P1..P7 in s.
    pub t: [f64; 7],
    /// Time at the end of P1..P7 in s (without the brake pre-phase).
    pub t_sum: [f64; 7],
    /// Jerk in P1..P7 in m/s^3.
    pub j: [f64; 7],
    /// Acceleration at the start of P1..P7 and at the end (m/s^2).
    pub a: [f64; 8],
    /// Velocity at the start of P1..P7 and at the end (m/s).
    pub v: [f64; 8],
    /// Position at the start of P1..P7 and at the end (m).
    pub p: [f64; 8],
    /// Brake pre-phase before P1.
    pub brake: BrakePhase,
    /// Target position (m).
    pub pf: f64,
    /// Target velocity (m/s).
    pub vf: f64,
    /// Target acceleration (m/s^2).
    pub af: f64,
    pub limits: ReachedLimits,
    pub direction: Direction,
    pub control_signs: ControlSigns,
}

impl Profile {
    /// Accumulate the phase times, integrate the phases and check that the
    /// profile ends in the target and respects the velocity and acceleration
    /// limits.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn check(
        &mut self,
        control_signs: ControlSigns,
        limits: ReachedLimits,
        set_limits: bool,
        jf: f64,
        v_max: f64,
        v_min: f64,
        a_max: f64,
        a_min: f64,
    ) -> bool {
        if self.t[0] < 0.0 {
            return false;
        }

        self.t_sum[0] = self.t[0];
        for i in 0..6 {
            if self.t[i + 1] < 0.0 {
                return false;
            }
            self.t_sum[i + 1] = self.t_sum[i] + self.t[i + 1];
        }

        if matches!(limits, ReachedLimits::Acc1Vel | ReachedLimits::Vel) && self.t[3] < f64::EPSILON
        {
            return false;
        }

        if matches!(limits, ReachedLimits::Acc0 | ReachedLimits::Acc0Acc1)
            && self.t[1] < f64::EPSILON
        {
            return false;
        }

        if matches!(limits, ReachedLimits::Acc1 | ReachedLimits::Acc0Acc1)
            && self.t[5] < f64::EPSILON
        {
            return false;
        }

        if self.t_sum[6] > T_MAX {
            return false;
        }

        self.j = [
            if self.t[0] > 0.0 { jf } else { 0.0 },
            0.0,
            if self.t[2] > 0.0 { -jf } else { 0.0 },
            0.0,
            if self.t[4] > 0.0 { -jf } else { 0.0 },
            0.0,
            if self.t[6] > 0.0 { jf } else { 0.0 },
        ];

        self.direction = if v_max > 0.0 {
            Direction::Up
        } else {
            Direction::Down
        };

        let v_upp_lim = if self.direction == Direction::Up {
            v_max
        } else {
            v_min
        } + V_EPS;
        let v_low_lim = if self.direction == Direction::Up {
            v_min
        } else {
            v_max
        } - V_EPS;

        for i in 0..7 {
            self.a[i + 1] = self.a[i] + self.t[i] * self.j[i];
            self.v[i + 1] = self.v[i] + self.t[i] * (self.a[i] + self.t[i] * self.j[i] / 2.0);
            self.p[i + 1] = self.p[i]
                + self.t[i]
                    * (self.v[i] + self.t[i] * (self.a[i] / 2.0 + self.t[i] * self.j[i] / 6.0));

            if matches!(
                limits,
                ReachedLimits::Acc0Acc1 | ReachedLimits::Acc1Vel | ReachedLimits::Vel
            ) && i == 2
            {
                self.a[3] = 0.0;
            }

            if set_limits {
                match limits {
                    ReachedLimits::Acc1 if i == 2 => {
                        self.a[3] = a_min;
                    }
                    ReachedLimits::Acc0Acc1 => {
                        if i == 0 {
                            self.a[1] = a_max;
                        }
                        if i == 4 {
                            self.a[5] = a_min;
                        }
                    }
                    _ => {}
                }
            }

            if i > 1 && self.a[i + 1] * self.a[i] < -f64::EPSILON {
                let v_a_zero = self.v[i] - (self.a[i] * self.a[i]) / (2.0 * self.j[i]);
                if v_a_zero > v_upp_lim || v_a_zero < v_low_lim {
                    return false;
                }
            }
        }

        self.control_signs = control_signs;
        self.limits = limits;

        let a_upp_lim = if self.direction == Direction::Up {
            a_max
        } else {
            a_min
        } + A_EPS;
        let a_low_lim = if self.direction == Direction::Up {
            a_min
        } else {
            a_max
        } - A_EPS;

        (self.p[7] - self.pf).abs() < P_PRECISION
            && (self.v[7] - self.vf).abs() < V_PRECISION
            && (self.a[7] - self.af).abs() < A_PRECISION
            && self.a[1] >= a_low_lim
            && self.a[1] <= a_upp_lim
            && self.a[3] >= a_low_lim
            && self.a[3] <= a_upp_lim
            && self.a[5] >= a_low_lim
            && self.a[5] <= a_upp_lim
            && self.v[3] <= v_upp_lim
            && self.v[3] >= v_low_lim
            && self.v[4] <= v_upp_lim
            && self.v[4] >= v_low_lim
            && self.v[5] <= v_upp_lim
            && self.v[5] >= v_low_lim
            && self.v[6] <= v_upp_lim
            && self.v[6] >= v_low_lim
    }

    /// [`Self::check`] without forcing the reached limits.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn check_with_timing(
        &mut self,
        control_signs: ControlSigns,
        limits: ReachedLimits,
        jf: f64,
        v_max: f64,
        v_min: f64,
        a_max: f64,
        a_min: f64,
    ) -> bool {
        self.check(control_signs, limits, false, jf, v_max, v_min, a_max, a_min)
    }

    /// Copy the boundary states (and brake pre-phase) of `profile`.
    #[inline]
    pub(crate) fn set_boundary_from_profile(&mut self, profile: &Profile) {
        self.a[0] = profile.a[0];
        self.v[0] = profile.v[0];
        self.p[0] = profile.p[0];
        self.af = profile.af;
        self.vf = profile.vf;
        self.pf = profile.pf;
        self.brake = profile.brake;
    }

    /// Total duration including the brake pre-phase (s).
    #[inline]
    pub(crate) fn total_duration(&self) -> f64 {
        self.t_sum[6] + self.brake.duration
    }

    fn include_segment_extrema(t: f64, p: f64, v: f64, a: f64, j: f64, ext: &mut PositionBounds) {
        ext.min = ext.min.min(p);
        ext.max = ext.max.max(p);
        // Interior extrema where v(tau) = v + a tau + j tau^2 / 2 = 0.
        let mut check = |tau: f64| {
            if 0.0 < tau && tau < t {
                let k = integrate(tau, p, v, a, j);
                ext.min = ext.min.min(k.position);
                ext.max = ext.max.max(k.position);
            }
        };
        if j != 0.0 {
            let d = a * a - 2.0 * j * v;
            if d.abs() < f64::EPSILON {
                check(-a / j);
            } else if d > 0.0 {
                let d_sqrt = d.sqrt();
                check((-a - d_sqrt) / j);
                check((-a + d_sqrt) / j);
            }
        } else if a != 0.0 {
            check(-v / a);
        }
    }

    /// Lowest and highest position over the brake pre-phase, P1-P7 and the end.
    pub(crate) fn position_bounds(&self) -> PositionBounds {
        let mut ext = PositionBounds {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        };
        if self.brake.duration > 0.0 {
            for i in 0..2 {
                if self.brake.t[i] > 0.0 {
                    let b = &self.brake;
                    Self::include_segment_extrema(b.t[i], b.p[i], b.v[i], b.a[i], b.j[i], &mut ext);
                }
            }
        }
        for i in 0..7 {
            Self::include_segment_extrema(
                self.t[i], self.p[i], self.v[i], self.a[i], self.j[i], &mut ext,
            );
        }
        ext.min = ext.min.min(self.p[7]);
        ext.max = ext.max.max(self.p[7]);
        ext
    }
}
