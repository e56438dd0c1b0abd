//! Randomised diagnosis battery (issue "Honest diagnosis"): random linear blocks of order 1–4, a
//! random subset of the UDN's effects with random parameters, four input kinds, SNR 15–35 dB,
//! N 1000–5000, output offsets (`tests/common/random_system.rs`). On three records in four one of
//! the present effects is hidden from the model (fitted with the default settings: order
//! selection, refinement); on the others (and where the record has no effect) nothing is hidden.
//! `Diagnoser::follow` then runs from that model.
//!
//! Measured: the hidden effect named first; complete models adequate with no suggestion; after
//! following, the validation MSE within 1.5× the noise variance; failures (errors).
//! Targets (issue): ≥ 90 %, ≥ 95 %, ≥ 90 %, none.
//!
//! `cargo test` runs a fast slice. The battery:
//! `BATTERY_SEEDS=100 cargo test --release --test diagnosis_random_battery battery -- --ignored --nocapture`
//! (`BATTERY_WRITE=docs/diagnosis-battery.md` appends the table there); `BATTERY_OFFSET=200`
//! runs seeds 201–(200 + BATTERY_SEEDS) instead, seeds no change was measured on.

mod common;

use common::random_system::{Ranges, random_record};
use hammerstein::IoData;
use hammerstein::diagnosis::{Diagnoser, FollowStop, compare};
use hammerstein::fit::Hammerstein;
use hammerstein::regressors::{Effect, EffectSet};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rayon::prelude::*;

#[derive(Debug, Clone)]
struct Outcome {
    seed: u64,
    order: usize,
    effects: String,
    hidden: Option<Effect>,
    excitation: &'static str,
    snr: f64,
    /// Validation MSE / noise of the starting model.
    start_ratio: f64,
    top: String,
    adequate: bool,
    /// Validation MSE / noise of the followed model.
    final_ratio: f64,
    /// Training MSE / noise of the followed model (initial state estimated, as on validation):
    /// near 1 where the validation ratio is high, the training part did not show the misfit.
    final_train_ratio: f64,
    /// The followed model's diagnosis says it does not carry over to the validation part
    /// (`Diagnosis::generalisation`, notable).
    told: bool,
    steps: Vec<String>,
    stop: String,
    error: Option<String>,
}

impl Outcome {
    fn correct(&self) -> bool {
        match self.hidden {
            Some(h) => self.top == h.name(),
            None => self.adequate && self.top == "none",
        }
    }
}

fn run(seed: u64) -> Outcome {
    let ranges = Ranges {
        snr_db: (15.0, 35.0),
        ..Ranges::default()
    };
    let rec = random_record(seed, &ranges);
    let present = rec.effects.effects();
    let mut rng = StdRng::seed_from_u64(seed ^ 0xd1a9);
    let hidden = if present.is_empty() || seed.is_multiple_of(4) {
        None
    } else {
        Some(present[rng.random_range(0..present.len())])
    };
    let given: Vec<Effect> = present
        .iter()
        .copied()
        .filter(|e| Some(*e) != hidden)
        .collect();
    let mut out = Outcome {
        seed,
        order: rec.order,
        effects: rec.effects.label(),
        hidden,
        excitation: rec.excitation.name(),
        snr: rec.snr_db,
        start_ratio: f64::NAN,
        top: String::new(),
        adequate: false,
        final_ratio: f64::NAN,
        final_train_ratio: f64::NAN,
        told: false,
        steps: Vec::new(),
        stop: String::new(),
        error: None,
    };
    let res = (|| -> hammerstein::Result<()> {
        let data = IoData::siso(&rec.u, &rec.y)?;
        let (train, valid) = data.split_validation(0.3)?;
        let settings = Hammerstein::udn(EffectSet::of(&given)).seed(seed);
        let followed = Diagnoser::new().follow(&settings, &train, &valid, 4)?;
        let first = &followed.steps[0];
        out.start_ratio = compare(&first.model, &valid)?.metrics.mse / rec.noise_var;
        out.top = common::top_effect(&first.diagnosis);
        out.adequate = first.diagnosis.adequate;
        let last = followed.last().expect("a followed sequence has a step");
        out.final_ratio = compare(&last.model, &valid)?.metrics.mse / rec.noise_var;
        out.final_train_ratio = compare(&last.model, &train)?.metrics.mse / rec.noise_var;
        out.told = last
            .diagnosis
            .generalisation
            .as_ref()
            .is_some_and(|g| g.notable);
        out.steps = followed.steps.iter().map(|s| s.change.clone()).collect();
        out.stop = match &followed.stop {
            FollowStop::Adequate => "adequate".into(),
            FollowStop::NothingHelps => "nothing-helps".into(),
            FollowStop::CannotApply(_) => "cannot-apply".into(),
            FollowStop::MaxSteps => "max-steps".into(),
            FollowStop::NotConfirmed(_) => "not-confirmed".into(),
            FollowStop::TimeBudget => "time-budget".into(),
        };
        Ok(())
    })();
    if let Err(e) = res {
        out.error = Some(e.to_string());
    }
    out
}

/// Records whose first diagnosis names the feedback nonlinearity first (none has one).
fn feedback_first(outs: &[Outcome]) -> usize {
    outs.iter()
        .filter(|o| o.top == "feedback-nonlinearity")
        .count()
}

fn pct(k: usize, n: usize) -> String {
    if n == 0 {
        "-".into()
    } else {
        format!("{k}/{n} ({:.0} %)", 100.0 * k as f64 / n as f64)
    }
}

/// The rates as a table.
fn table(outs: &[Outcome]) -> String {
    let hidden: Vec<&Outcome> = outs.iter().filter(|o| o.hidden.is_some()).collect();
    // a hidden effect whose absence leaves the model at the noise floor is not detectable
    let visible: Vec<&&Outcome> = hidden.iter().filter(|o| o.start_ratio > 1.2).collect();
    let complete: Vec<&Outcome> = outs.iter().filter(|o| o.hidden.is_none()).collect();
    // a complete model whose fit missed the floor (order selection, a local optimum) is rightly
    // not adequate: the first row counts it as a miss, the second leaves it out
    let at_floor: Vec<&Outcome> = complete
        .iter()
        .copied()
        .filter(|o| o.start_ratio <= 1.2)
        .collect();
    let ok = |v: &[&Outcome]| {
        v.iter()
            .filter(|o| o.error.is_none() && o.correct())
            .count()
    };
    let followed = |v: &[&Outcome]| {
        v.iter()
            .filter(|o| o.error.is_none() && o.final_ratio <= 1.5)
            .count()
    };
    let errors = outs.iter().filter(|o| o.error.is_some()).count();
    let visible_ok = visible
        .iter()
        .filter(|o| o.error.is_none() && o.correct())
        .count();
    format!(
        "| measure | result | target |\n|---|---|---|\n\
         | hidden effect named first (all) | {} | ≥ 90 % |\n\
         | hidden effect named first (start above 1.2× noise) | {} | |\n\
         | complete model: adequate, no suggestion | {} | ≥ 95 % |\n\
         | complete model starting at the floor (≤ 1.2× noise): adequate, no suggestion | {} | |\n\
         | after `follow`: validation MSE ≤ 1.5× noise (hidden) | {} | ≥ 90 % |\n\
         | after `follow`: validation MSE ≤ 1.5× noise (all) | {} | |\n\
         | feedback-nonlinearity named first (Hammerstein records) | {} | 0 |\n\
         | failures (errors) | {errors} | 0 |\n\
         | followed model above 1.5× noise on validation: told it does not carry over | {} | |\n\
         | followed model at ≤ 1.2× noise on validation: told (false alarm) | {} | |\n",
        pct(ok(&hidden), hidden.len()),
        pct(visible_ok, visible.len()),
        pct(ok(&complete), complete.len()),
        pct(ok(&at_floor), at_floor.len()),
        pct(followed(&hidden), hidden.len()),
        pct(followed(&outs.iter().collect::<Vec<_>>()), outs.len()),
        pct(feedback_first(outs), outs.len()),
        told(outs, |r| r > 1.5),
        told(outs, |r| r <= 1.2),
    )
}

/// How many of the records whose followed model's validation ratio satisfies `band` were told
/// that the model does not carry over to the validation part.
fn told(outs: &[Outcome], band: impl Fn(f64) -> bool) -> String {
    let v: Vec<&Outcome> = outs
        .iter()
        .filter(|o| o.error.is_none() && band(o.final_ratio))
        .collect();
    pct(v.iter().filter(|o| o.told).count(), v.len())
}

fn misses(outs: &[Outcome]) -> String {
    let mut s = String::from(
        "| seed | order | effects | hidden | input | SNR dB | start/noise | named first | steps | stop | final/noise | final train/noise | told |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for o in outs
        .iter()
        .filter(|o| o.error.is_some() || !o.correct() || o.final_ratio > 1.5)
    {
        s.push_str(&format!(
            "| {} | {} | [{}] | {} | {} | {:.0} | {:.2} | {} | {} | {} | {} | {:.2} | {} |\n",
            o.seed,
            o.order,
            o.effects,
            o.hidden.map_or("none".into(), |h| h.name().to_string()),
            o.excitation,
            o.snr,
            o.start_ratio,
            o.top,
            o.steps.join(" → "),
            o.stop,
            o.error
                .clone()
                .unwrap_or_else(|| format!("{:.2}", o.final_ratio)),
            o.final_train_ratio,
            if o.told { "yes" } else { "" }
        ));
    }
    s
}

/// Fast slice: no failure, and most hidden effects named and followed to the floor.
#[test]
fn diagnosis_random_slice() {
    let outs: Vec<Outcome> = (1..=6u64).into_par_iter().map(run).collect();
    println!("{}\n{}", table(&outs), misses(&outs));
    assert!(outs.iter().all(|o| o.error.is_none()), "{outs:#?}");
    assert_eq!(
        feedback_first(&outs),
        0,
        "feedback named on a Hammerstein record"
    );
    let good = outs
        .iter()
        .filter(|o| o.correct() && o.final_ratio <= 1.5)
        .count();
    assert!(good >= 5, "only {good}/6 named and followed to the floor");
}

#[test]
#[ignore]
fn battery() {
    let seeds: u64 = common::env_count("BATTERY_SEEDS", 100);
    // seeds beyond the documented ones: BATTERY_OFFSET=200 runs seeds 201–(200 + BATTERY_SEEDS)
    let offset: u64 = common::env_count("BATTERY_OFFSET", 0);
    let (first, last) = (offset + 1, offset + seeds);
    let outs: Vec<Outcome> = (first..=last).into_par_iter().map(run).collect();
    let text = format!(
        "### {seeds} records (seeds {first}–{last})\n\n{}\nMisses:\n\n{}\n",
        table(&outs),
        misses(&outs)
    );
    common::publish_battery(&text);
    assert_eq!(
        feedback_first(&outs),
        0,
        "feedback named on a Hammerstein record"
    );
}
