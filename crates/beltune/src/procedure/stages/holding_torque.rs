//! Stage 3: the torque that holds the cart against gravity (thesis chapter 7),
//! from a slow run up and a slow run down around the identification position:
//! the mean of the two mean torques cancels Coulomb and viscous friction. (The
//! thesis proposes an integrating position loop; its static torque is only
//! known within the friction band, this is not.)

use super::super::commission::{positioning_limits, DataSheet};
use super::super::motion::{move_to, track, TrackOptions};
use super::friction::constant_velocity_point;
use super::Stages;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::{Limits, State, Trajectory};

/// Speed of the two runs, m/s.
const RUN_SPEED_M_S: f64 = 0.1;
/// Half the length of the runs, m (each run is twice this long).
const RUN_HALF_M: f64 = 0.03;

/// Stage 3: the holding torque, N m, measured with `ctrl` around `center_m`.
pub fn holding_torque_stage(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    center_m: f64,
    ds: &DataSheet,
) -> Result<f64> {
    st.start("holding torque", 0);
    let holding = holding_torque(st, ctrl, center_m, ds)?;
    let line = format!(
        "{holding:+.4} N m (mean of slow up and down runs: friction cancels; offset for the open-loop excitation)"
    );
    st.finish("holding torque", line);
    Ok(holding)
}

fn holding_torque(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    center_m: f64,
    ds: &DataSheet,
) -> Result<f64> {
    let v = RUN_SPEED_M_S;
    let half = RUN_HALF_M;
    let limits = Limits {
        v_max: v,
        v_min: -v,
        a_max: 4.0,
        a_min: -4.0,
        j_max: 100.0,
        j_min: -100.0,
        position_min: ds.travel_min_m,
        position_max: ds.travel_max_m,
    };
    let runner = &mut *st.runner;
    move_to(runner, ctrl, center_m - half, &positioning_limits(ds), 0.05)?;
    let mut torques = Vec::new();
    for target in [center_m + half, center_m - half] {
        let traj = Trajectory::plan(
            &State::at_rest(runner.position_m()),
            &State::at_rest(target),
            &limits,
        )?;
        let rec = track(runner, ctrl, &traj, 0.0, TrackOptions::default())?;
        let point = constant_velocity_point(&rec, v, None).ok_or_else(|| Error::TooShort {
            what: "holding-torque run (constant-velocity part)".into(),
            needed: 40,
            got: 0,
        })?;
        torques.push(point.mean_torque_nm);
    }
    move_to(runner, ctrl, center_m, &positioning_limits(ds), 0.05)?;
    Ok(0.5 * (torques[0] + torques[1]))
}
