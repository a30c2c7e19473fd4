//! Planning cost of `beltune-rt` against the reference rsruckig 3.0.1 on the
//! same seeded cases, interleaved in one process (issue: planning no slower
//! than Ruckig). Prints the ratio beltune-rt / rsruckig of the time per plan
//! (target <= 1.0). Both plan with a reused planner object, as a firmware
//! would. That the durations agree to 1e-9 is checked by
//! `tests/trajectory_vs_ruckig.rs` (`reused_planner_equals_rsruckig_and_fresh_plans`);
//! here the durations are compared again before timing.
//!
//! Run: `cargo bench -p beltune-rt --bench vs_ruckig`.

use beltune_rt::trajectory::{Limits, Planner, State};
use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rsruckig::prelude::*;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Seeded cases (rest-to-rest and moving, symmetric jerk: what rsruckig plans).
const CASES: usize = 2_000;

fn cases() -> Vec<(State, State, Limits)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x5EED_0031);
    let mut out = Vec::with_capacity(CASES);
    while out.len() < CASES {
        let v = 10f64.powf(rng.random_range(-1.0..1.0));
        let a = 10f64.powf(rng.random_range(0.0..2.0));
        let j = 10f64.powf(rng.random_range(1.0..3.0));
        let limits = Limits::symmetric(v, a, j);
        let moving = out.len() % 2 == 1;
        let state = |rng: &mut Xoshiro256PlusPlus| State {
            position: rng.random_range(-1.0..1.0),
            velocity: if moving {
                rng.random_range(-0.8..0.8) * v
            } else {
                0.0
            },
            acceleration: if moving {
                rng.random_range(-0.5..0.5) * a
            } else {
                0.0
            },
        };
        let (start, target) = (state(&mut rng), state(&mut rng));
        out.push((start, target, limits));
    }
    out
}

struct Reference {
    otg: Ruckig<1, ThrowErrorHandler>,
    input: InputParameter<1>,
    traj: rsruckig::trajectory::Trajectory<1>,
}

impl Reference {
    fn new() -> Self {
        Self {
            otg: Ruckig::<1, ThrowErrorHandler>::new(None, 1e-4),
            input: InputParameter::new(None),
            traj: rsruckig::trajectory::Trajectory::new(None),
        }
    }

    fn plan(&mut self, start: &State, target: &State, l: &Limits) -> Option<f64> {
        let i = &mut self.input;
        i.current_position[0] = start.position;
        i.current_velocity[0] = start.velocity;
        i.current_acceleration[0] = start.acceleration;
        i.target_position[0] = target.position;
        i.target_velocity[0] = target.velocity;
        i.target_acceleration[0] = target.acceleration;
        i.max_velocity[0] = l.v_max;
        i.max_acceleration[0] = l.a_max;
        i.max_jerk[0] = l.j_max;
        i.min_velocity = Some(DataArrayOrVec::Stack([l.v_min]));
        i.min_acceleration = Some(DataArrayOrVec::Stack([l.a_min]));
        match self.otg.calculate(&self.input, &mut self.traj) {
            Ok(RuckigResult::Working) => Some(self.traj.get_duration()),
            _ => None,
        }
    }
}

fn bench_vs_ruckig(c: &mut Criterion) {
    let mut ours = Planner::default();
    let mut reference = Reference::new();
    // Only what the reference can plan (it refuses some moving targets whose
    // velocity cannot be reached within the limits).
    let mut cases = cases();
    cases.retain(|(s, t, l)| reference.plan(s, t, l).is_some());
    println!(
        "{} of {CASES} seeded cases planned by rsruckig",
        cases.len()
    );
    // Same answers first (the unit test checks 12,000 cases).
    for (s, t, l) in &cases {
        let d_ref = reference.plan(s, t, l).expect("kept above");
        let d = ours
            .plan(s, t, l)
            .expect("beltune-rt plans the case")
            .duration_s();
        assert!((d - d_ref).abs() <= 1e-9 * d_ref + 1e-12, "{d} vs {d_ref}");
    }
    let mut group = c.benchmark_group("plan the seeded cases");
    group.bench_function("beltune-rt Planner::plan", |b| {
        b.iter(|| {
            for (s, t, l) in &cases {
                let _ = black_box(ours.plan(black_box(s), black_box(t), black_box(l)));
            }
        })
    });
    group.bench_function("rsruckig Ruckig::calculate", |b| {
        b.iter(|| {
            for (s, t, l) in &cases {
                black_box(reference.plan(black_box(s), black_box(t), black_box(l)));
            }
        })
    });
    group.finish();

    // The ratio from interleaved rounds (the machine is shared: the
    // interleaving lets both see the same load).
    let (mut t_ours, mut t_ref) = (Duration::ZERO, Duration::ZERO);
    for _ in 0..50 {
        let t0 = Instant::now();
        for (s, t, l) in &cases {
            let _ = black_box(ours.plan(black_box(s), black_box(t), black_box(l)));
        }
        let t1 = Instant::now();
        for (s, t, l) in &cases {
            black_box(reference.plan(black_box(s), black_box(t), black_box(l)));
        }
        let t2 = Instant::now();
        t_ours += t1 - t0;
        t_ref += t2 - t1;
    }
    let per_plan = |d: Duration| d.as_secs_f64() * 1e9 / (50 * cases.len()) as f64;
    println!(
        "per plan: beltune-rt {:.0} ns, rsruckig {:.0} ns, ratio beltune-rt/rsruckig {:.3} (target <= 1.0)",
        per_plan(t_ours),
        per_plan(t_ref),
        t_ours.as_secs_f64() / t_ref.as_secs_f64()
    );
}

criterion_group!(benches, bench_vs_ruckig);
criterion_main!(benches);
