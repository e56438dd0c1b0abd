//! `diagnose` at scale with the default settings (as `hammerstein diagnose` with no option:
//! linear model, order and feed-through selected, refinement, every candidate), 30 % held out
//! for validation.
//!
//! Data: random steps (a new level, uniform in [−2, 2], with probability 1/50 at each sample)
//! plus a sine of amplitude 1 and period 400 samples, through a saturation at ±1.5 into the
//! paper's second-order block, 25 dB output noise (as `examples/large_record.rs` with
//! `steps-sine`).
//!
//! - `cargo bench --bench diagnose_scale`: criterion, 10 samples, the fit + diagnosis of the
//!   10⁶-sample record (target: < 10 s of CPU);
//! - `DIAGNOSE_SCALE_MAX=10000000 cargo bench --bench diagnose_scale -- --memory`: the wall time
//!   and the peak resident memory (VmHWM of /proc/self/status) of a fresh process per size
//!   (10⁵, 10⁶, and up to the maximum), beside the record's size in memory (u, y as f64, 16
//!   bytes a sample; target: peak < 3× the record);
//! - `DIAGNOSE_SCALE_ACCURACY=1000000 cargo bench --bench diagnose_scale` compares the screened
//!   fit with the whole-record fit instead (validation MSE and time).

use hammerstein::IoData;
use hammerstein::StateSpace;
use hammerstein::diagnosis::diagnose;
use hammerstein::fit::Hammerstein;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::time::Instant;

fn record(n: usize, seed: u64) -> IoData<f64> {
    let g = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .expect("a valid state-space model");
    let mut rng = StdRng::seed_from_u64(seed);
    let mut level = 0.0;
    let u: Vec<f64> = (0..n)
        .map(|k| {
            if rng.random_range(0.0..1.0) < 0.02 {
                level = rng.random_range(-2.0..2.0);
            }
            level + (2.0 * std::f64::consts::PI * k as f64 / 400.0).sin()
        })
        .collect();
    let v: Vec<f64> = u.iter().map(|u| u.clamp(-1.5, 1.5)).collect();
    let mut y = g.simulate_siso(&v, None).expect("a stable simulation");
    drop(v);
    let var = y.iter().map(|y| y * y).sum::<f64>() / n as f64;
    let noise = Normal::new(0.0, (var / 10f64.powf(2.5)).sqrt()).expect("a positive deviation");
    for x in y.iter_mut() {
        *x += noise.sample(&mut rng);
    }
    IoData::siso(&u, &y).expect("a valid record")
}

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn one(n: usize) {
    let (train, val) = {
        let d = record(n, 1);
        d.split_validation(0.3).expect("a valid split")
    };
    let base = peak_rss_mb();
    let t = Instant::now();
    let model = Hammerstein::<f64>::linear()
        .fit(&train)
        .expect("the fit succeeds");
    let t_fit = t.elapsed().as_secs_f64();
    let d = diagnose(&model, &train, &val).expect("the diagnosis succeeds");
    let total = t.elapsed().as_secs_f64();
    // MiB, as the peak (VmHWM is in KiB)
    let uy_mb = (2 * n * 8) as f64 / 1048576.0;
    let peak = peak_rss_mb();
    println!(
        "N = {n:>9}: fit {t_fit:7.2} s, fit + diagnose {total:7.2} s; peak RSS {peak:7.1} MiB \
         (record u, y {uy_mb:.1} MiB, ratio {:.2}; after generation {base:.0} MiB); top: {}",
        peak / uy_mb,
        d.suggestions
            .first()
            .map_or("none".to_string(), |s| s.effect.to_string())
    );
}

/// The accuracy of screening: the default (screened) fit against the whole-record fit, by their
/// validation MSEs.
fn accuracy(n: usize) {
    use hammerstein::diagnosis::compare;
    use hammerstein::fit::Screening;
    let (train, val) = record(n, 1).split_validation(0.3).expect("a valid split");
    for settings in [
        Hammerstein::<f64>::linear(),
        Hammerstein::<f64>::sh().order(hammerstein::subspace::Order::Fixed(2)),
    ] {
        let t = Instant::now();
        let screened = settings.fit(&train).expect("the screened fit");
        let ts = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let whole = settings
            .clone()
            .screening(Screening::off())
            .fit(&train)
            .expect("the whole fit");
        let tw = t.elapsed().as_secs_f64();
        let ms = compare(&screened, &val).expect("comparison").metrics.mse;
        let mw = compare(&whole, &val).expect("comparison").metrics.mse;
        println!(
            "N = {n}, {}: validation MSE screened {ms:.6e} ({ts:.2} s, order {}), whole {mw:.6e} \
             ({tw:.2} s, order {}), relative difference {:+.3e}",
            settings.nonlinearity_name(),
            screened.linear().order(),
            whole.linear().order(),
            (ms - mw) / mw
        );
    }
}

/// The criterion measurement: fit + diagnosis of the 10⁶-sample record, 10 samples.
fn criterion_1e6() {
    let (train, val) = record(1_000_000, 1)
        .split_validation(0.3)
        .expect("a valid split");
    let mut c = criterion::Criterion::default()
        .configure_from_args()
        .sample_size(10)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(30));
    c.bench_function("diagnose_default_1e6", |b| {
        b.iter(|| {
            let model = Hammerstein::<f64>::linear()
                .fit(&train)
                .expect("the fit succeeds");
            diagnose(&model, &train, &val).expect("the diagnosis succeeds")
        })
    });
    c.final_summary();
}

/// A fresh process per size, so that VmHWM is this size's peak.
fn memory() {
    let max: usize = std::env::var("DIAGNOSE_SCALE_MAX")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .map_or(1_000_000, |x| x as usize);
    let exe = std::env::current_exe().expect("the bench binary's path");
    for n in [100_000usize, 1_000_000, 10_000_000] {
        if n > max {
            break;
        }
        let status = std::process::Command::new(&exe)
            .env("DIAGNOSE_SCALE_N", n.to_string())
            .status();
        if !status.is_ok_and(|s| s.success()) {
            eprintln!("N = {n}: the run failed");
        }
    }
}

fn main() {
    if let Ok(n) = std::env::var("DIAGNOSE_SCALE_ACCURACY") {
        accuracy(n.parse().expect("a sample count"));
        return;
    }
    if let Ok(n) = std::env::var("DIAGNOSE_SCALE_N") {
        one(n.parse().expect("a sample count"));
        return;
    }
    if std::env::args().any(|a| a == "--memory") {
        memory();
        return;
    }
    criterion_1e6();
}
