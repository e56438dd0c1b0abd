//! The report writer: files exist, the page inlines every plot, the SVGs are well-formed XML, and
//! bad input is an error, not a panic.

use hammerstein::report::*;
use std::path::PathBuf;

/// A small synthetic report: a backlash-like system with a first-order lag, seeded noise.
fn synthetic() -> ReportInput {
    let n = 600;
    let mut u = Vec::with_capacity(n);
    let mut state = 0.3f64;
    for k in 0..n {
        // deterministic pseudo-random smooth input
        state = (state * 3.9 * (1.0 - state)).clamp(0.01, 0.99);
        u.push((k as f64 * 0.05).sin() * 2.0 + 0.3 * (state - 0.5));
    }
    let mut v = vec![0.0; n];
    let mut s = 1.0;
    for k in 0..n {
        if k > 0 && u[k] > u[k - 1] {
            s = 1.0;
        } else if k > 0 && u[k] < u[k - 1] {
            s = -1.0;
        }
        v[k] = (2.0 * (u[k] - 0.4 * s)).clamp(-2.5, 3.0);
    }
    let mut y = vec![0.0; n];
    let mut y_lin = vec![0.0; n];
    for k in 1..n {
        y[k] = 0.8 * y[k - 1] + 0.2 * v[k - 1];
        y_lin[k] = 0.8 * y_lin[k - 1] + 0.2 * 1.7 * u[k - 1];
    }
    let noise: Vec<f64> = (0..n)
        .map(|k| 0.02 * ((k * 7919 % 101) as f64 / 50.0 - 1.0))
        .collect();
    let y: Vec<f64> = y.iter().zip(&noise).map(|(a, b)| a + b).collect();
    let split = 400;
    let train = Record::new(
        u[..split].to_vec(),
        y[..split].to_vec(),
        y_lin[..split].to_vec(),
    );
    let val = Record::new(
        u[split..].to_vec(),
        y[split..].to_vec(),
        y_lin[split..].to_vec(),
    );
    let grid: Vec<f64> = (0..101).map(|i| -2.5 + 5.0 * i as f64 / 100.0).collect();
    let rise: Vec<f64> = grid
        .iter()
        .map(|x| (2.0 * (x - 0.4)).clamp(-2.5, 3.0))
        .collect();
    let fall: Vec<f64> = grid
        .iter()
        .map(|x| (2.0 * (x + 0.4)).clamp(-2.5, 3.0))
        .collect();
    let dir: Vec<f64> = (0..split)
        .map(|k| if k > 0 && u[k] < u[k - 1] { -1.0 } else { 1.0 })
        .collect();
    ReportInput {
        title: "Synthetic <report> & test".into(),
        dataset: "synthetic backlash".into(),
        units: Units {
            input: "V".into(),
            output: "mm".into(),
            sample_time: Some(0.01),
        },
        train,
        validation: Some(val),
        other_inputs: Vec::new(),
        nonlinearity: Some(NonlinearityCurve {
            name: "udn: hysteresis, saturation".into(),
            u_grid: grid,
            v_rising: rise,
            v_falling: fall,
            data_u: u[..split].to_vec(),
            data_v: v[..split].to_vec(),
            data_direction: dir,
            data_note: "true v(k)".into(),
        }),
        output_map: None,
        feedback: None,
        autocorrelation: Some(Correlation {
            lags: (1..=20).collect(),
            values: (1..=20).map(|l| 0.9f64.powi(l)).collect(),
            bound: 0.12,
            level: 0.99,
        }),
        cross_correlation: Some(Correlation {
            lags: (-20..=20).collect(),
            values: (-20..=20)
                .map(|l: i64| if l > 0 { 0.3 / l as f64 } else { 0.01 })
                .collect(),
            bound: 0.12,
            level: 0.99,
        }),
        order: Some(OrderChoice {
            singular_values: vec![10.0, 3.0, 0.05, 0.04, 0.03, 0.02],
            chosen: 2,
            criterion: vec![
                (1, false, -1200.0),
                (2, false, -2400.0),
                (3, false, -2390.0),
                (2, true, -2393.0),
            ],
        }),
        steps: vec![
            Step {
                label: "linear".into(),
                validation_mse: 0.2,
                fit_percent: 40.0,
            },
            Step {
                label: "+ hysteresis".into(),
                validation_mse: 0.05,
                fit_percent: 80.0,
            },
            Step {
                label: "+ saturation".into(),
                validation_mse: 0.001,
                fit_percent: 95.0,
            },
        ],
        noise_floor: Some(0.0004),
        diagnosis_summary: "most likely missing: hysteresis".into(),
        diagnosis: vec![DiagnosisRow {
            effect: "hysteresis".into(),
            score: 0.7,
            evidence: "rising − falling = 0.8 V".into(),
            estimate: "a = 0.4".into(),
            validation_mse_after: 0.05,
        }],
        tests: vec![TestRow {
            name: "whiteness".into(),
            description: "Ljung–Box".into(),
            p_adjusted: 1e-9,
            significant: true,
        }],
        parameters: vec![Parameter {
            name: "p".into(),
            value: 2.0,
            note: "gain".into(),
        }],
        notes: vec!["Offsets removed.".into()],
        referred_residual: None,
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hammerstein-report-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Minimal XML well-formedness check: tags balance, attributes quoted, no stray '<' or '&'.
fn check_xml(s: &str) -> Result<(), String> {
    let mut stack: Vec<String> = Vec::new();
    let b = s.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'<' => {
                let end = s[i..].find('>').ok_or("unclosed tag")? + i;
                let tag = &s[i + 1..end];
                if tag.starts_with('?') || tag.starts_with('!') {
                } else if let Some(name) = tag.strip_prefix('/') {
                    let open = stack
                        .pop()
                        .ok_or(format!("closing {name} without opening"))?;
                    if open != name.trim() {
                        return Err(format!("<{open}> closed by </{name}>"));
                    }
                } else {
                    if tag.contains('<') {
                        return Err(format!("'<' inside tag {tag}"));
                    }
                    let name = tag
                        .split_whitespace()
                        .next()
                        .ok_or("empty tag")?
                        .trim_end_matches('/');
                    if !tag.matches('"').count().is_multiple_of(2) {
                        return Err(format!("unbalanced quotes in <{tag}>"));
                    }
                    if !tag.ends_with('/') {
                        stack.push(name.to_string());
                    }
                }
                i = end + 1;
            }
            b'&' => {
                let end = s[i..].find(';').ok_or("bare '&'")? + i;
                let ent = &s[i + 1..end];
                if !(ent.starts_with('#') || ["amp", "lt", "gt", "quot", "apos"].contains(&ent)) {
                    return Err(format!("unknown entity &{ent};"));
                }
                i = end + 1;
            }
            _ => i += 1,
        }
    }
    if stack.is_empty() {
        Ok(())
    } else {
        Err(format!("unclosed elements {stack:?}"))
    }
}

#[test]
fn writes_every_plot_and_one_self_contained_page() {
    let dir = tmp("full");
    let index = write_report(&dir, &synthetic()).unwrap();
    assert_eq!(index, dir.join("index.html"));
    let html = std::fs::read_to_string(&index).unwrap();
    for id in [
        "output",
        "residual-time",
        "residual-direction",
        "nonlinearity",
        "correlation",
        "order",
        "order-selection",
        "steps",
    ] {
        let svg_path = dir.join(format!("{id}.svg"));
        let svg = std::fs::read_to_string(&svg_path).unwrap_or_else(|e| panic!("{id}.svg: {e}"));
        check_xml(&svg).unwrap_or_else(|e| panic!("{id}.svg is not well-formed: {e}"));
        assert!(svg.contains("<svg") && svg.contains("</svg>"));
        assert!(
            html.contains(&format!("<section id=\"{id}\">")),
            "page lacks {id}"
        );
    }
    assert_eq!(html.matches("<svg").count(), 8, "every plot inlined once");
    // self-contained: no external resources
    for bad in [
        "src=\"http",
        "href=\"http",
        "<link",
        "<script",
        "@import",
        "url(",
    ] {
        assert!(!html.contains(bad), "external resource: {bad}");
    }
    // title escaped
    assert!(html.contains("Synthetic &lt;report&gt; &amp; test"));
    assert!(
        html.contains("if the two colours separate")
            || html.contains("If the two colours separate")
    );
}

#[test]
fn optional_parts_are_left_out() {
    let mut input = synthetic();
    input.validation = None;
    input.nonlinearity = None;
    input.order = None;
    input.steps.clear();
    input.noise_floor = None;
    let dir = tmp("minimal");
    let index = write_report(&dir, &input).unwrap();
    let html = std::fs::read_to_string(index).unwrap();
    assert!(!html.contains("id=\"nonlinearity\""));
    assert!(!html.contains("id=\"order\""));
    assert!(!dir.join("steps.svg").exists());
    assert!(dir.join("output.svg").exists());
}

#[test]
fn nan_in_input_is_an_error_not_a_panic() {
    let mut input = synthetic();
    input.train.y[17] = f64::NAN;
    let err = write_report(&tmp("nan"), &input).unwrap_err();
    assert!(
        matches!(err, hammerstein::Error::NonFinite { index: 17, .. }),
        "{err}"
    );

    let mut input = synthetic();
    if let Some(nl) = input.nonlinearity.as_mut() {
        nl.v_falling[3] = f64::INFINITY;
    }
    assert!(matches!(
        write_report(&tmp("inf"), &input),
        Err(hammerstein::Error::NonFinite { .. })
    ));

    let mut input = synthetic();
    input.steps[1].validation_mse = f64::NAN;
    assert!(write_report(&tmp("nanstep"), &input).is_err());

    let mut input = synthetic();
    input.train.y_hat.pop();
    assert!(matches!(
        write_report(&tmp("len"), &input),
        Err(hammerstein::Error::LengthMismatch { .. })
    ));

    let mut input = synthetic();
    input.order.as_mut().unwrap().chosen = 99;
    assert!(write_report(&tmp("order"), &input).is_err());
}

#[test]
fn constant_signals_do_not_break_the_axes() {
    let mut input = synthetic();
    let n = input.train.len();
    input.train.y = vec![1.0; n];
    input.train.y_hat = vec![1.0; n];
    input
        .autocorrelation
        .as_mut()
        .unwrap()
        .values
        .iter_mut()
        .for_each(|v| *v = 0.0);
    let dir = tmp("constant");
    write_report(&dir, &input).unwrap();
    let svg = std::fs::read_to_string(dir.join("residual-direction.svg")).unwrap();
    check_xml(&svg).unwrap();
}

#[test]
#[ignore = "writes the example report for a visual check: cargo test --test report_writer -- --ignored"]
fn write_example_for_inspection() {
    let dir = std::env::var("REPORT_DIR").unwrap_or_else(|_| "/tmp/report-example".into());
    println!(
        "{}",
        write_report(std::path::Path::new(&dir), &synthetic())
            .unwrap()
            .display()
    );
}
