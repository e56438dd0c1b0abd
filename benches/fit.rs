//! One complete Hammerstein fit of 2000 samples (paper Example 1, noise-free and at 10 dB):
//! SH structure and full UDN. Targets (release): the default fit (order selection, feed-through
//! decision, refinement) of the full UDN < 30 ms; the fixed-order fit (order 2, D = 0, with the
//! refinement) < 10 ms; the loop alone for reference.

#[path = "common/example1_record.rs"]
mod example1_record;

use criterion::{Criterion, criterion_group, criterion_main};
use example1_record::example1;
use hammerstein::Hammerstein;
use hammerstein::regressors::EffectSet;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let clean = example1(0.0);
    let noisy = example1(0.87); // ≈ 10 dB
    use hammerstein::Order;
    let fixed = |h: Hammerstein<f64>| h.order(Order::Fixed(2)).with_d(false);
    let sh = fixed(Hammerstein::<f64>::sh());
    let udn = fixed(Hammerstein::<f64>::udn(EffectSet::all()));
    let udn_default = Hammerstein::<f64>::udn(EffectSet::all());
    let udn_loop = udn.clone().refine(false);
    c.bench_function("fit_sh_2000_clean", |b| {
        b.iter(|| black_box(sh.fit(black_box(&clean)).unwrap()))
    });
    c.bench_function("fit_udn_2000_clean", |b| {
        b.iter(|| black_box(udn.fit(black_box(&clean)).unwrap()))
    });
    c.bench_function("fit_udn_2000_10db", |b| {
        b.iter(|| black_box(udn.fit(black_box(&noisy)).unwrap()))
    });
    c.bench_function("fit_udn_2000_10db_loop_only", |b| {
        b.iter(|| black_box(udn_loop.fit(black_box(&noisy)).unwrap()))
    });
    c.bench_function("fit_udn_2000_10db_default", |b| {
        b.iter(|| black_box(udn_default.fit(black_box(&noisy)).unwrap()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
