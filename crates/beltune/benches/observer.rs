//! Cost of the cart observer of the friction-aware fit
//! (`beltune::ident::nonlinear::observer::belt_torque`): one call per
//! evaluation of the fit's objective, a few hundred per commissioning.
//!
//! `cargo bench -p beltune --bench observer`: criterion reports the time of
//! one call on a 10-s record at 10 kHz (100,000 samples) with stick-slip
//! (a cart on a soft belt whose motor side reverses).

use beltune::ident::nonlinear::observer::{belt_torque, CartParams};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let (ts, i_t) = (1e-4, 0.0124);
    let angle: Vec<f64> = (0..100_000)
        .map(|k| {
            let t = k as f64 * ts;
            (0.02 * (2.0 * std::f64::consts::PI * 1.3 * t).sin()
                + 0.001 * (2.0 * std::f64::consts::PI * 23.0 * t).sin())
                / i_t
        })
        .collect();
    let cart = CartParams {
        m_c: 12.0,
        c: 6e5,
        d: 60.0,
        d_c: 15.0,
        f_c: 20.0,
    };
    c.bench_function("belt_torque, 100k samples", |b| {
        b.iter(|| belt_torque(black_box(&angle), ts, i_t, -40.0, black_box(&cart)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
