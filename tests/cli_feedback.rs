//! `fit --feedback-nonlinearity` with `--save`, then `compare` and `simulate` of the saved
//! feedback model; the algebraic-loop refusal.

mod common;

use common::{run_cli as run, run_cli_outcome, temp_dir, write_train_val};

/// A cubic stiffness in feedback around a resonant second-order block, 40 dB-ish noise.
fn record(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    common::resonant_loop_record(n, seed, 0.08, |u| u, |x1, _| -0.02 * x1.powi(3))
}

#[test]
fn a_feedback_model_is_fitted_saved_compared_and_simulated() {
    let dir = temp_dir("cli-feedback");
    let (u, y) = record(3000, 1);
    let (uv, yv) = record(2000, 2);
    let (train, val) = write_train_val(&dir, (&u, &y), (&uv, &yv));
    let model = dir.join("model.json");
    let out = run(&[
        "fit",
        train.to_str().unwrap(),
        "--feedback-nonlinearity",
        "poly3",
        "--order",
        "2",
        "--validation-file",
        val.to_str().unwrap(),
        "--save",
        model.to_str().unwrap(),
        "--json",
    ]);
    let j: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(j["kind"], "feedback");
    let lin = j["linear_rms"].as_f64().unwrap();
    let val_rms = j["validation_rms"].as_f64().unwrap();
    // the noise is uniform with RMS 0.01/√12 ≈ 0.0029
    assert!(val_rms < 0.0045 && val_rms < 0.5 * lin, "{j}");
    let text = std::fs::read_to_string(&model).unwrap();
    assert!(text.contains("\"kind\": \"feedback\""));
    let c = run(&[
        "compare",
        model.to_str().unwrap(),
        val.to_str().unwrap(),
        "--json",
    ]);
    let c: serde_json::Value = serde_json::from_str(c.trim()).unwrap();
    assert!((c["rms"].as_f64().unwrap() - val_rms).abs() < 1e-9, "{c}");
    let s = run(&["simulate", model.to_str().unwrap(), val.to_str().unwrap()]);
    assert_eq!(s.lines().count(), uv.len() + 1);
    assert!(s.starts_with("u,y_hat"));
    let (ok, _, err) = run_cli_outcome(&[
        "fit",
        train.to_str().unwrap(),
        "--feedback-nonlinearity",
        "coulomb",
        "--feedback-on",
        "velocity",
        "--feedthrough",
        "on",
    ]);
    assert!(!ok && err.contains("algebraic"), "{err}");
    let (ok, _, err) = run_cli_outcome(&[
        "fit",
        train.to_str().unwrap(),
        "--feedback-nonlinearity",
        "cubic",
    ]);
    assert!(
        !ok && err.contains("unknown feedback nonlinearity"),
        "{err}"
    );
    let (ok, _, err) = run_cli_outcome(&[
        "fit",
        train.to_str().unwrap(),
        "--feedback-nonlinearity",
        "poly3",
        "--output-nonlinearity",
        "poly",
        "--feedback-on",
        "sideways",
    ]);
    assert!(!ok && err.contains("--feedback-on takes"), "{err}");
    let (ok, _, err) = run_cli_outcome(&[
        "fit",
        train.to_str().unwrap(),
        "--feedback-nonlinearity",
        "poly3",
        "--output-nonlinearity",
        "poly1",
    ]);
    assert!(!ok && err.contains("degree must be 2..=9"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
