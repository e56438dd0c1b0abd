//! `diagnose` on 3000 samples, refits included (target: under 1 s in release), and
//! `diagnose --follow` from a linear model (three steps: linear, + saturation, + hysteresis;
//! target: under 1 s).
//! Data: the paper's linear block with a saturation + hysteresis UDN, uniform input, 25 dB;
//! the model has saturation only, so the diagnosis finds hysteresis and refits every candidate.

use criterion::{Criterion, criterion_group, criterion_main};
use hammerstein::IoData;
use hammerstein::StateSpace;
use hammerstein::diagnosis::{Diagnoser, diagnose};
use hammerstein::fit::Hammerstein;
use hammerstein::regressors::{Effect, EffectSet};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

fn data() -> IoData<f64> {
    let g = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let mut rng = StdRng::seed_from_u64(1);
    let n = 3000;
    let u: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
    // saturation (z1 = 1.5, z2 = -1) with hysteresis a = 0.3, gain 2
    let mut s = 1.0;
    let v: Vec<f64> = (0..n)
        .map(|k| {
            if k > 0 && u[k] != u[k - 1] {
                s = if u[k] > u[k - 1] { 1.0 } else { -1.0 };
            }
            (2.0 * (u[k] - 0.3 * s)).clamp(-2.0, 3.0)
        })
        .collect();
    let y0 = g.simulate_siso(&v, None).unwrap();
    let var = y0.iter().map(|y| y * y).sum::<f64>() / n as f64;
    let noise = Normal::new(0.0, (var / 10f64.powf(2.5)).sqrt()).unwrap();
    let y: Vec<f64> = y0.iter().map(|y| y + noise.sample(&mut rng)).collect();
    IoData::siso(&u, &y).unwrap()
}

fn bench(c: &mut Criterion) {
    let d = data();
    let (train, val) = d.split_validation(0.3).unwrap();
    let model = Hammerstein::udn(EffectSet::of(&[Effect::Saturation]))
        .fit(&train)
        .unwrap();
    let mut g = c.benchmark_group("diagnose");
    g.sample_size(10);
    g.bench_function("3000 samples, refits included", |b| {
        b.iter(|| diagnose(&model, &train, &val).unwrap())
    });
    let diagnoser = Diagnoser::<f64>::new();
    let start = Hammerstein::<f64>::linear();
    let steps = diagnoser
        .follow(&start, &train, &val, 6)
        .unwrap()
        .steps
        .len();
    g.bench_function(
        format!("follow from linear, 3000 samples, {steps} steps"),
        |b| b.iter(|| diagnoser.follow(&start, &train, &val, 6).unwrap()),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
