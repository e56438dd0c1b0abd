//! `diagnose --save FILE` writes the model it reports: with `--follow` the model the guided loop
//! ends with, without it the diagnosed model; `compare` of the saved model on the validation
//! record gives the validation numbers `diagnose` printed.

mod common;

use common::{Udn, lcg_uniform, run_cli, slow_block, temp_dir, write_csv};

/// A saturation record through the slow second-order block, written as train.csv and
/// val.csv in a fresh directory.
fn records() -> std::path::PathBuf {
    let n = 900;
    let u: Vec<f64> = lcg_uniform(n, 31).iter().map(|x| 2.0 * x).collect();
    let truth = Udn {
        z1: 1.2,
        z2: -1.0,
        ..Udn::linear(1.0)
    };
    let y0 = slow_block().simulate_siso(&truth.eval(&u), None).unwrap();
    let e = lcg_uniform(n, 32);
    let y: Vec<f64> = y0.iter().zip(&e).map(|(y, e)| y + 0.02 * e).collect();
    let dir = temp_dir("diagnose-save");
    write_csv(&dir.join("train.csv"), &["u", "y"], &[&u[..600], &y[..600]]);
    write_csv(&dir.join("val.csv"), &["u", "y"], &[&u[600..], &y[600..]]);
    dir
}

fn number(v: &serde_json::Value, what: &str) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{what}: {v}"))
}

/// `diagnose … --save m.json --json` (with `extra`), then `compare m.json val.csv --json`: the
/// validation MSE and fit % agree to round-off, and the saved model's structure is the one
/// reported.
fn saved_model_reproduces(extra: &[&str]) {
    let dir = records();
    let (train, val, model) = (
        dir.join("train.csv"),
        dir.join("val.csv"),
        dir.join("m.json"),
    );
    let mut args = vec![
        "diagnose",
        train.to_str().unwrap(),
        "--validation-file",
        val.to_str().unwrap(),
        "--order",
        "2",
        "--save",
        model.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    let d: serde_json::Value = serde_json::from_str(&run_cli(&args)).unwrap();
    let c: serde_json::Value = serde_json::from_str(&run_cli(&[
        "compare",
        model.to_str().unwrap(),
        val.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    for key in ["mse", "fit_percent"] {
        let (a, b) = (number(&d["validation"][key], key), number(&c[key], key));
        assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(1e-300),
            "{extra:?}: diagnose's validation {key} {a} against the saved model's {b}"
        );
    }
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(number(&d["order"], "order") as usize, order_of(&saved));
    std::fs::remove_dir_all(&dir).ok();
}

/// The linear block's order of a saved model file (the side of its A matrix).
fn order_of(file: &serde_json::Value) -> usize {
    file["linear"]["a"].as_array().map_or(0, |a| a.len())
}

#[test]
fn diagnose_save_writes_the_diagnosed_model() {
    saved_model_reproduces(&["--effects", "linear"]);
}

#[test]
fn diagnose_follow_save_writes_the_final_model() {
    saved_model_reproduces(&["--effects", "linear", "--follow", "--max-steps", "2"]);
}
