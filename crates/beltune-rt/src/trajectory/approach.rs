//! Single-direction final approach (beyond the thesis): a move
//! that stops `distance_m` short of its target at the move's limits, then
//! creeps the rest at `speed_m_s`, both jerk-limited. The axis always
//! arrives at the target slowly and from the side it came from, as CNC
//! controls position against backlash (G60).
//!
//! On a belt axis with a sticky cart the friction band `+-F_c / c` (up to
//! 0.18 mm on the soft, sticky axes of the robustness study) is the
//! backlash: where the cart rests inside it depends on how it arrives. At
//! the end of a fast move a soft position loop lets the cart swing up to
//! 0.3 mm ahead or behind, and it sticks wherever that swing ends. A cart
//! dragged slowly (the creep) lags its motor by exactly the stretch of its
//! kinetic friction, so with the setpoint's Coulomb lead held at rest
//! ([`crate::control::BeltProfile::coulomb_travel_m`]) it stops at the
//! target. The approach distance must exceed that swing plus the band, so
//! the creep starts with the cart behind the target whatever the main move
//! left; the creep must last long enough for the cascade's integrator to
//! settle its torque (a few tenths of a second: a creep of 0.2 s left the
//! motor 0.15 mm ahead of its setpoint on two plants of the study).
//!
//! Planned once ([`Approach::plan`], no allocation), sampled like a
//! [`Trajectory`] ([`Approach::sample`]).

use super::{Limits, Sample, State, Trajectory};
use crate::error::positive;
use crate::Error;

/// How the final approach runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ApproachConfig {
    /// Distance crept at the end of the move, m (`>= 0`; 0: no creep).
    pub distance_m: f64,
    /// Creep speed, m/s (`> 0`).
    pub speed_m_s: f64,
}

/// Time over which the creep reaches its speed, s: the creep's acceleration
/// limit is `speed_m_s` over it, its jerk limit four times that
/// acceleration over it (at most the move's). A creep that started with
/// the move's jerk (40 m/s^3: the acceleration within a millisecond) broke
/// sticky carts loose at its start and left them up to 0.19 mm past the
/// target.
pub const CREEP_RAMP_S: f64 = 0.04;

/// A move with its final approach: the main move to `target - d * distance`
/// (`d` the direction of the move) and the creep from there to the target.
#[derive(Clone, Copy, Debug)]
pub struct Approach {
    main: Trajectory,
    creep: Option<Trajectory>,
}

impl Approach {
    /// Plan from `start` to rest at `target_m` with `limits`, the last
    /// `approach.distance_m` at `approach.speed_m_s` (the move's jerk and
    /// position limits; acceleration and jerk as [`CREEP_RAMP_S`] says). A move
    /// shorter than the approach distance creeps all the way. Errors: an
    /// invalid configuration ([`Error::InvalidParameter`]) or what
    /// [`Trajectory::plan`] refuses.
    pub fn plan(
        start: &State,
        target_m: f64,
        limits: &Limits,
        approach: &ApproachConfig,
    ) -> Result<Self, Error> {
        let speed = positive("speed_m_s", approach.speed_m_s)?;
        let distance = approach.distance_m;
        if !(distance.is_finite() && distance >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "distance_m",
                reason: "must be finite and >= 0",
            });
        }
        let accel = (speed / CREEP_RAMP_S).min(limits.a_max).min(-limits.a_min);
        let jerk = (4.0 * accel / CREEP_RAMP_S)
            .min(limits.j_max)
            .min(-limits.j_min);
        let creep_limits = Limits {
            v_max: speed.min(limits.v_max),
            v_min: (-speed).max(limits.v_min),
            a_max: accel,
            a_min: -accel,
            j_max: jerk,
            j_min: -jerk,
            ..*limits
        };
        let travel = target_m - start.position;
        let end = State::at_rest(target_m);
        if distance == 0.0 {
            return Ok(Approach {
                main: Trajectory::plan(start, &end, limits)?,
                creep: None,
            });
        }
        if travel.abs() <= distance {
            return Ok(Approach {
                main: Trajectory::plan(start, &end, &creep_limits)?,
                creep: None,
            });
        }
        let short = State::at_rest(target_m - travel.signum() * distance);
        Ok(Approach {
            main: Trajectory::plan(start, &short, limits)?,
            creep: Some(Trajectory::plan(&short, &end, &creep_limits)?),
        })
    }

    /// A move without a final approach.
    pub fn direct(trajectory: Trajectory) -> Self {
        Approach {
            main: trajectory,
            creep: None,
        }
    }

    /// Duration of the main move and the creep, s.
    pub fn duration_s(&self) -> f64 {
        self.main.duration_s() + self.creep.map_or(0.0, |c| c.duration_s())
    }

    /// The main move (to the start of the creep).
    pub fn main(&self) -> &Trajectory {
        &self.main
    }

    /// The creep, if any.
    pub fn creep(&self) -> Option<&Trajectory> {
        self.creep.as_ref()
    }

    /// Direction whose Coulomb lead the setpoint holds at `t_s`
    /// ([`crate::control::SetpointConversion::motor_sample_held`]): the
    /// move's direction from the main move's middle on (its top speed, on a
    /// rest-to-rest move beyond the lead's ramp) through the creep and at
    /// rest; 0 before, and for a move without a creep.
    pub fn lead_hold(&self, t_s: f64) -> f64 {
        match &self.creep {
            Some(c) if t_s >= 0.5 * self.main.duration_s() => {
                (c.end().position - self.main.start().position).signum()
            }
            _ => 0.0,
        }
    }

    /// The desired state at `t_s` (s) after the start: the main move's, then
    /// the creep's; after the end the target at rest.
    pub fn sample(&self, t_s: f64) -> Sample {
        let d = self.main.duration_s();
        match &self.creep {
            Some(c) if t_s > d => c.sample(t_s - d),
            _ => self.main.sample(t_s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TS: f64 = 1e-4;

    fn table_a8() -> Limits {
        Limits {
            position_min: -0.01,
            position_max: 0.57,
            ..Limits::default()
        }
    }

    /// Both directions, several distances: the path is continuous in
    /// position and velocity, never passes the target or reverses, ends at
    /// rest on the target, and runs the last `distance` no faster than the
    /// creep speed (checked on the samples, independently of the plan).
    #[test]
    fn the_approach_arrives_slowly_from_one_side() {
        for (start, target) in [(0.0, 0.5), (0.5, 0.02), (0.3, 0.3015)] {
            for distance in [0.0, 1.3e-3, 5e-3] {
                let cfg = ApproachConfig {
                    distance_m: distance,
                    speed_m_s: 2e-3,
                };
                let a = Approach::plan(&State::at_rest(start), target, &table_a8(), &cfg).unwrap();
                let dir = (target - start).signum();
                let n = (a.duration_s() / TS).ceil() as usize + 10;
                let mut prev = a.sample(0.0);
                for k in 1..=n {
                    let s = a.sample(k as f64 * TS);
                    assert!(
                        (s.position - prev.position).abs() < 5.0 * TS + 1e-12,
                        "jump at {k}"
                    );
                    assert!((s.velocity - prev.velocity).abs() < 45.0 * TS + 1e-9);
                    assert!(s.velocity * dir >= -1e-9, "reverses at {k}: {s:?}");
                    assert!((target - s.position) * dir >= -1e-9, "passes at {k}");
                    if distance > 0.0 && (target - s.position).abs() < distance - 1e-9 {
                        assert!(s.velocity.abs() <= 2e-3 + 1e-9, "fast near the end: {s:?}");
                    }
                    prev = s;
                }
                let end = a.sample(a.duration_s() + 1.0);
                assert!((end.position - target).abs() < 1e-8 && end.velocity.abs() < 1e-9);
            }
        }
    }

    /// The held Coulomb lead ([`Approach::lead_hold`]): none in the main
    /// move's first half, the move's direction from its middle through the
    /// creep and after the end; none for a move without a creep.
    #[test]
    fn the_lead_is_held_from_the_main_move_s_middle() {
        let cfg = ApproachConfig {
            distance_m: 1.3e-3,
            speed_m_s: 2e-3,
        };
        for (start, target) in [(0.0, 0.5), (0.5, 0.02)] {
            let a = Approach::plan(&State::at_rest(start), target, &table_a8(), &cfg).unwrap();
            let dir = (target - start).signum();
            let half = 0.5 * a.main().duration_s();
            assert_eq!(a.lead_hold(0.0), 0.0);
            assert_eq!(a.lead_hold(0.99 * half), 0.0);
            assert_eq!(a.lead_hold(half), dir);
            assert_eq!(a.lead_hold(a.duration_s() + 1.0), dir);
            let direct = Approach::direct(*a.main());
            assert_eq!(direct.lead_hold(a.duration_s()), 0.0);
        }
    }

    #[test]
    fn an_invalid_approach_is_an_error() {
        let start = State::at_rest(0.0);
        for cfg in [
            ApproachConfig {
                distance_m: -1e-3,
                speed_m_s: 2e-3,
            },
            ApproachConfig {
                distance_m: f64::NAN,
                speed_m_s: 2e-3,
            },
            ApproachConfig {
                distance_m: 1e-3,
                speed_m_s: 0.0,
            },
        ] {
            assert!(
                Approach::plan(&start, 0.5, &table_a8(), &cfg).is_err(),
                "{cfg:?}"
            );
        }
    }
}
