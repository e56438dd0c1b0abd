//! A one-sided saturation (v = min(u, z1): the diode of the Wiener–Hammerstein 2009 benchmark)
//! fitted with the UDN's saturation, which has two finite limits: the upper limit is found, the
//! lower one ends where no training sample reaches it (at or below the input's minimum), so it
//! changes nothing on the training record — the behaviour docs/case-studies.md describes for
//! that benchmark. Random held levels, a random stable second-order block, SNR 30 dB, a few
//! seeds. The guided loop's final check drops that limit (`final_check.rs`): the model it ends
//! with has a one-sided saturation (`SaturationSides::Upper`), which also fits directly and
//! round-trips through the model file.

mod common;

use hammerstein::fit::HammersteinModel;
use hammerstein::regressors::{Effect, EffectSet, SaturationSides, Udn};
use hammerstein::subspace::Order;
use hammerstein::{Hammerstein, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Upper limit of the truth.
const Z1: f64 = 0.8;

fn record(seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let n = 2000;
    let mut u: Vec<f64> = Vec::with_capacity(n);
    while u.len() < n {
        let level: f64 = rng.random_range(-2.0..2.0);
        let hold = rng.random_range(5..30usize);
        u.extend(std::iter::repeat_n(level, hold));
    }
    u.truncate(n);
    let (r, th) = (rng.random_range(0.5..0.9), rng.random_range(0.1..0.8));
    let g = StateSpace::from_rows(
        &[&[2.0 * r * f64::cos(th), 1.0], &[-r * r, 0.0]],
        &[&[1.0], &[0.3]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let v: Vec<f64> = u.iter().map(|&x| x.min(Z1)).collect();
    let (y, _) = common::output(&g, &v, 30.0, seed);
    (u, y)
}

#[test]
fn a_one_sided_saturation_keeps_its_lower_limit_out_of_the_training_input() {
    for seed in 1..=4u64 {
        let (u, y) = record(seed);
        let data = IoData::siso(&u, &y).unwrap();
        let model = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation]))
            .order(Order::Fixed(2))
            .seed(seed)
            .fit(&data)
            .unwrap();
        let p: std::collections::HashMap<String, f64> = model.parameters().into_iter().collect();
        let (z1, z2) = (p["z1"], p["z2"]);
        let below = u.iter().filter(|&&x| x < z2).count();
        let min = u.iter().copied().fold(f64::INFINITY, f64::min);
        println!("seed {seed}: z1 {z1:.4}, z2 {z2:.4} (min u {min:.4}), {below} samples below z2");
        assert!(
            (z1 - Z1).abs() < 0.05,
            "seed {seed}: upper limit {z1} (truth {Z1})"
        );
        // the lower limit acts on no more than 1 % of the training samples
        assert!(
            below * 100 <= u.len(),
            "seed {seed}: the lower limit {z2} clips {below} training samples (min u {min})"
        );
    }
}

/// The guided loop (three steps) from a saturation model on the record (u, y), its last 30 %
/// held out for validation.
fn follow_saturation(u: &[f64], y: &[f64], seed: u64) -> hammerstein::diagnosis::Followed<f64> {
    let data = IoData::siso(u, y).unwrap();
    let (train, val) = data.split_validation(0.3).unwrap();
    let start = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation])).seed(seed);
    hammerstein::diagnosis::Diagnoser::new()
        .follow(&start, &train, &val, 3)
        .unwrap()
}

/// The final model of the guided loop on a truly one-sided saturation has no lower limit: the
/// final check drops it (a step "- saturation's lower limit", the note with both training MSEs),
/// on every seed.
#[test]
fn the_final_check_drops_the_limit_the_record_does_not_measure() {
    for seed in 1..=4u64 {
        let (u, y) = record(seed);
        let followed = follow_saturation(&u, &y, seed);
        println!("seed {seed}: final check {:?}", followed.final_check);
        let last = followed.model().unwrap();
        let p: std::collections::HashMap<String, f64> = last.parameters().into_iter().collect();
        assert!(
            p.contains_key("z1") && !p.contains_key("z2"),
            "seed {seed}: final parameters {p:?}; final check {:?}",
            followed.final_check
        );
        assert!(
            (p["z1"] - Z1).abs() < 0.05,
            "seed {seed}: upper limit {} (truth {Z1})",
            p["z1"]
        );
        assert!(last.nonlinearity().name().contains("-upper-only"));
        assert_eq!(
            followed.steps.last().unwrap().change,
            "- saturation's lower limit"
        );
        let said: Vec<&String> = followed
            .final_check
            .iter()
            .filter(|n| n.contains("does not measure it"))
            .collect();
        assert_eq!(said.len(), 1, "{:?}", followed.final_check);
        assert!(
            said[0].contains("z2")
                && said[0].contains("minimum")
                && said[0].contains("dropped")
                && said[0].contains("with the upper limit only"),
            "{}",
            said[0]
        );
    }
}

/// A saturation clipped on both sides keeps both limits through the guided loop (neither is
/// said unmeasured), on every seed.
#[test]
fn a_two_sided_saturation_keeps_both_limits() {
    for seed in 3..=5u64 {
        let (u, _) = record(seed);
        let g = StateSpace::from_rows(
            &[&[1.2, 1.0], &[-0.5, 0.0]],
            &[&[0.3], &[0.12]],
            &[&[1.0, 0.0]],
            &[&[0.0]],
        )
        .unwrap();
        let v: Vec<f64> = u.iter().map(|&x| x.clamp(-Z1, Z1)).collect();
        let (y, _) = common::output(&g, &v, 30.0, seed);
        let followed = follow_saturation(&u, &y, seed);
        assert!(
            !followed
                .final_check
                .iter()
                .any(|n| n.contains("does not measure it")),
            "seed {seed}: {:?}",
            followed.final_check
        );
        let p: std::collections::HashMap<String, f64> =
            followed.model().unwrap().parameters().into_iter().collect();
        assert!(
            (p["z1"] - Z1).abs() < 0.05 && (p["z2"] + Z1).abs() < 0.05,
            "seed {seed}: {p:?}"
        );
    }
}

/// The one-sided UDN fitted directly (f64 and f32) finds the upper limit and has no lower one;
/// its model file holds `"saturation_sides": "upper"`, no z2 and no non-finite number, and reads
/// back to the same parameters bit for bit and the same simulation.
#[test]
fn a_one_sided_fit_round_trips_through_the_model_file() {
    let upper = || {
        Udn::<f64>::new(EffectSet::of(&[Effect::Saturation]))
            .with_saturation_sides(SaturationSides::Upper)
            .unwrap()
    };
    for seed in 1..=3u64 {
        let (u, y) = record(seed);
        let data = IoData::siso(&u, &y).unwrap();
        let model = Hammerstein::<f64>::new(Box::new(upper()))
            .order(Order::Fixed(2))
            .seed(seed)
            .fit(&data)
            .unwrap();
        let names: Vec<String> = model.parameters().into_iter().map(|(k, _)| k).collect();
        assert_eq!(names, ["p", "z1"], "seed {seed}");
        let z1 = model.parameters()[1].1;
        assert!((z1 - Z1).abs() < 0.05, "seed {seed}: z1 = {z1}");
        let text = serde_json::to_string_pretty(&model).unwrap();
        assert!(text.contains("\"saturation_sides\": \"upper\""), "{text}");
        assert!(!text.contains("\"z2\"") && !text.contains("inf") && !text.contains("e308"));
        let back = HammersteinModel::<f64>::from_json(&text).unwrap();
        for ((k, a), (_, b)) in model.parameters().into_iter().zip(back.parameters()) {
            assert_eq!(a.to_bits(), b.to_bits(), "seed {seed}: {k}");
        }
        assert_eq!(back.nonlinearity().name(), "dn8-upper-only");
        assert_eq!(model.simulate(&u).unwrap(), back.simulate(&u).unwrap());
        assert_eq!(serde_json::to_string_pretty(&back).unwrap(), text);
        // f32: the same structure, the limit to the noise's precision
        let d32: IoData<f32> = data.cast();
        let one32 = Udn::<f32>::new(EffectSet::of(&[Effect::Saturation]))
            .with_saturation_sides(SaturationSides::Upper)
            .unwrap();
        let m32 = Hammerstein::<f32>::new(Box::new(one32))
            .order(Order::Fixed(2))
            .seed(seed)
            .fit(&d32)
            .unwrap();
        let p32 = m32.parameters();
        assert_eq!(p32.len(), 2, "seed {seed}: {p32:?}");
        assert!(
            (p32[1].1 - z1).abs() < 1e-3,
            "seed {seed}: f32 z1 {} vs f64 {z1}",
            p32[1].1
        );
    }
}

/// The command line on a one-sided saturation: `diagnose --follow --save` prints the final
/// model's absent limit as `z2 = -inf (none)` (no long number anywhere), saves it with
/// `"saturation_sides": "upper"` and no z2, and `compare` of the saved model reproduces the
/// validation MSE `diagnose --json` reports.
#[cfg(feature = "cli")]
#[test]
fn the_command_line_prints_saves_and_compares_a_one_sided_model() {
    let (u, y) = record(2);
    let dir = common::temp_dir("one-sided");
    let (n_train, n) = (1400, u.len());
    let (train, val) = common::write_train_val(
        &dir,
        (&u[..n_train], &y[..n_train]),
        (&u[n_train..n], &y[n_train..n]),
    );
    let model = dir.join("m.json");
    let (t, v, m) = (
        train.to_str().unwrap(),
        val.to_str().unwrap(),
        model.to_str().unwrap(),
    );
    let text = common::run_cli(&["diagnose", t, "--validation-file", v, "--follow"]);
    assert!(text.contains("dn8-upper-only"), "{text}");
    assert!(text.contains("z2 = -inf (none)"), "{text}");
    let longest = text
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest < 20, "a {longest}-digit number in {text}");
    let json: serde_json::Value = serde_json::from_str(&common::run_cli(&[
        "diagnose",
        t,
        "--validation-file",
        v,
        "--follow",
        "--json",
        "--save",
        m,
    ]))
    .unwrap();
    let file = std::fs::read_to_string(&model).unwrap();
    assert!(file.contains("\"saturation_sides\": \"upper\""), "{file}");
    assert!(!file.contains("\"z2\""), "{file}");
    let cmp: serde_json::Value =
        serde_json::from_str(&common::run_cli(&["compare", m, v, "--json"])).unwrap();
    let (a, b) = (
        json["validation"]["mse"].as_f64().unwrap(),
        cmp["mse"].as_f64().unwrap(),
    );
    assert!((a - b).abs() <= 1e-9 * a, "diagnose {a} vs compare {b}");
    std::fs::remove_dir_all(&dir).ok();
}
