//! Bad input on every subcommand gives a one-line error on stderr and a non-zero exit code.

mod common;

use common::{InputKind, Udn, add_noise, input, paper_block, temp_dir, write_csv};
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hammerstein"))
}

/// Runs the binary and checks a failing exit with exactly one `error: …` line on stderr.
fn fails(args: &[&str], needle: &str) {
    let out = bin().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?}: not one line:\n{stderr}");
    assert!(lines[0].starts_with("error: "), "{args:?}: {stderr}");
    assert!(
        lines[0].to_lowercase().contains(&needle.to_lowercase()),
        "{args:?}: '{}' lacks '{needle}'",
        lines[0]
    );
}

struct Files {
    dir: PathBuf,
    good: PathBuf,
    nan: PathBuf,
    short: PathBuf,
    constant: PathBuf,
}

fn files(tag: &str) -> Files {
    let dir = temp_dir(tag);
    let u = input(InputKind::Uniform, 600, 3.0, 1);
    let v = Udn::linear(2.0).eval(&u);
    let y0 = paper_block().simulate_siso(&v, None).unwrap();
    let y = add_noise(&y0, 0.01, 1);
    let good = dir.join("good.csv");
    write_csv(&good, &["u", "y"], &[&u, &y]);
    let mut un = u.clone();
    un[17] = f64::NAN;
    let nan = dir.join("nan.csv");
    write_csv(&nan, &["u", "y"], &[&un, &y]);
    let short = dir.join("short.csv");
    write_csv(&short, &["u", "y"], &[&u[..8], &y[..8]]);
    let constant = dir.join("constant.csv");
    write_csv(&constant, &["u", "y"], &[&vec![1.0; 600], &y]);
    Files {
        dir,
        good,
        nan,
        short,
        constant,
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn fit_and_diagnose_reject_bad_input() {
    let f = files("cli-err-fit");
    for cmd in ["fit", "diagnose"] {
        fails(&[cmd, s(&f.dir.join("missing.csv"))], "cannot access");
        fails(
            &[cmd, s(&f.good), "--input", "force"],
            "unknown column 'force'",
        );
        fails(
            &[cmd, s(&f.good), "--output", "pos"],
            "unknown column 'pos'",
        );
        fails(&[cmd, s(&f.nan)], "non-finite");
        fails(&[cmd, s(&f.short)], "not enough samples");
        fails(&[cmd, s(&f.constant)], "constant");
        fails(
            &[cmd, s(&f.good), "--effects", "hysteresis,frictoin"],
            "unknown effect",
        );
        fails(
            &[cmd, s(&f.good), "--nonlinearity", "cubic"],
            "unknown nonlinearity",
        );
        fails(
            &[cmd, s(&f.good), "--validate", "1.5"],
            "validation fraction",
        );
        fails(&[cmd, s(&f.good), "--order", "many"], "order");
        fails(&[cmd, s(&f.good), "--precision", "f16"], "precision");
    }
    fails(
        &["diagnose", s(&f.good), "--add-effect", "stiction"],
        "unknown effect",
    );
}

#[test]
fn compare_and_simulate_reject_bad_input() {
    let f = files("cli-err-cmp");
    let model = f.dir.join("model.json");
    let out = bin()
        .args(["fit", s(&f.good), "--save", s(&model)])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // compare
    fails(
        &["compare", s(&f.dir.join("nope.json")), s(&f.good)],
        "cannot access",
    );
    fails(&["compare", s(&f.good), s(&f.good)], "model file");
    fails(
        &["compare", s(&model), s(&f.dir.join("missing.csv"))],
        "cannot access",
    );
    fails(
        &["compare", s(&model), s(&f.good), "--input", "force"],
        "unknown column",
    );
    fails(&["compare", s(&model), s(&f.nan)], "non-finite");
    fails(&["compare", s(&model), s(&f.constant)], "constant");
    // simulate
    fails(
        &["simulate", s(&f.dir.join("nope.json")), s(&f.good)],
        "cannot access",
    );
    fails(
        &["simulate", s(&model), s(&f.dir.join("missing.csv"))],
        "cannot access",
    );
    fails(
        &["simulate", s(&model), s(&f.good), "--input", "force"],
        "unknown column",
    );
    fails(&["simulate", s(&model), s(&f.nan)], "non-finite");
    let one = f.dir.join("one.csv");
    write_csv(&one, &["u"], &[&[0.5]]);
    fails(&["simulate", s(&model), s(&one)], "not enough samples");
    // a constant input is a valid simulation input
    let outp = f.dir.join("sim.csv");
    let out = bin()
        .args(["simulate", s(&model), s(&f.constant), "--out", s(&outp)])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&outp).unwrap();
    assert_eq!(text.lines().count(), 601);
    assert!(text.starts_with("u,y_hat\n"));
}
