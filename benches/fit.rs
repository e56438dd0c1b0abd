//! One complete Hammerstein fit of 2000 samples (paper Example 1, noise-free and at 10 dB):
//! SH structure and full UDN. Targets (release): the default fit (order selection, feed-through
//! decision, refinement) of the full UDN < 30 ms; the fixed-order fit (order 2, D = 0, with the
//! refinement) < 10 ms; the loop alone for reference.

use criterion::{Criterion, criterion_group, criterion_main};
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::hint::black_box;

fn example1(noise_sd: f64) -> IoData<f64> {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let mut rng = StdRng::seed_from_u64(7);
    let u: Vec<f64> = (0..2000).map(|_| rng.random_range(-3.0..3.0)).collect();
    let g = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let normal = Normal::new(0.0, noise_sd.max(1e-300)).unwrap();
    let y: Vec<f64> = g
        .simulate_siso(&truth.eval(&u), None)
        .unwrap()
        .into_iter()
        .map(|y| {
            y + if noise_sd > 0.0 {
                normal.sample(&mut rng)
            } else {
                0.0
            }
        })
        .collect();
    IoData::siso(&u, &y).unwrap()
}

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
