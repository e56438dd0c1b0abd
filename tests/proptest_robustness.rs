//! Property-based robustness (issue 13): arbitrary input to the CSV reader, the model-file
//! loader, the record constructors, the Hammerstein fit and the subspace entry points returns
//! `Ok` or a typed `Err`, never a panic. Case counts are modest so `cargo test` stays fast; set
//! PROPTEST_CASES to run more.

use faer::Mat;
use hammerstein::data::CsvTable;
use hammerstein::fit::HammersteinModel;
use hammerstein::regressors::EffectSet;
use hammerstein::subspace::{
    Compression, MethodKind, Order, SubspaceOptions, ac_from_observability, correlation,
    estimate_bd_x0, identify, max_order, select_order,
};
use hammerstein::{Faer, Hammerstein, IoData, IoView};
use proptest::prelude::*;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases: std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|c| c.parse().ok())
            .unwrap_or(cases),
        // shrinking reruns fits: keep a failure report quick
        max_shrink_iters: 200,
        ..ProptestConfig::default()
    }
}

/// Numbers as hostile input has them: ordinary, tiny, huge, zero, non-finite.
fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -10.0..10.0f64,
        1 => Just(0.0),
        1 => prop::num::f64::ANY,
        1 => prop_oneof![
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(1e308),
            Just(-1e308),
            Just(1e39),
            Just(5e-324),
        ],
    ]
}

/// Finite numbers, some extreme.
fn finite_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => -10.0..10.0f64,
        1 => Just(0.0),
        1 => prop_oneof![Just(1e150), Just(-1e200), Just(1e-300), Just(3.0e38)],
    ]
}

/// `len` ordinary numbers with, in a third of the cases, one or two extreme finite ones: most
/// records pass validation and reach the algorithms, some probe overflow inside them.
fn mostly_ordinary(len: usize) -> impl Strategy<Value = Vec<f64>> {
    (
        prop::collection::vec(-10.0..10.0f64, len),
        prop_oneof![
            2 => Just(Vec::new()),
            1 => prop::collection::vec((0..len.max(1), finite_f64()), 1..3),
        ],
    )
        .prop_map(|(mut v, extreme)| {
            for (i, x) in extreme {
                if i < v.len() {
                    v[i] = x;
                }
            }
            v
        })
}

/// One CSV cell: numbers in several spellings and some junk.
fn cell() -> impl Strategy<Value = String> {
    prop_oneof![
        5 => (-1e3..1e3f64).prop_map(|v| v.to_string()),
        1 => wild_f64().prop_map(|v| v.to_string()),
        1 => prop_oneof![
            Just("".to_string()),
            Just("nan".to_string()),
            Just("inf".to_string()),
            Just("1e400".to_string()),
            Just("-0".to_string()),
            Just(" 1 ".to_string()),
            Just("\"2\"".to_string()),
            Just("#".to_string()),
            Just("u".to_string()),
        ],
        1 => "[ -~]{0,6}",
    ]
}

/// CSV-shaped text: a header from a few names, rows of cells, ragged at times.
fn csv_text() -> impl Strategy<Value = String> {
    let names = prop::collection::vec(
        prop_oneof![
            Just("t"),
            Just("u"),
            Just("y"),
            Just("u2"),
            Just(""),
            Just("time")
        ],
        0..5,
    );
    (
        names,
        prop::collection::vec(prop::collection::vec(cell(), 0..6), 0..30),
    )
        .prop_map(|(names, rows)| {
            let mut s = names.join(",");
            s.push('\n');
            for r in rows {
                s.push_str(&r.join(","));
                s.push('\n');
            }
            s
        })
}

/// CSV text of a rectangular table: a header of distinct-ish names and rows of as many cells,
/// mostly numbers (so that most tables reach the record's validation, some its errors).
fn rectangular_csv() -> impl Strategy<Value = String> {
    let names = prop::collection::vec(
        prop_oneof![Just("t"), Just("u"), Just("y"), Just("u2"), Just("time")],
        1..5,
    );
    (names, 0..12usize)
        .prop_flat_map(|(names, rows)| {
            let width = names.len();
            let number = prop_oneof![
                20 => (-1e3..1e3f64).prop_map(|v| v.to_string()),
                1 => cell(),
            ];
            (
                Just(names),
                prop::collection::vec(prop::collection::vec(number, width), rows),
            )
        })
        .prop_map(|(names, rows)| {
            let mut s = names.join(",");
            s.push('\n');
            for r in rows {
                s.push_str(&r.join(","));
                s.push('\n');
            }
            s
        })
}

/// The streamed reader ([`IoData::parse_csv`]) and the table ([`CsvTable::parse`] then
/// `io_data`) agree: the same record or the same message.
fn streamed_agrees<T: hammerstein::Real>(text: &str) -> Result<(), TestCaseError> {
    let choices: [(&[&str], &[&str]); 4] = [
        (&["u"], &["y"]),
        (&["u", "u2"], &["y", "t"]),
        (&["u"], &["u"]),
        (&[], &["y"]),
    ];
    for (ins, outs) in choices {
        let table =
            CsvTable::parse(text.as_bytes(), "fuzz.csv").and_then(|t| t.io_data::<T>(ins, outs));
        let streamed = IoData::<T>::parse_csv(text.as_bytes(), "fuzz.csv", ins, outs);
        match (table, streamed) {
            (Ok(a), Ok(b)) => {
                prop_assert!(a.u() == b.u() && a.y() == b.y());
                prop_assert_eq!(a.sample_time(), b.sample_time());
                prop_assert_eq!(a.input_names(), b.input_names());
                prop_assert_eq!(a.output_names(), b.output_names());
            }
            (Err(a), Err(b)) => prop_assert_eq!(a.to_string(), b.to_string()),
            (a, b) => prop_assert!(false, "table {:?}, streamed {:?}", a.err(), b.err()),
        }
    }
    Ok(())
}

/// Exercises everything a caller does with a parsed table.
fn use_table(t: &CsvTable) {
    let _ = t.data_columns();
    let _ = t.sample_time();
    let _ = t.column("u");
    let _ = t.io_data::<f64>(&["u"], &["y"]);
    let _ = t.io_data::<f32>(&["u"], &["y"]);
    let _ = t.io_data::<f64>(&["u", "u2"], &["y", "t"]);
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn csv_reader_never_panics_on_bytes(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        if let Ok(t) = CsvTable::parse(&bytes, "fuzz.csv") {
            use_table(&t);
        }
    }

    #[test]
    fn csv_reader_never_panics_on_csv_like_text(text in csv_text()) {
        if let Ok(t) = CsvTable::parse(text.as_bytes(), "fuzz.csv") {
            // a parsed table is rectangular with its header
            prop_assert_eq!(t.columns.len(), t.names.len());
            use_table(&t);
        }
    }

    #[test]
    fn streamed_csv_reader_agrees_with_the_table(text in csv_text()) {
        streamed_agrees::<f64>(&text)?;
        streamed_agrees::<f32>(&text)?;
    }

    #[test]
    fn streamed_csv_reader_agrees_on_rectangular_tables(text in rectangular_csv()) {
        streamed_agrees::<f64>(&text)?;
        streamed_agrees::<f32>(&text)?;
    }

    #[test]
    fn model_loader_never_panics_on_text(text in "\\PC{0,300}") {
        let _ = HammersteinModel::from_json(&text);
    }
}

/// A valid model file as JSON, fitted once.
fn valid_model_json() -> &'static serde_json::Value {
    static JSON: std::sync::OnceLock<serde_json::Value> = std::sync::OnceLock::new();
    JSON.get_or_init(|| {
        let n = 400;
        let u: Vec<f64> = (0..n).map(|k| ((k * 7919) % 13) as f64 - 6.0).collect();
        let mut y = vec![0.0; n];
        for k in 1..n {
            let v = 2.0 * u[k - 1] + 0.3 * u[k - 1].abs();
            y[k] = 0.6 * y[k - 1] + v + 0.01 * (((k * 31) % 7) as f64 - 3.0);
        }
        let d = IoData::siso(&u, &y).unwrap();
        let m = Hammerstein::<f64>::udn(EffectSet::all())
            .order(Order::Fixed(2))
            .fit(&d)
            .unwrap();
        serde_json::to_value(m.to_file()).unwrap()
    })
}

/// A JSON value to put somewhere in a model file.
fn json_leaf() -> impl Strategy<Value = serde_json::Value> {
    use serde_json::{Value, json};
    prop_oneof![
        wild_f64().prop_map(|v| json!(v)),
        any::<i64>().prop_map(|v| json!(v)),
        Just(Value::Null),
        Just(json!([])),
        Just(json!({})),
        Just(json!("udn")),
        Just(json!(true)),
        prop::collection::vec(finite_f64(), 0..4).prop_map(|v| json!(v)),
        prop::collection::vec(prop::collection::vec(finite_f64(), 0..3), 0..3)
            .prop_map(|v| json!(v)),
    ]
}

/// Replaces the `pick`-th node (in a depth-first walk) of `v` with `leaf`, or removes it from
/// its object when `remove`.
fn mutate(
    v: &mut serde_json::Value,
    pick: &mut usize,
    leaf: &serde_json::Value,
    remove: bool,
) -> bool {
    use serde_json::Value;
    match v {
        Value::Object(map) => {
            let keys: Vec<String> = map.keys().cloned().collect();
            for k in keys {
                if *pick == 0 {
                    if remove {
                        map.remove(&k);
                    } else {
                        map.insert(k, leaf.clone());
                    }
                    return true;
                }
                *pick -= 1;
                if let Some(child) = map.get_mut(&k)
                    && mutate(child, pick, leaf, remove)
                {
                    return true;
                }
            }
            false
        }
        Value::Array(items) => {
            for item in items.iter_mut() {
                if *pick == 0 {
                    *item = leaf.clone();
                    return true;
                }
                *pick -= 1;
                if mutate(item, pick, leaf, remove) {
                    return true;
                }
            }
            false
        }
        _ => false,
    }
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn model_loader_never_panics_on_mutated_files(
        edits in prop::collection::vec((0usize..400, json_leaf(), any::<bool>()), 1..4),
        u in prop::collection::vec(wild_f64(), 0..40),
    ) {
        let mut v = valid_model_json().clone();
        for (pick, leaf, remove) in &edits {
            let mut p = *pick;
            mutate(&mut v, &mut p, leaf, *remove);
        }
        if let Ok(m) = HammersteinModel::from_json(&v.to_string()) {
            // a loaded model is usable: simulating returns Ok or Err
            let _ = m.simulate(&u);
            let _ = m.simulate_finite(&u);
            let _ = m.transfer_function();
            let _ = m.parameters();
            if let Ok(d) = IoData::siso(&u, &u.iter().map(|x| x * 0.5 + 1.0).collect::<Vec<_>>()) {
                let _ = hammerstein::diagnosis::compare(&m, &d);
            }
        }
    }

    #[test]
    fn record_constructors_never_panic(
        n in 0usize..12,
        m in 0usize..3,
        l in 0usize..3,
        vals in prop::collection::vec(wild_f64(), 72),
        fraction in wild_f64(),
        ts in wild_f64(),
        horizon in prop_oneof![0usize..10, Just(usize::MAX), Just(1usize << 62)],
    ) {
        let u = Mat::from_fn(n, m, |i, j| vals[(i * 3 + j) % 72]);
        let y = Mat::from_fn(n, l, |i, j| vals[(36 + i * 3 + j) % 72]);
        let _ = IoView::new(u.as_ref(), y.as_ref());
        if let Ok(d) = IoData::new(u, y) {
            let _ = d.check_horizon(horizon);
            let _ = d.split_validation(fraction);
            let _ = d.clone().with_sample_time(ts);
            let _ = d.detrend_mean();
            let _ = d.slice(n / 3, n);
            let _ = d.cast::<f32>();
        }
        let uu: Vec<f64> = vals[..n].to_vec();
        let yy: Vec<f64> = vals[36..36 + n].to_vec();
        let _ = IoData::siso(&uu, &yy);
        let _ = IoData::<f32>::siso(
            &uu.iter().map(|x| *x as f32).collect::<Vec<_>>(),
            &yy.iter().map(|x| *x as f32).collect::<Vec<_>>(),
        );
    }

    #[test]
    fn order_selection_never_panics(
        sv in prop::collection::vec(wild_f64(), 0..8),
        rule in prop_oneof![
            Just(Order::Auto),
            (0usize..10).prop_map(Order::Fixed),
            wild_f64().prop_map(Order::Threshold),
        ],
        max in prop_oneof![0usize..10, Just(usize::MAX)],
    ) {
        if let Ok(n) = select_order(&sv, &rule, max) {
            prop_assert!(n >= 1);
        }
    }
}

proptest! {
    #![proptest_config(config(64))]

    #[test]
    fn subspace_identify_never_panics(
        n in 0usize..60,
        m in 1usize..3,
        l in 1usize..3,
        vals in mostly_ordinary(120),
        poison in prop::option::of((0usize..60, wild_f64())),
        horizon in prop_oneof![0usize..7, Just(usize::MAX / 2 + 2)],
        kind in prop_oneof![
            Just(MethodKind::Moesp),
            Just(MethodKind::N4sid),
            Just(MethodKind::N4sidUnweighted)
        ],
        compression in prop_oneof![
            Just(Compression::Cholesky),
            Just(Compression::Qr),
            Just(Compression::Semidefinite)
        ],
        order in prop_oneof![Just(Order::Auto), (0usize..6).prop_map(Order::Fixed)],
        with_d in any::<bool>(),
        estimate_x0 in any::<bool>(),
    ) {
        let mut u = Mat::from_fn(n, m, |i, j| vals[(i * 2 + j) % 120]);
        let y = Mat::from_fn(n, l, |i, j| vals[(60 + i * 2 + j * 7) % 120]);
        if let Some((k, v)) = poison
            && k < n
        {
            u[(k, 0)] = v;
        }
        let view = IoView::new(u.as_ref(), y.as_ref()).unwrap();
        let opts = SubspaceOptions {
            order,
            with_d,
            estimate_x0,
            ..Default::default()
        };
        let la = Faer::default();
        // through the checked constructor and through the raw structs
        if let Ok(method) = kind.build_with::<f64>(horizon, compression) {
            let _ = identify(method.as_ref(), &la, &[view], &opts);
        }
        let _ = identify(&hammerstein::Moesp::new(horizon), &la, &[view], &opts);
        let _ = identify(&hammerstein::subspace::N4sid::new(horizon), &la, &[view], &opts);
    }

    #[test]
    fn realization_and_correlation_never_panic(
        rows in 0usize..12,
        cols in 0usize..6,
        vals in prop::collection::vec(wild_f64(), 72),
        horizon in prop_oneof![0usize..6, Just(usize::MAX), Just(1usize << 40)],
        n_outputs in prop_oneof![0usize..3, Just(usize::MAX)],
        n in prop_oneof![0usize..5, Just(usize::MAX)],
        samples in 0usize..40,
    ) {
        let u_obs = Mat::from_fn(rows, cols, |i, j| vals[(i * 6 + j) % 72]);
        let _ = ac_from_observability(&Faer::default(), u_obs.as_ref(), horizon, n_outputs, n);
        let _ = max_order(horizon, n_outputs);
        let u = Mat::from_fn(samples, 1, |i, _| vals[i % 72]);
        let y = Mat::from_fn(samples, 1, |i, _| vals[(i + 7) % 72]);
        let view = IoView::new(u.as_ref(), y.as_ref()).unwrap();
        let _ = correlation(&[view], horizon);
    }

    #[test]
    fn bd_x0_never_panics(
        n in 0usize..4,
        l in 0usize..3,
        rows in 0usize..30,
        m in 0usize..3,
        vals in prop::collection::vec(wild_f64(), 64),
        with_d in any::<bool>(),
        estimate_x0 in any::<bool>(),
    ) {
        let a = Mat::from_fn(n, n, |i, j| vals[(i * 4 + j) % 64] * 0.1);
        let c = Mat::from_fn(l, n, |i, j| vals[(20 + i * 4 + j) % 64]);
        let u = Mat::from_fn(rows, m, |i, j| vals[(30 + i + j) % 64]);
        let y = Mat::from_fn(rows, l.max(1), |i, j| vals[(40 + i + 3 * j) % 64]);
        let view = IoView::new(u.as_ref(), y.as_ref()).unwrap();
        let _ = estimate_bd_x0(&Faer::default(), a.as_ref(), c.as_ref(), &[view], with_d, estimate_x0);
    }
}

proptest! {
    #![proptest_config(config(48))]

    #[test]
    fn hammerstein_fit_never_panics(
        n in 0usize..150,
        uy in mostly_ordinary(300),
        nl in 0usize..3,
        horizon in prop_oneof![8 => 2usize..7, 1 => 0usize..2, 1 => Just(usize::MAX)],
        order in prop_oneof![Just(Order::Auto), (0usize..5).prop_map(Order::Fixed)],
        delay in prop_oneof![8 => Just(0usize), 2 => 1usize..4, 1 => Just(usize::MAX)],
        kind in prop_oneof![Just(MethodKind::Moesp), Just(MethodKind::N4sid)],
        max_iter in prop_oneof![8 => 1usize..6, 1 => Just(0usize)],
        tolerance in prop_oneof![8 => 1e-8..1e-2f64, 1 => wild_f64()],
        offset in any::<bool>(),
        lag in 1usize..3,
    ) {
        // an output that depends on the input often enough for fits to succeed
        let u = &uy[..n];
        let y: Vec<f64> = (0..n)
            .map(|k| if k >= lag { 0.8 * u[k - lag] + 0.3 * uy[150 + k] } else { uy[150 + k] })
            .collect();
        let Ok(data) = IoData::siso(u, &y) else { return Ok(()) };
        let base = match nl {
            0 => Hammerstein::<f64>::linear(),
            1 => Hammerstein::sh(),
            _ => Hammerstein::udn(EffectSet::all()),
        };
        // a delay near usize::MAX overflows the sample count inside the fit (src/fit/
        // driver.rs, not hardened here): it is kept to realistic values
        let delay = if delay == usize::MAX { n } else { delay };
        let settings = base
            .horizon(horizon)
            .order(order)
            .delay(delay)
            .method(kind)
            .max_iter(max_iter)
            .tolerance(tolerance)
            .offset(offset);
        if let Ok(model) = settings.fit(&data) {
            let _ = hammerstein::diagnosis::compare(&model, &data);
            let _ = model.simulate(u);
        }
    }
}
