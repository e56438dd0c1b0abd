//! `design` → replay on a simulated plant → `bla` and `structure`, as one flow through the
//! command line; and the record errors the commands report.

mod structure_common;

use hammerstein::data::CsvTable;
use hammerstein::structure::Record;
use rand::{SeedableRng, rngs::StdRng};
use std::path::{Path, PathBuf};
use std::process::Command;
use structure_common::{Family, Plant, replay};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hammerstein"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "hammerstein-structure-{name}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> (bool, String, String) {
    let o = bin().args(args).output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn measured(design: &Path, family: Family, seed: u64, out: &Path) {
    let t = CsvTable::read(design).unwrap();
    let rec = Record::from_columns(&t.names, &t.columns, "u", None, "design").unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    let plant = Plant::random(family, &mut rng, 1.0, 1.0);
    let r = replay(&rec, &plant, 40.0, seed + 1).unwrap();
    let mut bytes = Vec::new();
    r.write_csv(&mut bytes).unwrap();
    std::fs::write(out, bytes).unwrap();
}

#[test]
fn design_replay_structure_flow() {
    let d = dir("flow");
    let design = d.join("design.csv");
    let (ok, _, err) = run(&[
        "design",
        "--multisine",
        "random-odd",
        "--samples",
        "1024",
        "--band",
        "0.01,0.2",
        "--group",
        "4",
        "--levels",
        "0.25,0.5,1",
        "--realizations",
        "4",
        "--periods",
        "2",
        "--seed",
        "7",
        "--out",
        design.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let head = std::fs::read_to_string(&design).unwrap();
    assert!(head.starts_with("level,realization,period,u\n"));
    for (family, expect) in [
        (Family::Feedback, "feedback"),
        (Family::Hammerstein, "single-branch"),
    ] {
        let rec = d.join(format!("{family:?}.csv"));
        measured(&design, family, 3, &rec);
        let (ok, out, err) = run(&[
            "structure",
            rec.to_str().unwrap(),
            "--input",
            "u",
            "--output",
            "y",
            "--json",
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["verdict"], expect, "{family:?}: {out}");
        assert_eq!(v["levels"].as_array().unwrap().len(), 3);
        for key in ["rms", "poles", "zeros", "distortion_db"] {
            assert!(v["levels"][0].get(key).is_some(), "{key} missing");
        }
        assert!(v["moved"].is_array() && v["candidates"].is_array());
        if expect == "single-branch" {
            assert_eq!(v["candidates"][0], "hammerstein", "{out}");
            let r = &v["ranking"]["candidates"];
            assert_eq!(r.as_array().unwrap().len(), 3, "{out}");
            assert!(r[0]["validation_mse"].as_f64().unwrap() > 0.0);
            assert!(v["ranking"]["decisive"].is_boolean());
        } else {
            assert!(v["ranking"].is_null());
        }
        if expect == "feedback" {
            assert!(
                !v["moved"].as_array().unwrap().is_empty(),
                "feedback names no moved pole"
            );
            assert_eq!(v["moved"][0]["kind"], "pole");
        }
        let (ok, out, err) = run(&["bla", rec.to_str().unwrap()]);
        assert!(ok, "{err}");
        assert!(out.contains("NONLINEAR"), "{out}");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn record_errors_are_clear() {
    let d = dir("errors");
    // blocks that are not whole periods
    let p = d.join("ragged.csv");
    let mut s = String::from("level,realization,period,u,y\n");
    for (per, n) in [(0, 8), (1, 7)] {
        for i in 0..n {
            s.push_str(&format!("0,0,{per},{},{}\n", i as f64, i as f64));
        }
    }
    std::fs::write(&p, &s).unwrap();
    let (ok, _, err) = run(&["bla", p.to_str().unwrap()]);
    assert!(!ok && err.contains("not whole periods"), "{err}");
    // a period column that does not count up
    let p = d.join("count.csv");
    let mut s = String::from("level,realization,period,u,y\n");
    for per in [0, 2] {
        for i in 0..8 {
            s.push_str(&format!("0,0,{per},{},{}\n", i as f64, i as f64));
        }
    }
    std::fs::write(&p, &s).unwrap();
    let (ok, _, err) = run(&["bla", p.to_str().unwrap()]);
    assert!(!ok && err.contains("does not count up"), "{err}");
    // a plain record whose length is not whole periods
    let p = d.join("plain.csv");
    let s: String = std::iter::once("u,y\n".to_string())
        .chain((0..100).map(|i| format!("{},{}\n", (i as f64).sin(), (i as f64).cos())))
        .collect();
    std::fs::write(&p, &s).unwrap();
    let (ok, _, err) = run(&["structure", p.to_str().unwrap(), "--period", "30"]);
    assert!(!ok && err.contains("not whole periods"), "{err}");
    let (ok, _, err) = run(&["structure", p.to_str().unwrap()]);
    assert!(!ok && err.contains("--period"), "{err}");
    // one level only: structure refuses and says what one level tells
    let design = d.join("one.csv");
    let (ok, _, err) = run(&[
        "design",
        "--levels",
        "1",
        "--samples",
        "256",
        "--out",
        design.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let one = d.join("one_measured.csv");
    measured(&design, Family::Wiener, 5, &one);
    let (ok, _, err) = run(&["structure", one.to_str().unwrap()]);
    assert!(
        !ok && err.contains("one level") && err.contains("nonlinear"),
        "{err}"
    );
    // unexcited lines: one realization leaves out a line the others excite
    let t = CsvTable::read(&one).unwrap();
    let rec = Record::from_columns(&t.names, &t.columns, "u", Some("y"), "one").unwrap();
    let mut blocks = rec.blocks().to_vec();
    let n = rec.period();
    let u0 = blocks[0].u[..n].to_vec();
    let k = hammerstein::structure::bla::excited_lines(&rec).unwrap()[3];
    // remove line k from realization 0 by subtracting its projection, period by period
    let (mut c, mut sn) = (0.0, 0.0);
    for (i, v) in u0.iter().enumerate() {
        let ph = std::f64::consts::TAU * (k * i) as f64 / n as f64;
        c += v * ph.cos();
        sn += v * ph.sin();
    }
    for (i, v) in blocks[0].u.iter_mut().enumerate() {
        let ph = std::f64::consts::TAU * (k * (i % n)) as f64 / n as f64;
        *v -= 2.0 / n as f64 * (c * ph.cos() + sn * ph.sin());
    }
    let bad = Record::new(n, blocks).unwrap();
    let p = d.join("unexcited.csv");
    let mut bytes = Vec::new();
    bad.write_csv(&mut bytes).unwrap();
    std::fs::write(&p, bytes).unwrap();
    let (ok, _, err) = run(&["bla", p.to_str().unwrap()]);
    assert!(!ok && err.contains("unexcited line"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn diagnose_reports_the_structure_verdict() {
    let d = dir("diagnose");
    let design = d.join("design.csv");
    let (ok, _, err) = run(&[
        "design",
        "--samples",
        "512",
        "--levels",
        "0.25,1",
        "--realizations",
        "4",
        "--periods",
        "2",
        "--seed",
        "11",
        "--out",
        design.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    for (family, verdict, beyond) in [
        (Family::Feedback, "feedback", true),
        (Family::Hammerstein, "single-branch", false),
    ] {
        let rec = d.join(format!("{family:?}.csv"));
        measured(&design, family, 3, &rec);
        let (ok, out, err) = run(&["diagnose", rec.to_str().unwrap(), "--json"]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["structure"]["verdict"], verdict, "{family:?}: {out}");
        // the model is fitted on the highest level: its 4 blocks of 3 periods of 512 samples
        assert_eq!(v["structure"]["fitted_level"], 1);
        assert_eq!(v["structure"]["fitted_samples"], 4 * 3 * 512);
        let entry = v["unexplained"]
            .as_array()
            .unwrap()
            .iter()
            .find(|u| u["test"] == "structure-verdict")
            .cloned();
        assert_eq!(entry.is_some(), beyond, "{family:?}: {}", v["unexplained"]);
        // the feedback verdict is the feedback candidate's evidence: it is suggested, citing
        // the pole that moves; on the Hammerstein system it is not suggested
        let fb = v["suggestions"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["effect"] == "feedback-nonlinearity")
            .cloned();
        assert_eq!(fb.is_some(), beyond, "{family:?}: {}", v["suggestions"]);
        if let Some(s) = fb {
            let ev = s["evidence"].as_str().unwrap();
            assert!(
                ev.contains("the levels' best linear approximations: feedback: "),
                "{ev}"
            );
        }
        if let Some(u) = entry {
            let why = u["model_classes"][0].as_str().unwrap();
            assert!(
                why.starts_with("the structure verdict is feedback")
                    && why.contains("--feedback-nonlinearity"),
                "{why}"
            );
        }
        let (ok, out, err) = run(&["diagnose", rec.to_str().unwrap()]);
        assert!(ok, "{err}");
        assert!(
            out.contains(&format!("structure (BLAs of the 2 levels): {verdict}")),
            "{out}"
        );
        assert!(
            out.contains("fitted on the record format's level 1 of 2"),
            "{out}"
        );
    }
    // the format's columns without whole periods: diagnosed as a plain record, with a note
    let ragged = d.join("ragged.csv");
    let mut text = String::from("level,realization,period,u,y\n");
    let (mut y1, mut state) = (0.0f64, 1u64);
    for (per, n) in [(0, 300), (1, 299)] {
        for _ in 0..n {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            y1 = 0.8 * y1 + u;
            text.push_str(&format!("0,0,{per},{u},{y1}\n"));
        }
    }
    std::fs::write(&ragged, text).unwrap();
    let (ok, out, err) = run(&["diagnose", ragged.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    assert!(err.contains("diagnosed as a plain record"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v.get("structure").is_none(), "{out}");
    std::fs::remove_dir_all(&d).ok();
}

/// The Wiener–Hammerstein benchmark (SYSID 2009) holds one input level of filtered noise:
/// `structure` says movement is not testable, and that the record is nonlinear; `bla` points a
/// non-periodic record to `--by-rms`.
#[test]
fn wiener_hammerstein_2009_is_one_level() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/wiener_hammerstein_2009/excerpt.csv");
    let (ok, _, err) = run(&["structure", p.to_str().unwrap(), "--by-rms", "2"]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("one amplitude level") && err.contains("not testable"),
        "{err}"
    );
    assert!(err.contains("the record is nonlinear (RESET test"), "{err}");
    let (ok, _, err) = run(&["bla", p.to_str().unwrap()]);
    assert!(!ok && err.contains("--by-rms"), "{err}");
}
