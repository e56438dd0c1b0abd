//! The hysteresis' direction of motion before the record's first sample is a nuisance
//! parameter the fit estimates (`fit/initial_direction.rs`), as `compare` does: on a held
//! (PRBS) input whose hysteresis starts on the falling branch, the fit's own training MSE is
//! the one `compare` finds on the same record, and the model file keeps the direction.

mod common;
use common::{Udn, output, slow_block};
use hammerstein::diagnosis::compare;
use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::{Hammerstein, HammersteinModel, IoData, Order};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Levels held 1–20 samples, the first change downwards (the truth starts falling).
fn prbs(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut u = vec![0.5; 12];
    u.extend(std::iter::repeat_n(-1.5, 6));
    while u.len() < n {
        let level = rng.random_range(-2.0..2.0);
        let hold = rng.random_range(1..=20usize);
        u.extend(std::iter::repeat_n(level, hold));
    }
    u.truncate(n);
    u
}

fn record() -> IoData<f64> {
    let truth = Udn {
        a: 0.6,
        ..Udn::linear(1.0)
    };
    let u = prbs(3000, 5);
    let (y, _) = output(&slow_block(), &truth.eval(&u), 30.0, 9);
    IoData::siso(&u, &y).unwrap()
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b
}

#[test]
fn the_fit_estimates_the_initial_direction_as_compare_does() {
    let data = record();
    let model = Hammerstein::udn(EffectSet::of(&[Effect::Hysteresis]))
        .order(Order::Fixed(2))
        .fit(&data)
        .unwrap();
    assert!(model.nonlinearity().initial_falling());
    let own = model.report().train_mse;
    let seen = compare(&model, &data).unwrap().metrics.mse;
    assert!(relative(own, seen) < 1e-6, "fit {own} vs compare {seen}");
    // the file keeps the direction: the reloaded model simulates the same
    let json = serde_json::to_string(&model).unwrap();
    let back: HammersteinModel<f64> = serde_json::from_str(&json).unwrap();
    assert!(back.nonlinearity().initial_falling());
    let u = data.input(0);
    assert_eq!(model.simulate(&u).unwrap(), back.simulate(&u).unwrap());
}
