//! The stability constraint (`Hammerstein::stable`, `--stable`): a fit asked for a stable block
//! returns one, says what it replaced, and changes nothing where the fit is stable anyway.

use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, HammersteinModel, IoData, Order, StateSpace};

mod common;

/// A uniform input in [-amp, amp) (`common::lcg_uniform`).
fn input(n: usize, seed: u64, amp: f64) -> Vec<f64> {
    common::lcg_uniform(n, seed)
        .into_iter()
        .map(|x| x * amp)
        .collect()
}

/// A saturation into the second-order block with poles `r` and 0.5, output noise of standard
/// deviation `sigma` (uniform), `n` samples.
fn record(r: f64, sigma: f64, seed: u64, n: usize) -> IoData<f64> {
    let set = EffectSet::of(&[Effect::Saturation]);
    let truth = Udn::with_params(set, &[1.0, 1.2, -0.9]).unwrap();
    // (1 − r z⁻¹)(1 − 0.5 z⁻¹) in companion form, gain into the first state
    let g = StateSpace::from_rows(
        &[&[r + 0.5, 1.0], &[-0.5 * r, 0.0]],
        &[&[1.0], &[0.3]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let u = input(n, seed, 2.0);
    let y = g.simulate_siso(&truth.eval(&u), None).unwrap();
    let e = input(n, seed + 99, sigma * 3f64.sqrt());
    let y: Vec<f64> = y.iter().zip(&e).map(|(a, b)| a + b).collect();
    IoData::siso(&u, &y).unwrap()
}

fn saturation() -> Hammerstein<f64> {
    Hammerstein::udn(EffectSet::of(&[Effect::Saturation]))
}

fn rho(m: &HammersteinModel<f64>) -> f64 {
    m.linear().spectral_radius().unwrap()
}

/// A short record of an unstable plant (a pole at 1.003: its output grows by e every 334
/// samples; 300 samples) fits to an unstable block by default (1.00302 at the time of writing;
/// longer records of it are not fitted well at all: the loop's blocks are held inside the circle
/// and the output-error refinement from there does not reach the unstable optimum). With the
/// constraint the block is stable and its training MSE above the unconstrained one (the
/// optimum lies outside the circle). A fit from the unstable model (`fit_from`, as a diagnosis'
/// candidates start) starts outside the circle: its block is pulled inside and refined under the
/// constraint, and the report names the block it replaced.
#[test]
fn an_unstable_plant_is_fitted_with_a_stable_block_when_asked() {
    let data = record(1.003, 0.02, 7, 300);
    let free = saturation().order(Order::Fixed(2)).fit(&data).unwrap();
    assert!(
        rho(&free) > 1.0,
        "the unconstrained fit is stable: {}",
        rho(&free)
    );
    assert!(free.report().stabilised.is_none());
    let stable = saturation().order(Order::Fixed(2)).stable(true);
    let held = stable.fit(&data).unwrap();
    assert!(rho(&held) < 1.0, "{}", rho(&held));
    assert!(held.report().train_mse > free.report().train_mse);
    if let Some(b) = held.report().stabilised {
        assert!(b.spectral_radius >= 1.0, "{b:?}");
    }
    let sim = held.simulate_on(&data).unwrap();
    assert!(sim.y_hat.iter().all(|v| v.is_finite()));
    // from the unstable model: replaced, and said so
    let theta: Vec<f64> = free.nonlinearity().params();
    let from = stable.fit_from(&data, &free, &theta).unwrap();
    assert!(rho(&from) < 1.0, "{}", rho(&from));
    let b = from
        .report()
        .stabilised
        .expect("the report names what it replaced");
    assert!((b.spectral_radius - rho(&free)).abs() < 1e-9, "{b:?}");
    assert!(from.report().train_mse > b.train_mse, "{b:?}");
    // the setting and the replaced block survive the model file
    let text = serde_json::to_string(&from.to_file()).unwrap();
    let back = HammersteinModel::from_json(&text).unwrap();
    assert!(back.settings().options().stable);
    assert_eq!(back.report().stabilised, from.report().stabilised);
    // a file without the field (every file before it) loads with the constraint off
    let back = HammersteinModel::from_json(&serde_json::to_string(&free.to_file()).unwrap());
    assert!(!back.unwrap().settings().options().stable);
}

/// On a stable plant the constraint never binds: the automatic fit (order selection, the
/// refinement, the steps after it) is the same with and without it, and reports nothing.
#[test]
fn a_stable_fit_is_the_same_with_the_constraint() {
    for (seed, r) in [(3u64, 0.9), (5, -0.7)] {
        let data = record(r, 0.05, seed, 1200);
        let free = saturation().fit(&data).unwrap();
        let held = saturation().stable(true).fit(&data).unwrap();
        assert!(rho(&free) < 1.0);
        assert_eq!(held.linear().order(), free.linear().order());
        let rel = (held.report().train_mse / free.report().train_mse - 1.0).abs();
        assert!(rel < 1e-12, "seed {seed}: {rel}");
        assert!(held.report().stabilised.is_none());
    }
}

/// `--stable` on the real MR damper record ensaio04 (`tests/data/mr_damper/`, velocity → force,
/// 70/30), whose default fit has a pole just outside the circle: the JSON's spectral radius is
/// below 1, `stabilised_from` holds the replaced block's radius (≥ 1), the text says so instead of
/// the unstable line, and the validation fit stays within 2 points of the unconstrained one.
#[cfg(feature = "cli")]
#[test]
fn the_mr_damper_record_fits_to_a_stable_block_with_stable() {
    let record = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/mr_damper/ensaio04.csv"
    );
    let run = |extra: &[&str]| {
        let mut args = vec![
            "fit",
            record,
            "--input",
            "vel_mm_s",
            "--output",
            "force_N",
            "--validate",
            "0.3",
        ];
        args.extend_from_slice(extra);
        common::run_cli(&args)
    };
    let json = |extra: &[&str]| -> serde_json::Value {
        serde_json::from_str(run(&[extra, &["--json"]].concat()).trim()).unwrap()
    };
    let free = json(&[]);
    let held = json(&["--stable"]);
    assert!(free["spectral_radius"].as_f64().unwrap() >= 1.0, "{free}");
    assert!(held["spectral_radius"].as_f64().unwrap() < 1.0, "{held}");
    assert_eq!(held["stable_enforced"], true);
    assert_eq!(free["stable_enforced"], false);
    assert!(free["stabilised_from"].is_null());
    // the block replaced at the end, when a step after the constrained refinements began
    // outside the circle
    if let Some(from) = held["stabilised_from"]["spectral_radius"].as_f64() {
        assert!(from >= 1.0, "{held}");
    }
    let fit = |j: &serde_json::Value| j["validation"]["fit_percent"].as_f64().unwrap();
    assert!(
        fit(&held) > fit(&free) - 2.0,
        "{} against {}",
        fit(&held),
        fit(&free)
    );
    let text = run(&["--stable"]);
    assert!(text.contains("stability enforced (--stable)"), "{text}");
    assert!(!text.contains("linear block unstable"), "{text}");
}
