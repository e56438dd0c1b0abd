//! Shared helpers of the diagnosis and CLI tests: a reference UDN written from NOTES.md (independent
//! of the library's), the paper's linear block, inputs and noise.
#![allow(dead_code)]

pub mod paper;

use hammerstein::StateSpace;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// UDN parameters; `None`/0 switches an effect off.
#[derive(Debug, Clone, Copy)]
pub struct Udn {
    pub p: f64,
    pub a: f64,
    pub b: f64,
    pub z1: f64,
    pub z2: f64,
    pub e1: f64,
    pub e2: f64,
}

impl Udn {
    pub fn linear(p: f64) -> Self {
        Udn {
            p,
            a: 0.0,
            b: 0.0,
            z1: f64::INFINITY,
            z2: f64::NEG_INFINITY,
            e1: 0.0,
            e2: 0.0,
        }
    }
    /// v = N(u) by the corrected piecewise definition of NOTES.md.
    pub fn eval(&self, u: &[f64]) -> Vec<f64> {
        let mut s = 1.0;
        if let Some(w) = u.windows(2).find(|w| w[1] != w[0]) {
            s = if w[1] > w[0] { 1.0 } else { -1.0 };
        }
        let mut out = Vec::with_capacity(u.len());
        for k in 0..u.len() {
            if k > 0 {
                if u[k] > u[k - 1] {
                    s = 1.0;
                } else if u[k] < u[k - 1] {
                    s = -1.0;
                }
            }
            let x = u[k] - self.a * s;
            let w = x.signum() * (x.abs() - self.b).max(0.0);
            let mut v = (self.p * w).clamp(self.p * self.z2, self.p * self.z1);
            if x > self.b {
                v += self.e1;
            }
            if x < -self.b {
                v += self.e2;
            }
            out.push(v);
        }
        out
    }
}

/// The paper's linear block (see `paper.rs`), re-exported for the tests that do not all use it.
#[allow(unused_imports)]
pub use paper::paper_block;

/// A slower second-order block: G(z) = z⁻¹ 0.3 (1 + 0.4 z⁻¹) / (1 − 1.2 z⁻¹ + 0.5 z⁻²).
pub fn slow_block() -> StateSpace<f64> {
    StateSpace::from_rows(
        &[&[1.2, 1.0], &[-0.5, 0.0]],
        &[&[0.3], &[0.12]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap()
}

/// Input kinds of the battery.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    Uniform,
    Smooth,
    Multisine,
}

impl InputKind {
    pub fn name(self) -> &'static str {
        match self {
            InputKind::Uniform => "uniform",
            InputKind::Smooth => "smooth",
            InputKind::Multisine => "multisine",
        }
    }
}

/// An input of length n in roughly [−amp, amp].
pub fn input(kind: InputKind, n: usize, amp: f64, seed: u64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    match kind {
        InputKind::Uniform => (0..n).map(|_| rng.random_range(-amp..amp)).collect(),
        InputKind::Smooth => {
            // second-order low-pass of uniform noise, rescaled to the amplitude
            let mut x1 = 0.0;
            let mut x2 = 0.0;
            let raw: Vec<f64> = (0..n + 100)
                .map(|_| {
                    x1 = 0.85 * x1 + rng.random_range(-1.0..1.0);
                    x2 = 0.6 * x2 + x1;
                    x2
                })
                .skip(100)
                .collect();
            let m = raw.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            raw.iter().map(|v| amp * v / m).collect()
        }
        InputKind::Multisine => {
            let nf = 40;
            let phases: Vec<f64> = (0..nf)
                .map(|_| rng.random_range(0.0..std::f64::consts::TAU))
                .collect();
            let raw: Vec<f64> = (0..n)
                .map(|k| {
                    (0..nf)
                        .map(|f| {
                            let w = std::f64::consts::TAU * (f + 1) as f64 * 3.0 / n as f64
                                * (1.0 + f as f64 * 0.37);
                            (w * k as f64 + phases[f]).sin()
                        })
                        .sum::<f64>()
                })
                .collect();
            let m = raw.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            raw.iter().map(|v| amp * v / m).collect()
        }
    }
}

/// y = G·v + white Gaussian noise at the given SNR (10·log10(var(y_clean)/var(noise))).
/// Returns (y, noise variance).
pub fn output(g: &StateSpace<f64>, v: &[f64], snr_db: f64, seed: u64) -> (Vec<f64>, f64) {
    let y0 = g.simulate_siso(v, None).unwrap();
    let m = y0.iter().sum::<f64>() / y0.len() as f64;
    let var = y0.iter().map(|y| (y - m).powi(2)).sum::<f64>() / y0.len() as f64;
    let nv = var / 10f64.powf(snr_db / 10.0);
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed);
    let nd = Normal::new(0.0, nv.sqrt()).unwrap();
    (y0.iter().map(|y| y + nd.sample(&mut rng)).collect(), nv)
}

/// Noise variance that makes a hidden effect raise the residual variance by `ratio` − 1: given the
/// clean output error energy of the effect `err_var`, noise = err_var / (ratio − 1).
pub fn noise_for_ratio(err_var: f64, ratio: f64) -> f64 {
    err_var / (ratio - 1.0)
}

/// Adds white Gaussian noise of variance `nv`.
pub fn add_noise(y0: &[f64], nv: f64, seed: u64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed ^ 0xabcd);
    let nd = Normal::new(0.0, nv.sqrt()).unwrap();
    y0.iter().map(|y| y + nd.sample(&mut rng)).collect()
}

/// A whole number from the environment variable `var` (a battery's size, a seed to inspect);
/// `default` when it is unset or not a number.
pub fn env_count(var: &str, default: u64) -> u64 {
    std::env::var(var)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The effect of a diagnosis' first suggestion, "none" when it suggests nothing.
pub fn top_effect(d: &hammerstein::diagnosis::Diagnosis<f64>) -> String {
    d.suggestions
        .first()
        .map_or("none".into(), |s| s.effect.to_string())
}

/// Prints a battery's text and appends it to the file `BATTERY_WRITE` names, when set.
pub fn publish_battery(text: &str) {
    println!("{text}");
    if let Ok(path) = std::env::var("BATTERY_WRITE") {
        let mut old = std::fs::read_to_string(&path).unwrap_or_default();
        old.push_str(text);
        std::fs::write(&path, old).unwrap();
    }
}

mod cli_io;
// each test uses some of them
#[allow(unused_imports)]
pub use cli_io::{entries, temp_dir, write_csv, write_train_val};
#[cfg(feature = "cli")]
#[allow(unused_imports)]
pub use cli_io::{run_cli, run_cli_outcome};
pub mod oversampled;
pub mod random_miso;
pub mod random_system;

/// `n` numbers uniform in [-1, 1) from a 64-bit LCG (Knuth's MMIX constants) seeded with `seed`:
/// records reproducible without a random-number crate.
pub fn lcg_uniform(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

/// The resonant second-order block of the feedback tests (poles 0.95·e^{±0.3j} in companion
/// form, y = x₁) with a static nonlinearity in its loop, simulated independently of the crate:
/// x⁺ = A x + B (N(u) + w), B = (1, 0.5)ᵀ, w = `loop_force`(x₁, x₂), N = `input_map`. Returns
/// the noise-free output.
pub fn resonant_loop(
    u: &[f64],
    input_map: impl Fn(f64) -> f64,
    loop_force: impl Fn(f64, f64) -> f64,
) -> Vec<f64> {
    let (a1, a2) = (2.0 * 0.95 * 0.3f64.cos(), -0.95 * 0.95);
    let (mut x1, mut x2) = (0.0f64, 0.0f64);
    let mut y = Vec::with_capacity(u.len());
    for &uk in u {
        let v = input_map(uk);
        let w = loop_force(x1, x2);
        y.push(x1);
        (x1, x2) = (a1 * x1 + x2 + v + w, a2 * x1 + 0.5 * (v + w));
    }
    y
}

/// A seeded record of [`resonant_loop`]: the input u⁺ = 0.7 u + `amp`·e (e uniform in
/// [−0.5, 0.5)), the output with uniform noise of RMS 0.01/√12; both from [`lcg_uniform`].
pub fn resonant_loop_record(
    n: usize,
    seed: u64,
    amp: f64,
    input_map: impl Fn(f64) -> f64,
    loop_force: impl Fn(f64, f64) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let e = lcg_uniform(
        2 * n,
        seed.wrapping_mul(2862933555777941757)
            .wrapping_add(3037000493),
    );
    let mut s = 0.0;
    let u: Vec<f64> = (0..n)
        .map(|k| {
            s = 0.7 * s + amp * (0.5 * e[2 * k]);
            s
        })
        .collect();
    let y = resonant_loop(&u, input_map, loop_force)
        .iter()
        .enumerate()
        .map(|(k, y)| y + 0.01 * (0.5 * e[2 * k + 1]))
        .collect();
    (u, y)
}
