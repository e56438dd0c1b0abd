//! `fit --feedback-nonlinearity poly3 --effects saturation`: an input saturation before the
//! loop, saved, compared and simulated; `diagnose` of the same combined model.

mod common;

use common::{run_cli as run, temp_dir, write_train_val};

/// u saturated at ±0.06 into a resonant second-order block with a cubic stiffness on the
/// output; uniform output noise of RMS 0.01/√12.
fn record(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    common::resonant_loop_record(
        n,
        seed,
        0.12,
        |u: f64| u.clamp(-0.06, 0.06),
        |x1, _| -0.02 * x1.powi(3),
    )
}

#[test]
fn an_input_saturation_before_the_loop_is_fitted_saved_compared_and_simulated() {
    let dir = temp_dir("cli-feedback-input");
    let (u, y) = record(3000, 1);
    let (uv, yv) = record(2000, 2);
    let (train, val) = write_train_val(&dir, (&u, &y), (&uv, &yv));
    let (t, v) = (train.to_str().unwrap(), val.to_str().unwrap());
    let model = dir.join("model.json");
    let fit = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "fit",
            t,
            "--feedback-nonlinearity",
            "poly3",
            "--order",
            "2",
            "--validation-file",
            v,
            "--json",
        ];
        args.extend_from_slice(extra);
        serde_json::from_str(run(&args).trim()).unwrap()
    };
    let alone = fit(&[]);
    let j = fit(&["--effects", "saturation", "--save", model.to_str().unwrap()]);
    assert!(j["input_nonlinearity"].is_string(), "{j}");
    let (va, vw) = (
        alone["validation_rms"].as_f64().unwrap(),
        j["validation_rms"].as_f64().unwrap(),
    );
    // the noise is uniform with RMS 0.01/√12 ≈ 0.0029
    assert!(
        vw < 0.0035 && va > 1.5 * vw,
        "alone {va}, with the saturation {vw}"
    );
    assert!(
        j["train_rms"].as_f64().unwrap() <= alone["train_rms"].as_f64().unwrap() * (1.0 + 1e-9)
    );
    let text = std::fs::read_to_string(&model).unwrap();
    assert!(text.contains("\"input_nonlinearity\""));
    let c = run(&["compare", model.to_str().unwrap(), v, "--json"]);
    let c: serde_json::Value = serde_json::from_str(c.trim()).unwrap();
    assert!((c["rms"].as_f64().unwrap() - vw).abs() < 1e-9, "{c}");
    let s = run(&["simulate", model.to_str().unwrap(), v]);
    assert_eq!(s.lines().count(), uv.len() + 1);
    // diagnose of the combined model: the same input nonlinearity before the loop, its
    // residual tests, and its error on the held-back part below the loop alone's
    let diagnose = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "diagnose",
            t,
            "--feedback-nonlinearity",
            "poly3",
            "--order",
            "2",
            "--json",
        ];
        args.extend_from_slice(extra);
        serde_json::from_str(run(&args).trim()).unwrap()
    };
    let d_alone = diagnose(&[]);
    let d = diagnose(&["--effects", "saturation"]);
    assert!(d["input_nonlinearity"].is_string(), "{d}");
    assert!(d_alone["input_nonlinearity"].is_null(), "{d_alone}");
    assert!(!d["tests"].as_array().unwrap().is_empty(), "{d}");
    let (da, dw) = (
        d_alone["validation_rms"].as_f64().unwrap(),
        d["validation_rms"].as_f64().unwrap(),
    );
    eprintln!("diagnose, held-back RMS: loop alone {da:.4e}, with the saturation {dw:.4e}");
    assert!(dw < 0.0035 && da > 1.5 * dw, "alone {da}, with {dw}");
    std::fs::remove_dir_all(&dir).ok();
}
