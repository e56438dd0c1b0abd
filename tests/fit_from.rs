//! `Hammerstein::fit_from`: a fit that extends a fitted model (an effect at its null value, or
//! more states) starts at that model, so its training error is never above the model's; from a
//! size guess it finds an effect the model lacks.

mod hammerstein_common;
use hammerstein::Order;
use hammerstein::diagnosis::compare;
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein::{Hammerstein, HammersteinModel, IoData};
use hammerstein_common::*;

fn sh_record(seed: u64) -> IoData<f64> {
    let truth = Udn::<f64>::with_params(
        EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]),
        &[2.0, 0.4, 1.5, -1.0],
    )
    .unwrap();
    add_noise(
        &record(&truth, &example1_input(1500, seed), 0.0),
        30.0,
        seed + 1,
    )
}

fn train_mse(m: &HammersteinModel<f64>, d: &IoData<f64>) -> f64 {
    compare(m, d).unwrap().metrics.mse
}

fn saturation_model(data: &IoData<f64>) -> HammersteinModel<f64> {
    Hammerstein::udn(EffectSet::of(&[Effect::Saturation]))
        .order(Order::Fixed(2))
        .fit(data)
        .unwrap()
}

/// Hysteresis added at a = 0: the training MSE does not rise above the saturation model's;
/// started at a = 0.3 it finds the hysteresis (a near the true 0.4) and the MSE falls by far.
#[test]
fn an_effect_added_at_its_null_value_is_not_worse() {
    let data = sh_record(3);
    let base = saturation_model(&data);
    let before = train_mse(&base, &data);
    let p: std::collections::BTreeMap<String, f64> = base.parameters().into_iter().collect();
    let settings = Hammerstein::udn(EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]))
        .order(Order::Fixed(2));
    let at = |a: f64| vec![p["p"], a, p["z1"], p["z2"]];
    let null = settings.fit_from(&data, &base, &at(0.0)).unwrap();
    assert!(
        train_mse(&null, &data) <= before * (1.0 + 1e-6),
        "nested start at a = 0: {} against {before}",
        train_mse(&null, &data)
    );
    let guessed = settings.fit_from(&data, &base, &at(0.3)).unwrap();
    let a = guessed.parameters()[1].1;
    assert!((a - 0.4).abs() < 0.05, "a = {a}");
    assert!(
        train_mse(&guessed, &data) < 0.5 * before,
        "{} against {before}",
        train_mse(&guessed, &data)
    );
}

/// One more state (a pole at 0 added): not worse than the model it extends; a lower order than
/// the base model is refused with a typed error.
#[test]
fn more_states_are_not_worse_and_fewer_are_refused() {
    let data = sh_record(4);
    let base = saturation_model(&data);
    let before = train_mse(&base, &data);
    let theta: Vec<f64> = base.parameters().into_iter().map(|(_, v)| v).collect();
    let settings = Hammerstein::udn(EffectSet::of(&[Effect::Saturation]));
    let bigger = settings
        .clone()
        .order(Order::Fixed(3))
        .fit_from(&data, &base, &theta)
        .unwrap();
    assert_eq!(bigger.linear().order(), 3);
    assert!(
        train_mse(&bigger, &data) <= before * (1.0 + 1e-6),
        "{} against {before}",
        train_mse(&bigger, &data)
    );
    let smaller = settings
        .order(Order::Fixed(1))
        .fit_from(&data, &base, &theta);
    assert!(matches!(
        smaller,
        Err(hammerstein::Error::InvalidParameter(_))
    ));
}

/// A Hammerstein–Wiener model (saturation, then a cubic output map) extended by an effect at its
/// null value — a preload without dead-zone (it spans the constant, so the model's offset must
/// stay outside the map) and a hysteresis — starts at that model: the refit's training error is
/// not above it, and the map is still there.
#[test]
fn a_hammerstein_wiener_model_extended_at_null_is_not_worse() {
    use hammerstein::regressors::output_map_from_name;
    let clean = sh_record(5);
    // the record through a compressing cubic and an offset: y ← y − 0.04·y³ + 0.7
    let y: Vec<f64> = clean
        .output_slice(0)
        .iter()
        .map(|&v| v - 0.04 * v * v * v + 0.7)
        .collect();
    let data = IoData::siso(clean.input_slice(0), &y).unwrap();
    let with_map = |s: Hammerstein<f64>| {
        s.order(Order::Fixed(2))
            .output_nonlinearity(Some(output_map_from_name("poly3").unwrap()))
    };
    let base = with_map(Hammerstein::udn(EffectSet::of(&[Effect::Saturation])))
        .fit(&data)
        .unwrap();
    let before = train_mse(&base, &data);
    let p: std::collections::BTreeMap<String, f64> = base.parameters().into_iter().collect();
    for (effects, theta) in [
        (
            EffectSet::of(&[Effect::Saturation, Effect::Preload]),
            vec![p["p"], p["z1"], p["z2"], 0.0, 0.0],
        ),
        (
            EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]),
            vec![p["p"], 0.0, p["z1"], p["z2"]],
        ),
    ] {
        let settings = with_map(Hammerstein::udn(effects));
        let refit = settings.fit_from(&data, &base, &theta).unwrap();
        assert!(refit.output_map().is_some());
        let after = train_mse(&refit, &data);
        assert!(
            after <= before * (1.0 + 1e-6),
            "{}: nested refit {after} against the model it extends {before}",
            effects.label()
        );
    }
}
