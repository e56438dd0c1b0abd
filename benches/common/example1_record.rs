//! The single-input bench record (paper Example 1, 2000 samples), shared by `benches/fit.rs` and
//! `examples/fit_timing.rs`.

use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// Example 1's SH system driven by uniform noise on [-3, 3]; `noise_sd` 0.87 is ≈ 10 dB.
pub fn example1(noise_sd: f64) -> IoData<f64> {
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
