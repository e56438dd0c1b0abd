//! Does the suggested decimation factor belong on the default path? A battery of oversampled
//! simulated records: random slow second-order blocks (ω₀ between 0.004 and 0.03 rad per
//! sample, damping 0.2–0.9), a random static nonlinearity (saturation, dead-zone, preload or
//! none), random held inputs (levels held 20–400 samples), output SNR 15–40 dB, random seeds.
//! Each record is fitted at its own rate and decimated by the factor `--decimate auto` finds
//! (the band of a linear MOESP model of the record, `decimation::suggested_factor`), with the
//! same settings (`Hammerstein::udn` with the true effect, order 2, no feed-through); both models
//! simulate a fresh validation record of the same system, and their errors against the
//! noise-free output are compared on the same samples (every K-th one). Prints one line per
//! record and the rates.
//!
//! `cargo run --release --example decimation_battery [RECORDS] [SAMPLES] [SEED]`
//! (defaults 12, 20000, 1); with `BATTERY_GRID=1` the inputs switch only on multiples of 20
//! samples (held on the grid of the factor).

use hammerstein::diagnosis::compare;
use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::{Hammerstein, IoData, Order, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::time::Instant;

/// The factor `--decimate auto` finds for `record` (as `cli/common.rs`).
fn auto_factor(record: &IoData<f64>) -> usize {
    let Ok(centred) = record.detrend_mean() else {
        return 1;
    };
    hammerstein::subspace::identify(
        &hammerstein::Moesp::new(10),
        &hammerstein::Faer::default(),
        &[centred.view()],
        &hammerstein::SubspaceOptions::default(),
    )
    .ok()
    .and_then(|id| hammerstein::decimation::suggested_factor(&id.model, record.len()))
    .unwrap_or(1)
}

#[derive(Clone, Copy, Debug)]
enum Nl {
    None,
    Saturation(f64, f64),
    DeadZone(f64),
    Preload(f64),
}

impl Nl {
    fn eval(self, u: f64) -> f64 {
        match self {
            Nl::None => u,
            Nl::Saturation(hi, lo) => u.clamp(lo, hi),
            Nl::DeadZone(b) => {
                if u > b {
                    u - b
                } else if u < -b {
                    u + b
                } else {
                    0.0
                }
            }
            Nl::Preload(e) => u + e * u.signum(),
        }
    }
    fn effects(self) -> EffectSet {
        match self {
            Nl::None => EffectSet::empty(),
            Nl::Saturation(..) => EffectSet::of(&[Effect::Saturation]),
            Nl::DeadZone(_) => EffectSet::of(&[Effect::DeadZone]),
            Nl::Preload(_) => EffectSet::of(&[Effect::Preload]),
        }
    }
}

struct System {
    g: StateSpace<f64>,
    nl: Nl,
    noise_sd: f64,
}

fn input(n: usize, rng: &mut StdRng) -> Vec<f64> {
    let grid = std::env::var("BATTERY_GRID").is_ok();
    let mut u = Vec::with_capacity(n);
    while u.len() < n {
        let level = rng.random_range(-2.0..2.0);
        // BATTERY_GRID: holds of whole multiples of 20 samples (switching on the kept samples
        // of a factor 10 or 20)
        let hold = if grid {
            20 * rng.random_range(1..20)
        } else {
            rng.random_range(20..400)
        };
        u.extend(std::iter::repeat_n(level, hold));
    }
    u.truncate(n);
    u
}

fn record(s: &System, n: usize, rng: &mut StdRng) -> (IoData<f64>, Vec<f64>) {
    let u = input(n, rng);
    let v: Vec<f64> = u.iter().map(|&x| s.nl.eval(x)).collect();
    let clean = s.g.simulate_siso(&v, None).expect("a stable block");
    let noise = Normal::new(0.0, s.noise_sd).expect("a positive deviation");
    let y: Vec<f64> = clean.iter().map(|c| c + noise.sample(rng)).collect();
    (IoData::siso(&u, &y).expect("a record"), clean)
}

fn system(rng: &mut StdRng, n: usize) -> System {
    let w0: f64 = rng.random_range(0.004..0.03);
    let zeta: f64 = rng.random_range(0.2..0.9);
    let r = (-zeta * w0).exp();
    let theta = w0 * (1.0 - zeta * zeta).sqrt();
    let (a1, a2) = (2.0 * r * theta.cos(), -r * r);
    // unit static gain: b / (1 − a1 − a2)
    let b = 1.0 - a1 - a2;
    let g = StateSpace::from_rows(
        &[&[a1, 1.0], &[a2, 0.0]],
        &[&[b], &[0.0]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .expect("a block");
    let nl = match rng.random_range(0..4) {
        0 => Nl::None,
        1 => Nl::Saturation(rng.random_range(0.8..1.6), -rng.random_range(0.8..1.6)),
        2 => Nl::DeadZone(rng.random_range(0.2..0.6)),
        _ => Nl::Preload(rng.random_range(0.2..0.6)),
    };
    let mut probe = System {
        g,
        nl,
        noise_sd: 0.0,
    };
    let (_, clean) = record(&probe, n, rng);
    let var = clean.iter().map(|c| c * c).sum::<f64>() / n as f64;
    let snr_db: f64 = rng.random_range(15.0..40.0);
    probe.noise_sd = (var / 10f64.powf(snr_db / 10.0)).sqrt();
    probe
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let records = args.first().copied().unwrap_or(12);
    let n = args.get(1).copied().unwrap_or(20_000);
    let seed = args.get(2).copied().unwrap_or(1) as u64;
    println!(
        "{:>4} {:>14} {:>5} {:>11} {:>11} {:>8} {:>8} {:>8}",
        "rec", "nonlinearity", "K", "MSE full", "MSE dec", "ratio", "t full", "t dec"
    );
    let (mut not_worse, mut within_10, mut decimated, mut failed) = (0, 0, 0, 0);
    let (mut t_full_sum, mut t_dec_sum) = (0.0, 0.0);
    for i in 0..records {
        let mut rng = StdRng::seed_from_u64(seed * 1000 + i as u64);
        let s = system(&mut rng, n);
        let (train, _) = record(&s, n, &mut rng);
        let (val, val_clean) = record(&s, n, &mut rng);
        let k = auto_factor(&train);
        if k == 1 {
            println!(
                "{i:>4} {:>14} {k:>5} (not oversampled by the rule)",
                format!("{:?}", s.nl).chars().take(14).collect::<String>()
            );
            continue;
        }
        decimated += 1;
        let settings = Hammerstein::<f64>::udn(s.nl.effects())
            .order(Order::Fixed(2))
            .with_d(false);
        let t = Instant::now();
        let full = settings.fit(&train);
        let t_full = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let dec = train.decimate(k).and_then(|d| settings.fit(&d));
        let t_dec = t.elapsed().as_secs_f64();
        let err = |m: &hammerstein::HammersteinModel<f64>, data: &IoData<f64>, step: usize| {
            compare(m, data).ok().map(|c| {
                let picked = &c.y_hat;
                let m: f64 = picked
                    .iter()
                    .enumerate()
                    .map(|(j, yh)| (yh - val_clean[j * step]).powi(2))
                    .sum::<f64>()
                    / picked.len() as f64;
                m
            })
        };
        let val_dec = val.decimate(k).expect("a decimated record");
        let mse_full = full.as_ref().ok().and_then(|m| {
            // the full-rate simulation at the kept samples
            compare(m, &val).ok().map(|c| {
                let (s, cnt) = c
                    .y_hat
                    .iter()
                    .step_by(k)
                    .enumerate()
                    .fold((0.0, 0usize), |(s, c), (j, yh)| {
                        (s + (yh - val_clean[j * k]).powi(2), c + 1)
                    });
                s / cnt as f64
            })
        });
        let mse_dec = dec.as_ref().ok().and_then(|m| err(m, &val_dec, k));
        let name: String = format!("{:?}", s.nl).chars().take(14).collect();
        match (mse_full, mse_dec) {
            (Some(f), Some(d)) => {
                let ratio = d / f;
                if ratio <= 1.0 {
                    not_worse += 1;
                }
                if ratio <= 1.1 {
                    within_10 += 1;
                }
                t_full_sum += t_full;
                t_dec_sum += t_dec;
                println!(
                    "{i:>4} {name:>14} {k:>5} {f:>11.3e} {d:>11.3e} {ratio:>8.3} {t_full:>8.2} {t_dec:>8.2}"
                );
            }
            _ => {
                failed += 1;
                println!(
                    "{i:>4} {name:>14} {k:>5} failed: full {:?} / decimated {:?}",
                    full.err().map(|e| e.to_string()),
                    dec.err().map(|e| e.to_string())
                );
            }
        }
    }
    println!(
        "decimated: {decimated} of {records}; decimated MSE ≤ full-rate MSE: {not_worse}; within 10 %: {within_10}; failed: {failed}; fit time full {t_full_sum:.1} s, decimated {t_dec_sum:.1} s"
    );
}
