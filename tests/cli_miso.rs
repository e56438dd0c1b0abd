//! `fit` and `diagnose` with several inputs on the command line (issue 12, item 2):
//! `--input u1,u2 --effects u1:LIST`, suggestions naming their input, the model file, errors.

mod common;

use common::{InputKind, Udn, input, write_csv};

use common::run_cli_outcome as run;

/// u1 through a saturation into a second-order block, u2 through a dead-zone into a
/// first-order one, summed, offset 0.5, white noise of variance 4e-4.
fn record(dir: &std::path::Path) -> std::path::PathBuf {
    let n = 3000;
    let u1 = input(InputKind::Uniform, n, 2.0, 11);
    let u2 = input(InputKind::Smooth, n, 2.0, 12);
    let g1 = common::slow_block();
    let g2 =
        hammerstein::StateSpace::from_rows(&[&[0.7]], &[&[0.6]], &[&[1.0]], &[&[0.0]]).unwrap();
    let s1 = Udn {
        z1: 0.8,
        z2: -1.0,
        ..Udn::linear(1.0)
    };
    let d2 = Udn {
        b: 0.4,
        ..Udn::linear(1.5)
    };
    let y1 = g1.simulate_siso(&s1.eval(&u1), None).unwrap();
    let y2 = g2.simulate_siso(&d2.eval(&u2), None).unwrap();
    let y0: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b + 0.5).collect();
    let y = common::add_noise(&y0, 4e-4, 5);
    let path = dir.join("two.csv");
    write_csv(&path, &["u1", "u2", "y"], &[&u1, &u2, &y]);
    path
}

/// `fit` of the record with both inputs' true effects, plus `extra` arguments.
fn fit_true_effects(data: &str, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec![
        "fit",
        data,
        "--input",
        "u1,u2",
        "--effects",
        "u1:saturation",
        "--effects",
        "u2:dead-zone",
    ];
    args.extend_from_slice(extra);
    run(&args)
}

#[test]
fn diagnose_names_the_input_and_follow_reaches_the_floor() {
    let dir = common::temp_dir("cli-miso");
    let data = record(&dir);
    let d = data.to_str().unwrap();
    let (ok, out, err) = run(&[
        "diagnose",
        d,
        "--input",
        "u1,u2",
        "--effects",
        "u1:saturation",
        "--json",
    ]);
    assert!(ok, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let top = &j["suggestions"][0];
    assert_eq!(top["input"], "u2", "{top}");
    assert_eq!(top["effect"], "dead-zone", "{top}");
    assert_eq!(j["model"]["inputs"][1]["input"], "u2");
    let (ok, out, err) = run(&[
        "diagnose",
        d,
        "--input",
        "u1,u2",
        "--effects",
        "u1:saturation",
        "--follow",
        "--json",
    ]);
    assert!(ok, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["steps"][1]["change"], "u2: + dead-zone", "{}", j["steps"]);
    let mse = j["validation"]["mse"].as_f64().unwrap();
    assert!(
        mse <= 1.5 * 4e-4,
        "validation MSE {mse:e} after following (noise 4e-4)"
    );
}

#[test]
fn report_draws_every_input_nonlinearity() {
    let dir = common::temp_dir("cli-miso-report");
    let data = record(&dir);
    let rep = dir.join("rep");
    let (ok, _, err) =
        fit_true_effects(data.to_str().unwrap(), &["--report", rep.to_str().unwrap()]);
    assert!(ok, "{err}");
    for f in [
        "index.html",
        "output.svg",
        "nonlinearity.svg",
        "nonlinearity-input-2.svg",
    ] {
        assert!(rep.join(f).exists(), "{f} missing");
    }
    let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
    assert!(
        html.contains("(input u2)"),
        "the second input's plot is not titled by its name"
    );
}

#[test]
fn fit_saves_a_model_compare_reads_it() {
    let dir = common::temp_dir("cli-miso-save");
    let data = record(&dir);
    let model = dir.join("m.json");
    let (d, m) = (data.to_str().unwrap(), model.to_str().unwrap());
    let (ok, out, err) = fit_true_effects(d, &["--save", m, "--json"]);
    assert!(ok, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let fit = j["train"]["fit_percent"].as_f64().unwrap();
    assert!(fit > 95.0, "train fit {fit} %");
    let (ok, out, err) = run(&["compare", m, d, "--json"]);
    assert!(ok, "{err}");
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    let again = c["fit_percent"].as_f64().unwrap();
    assert!(
        (again - fit).abs() < 0.05,
        "compare {again} % vs fit {fit} %"
    );
    // the model's own input names in another order: each branch reads its own column (they
    // were mapped by position: the u1 branch fed u2, fit 18.8 % on the audit's record)
    let (ok, out, err) = run(&["compare", m, d, "--input", "u2,u1", "--json"]);
    assert!(ok, "{err}");
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(c["fit_percent"].as_f64().unwrap(), again);
}

#[test]
fn several_input_mistakes_are_one_line_errors() {
    let dir = common::temp_dir("cli-miso-err");
    let data = record(&dir);
    let d = data.to_str().unwrap();
    for (args, needle) in [
        (vec!["--effects", "saturation"], "name the input"),
        (
            vec!["--effects", "u3:saturation"],
            "'u3' is not one of the inputs",
        ),
        (
            vec!["--effects", "u1:saturation", "--effects", "u1:dead-zone"],
            "given twice",
        ),
        (
            vec!["--output-nonlinearity", "poly3"],
            "not supported with several inputs",
        ),
    ] {
        let mut a = vec!["fit", d, "--input", "u1,u2"];
        a.extend(args.iter());
        let (ok, _, err) = run(&a);
        assert!(!ok && err.contains(needle), "{a:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    let (ok, _, err) = run(&["fit", d, "--input", "u1,u9"]);
    assert!(!ok && err.contains("unknown column 'u9'"), "{err}");
}

#[test]
fn simulate_runs_a_saved_two_input_model() {
    let dir = common::temp_dir("cli-miso-sim");
    let data = record(&dir);
    let model = dir.join("m.json");
    let out = dir.join("sim.csv");
    let (ok, _, err) =
        fit_true_effects(data.to_str().unwrap(), &["--save", model.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, _, err) = run(&[
        "simulate",
        model.to_str().unwrap(),
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("u1,u2,y_hat"));
    assert_eq!(lines.count(), 3000);
}

/// A damaged several-input model file: `compare` and `simulate` (which read the file once, then
/// take it by its kind) refuse it in one line naming the file and, where the JSON is whole but
/// its fields are not, the field with its line and column.
#[test]
fn a_damaged_two_input_model_file_is_one_line_error() {
    let dir = common::temp_dir("cli-miso-damaged");
    let data = record(&dir);
    let d = data.to_str().unwrap();
    let model = dir.join("m.json");
    let (ok, _, err) = run(&[
        "fit",
        d,
        "--input",
        "u1,u2",
        "--order",
        "2",
        "--save",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&model).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_object_mut().unwrap().remove("inputs");
    let no_inputs = dir.join("no-inputs.json");
    std::fs::write(&no_inputs, v.to_string()).unwrap();
    let truncated = dir.join("truncated.json");
    std::fs::write(&truncated, &text[..text.len() / 2]).unwrap();
    for cmd in ["compare", "simulate"] {
        for (file, needle) in [
            (
                &no_inputs,
                "no-inputs.json: not a several-input model file: missing field `inputs` at line 1",
            ),
            (
                &truncated,
                "truncated.json: not valid JSON: EOF while parsing",
            ),
        ] {
            let (ok, out, err) = run(&[cmd, file.to_str().unwrap(), d]);
            assert!(!ok, "{cmd} {file:?} succeeded: {out}");
            assert_eq!(err.trim().lines().count(), 1, "{err}");
            assert!(
                err.starts_with("error: model file: ") && err.contains(needle),
                "{cmd} {file:?}: {err}"
            );
        }
    }
}
