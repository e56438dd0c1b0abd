//! Decimation of an oversampled record (`IoData::decimate`, `--decimate`): the fit of the
//! decimated record finds the plant at the slower rate (its poles the fast ones to the power
//! K), the output's noise is filtered down, and a saved model carries the factor to `compare`
//! and `simulate`.

use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, Order, StateSpace};

mod common;

/// Fast-rate poles r·e^{±jθ}: a lightly damped, slow mode (about 300 samples per period).
const R: f64 = 0.995;
const THETA: f64 = 0.02;
/// The decimation factor.
const K: usize = 10;

/// The slow block: poles R·e^{±jθ}, companion form.
fn slow_block() -> StateSpace<f64> {
    let (a1, a2) = (2.0 * R * THETA.cos(), -R * R);
    StateSpace::from_rows(
        &[&[a1, 1.0], &[a2, 0.0]],
        &[&[0.01], &[0.0]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap()
}

/// An oversampled record: random levels in [-2, 2) held for 40 samples (the holds start at
/// multiples of K), a saturation at 1.2 / −0.9, the slow second-order block, white output
/// noise of variance `nv`. Returns (record, clean output).
fn oversampled(n: usize, nv: f64, seed: u64) -> (IoData<f64>, Vec<f64>) {
    let levels = common::lcg_uniform(n / 40 + 1, seed);
    let u: Vec<f64> = (0..n).map(|i| 2.0 * levels[i / 40]).collect();
    let set = EffectSet::of(&[Effect::Saturation]);
    let truth = Udn::with_params(set, &[1.0, 1.2, -0.9]).unwrap();
    let v = truth.eval(&u);
    let clean = slow_block().simulate_siso(&v, None).unwrap();
    let y = common::add_noise(&clean, nv, seed);
    let d = IoData::new(
        hammerstein::faer::Mat::from_fn(n, 1, |i, _| u[i]),
        hammerstein::faer::Mat::from_fn(n, 1, |i, _| y[i]),
    )
    .unwrap();
    (d, clean)
}

#[test]
fn the_decimated_fit_finds_the_plant_at_the_slow_rate() {
    let n = 30_000;
    let (data, clean) = oversampled(n, 1e-3, 7);
    let slow = data.decimate(K).unwrap();
    assert_eq!(slow.len(), n / K);
    assert_eq!(slow.sample_time(), K as f64);
    let set = EffectSet::of(&[Effect::Saturation]);
    let model = Hammerstein::<f64>::udn(set)
        .order(Order::Fixed(2))
        .with_d(false)
        .fit(&slow)
        .unwrap();
    // the slow-rate poles: the fast ones to the power K (a held input is sampled exactly)
    let (mag, ang) = (R.powi(K as i32), THETA * K as f64);
    let poles = model.linear().poles().unwrap();
    for (re, im) in poles {
        let err = (re - mag * ang.cos()).hypot(im.abs() - mag * ang.sin());
        assert!(err < 1e-4, "pole {re}{im:+}j against {mag}·e^±{ang}j");
    }
    let p = model.parameters();
    let z1 = p.iter().find(|(k, _)| k == "z1").unwrap().1;
    let z2 = p.iter().find(|(k, _)| k == "z2").unwrap().1;
    assert!((z1 - 1.2).abs() < 2e-3 && (z2 + 0.9).abs() < 2e-3, "{p:?}");
    // the output's noise is filtered with the band it cannot keep: its variance in the kept
    // samples is about CUTOFF / K of the record's (white noise), not the record's
    let noisy = hammerstein::decimation::decimate_filtered(data.output_slice(0), K);
    let quiet = hammerstein::decimation::decimate_filtered(&clean, K);
    let var = noisy
        .iter()
        .zip(&quiet)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / noisy.len() as f64;
    let expected = 1e-3 * hammerstein::decimation::CUTOFF / K as f64;
    assert!(
        (var / expected - 1.0).abs() < 0.15,
        "noise variance kept {var:e}, expected {expected:e}"
    );
}

#[cfg(feature = "cli")]
mod cli {
    use super::*;

    use common::run_cli_outcome as run;

    /// The model file `m` records the factor `k`, and `compare` and `simulate` of the
    /// `n`-sample record `c` decimate by it and say so; `compare`'s JSON.
    fn carries_its_decimation(m: &str, c: &str, n: usize, k: usize) -> serde_json::Value {
        let file: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(m).unwrap()).unwrap();
        assert_eq!(file["decimation"], k);
        let note = format!("decimated by {k}");
        let (ok, out, err) = run(&["compare", m, c, "--json"]);
        assert!(ok, "{err}");
        let cj: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(cj["n"], n / k);
        assert!(err.contains(&note), "{err}");
        // simulate takes every k-th input sample
        let (ok, out, err) = run(&["simulate", m, c]);
        assert!(ok, "{err}");
        assert_eq!(out.lines().count(), n / k + 1);
        assert!(err.contains(&note), "{err}");
        cj
    }

    #[test]
    fn a_saved_model_carries_its_decimation_to_compare_and_simulate() {
        let n = 12_000;
        let (data, _) = oversampled(n, 1e-3, 11);
        let dir = common::temp_dir("decimate");
        let csv = dir.join("record.csv");
        common::write_csv(
            &csv,
            &["u", "y"],
            &[data.input_slice(0), data.output_slice(0)],
        );
        let model = dir.join("model.json");
        let (c, m) = (csv.to_str().unwrap(), model.to_str().unwrap());
        let fit = common::run_cli(&[
            "fit",
            c,
            "--effects",
            "saturation",
            "--decimate",
            "10",
            "--save",
            m,
            "--json",
        ]);
        let j: serde_json::Value = serde_json::from_str(&fit).unwrap();
        assert_eq!(j["decimation"], 10);
        // 1200 samples left: not worth decimating further
        assert!(j["suggested_decimation"].is_null(), "{fit}");
        // the record as it is: its block's band (about 0.07 rad/sample) allows 20, its length
        // (12 000 samples, at least 1000 kept) 10
        let whole = common::run_cli(&["fit", c, "--effects", "saturation", "--json"]);
        let w: serde_json::Value = serde_json::from_str(&whole).unwrap();
        assert_eq!(w["decimation"], 1);
        assert_eq!(w["suggested_decimation"], 10, "{whole}");
        let file: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
        assert_eq!(file["linear"]["ts"], 10.0);
        // compare and simulate decimate the record as the fit did, and say so
        let cj = carries_its_decimation(m, c, n, 10);
        assert!(cj["fit_percent"].as_f64().unwrap() > 90.0, "{cj}");
        // --decimate overrides the factor the file records (a model saved by the library
        // records none)
        let (ok, out, err) = run(&["compare", m, c, "--json", "--decimate", "20"]);
        assert!(ok, "{err}");
        let cj: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(cj["n"], n / 20);
        let (ok, out, _) = run(&["simulate", m, c, "--decimate", "1"]);
        assert!(ok);
        assert_eq!(out.lines().count(), n + 1);
        // --decimate auto: the band of a linear subspace model of the record allows 20, its
        // length 12 (so 10), said on standard error
        let (ok, out, err) = run(&[
            "fit",
            c,
            "--effects",
            "saturation",
            "--decimate",
            "auto",
            "--json",
        ]);
        assert!(ok, "{err}");
        let aj: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(aj["decimation"], 10, "{err}");
        assert!(err.contains("--decimate auto: 10"), "{err}");
        // the text output says what was done
        let text = common::run_cli(&["fit", c, "--effects", "saturation", "--decimate", "10"]);
        assert!(text.starts_with("record decimated by 10"), "{text}");
        // and diagnose decimates as fit does
        let diag = common::run_cli(&[
            "diagnose",
            c,
            "--effects",
            "saturation",
            "--decimate",
            "10",
            "--json",
        ]);
        let dj: serde_json::Value = serde_json::from_str(&diag).unwrap();
        assert_eq!(dj["decimation"], 10);
        assert!(dj["suggested_decimation"].is_null(), "{diag}");
        let text = common::run_cli(&["diagnose", c, "--effects", "saturation", "--decimate", "10"]);
        assert!(text.starts_with("record decimated by 10"), "{text}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_several_input_model_records_its_decimation_too() {
        let n = 8000;
        let (data, _) = oversampled(n, 1e-3, 5);
        // a second input, held 60 samples, through half the slow block into the same output
        let u2: Vec<f64> = {
            let l = common::lcg_uniform(n / 60 + 1, 99);
            (0..n).map(|i| l[i / 60]).collect()
        };
        let half: Vec<f64> = u2.iter().map(|v| 0.5 * v).collect();
        let y2 = slow_block().simulate_siso(&half, None).unwrap();
        let y: Vec<f64> = data
            .output_slice(0)
            .iter()
            .zip(&y2)
            .map(|(y, b)| y + b)
            .collect();
        let dir = common::temp_dir("decimate-miso");
        let csv = dir.join("record.csv");
        common::write_csv(&csv, &["u1", "u2", "y"], &[data.input_slice(0), &u2, &y]);
        let model = dir.join("model.json");
        let (c, m) = (csv.to_str().unwrap(), model.to_str().unwrap());
        let fit = common::run_cli(&[
            "fit",
            c,
            "--input",
            "u1,u2",
            "--decimate",
            "10",
            "--save",
            m,
            "--json",
        ]);
        let j: serde_json::Value = serde_json::from_str(&fit).unwrap();
        assert_eq!(j["decimation"], 10);
        assert!(j["suggested_decimation"].is_null(), "{fit}");
        // at the full rate both branches' blocks are slow: the band allows 20, the length
        // (8000 samples) 8, so 5
        let whole = common::run_cli(&["fit", c, "--input", "u1,u2", "--json"]);
        let w: serde_json::Value = serde_json::from_str(&whole).unwrap();
        assert_eq!(w["suggested_decimation"], 5, "{whole}");
        carries_its_decimation(m, c, n, 10);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn bad_factors_are_refused_with_their_cause() {
        let (data, _) = oversampled(400, 1e-3, 3);
        let dir = common::temp_dir("decimate-bad");
        let csv = dir.join("record.csv");
        common::write_csv(
            &csv,
            &["u", "y"],
            &[data.input_slice(0), data.output_slice(0)],
        );
        let c = csv.to_str().unwrap();
        let (ok, _, err) = run(&["fit", c, "--decimate", "0"]);
        assert!(!ok && err.contains("a factor ≥ 1"), "{err}");
        // auto on a record too short to decimate: 1, and said so
        let (ok, out, err) = run(&["fit", c, "--decimate", "auto", "--json"]);
        assert!(ok, "{err}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(j["decimation"], 1);
        assert!(err.contains("not oversampled"), "{err}");
        let (ok, _, err) = run(&["fit", c, "--decimate", "400"]);
        assert!(
            !ok && err.contains("decimating by 400") && err.contains("record.csv"),
            "{err}"
        );
        let (ok, _, err) = run(&["subspace", c, "--decimate", "400"]);
        assert!(!ok && err.contains("decimating by 400"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
