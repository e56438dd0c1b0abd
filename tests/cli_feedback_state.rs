//! `--feedback-on state` on the command line: `fit` (with `--save`, `--json`), `compare` and
//! `simulate` of the saved model, and `diagnose --feedback-nonlinearity … --feedback-on state`.

mod common;

use common::{run_cli as run, run_cli_outcome, temp_dir, write_train_val};

/// A cubic loop on the state combination z = 0.5 x₁ + x₂ of a resonant second-order block
/// (y = x₁), uniform output noise of RMS 0.01/√12.
fn record(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    common::resonant_loop_record(
        n,
        seed,
        0.08,
        |u| u,
        |x1, x2| -0.05 * (0.5 * x1 + x2).powi(3),
    )
}

fn fit_json(train: &str, val: &str, on: &str, save: Option<&str>) -> serde_json::Value {
    let mut args = vec![
        "fit",
        train,
        "--feedback-nonlinearity",
        "poly3",
        "--feedback-on",
        on,
        "--order",
        "2",
        "--validation-file",
        val,
        "--json",
    ];
    if let Some(p) = save {
        args.extend(["--save", p]);
    }
    serde_json::from_str(run(&args).trim()).unwrap()
}

#[test]
fn a_state_feedback_model_is_fitted_saved_compared_simulated_and_diagnosed() {
    let dir = temp_dir("cli-feedback-state");
    let (u, y) = record(3000, 1);
    let (uv, yv) = record(2000, 2);
    let (train, val) = write_train_val(&dir, (&u, &y), (&uv, &yv));
    let (t, v) = (train.to_str().unwrap(), val.to_str().unwrap());
    let model = dir.join("model.json");
    let j = fit_json(t, v, "state", Some(model.to_str().unwrap()));
    assert_eq!(j["kind"], "feedback");
    assert_eq!(j["feedback_on"], "state");
    assert_eq!(j["state_combination"].as_array().unwrap().len(), 2, "{j}");
    let val_rms = j["validation_rms"].as_f64().unwrap();
    // the noise is uniform with RMS 0.01/√12 ≈ 0.0029
    assert!(val_rms < 0.0035, "{j}");
    let out = fit_json(t, v, "output", None);
    let out_rms = out["validation_rms"].as_f64().unwrap();
    assert!(
        out_rms > 1.5 * val_rms,
        "output {out_rms} vs state {val_rms}"
    );
    let text = std::fs::read_to_string(&model).unwrap();
    assert!(text.contains("\"state_combination\""));
    let c = run(&["compare", model.to_str().unwrap(), v, "--json"]);
    let c: serde_json::Value = serde_json::from_str(c.trim()).unwrap();
    assert!((c["rms"].as_f64().unwrap() - val_rms).abs() < 1e-9, "{c}");
    let s = run(&["simulate", model.to_str().unwrap(), v]);
    assert_eq!(s.lines().count(), uv.len() + 1);
    let d = run(&[
        "diagnose",
        t,
        "--feedback-nonlinearity",
        "poly3",
        "--feedback-on",
        "state",
        "--order",
        "2",
        "--json",
    ]);
    let d: serde_json::Value = serde_json::from_str(d.trim()).unwrap();
    assert_eq!(d["feedback_on"], "state", "{d}");
    let (ok, _, err) = run_cli_outcome(&[
        "fit",
        t,
        "--feedback-nonlinearity",
        "poly3",
        "--feedback-on",
        "states",
    ]);
    assert!(!ok && err.contains("'state'"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
