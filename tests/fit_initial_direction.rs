//! The hysteresis' direction of motion before the record's first sample is a nuisance
//! parameter the fit estimates (`fit/iteration/initial_direction.rs`), as `compare` does: on a held
//! (PRBS) input whose hysteresis starts on the falling branch, the fit's own training MSE is
//! the one `compare` finds on the same record, and the model file keeps the direction.

mod common;
use common::{Udn, output, slow_block};
use hammerstein::diagnosis::compare;
use hammerstein::regressors::{
    Effect, EffectSet, HysteresisForm, StaticNonlinearity, Udn as LibUdn,
};
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

/// `compare`'s falling start is the fit's own (the nonlinearity's `set_initial_falling`), at
/// any input scale: a play-form model saved without its direction (rising) finds the falling
/// start again when the hysteresis is wider than the one-unit step a history sample takes.
#[test]
fn compare_takes_the_fits_falling_start_for_a_wide_play_hysteresis() {
    let hyst = EffectSet::of(&[Effect::Hysteresis]);
    let play = || LibUdn::<f64>::new(hyst).with_form(HysteresisForm::Play);
    let mut truth = play();
    truth.set_params(&[1.5, 1.0]).unwrap();
    assert!(truth.set_initial_falling(true));
    let u = prbs(3000, 7);
    let (y, _) = output(&slow_block(), &truth.eval(&u), 60.0, 3);
    let data = IoData::siso(&u, &y).unwrap();
    let model = Hammerstein::new(Box::new(play()))
        .order(Order::Fixed(2))
        .fit(&data)
        .unwrap();
    assert!(model.nonlinearity().initial_falling());
    let a = model.parameters().iter().find(|(n, _)| n == "a").unwrap().1;
    assert!(2.0 * a > u[0].abs().max(1.0), "a = {a}, u0 = {}", u[0]);
    let json = serde_json::to_string(&model).unwrap();
    let as_rising = json.replace(
        "\"initial_direction\":\"falling\"",
        "\"initial_direction\":\"rising\"",
    );
    assert_ne!(json, as_rising);
    let rising: HammersteinModel<f64> = serde_json::from_str(&as_rising).unwrap();
    assert!(!rising.nonlinearity().initial_falling());
    let own = compare(&model, &data).unwrap().metrics.mse;
    let seen = compare(&rising, &data).unwrap().metrics.mse;
    assert!(
        relative(seen, own) < 1e-9,
        "falling {own} vs the rising model's best start {seen}"
    );
}
