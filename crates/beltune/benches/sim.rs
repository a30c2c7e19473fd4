//! Simulator speed as a real-time factor (simulated seconds per wall-clock
//! second) for the nonlinear three-mass plant `egc70` at 10 kHz, plus the
//! two-mass and linear variants for comparison.
//!
//! `cargo bench -p beltune --bench sim`: criterion reports the time per
//! simulated second (10,000 samples); the real-time factor is 1 s divided by it
//! and is printed at the end.

use beltune::model::builtin;
use beltune::sim::{SimAxis, SimConfig, SimModel};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Instant;

/// One simulated second: a PRBS-like torque (a sign sequence from an LCG), as
/// during identification, so that the friction switches between stick and slip.
fn one_second(axis: &mut SimAxis, state: &mut u64) -> i64 {
    let mut acc = 0;
    for _ in 0..10_000 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let tau = if (*state >> 63) == 1 { 0.15 } else { -0.15 };
        acc += axis.step(black_box(tau)).motor_counts;
    }
    acc
}

/// CPU time of this thread, s (Linux `/proc/thread-self/schedstat`, ns resolution).
fn thread_cpu_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

fn cases() -> Vec<(&'static str, SimAxis)> {
    let egc = builtin("egc70", None).expect("built-in");
    let three = SimAxis::new(&egc, SimConfig::default()).expect("valid");
    let two = SimAxis::new(
        &egc,
        SimConfig {
            model: SimModel::TwoMass,
            ..SimConfig::default()
        },
    )
    .expect("valid");
    let lin = SimAxis::new(
        &builtin("sim-a", None).expect("built-in"),
        SimConfig::default(),
    )
    .expect("valid");
    vec![
        ("egc70 three-mass", three),
        ("egc70 two-mass", two),
        ("sim-a linear", lin),
    ]
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("simulate 1 s at 10 kHz");
    for (name, axis) in cases() {
        let mut axis = axis;
        let mut state = 1u64;
        group.bench_function(name, |b| b.iter(|| one_second(&mut axis, &mut state)));
    }
    group.finish();
    // The headline number: real-time factor over 100 simulated seconds, by
    // wall clock and by the thread's CPU time (the latter is what the number
    // would be on an idle core; this machine's 2 cores are shared).
    for (name, mut axis) in cases() {
        let mut state = 7u64;
        let cpu0 = thread_cpu_s();
        let start = Instant::now();
        for _ in 0..100 {
            black_box(one_second(&mut axis, &mut state));
        }
        let wall = start.elapsed().as_secs_f64();
        let cpu = thread_cpu_s().zip(cpu0).map(|(b, a)| b - a);
        println!(
            "{name}: real-time factor {:.0}x by wall clock, {} by CPU time (100 s simulated, {} sub-steps per sample)",
            100.0 / wall,
            cpu.map(|c| format!("{:.0}x", 100.0 / c)).unwrap_or_else(|| "n/a".into()),
            axis.substeps()
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
