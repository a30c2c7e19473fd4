//! Sampling a planned move in single precision ([`TrajectoryF32`]): the
//! documented f32 path of the trajectory generator. Planning stays in `f64`
//! (its closed forms, quartic roots and differences of nearly equal
//! durations, need double precision to end on the target to 1e-8 m); a
//! firmware on an MCU with only a single-precision FPU plans once per move
//! (soft-float, outside the sample interrupt) and converts the plan with
//! [`Trajectory::to_f32`]; the sample interrupt then evaluates one cubic in
//! `f32` per sample ([`TrajectoryF32::sample`]) instead of the `f64` sample's
//! soft-float arithmetic.
//!
//! Accuracy (checked against [`Trajectory::sample`] in
//! `tests/trajectory_f32.rs`): each segment's start state is the `f32`
//! nearest to the `f64` plan's, its start time is rounded to `f32` (half an
//! ulp of the move's duration), and the cubic adds a few ulp of the
//! position: the position is off by at most `|v|max ulp(T) + 8 ulp(p)max`
//! (T the duration), e.g. 0.2 um for the thesis' 0.5 m move.

use super::{Sample, Trajectory};

/// Constant-jerk segments of a move: two of the brake pre-phase, P1..P7 and
/// the continuation after the end.
const SEGMENTS: usize = 10;

/// The desired state and jerk at one instant, in single precision.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleF32 {
    /// Position in m.
    pub position: f32,
    /// Velocity in m/s.
    pub velocity: f32,
    /// Acceleration in m/s^2.
    pub acceleration: f32,
    /// Jerk in m/s^3.
    pub jerk: f32,
}

/// A planned move for sampling in `f32` ([`Trajectory::to_f32`]; module
/// docs). Plain data (about 210 bytes), no allocation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrajectoryF32 {
    /// Start time of each segment after the start of the move, s (rounded to f32).
    start_s: [f32; SEGMENTS],
    /// Position at the start of each segment, m.
    p: [f32; SEGMENTS],
    /// Velocity at the start of each segment, m/s.
    v: [f32; SEGMENTS],
    /// Acceleration at the start of each segment, m/s^2.
    a: [f32; SEGMENTS],
    /// Jerk in each segment, m/s^3.
    j: [f32; SEGMENTS],
    /// Segments in use (at least 1: the continuation after the end).
    n: usize,
    /// Duration of the move, s (rounded to f32).
    duration_s: f32,
}

impl Trajectory {
    /// This move for sampling in single precision (module `single`): every
    /// segment's start time and start state rounded to the nearest `f32`.
    /// Cost: a few dozen conversions, once per move.
    pub fn to_f32(&self) -> TrajectoryF32 {
        let mut out = TrajectoryF32 {
            duration_s: self.duration_s as f32,
            ..TrajectoryF32::default()
        };
        let mut push = |start_s: f64, p: f64, v: f64, a: f64, j: f64| {
            let n = out.n;
            if n < SEGMENTS {
                out.start_s[n] = start_s as f32;
                out.p[n] = p as f32;
                out.v[n] = v as f32;
                out.a[n] = a as f32;
                out.j[n] = j as f32;
                out.n = n + 1;
            }
        };
        let b = &self.profile.brake;
        if b.duration > 0.0 {
            push(0.0, b.p[0], b.v[0], b.a[0], b.j[0]);
            if b.t[1] > 0.0 {
                push(b.t[0], b.p[1], b.v[1], b.a[1], b.j[1]);
            }
        }
        let pr = &self.profile;
        for i in 0..7 {
            let begin = if i > 0 { pr.t_sum[i - 1] } else { 0.0 };
            push(b.duration + begin, pr.p[i], pr.v[i], pr.a[i], pr.j[i]);
        }
        push(b.duration + pr.t_sum[6], pr.p[7], pr.v[7], pr.a[7], 0.0);
        out
    }
}

impl TrajectoryF32 {
    /// Duration of the move, s.
    pub fn duration_s(&self) -> f32 {
        self.duration_s
    }

    /// The desired state at time `t_s` (s) after the start, as
    /// [`Trajectory::sample`] (times before 0 and NaN give the start state;
    /// after the end the end state continues with constant acceleration),
    /// in `f32`. Cost: at most 10 comparisons and about 15 `f32`
    /// operations, no division, no call.
    pub fn sample(&self, t_s: f32) -> SampleF32 {
        let t = if t_s > 0.0 { t_s } else { 0.0 };
        // the last segment that has begun (a zero-length phase is passed over,
        // as in the f64 sample)
        let mut i = 0;
        let n = if self.n > 0 { self.n } else { 1 };
        while i + 1 < n && i + 1 < SEGMENTS && t >= self.start_s[i + 1] {
            i += 1;
        }
        let tau = t - self.start_s[i];
        let (p0, v0, a0, j) = (self.p[i], self.v[i], self.a[i], self.j[i]);
        SampleF32 {
            position: p0 + tau * (v0 + tau * (a0 / 2.0 + tau * j / 6.0)),
            velocity: v0 + tau * (a0 + tau * j / 2.0),
            acceleration: a0 + tau * j,
            jerk: j,
        }
    }
}

impl From<Sample> for SampleF32 {
    /// Each value rounded to the nearest `f32`.
    fn from(s: Sample) -> Self {
        SampleF32 {
            position: s.position as f32,
            velocity: s.velocity as f32,
            acceleration: s.acceleration as f32,
            jerk: s.jerk as f32,
        }
    }
}
