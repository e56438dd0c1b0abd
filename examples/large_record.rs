//! Writes a long synthetic record (CSV with columns u, y) for the scale benchmark of `diagnose`:
//! the paper's linear block after a saturation + hysteresis UDN, uniform input, 25 dB output noise;
//! or, with a fourth argument `steps-sine`, random steps plus a sine through a saturation into the
//! same second-order block, 25 dB output noise.
//!
//! `cargo run --release --example large_record -- N SEED PATH [steps-sine]`

use hammerstein::StateSpace;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::io::Write;

/// The record (u, y) of `n` samples drawn with `seed`.
fn record(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let g = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .expect("a valid state-space model");
    let mut rng = StdRng::seed_from_u64(seed);
    let u: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
    let mut s = 1.0;
    let v: Vec<f64> = (0..n)
        .map(|k| {
            if k > 0 && u[k] != u[k - 1] {
                s = if u[k] > u[k - 1] { 1.0 } else { -1.0 };
            }
            (2.0 * (u[k] - 0.3 * s)).clamp(-2.0, 3.0)
        })
        .collect();
    let y0 = g.simulate_siso(&v, None).expect("a stable simulation");
    let var = y0.iter().map(|y| y * y).sum::<f64>() / n as f64;
    let noise = Normal::new(0.0, (var / 10f64.powf(2.5)).sqrt()).expect("a positive deviation");
    let y = y0.iter().map(|y| y + noise.sample(&mut rng)).collect();
    (u, y)
}

/// The record (u, y) of `n` samples drawn with `seed`: random steps (a new level, uniform in
/// [−2, 2], with probability 1/50 at each sample) plus a sine of amplitude 1 and period 400
/// samples, through a saturation at ±1.5 into the paper's second-order block, 25 dB.
fn steps_sine(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
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
    let y0 = g.simulate_siso(&v, None).expect("a stable simulation");
    let var = y0.iter().map(|y| y * y).sum::<f64>() / n as f64;
    let noise = Normal::new(0.0, (var / 10f64.powf(2.5)).sqrt()).expect("a positive deviation");
    let y = y0.iter().map(|y| y + noise.sample(&mut rng)).collect();
    (u, y)
}

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let path = args.get(3).cloned().unwrap_or_else(|| "large.csv".into());
    let (u, y) = match args.get(4).map(String::as_str) {
        Some("steps-sine") => steps_sine(n, seed),
        _ => record(n, seed),
    };
    let mut w = std::io::BufWriter::new(std::fs::File::create(&path)?);
    writeln!(w, "u,y")?;
    for (a, b) in u.iter().zip(&y) {
        writeln!(w, "{a},{b}")?;
    }
    w.flush()
}
