//! Cost of one trajectory planning and one sample (item 9).
//! Run: `cargo bench -p beltune-rt --bench trajectory`.

use beltune_rt::trajectory::{Limits, State, Trajectory};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn thesis_limits() -> Limits {
    Limits {
        position_min: -0.01,
        position_max: 0.57,
        ..Limits::symmetric(5.0, 45.0, 40.0)
    }
}

fn bench_trajectory(c: &mut Criterion) {
    let limits = thesis_limits();
    let start = State::at_rest(0.0);
    let target = State::at_rest(0.5);
    c.bench_function("trajectory plan (thesis 0 -> 0.5 m, Table A.8)", |b| {
        b.iter(|| Trajectory::plan(black_box(&start), black_box(&target), black_box(&limits)))
    });

    // Moving start and target, asymmetric limits: every profile family is tried.
    let general = Limits {
        v_max: 2.0,
        v_min: -1.5,
        a_max: 8.0,
        a_min: -5.0,
        j_max: 50.0,
        j_min: -50.0,
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
    };
    let moving_start = State {
        position: 0.3,
        velocity: 1.5,
        acceleration: -2.0,
    };
    let moving_target = State {
        position: -0.4,
        velocity: 0.2,
        acceleration: 1.0,
    };
    c.bench_function("trajectory plan (moving start and target)", |b| {
        b.iter(|| {
            Trajectory::plan(
                black_box(&moving_start),
                black_box(&moving_target),
                black_box(&general),
            )
        })
    });

    c.bench_function("trajectory plan, general solver (thesis move)", |b| {
        b.iter(|| {
            Trajectory::plan_with_general_solver(
                black_box(&start),
                black_box(&target),
                black_box(&limits),
            )
        })
    });
    let asymmetric = Limits {
        j_min: -25.0,
        ..general
    };
    c.bench_function("trajectory plan (moving, asymmetric jerk)", |b| {
        b.iter(|| {
            Trajectory::plan(
                black_box(&moving_start),
                black_box(&moving_target),
                black_box(&asymmetric),
            )
        })
    });

    let traj = Trajectory::plan(&start, &target, &limits).expect("plannable");
    let mut t = 0.0;
    c.bench_function("trajectory sample", |b| {
        b.iter(|| {
            t += 1e-4;
            if t > traj.duration_s() {
                t = 0.0;
            }
            traj.sample(black_box(t))
        })
    });
}

criterion_group!(benches, bench_trajectory);
criterion_main!(benches);
