//! A two-input fit of 2000 samples with one UDN per input (issue 12: < 50 ms): input 1 through
//! the paper's saturation with hysteresis into its second-order block, input 2 through a
//! dead-zone into a first-order block, summed, 30 dB. Default settings per branch (order
//! selection, feed-through decision, refinement) and with each branch's order given.

use criterion::{Criterion, criterion_group, criterion_main};
use hammerstein::faer::Mat;
use hammerstein::miso::MisoHammerstein;
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, Order, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::hint::black_box;

fn record() -> IoData<f64> {
    let n = 2000;
    let mut rng = StdRng::seed_from_u64(7);
    let u1: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
    let u2: Vec<f64> = (0..n).map(|_| rng.random_range(-2.0..2.0)).collect();
    let sh = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let n1 = Udn::<f64>::with_params(sh, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let n2 = Udn::<f64>::with_params(EffectSet::of(&[Effect::DeadZone]), &[1.0, 0.5]).unwrap();
    let g1 = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let g2 = StateSpace::<f64>::from_rows(&[&[0.7]], &[&[0.6]], &[&[1.0]], &[&[0.0]]).unwrap();
    let y1 = g1.simulate_siso(&n1.eval(&u1), None).unwrap();
    let y2 = g2.simulate_siso(&n2.eval(&u2), None).unwrap();
    let y0: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b).collect();
    let m = y0.iter().sum::<f64>() / n as f64;
    let var = y0.iter().map(|y| (y - m).powi(2)).sum::<f64>() / n as f64;
    let noise = Normal::new(0.0, (var / 1000.0).sqrt()).unwrap();
    let y: Vec<f64> = y0.iter().map(|y| y + noise.sample(&mut rng)).collect();
    IoData::new(
        Mat::from_fn(n, 2, |k, j| if j == 0 { u1[k] } else { u2[k] }),
        Mat::from_fn(n, 1, |k, _| y[k]),
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let data = record();
    let sh = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let dz = EffectSet::of(&[Effect::DeadZone]);
    let default = MisoHammerstein::new(vec![Hammerstein::udn(sh), Hammerstein::udn(dz)]);
    let fixed = MisoHammerstein::new(vec![
        Hammerstein::udn(sh).order(Order::Fixed(2)).with_d(false),
        Hammerstein::udn(dz).order(Order::Fixed(1)).with_d(false),
    ]);
    let model = default.fit(&data).unwrap();
    eprintln!(
        "default: orders {:?}, sweeps {}, train MSE {:.3e}",
        model
            .branches()
            .iter()
            .map(|b| b.linear().order())
            .collect::<Vec<_>>(),
        model.report().sweeps.len(),
        model.report().train_mse
    );
    c.bench_function("fit_two_inputs_2000_default", |b| {
        b.iter(|| black_box(default.fit(black_box(&data)).unwrap()))
    });
    c.bench_function("fit_two_inputs_2000_orders_given", |b| {
        b.iter(|| black_box(fixed.fit(black_box(&data)).unwrap()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
