//! The guided loop's final check: an input of two levels identifies no input effect (none is
//! suggested, refitted or kept), and an effect whose parameter sits at its null value on the
//! final model is dropped and the model refitted without it.

mod common;

use common::{Udn, lcg_uniform, slow_block};
use hammerstein::diagnosis::{CandidateId, Diagnoser, RefitContext, compare};
use hammerstein::fit::order_selection::training_mse;
use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::subspace::Order;
use hammerstein::{Hammerstein, IoData};

/// A record of `n` samples: `u` through `nl` and the slow second-order block, white noise of
/// standard deviation `sd` (from the LCG seeded with `seed`).
fn record(u: &[f64], nl: &Udn, sd: f64, seed: u64) -> IoData<f64> {
    let v = nl.eval(u);
    let y0 = slow_block().simulate_siso(&v, None).unwrap();
    let e = lcg_uniform(u.len(), seed);
    // uniform on [−1, 1) has standard deviation 1/√3
    let y: Vec<f64> = y0
        .iter()
        .zip(&e)
        .map(|(y, e)| y + sd * 3f64.sqrt() * e)
        .collect();
    IoData::siso(u, &y).unwrap()
}

/// A two-level PRBS of `n` samples (levels ±1, each held 1–16 samples), from the LCG.
fn two_level(n: usize, seed: u64) -> Vec<f64> {
    let r = lcg_uniform(n, seed);
    let mut out = Vec::with_capacity(n);
    let mut level = 1.0;
    let mut k = 0;
    while out.len() < n {
        let hold = 1 + ((r[k % n] + 1.0) * 8.0) as usize;
        out.extend(std::iter::repeat_n(level, hold));
        level = -level;
        k += 1;
    }
    out.truncate(n);
    out
}

#[test]
fn a_two_level_input_gets_no_input_effect() {
    // a saturation and a hysteresis in the truth, invisible on two levels
    let truth = Udn {
        a: 0.2,
        z1: 0.7,
        z2: -0.8,
        ..Udn::linear(1.0)
    };
    let u = two_level(1200, 5);
    let data = record(&u, &truth, 0.05, 9);
    let (train, val) = (data.slice(0, 800).unwrap(), data.slice(800, 1200).unwrap());
    let d = Diagnoser::<f64>::new();
    // from the linear model: no input effect is refitted (each candidate says why)
    let linear = Hammerstein::<f64>::linear()
        .order(Order::Fixed(2))
        .fit(&train)
        .unwrap();
    let diag = d.diagnose(&linear, &train, &val).unwrap();
    for c in &diag.candidates {
        if matches!(c.effect, CandidateId::Effect(_)) {
            assert!(c.refit.is_none(), "{} was refitted", c.effect);
        }
    }
    // each input effect's refit, asked directly, refuses and says why
    let analysis = d.analysis(&linear, &train).unwrap();
    let vc = compare(&linear, &val).unwrap();
    let ctx = RefitContext {
        model: &linear,
        train: &train,
        validation: &val,
        validation_comparison: &vc,
        analysis: &analysis,
        train_mse: training_mse(&linear, &train),
        observer: None,
    };
    for e in Effect::ALL.into_iter().chain([Effect::PrandtlIshlinskii]) {
        let c = d.candidates().get(&CandidateId::Effect(e)).unwrap();
        let why = c
            .refit(&ctx)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(why.contains("2 level"), "{e}: {why}");
    }
    assert!(
        diag.suggestions
            .iter()
            .all(|s| !matches!(s.effect, CandidateId::Effect(_))),
        "{:?}",
        diag.suggestions
            .iter()
            .map(|s| s.effect.to_string())
            .collect::<Vec<_>>()
    );
    // from a model with hysteresis and saturation: the final model keeps neither
    let start = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]))
        .order(Order::Fixed(2));
    let followed = d.follow(&start, &train, &val, 2).unwrap();
    let last = followed.model().unwrap();
    assert!(
        last.nonlinearity().effects().is_empty(),
        "{:?}",
        last.nonlinearity().effects()
    );
    assert!(
        followed.final_check.iter().any(|n| n.contains("2 levels")),
        "{:?}",
        followed.final_check
    );
}

#[test]
fn a_null_hysteresis_on_the_final_model_is_dropped() {
    // a linear system under a multilevel input: a hysteresis the fit is forced to carry has its
    // half-width at its null value
    let u: Vec<f64> = lcg_uniform(900, 21);
    let data = record(&u, &Udn::linear(1.0), 0.05, 22);
    let (train, val) = (data.slice(0, 600).unwrap(), data.slice(600, 900).unwrap());
    let start =
        Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Hysteresis])).order(Order::Fixed(2));
    let followed = Diagnoser::<f64>::new()
        .follow(&start, &train, &val, 0)
        .unwrap();
    let first = &followed.steps[0].model;
    assert_eq!(
        first.nonlinearity().effects(),
        vec!["hysteresis".to_string()]
    );
    let last = followed.model().unwrap();
    assert!(
        last.nonlinearity().effects().is_empty(),
        "kept {:?}; final check: {:?}",
        last.nonlinearity().effects(),
        followed.final_check
    );
    assert!(
        followed
            .final_check
            .iter()
            .any(|n| n.contains("hysteresis")),
        "{:?}",
        followed.final_check
    );
    assert_eq!(followed.steps.last().unwrap().change, "- hysteresis");
}
