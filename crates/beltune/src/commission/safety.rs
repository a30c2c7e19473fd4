//! The safety supervisor, active in every commissioning stage: a travel window
//! inside the stroke, a torque limit, a velocity limit and a following-error
//! limit. It only judges; the procedure reacts to a [`Violation`] by stopping
//! the excitation at once and bringing the axis to rest with a jerk-limited stop.

use crate::error::{require_finite, require_positive};
use crate::{Error, Result};

/// Limits the supervisor enforces (cart coordinates, measured on the motor side as `i_t phi_m`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SafetyLimits {
    /// Lowest allowed cart position, m.
    pub travel_min_m: f64,
    /// Highest allowed cart position, m.
    pub travel_max_m: f64,
    /// Largest allowed torque command magnitude, N m.
    pub torque_max_nm: f64,
    /// Largest allowed cart speed, m/s.
    pub velocity_max_m_s: f64,
    /// Largest allowed following error (desired minus measured position) in
    /// closed-loop stages, m.
    pub following_error_max_m: f64,
}

impl SafetyLimits {
    /// Check the limits for consistency.
    pub fn validate(&self) -> Result<()> {
        require_finite("travel_min_m", self.travel_min_m)?;
        require_finite("travel_max_m", self.travel_max_m)?;
        if self.travel_max_m <= self.travel_min_m {
            return Err(Error::invalid(
                "travel window",
                self.travel_max_m - self.travel_min_m,
                "the travel window must have positive width (max > min)",
            ));
        }
        require_positive("torque_max_nm", self.torque_max_nm)?;
        require_positive("velocity_max_m_s", self.velocity_max_m_s)?;
        require_positive("following_error_max_m", self.following_error_max_m)?;
        Ok(())
    }

    /// Width of the travel window, m.
    pub fn travel_width_m(&self) -> f64 {
        self.travel_max_m - self.travel_min_m
    }
}

/// Which limit was violated, with the values (SI units).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Violation {
    /// The position left the travel window.
    Travel {
        /// Measured position, m.
        position_m: f64,
        /// Window, m.
        min_m: f64,
        /// Window, m.
        max_m: f64,
    },
    /// The position will leave the travel window before the axis can stop.
    TravelAhead {
        /// Measured position, m.
        position_m: f64,
        /// Where the axis would come to rest with the stop deceleration, m.
        stop_position_m: f64,
    },
    /// The speed exceeded the limit.
    Velocity {
        /// Measured speed, m/s.
        velocity_m_s: f64,
        /// Limit, m/s.
        limit_m_s: f64,
    },
    /// A torque command beyond the limit was requested.
    Torque {
        /// Requested torque, N m.
        torque_nm: f64,
        /// Limit, N m.
        limit_nm: f64,
    },
    /// The following error exceeded the limit.
    FollowingError {
        /// Error, m.
        error_m: f64,
        /// Limit, m.
        limit_m: f64,
    },
    /// A measurement was not finite (encoder or torque fault).
    NonFinite,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Violation::Travel {
                position_m,
                min_m,
                max_m,
            } => write!(
                f,
                "position {:.1} mm left the travel window [{:.1}, {:.1}] mm",
                position_m * 1e3,
                min_m * 1e3,
                max_m * 1e3
            ),
            Violation::TravelAhead {
                position_m,
                stop_position_m,
            } => write!(
                f,
                "at {:.1} mm the axis could not stop before {:.1} mm, outside the travel window",
                position_m * 1e3,
                stop_position_m * 1e3
            ),
            Violation::Velocity {
                velocity_m_s,
                limit_m_s,
            } => write!(
                f,
                "speed {:.3} m/s exceeded the limit {:.3} m/s",
                velocity_m_s.abs(),
                limit_m_s
            ),
            Violation::Torque {
                torque_nm,
                limit_nm,
            } => write!(
                f,
                "torque {:.3} N m exceeded the limit {:.3} N m",
                torque_nm.abs(),
                limit_nm
            ),
            Violation::FollowingError { error_m, limit_m } => {
                // A limit below 0.1 mm in um, so that the digits show it.
                let (scale, unit) = if limit_m < 1e-4 {
                    (1e6, "um")
                } else {
                    (1e3, "mm")
                };
                write!(
                    f,
                    "following error {:.2} {unit} exceeded the limit {:.2} {unit}",
                    error_m.abs() * scale,
                    limit_m * scale
                )
            }
            Violation::NonFinite => write!(f, "a measurement was not finite"),
        }
    }
}

/// What the axis can be relied on to do when it must stop: the deceleration
/// in each direction of travel and the time before it acts.
///
/// A tilted axis brakes harder uphill than downhill: with the holding torque
/// `tau_h` (gravity) and a stop budget `beta T_max` of the torque limit, the
/// command while braking a move towards +x is `tau_h - J a / i_t` and towards
/// -x `tau_h + J a / i_t`; both must stay within `beta T_max`, so
/// `a_+ = min(gamma T_max + tau_h, beta T_max) i_t / J` and
/// `a_- = min(gamma T_max - tau_h, beta T_max) i_t / J` with the total command
/// fraction `gamma` (friction, which helps the stop, counted at half its estimate). See
/// [`StopCapability::from_axis`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StopCapability {
    /// Deceleration available while moving towards +x, m/s^2.
    pub deceleration_positive_m_s2: f64,
    /// Deceleration available while moving towards -x, m/s^2.
    pub deceleration_negative_m_s2: f64,
    /// Time during which the axis keeps its speed before the deceleration
    /// builds up (dead time, velocity-filter lag, the stop's jerk ramp), s.
    pub reaction_time_s: f64,
    /// Deceleration a stop may use towards +x when the planned one would end
    /// outside the travel window (the whole command budget
    /// [`STOP_COMMAND_FRACTION`] instead of [`STOP_TORQUE_FRACTION`]), m/s^2.
    /// The look-ahead plans with the smaller deceleration above; this is
    /// the stop's reserve (stops that ended outside the window).
    #[serde(default)]
    pub reserve_deceleration_positive_m_s2: f64,
    /// Reserve deceleration towards -x, m/s^2 (see above).
    #[serde(default)]
    pub reserve_deceleration_negative_m_s2: f64,
    /// Rigid-body inertia the decelerations were computed for, kg m^2 (0:
    /// unknown). The stop feeds its deceleration forward with it when the
    /// stop controller has no inertia feedforward of its own.
    #[serde(default)]
    pub inertia_kg_m2: f64,
}

/// Fraction of the torque limit a stop may use (the rest is margin for the
/// loop's transient and the model's errors).
pub const STOP_TORQUE_FRACTION: f64 = 0.6;
/// Fraction of the torque limit the stop's command may reach in total,
/// gravity compensation included.
pub const STOP_COMMAND_FRACTION: f64 = 0.9;
/// Smallest braking torque, as a fraction of the limit, with which an axis is
/// still commissioned (below it: [`Error::Infeasible`]).
pub const STOP_MIN_FRACTION: f64 = 0.15;
/// Largest stop deceleration used, m/s^2 (a stop need not be violent).
pub const STOP_DECELERATION_MAX_M_S2: f64 = 20.0;
/// Jerk of the stop trajectory relative to its deceleration, 1/s.
pub const STOP_JERK_PER_DECELERATION: f64 = 20.0;
/// Reaction time besides the stop's jerk ramp: the largest dead time the
/// commissioning accepts (2 ms) and the supervision velocity filter (2 ms), s.
pub const STOP_LATENCY_S: f64 = 4e-3;
/// Largest reserve deceleration of a stop, m/s^2 (see
/// [`StopCapability::reserve_deceleration_positive_m_s2`]).
pub const STOP_RESERVE_DECELERATION_MAX_M_S2: f64 = 30.0;
/// Distance a stop keeps from the window's edge when it has to use its
/// reserve, m: the belt stretches by `m a / c` (25 kg at 10 m/s^2 on
/// 100 kN/m: 2.5 mm) and the cart swings past the motor by that much.
pub const STOP_EDGE_MARGIN_M: f64 = 3e-3;
/// Smallest braking torque, as a fraction of the torque limit, a
/// provisional capability assumes ([`StopCapability::provisional`]).
pub const PROVISIONAL_MIN_FRACTION: f64 = 0.05;

impl StopCapability {
    /// The same deceleration both ways, with the latency and jerk ramp.
    pub fn symmetric(deceleration_m_s2: f64) -> Self {
        StopCapability {
            deceleration_positive_m_s2: deceleration_m_s2,
            deceleration_negative_m_s2: deceleration_m_s2,
            reaction_time_s: STOP_LATENCY_S + 0.5 / STOP_JERK_PER_DECELERATION,
            reserve_deceleration_positive_m_s2: deceleration_m_s2,
            reserve_deceleration_negative_m_s2: deceleration_m_s2,
            inertia_kg_m2: 0.0,
        }
    }

    /// The capability while the holding torque is known only from the first
    /// hold (stage 2: it still contains the static friction the sagging load
    /// met): like [`StopCapability::from_axis`] but refusing only a load
    /// whose first hold takes more than the stop's whole command budget
    /// ([`STOP_COMMAND_FRACTION`] of the limit): the stop has nothing left
    /// to brake it downhill. The braking torque in the weak direction is
    /// what the first hold leaves, at least [`PROVISIONAL_MIN_FRACTION`] of
    /// the limit; the finer refusal is left to the holding-torque stage,
    /// which measures gravity without friction (plants refused on
    /// the first hold that physics allows). A plant refused here is
    /// infeasible unless its first hold overstates gravity by more than
    /// `STOP_MIN_FRACTION T_max - tau_c / 2` (from_axis accepts up to
    /// `(STOP_COMMAND_FRACTION - STOP_MIN_FRACTION) T_max + tau_c / 2`;
    /// such loads were run until a stop or a following error
    /// ended the holding-torque runs).
    pub fn provisional(
        torque_max_nm: f64,
        inertia_kg_m2: f64,
        i_t_m: f64,
        first_hold_nm: f64,
    ) -> Result<Self> {
        match Self::from_axis(torque_max_nm, inertia_kg_m2, i_t_m, first_hold_nm, 0.0) {
            Err(Error::Infeasible { .. })
                if first_hold_nm.abs() > STOP_COMMAND_FRACTION * torque_max_nm =>
            {
                Err(Error::Infeasible {
                    reason: format!(
                        "the axis needs {:.3} N m to hold its load (first hold), more than {:.0} % of the torque limit {:.3} N m: nothing is left to stop it downhill",
                        first_hold_nm.abs(),
                        STOP_COMMAND_FRACTION * 100.0,
                        torque_max_nm
                    ),
                })
            }
            Err(Error::Infeasible { .. }) => {
                let total = STOP_COMMAND_FRACTION * torque_max_nm;
                let floor = PROVISIONAL_MIN_FRACTION * torque_max_nm;
                let budget = STOP_TORQUE_FRACTION * torque_max_nm;
                let a = |tau: f64| {
                    (tau.clamp(floor, budget) * i_t_m / inertia_kg_m2)
                        .min(STOP_DECELERATION_MAX_M_S2)
                };
                let pos = a(total + first_hold_nm);
                let neg = a(total - first_hold_nm);
                Ok(StopCapability {
                    deceleration_positive_m_s2: pos,
                    deceleration_negative_m_s2: neg,
                    reserve_deceleration_positive_m_s2: pos,
                    reserve_deceleration_negative_m_s2: neg,
                    inertia_kg_m2,
                    ..StopCapability::symmetric(1.0)
                })
            }
            other => other,
        }
    }

    /// The capability of an axis with torque limit `torque_max_nm`, rigid
    /// inertia `inertia_kg_m2` (kg m^2), transmission `i_t_m` (m/rad), holding
    /// torque `holding_nm` (gravity, N m) and Coulomb friction estimate
    /// `coulomb_nm` (N m). [`Error::Infeasible`] when the stop budget cannot
    /// even hold the load: such an axis cannot be commissioned safely.
    pub fn from_axis(
        torque_max_nm: f64,
        inertia_kg_m2: f64,
        i_t_m: f64,
        holding_nm: f64,
        coulomb_nm: f64,
    ) -> Result<Self> {
        require_positive("torque limit [N m]", torque_max_nm)?;
        require_positive("inertia [kg m^2]", inertia_kg_m2)?;
        require_positive("i_t [m/rad]", i_t_m)?;
        require_finite("holding torque [N m]", holding_nm)?;
        let friction = 0.5 * coulomb_nm.max(0.0);
        let budget = STOP_TORQUE_FRACTION * torque_max_nm;
        let a = |tau: f64| (tau * i_t_m / inertia_kg_m2).min(STOP_DECELERATION_MAX_M_S2);
        // The stop may command up to STOP_COMMAND_FRACTION of the limit in
        // total (gravity compensation included) and brakes with at most the
        // stop budget: on a level axis `beta T_max`, downhill what gravity leaves.
        let total = STOP_COMMAND_FRACTION * torque_max_nm;
        let pos = (total + holding_nm + friction).min(budget);
        let neg = (total - holding_nm + friction).min(budget);
        // A load that leaves less than STOP_MIN_FRACTION of the limit to brake
        // downhill cannot be stopped reliably.
        if pos.min(neg) < STOP_MIN_FRACTION * torque_max_nm {
            return Err(Error::Infeasible {
                reason: format!(
                    "the axis needs {:.3} N m to hold its load, too much of the torque limit {:.3} N m to stop it safely in both directions",
                    holding_nm.abs(),
                    torque_max_nm
                ),
            });
        }
        let reserve = |tau: f64| {
            (tau * i_t_m / inertia_kg_m2)
                .min(STOP_RESERVE_DECELERATION_MAX_M_S2)
                .max(a(tau.min(budget)))
        };
        Ok(StopCapability {
            deceleration_positive_m_s2: a(pos),
            deceleration_negative_m_s2: a(neg),
            reserve_deceleration_positive_m_s2: reserve(total + holding_nm + friction),
            reserve_deceleration_negative_m_s2: reserve(total - holding_nm + friction),
            inertia_kg_m2,
            ..StopCapability::symmetric(1.0)
        })
    }

    /// Reserve deceleration available while moving with `velocity_m_s`, m/s^2.
    pub fn reserve_deceleration_for(&self, velocity_m_s: f64) -> f64 {
        let r = if velocity_m_s >= 0.0 {
            self.reserve_deceleration_positive_m_s2
        } else {
            self.reserve_deceleration_negative_m_s2
        };
        // a capability read from an older file has no reserve
        r.max(self.deceleration_for(velocity_m_s))
    }

    /// The smaller deceleration of the two directions, m/s^2.
    pub fn worst_deceleration_m_s2(&self) -> f64 {
        self.deceleration_positive_m_s2
            .min(self.deceleration_negative_m_s2)
    }

    /// Deceleration available while moving with `velocity_m_s`, m/s^2.
    pub fn deceleration_for(&self, velocity_m_s: f64) -> f64 {
        if velocity_m_s >= 0.0 {
            self.deceleration_positive_m_s2
        } else {
            self.deceleration_negative_m_s2
        }
    }

    fn validate(&self) -> Result<()> {
        require_positive(
            "stop deceleration (+x) [m/s^2]",
            self.deceleration_positive_m_s2,
        )?;
        require_positive(
            "stop deceleration (-x) [m/s^2]",
            self.deceleration_negative_m_s2,
        )?;
        require_finite("stop reaction time [s]", self.reaction_time_s)?;
        crate::error::require_non_negative(
            "stop reserve deceleration (+x) [m/s^2]",
            self.reserve_deceleration_positive_m_s2,
        )?;
        crate::error::require_non_negative(
            "stop reserve deceleration (-x) [m/s^2]",
            self.reserve_deceleration_negative_m_s2,
        )?;
        crate::error::require_non_negative("stop inertia [kg m^2]", self.inertia_kg_m2)?;
        if self.reaction_time_s < 0.0 {
            return Err(Error::invalid(
                "stop reaction time [s]",
                self.reaction_time_s,
                "must not be negative",
            ));
        }
        Ok(())
    }
}

/// The supervisor: call [`SafetySupervisor::check`] every sample.
#[derive(Clone, Debug)]
pub struct SafetySupervisor {
    limits: SafetyLimits,
    capability: StopCapability,
}

impl SafetySupervisor {
    /// A supervisor for `limits`; `stop_deceleration_m_s2` is the deceleration
    /// the jerk-limited stop can be relied on to reach in both directions (used for the
    /// look-ahead that stops the axis before it reaches the window edge; in
    /// open-loop stages the look-ahead assumes half of it).
    pub fn new(limits: SafetyLimits, stop_deceleration_m_s2: f64) -> Result<Self> {
        require_positive("stop_deceleration_m_s2", stop_deceleration_m_s2)?;
        Self::with_capability(limits, StopCapability::symmetric(stop_deceleration_m_s2))
    }

    /// A supervisor for `limits` with a direction-dependent stop capability.
    pub fn with_capability(limits: SafetyLimits, capability: StopCapability) -> Result<Self> {
        limits.validate()?;
        capability.validate()?;
        Ok(SafetySupervisor { limits, capability })
    }

    /// Replace the stop capability (when the holding torque, the inertia or
    /// the friction become known).
    pub fn set_capability(&mut self, capability: StopCapability) -> Result<()> {
        capability.validate()?;
        self.capability = capability;
        Ok(())
    }

    /// The stop capability.
    pub fn capability(&self) -> &StopCapability {
        &self.capability
    }

    /// The limits.
    pub fn limits(&self) -> &SafetyLimits {
        &self.limits
    }

    /// Distance needed to stop from `velocity_m_s`, m: the reaction time at
    /// full speed plus `v^2 / (2 a)` with the deceleration of that direction.
    pub fn stopping_distance_m(&self, velocity_m_s: f64) -> f64 {
        let a = self.capability.deceleration_for(velocity_m_s);
        velocity_m_s.abs() * self.capability.reaction_time_s
            + velocity_m_s * velocity_m_s / (2.0 * a)
    }

    /// Judge one sample. `following_error_m` is `None` in open-loop stages.
    pub fn check(
        &self,
        position_m: f64,
        velocity_m_s: f64,
        torque_command_nm: f64,
        following_error_m: Option<f64>,
    ) -> std::result::Result<(), Violation> {
        self.check_lagged(
            position_m,
            velocity_m_s,
            0.0,
            torque_command_nm,
            following_error_m,
        )
    }

    /// [`SafetySupervisor::check`] for a velocity estimate that lags the
    /// axis by `velocity_lag_s` (a smoothed estimate): the look-ahead adds
    /// the distance the axis covers meanwhile.
    pub fn check_lagged(
        &self,
        position_m: f64,
        velocity_m_s: f64,
        velocity_lag_s: f64,
        torque_command_nm: f64,
        following_error_m: Option<f64>,
    ) -> std::result::Result<(), Violation> {
        let l = &self.limits;
        if !(position_m.is_finite() && velocity_m_s.is_finite() && torque_command_nm.is_finite()) {
            return Err(Violation::NonFinite);
        }
        if position_m < l.travel_min_m || position_m > l.travel_max_m {
            return Err(Violation::Travel {
                position_m,
                min_m: l.travel_min_m,
                max_m: l.travel_max_m,
            });
        }
        // In open-loop stages (no following error: nothing tracks a plan) the
        // look-ahead assumes half the stop deceleration: the torque already
        // queued in the dead time and the stop controller's lag come first.
        let distance = match following_error_m {
            Some(_) => self.stopping_distance_m(velocity_m_s),
            None => {
                self.stopping_distance_m(velocity_m_s)
                    + velocity_m_s * velocity_m_s
                        / (2.0 * self.capability.deceleration_for(velocity_m_s))
            }
        };
        let distance = distance + velocity_m_s.abs() * velocity_lag_s.max(0.0);
        let stop = position_m + velocity_m_s.signum() * distance;
        if stop < l.travel_min_m || stop > l.travel_max_m {
            return Err(Violation::TravelAhead {
                position_m,
                stop_position_m: stop,
            });
        }
        if velocity_m_s.abs() > l.velocity_max_m_s {
            return Err(Violation::Velocity {
                velocity_m_s,
                limit_m_s: l.velocity_max_m_s,
            });
        }
        // A command exactly at the limit is saturation, not a violation.
        if torque_command_nm.abs() > l.torque_max_nm * (1.0 + 1e-9) {
            return Err(Violation::Torque {
                torque_nm: torque_command_nm,
                limit_nm: l.torque_max_nm,
            });
        }
        if let Some(e) = following_error_m {
            if !e.is_finite() {
                return Err(Violation::NonFinite);
            }
            if e.abs() > l.following_error_max_m {
                return Err(Violation::FollowingError {
                    error_m: e,
                    limit_m: l.following_error_max_m,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> SafetyLimits {
        SafetyLimits {
            travel_min_m: 0.0,
            travel_max_m: 0.5,
            torque_max_nm: 1.0,
            velocity_max_m_s: 1.0,
            following_error_max_m: 0.01,
        }
    }

    /// The look-ahead of the thesis-era tests: no reaction time.
    fn instant(a: f64) -> StopCapability {
        StopCapability {
            reaction_time_s: 0.0,
            ..StopCapability::symmetric(a)
        }
    }

    #[test]
    fn each_limit_is_enforced() {
        let s = SafetySupervisor::with_capability(limits(), instant(10.0)).unwrap();
        assert!(s.check(0.25, 0.0, 0.5, Some(0.001)).is_ok());
        assert!(matches!(
            s.check(0.6, 0.0, 0.0, None),
            Err(Violation::Travel { .. })
        ));
        // Closed loop: 0.449 m moving at 0.99 m/s towards 0.5 m needs 0.049 m to
        // stop at 10 m/s^2 -> stops at 0.498 m: ok;
        assert!(s.check(0.449, 0.99, 0.0, Some(0.0)).is_ok());
        // open loop: twice the distance, 0.547 m: outside.
        assert!(matches!(
            s.check(0.449, 0.99, 0.0, None),
            Err(Violation::TravelAhead { .. })
        ));
        // 0.48 m at 0.9 m/s needs 0.0405 m -> 0.5205 m: outside even in closed loop.
        assert!(matches!(
            s.check(0.48, 0.9, 0.0, Some(0.0)),
            Err(Violation::TravelAhead { .. })
        ));
        // With the default reaction time (dead time, filter, jerk ramp: 29 ms)
        // 0.449 m at 0.99 m/s stops at 0.498 + 0.029 m: outside.
        let r = SafetySupervisor::new(limits(), 10.0).unwrap();
        assert!(matches!(
            r.check(0.449, 0.99, 0.0, Some(0.0)),
            Err(Violation::TravelAhead { .. })
        ));
        assert!(matches!(
            s.check(0.48, 0.9, 0.0, Some(0.0)),
            Err(Violation::TravelAhead { .. })
        ));
        assert!(matches!(
            s.check(0.1, 1.5, 0.0, None),
            Err(Violation::Velocity { .. })
        ));
        assert!(
            s.check(0.25, 0.0, 1.0, None).is_ok(),
            "saturation is not a violation"
        );
        assert!(matches!(
            s.check(0.25, 0.0, -1.2, None),
            Err(Violation::Torque { .. })
        ));
        assert!(matches!(
            s.check(0.25, 0.0, 0.0, Some(-0.02)),
            Err(Violation::FollowingError { .. })
        ));
        assert!(matches!(
            s.check(f64::NAN, 0.0, 0.0, None),
            Err(Violation::NonFinite)
        ));
    }

    /// Stops that ended outside the window: on a tilted axis the
    /// stop brakes downhill with the torque gravity leaves, uphill with the
    /// torque plus gravity; the look-ahead uses the deceleration of the
    /// direction of travel.
    #[test]
    fn stops_are_planned_with_the_deceleration_gravity_leaves() {
        let (t_max, j, i_t) = (3.1, 2e-3, 0.0124);
        let hold = 1.0; // gravity pulls towards -x
        let c = StopCapability::from_axis(t_max, j, i_t, hold, 0.0).unwrap();
        let budget = STOP_TORQUE_FRACTION * t_max;
        let total = STOP_COMMAND_FRACTION * t_max;
        let expect_pos = ((total + hold).min(budget) * i_t / j).min(STOP_DECELERATION_MAX_M_S2);
        let expect_neg = (total - hold).min(budget) * i_t / j;
        assert!((c.deceleration_positive_m_s2 - expect_pos).abs() < 1e-12);
        assert!((c.deceleration_negative_m_s2 - expect_neg).abs() < 1e-12);
        assert!(c.deceleration_negative_m_s2 < c.deceleration_positive_m_s2);
        let s = SafetySupervisor::with_capability(limits(), c).unwrap();
        // downhill (towards -x) needs more room than uphill at the same speed
        assert!(s.stopping_distance_m(-0.5) > s.stopping_distance_m(0.5));
        let flat = StopCapability::from_axis(t_max, j, i_t, 0.0, 0.0).unwrap();
        let level = SafetySupervisor::with_capability(limits(), flat).unwrap();
        assert!(s.stopping_distance_m(-0.5) > level.stopping_distance_m(-0.5));
        // a load that takes most of the stop budget is refused
        assert!(matches!(
            StopCapability::from_axis(t_max, j, i_t, 0.8 * t_max, 0.0),
            Err(Error::Infeasible { .. })
        ));
        assert!(StopCapability::from_axis(t_max, j, i_t, f64::NAN, 0.0).is_err());
    }

    /// The first hold (gravity plus the static friction a sagging
    /// load meets) refuses no axis within the stop's command budget that
    /// from_axis would; the braking torque it leaves is assumed, at least
    /// PROVISIONAL_MIN_FRACTION of the limit.
    #[test]
    fn a_provisional_capability_refuses_nothing_within_the_budget() {
        let (t_max, j, i_t) = (3.1, 3e-3, 0.0124);
        let first_hold = 2.4; // from_axis refuses: 0.9 * 3.1 - 2.4 < 0.15 * 3.1
        assert!(StopCapability::from_axis(t_max, j, i_t, first_hold, 0.0).is_err());
        let c = StopCapability::provisional(t_max, j, i_t, first_hold).unwrap();
        let weak = (STOP_COMMAND_FRACTION * t_max - first_hold) * i_t / j;
        assert!((c.deceleration_negative_m_s2 - weak).abs() < 1e-12, "{c:?}");
        assert!(c.deceleration_positive_m_s2 > c.deceleration_negative_m_s2);
        let c = StopCapability::provisional(t_max, j, i_t, 2.75).unwrap();
        let floor = PROVISIONAL_MIN_FRACTION * t_max * i_t / j;
        assert!((c.deceleration_negative_m_s2 - floor).abs() < 1e-12);
        // where from_axis accepts, the same capability
        assert_eq!(
            StopCapability::provisional(t_max, j, i_t, 0.5).unwrap(),
            StopCapability::from_axis(t_max, j, i_t, 0.5, 0.0).unwrap()
        );
        assert!(StopCapability::provisional(t_max, j, i_t, f64::NAN).is_err());
    }

    /// Heavy loads run until a stop: a first hold beyond the
    /// stop's whole command budget leaves nothing to brake downhill; it is
    /// refused at once, in either direction of gravity, while a first hold
    /// just inside it is still left to the holding-torque stage.
    #[test]
    fn a_first_hold_beyond_the_command_budget_is_refused() {
        let (t_max, j, i_t) = (3.1, 3.9e-3, 0.0124);
        let budget = STOP_COMMAND_FRACTION * t_max;
        for hold in [budget + 1e-3, 2.9, 3.05, 3.1] {
            for sign in [1.0, -1.0] {
                assert!(matches!(
                    StopCapability::provisional(t_max, j, i_t, sign * hold),
                    Err(Error::Infeasible { .. })
                ));
            }
        }
        assert!(StopCapability::provisional(t_max, j, i_t, budget - 1e-3).is_ok());
        assert!(StopCapability::provisional(t_max, j, i_t, -(budget - 1e-3)).is_ok());
    }

    /// A lagging (smoothed) velocity estimate: the look-ahead adds the
    /// distance covered during the lag.
    #[test]
    fn a_lagging_velocity_adds_its_distance() {
        let s = SafetySupervisor::with_capability(limits(), instant(10.0)).unwrap();
        // 0.449 m at 0.99 m/s stops at 0.498 m; 20 ms of lag add 19.8 mm
        assert!(s.check_lagged(0.449, 0.99, 0.0, 0.0, Some(0.0)).is_ok());
        assert!(matches!(
            s.check_lagged(0.449, 0.99, 0.02, 0.0, Some(0.0)),
            Err(Violation::TravelAhead { .. })
        ));
    }

    #[test]
    fn inconsistent_limits_are_rejected() {
        let mut l = limits();
        l.travel_max_m = -1.0;
        assert!(SafetySupervisor::new(l, 10.0).is_err());
        assert!(SafetySupervisor::new(limits(), 0.0).is_err());
        let l = SafetyLimits {
            torque_max_nm: f64::NAN,
            ..limits()
        };
        assert!(SafetySupervisor::new(l, 10.0).is_err());
    }

    /// A following-error limit of 1 um printed as "0.00 mm".
    #[test]
    fn a_small_following_error_limit_prints_in_um() {
        let v = Violation::FollowingError {
            error_m: -1.05e-6,
            limit_m: 1e-6,
        };
        assert_eq!(
            v.to_string(),
            "following error 1.05 um exceeded the limit 1.00 um"
        );
        let v = Violation::FollowingError {
            error_m: 0.05005,
            limit_m: 0.05,
        };
        assert_eq!(
            v.to_string(),
            "following error 50.05 mm exceeded the limit 50.00 mm"
        );
    }

    #[test]
    fn messages_name_the_values_in_mm() {
        let v = Violation::Travel {
            position_m: 0.6,
            min_m: 0.0,
            max_m: 0.5,
        };
        assert_eq!(
            v.to_string(),
            "position 600.0 mm left the travel window [0.0, 500.0] mm"
        );
    }
}
