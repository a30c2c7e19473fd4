//! Jerk-limited, time-optimal trajectory generator for one axis (thesis 6.3,
//! Figure 6.11).
//!
//! A move from any start state `(position, velocity, acceleration)` to any
//! admissible target state is planned once ([`Trajectory::plan`], no
//! allocation) and then sampled every `T_s` ([`Trajectory::sample`]). The
//! profile has the seven phases P1-P7 of Figure 6.11 with jerk `j_max`, `j_min` or 0
//! in each; limits may be asymmetric (`v_min < 0 < v_max`,
//! `a_min < 0 < a_max`, `j_min < 0 < j_max`). A start state
//! that violates (or will inevitably violate) the velocity or acceleration
//! limits is first brought back inside them by a brake pre-phase of at most
//! two constant-jerk segments. Position limits are checked: a target outside
//! is [`Error::TargetOutsideLimits`], a planned move whose position extrema
//! leave them is [`Error::PositionLimitsViolated`].
//!
//! Units: positions in m (or rad for a rotary axis), velocities in m/s,
//! accelerations in m/s^2, jerks in m/s^3, times in s.
//!
//! ```
//! use beltune_rt::trajectory::{Limits, State, Trajectory};
//!
//! // Thesis 6.3: 0 -> 0.5 m with the limits of Table A.8.
//! let limits = Limits { position_min: -0.01, position_max: 0.57, ..Limits::default() };
//! let traj = Trajectory::plan(&State::at_rest(0.0), &State::at_rest(0.5), &limits)?;
//! assert!((traj.duration_s() - 0.7368063).abs() < 1e-6);
//! // In the 100 us interrupt: the desired state of sample k.
//! let ts = 1e-4;
//! let k = 1234;
//! let desired = traj.sample(k as f64 * ts);
//! assert!(desired.velocity > 0.0 && desired.jerk.abs() <= 40.0);
//! # Ok::<(), beltune_rt::Error>(())
//! ```
//!
//! Two solvers find the seven phases. For symmetric jerk limits
//! (`j_min = -j_max`) the closed forms of Ruckig (`step1.rs`, a port); they are
//! bit-identical to the reference rsruckig. For asymmetric jerk, where no
//! closed forms exist, the general solver of `asymmetric.rs`: the same profile
//! families, each reduced to one polynomial equation whose real roots are all
//! taken (about 60,000 instructions per plan against 4,400). It reproduces
//! rsruckig on the symmetric test cases too (`tests/trajectory_vs_ruckig.rs`),
//! and its asymmetric plans are checked for invariances and against a
//! discretized linear program (`tests/trajectory_asymmetric.rs`,
//! `tests/discrete_lp_oracle.rs`).
//!
//! | file | step |
//! | --- | --- |
//! | `brake.rs` | brake pre-phase for start states outside the limits |
//! | `step1.rs` | the extremal (time-optimal) profile families, symmetric jerk |
//! | `roots.rs` | roots of the quartics of step 1 |
//! | `asymmetric.rs` | the same families for `j_min != -j_max` |
//! | `poly.rs` | polynomial arithmetic and real roots for `asymmetric.rs` |
//! | `profile.rs` | a seven-phase profile and its admissibility check |
//! | `block.rs` | choice of the fastest valid profile |
//! | `math.rs` | integration of a constant-jerk phase, `libm` helpers |
//! | `single.rs` | sampling a planned move in `f32` ([`TrajectoryF32`]) |
//!
//! ## Attribution
//!
//! The step-1 equations, the brake pre-phase, the profile check, the quartic
//! solver and the profile selection are a no_std, allocation-free port of
//! Ruckig's 1-DOF position algorithm (Berscheid and Kroeger, "Jerk-limited
//! Real-time Trajectory Generation with Arbitrary Target States", RSS 2021)
//! from its Rust port rsruckig 3.0.1, under the MIT License (Ruckig has no
//! asymmetric jerk limits: `asymmetric.rs` and `poly.rs` are this project's own,
//! and the brake takes the jerk of each direction from `j_max`/`j_min`):
//!
//! ```text
//! MIT License
//!
//! Copyright (c) 2021 Lars Berscheid
//! Copyright (c) 2023 Petri Koskinen (rsruckig)
//!
//! Permission is hereby granted, free of charge, to any person obtaining a copy
//! of this software and associated documentation files (the "Software"), to deal
//! in the Software without restriction, including without limitation the rights
//! to use, copy, modify, merge, publish, distribute, sublicense, and/or sell
//! copies of the Software, and to permit persons to whom the Software is
//! furnished to do so, subject to the following conditions:
//!
//! The above copyright notice and this permission notice shall be included in all
//! copies or substantial portions of the Software.
//!
//! THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
//! IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
//! FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
//! AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
//! LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
//! OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
//! SOFTWARE.
//! ```

mod approach;
mod asymmetric;
mod block;
mod brake;
mod math;
mod poly;
mod profile;
mod roots;
mod single;
mod step1;

pub use approach::{Approach, ApproachConfig, CREEP_RAMP_S};
pub use single::{SampleF32, TrajectoryF32};

use crate::error::{finite, positive};
use crate::Error;
use asymmetric::{time_optimal_profile, Problem};
use block::Block;
use brake::{v_at_a_zero, BrakePhase};
use math::integrate;
use profile::{Profile, A_PRECISION, P_PRECISION, V_PRECISION};
use step1::ExtremalProfiles;

/// Tolerance (m) with which the planned position extrema may touch the
/// position limits: the profile check only guarantees the final position to
/// 1e-8 m, so a move that ends exactly on a limit must not be rejected.
const POSITION_LIMIT_TOL: f64 = 1e-8;

/// Which step-1 solver plans the move.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Solver {
    /// Ruckig's closed forms for symmetric jerk, the general one otherwise.
    Auto,
    /// The general solver of `asymmetric.rs` always.
    General,
}

/// No candidate profile passed the check.
const NO_PROFILE: Error = Error::Infeasible {
    reason: "no time-optimal profile found (numerically degenerate request)",
};

/// A kinematic state of the axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct State {
    /// Position in m (or rad).
    pub position: f64,
    /// Velocity in m/s (or rad/s).
    pub velocity: f64,
    /// Acceleration in m/s^2 (or rad/s^2).
    pub acceleration: f64,
}

impl State {
    /// A state at rest at `position`.
    pub fn at_rest(position: f64) -> Self {
        Self {
            position,
            velocity: 0.0,
            acceleration: 0.0,
        }
    }
}

/// Kinematic limits of a move. Validated by [`Trajectory::plan`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Highest velocity, m/s, finite and `> 0`.
    pub v_max: f64,
    /// Lowest velocity, m/s, finite and `< 0`.
    pub v_min: f64,
    /// Highest acceleration, m/s^2, finite and `> 0`.
    pub a_max: f64,
    /// Lowest acceleration, m/s^2, finite and `< 0`.
    pub a_min: f64,
    /// Highest jerk, m/s^3, finite and `> 0`.
    pub j_max: f64,
    /// Lowest jerk, m/s^3, finite and `< 0` (`-j_max` for symmetric limits).
    pub j_min: f64,
    /// Lowest admissible position, m (may be `-inf`).
    pub position_min: f64,
    /// Highest admissible position, m (may be `+inf`, `>= position_min`).
    pub position_max: f64,
}

impl Limits {
    /// Symmetric limits `+-v_max`, `+-a_max`, `+-j_max` without position limits.
    pub fn symmetric(v_max: f64, a_max: f64, j_max: f64) -> Self {
        Self {
            v_max,
            v_min: -v_max,
            a_max,
            a_min: -a_max,
            j_max,
            j_min: -j_max,
            position_min: f64::NEG_INFINITY,
            position_max: f64::INFINITY,
        }
    }

    fn validate(&self) -> Result<(), Error> {
        positive("v_max", self.v_max)?;
        positive("-v_min", -self.v_min)?;
        positive("a_max", self.a_max)?;
        positive("-a_min", -self.a_min)?;
        positive("j_max", self.j_max)?;
        positive("-j_min", -self.j_min)?;
        if self.position_min.is_nan() || self.position_max.is_nan() {
            return Err(Error::InvalidParameter {
                name: "position limits",
                reason: "must not be NaN",
            });
        }
        if self.position_min > self.position_max {
            return Err(Error::InvalidParameter {
                name: "position limits",
                reason: "position_min must be <= position_max",
            });
        }
        Ok(())
    }
}

impl Default for Limits {
    /// The limits of thesis Table A.8 (`v` 5 m/s, `a` 45 m/s^2, `j` 40 m/s^3,
    /// symmetric) without position limits.
    fn default() -> Self {
        Self::symmetric(5.0, 45.0, 40.0)
    }
}

/// The desired state and jerk at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    /// Position in m.
    pub position: f64,
    /// Velocity in m/s.
    pub velocity: f64,
    /// Acceleration in m/s^2.
    pub acceleration: f64,
    /// Jerk in m/s^3.
    pub jerk: f64,
}

/// Durations and jerks of the phases of a planned move.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Phases {
    /// Durations of the (at most two) brake pre-phase segments, s; zero when
    /// the start state is admissible.
    pub brake_durations_s: [f64; 2],
    /// Jerks of the brake pre-phase segments, m/s^3.
    pub brake_jerks_m_s3: [f64; 2],
    /// Durations of P1..P7 (Figure 6.11), s.
    pub durations_s: [f64; 7],
    /// Jerks in P1..P7, m/s^3 (`j_max`, `j_min` or 0).
    pub jerks_m_s3: [f64; 7],
}

/// Lowest and highest position reached by a planned move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionRange {
    /// Lowest position, m.
    pub lowest: f64,
    /// Highest position, m.
    pub highest: f64,
}

/// Reusable scratch space of the planner: the candidate profiles of step 1,
/// the selected one and the boundary (about 4 kB). [`Trajectory::plan`]
/// builds a fresh one per call; keeping one and calling [`Planner::plan`]
/// avoids initializing it on every plan (the plans are the same either way,
/// checked against rsruckig in `tests/trajectory_vs_ruckig.rs`).
///
/// ```
/// use beltune_rt::trajectory::{Limits, Planner, State};
///
/// let mut planner = Planner::default();
/// let limits = Limits::default();
/// let a = planner.plan(&State::at_rest(0.0), &State::at_rest(0.5), &limits)?;
/// let b = planner.plan(&State::at_rest(0.5), &State::at_rest(0.0), &limits)?;
/// assert_eq!(a.duration_s(), b.duration_s());
/// # Ok::<(), beltune_rt::Error>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct Planner {
    step1: ExtremalProfiles,
    block: Block,
    input: Profile,
}

impl Planner {
    /// Plan the time-optimal jerk-limited move from `start` to `target`,
    /// reusing this planner's scratch space; errors as [`Trajectory::plan`].
    pub fn plan(
        &mut self,
        start: &State,
        target: &State,
        limits: &Limits,
    ) -> Result<Trajectory, Error> {
        self.plan_with(start, target, limits, Solver::Auto)
    }

    fn plan_with(
        &mut self,
        start: &State,
        target: &State,
        limits: &Limits,
        solver: Solver,
    ) -> Result<Trajectory, Error> {
        finite("start.position", start.position)?;
        finite("start.velocity", start.velocity)?;
        finite("start.acceleration", start.acceleration)?;
        finite("target.position", target.position)?;
        finite("target.velocity", target.velocity)?;
        finite("target.acceleration", target.acceleration)?;
        limits.validate()?;
        let Limits {
            v_max,
            v_min,
            a_max,
            a_min,
            j_max,
            j_min,
            position_min,
            position_max,
        } = *limits;
        let (pf, vf, af) = (target.position, target.velocity, target.acceleration);
        if af > a_max || af < a_min {
            return Err(Error::Infeasible {
                reason: "target acceleration outside [a_min, a_max]",
            });
        }
        if vf > v_max || vf < v_min {
            return Err(Error::Infeasible {
                reason: "target velocity outside [v_min, v_max]",
            });
        }
        // A target with a != 0 must have been reached from inside the velocity limits.
        if (af < 0.0 && v_at_a_zero(vf, af, -j_min) > v_max)
            || (af > 0.0 && v_at_a_zero(vf, af, -j_max) < v_min)
        {
            return Err(Error::Infeasible {
                reason: "target state cannot be reached without exceeding the velocity limits",
            });
        }
        if pf < position_min || pf > position_max {
            return Err(Error::TargetOutsideLimits);
        }
        if (pf - start.position).abs() < P_PRECISION
            && (vf - start.velocity).abs() < V_PRECISION
            && (af - start.acceleration).abs() < A_PRECISION
        {
            // Already at the target (to the precision every profile ends
            // with): no move. Ruckig plans a loop back to a moving start
            // state instead (0.64 s for (0.1, 0.5, 1) with Table A.8's limits).
            return Ok(Trajectory::stationary(start, target));
        }

        // Brake pre-phase, then the seven phases from the braked state.
        let mut brake = BrakePhase::plan(
            start.velocity,
            start.acceleration,
            v_max,
            v_min,
            a_max,
            a_min,
            j_max,
            j_min,
        );
        let (mut p0, mut v0, mut a0) = (start.position, start.velocity, start.acceleration);
        brake.finalize(&mut p0, &mut v0, &mut a0);
        let (profile, duration_s) = if j_min == -j_max && solver == Solver::Auto {
            // Only the boundary (p/v/a[0], pf/vf/af, brake) of `input` is read;
            // the scratch profiles are overwritten before they are read (see
            // `ExtremalProfiles::reset`), so nothing is zero-filled here.
            let input = &mut self.input;
            input.p[0] = p0;
            input.v[0] = v0;
            input.a[0] = a0;
            input.brake = brake;
            input.pf = pf;
            input.vf = vf;
            input.af = af;
            let step1 = &mut self.step1;
            step1.reset(p0, v0, a0, pf, vf, af, v_max, v_min, a_max, a_min, j_max);
            let block = &mut self.block;
            if !step1.get_profile(input, block) || !block.t_min.is_finite() {
                return Err(NO_PROFILE);
            }
            (block.p_min, block.t_min)
        } else {
            let problem = Problem {
                p0,
                v0,
                a0,
                pf,
                vf,
                af,
                v_max,
                v_min,
                a_max,
                a_min,
                j_max,
                j_min,
                // The start is brake.v[0] when braked, else v0.
                v_scale: brake
                    .v
                    .iter()
                    .chain(&[v0, vf])
                    .fold(0.0, |m: f64, v| m.max(v.abs())),
            };
            let mut profile = time_optimal_profile(&problem).ok_or(NO_PROFILE)?;
            profile.brake = brake;
            (profile, profile.total_duration())
        };

        let trajectory = Trajectory {
            profile,
            start: *start,
            duration_s,
        };
        // Without position limits there is nothing to check (and the
        // extrema of the seven phases are not computed).
        if position_min > f64::NEG_INFINITY || position_max < f64::INFINITY {
            let range = trajectory.position_range();
            if range.lowest < position_min - POSITION_LIMIT_TOL
                || range.highest > position_max + POSITION_LIMIT_TOL
            {
                return Err(Error::PositionLimitsViolated {
                    lowest: range.lowest,
                    highest: range.highest,
                });
            }
        }
        Ok(trajectory)
    }
}

/// A planned time-optimal move; sample it with [`Trajectory::sample`].
#[derive(Clone, Copy, Debug)]
pub struct Trajectory {
    profile: Profile,
    start: State,
    duration_s: f64,
}

impl Trajectory {
    /// Plan the time-optimal jerk-limited move from `start` to `target`.
    ///
    /// A convenience for [`Planner::plan`] with a fresh [`Planner`]: it
    /// initializes the planner's scratch space (eight profiles, about 4 kB)
    /// on every call. Code that plans repeatedly (a firmware's retargeting, a
    /// benchmark) keeps one [`Planner`] instead.
    ///
    /// Errors: non-finite states or invalid limits ([`Error::InvalidParameter`]),
    /// a target whose acceleration or velocity is outside the limits, or from
    /// which the velocity limits would inevitably be exceeded
    /// ([`Error::Infeasible`]), a target position outside the position limits
    /// ([`Error::TargetOutsideLimits`]), a planned move that leaves them
    /// ([`Error::PositionLimitsViolated`]), and a numerical failure of the
    /// profile search ([`Error::Infeasible`]).
    pub fn plan(start: &State, target: &State, limits: &Limits) -> Result<Self, Error> {
        Planner::default().plan(start, target, limits)
    }

    /// [`Self::plan`] with the general solver of `asymmetric.rs` even for
    /// symmetric jerk limits, where [`Self::plan`] uses Ruckig's closed forms.
    /// For cross-checking the two (tests, benchmarks); not a stable API.
    #[doc(hidden)]
    pub fn plan_with_general_solver(
        start: &State,
        target: &State,
        limits: &Limits,
    ) -> Result<Self, Error> {
        Planner::default().plan_with(start, target, limits, Solver::General)
    }

    /// The zero-duration move of a start that is already at `target`.
    fn stationary(start: &State, target: &State) -> Self {
        let profile = Profile {
            p: [start.position; 8],
            v: [start.velocity; 8],
            a: [start.acceleration; 8],
            pf: target.position,
            vf: target.velocity,
            af: target.acceleration,
            ..Profile::default()
        };
        Self {
            profile,
            start: *start,
            duration_s: 0.0,
        }
    }

    /// Total duration including the brake pre-phase, s.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Duration of the brake pre-phase alone, s (0 for an admissible start).
    pub fn brake_duration_s(&self) -> f64 {
        self.profile.brake.duration
    }

    /// Durations and jerks of the brake pre-phase and of P1..P7.
    pub fn phases(&self) -> Phases {
        let b = &self.profile.brake;
        let used = |i: usize| b.duration > 0.0 && (i == 0 || b.t[1] > 0.0);
        Phases {
            brake_durations_s: [
                if used(0) { b.t[0] } else { 0.0 },
                if used(1) { b.t[1] } else { 0.0 },
            ],
            brake_jerks_m_s3: [
                if used(0) { b.j[0] } else { 0.0 },
                if used(1) { b.j[1] } else { 0.0 },
            ],
            durations_s: self.profile.t,
            jerks_m_s3: self.profile.j,
        }
    }

    /// The start state the move was planned from.
    pub fn start(&self) -> State {
        self.start
    }

    /// The state at the end of the move (equals the target to 1e-8).
    pub fn end(&self) -> State {
        State {
            position: self.profile.p[7],
            velocity: self.profile.v[7],
            acceleration: self.profile.a[7],
        }
    }

    /// Lowest and highest position over the whole move.
    pub fn position_range(&self) -> PositionRange {
        let b = self.profile.position_bounds();
        PositionRange {
            lowest: b.min.min(self.start.position),
            highest: b.max.max(self.start.position),
        }
    }

    /// The desired state at time `t_s` (s) after the start. Times before 0
    /// (and NaN) give the start state; after [`Self::duration_s`] the end state
    /// is continued with constant acceleration and zero jerk (as Ruckig does;
    /// for a target at rest this is the target itself).
    pub fn sample(&self, t_s: f64) -> Sample {
        let t = if t_s > 0.0 { t_s } else { 0.0 };
        let b = &self.profile.brake;
        if t < b.duration {
            let i = if t < b.t[0] || b.t[1] <= 0.0 { 0 } else { 1 };
            let tau = if i == 0 { t } else { t - b.t[0] };
            let k = integrate(tau, b.p[i], b.v[i], b.a[i], b.j[i]);
            return Sample {
                position: k.position,
                velocity: k.velocity,
                acceleration: k.acceleration,
                jerk: b.j[i],
            };
        }
        let p = &self.profile;
        let tp = t - b.duration;
        if tp >= p.t_sum[6] {
            let k = integrate(tp - p.t_sum[6], p.p[7], p.v[7], p.a[7], 0.0);
            return Sample {
                position: k.position,
                velocity: k.velocity,
                acceleration: k.acceleration,
                jerk: 0.0,
            };
        }
        let mut i = 0;
        while i < 6 && tp >= p.t_sum[i] {
            i += 1;
        }
        let t_begin = if i > 0 { p.t_sum[i - 1] } else { 0.0 };
        let k = integrate(tp - t_begin, p.p[i], p.v[i], p.a[i], p.j[i]);
        Sample {
            position: k.position,
            velocity: k.velocity,
            acceleration: k.acceleration,
            jerk: p.j[i],
        }
    }
}

#[cfg(test)]
mod tests;
