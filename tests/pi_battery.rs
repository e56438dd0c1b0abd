//! Randomised battery of hidden Prandtl–Ishlinskii (dynamic) hysteresis: random linear blocks of
//! order 1–3 (random stable poles, unit H2 norm), a truth p·u + ∫ w(r)·F_r[u] dr with an
//! exponential weight density on 30 thresholds (not the model's 6-play grid), optionally after
//! a UDN saturation or dead-zone (the model has those), three input kinds (multisine,
//! random-level steps, filtered noise with a varying amplitude envelope so that the loop width
//! varies), SNR 25–35 dB, N 2000–3000 (30 % held out).
//!
//! Measured: the diagnosis of the model without the play operators names `prandtl-ishlinskii`
//! first; the refitted model with them has a validation MSE within 1.5× the noise variance.
//! False alarms: records without any dynamic hysteresis (random UDN effects, the model given
//! all of them) where `prandtl-ishlinskii` is suggested at all, and records whose constant-width
//! UDN hysteresis is hidden from the model where `prandtl-ishlinskii` is named first instead of
//! `hysteresis`.
//!
//! `cargo test` runs 10 seeds of each. The battery:
//! `PI_SEEDS=60 cargo test --release --test pi_battery battery -- --ignored --nocapture`.

mod common;

use common::random_system::{PoleKind, Ranges, random_block, random_record};
use common::{InputKind, Udn, input};
use hammerstein::diagnosis::{Diagnoser, compare};
use hammerstein::fit::Hammerstein;
use hammerstein::regressors::{Effect, EffectSet, play};
use hammerstein::{IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// Thresholds of the truth's (finer) play grid.
const TRUTH_PLAYS: usize = 30;

#[derive(Debug, Clone)]
struct Outcome {
    seed: u64,
    order: usize,
    input: &'static str,
    base: String,
    snr: f64,
    /// Validation MSE / noise of the model without the play operators.
    start_ratio: f64,
    top: String,
    /// Validation MSE / noise of the refit with them (NaN when it was not suggested).
    final_ratio: f64,
    error: Option<String>,
}

/// Random levels held for 5–40 samples.
fn steps(rng: &mut StdRng, n: usize, amp: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let level = rng.random_range(-amp..amp);
        let hold = rng.random_range(5..=40usize);
        out.extend(std::iter::repeat_n(level, hold));
    }
    out.truncate(n);
    out
}

struct Record {
    order: usize,
    input: &'static str,
    base: EffectSet,
    snr: f64,
    u: Vec<f64>,
    y: Vec<f64>,
    noise_var: f64,
}

fn pi_record(seed: u64) -> Record {
    let mut rng = StdRng::seed_from_u64(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x91);
    let order = rng.random_range(1..=3usize);
    let poles = [
        PoleKind::Slow,
        PoleKind::Fast,
        PoleKind::Anywhere,
        PoleKind::LightlyDamped,
    ][rng.random_range(0..4usize)];
    let block: StateSpace<f64> = random_block(&mut rng, order, poles, false);
    let amp = 10f64.powf(rng.random_range(-0.5..0.7));
    let n = rng.random_range(2000..=3000usize);
    let kind = rng.random_range(0..3usize);
    let (u, name) = match kind {
        0 => (
            input(InputKind::Multisine, n, amp, seed ^ 0x33),
            "multisine",
        ),
        1 => (steps(&mut rng, n, amp), "random steps"),
        _ => {
            let base = input(InputKind::Smooth, n, amp, seed ^ 0x44);
            let period = rng.random_range(300.0..900.0);
            let env: Vec<f64> = (0..n)
                .map(|k| {
                    0.3 + 0.7 * (0.5 + 0.5 * (std::f64::consts::TAU * k as f64 / period).sin())
                })
                .collect();
            (
                base.iter().zip(&env).map(|(b, e)| b * e).collect(),
                "varying filtered noise",
            )
        }
    };
    // base: linear, saturation or dead-zone (input-referred sizes as the other batteries)
    let p = rng.random_range(0.5..2.0);
    let mut udn = Udn::linear(p);
    let base = match rng.random_range(0..3usize) {
        0 => EffectSet::empty(),
        1 => {
            udn.z1 = amp * rng.random_range(0.6..0.85);
            udn.z2 = -amp * rng.random_range(0.6..0.85);
            EffectSet::of(&[Effect::Saturation])
        }
        _ => {
            udn.b = amp * rng.random_range(0.05..0.15);
            EffectSet::of(&[Effect::DeadZone])
        }
    };
    // PI part: total weight 0.3–1 × p, density ∝ exp(−r/λ) on r ∈ (0, amp]
    let total = p * rng.random_range(0.3..1.0);
    let lambda = amp * rng.random_range(0.15..0.6);
    let r: Vec<f64> = (1..=TRUTH_PLAYS)
        .map(|j| amp * j as f64 / TRUTH_PLAYS as f64)
        .collect();
    let dens: Vec<f64> = r.iter().map(|r| (-r / lambda).exp()).collect();
    let sum: f64 = dens.iter().sum();
    let mut v = udn.eval(&u);
    for (rj, dj) in r.iter().zip(&dens) {
        let f = play(&u, *rj, 0.0);
        for k in 0..n {
            v[k] += total * dj / sum * f[k];
        }
    }
    let y0 = block.simulate_siso(&v, None).unwrap();
    let m = y0.iter().sum::<f64>() / n as f64;
    let var = y0.iter().map(|y| (y - m).powi(2)).sum::<f64>() / n as f64;
    let snr = rng.random_range(25.0..35.0);
    let noise_var = var / 10f64.powf(snr / 10.0);
    let nd = Normal::new(0.0, noise_var.sqrt()).unwrap();
    let y = y0.iter().map(|y| y + nd.sample(&mut rng)).collect();
    Record {
        order,
        input: name,
        base,
        snr,
        u,
        y,
        noise_var,
    }
}

fn run(seed: u64) -> Outcome {
    let rec = pi_record(seed);
    let mut out = Outcome {
        seed,
        order: rec.order,
        input: rec.input,
        base: rec.base.label(),
        snr: rec.snr,
        start_ratio: f64::NAN,
        top: String::new(),
        final_ratio: f64::NAN,
        error: None,
    };
    let res = (|| -> hammerstein::Result<()> {
        let data = IoData::siso(&rec.u, &rec.y)?;
        let (train, valid) = data.split_validation(0.3)?;
        let model = Hammerstein::udn(rec.base).seed(seed).fit(&train)?;
        out.start_ratio = compare(&model, &valid)?.metrics.mse / rec.noise_var;
        let d = Diagnoser::new().diagnose(&model, &train, &valid)?;
        out.top = d
            .suggestions
            .first()
            .map_or("none".into(), |s| s.effect.to_string());
        if let Some(s) = d
            .suggestions
            .iter()
            .find(|s| s.effect == "prandtl-ishlinskii")
            && let Some(m) = d.refitted(s)
        {
            out.final_ratio = compare(m, &valid)?.metrics.mse / rec.noise_var;
        }
        Ok(())
    })();
    if let Err(e) = res {
        out.error = Some(e.to_string());
    }
    out
}

/// On a record without dynamic hysteresis (random UDN effects, the model given all of them):
/// whether `prandtl-ishlinskii` is suggested, and the top suggestion.
fn false_alarm(seed: u64) -> (bool, String, String) {
    let ranges = Ranges {
        orders: (1, 3),
        snr_db: (25.0, 35.0),
        n: (2000, 3000),
        effect_prob: 0.5,
    };
    let rec = random_record(seed, &ranges);
    let res = (|| -> hammerstein::Result<(bool, String)> {
        let data = IoData::siso(&rec.u, &rec.y)?;
        let (train, valid) = data.split_validation(0.3)?;
        let model = Hammerstein::udn(rec.effects).seed(seed).fit(&train)?;
        let d = Diagnoser::new().diagnose(&model, &train, &valid)?;
        let top = d
            .suggestions
            .first()
            .map_or("none".into(), |s| s.effect.to_string());
        Ok((
            d.suggestions
                .iter()
                .any(|s| s.effect == "prandtl-ishlinskii"),
            top,
        ))
    })();
    match res {
        Ok((s, top)) => (s, top, rec.effects.label()),
        Err(e) => (false, format!("error: {e}"), rec.effects.label()),
    }
}

/// On a record with the UDN's constant-width hysteresis hidden from the model (records without
/// hysteresis skipped: `None`): the top suggestion.
fn udn_hysteresis_top(seed: u64) -> Option<String> {
    let ranges = Ranges {
        orders: (1, 3),
        snr_db: (25.0, 35.0),
        n: (2000, 3000),
        effect_prob: 0.5,
    };
    let rec = random_record(seed, &ranges);
    if !rec.effects.contains(Effect::Hysteresis) {
        return None;
    }
    let given = rec.effects.without(Effect::Hysteresis);
    let res = (|| -> hammerstein::Result<String> {
        let data = IoData::siso(&rec.u, &rec.y)?;
        let (train, valid) = data.split_validation(0.3)?;
        let model = Hammerstein::udn(given).seed(seed).fit(&train)?;
        let d = Diagnoser::new().diagnose(&model, &train, &valid)?;
        Ok(d.suggestions
            .first()
            .map_or("none".into(), |s| s.effect.to_string()))
    })();
    Some(res.unwrap_or_else(|e| format!("error: {e}")))
}

fn udn_hysteresis_confusions(seeds: std::ops::Range<u64>) -> (usize, usize) {
    let r: Vec<String> = seeds
        .into_par_iter()
        .filter_map(udn_hysteresis_top)
        .collect();
    let pi = r.iter().filter(|t| *t == "prandtl-ishlinskii").count();
    let h = r.iter().filter(|t| *t == "hysteresis").count();
    println!(
        "UDN hysteresis hidden: hysteresis named first {h}/{n}, prandtl-ishlinskii first {pi}/{n} ({r:?})",
        n = r.len()
    );
    (pi, r.len())
}

fn report(outs: &[Outcome]) -> (usize, usize) {
    for o in outs {
        println!(
            "seed {:3} order {} {:22} base {:11} {:4.1} dB: start {:7.2}× noise, top {:20} final {:6.2}× {}",
            o.seed,
            o.order,
            o.input,
            o.base,
            o.snr,
            o.start_ratio,
            o.top,
            o.final_ratio,
            o.error.as_deref().unwrap_or("")
        );
    }
    let first = outs
        .iter()
        .filter(|o| o.error.is_none() && o.top == "prandtl-ishlinskii")
        .count();
    let good = outs
        .iter()
        .filter(|o| o.error.is_none() && o.final_ratio <= 1.5)
        .count();
    println!(
        "PI named first: {first}/{n}; validation MSE ≤ 1.5× noise after adding it: {good}/{n}",
        n = outs.len()
    );
    (first, good)
}

fn false_alarms(seeds: std::ops::Range<u64>) -> usize {
    let r: Vec<(bool, String, String)> = seeds.into_par_iter().map(false_alarm).collect();
    for (s, top, eff) in &r {
        println!("no PI, effects {eff:40} top {top:22} PI suggested: {s}");
    }
    let k = r.iter().filter(|x| x.0).count();
    println!("PI suggested without PI hysteresis: {k}/{}", r.len());
    k
}

#[test]
fn hidden_pi_hysteresis_is_named_and_fixed() {
    let outs: Vec<Outcome> = (0..10u64).into_par_iter().map(run).collect();
    let (first, good) = report(&outs);
    assert!(first >= 8, "PI named first on {first}/10 records");
    assert!(
        good >= 8,
        "validation MSE within 1.5× noise on {good}/10 records"
    );
}

#[test]
fn pi_is_not_suggested_without_dynamic_hysteresis() {
    let k = false_alarms(1000..1010);
    assert!(k <= 1, "PI suggested on {k}/10 records without it");
}

#[test]
fn constant_width_hysteresis_is_not_taken_for_pi() {
    let (pi, n) = udn_hysteresis_confusions(3000..3016);
    assert!(n >= 5, "only {n} records with hysteresis");
    assert!(
        pi * 5 <= n,
        "PI named first on {pi}/{n} records with UDN hysteresis"
    );
}

#[test]
#[ignore]
fn battery() {
    let n: u64 = std::env::var("PI_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let outs: Vec<Outcome> = (100..100 + n).into_par_iter().map(run).collect();
    report(&outs);
    false_alarms(2000..2000 + n);
    udn_hysteresis_confusions(4000..4000 + 2 * n);
}
