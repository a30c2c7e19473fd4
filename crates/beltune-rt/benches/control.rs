//! One full cascade step (two prefilter sections, nonlinear feedforward with
//! preview, desired-velocity filter, anti-windup), f64 and f32.
//! `cargo bench -p beltune-rt --bench control`

use beltune_rt::control::{
    CascadeConfig, CascadeController, CascadeGains, Feedforward, MotionSample, Setpoint,
};
use beltune_rt::filter::{butterworth_lowpass, notch};
use beltune_rt::Real;
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn full_cascade<T: Real>() -> CascadeController<T> {
    let ts = 1e-4;
    let mut cfg = CascadeConfig::<f64>::new(CascadeGains::new(6.29, 0.12, 1.39), ts, 2e-3, 2.0)
        .expect("valid config");
    cfg.prefilter = [
        butterworth_lowpass(123.24, ts).expect("valid filter"),
        notch(673.0, 4.6, ts).expect("valid filter"),
    ];
    cfg.feedforward = Feedforward::nonlinear(2.14e-3, 2.53e-3, 0.125);
    cfg.feedforward_preview = true;
    cfg.filter_desired_velocity = true;
    CascadeController::new(cfg.cast()).expect("valid config")
}

fn bench_step<T: Real>(c: &mut Criterion, name: &str) {
    let mut ctrl = full_cascade::<T>();
    let now = MotionSample {
        angle_rad: T::from_f64(0.3),
        velocity_rad_s: T::from_f64(2.0),
        acceleration_rad_s2: T::from_f64(50.0),
    };
    let sp = Setpoint::with_preview(now, now);
    let mut angle = T::from_f64(0.29);
    c.bench_function(name, |b| {
        b.iter(|| {
            let out = ctrl.step(black_box(&sp), black_box(angle));
            // keep the loop state bounded and data-dependent
            angle = T::from_f64(0.29) + T::from_f64(1e-6) * out.torque_nm;
            out.torque_nm
        })
    });
}

fn benches(c: &mut Criterion) {
    bench_step::<f64>(c, "cascade_step_f64");
    bench_step::<f32>(c, "cascade_step_f32");
}

criterion_group!(control, benches);
criterion_main!(control);
