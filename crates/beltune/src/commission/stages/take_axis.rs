//! Stage 2: take the axis (hold it where it is until the integrator carries
//! the load: a vertical axis sags first) for a first holding torque; after
//! the holding-torque runs (stage 3, where the axis was taken), move to the
//! identification position, the cart farthest from the motor (longest belt
//! segment, lowest resonance: the worst case, thesis 2.2), with the
//! bootstrap controller fitted to the measured friction.

use super::super::motion::move_to;
use super::super::runner::{Runner, Sample};
use super::super::safety::{StopCapability, STOP_COMMAND_FRACTION, STOP_TORQUE_FRACTION};
use super::super::{positioning_limits, DataSheet};
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
    let rec = hold(
        st.runner,
        &bootstrap,
        datasheet.rigid_inertia(),
        torque_max_nm,
        CATCH_S,
    )?;
    let tail = &rec[rec.len() / 2..];
    let first_hold = tail.iter().map(|s| s.torque_command_nm).sum::<f64>() / tail.len() as f64;
    let mut boot = bootstrap;
    boot.torque_offset_nm = first_hold;
    st.runner.set_stop_controller(boot);
    // The first holding torque is gravity (and friction): the stops brake
    // with what is left of the torque in each direction. It is
    // known only within the friction band, so it refuses only a load that
    // takes the stop's whole command budget: the holding-torque stage does
    // the rest, on gravity measured without friction.
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
/// check: the load may sag while the integrator takes it), catching a
/// falling load whose first fall shows a holding torque beyond the stop
/// budget ([`STOP_TORQUE_FRACTION`] of `torque_max_nm`) with that torque
/// ([`fall_holding_torque_nm`] over [`FALL_WINDOW_S`], by the rigid-body
/// inertia `inertia_kg_m2`, [`FALL_TORQUE_SHARE`] of it, within
/// [`STOP_COMMAND_FRACTION`] of the limit) set as the controller's torque
/// offset. A lighter load leaves the stop enough torque to brake what the
/// loop's own catch lets it reach (at most 0.75 of the limit holding,
/// 0.25 left: 2.5 m/s^2 on a 25 kg egc70 stops 0.3 m/s within 20 mm) and
/// is caught by the loop alone, as before: the holding-torque runs, which
/// start from the first hold as their offset, measure what they measured.
///
/// The bootstrap loop alone builds the holding torque from the
/// sag through its slow velocity loop (a crossover of 4 Hz, kept below the
/// unidentified resonance): a 25 kg cart on a steep axis fell for 60 ms,
/// reached 0.31 m/s and, with 0.2 N m left of the torque limit to brake
/// it, ran 60 mm down and out of the window. Caught after the window the
/// cart falls about `a_g (W + T_t)`: 0.11 m/s.
pub fn hold(
    runner: &mut Runner,
    ctrl: &CascadeConfig<f64>,
    inertia_kg_m2: f64,
    torque_max_nm: f64,
    duration_s: f64,
) -> Result<Vec<Sample>> {
    let ts = runner.info().ts_s;
    let mut c = CascadeController::new(*ctrl)?;
    let target = runner.motor_angle_rad();
    let start_m = runner.position_m();
    c.reset_to(target);
    let n = (duration_s / ts).ceil() as usize;
    let n_fall = ((FALL_WINDOW_S / ts).round() as usize).clamp(2, n.max(2));
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let o = c.step(&Setpoint::hold(target), runner.motor_angle_rad());
        out.push(runner.step(o.torque_nm, None)?);
        if k + 1 == n_fall {
            let h = fall_holding_torque_nm(&out, start_m, ts, inertia_kg_m2, runner.i_t());
            let limit = STOP_COMMAND_FRACTION * torque_max_nm;
            let offset = (FALL_TORQUE_SHARE * h).clamp(-limit, limit);
            if offset.is_finite() && h.abs() > STOP_TORQUE_FRACTION * torque_max_nm {
                c.set_torque_offset(ctrl.torque_offset_nm + offset);
            }
        }
    }
    Ok(out)
}

/// How long the first fall of the load is watched before it is caught, s:
/// a few periods of the motor's resonance against the belt (100-200 Hz),
/// short against the cart's (15-80 Hz).
pub const FALL_WINDOW_S: f64 = 10e-3;
/// Share of the estimated holding torque set at once ([`hold`]): the motor
/// side lags or leads the cart while the belt takes the load; the loop
/// supplies the rest.
pub const FALL_TORQUE_SHARE: f64 = 0.8;

/// The holding torque a rigid body of inertia `inertia_kg_m2` (kg m^2)
/// shows in `samples` (one every `ts_s` from rest at `start_m`, the
/// commands applied): with `J x'' / i_t = tau - tau_h`, the least-squares
/// `tau_h` of `x_k - x_0 = (i_t / J) (S_k - tau_h t_k^2 / 2)`, `S_k` the
/// double integral of the commands, N m (kinetic friction makes it smaller
/// in magnitude by the friction). NaN for fewer than two samples.
pub fn fall_holding_torque_nm(
    samples: &[Sample],
    start_m: f64,
    ts_s: f64,
    inertia_kg_m2: f64,
    i_t_m: f64,
) -> f64 {
    let (mut w, mut s, mut num, mut den) = (0.0, 0.0, 0.0, 0.0);
    for (k, smp) in samples.iter().enumerate() {
        // velocity and position after sample k of the commands alone (per
        // unit inertia), exact for the zero-order hold of each command
        s += w * ts_s + 0.5 * smp.torque_command_nm * ts_s * ts_s;
        w += smp.torque_command_nm * ts_s;
        let t = (k + 1) as f64 * ts_s;
        let y = s - (smp.position_m - start_m) * inertia_kg_m2 / i_t_m;
        let q = 0.5 * t * t;
        num += y * q;
        den += q * q;
    }
    if samples.len() < 2 || den <= 0.0 {
        return f64::NAN;
    }
    num / den
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 12 (a heavy load falling while the loop builds its torque):
    /// the holding torque of a rigid body from its first fall is exact on a
    /// fall computed in closed form, with and without commands applied.
    #[test]
    fn the_first_fall_shows_the_holding_torque() {
        let (ts, j, i_t, x0) = (1e-4, 3.9e-3, 0.0124, 0.05);
        for (tau_h, command) in [(2.9, 0.0), (-1.3, 0.0), (2.9, 0.4), (0.0, 0.0)] {
            // x(t) = x0 + (i_t / J) (command - tau_h) t^2 / 2 for a constant command
            let samples: Vec<Sample> = (0..100)
                .map(|k| {
                    let t = (k + 1) as f64 * ts;
                    Sample {
                        torque_command_nm: command,
                        position_m: x0 + i_t / j * (command - tau_h) * t * t / 2.0,
                        ..Sample::default()
                    }
                })
                .collect();
            let got = fall_holding_torque_nm(&samples, x0, ts, j, i_t);
            assert!((got - tau_h).abs() < 1e-9, "{tau_h} with {command}: {got}");
        }
        // a ramp of the command (the loop reacting): the double integral
        let samples: Vec<Sample> = {
            let (mut x, mut v) = (x0, 0.0);
            (0..100)
                .map(|k| {
                    let tau = 0.01 * k as f64;
                    let a = i_t / j * (tau - 2.0);
                    x += v * ts + 0.5 * a * ts * ts;
                    v += a * ts;
                    Sample {
                        torque_command_nm: tau,
                        position_m: x,
                        ..Sample::default()
                    }
                })
                .collect()
        };
        let got = fall_holding_torque_nm(&samples, x0, ts, j, i_t);
        assert!((got - 2.0).abs() < 1e-9, "{got}");
        assert!(fall_holding_torque_nm(&samples[..1], x0, ts, j, i_t).is_nan());
    }
}
