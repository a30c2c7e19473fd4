//! Cost of one velocity-estimator update (each method), one decoder edge and
//! one excitation sample. Run: `cargo bench -p beltune-rt --bench velocity`.

use std::hint::black_box;

use beltune_rt::encoder::{quadrature_levels, EdgeWindow, QuadratureDecoder};
use beltune_rt::prbs::{Chirp, Multisine, Prbs, Sweep};
use beltune_rt::velocity::{
    Blended, EncoderResolution, EventCounter, GateMeasurement, HighPassDifferentiator,
};
use criterion::{criterion_group, criterion_main, Criterion};

/// Windows of a realistic stream: the speed sweeps 0.002..0.5 m/s so that all
/// branches (gate with timeout, blend band, event counter) are exercised.
fn windows(r: &EncoderResolution) -> Vec<(EdgeWindow, u64)> {
    let (a, b) = quadrature_levels(0);
    let mut d = QuadratureDecoder::new(a, b);
    let tps = r.ticks_per_sample();
    let mut out = Vec::with_capacity(4096);
    let mut pos = 0i64;
    let mut t = 0.0f64; // ticks of the next edge
    for k in 1..=4096u64 {
        let speed = 0.002 * (250.0f64).powf((k % 1024) as f64 / 1023.0);
        let ticks_per_edge = r.increment / speed / r.tick_s;
        let end = k * tps;
        while (t as u64) < end {
            pos += 1;
            let (a, b) = quadrature_levels(pos);
            d.update(a, b, t as u64);
            t += ticks_per_edge;
        }
        out.push((d.take_window(), end));
    }
    out
}

/// Index mask for cycling through the 4096 windows (no division in the loop).
const MASK: usize = 4095;

fn bench(c: &mut Criterion) {
    let r = EncoderResolution::thesis();
    let w = windows(&r);
    assert_eq!(w.len(), MASK + 1);

    let mut hp = HighPassDifferentiator::<f64>::new(&r, 2e-3).unwrap();
    let mut i = 0usize;
    c.bench_function("velocity/high_pass_differentiator_f64", |bch| {
        bch.iter(|| {
            i = (i + 1) & MASK;
            black_box(hp.update(black_box(w[i].0.net_counts)))
        })
    });

    let mut ec = EventCounter::<f64>::new(&r).unwrap();
    c.bench_function("velocity/event_counter_f64", |bch| {
        bch.iter(|| {
            i = (i + 1) & MASK;
            black_box(ec.update(black_box(&w[i].0)))
        })
    });

    let mut gm = GateMeasurement::<f64>::new(&r, 20e-3).unwrap();
    c.bench_function("velocity/gate_measurement_f64", |bch| {
        bch.iter(|| {
            i = (i + 1) & MASK;
            black_box(gm.update(black_box(&w[i].0), black_box(w[i].1)))
        })
    });

    let mut bl = Blended::<f64>::new(&r, 20e-3, 2e-3).unwrap();
    c.bench_function("velocity/blended_f64", |bch| {
        bch.iter(|| {
            i = (i + 1) & MASK;
            black_box(bl.update(black_box(&w[i].0), black_box(w[i].1)))
        })
    });

    let mut bl32 = Blended::<f32>::new(&r, 20e-3, 2e-3).unwrap();
    c.bench_function("velocity/blended_f32", |bch| {
        bch.iter(|| {
            i = (i + 1) & MASK;
            black_box(bl32.update(black_box(&w[i].0), black_box(w[i].1)))
        })
    });

    let (a, b) = quadrature_levels(0);
    let mut dec = QuadratureDecoder::new(a, b);
    let mut pos = 0i64;
    let mut t = 0u64;
    c.bench_function("encoder/decoder_update_edge", |bch| {
        bch.iter(|| {
            pos += 1;
            t += 37;
            let (a, b) = quadrature_levels(pos);
            black_box(dec.update(black_box(a), black_box(b), black_box(t)))
        })
    });

    let mut prbs = Prbs::<f64>::new(12, 1, 0.3).unwrap();
    c.bench_function("prbs/prbs_sample_f64_p1", |bch| {
        bch.iter(|| black_box(prbs.step()))
    });
    let mut prbs32 = Prbs::<f32>::new(12, 1, 0.3).unwrap();
    c.bench_function("prbs/prbs_sample_f32_p1", |bch| {
        bch.iter(|| black_box(prbs32.step()))
    });

    let mut chirp = Chirp::<f64>::new(Sweep::Logarithmic, 1.0, 1000.0, 100_000, 1e-4, 0.1).unwrap();
    c.bench_function("prbs/chirp_log_sample_f64", |bch| {
        bch.iter(|| black_box(chirp.step()))
    });

    let h: [u32; 16] = core::array::from_fn(|i| 3 * i as u32 + 1);
    let mut ms = Multisine::<f64, 16>::new(10_000, h, 0.01).unwrap();
    c.bench_function("prbs/multisine16_sample_f64", |bch| {
        bch.iter(|| black_box(ms.step()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
