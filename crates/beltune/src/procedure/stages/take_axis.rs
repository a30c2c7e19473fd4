//! Stage 2: take the axis (hold it where it is until the integrator carries
//! the load: a vertical axis sags first) for a first holding torque; after
//! the holding-torque runs (stage 3, where the axis was taken), move to the
//! identification position, the cart farthest from the motor (longest belt
//! segment, lowest resonance: the worst case, thesis 2.2), with the
//! bootstrap controller fitted to the measured friction.

use super::super::commission::{positioning_limits, DataSheet};
use super::super::motion::move_to;
use super::super::runner::{Runner, Sample};
use super::super::safety::StopCapability;
use super::Stages;
use crate::Result;
use beltune_rt::control::{CascadeConfig, CascadeController, Setpoint};

/// How long the axis is held when it is taken, s.
const CATCH_S: f64 = 0.3;

/// What stage 2 hands on.
pub struct TakenAxis {
    /// The bootstrap controller with the first holding torque as its offset.
    pub bootstrap: CascadeConfig<f64>,
    /// The identification position, m.
    pub identification_position_m: f64,
}

/// Stage 2: take the axis with `bootstrap` (the identification position is
/// only computed; [`move_to_worst_case`] goes there after stage 3).
pub fn take_axis(
    st: &mut Stages,
    bootstrap: CascadeConfig<f64>,
    datasheet: &DataSheet,
    torque_max_nm: f64,
) -> Result<TakenAxis> {
    st.start("take axis", 0);
    let start = st.runner.position_m();
    let rec = hold(st.runner, &bootstrap, CATCH_S)?;
    let tail = &rec[rec.len() / 2..];
    let first_hold = tail.iter().map(|s| s.torque_command_nm).sum::<f64>() / tail.len() as f64;
    let mut boot = bootstrap;
    boot.torque_offset_nm = first_hold;
    st.runner.set_stop_controller(boot);
    // The first holding torque is gravity (and friction): the stops brake
    // with what is left of the torque in each direction (issue 12). It is
    // known only within the friction band, so it does not refuse the axis:
    // the holding-torque stage does, on gravity measured without friction.
    st.runner.set_stop_capability(StopCapability::provisional(
        torque_max_nm,
        datasheet.rigid_inertia(),
        datasheet.i_t_m,
        first_hold,
    )?)?;
    let line = format!(
        "held at {:.1} mm (sag {:.2} mm) with {first_hold:+.3} N m",
        st.runner.position_m() * 1e3,
        (st.runner.position_m() - start) * 1e3
    );
    st.finish("take axis", line);

    Ok(TakenAxis {
        bootstrap: boot,
        identification_position_m: identification_position_m(datasheet),
    })
}

/// The identification position of `ds`: the cart far from the motor, 12 %
/// of the window (at least 50 mm) inside its upper edge, m.
pub fn identification_position_m(ds: &DataSheet) -> f64 {
    let width = ds.travel_max_m - ds.travel_min_m;
    ds.travel_max_m - (0.12 * width).max(0.05)
}

/// Stage 3b: move to the identification position `id_pos_m` with the
/// bootstrap `ctrl` fitted to the measured friction.
pub fn move_to_worst_case(
    st: &mut Stages,
    ctrl: &CascadeConfig<f64>,
    id_pos_m: f64,
    datasheet: &DataSheet,
) -> Result<()> {
    st.start("move to worst-case position", 0);
    move_to(
        st.runner,
        ctrl,
        id_pos_m,
        &positioning_limits(datasheet),
        0.1,
    )?;
    let line = format!(
        "at {:.1} mm (cart far from the motor: longest belt segment, lowest resonance)",
        st.runner.position_m() * 1e3
    );
    st.finish("position", line);
    Ok(())
}

/// Hold the current position with `ctrl` for `duration_s` (no following-error
/// check: the load may sag while the integrator takes it).
pub fn hold(
    runner: &mut Runner,
    ctrl: &CascadeConfig<f64>,
    duration_s: f64,
) -> Result<Vec<Sample>> {
    let ts = runner.info().ts_s;
    let mut c = CascadeController::new(*ctrl)?;
    let target = runner.motor_angle_rad();
    c.reset_to(target);
    let n = (duration_s / ts).ceil() as usize;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let o = c.step(&Setpoint::hold(target), runner.motor_angle_rad());
        out.push(runner.step(o.torque_nm, None)?);
    }
    Ok(out)
}
