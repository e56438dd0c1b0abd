//! Hammerstein with feedback: an input saturation before a loop with a cubic stiffness. The
//! fit with the input nonlinearity reaches the noise where the loop alone does not, is never
//! worse on training than the loop alone, and its model file round-trips.

use hammerstein::IoData;
use hammerstein::feedback::{
    self, FeedbackKind, FeedbackModel, FeedbackModelFile, FeedbackOn, FeedbackSettings,
};
use hammerstein::regressors::{EffectSet, Udn};
use rand::{SeedableRng, rngs::StdRng};

mod common;
mod feedback_common;
use feedback_common::{add_noise, filtered_noise};

/// v = clip(u, ±sat), x+ = A x + B (v + w), y = x₁, w = −0.02 z³ on z = y (a second-order
/// resonant block), simulated independently of the crate.
fn truth(u: &[f64], sat: f64) -> Vec<f64> {
    common::resonant_loop(u, |v| v.clamp(-sat, sat), |x1, _| -0.02 * x1.powi(3))
}

/// Training and validation records of `n` samples each, the noise variance and the training
/// input; `saturate`: the input saturates a quarter of the time (else never).
fn records(seed: u64, n: usize, saturate: bool) -> (IoData<f64>, IoData<f64>, f64, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let u = filtered_noise(2 * n, &mut rng, 0.06);
    let mut abs: Vec<f64> = u.iter().map(|v| v.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let sat = if saturate {
        abs[abs.len() * 3 / 4]
    } else {
        f64::INFINITY
    };
    let y0 = truth(&u, sat);
    let (y, s2) = add_noise(&y0, 40.0, &mut rng);
    (
        IoData::siso(&u[..n], &y[..n]).unwrap(),
        IoData::siso(&u[n..], &y[n..]).unwrap(),
        s2,
        u[..n].to_vec(),
    )
}

fn settings(input: bool) -> FeedbackSettings {
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    s.order = hammerstein::Order::Fixed(2);
    if input {
        s.input = Some(Box::new(Udn::<f64>::new(
            EffectSet::parse("saturation").unwrap(),
        )));
    }
    s
}

#[test]
fn an_input_saturation_before_the_loop_is_fitted_to_the_noise() {
    let (train, val, s2, u) = records(21, 3000, true);
    let alone = feedback::fit(&settings(false), &train).unwrap();
    let with = feedback::fit(&settings(true), &train).unwrap();
    let va = alone.model.compare(&val).unwrap().rms.powi(2);
    let vw = with.model.compare(&val).unwrap().rms.powi(2);
    eprintln!(
        "loop alone: train {:.3e} val {va:.3e}; with the input saturation: train {:.3e} val {vw:.3e}; noise {s2:.3e}; warnings {:?}",
        alone.rms.powi(2),
        with.rms.powi(2),
        with.warnings
    );
    assert!(
        with.model.input_nonlinearity().is_some(),
        "{:?}",
        with.warnings
    );
    // nested: never worse on training than the loop alone
    assert!(with.rms <= alone.rms * (1.0 + 1e-9));
    assert!(
        vw < 1.5 * s2,
        "with the input saturation: {vw} vs noise {s2}"
    );
    assert!(
        va > 2.0 * s2,
        "the loop alone reaches {va} (noise {s2}): the record does not tell"
    );
    // the file round trip: the input nonlinearity travels with the model
    let text = serde_json::to_string(&with.model.to_file()).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["version"], 2);
    assert!(value.get("input_nonlinearity").is_some());
    let back = FeedbackModel::from_file(&FeedbackModelFile::from_value(value).unwrap(), |_| {
        unreachable!("a built-in basis")
    })
    .unwrap();
    let x0 = with.model.training_x0().to_vec();
    assert_eq!(
        back.simulate(&u, Some(&x0)).unwrap(),
        with.model.simulate(&u, Some(&x0)).unwrap()
    );
}

#[test]
fn without_an_input_nonlinearity_in_the_truth_the_fit_is_no_worse_than_the_loop_alone() {
    let (train, val, s2, _) = records(22, 2000, false);
    let alone = feedback::fit(&settings(false), &train).unwrap();
    let with = feedback::fit(&settings(true), &train).unwrap();
    let vw = with.model.compare(&val).unwrap().rms.powi(2);
    eprintln!(
        "no saturation in the truth: loop alone train {:.3e}, with N train {:.3e} val {vw:.3e} (kept: {}), noise {s2:.3e}",
        alone.rms.powi(2),
        with.rms.powi(2),
        with.model.input_nonlinearity().is_some()
    );
    assert!(with.rms <= alone.rms * (1.0 + 1e-9));
    assert!(vw < 1.5 * s2, "{vw} vs noise {s2}");
    if with.model.input_nonlinearity().is_none() {
        assert!(
            with.warnings.iter().any(|w| w.contains("not kept")),
            "{:?}",
            with.warnings
        );
    }
}
