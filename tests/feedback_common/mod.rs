//! Shared pieces of the feedback tests (the batteries `tests/feedback_battery.rs`,
//! `tests/diagnosis_feedback_battery.rs`, and `tests/feedback*.rs`): the kinds of feedback
//! nonlinearity drawn, the random block, its simulation with the nonlinearity in the loop, the
//! inputs and the noise.
#![allow(dead_code)]

use rand::{RngExt, rngs::StdRng};

/// The nonlinearity in the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Truth {
    /// A cubic stiffness on the output.
    Stiffness,
    /// Coulomb plus viscous friction on the velocity (the output's difference).
    Friction,
    /// A clearance (dead-zone) on the output.
    Clearance,
}

impl Truth {
    /// The `--feedback-nonlinearity X --feedback-on Y` of the truth.
    pub fn command(self) -> &'static str {
        match self {
            Truth::Stiffness => "--feedback-nonlinearity poly3 --feedback-on output",
            Truth::Friction => "--feedback-nonlinearity coulomb --feedback-on velocity",
            Truth::Clearance => "--feedback-nonlinearity dead-zone --feedback-on output",
        }
    }
}

/// The block's denominator a(z) = zⁿ + a1 zⁿ⁻¹ + … from a random resonance (and a real pole
/// for order 3).
pub fn denominator(rng: &mut StdRng, order: usize) -> Vec<f64> {
    let r = rng.random_range(0.85..0.97);
    let th = rng.random_range(0.1..0.6);
    let mut a = vec![1.0, -2.0 * r * f64::cos(th), r * r];
    if order == 3 {
        let p = rng.random_range(0.3..0.8);
        a = vec![1.0, a[1] - p, a[2] - p * a[1], -p * a[2]];
    }
    a
}

/// Simulates x+ = A x + B (u + w), y = x₁ (observer companion form), w = f(z), z = y or its
/// first difference.
pub fn simulate(
    a: &[f64],
    b: &[f64],
    u: &[f64],
    f: &dyn Fn(f64) -> f64,
    velocity: bool,
) -> Vec<f64> {
    let n = a.len() - 1;
    let mut x = vec![0.0; n];
    let mut prev = 0.0;
    let mut y = Vec::with_capacity(u.len());
    for &uk in u {
        let cx = x[0];
        let z = if velocity { cx - prev } else { cx };
        let v = uk + f(z);
        y.push(cx);
        prev = cx;
        x = (0..n)
            .map(|i| -a[i + 1] * x[0] + if i + 1 < n { x[i + 1] } else { 0.0 } + b[i] * v)
            .collect();
    }
    y
}

/// White noise through a random first-order low-pass filter (pole in [0, 0.8)).
pub fn input(rng: &mut StdRng, n: usize) -> Vec<f64> {
    let pole = rng.random_range(0.0..0.8);
    let mut s = 0.0;
    (0..n)
        .map(|_| {
            s = pole * s + rng.random_range(-1.0..1.0);
            s
        })
        .collect()
}

/// An approximately standard normal number (the sum of 12 uniforms, less 6).
pub fn gauss(rng: &mut StdRng) -> f64 {
    (0..12).map(|_| rng.random_range(0.0..1.0)).sum::<f64>() - 6.0
}

/// The root mean square about the mean.
pub fn rms(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
}

/// Filtered uniform noise: s⁺ = 0.7 s + e, e uniform in [−1, 1), scaled by `amp`.
pub fn filtered_noise(n: usize, rng: &mut StdRng, amp: f64) -> Vec<f64> {
    let mut s = 0.0;
    (0..n)
        .map(|_| {
            s = 0.7 * s + rng.random_range(-1.0..1.0);
            amp * s
        })
        .collect()
}

/// y plus white noise at `snr_db` below y's mean square ([`gauss`]: nearly Gaussian); returns
/// the noise variance.
pub fn add_noise(y: &[f64], snr_db: f64, rng: &mut StdRng) -> (Vec<f64>, f64) {
    let p = y.iter().map(|v| v * v).sum::<f64>() / y.len() as f64;
    let sd = (p / 10f64.powf(snr_db / 10.0)).sqrt();
    (y.iter().map(|v| v + sd * gauss(rng)).collect(), sd * sd)
}
