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
    /// The plays the PI refit removed to keep its weights of one sign ("" when none).
    removed: String,
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
    block: StateSpace<f64>,
    /// The truth's static (UDN) part of v.
    v_static: Vec<f64>,
    /// The truth's play thresholds and weights.
    truth: Vec<(f64, f64)>,
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
    let v_static = udn.eval(&u);
    let mut v = v_static.clone();
    let truth = r
        .iter()
        .zip(&dens)
        .map(|(r, d)| (*r, total * d / sum))
        .collect();
    for (rj, dj) in r.iter().zip(&dens) {
        let f = play(&u, *rj, 0.0).unwrap();
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
        block,
        v_static,
        truth,
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
        removed: String::new(),
        error: None,
    };
    let res = (|| -> hammerstein::Result<()> {
        let data = IoData::siso(&rec.u, &rec.y)?;
        let (train, valid) = data.split_validation(0.3)?;
        let model = Hammerstein::udn(rec.base).seed(seed).fit(&train)?;
        out.start_ratio = compare(&model, &valid)?.metrics.mse / rec.noise_var;
        let d = Diagnoser::new().diagnose(&model, &train, &valid)?;
        out.top = common::top_effect(&d);
        out.removed = d
            .candidates
            .iter()
            .filter(|c| c.effect == "prandtl-ishlinskii")
            .filter_map(|c| c.refit.as_ref()?.change.split_once("; plays "))
            .map(|(_, r)| r.split(" removed").next().unwrap_or_default().to_string())
            .collect();
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
        let top = common::top_effect(&d);
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
        Ok(common::top_effect(&d))
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
            "seed {:3} order {} {:22} base {:11} {:4.1} dB: start {:7.2}× noise, top {:20} final {:6.2}× {}{}",
            o.seed,
            o.order,
            o.input,
            o.base,
            o.snr,
            o.start_ratio,
            o.top,
            o.final_ratio,
            if o.removed.is_empty() {
                String::new()
            } else {
                format!("(removed {}) ", o.removed)
            },
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
    let n = common::env_count("PI_SEEDS", 60);
    let outs: Vec<Outcome> = (offset()..offset() + n).into_par_iter().map(run).collect();
    report(&outs);
    // other seeds move the false-alarm and hysteresis records along (2000 and 4000 at 100)
    let shift = offset().saturating_sub(100);
    false_alarms(2000 + shift..2000 + shift + n);
    udn_hysteresis_confusions(4000 + 2 * shift..4000 + 2 * shift + 2 * n);
}

/// First seed of the battery's PI records (`PI_OFFSET`, default 100).
fn offset() -> u64 {
    common::env_count("PI_OFFSET", 100)
}

/// Least squares of `y` on the columns `cols` over the first `n` samples, by the crate's QR
/// (`LinAlg::lstsq` of the faer backend).
fn lsq(cols: &[Vec<f64>], y: &[f64], n: usize) -> Vec<f64> {
    use hammerstein::LinAlg;
    let a = hammerstein::faer::Mat::from_fn(n, cols.len(), |k, j| cols[j][k]);
    let b = hammerstein::faer::Mat::from_fn(n, 1, |k, _| y[k]);
    let x = hammerstein::Faer::default()
        .lstsq(a.as_ref(), b.as_ref())
        .expect("finite play columns");
    (0..cols.len()).map(|j| x[(j, 0)]).collect()
}

/// Validation MSE / noise of the best fit with the true block and static part and play weights
/// (least squares on the training part) on thresholds `r` started at `c`.
fn oracle(rec: &Record, r: &[f64], c: f64, cut: usize) -> (f64, Vec<f64>) {
    let mut cols = vec![rec.v_static.clone(), vec![1.0; rec.u.len()]];
    cols.extend(r.iter().map(|&r| play(&rec.u, r, c).unwrap()));
    let filt: Vec<Vec<f64>> = cols
        .iter()
        .map(|c| rec.block.simulate_siso(c, None).unwrap())
        .collect();
    let w = lsq(&filt, &rec.y, cut);
    let n = rec.u.len();
    let mse = (cut..n)
        .map(|k| {
            let yh: f64 = filt.iter().zip(&w).map(|(f, w)| f[k] * w).sum();
            (rec.y[k] - yh).powi(2)
        })
        .sum::<f64>()
        / (n - cut) as f64;
    (mse / rec.noise_var, w)
}

/// Half amplitudes of the input's reversals (between consecutive turning points), sorted.
fn reversal_halves(u: &[f64]) -> Vec<f64> {
    let mut turns = vec![u[0]];
    let mut dir = 0.0;
    for w in u.windows(2) {
        let d = (w[1] - w[0]).signum();
        if d != 0.0 && d != dir {
            if dir != 0.0 {
                turns.push(w[0]);
            }
            dir = d;
        }
    }
    turns.push(u[u.len() - 1]);
    let mut h: Vec<f64> = turns
        .windows(2)
        .map(|t| (t[1] - t[0]).abs() / 2.0)
        .collect();
    h.sort_by(f64::total_cmp);
    h
}

/// The oracle on other grids: the model's grid started at 0 (the truth's start), K = 10 at c and
/// at 0, thresholds at the quantiles j/7 of the half reversals, the power grid on the largest one.
fn other_grids(rec: &Record, cut: usize) -> Vec<String> {
    let train = &rec.u[..cut];
    let (g6, _) = hammerstein::regressors::play_grid(train, 6).unwrap();
    let (g10, c) = hammerstein::regressors::play_grid(train, 10).unwrap();
    let half = reversal_halves(train);
    let q = |f: f64| half[((half.len() - 1) as f64 * f).round() as usize];
    let quantiles: Vec<f64> = (1..=6).map(|j| q(j as f64 / 7.0)).collect();
    let power: Vec<f64> = (1..=6)
        .map(|j| q(1.0) * (j as f64 / 7.0).powf(1.5))
        .collect();
    [
        (&g6, 0.0),
        (&g10, c),
        (&g10, 0.0),
        (&quantiles, c),
        (&power, c),
    ]
    .iter()
    .map(|(g, c)| format!("{:5.2}", oracle(rec, g, *c, cut).0))
    .collect()
}

/// Validation error (/ noise) of the truth's plays started again at the validation part (at 0)
/// instead of carried over, through the block.
fn restart_error(rec: &Record, cut: usize) -> f64 {
    let n = rec.u.len();
    let mut dv = vec![0.0; n - cut];
    for &(r, w) in &rec.truth {
        let a = play(&rec.u, r, 0.0).unwrap();
        let b = play(&rec.u[cut..], r, 0.0).unwrap();
        for (d, (x, y)) in dv.iter_mut().zip(a[cut..].iter().zip(&b)) {
            *d += w * (x - y);
        }
    }
    let dy = rec.block.simulate_siso(&dv, None).unwrap();
    dy.iter().map(|x| x * x).sum::<f64>() / (n - cut) as f64 / rec.noise_var
}

/// The PI candidate's outcome, the suggested refit's validation MSE restarted and on the whole
/// record (memory carried over), and fresh PI fits with the order selected and at the truth's.
fn fits_line(rec: &Record, seed: u64) -> hammerstein::Result<String> {
    let data = IoData::siso(&rec.u, &rec.y)?;
    let (train, valid) = data.split_validation(0.3)?;
    let model = Hammerstein::udn(rec.base).seed(seed).fit(&train)?;
    let d = Diagnoser::new().diagnose(&model, &train, &valid)?;
    let top = common::top_effect(&d);
    let mut refit = String::from("no refit");
    if let Some(c) = d
        .candidates
        .iter()
        .find(|c| c.effect == "prandtl-ishlinskii")
    {
        refit = format!(
            "cand: ev {:?} impr {:?} dbic {:?} err {:?} null {:?} refit val {:?}",
            c.evidence.as_ref().map(|e| e.p_value),
            c.improvement,
            c.criterion_change,
            c.refit_error,
            c.refit.as_ref().and_then(|r| r.null_parameters.clone()),
            c.refit.as_ref().map(|r| r.validation_mse / rec.noise_var)
        );
    }
    if let Some(s) = d
        .suggestions
        .iter()
        .find(|s| s.effect == "prandtl-ishlinskii")
        && let Some(m) = d.refitted(s)
    {
        let r = compare(m, &valid)?.metrics.mse / rec.noise_var;
        let ws: Vec<String> = m
            .parameters()
            .iter()
            .map(|(k, v)| format!("{k}={v:.3}"))
            .collect();
        let whole = compare(m, &data)?.residual;
        let cont = whole[train.len()..].iter().map(|x| x * x).sum::<f64>()
            / valid.len() as f64
            / rec.noise_var;
        let n = m.linear().order();
        refit = format!("refit {r:6.2}× cont {cont:5.2} n={n} [{}]", ws.join(" "));
    }
    let with_pi = Hammerstein::udn(rec.base.with(Effect::PrandtlIshlinskii)).seed(seed);
    let ratio = |m: hammerstein::fit::HammersteinModel<f64>| -> hammerstein::Result<(f64, usize)> {
        Ok((
            compare(&m, &valid)?.metrics.mse / rec.noise_var,
            m.linear().order(),
        ))
    };
    let fresh = with_pi.clone().fit(&train).and_then(ratio);
    let true_order = with_pi
        .order(hammerstein::subspace::Order::Fixed(rec.order))
        .fit(&train)
        .and_then(ratio);
    Ok(format!(
        "base n={} top {top:18} {refit} | fresh {:?} trueorder {:?}",
        model.linear().order(),
        fresh.ok(),
        true_order.ok()
    ))
}

/// Per record: bounds (the best weights on the model's grid and on others with the true block
/// and static part, the truth's plays restarted on the validation part) and the fits.
fn analyse_one(seed: u64) -> String {
    let rec = pi_record(seed);
    let n = rec.u.len();
    let cut = n - ((n as f64) * 0.3).round() as usize;
    let (grid_r, grid_c) = hammerstein::regressors::play_grid(&rec.u[..cut], 6).unwrap();
    let (orc, w) = oracle(&rec, &grid_r, grid_c, cut);
    let ws: Vec<String> = w[2..].iter().map(|x| format!("{x:.3}")).collect();
    format!(
        "seed {seed} n={} {:10} {:22} oracle grid {orc:5.2} other grids {:?} restart {:5.2} w[{}] | {}",
        rec.order,
        rec.base.label(),
        rec.input,
        other_grids(&rec, cut),
        restart_error(&rec, cut),
        ws.join(" "),
        fits_line(&rec, seed).unwrap_or_else(|e| format!("error {e}"))
    )
}

/// Development analysis of the failing records (`PI_OFFSET`, `PI_SEEDS`, default 20 seeds): per
/// record the oracle fits, the restart error and the diagnosis' refit.
#[test]
#[ignore]
fn analyse() {
    let n = common::env_count("PI_SEEDS", 20);
    let lines: Vec<String> = (offset()..offset() + n)
        .into_par_iter()
        .map(analyse_one)
        .collect();
    for l in lines {
        println!("{l}");
    }
}
