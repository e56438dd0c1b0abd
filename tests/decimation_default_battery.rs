//! The battery behind `fit`'s default of keeping every sample of an oversampled record: random
//! oversampled records (a slow second-order block drawn at random, four input kinds, five
//! static nonlinearities, SNR 10–40 dB, 20 000–40 000 samples) and records that are not
//! oversampled (the controls: a fast block, an input that changes every sample or two), each
//! fitted by the command line twice — on its default path and with `--decimate auto` (the factor
//! the record's band allows) — with the default options or, drawn at random, the options of a
//! user who knows the nonlinearity's kind. Both models are simulated by `simulate` on a held-out
//! record (another input of the same kind) and compared with its noise-free output at the
//! samples the decimated model keeps (samples 0, K, 2K, …: the same instants for both).
//!
//! What holds: the default path keeps every sample; `--decimate auto` leaves every control at
//! factor 1; and on at least [`HOLD_RATE`] of the oversampled records the default path's
//! held-out error is no worse than the decimated one's (within [`SAME`]). The rate at which
//! `--decimate auto` is no worse, the errors and the times are printed (docs/guided-loop.md);
//! `BATTERY_WRITE=FILE` appends them to FILE.
//!
//! `cargo test --release --test decimation_default_battery` draws [`SMALL`] records;
//! `-- --ignored` draws `DECIMATION_BATTERY_N` (default [`LARGE`]) and reports the rates;
//! `DECIMATION_BATTERY_SEED=S` runs record S alone and keeps its files.

mod common;

use common::oversampled::{Record, record};
use std::path::Path;
use std::time::Instant;

/// Records of the default draw (every fifth a control).
const SMALL: u64 = 10;
/// Records of the ignored draw.
const LARGE: u64 = 60;
/// Fraction of the oversampled records on which the default path must be no worse than
/// `--decimate auto`.
const HOLD_RATE: f64 = 0.9;
/// Relative difference of held-out error counted as "the same".
const SAME: f64 = 0.02;

/// Outcome of one record.
struct Outcome {
    seed: u64,
    oversampled: bool,
    factor: usize,
    /// Held-out error against the noise-free output: default path, `--decimate auto`.
    err_default: f64,
    err_auto: f64,
    /// The same against the measured (noisy) held-out output, as a user sees it.
    meas_default: f64,
    meas_auto: f64,
    t_default: f64,
    t_auto: f64,
}

/// `fit` on `train` (validation on `val`) with `extra`; the model saved to `model`; returns
/// (the decimation it applied, its standard error, seconds).
fn fit(
    train: &Path,
    val: &Path,
    model: &Path,
    opts: &[&str],
    extra: &[&str],
) -> (usize, String, f64) {
    let mut args = vec![
        "fit",
        train.to_str().unwrap(),
        "--validation-file",
        val.to_str().unwrap(),
        "--save",
        model.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(opts);
    args.extend_from_slice(extra);
    let t = Instant::now();
    let (ok, out, err) = common::run_cli_outcome(&args);
    let secs = t.elapsed().as_secs_f64();
    assert!(ok, "{args:?}: {err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    (j["decimation"].as_u64().unwrap() as usize, err, secs)
}

/// The simulated output of `model` on `truth` (the model decimates it as it was fitted).
fn simulate(model: &Path, truth: &Path) -> Vec<f64> {
    let out = common::run_cli(&["simulate", model.to_str().unwrap(), truth.to_str().unwrap()]);
    out.lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
        .collect()
}

/// RMS of `sim[i] − truth[i·step]` over the kept instants, relative to the truth's spread.
fn rel_error(sim: &[f64], truth: &[f64], step: usize) -> f64 {
    let kept: Vec<f64> = truth.iter().step_by(step).copied().collect();
    assert_eq!(sim.len(), kept.len());
    let mean = kept.iter().sum::<f64>() / kept.len() as f64;
    let spread = kept.iter().map(|y| (y - mean).powi(2)).sum::<f64>();
    let err = sim
        .iter()
        .zip(&kept)
        .map(|(s, y)| (s - y).powi(2))
        .sum::<f64>();
    (err / spread).sqrt()
}

fn run(seed: u64, dir: &Path) -> Outcome {
    let Record {
        draw: d,
        u,
        y,
        uv,
        yv,
        yv0,
        ..
    } = record(seed);
    let (train, val, truth) = (
        dir.join(format!("train{seed}.csv")),
        dir.join(format!("val{seed}.csv")),
        dir.join(format!("truth{seed}.csv")),
    );
    common::write_csv(&train, &["u", "y"], &[&u, &y]);
    common::write_csv(&val, &["u", "y"], &[&uv, &yv]);
    common::write_csv(&truth, &["u", "y"], &[&uv, &yv0]);
    let opts = if d.known { d.map.fit_options() } else { &[] };
    let (m_default, m_auto) = (
        dir.join(format!("default{seed}.json")),
        dir.join(format!("auto{seed}.json")),
    );
    let (one, _, t_default) = fit(&train, &val, &m_default, opts, &[]);
    assert_eq!(one, 1, "seed {seed}: the default path decimated the record");
    let (factor, said, t_auto) = fit(&train, &val, &m_auto, opts, &["--decimate", "auto"]);
    assert!(
        said.contains(&format!("--decimate auto: {factor} ")),
        "seed {seed}: the factor is not said: {said}"
    );
    let auto = simulate(&m_auto, &truth);
    let every = simulate(&m_default, &truth);
    let every_kept: Vec<f64> = every.iter().step_by(factor).copied().collect();
    let o = Outcome {
        seed,
        oversampled: d.oversampled,
        factor,
        err_default: rel_error(&every_kept, &yv0, factor),
        err_auto: rel_error(&auto, &yv0, factor),
        meas_default: rel_error(&every_kept, &yv, factor),
        meas_auto: rel_error(&auto, &yv, factor),
        t_default,
        t_auto,
    };
    println!(
        "seed {seed:3} {:11} wn {:.4} zeta {:.2} {:9} hold {:4} {:10} {:5} snr {:4.1} n {:5}: \
         K {factor:3}, held-out error {:.4} (default) vs {:.4} (auto), measured {:.4} vs {:.4}, \
         {:.1} s vs {:.1} s",
        if d.oversampled {
            "oversampled"
        } else {
            "control"
        },
        d.wn,
        d.zeta,
        d.input.name(),
        d.hold,
        d.map.name(),
        if d.known { "fit" } else { "lin" },
        d.snr,
        d.n,
        o.err_default,
        o.err_auto,
        o.meas_default,
        o.meas_auto,
        t_default,
        t_auto
    );
    o
}

fn battery(count: u64) {
    let dir = common::temp_dir("decimation-default");
    // DECIMATION_BATTERY_SEED=S: that record alone, its files kept (to inspect)
    let one = std::env::var("DECIMATION_BATTERY_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok());
    let seeds = one.map_or(0..count, |s| s..s + 1);
    let outcomes: Vec<Outcome> = seeds.map(|s| run(s, &dir)).collect();
    match one {
        Some(_) => println!("files kept in {}", dir.display()),
        None => {
            std::fs::remove_dir_all(&dir).ok();
        }
    }
    let over: Vec<&Outcome> = outcomes.iter().filter(|o| o.oversampled).collect();
    let controls: Vec<&Outcome> = outcomes.iter().filter(|o| !o.oversampled).collect();
    let no_worse = |a: f64, b: f64| a <= b * (1.0 + SAME);
    let held = over
        .iter()
        .filter(|o| no_worse(o.err_default, o.err_auto))
        .count();
    let auto_held = over
        .iter()
        .filter(|o| no_worse(o.err_auto, o.err_default))
        .count();
    let auto_held_measured = over
        .iter()
        .filter(|o| no_worse(o.meas_auto, o.meas_default))
        .count();
    let decimated = over.iter().filter(|o| o.factor > 1).count();
    let (td, ta): (f64, f64) = over
        .iter()
        .fold((0.0, 0.0), |(a, b), o| (a + o.t_default, b + o.t_auto));
    let wrong_controls: Vec<u64> = controls
        .iter()
        .filter(|o| o.factor != 1)
        .map(|o| o.seed)
        .collect();
    let pct = |k: usize| 100.0 * k as f64 / over.len().max(1) as f64;
    common::publish_battery(&format!(
        "decimation battery, {count} records: oversampled {}, decimated by --decimate auto {}; \
         held-out error (noise-free) no worse within {:.0} %: default path {held} ({:.0} %), \
         --decimate auto {auto_held} ({:.0} %); against the measured output --decimate auto \
         {auto_held_measured} ({:.0} %); fit time {td:.1} s default vs {ta:.1} s auto; controls \
         {} (at factor 1: {})\n",
        over.len(),
        decimated,
        100.0 * SAME,
        pct(held),
        pct(auto_held),
        pct(auto_held_measured),
        controls.len(),
        controls.len() - wrong_controls.len()
    ));
    assert!(
        wrong_controls.is_empty(),
        "--decimate auto decimated records that are not oversampled: seeds {wrong_controls:?}"
    );
    if one.is_some() || over.is_empty() {
        // one record inspected: no rate to judge
        return;
    }
    let rate = held as f64 / over.len() as f64;
    assert!(
        rate >= HOLD_RATE,
        "the default path is no worse than --decimate auto on {:.0} % of the oversampled \
         records (< {:.0} %)",
        100.0 * rate,
        100.0 * HOLD_RATE
    );
}

#[test]
fn the_default_path_keeps_every_sample_and_is_no_worse() {
    battery(SMALL);
}

#[test]
#[ignore = "larger draw (DECIMATION_BATTERY_N records, default 60): reports the rate"]
fn the_decimation_rates_on_a_larger_draw() {
    battery(common::env_count("DECIMATION_BATTERY_N", LARGE));
}
