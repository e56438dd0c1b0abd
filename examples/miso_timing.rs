//! Times the two-input default fit of `benches/fit_miso.rs` (issue 12) in one process, for a
//! CPU-time figure beside the bench's wall time: `/usr/bin/time cargo run --release --example
//! miso_timing -- 20` (the fits run one after another; the branch work inside may use 2 threads).

use hammerstein::faer::Mat;
use hammerstein::miso::MisoHammerstein;
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::time::Instant;

/// The bench's record: 2000 samples, two inputs, 30 dB.
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

fn main() -> Result<(), hammerstein::Error> {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20);
    let data = record();
    let sh = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let dz = EffectSet::of(&[Effect::DeadZone]);
    let settings = MisoHammerstein::new(vec![Hammerstein::udn(sh), Hammerstein::udn(dz)]);
    let t = Instant::now();
    let mut last = None;
    for _ in 0..reps {
        last = Some(settings.fit(&data)?);
    }
    let wall = t.elapsed().as_secs_f64() * 1e3 / reps.max(1) as f64;
    if let Some(m) = last {
        let orders: Vec<usize> = m.branches().iter().map(|b| b.linear().order()).collect();
        println!(
            "{reps} fits, {wall:.1} ms wall each; orders {orders:?}, sweeps {}, train MSE {:.4e}",
            m.report().sweeps.len(),
            m.report().train_mse
        );
    }
    Ok(())
}
