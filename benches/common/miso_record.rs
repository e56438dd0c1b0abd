//! The two-input record of `benches/fit_miso.rs` and `examples/miso_timing.rs` (included by
//! both with `#[path]`): input 1 through the paper's saturation with hysteresis into its
//! second-order block, input 2 through a dead-zone into a first-order block, summed, 30 dB,
//! 2000 samples; and the default settings both time.

use hammerstein::faer::Mat;
use hammerstein::miso::MisoHammerstein;
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// The saturation-with-hysteresis effects of input 1 and the dead-zone of input 2.
pub fn effects() -> (EffectSet, EffectSet) {
    (
        EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]),
        EffectSet::of(&[Effect::DeadZone]),
    )
}

/// Default settings per branch (order and feed-through selected, refinement).
pub fn default_settings() -> MisoHammerstein<f64> {
    let (sh, dz) = effects();
    MisoHammerstein::new(vec![Hammerstein::udn(sh), Hammerstein::udn(dz)])
}

/// The record (seed 7).
pub fn record() -> IoData<f64> {
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
