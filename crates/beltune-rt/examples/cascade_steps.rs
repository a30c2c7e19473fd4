//! Runs `N` steps of the full cascade (two prefilter sections, nonlinear
//! feedforward with preview, desired-velocity filter, anti-windup) in `f64` or
//! `f32`, for counting instructions per step with callgrind:
//!
//! ```sh
//! cargo build --release -p beltune-rt --example cascade_steps
//! valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.1 target/release/examples/cascade_steps f64 100000
//! valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.2 target/release/examples/cascade_steps f64 200000
//! # instructions per step = (total(200000) - total(100000)) / 100000
//! ```

use beltune_rt::control::{
    CascadeConfig, CascadeController, CascadeGains, Feedforward, MotionSample, Setpoint,
};
use beltune_rt::filter::{butterworth_lowpass, notch};
use beltune_rt::{Error, Real};
use std::hint::black_box;

/// The controller every benchmark and cost measurement uses: Table A.7-sized
/// gains, Butterworth (4.3) and notch (4.1) prefilter, nonlinear feedforward
/// (Table A.10) with preview and desired-velocity filter, anti-windup on.
fn full_cascade<T: Real>() -> Result<CascadeController<T>, Error> {
    let ts = 1e-4;
    let mut cfg = CascadeConfig::<f64>::new(CascadeGains::new(6.29, 0.12, 1.39), ts, 2e-3, 2.0)?;
    cfg.prefilter = [butterworth_lowpass(123.24, ts)?, notch(673.0, 4.6, ts)?];
    cfg.feedforward = Feedforward::nonlinear(2.14e-3, 2.53e-3, 0.125);
    cfg.feedforward_preview = true;
    cfg.filter_desired_velocity = true;
    CascadeController::new(cfg.cast())
}

/// One controller step, kept out of line so that callgrind can attribute its
/// instructions (`callgrind_annotate --inclusive=yes`).
#[inline(never)]
fn controller_step<T: Real>(ctrl: &mut CascadeController<T>, sp: &Setpoint<T>, angle: T) -> T {
    ctrl.step(sp, angle).torque_nm
}

fn run<T: Real>(n: u64) -> Result<f64, Error> {
    let mut ctrl = full_cascade::<T>()?;
    let mut acc = T::ZERO;
    let mut angle = T::ZERO;
    let dt = T::from_f64(1e-4);
    for k in 0..n {
        // a slow ramp with a small position error, so no branch is constant
        let t = T::from_f64((k % 10_000) as f64) * dt;
        let now = MotionSample {
            angle_rad: t,
            velocity_rad_s: T::ONE,
            acceleration_rad_s2: T::from_f64(((k / 500) % 3) as f64 - 1.0),
        };
        let sp = Setpoint::with_preview(now, now);
        let torque = controller_step(&mut ctrl, black_box(&sp), black_box(angle));
        angle = t - T::from_f64(1e-3) * torque;
        acc += torque;
    }
    Ok(acc.to_f64())
}

fn main() -> Result<(), Error> {
    let mut args = std::env::args().skip(1);
    let ty = args.next().unwrap_or_else(|| "f64".into());
    let n: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let sum = match ty.as_str() {
        "f32" => run::<f32>(n)?,
        _ => run::<f64>(n)?,
    };
    println!("{ty} {n} steps, checksum {sum:.6e}");
    Ok(())
}
