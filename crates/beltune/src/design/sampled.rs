//! The controller at the sampling time `T_s` and the stability check of the
//! discretized loops: Tustin sections (prefilter pre-warped, PI and velocity
//! filter plain) from the real-time crate, the plant (2.42) with its dead time
//! discretized by ZOH, and the closed-loop poles as eigenvalues of the closed-loop
//! state matrix (all must lie inside the unit circle).

use super::velocity::PiGains;
use super::{DesignInput, Prefilter};
use crate::lti::discrete::{tustin_pi, StateSpace};
use crate::{Error, Result};
use beltune_rt::filter::{FirstOrderCoeffs, SosCoeffs};

/// Largest closed-loop pole magnitude accepted as stable. Poles of a well-damped
/// design lie far below; the margin only absorbs eigenvalue rounding (~1e-12) of
/// poles at `z = 1 - w T_s` for `w` down to 1e-4 rad/s.
pub const MAX_STABLE_POLE_MAGNITUDE: f64 = 1.0 - 1e-9;

/// Distance from `z = 1` within which an eigenvalue of the closed velocity loop is
/// taken as the rigid-body position mode (eigenvalue rounding is ~1e-12 here).
const RIGID_MODE_TOL: f64 = 1e-8;

/// Coefficients for the real-time controller at `ts_s`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiscreteController {
    /// Sampling time `T_s`, s.
    pub ts_s: f64,
    /// Prefilter section (identity for no prefilter).
    #[serde(with = "sos_serde")]
    pub prefilter: SosCoeffs<f64>,
    /// PI controller `K_P + K_I / s`, Tustin (input: velocity error in rad/s, output N m).
    #[serde(with = "first_order_serde")]
    pub pi: FirstOrderCoeffs<f64>,
    /// Velocity filter `G_R = s / (T_R s + 1)` (input: motor angle in rad, output rad/s).
    #[serde(with = "first_order_serde")]
    pub velocity_filter: FirstOrderCoeffs<f64>,
    /// Position gain `K_PP`, 1/s (static, identical in continuous and discrete time).
    pub k_pp: f64,
}

impl DiscreteController {
    /// Discretize the continuous design.
    pub fn new(
        prefilter: &Prefilter,
        gains: &PiGains,
        k_pp: f64,
        input: &DesignInput,
    ) -> Result<Self> {
        Ok(DiscreteController {
            ts_s: input.ts_s,
            prefilter: prefilter.discretize(input.ts_s)?,
            pi: tustin_pi(gains.k_p, gains.k_i, input.ts_s)?,
            velocity_filter: beltune_rt::filter::velocity_filter(input.t_r_s, input.ts_s)?,
            k_pp,
        })
    }
}

/// The discretized loops as state-space models.
#[derive(Clone, Debug, PartialEq)]
pub struct DiscreteLoops {
    /// Velocity open loop from the velocity error to the measured velocity:
    /// PI, prefilter, ZOH plant with dead time, velocity filter.
    pub velocity_open: StateSpace,
    /// Closed velocity loop from the velocity reference to the motor angle.
    pub velocity_closed: StateSpace,
    /// Position open loop `K_PP` times the closed velocity loop.
    pub position_open: StateSpace,
    /// Closed position loop from the angle reference to the motor angle.
    pub position_closed: StateSpace,
}

impl DiscreteLoops {
    /// Build all loops from the controller coefficients and the model.
    pub fn new(ctrl: &DiscreteController, input: &DesignInput) -> Result<Self> {
        let plant = StateSpace::zoh(
            &input.model.tf_rigid_flexible(),
            input.ts_s,
            input.dead_time_s,
        )?;
        let forward = StateSpace::from_first_order(&ctrl.pi)
            .series(&StateSpace::from_sos(&ctrl.prefilter))
            .series(&plant);
        let g_r = StateSpace::from_first_order(&ctrl.velocity_filter);
        let velocity_open = forward.series(&g_r);
        let velocity_closed = forward.feedback(&g_r)?;
        let position_open = StateSpace::gain(ctrl.k_pp).series(&velocity_closed);
        let position_closed = position_open.feedback(&StateSpace::gain(1.0))?;
        Ok(DiscreteLoops {
            velocity_open,
            velocity_closed,
            position_open,
            position_closed,
        })
    }
}

/// Largest closed-loop pole magnitudes of the discretized loops.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiscreteStability {
    /// Spectral radius of the closed velocity loop (< 1: stable).
    pub velocity_max_pole_magnitude: f64,
    /// Spectral radius of the closed position loop (< 1: stable).
    pub position_max_pole_magnitude: f64,
}

/// Closed-loop poles of both discretized loops; [`Error::Unstable`] if any pole
/// lies on or outside the unit circle.
///
/// The closed velocity loop (to the motor angle) always keeps the rigid-body
/// position mode at `z = 1`: the velocity filter's zero at `z = 1` cancels the
/// plant's integrator, so the velocity loop neither sees nor moves it (the position
/// loop closes it). That one eigenvalue is excluded from the velocity-loop check.
pub fn check_stability(loops: &DiscreteLoops) -> Result<DiscreteStability> {
    let mut poles = loops.velocity_closed.poles();
    if let Some(i) = poles
        .iter()
        .position(|p| (p - crate::lti::C64::new(1.0, 0.0)).norm() < RIGID_MODE_TOL)
    {
        poles.swap_remove(i);
    }
    let v = poles.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let p = loops.position_closed.spectral_radius();
    for (name, r) in [("velocity", v), ("position", p)] {
        if r.is_nan() || r >= MAX_STABLE_POLE_MAGNITUDE {
            return Err(Error::Unstable {
                reason: format!(
                    "discretized {name} loop has a closed-loop pole of magnitude {r:.9} (>= 1)"
                ),
            });
        }
    }
    Ok(DiscreteStability {
        velocity_max_pole_magnitude: v,
        position_max_pole_magnitude: p,
    })
}

#[derive(serde::Serialize, serde::Deserialize)]
struct SosFields {
    b0: f64,
    b1: f64,
    b2: f64,
    a1: f64,
    a2: f64,
}

#[derive(serde::Serialize, serde::Deserialize)]
struct FirstOrderFields {
    b0: f64,
    b1: f64,
    a1: f64,
}

mod sos_serde {
    use super::{SosCoeffs, SosFields};
    pub fn serialize<S: serde::Serializer>(c: &SosCoeffs<f64>, s: S) -> Result<S::Ok, S::Error> {
        serde::Serialize::serialize(
            &SosFields {
                b0: c.b0,
                b1: c.b1,
                b2: c.b2,
                a1: c.a1,
                a2: c.a2,
            },
            s,
        )
    }
    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<SosCoeffs<f64>, D::Error> {
        let f: SosFields = serde::Deserialize::deserialize(d)?;
        Ok(SosCoeffs {
            b0: f.b0,
            b1: f.b1,
            b2: f.b2,
            a1: f.a1,
            a2: f.a2,
        })
    }
}

mod first_order_serde {
    use super::{FirstOrderCoeffs, FirstOrderFields};
    pub fn serialize<S: serde::Serializer>(
        c: &FirstOrderCoeffs<f64>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        serde::Serialize::serialize(
            &FirstOrderFields {
                b0: c.b0,
                b1: c.b1,
                a1: c.a1,
            },
            s,
        )
    }
    pub fn deserialize<'de, D: serde::Deserializer<'de>>(
        d: D,
    ) -> Result<FirstOrderCoeffs<f64>, D::Error> {
        let f: FirstOrderFields = serde::Deserialize::deserialize(d)?;
        Ok(FirstOrderCoeffs {
            b0: f.b0,
            b1: f.b1,
            a1: f.a1,
        })
    }
}
