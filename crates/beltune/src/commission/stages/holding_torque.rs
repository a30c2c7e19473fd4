//! Stage 3: the torque that holds the cart against gravity (thesis chapter 7),
//! from slow runs up and down where the axis was taken, at two speeds: the
//! mean of an up and a down run cancels Coulomb and viscous friction, the
//! friction at the two speeds separates them. (The thesis proposes an
//! integrating position loop; its static torque is only known within the
//! friction band, this is not.) The friction then fits the bootstrap
//! controller to the axis ([`crate::commission::bootstrap::bootstrap_with_friction`])
//! before the long move to the identification position.

use super::super::config::POSITIONING_ACCELERATION_M_S2;
use super::super::motion::{move_to, track, TrackOptions};
use super::super::safety::StopCapability;
use super::super::{positioning_limits, DataSheet};
use super::friction::constant_velocity_point;
use super::Stages;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Speeds of the runs (each up and down), m/s.
const RUN_SPEEDS_M_S: [f64; 2] = [0.15, 0.3];
/// Half the length of the runs, m (each run is twice this long).
const RUN_HALF_M: f64 = 0.03;
/// Distance the runs keep from the window's edges, m (the bootstrap loop
/// may lag and overshoot before the friction is known).
const RUN_CLEARANCE_M: f64 = 0.05;

/// What stage 3 hands on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Holding {
    /// Holding torque (gravity), N m: the mean of the up and down runs.
    pub holding_nm: f64,
    /// Coulomb friction at the motor, N m: half the difference of the up and
    /// down runs, extrapolated to zero speed over the two speeds.
    pub friction_nm: f64,
    /// Viscous friction at the motor, N m s/rad: the slope of the friction
    /// between the two speeds (never negative).
    pub viscous_nm_s_per_rad: f64,
}

/// The centre of the holding-torque runs near `position_m`: inside the
/// window of `ds` by the runs' half length and a clearance, m.
pub fn run_center_m(position_m: f64, ds: &DataSheet) -> f64 {
    let lo = ds.travel_min_m + RUN_HALF_M + RUN_CLEARANCE_M;
    let hi = ds.travel_max_m - RUN_HALF_M - RUN_CLEARANCE_M;
    if lo > hi {
        0.5 * (ds.travel_min_m + ds.travel_max_m)
    } else {
        position_m.clamp(lo, hi)
    }
}

/// One speed's up and down run: mean torque (N m) at the measured motor
/// velocity (rad/s) of each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunPair {
    /// Mean torque of the run towards +x, N m.
    pub up_nm: f64,
    /// Its motor velocity, rad/s (positive).
    pub up_rad_s: f64,
    /// Mean torque of the run towards -x, N m.
    pub down_nm: f64,
    /// Its motor velocity, rad/s (negative).
    pub down_rad_s: f64,
}

/// Gravity, Coulomb and viscous friction from the run pairs of two (or more)
/// speeds: `tau = tau_h + tau_c sign(w) + d w`. The friction of each pair
/// is half the difference of its torques at the mean speed; the viscous
/// part is the slope between the slowest and the fastest pair (0 if
/// negative: noise), the Coulomb part the rest at the slowest; gravity the
/// mean torque of a pair minus the viscous torque of its speed asymmetry.
pub fn holding_from_runs(pairs: &[RunPair]) -> Holding {
    let friction = |p: &RunPair| 0.5 * (p.up_nm - p.down_nm);
    let speed = |p: &RunPair| 0.5 * (p.up_rad_s - p.down_rad_s);
    let (slow, fast) = (pairs[0], pairs[pairs.len() - 1]);
    let dw = speed(&fast) - speed(&slow);
    let viscous = if pairs.len() > 1 && dw > 0.0 {
        ((friction(&fast) - friction(&slow)) / dw).max(0.0)
    } else {
        0.0
    };
    let coulomb = (friction(&slow) - viscous * speed(&slow)).max(0.0);
    let holding = pairs
        .iter()
        .map(|p| 0.5 * (p.up_nm + p.down_nm) - viscous * 0.5 * (p.up_rad_s + p.down_rad_s))
        .sum::<f64>()
        / pairs.len() as f64;
    Holding {
        holding_nm: holding,
        friction_nm: coulomb,
        viscous_nm_s_per_rad: viscous,
    }
}

/// Stage 3: the holding torque measured with `ctrl` around `center_m`. The
/// supervisor's stops then brake with what gravity leaves in each direction;
/// an axis whose holding torque leaves too little torque to stop is refused
/// ([`crate::Error::Infeasible`]).
pub fn holding_torque_stage(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    center_m: f64,
    ds: &DataSheet,
    torque_max_nm: f64,
) -> Result<Holding> {
    st.start("holding torque", 0);
    let pairs = holding_runs(st, ctrl, center_m, ds, torque_max_nm)?;
    let holding = holding_from_runs(&pairs);
    st.runner.set_stop_capability(StopCapability::from_axis(
        torque_max_nm,
        ds.rigid_inertia(),
        ds.i_t_m,
        holding.holding_nm,
        holding.friction_nm,
    )?)?;
    let line = format!(
        "{:+.4} N m (mean of slow up and down runs at {:.2} and {:.2} m/s around {:.1} mm: friction cancels; offset for the open-loop excitation), Coulomb friction {:.4} N m, viscous {:.3e} N m s/rad",
        holding.holding_nm,
        RUN_SPEEDS_M_S[0],
        RUN_SPEEDS_M_S[1],
        center_m * 1e3,
        holding.friction_nm,
        holding.viscous_nm_s_per_rad
    );
    st.finish("holding torque", line);
    Ok(holding)
}

/// The bootstrap controller fitted to the friction stage 3 measured
/// ([`crate::commission::bootstrap_margin::bootstrap_for_whole_stroke`]: the
/// data-sheet inertia, the margin over the resonances it allows along the
/// whole stroke), holding the measured holding torque as its offset: the
/// controller of the positioning moves and the stops from here on.
pub fn fitted_bootstrap(
    held: &Holding,
    ds: &DataSheet,
    ts_s: f64,
    torque_max_nm: f64,
) -> Result<CascadeConfig<f64>> {
    let (mut c, _) = crate::commission::bootstrap_margin::bootstrap_for_whole_stroke(
        ds,
        ts_s,
        torque_max_nm,
        held.viscous_nm_s_per_rad,
    )?;
    c.torque_offset_nm = held.holding_nm;
    // A loop lowered below the crossover rule's floor for a low
    // antiresonance (a long gantry) builds the friction torque too slowly
    // from its error (`e ~ tau_f i_t / (K_P K_I / J ...)`, 70 mm for 0.035
    // N m at 1.4 Hz on a 2.9 m GT2 gantry, a following-error stop at the
    // first reversal): the Coulomb friction the runs measured is fed
    // forward with the inertia.
    let crossover_hz = c.gains.k_p_nm_s_per_rad / ds.rigid_inertia() / (2.0 * std::f64::consts::PI);
    if crossover_hz < crate::commission::bootstrap::BOOTSTRAP_CROSSOVER_MIN_HZ * (1.0 - 1e-9) {
        c.feedforward = beltune_rt::control::Feedforward::nonlinear(
            c.feedforward.params.inertia_kg_m2,
            c.feedforward.params.viscous_nm_s_per_rad,
            held.friction_nm,
        );
    }
    Ok(c)
}

/// Fraction of the torque limit at which a run counts as saturated.
const SATURATED_FRACTION: f64 = 0.95;

/// Why an axis whose slow run saturated the torque is refused, one line.
fn saturated_reason(v_m_s: f64, peak_nm: f64, torque_max_nm: f64) -> String {
    format!(
        "the axis cannot move at {v_m_s:.2} m/s within the torque limit {torque_max_nm:.3} N m (the slow run needed {peak_nm:.3} N m): gravity and friction take the torque"
    )
}

/// The runs: the slow pair with `ctrl`, the fast pair with the bootstrap
/// fitted to the viscous friction the slow pair bounds (all its friction
/// taken as viscous: `d <= tau_f / w`), so that a heavily damped axis tracks
/// the fast runs (on sim-b the unfitted loop lagged so far that
/// the fast runs had no constant-velocity part).
fn holding_runs(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    center_m: f64,
    ds: &DataSheet,
    torque_max_nm: f64,
) -> Result<Vec<RunPair>> {
    let half = RUN_HALF_M;
    let ts = st.runner.info().ts_s;
    let runner = &mut *st.runner;
    let mut ctrl = *ctrl;
    let mut pairs = Vec::with_capacity(RUN_SPEEDS_M_S.len());
    'speeds: for (i, v) in RUN_SPEEDS_M_S.into_iter().enumerate() {
        // The faster runs only where the axis can stop from their speed
        // with room to spare in both directions (a heavy cart on
        // a steep axis brakes downhill with little torque; its look-ahead
        // stopped the fast run towards the lower edge).
        let sup = runner.supervisor();
        let room = (center_m - half - sup.limits().travel_min_m)
            .min(sup.limits().travel_max_m - center_m - half);
        if i > 0 && 2.0 * sup.stopping_distance_m(v).max(sup.stopping_distance_m(-v)) > room {
            break 'speeds;
        }
        if let Some(slow) = pairs.first() {
            let bound = holding_from_runs(&[*slow]);
            let w = 0.5 * (slow.up_rad_s - slow.down_rad_s);
            if w > 0.0 {
                let offset = ctrl.torque_offset_nm;
                ctrl = crate::commission::bootstrap_margin::bootstrap_for_data_sheet(
                    ds,
                    ts,
                    torque_max_nm,
                    bound.friction_nm / w,
                )?
                .0;
                ctrl.torque_offset_nm = offset;
            }
        }
        move_to(
            runner,
            &ctrl,
            center_m - half,
            &positioning_limits(ds),
            0.02,
        )?;
        let limits = Limits {
            v_max: v,
            v_min: -v,
            a_max: POSITIONING_ACCELERATION_M_S2,
            a_min: -POSITIONING_ACCELERATION_M_S2,
            j_max: 100.0,
            j_min: -100.0,
            position_min: ds.travel_min_m,
            position_max: ds.travel_max_m,
        };
        let mut points = [(0.0, 0.0); 2];
        for (point, target) in points.iter_mut().zip([center_m + half, center_m - half]) {
            let traj = Trajectory::plan(
                &State::at_rest(runner.position_m()),
                &State::at_rest(target),
                &limits,
            )?;
            let rec = track(runner, &ctrl, &traj, 0.0, TrackOptions::default())?;
            let Some(run) = constant_velocity_point(&rec, v, None) else {
                if i == 0 {
                    // a loop at the torque limit: the axis cannot follow
                    // the slow run (gravity and friction take the torque)
                    let peak = rec
                        .samples
                        .iter()
                        .map(|s| s.torque_command_nm.abs())
                        .fold(0.0, f64::max);
                    if peak >= SATURATED_FRACTION * torque_max_nm {
                        return Err(Error::Infeasible {
                            reason: saturated_reason(v, peak, torque_max_nm),
                        });
                    }
                    return Err(Error::TooShort {
                        what: "holding-torque run (constant-velocity part)".into(),
                        needed: 40,
                        got: 0,
                    });
                }
                // No plateau at the faster speed (a short run): the slow
                // pair alone, without a viscous part.
                break 'speeds;
            };
            *point = (run.mean_torque_nm, run.velocity_rad_s);
        }
        pairs.push(RunPair {
            up_nm: points[0].0,
            up_rad_s: points[0].1,
            down_nm: points[1].0,
            down_rad_s: points[1].1,
        });
    }
    Ok(pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An underpowered gantry was refused with "record too short for
    /// holding-torque run": the refusal names the physical reason.
    #[test]
    fn a_saturated_run_is_refused_for_its_torque() {
        let r = saturated_reason(0.15, 0.4, 0.4);
        assert!(r.contains("torque limit 0.400 N m") && r.contains("friction"));
        assert!(!r.contains('\n'));
    }

    /// The separation is exact on the friction model it assumes, also with
    /// runs slower one way than the other (a lagging loop).
    #[test]
    fn gravity_coulomb_and_viscous_friction_separate() {
        let (h, c, d) = (0.7, 0.12, 0.03);
        let tau = |w: f64| h + c * w.signum() + d * w;
        let pair = |up: f64, down: f64| RunPair {
            up_nm: tau(up),
            up_rad_s: up,
            down_nm: tau(-down),
            down_rad_s: -down,
        };
        let got = holding_from_runs(&[pair(8.0, 7.5), pair(16.0, 15.0)]);
        assert!((got.holding_nm - h).abs() < 1e-12, "{got:?}");
        assert!((got.friction_nm - c).abs() < 1e-12, "{got:?}");
        assert!((got.viscous_nm_s_per_rad - d).abs() < 1e-12, "{got:?}");
        // A negative slope (noise) is no viscous friction.
        let noisy = RunPair {
            up_nm: 1.0,
            up_rad_s: 16.0,
            down_nm: -1.0,
            down_rad_s: -16.0,
        };
        let slow = RunPair {
            up_nm: 1.2,
            up_rad_s: 8.0,
            down_nm: -1.2,
            down_rad_s: -8.0,
        };
        let got = holding_from_runs(&[slow, noisy]);
        assert_eq!(got.viscous_nm_s_per_rad, 0.0);
        assert!((got.friction_nm - 1.2).abs() < 1e-12);
    }
}
