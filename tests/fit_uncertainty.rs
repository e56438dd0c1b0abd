//! The parameter standard errors a fit reports agree with the spread of the estimates over noise
//! realisations (Monte Carlo), and name the parameters a record does not determine.

mod hammerstein_common;
use hammerstein::Hammerstein;
use hammerstein::Order;
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein_common::*;

fn fit_sh(seed: u64, snr: f64) -> (Vec<f64>, Vec<f64>) {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let clean = record(&truth, &example1_input(1000, 100 + seed), 0.0);
    let data = add_noise(&clean, snr, 200 + seed);
    let m = Hammerstein::sh().order(Order::Fixed(2)).fit(&data).unwrap();
    let pe = m.parameters_with_errors();
    (
        pe.iter().map(|p| p.1).collect(),
        pe.iter()
            .map(|p| p.2.expect("standard errors computed"))
            .collect(),
    )
}

/// Over 30 noise realisations the empirical standard deviation of each SH parameter is within
/// a factor 1.6 of the mean reported standard error (the asymptotic covariance σ²(JᵀJ)⁻¹).
#[test]
fn standard_errors_match_the_monte_carlo_spread() {
    let runs: Vec<(Vec<f64>, Vec<f64>)> = (0..30).map(|s| fit_sh(s, 15.0)).collect();
    let names = ["p", "a", "z1", "z2"];
    for (j, name) in names.iter().enumerate() {
        let vals: Vec<f64> = runs.iter().map(|r| r.0[j]).collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let sd =
            (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (vals.len() - 1) as f64).sqrt();
        let se = runs.iter().map(|r| r.1[j]).sum::<f64>() / runs.len() as f64;
        let ratio = sd / se;
        println!("{name}: mean {mean:.4} sd {sd:.3e} mean SE {se:.3e} ratio {ratio:.2}");
        assert!(
            (1.0 / 1.6..=1.6).contains(&ratio),
            "{name}: Monte Carlo sd {sd:.3e}, mean reported SE {se:.3e}, ratio {ratio:.2}"
        );
    }
}

/// A hysteresis fitted to data without hysteresis ends at a ≈ 0 within two standard errors; the
/// same fit on data with hysteresis is many standard errors from 0.
#[test]
fn a_null_parameter_is_within_its_standard_error() {
    let with = Udn::<f64>::with_params(
        EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]),
        &[2.0, 0.3, 1.5, -1.0],
    )
    .unwrap();
    let without =
        Udn::<f64>::with_params(EffectSet::of(&[Effect::Saturation]), &[2.0, 1.5, -1.0]).unwrap();
    let u = example1_input(1500, 5);
    let fit = |nl: &Udn<f64>| {
        let data = add_noise(&record(nl, &u, 0.0), 20.0, 6);
        let m = Hammerstein::sh().order(Order::Fixed(2)).fit(&data).unwrap();
        let a = m.parameters_with_errors()[1].clone();
        assert_eq!(a.0, "a");
        (a.1, a.2.unwrap())
    };
    let (a0, se0) = fit(&without);
    assert!(a0.abs() <= 2.0 * se0, "no hysteresis: a = {a0} ± {se0}");
    let (a1, se1) = fit(&with);
    assert!(a1 / se1 > 10.0, "hysteresis 0.3: a = {a1} ± {se1}");
}

/// The standard error of a combination from the fit's covariance agrees with the Monte Carlo
/// spread of that combination: a preload's jump e1 − e2 over 20 noise realisations of a
/// saturation + preload system (mean reported standard error within a factor 1.6 of the
/// empirical standard deviation), as the parameters' own errors do above.
#[test]
fn a_combination_standard_error_matches_the_monte_carlo_spread() {
    let set = EffectSet::of(&[Effect::Saturation, Effect::Preload]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 1.5, -1.0, 0.4, -0.3]).unwrap();
    let clean = record(&truth, &example1_input(1000, 77), 0.0);
    let runs: Vec<(f64, f64)> = (0..20)
        .map(|s| {
            let data = add_noise(&clean, 15.0, 300 + s);
            let m = Hammerstein::udn(set)
                .order(Order::Fixed(2))
                .fit(&data)
                .unwrap();
            let pe = m.parameters();
            let e = |n: &str| pe.iter().find(|p| p.0 == n).unwrap().1;
            let se = m
                .standard_error_of_combination(&[("e1", 1.0), ("e2", -1.0)])
                .expect("covariance computed");
            (e("e1") - e("e2"), se)
        })
        .collect();
    let n = runs.len() as f64;
    let mean = runs.iter().map(|r| r.0).sum::<f64>() / n;
    let sd = (runs.iter().map(|r| (r.0 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se = runs.iter().map(|r| r.1).sum::<f64>() / n;
    let ratio = sd / se;
    println!("e1 − e2: mean {mean:.4} sd {sd:.3e} mean SE {se:.3e} ratio {ratio:.2}");
    assert!(
        (1.0 / 1.6..=1.6).contains(&ratio),
        "e1 − e2: Monte Carlo sd {sd:.3e}, mean reported SE {se:.3e}, ratio {ratio:.2}"
    );
}
