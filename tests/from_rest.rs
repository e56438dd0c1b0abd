//! A model whose simulation from rest departs from its fit with the estimated initial state
//! (`hammerstein::fit::from_rest`), reproduced from the decimation battery's record of seed 32
//! (`tests/common/oversampled.rs`: a slow second-order block, ω₀ 0.0062 rad per sample, a
//! multisine through a saturation, 20 448 samples, SNR 15.5 dB, fitted with the default linear
//! options). Its full-rate fit chose order 6, whose extra modes (a pole pair of modulus 0.9995 at
//! 1.37 rad per sample, behind zeros clustered at z = 1 and a gain 3.8e6) the multisine does not
//! excite: with its initial state estimated it fitted the held-out record at 73 %, from rest
//! `simulate` left the output by 29 000 times its scale.
//!
//! What holds: the default fit of that record refuses such candidates and simulates the
//! held-out record from rest within 10 % of the output's spread (the decimated fit's error is
//! 5 %); a fixed order that keeps them is said by `fit`, `compare` and `simulate` on standard
//! error and in `fit --json` and `compare --json`.

mod common;

use common::oversampled::record;
use hammerstein::StateSpace;
use hammerstein::fit::from_rest::{REST_LIMIT, departs, free_response_peak};
use std::path::{Path, PathBuf};

/// The battery's record whose full-rate fit had the defect.
const SEED: u64 = 32;

/// The record's training, validation and noise-free held-out files in `dir`.
fn files(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let r = record(SEED);
    let (train, val, truth) = (
        dir.join("train.csv"),
        dir.join("val.csv"),
        dir.join("truth.csv"),
    );
    common::write_csv(&train, &["u", "y"], &[&r.u, &r.y]);
    common::write_csv(&val, &["u", "y"], &[&r.uv, &r.yv]);
    common::write_csv(&truth, &["u", "y"], &[&r.uv, &r.yv0]);
    (train, val, truth)
}

/// The simulated output of `simulate MODEL RECORD` and its standard error.
fn simulate(model: &Path, rec: &Path) -> (Vec<f64>, String) {
    let (ok, out, err) =
        common::run_cli_outcome(&["simulate", model.to_str().unwrap(), rec.to_str().unwrap()]);
    assert!(ok, "{err}");
    let y = out
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
        .collect();
    (y, err)
}

/// RMS of `sim − truth` relative to the RMS of the truth's deviation from its mean.
fn rel_error(sim: &[f64], truth: &[f64]) -> f64 {
    assert_eq!(sim.len(), truth.len());
    let mean = truth.iter().sum::<f64>() / truth.len() as f64;
    let spread: f64 = truth.iter().map(|y| (y - mean).powi(2)).sum();
    let err: f64 = sim.iter().zip(truth).map(|(s, y)| (s - y).powi(2)).sum();
    (err / spread).sqrt()
}

/// `fit` with `extra`, saved to `model`: its JSON and standard error.
fn fit(train: &Path, val: &Path, model: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let mut args = vec![
        "fit",
        train.to_str().unwrap(),
        "--validation-file",
        val.to_str().unwrap(),
        "--save",
        model.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    let (ok, out, err) = common::run_cli_outcome(&args);
    assert!(ok, "{args:?}: {err}");
    (serde_json::from_str(&out).unwrap(), err)
}

/// `compare MODEL VAL --json`: its JSON and standard error.
fn compare(model: &Path, val: &Path) -> (serde_json::Value, String) {
    let (ok, out, err) = common::run_cli_outcome(&[
        "compare",
        model.to_str().unwrap(),
        val.to_str().unwrap(),
        "--json",
    ]);
    assert!(ok, "{err}");
    (serde_json::from_str(&out).unwrap(), err)
}

const SAID: &str = "simulation from rest departs from its fit";

#[test]
fn the_default_fit_of_the_oversampled_record_simulates_from_rest() {
    let dir = common::temp_dir("from-rest-default");
    let (train, val, truth) = files(&dir);
    let model = dir.join("m.json");
    let (j, err) = fit(&train, &val, &model, &[]);
    assert_eq!(j["from_rest"]["departs"], false, "{j}\n{err}");
    assert!(!err.contains(SAID), "{err}");
    let (y, err) = simulate(&model, &truth);
    assert!(!err.contains(SAID), "{err}");
    let yv0 = record(SEED).yv0;
    let e = rel_error(&y, &yv0);
    assert!(
        e < 0.1,
        "order {}: held-out error from rest {e:.4} of the output's spread (order table {})",
        j["order"],
        j["order_selection"]
    );
    // the comparison with the initial state estimated agrees with the simulation from rest
    let (c, err) = compare(&model, &val);
    assert_eq!(c["from_rest"]["departs"], false, "{c}");
    assert!(!err.contains(SAID), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_fixed_order_whose_modes_the_input_does_not_excite_is_said() {
    let dir = common::temp_dir("from-rest-fixed");
    let (train, val, truth) = files(&dir);
    let model = dir.join("m6.json");
    let (j, err) = fit(&train, &val, &model, &["--order", "6"]);
    // the order the default fit chose before it refused such candidates: 30 000× from rest
    let (y, said) = simulate(&model, &truth);
    let e = rel_error(&y, &record(SEED).yv0);
    let departure = j["from_rest"]["departure"].as_f64().unwrap();
    if j["from_rest"]["departs"] == true {
        assert!(departure > REST_LIMIT, "{j}");
        assert!(err.contains(SAID), "fit did not say it: {err}");
        assert!(said.contains(SAID), "simulate did not say it: {said}");
        let (c, err) = compare(&model, &val);
        assert_eq!(c["from_rest"]["departs"], true, "{c}");
        assert!(err.contains(SAID), "compare did not say it: {err}");
        // diagnose says it of the model it diagnoses
        let (ok, out, err) = common::run_cli_outcome(&[
            "diagnose",
            train.to_str().unwrap(),
            "--validation-file",
            val.to_str().unwrap(),
            "--order",
            "6",
            "--json",
        ]);
        assert!(ok, "{err}");
        let d: serde_json::Value = serde_json::from_str(&out).unwrap();
        if d["order"] == j["order"] && d["from_rest"]["departs"] == true {
            assert!(err.contains(SAID), "diagnose did not say it: {err}");
        }
        assert_eq!(
            d["from_rest"]["departs"] == true,
            err.contains(SAID),
            "diagnose: {}\n{err}",
            d["from_rest"]
        );
    } else {
        // a fit of order 6 without such modes: its simulation from rest holds
        assert!(
            e < 0.1,
            "not said, yet the held-out error from rest is {e:.4}"
        );
    }
    // what is not said holds: a silent simulation from rest is near the held-out output
    if !said.contains(SAID) {
        assert!(
            e < 0.1,
            "not said, yet the held-out error from rest is {e:.4}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A first-order block x ← a x + (1 − a) v, y = x.
fn first_order(a: f64) -> StateSpace<f64> {
    StateSpace::from_rows(&[&[a]], &[&[1.0 - a]], &[&[1.0]], &[&[0.0]]).unwrap()
}

#[test]
fn the_free_response_peak_is_the_largest_c_a_k_x0() {
    // 2, −1, 0.5, …: the peak is the first
    assert_eq!(free_response_peak(&first_order(-0.5), &[2.0], 10), 2.0);
    // a growing mode: 1.5⁴ at the fifth sample
    assert_eq!(
        free_response_peak(&first_order(1.5), &[1.0], 5),
        1.5f64.powi(4)
    );
    // a state of another length is not this block's
    assert_eq!(free_response_peak(&first_order(0.5), &[1.0, 2.0], 5), 0.0);
    // an overflowing response is infinite
    assert_eq!(
        free_response_peak(&first_order(1e300), &[1e300], 5),
        f64::INFINITY
    );
}

#[test]
fn a_departure_beyond_the_limit_departs_and_an_undefined_one_does_not() {
    assert!(!departs(None));
    assert!(!departs(Some(REST_LIMIT)));
    assert!(departs(Some(REST_LIMIT * 1.01)));
    assert!(departs(Some(f64::INFINITY)));
    assert!(departs(Some(f64::NAN)));
}
