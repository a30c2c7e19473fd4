//! Instruction-count harness for the trajectory generator under
//! `valgrind --tool=callgrind` (repeatable on a loaded machine):
//!
//! ```text
//! cargo build -p beltune-rt --release --example trajectory_cost
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!     target/release/examples/trajectory_cost <plan|plan-general|plan-asymmetric|sample> <n>
//! ```
//!
//! Run with `n` and `2 n`; the difference of the total instruction counts
//! divided by `n` is the cost of one planning (thesis move 0 -> 0.5 m with the
//! limits of Table A.8) or one sample.

use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let method = args.get(1).map(String::as_str).unwrap_or("plan");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let limits = Limits {
        position_min: -0.01,
        position_max: 0.57,
        ..Limits::symmetric(5.0, 45.0, 40.0)
    };
    let start = State::at_rest(0.0);
    let target = State::at_rest(0.5);
    let mut acc = 0.0;
    match method {
        "plan" => {
            for _ in 0..n {
                let traj =
                    Trajectory::plan(black_box(&start), black_box(&target), black_box(&limits));
                acc += traj.map(|t| t.duration_s()).unwrap_or(0.0);
            }
        }
        "plan-general" => {
            for _ in 0..n {
                let traj = Trajectory::plan_with_general_solver(
                    black_box(&start),
                    black_box(&target),
                    black_box(&limits),
                );
                acc += traj.map(|t| t.duration_s()).unwrap_or(0.0);
            }
        }
        "plan-asymmetric" => {
            let slow_down = Limits {
                j_min: -20.0,
                ..limits
            };
            for _ in 0..n {
                let traj =
                    Trajectory::plan(black_box(&start), black_box(&target), black_box(&slow_down));
                acc += traj.map(|t| t.duration_s()).unwrap_or(0.0);
            }
        }
        "sample" => {
            let traj = Trajectory::plan(&start, &target, &limits).expect("plannable");
            let ts = 1e-4;
            let mut t = 0.0;
            for _ in 0..n {
                t += ts;
                if t > traj.duration_s() {
                    t = 0.0;
                }
                acc += traj.sample(black_box(t)).position;
            }
        }
        other => {
            eprintln!("unknown method `{other}` (plan | plan-general | plan-asymmetric | sample)");
            std::process::exit(2);
        }
    }
    println!("{acc}");
}
