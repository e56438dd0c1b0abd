//! `fit --feedback-nonlinearity poly3 --output-nonlinearity poly3`: a cubic stiffness in the
//! loop measured through a cubic sensor curve, fitted, saved, compared and simulated.

mod common;

use common::{run_cli as run, temp_dir, write_train_val};

/// The resonant second-order block with a cubic stiffness on the output (uniform output noise
/// of RMS 0.01/√12), its noise-free output x₁ measured as g(x₁) = x₁ + 0.12 x₁³ / r², `r` the
/// RMS of the training record's x₁ (`None`: this record's own).
fn record(n: usize, seed: u64, r: Option<f64>) -> (Vec<f64>, Vec<f64>, f64) {
    let force = |x1: f64, _| -0.02 * x1.powi(3);
    let (u, y) = common::resonant_loop_record(n, seed, 0.12, |u: f64| u, force);
    let x = common::resonant_loop(&u, |u| u, force);
    let r = r.unwrap_or_else(|| (x.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt());
    let y = x
        .iter()
        .zip(&y)
        .map(|(x, y)| x + 0.12 * x.powi(3) / (r * r) + (y - x))
        .collect();
    (u, y, r)
}

#[test]
fn an_output_map_after_the_loop_is_fitted_saved_compared_and_simulated() {
    let dir = temp_dir("cli-feedback-output");
    let (u, y, r) = record(3000, 1, None);
    let (uv, yv, _) = record(2000, 2, Some(r));
    let (train, val) = write_train_val(&dir, (&u, &y), (&uv, &yv));
    let (t, v) = (train.to_str().unwrap(), val.to_str().unwrap());
    let model = dir.join("model.json");
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "fit",
            t,
            "--feedback-nonlinearity",
            "poly3",
            "--order",
            "2",
            "--validation-file",
            v,
        ];
        a.extend_from_slice(extra);
        a
    };
    let alone: serde_json::Value = serde_json::from_str(run(&args(&["--json"])).trim()).unwrap();
    let mut with_args = args(&["--output-nonlinearity", "poly3", "--json", "--save"]);
    with_args.push(model.to_str().unwrap());
    let j: serde_json::Value = serde_json::from_str(run(&with_args).trim()).unwrap();
    assert_eq!(j["output_nonlinearity"], "poly3", "{j}");
    let (va, vw) = (
        alone["validation_rms"].as_f64().unwrap(),
        j["validation_rms"].as_f64().unwrap(),
    );
    eprintln!("validation RMS: loop alone {va:.4e}, with the output map {vw:.4e}");
    // the noise is uniform with RMS 0.01/√12 ≈ 0.0029
    assert!(
        vw < 0.0035 && va > 1.5 * vw,
        "alone {va}, with the output map {vw}"
    );
    assert!(
        j["train_rms"].as_f64().unwrap() <= alone["train_rms"].as_f64().unwrap() * (1.0 + 1e-9)
    );
    let text = std::fs::read_to_string(&model).unwrap();
    assert!(text.contains("\"output_nonlinearity\""));
    let c = run(&["compare", model.to_str().unwrap(), v, "--json"]);
    let c: serde_json::Value = serde_json::from_str(c.trim()).unwrap();
    assert!((c["rms"].as_f64().unwrap() - vw).abs() < 1e-9, "{c}");
    let s = run(&["simulate", model.to_str().unwrap(), v]);
    assert_eq!(s.lines().count(), uv.len() + 1);
    // the text output names the map; the report draws g beside f
    let report = dir.join("report");
    let mut text_args = args(&["--output-nonlinearity", "poly3", "--report"]);
    text_args.push(report.to_str().unwrap());
    let out = run(&text_args);
    assert!(out.contains("output map after the loop: poly3"), "{out}");
    assert!(report.join("output-map.svg").exists());
    assert!(report.join("feedback-nonlinearity.svg").exists());
    // diagnose of the combined model names the map and tests its residual
    let d = run(&[
        "diagnose",
        t,
        "--feedback-nonlinearity",
        "poly3",
        "--output-nonlinearity",
        "poly3",
        "--order",
        "2",
        "--json",
    ]);
    let d: serde_json::Value = serde_json::from_str(d.trim()).unwrap();
    assert_eq!(d["output_nonlinearity"], "poly3", "{d}");
    assert!(d["validation_rms"].as_f64().unwrap() < 0.0035, "{d}");
    std::fs::remove_dir_all(&dir).ok();
}
