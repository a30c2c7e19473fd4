//! Instruction-count harness for `valgrind --tool=callgrind` (repeatable on a
//! loaded machine, unlike wall-clock benchmarks):
//!
//! ```text
//! cargo build -p beltune-rt --release --example velocity_cost
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!     target/release/examples/velocity_cost <method> <n>
//! ```
//!
//! Run with `n` and `2 n` updates; the difference of the total instruction
//! counts divided by `n` is the cost of one update. `<method>` is one of
//! `highpass`, `event`, `gate`, `blend`, `blend32`, `prbs`, `decoder`.

use std::hint::black_box;

use beltune_rt::encoder::{quadrature_levels, EdgeWindow, QuadratureDecoder};
use beltune_rt::prbs::Prbs;
use beltune_rt::velocity::{
    Blended, EncoderResolution, EventCounter, GateMeasurement, HighPassDifferentiator,
};

const MASK: usize = 4095;

fn windows(r: &EncoderResolution) -> Vec<(EdgeWindow, u64)> {
    let (a, b) = quadrature_levels(0);
    let mut d = QuadratureDecoder::new(a, b);
    let tps = r.ticks_per_sample();
    let mut out = Vec::with_capacity(MASK + 1);
    let (mut pos, mut t) = (0i64, 0.0f64);
    for k in 1..=(MASK as u64 + 1) {
        let speed = 0.002 * 250.0f64.powf((k % 1024) as f64 / 1023.0);
        let end = k * tps;
        while (t as u64) < end {
            pos += 1;
            let (a, b) = quadrature_levels(pos);
            d.update(a, b, t as u64);
            t += r.increment / speed / r.tick_s;
        }
        out.push((d.take_window(), end));
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let method = args.get(1).map(String::as_str).unwrap_or("blend");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let r = EncoderResolution::thesis();
    let w = windows(&r);
    let mut acc = 0.0f64;
    match method {
        "highpass" => {
            let mut e = HighPassDifferentiator::<f64>::new(&r, 2e-3).unwrap();
            for i in 0..n {
                acc += e.update(black_box(w[i & MASK].0.net_counts));
            }
        }
        "event" => {
            let mut e = EventCounter::<f64>::new(&r).unwrap();
            for i in 0..n {
                acc += e.update(black_box(&w[i & MASK].0));
            }
        }
        "gate" => {
            let mut e = GateMeasurement::<f64>::new(&r, 20e-3).unwrap();
            for i in 0..n {
                let (win, now) = &w[i & MASK];
                acc += e.update(black_box(win), black_box(*now));
            }
        }
        "blend" => {
            let mut e = Blended::<f64>::new(&r, 20e-3, 2e-3).unwrap();
            for i in 0..n {
                let (win, now) = &w[i & MASK];
                acc += e.update(black_box(win), black_box(*now));
            }
        }
        "blend32" => {
            let mut e = Blended::<f32>::new(&r, 20e-3, 2e-3).unwrap();
            for i in 0..n {
                let (win, now) = &w[i & MASK];
                acc += f64::from(e.update(black_box(win), black_box(*now)));
            }
        }
        "prbs" => {
            let mut p = Prbs::<f64>::new(12, 1, 0.3).unwrap();
            for _ in 0..n {
                acc += black_box(p.step());
            }
        }
        "decoder" => {
            let (a, b) = quadrature_levels(0);
            let mut d = QuadratureDecoder::new(a, b);
            for i in 0..n {
                let (a, b) = quadrature_levels(i as i64 + 1);
                if let Some(inc) = d.update(black_box(a), black_box(b), black_box(i as u64)) {
                    acc += f64::from(inc.direction.sign());
                }
            }
        }
        other => {
            eprintln!("error: unknown method `{other}`");
            std::process::exit(1);
        }
    }
    println!("{method} {n} {acc}");
}
