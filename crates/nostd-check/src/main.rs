//! Proof that `beltune-rt` is `#![no_std]` and allocation-free: this binary has
//! no standard library, no allocator and no `main`, and links on the host.
//! Any dependency of `beltune-rt` that pulls in `std` or `alloc` breaks the build.
//!
//! Built in CI with `cargo build -p nostd-check --profile nostd`.
#![no_std]
#![no_main]

use beltune_rt::control::{CascadeConfig, CascadeController, CascadeGains, Setpoint};
use beltune_rt::filter::{butterworth_lowpass, Sos};
use beltune_rt::trajectory::{Limits, State, Trajectory};

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    loop {}
}

/// The host's precompiled `core` references this unwinding hook even with
/// `panic = "abort"`; a bare-metal target would not. It is never called.
#[no_mangle]
pub extern "C" fn rust_eh_personality() {}

/// Entry point called by the C runtime. Runs one filter sample, one
/// controller step and one trajectory planning and sample so the real-time
/// code is actually linked, not just type-checked.
#[no_mangle]
pub extern "C" fn main(_argc: i32, _argv: *const *const u8) -> i32 {
    let coeffs = match butterworth_lowpass(123.24, 1e-4) {
        Ok(c) => c,
        Err(_) => return 1,
    };
    let mut f = Sos::new(coeffs);
    let y = f.step(1.0);
    let cfg = match CascadeConfig::<f32>::new(CascadeGains::new(6.29, 0.12, 1.39), 1e-4, 2e-3, 2.0)
    {
        Ok(c) => c,
        Err(_) => return 3,
    };
    let mut ctrl = match CascadeController::new(cfg) {
        Ok(c) => c,
        Err(_) => return 4,
    };
    let out = ctrl.step(&Setpoint::hold(0.01), 0.0);
    let traj = match Trajectory::plan(
        &State::at_rest(0.0),
        &State::at_rest(0.5),
        &Limits::default(),
    ) {
        Ok(t) => t,
        Err(_) => return 5,
    };
    let s = traj.sample(1e-4);
    // Asymmetric jerk: the general solver (polynomial roots) links too.
    let asymmetric = Limits {
        j_min: -20.0,
        ..Limits::default()
    };
    let slow_down = match Trajectory::plan(&State::at_rest(0.0), &State::at_rest(0.5), &asymmetric)
    {
        Ok(t) => t,
        Err(_) => return 6,
    };
    if y.is_finite()
        && out.finite
        && s.position.is_finite()
        && slow_down.duration_s() > traj.duration_s()
    {
        0
    } else {
        2
    }
}
