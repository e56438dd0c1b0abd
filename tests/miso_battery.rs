//! Several-input battery (issue 12, item 2): random two-input records (`common/random_miso.rs`:
//! each input with its own random block of order 1–3, its own random UDN effects and input kind,
//! SNR 20–35 dB, N 2000–4000, an output offset). The second input has exactly one effect, hidden
//! from the model (that branch is fitted as a gain); the first input's effects are given.
//! `Diagnoser::diagnose_miso` must name the hidden effect first, on the second input; acting on
//! it (`MisoDiagnosis::apply`) must bring the validation MSE within 1.5× the noise variance.
//! Also measured: the fit with every true effect given.
//!
//! `cargo test` runs a fast slice. The battery:
//! `BATTERY_SEEDS=60 cargo test --release --test miso_battery battery -- --ignored --nocapture`
//! (`BATTERY_WRITE=docs/miso-battery.md` appends the table there). `BATTERY_OFFSET=40` runs
//! seeds 41–100 with `BATTERY_SEEDS=60` (development seeds: the documented 1–40 stay a held-out
//! check).

mod common;

use common::random_miso::{RandomMiso, io_data, random_miso};
use hammerstein::diagnosis::{Diagnoser, compare_miso};
use hammerstein::fit::Hammerstein;
use hammerstein::miso::MisoHammerstein;
use hammerstein::regressors::EffectSet;
use rayon::prelude::*;

#[derive(Debug, Clone)]
struct Outcome {
    seed: u64,
    effects: [String; 2],
    orders: [usize; 2],
    snr: f64,
    /// Validation MSE / noise with every true effect given.
    true_ratio: f64,
    /// Validation MSE / noise of the start (the second input's effect hidden).
    start_ratio: f64,
    /// Top suggestion as "input: effect".
    top: String,
    hidden: String,
    /// Validation MSE / noise after acting on the top suggestion.
    after_ratio: f64,
    error: Option<String>,
}

fn settings(r: &RandomMiso, second: EffectSet, seed: u64) -> MisoHammerstein<f64> {
    MisoHammerstein::new(vec![
        Hammerstein::udn(r.branches[0].effects).seed(seed),
        Hammerstein::udn(second).seed(seed),
    ])
}

fn run(seed: u64) -> Outcome {
    let r = random_miso(seed, (20.0, 35.0));
    let hidden = r.branches[1].effects.effects()[0];
    let mut out = Outcome {
        seed,
        effects: [r.branches[0].effects.label(), r.branches[1].effects.label()],
        orders: [r.branches[0].order, r.branches[1].order],
        snr: r.snr_db,
        true_ratio: f64::NAN,
        start_ratio: f64::NAN,
        top: "none".into(),
        hidden: format!("u2: {}", hidden.name()),
        after_ratio: f64::NAN,
        error: None,
    };
    let res = (|| -> hammerstein::Result<()> {
        let data = io_data(&r);
        let (train, valid) = data.split_validation(0.3)?;
        let full = settings(&r, r.branches[1].effects, seed).fit(&train)?;
        out.true_ratio = compare_miso(&full, &valid)?.metrics.mse / r.noise_var;
        let start = settings(&r, EffectSet::empty(), seed).fit(&train)?;
        out.start_ratio = compare_miso(&start, &valid)?.metrics.mse / r.noise_var;
        let d = Diagnoser::new().diagnose_miso(&start, &train, &valid)?;
        if let Some(s) = d.suggestions.first() {
            out.top = format!("{}: {}", s.input, s.suggestion.effect);
            let next = d.apply(s, &start, &train)?;
            out.after_ratio = compare_miso(&next, &valid)?.metrics.mse / r.noise_var;
        }
        Ok(())
    })();
    if let Err(e) = res {
        out.error = Some(e.to_string());
    }
    out
}

fn table(outs: &[Outcome]) -> String {
    let n = outs.len();
    let pct = |k: usize| format!("{k}/{n} ({:.0} %)", 100.0 * k as f64 / n.max(1) as f64);
    let named = outs.iter().filter(|o| o.top == o.hidden).count();
    let after = outs
        .iter()
        .filter(|o| o.top == o.hidden && o.after_ratio <= 1.5)
        .count();
    let truth = outs.iter().filter(|o| o.true_ratio <= 1.5).count();
    // as the single-input battery: the records whose start is clearly above the floor
    let above: Vec<&Outcome> = outs.iter().filter(|o| o.start_ratio > 1.2).collect();
    let named_above = above.iter().filter(|o| o.top == o.hidden).count();
    let after_above = above
        .iter()
        .filter(|o| o.top == o.hidden && o.after_ratio <= 1.5)
        .count();
    let errors = outs.iter().filter(|o| o.error.is_some()).count();
    let mut s = format!(
        "| records | hidden effect named first (input and effect) | named and, acted on, val. MSE ≤ 1.5× noise | true effects given: val. MSE ≤ 1.5× noise | errors |\n|---|---|---|---|---|\n| {n} | {} | {} | {} | {errors} |\n\nStart above 1.2× noise: {} records, named first {named_above}, named and at the floor after acting {after_above}.\n\n",
        pct(named),
        pct(after),
        pct(truth),
        above.len()
    );
    s.push_str("| seed | effects u1 | effects u2 (hidden) | orders | SNR dB | true effects: val/noise | start: val/noise | top suggestion | after: val/noise | error |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for o in outs.iter().filter(|o| {
        o.top != o.hidden || o.after_ratio > 1.5 || o.true_ratio > 1.5 || o.error.is_some()
    }) {
        s.push_str(&format!(
            "| {} | {} | {} | {:?} | {:.0} | {:.2} | {:.2} | {} | {:.2} | {} |\n",
            o.seed,
            o.effects[0],
            o.effects[1],
            o.orders,
            o.snr,
            o.true_ratio,
            o.start_ratio,
            o.top,
            o.after_ratio,
            o.error.clone().unwrap_or_default()
        ));
    }
    s
}

/// An unstable linear start (record 127: branch orders 3 and 1, dead-zone and preload beside a
/// dead-zone): the two-input subspace step gave a block of spectral radius 1.009 whose
/// per-input contributions reached 1e13 times the output's power and cancelled in the sum; the
/// backfit fitted each branch to the other's blown-up contribution and the model with the true
/// effects ended at 1.3e13 times the noise in training and 3.8e13 on validation, with no error.
/// Such a start is refused (`miso/linear_start.rs`) and the branches start from zero.
#[test]
fn an_unstable_linear_start_is_refused() {
    let r = random_miso(127, (20.0, 35.0));
    let data = io_data(&r);
    let (train, valid) = data.split_validation(0.3).unwrap();
    let model = settings(&r, r.branches[1].effects, 127)
        .fit(&train)
        .unwrap();
    let ratio = compare_miso(&model, &valid).unwrap().metrics.mse / r.noise_var;
    assert!(ratio <= 1.5, "validation MSE {ratio}× the noise");
}

/// Fast slice: no error, the hidden effect named on the right input and followed to the floor.
#[test]
fn miso_hidden_effect_slice() {
    let outs: Vec<Outcome> = (1..=3u64).into_par_iter().map(run).collect();
    println!("{}", table(&outs));
    assert!(outs.iter().all(|o| o.error.is_none()), "{outs:#?}");
    let good = outs
        .iter()
        .filter(|o| o.top == o.hidden && o.after_ratio <= 1.5)
        .count();
    assert!(
        good >= 2,
        "only {good}/3 named on u2 and followed to the floor: {outs:#?}"
    );
}

#[test]
#[ignore]
fn battery() {
    let seeds: u64 = common::env_count("BATTERY_SEEDS", 40);
    // development runs use other seeds: BATTERY_OFFSET=40 starts at seed 41
    let offset: u64 = common::env_count("BATTERY_OFFSET", 0);
    let (first, last) = (offset + 1, offset + seeds);
    let outs: Vec<Outcome> = (first..=last).into_par_iter().map(run).collect();
    let text = format!(
        "### {seeds} records (seeds {first}–{last})\n\n{}\n",
        table(&outs)
    );
    common::publish_battery(&text);
}

/// Prints one record's diagnosis in full (`MISO_SEED=11 cargo test --release --test
/// miso_battery inspect -- --ignored --nocapture`).
#[test]
#[ignore]
fn inspect() {
    let seed: u64 = common::env_count("MISO_SEED", 1);
    let r = random_miso(seed, (20.0, 35.0));
    let data = io_data(&r);
    let (train, valid) = data.split_validation(0.3).unwrap();
    let start = settings(&r, EffectSet::empty(), seed).fit(&train).unwrap();
    let d = Diagnoser::new()
        .diagnose_miso(&start, &train, &valid)
        .unwrap();
    for inp in &d.inputs {
        println!("== input {} adequate {}", inp.input, inp.diagnosis.adequate);
        for c in &inp.diagnosis.candidates {
            println!(
                "  {} applicable {} improvement {:?} criterion {:?} error {:?} null {:?}",
                c.effect,
                c.applicable,
                c.improvement,
                c.criterion_change,
                c.refit_error,
                c.refit.as_ref().and_then(|r| r.null_parameters.clone())
            );
            if let Some(m) = c.refit.as_ref().and_then(|r| r.model.as_ref()) {
                println!(
                    "    order {} parameters {:?}",
                    m.linear().order(),
                    m.parameters_with_errors()
                );
            }
        }
    }
    for s in &d.suggestions {
        println!(
            "suggestion {}: {} score {:.3}",
            s.input, s.suggestion.effect, s.suggestion.score
        );
    }
}
