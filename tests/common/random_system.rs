//! Random Hammerstein records for the batteries: a linear block of order 1–4 drawn at random
//! (lightly damped, slow, fast, anywhere in the disc, non-minimum-phase zeros), random UDN
//! parameters and effect subsets, four input kinds, SNR, length and output offset drawn at random.
//! Everything follows from one seed.
#![allow(dead_code)]

use super::{InputKind, Udn, input};
use hammerstein::StateSpace;
use hammerstein::regressors::{Effect, EffectSet};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// How the poles of a random block are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoleKind {
    /// A complex pair with radius 0.85–0.97 (resonant).
    LightlyDamped,
    /// Real poles 0.8–0.97 (slow).
    Slow,
    /// Poles of radius below 0.5 (fast).
    Fast,
    /// Anywhere in the disc of radius 0.95.
    Anywhere,
}

impl PoleKind {
    pub fn name(self) -> &'static str {
        match self {
            PoleKind::LightlyDamped => "lightly-damped",
            PoleKind::Slow => "slow",
            PoleKind::Fast => "fast",
            PoleKind::Anywhere => "anywhere",
        }
    }
}

/// Every input kind of the batteries, PRBS-like included.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Excitation {
    Base(InputKind),
    /// Random levels held for 1–20 samples.
    Prbs,
}

impl Excitation {
    pub fn name(self) -> &'static str {
        match self {
            Excitation::Base(k) => k.name(),
            Excitation::Prbs => "prbs",
        }
    }
    pub const ALL: [Excitation; 4] = [
        Excitation::Base(InputKind::Uniform),
        Excitation::Base(InputKind::Smooth),
        Excitation::Base(InputKind::Multisine),
        Excitation::Prbs,
    ];
}

/// One random record with its truth.
#[derive(Debug, Clone)]
pub struct RandomRecord {
    pub seed: u64,
    pub order: usize,
    pub poles: PoleKind,
    pub nmp_zero: bool,
    pub effects: EffectSet,
    pub truth: Udn,
    pub excitation: Excitation,
    pub snr_db: f64,
    pub n: usize,
    pub offset: f64,
    pub u: Vec<f64>,
    pub y: Vec<f64>,
    /// Variance of the added white output noise.
    pub noise_var: f64,
    pub block: StateSpace<f64>,
}

/// Ranges of a battery.
#[derive(Debug, Clone, Copy)]
pub struct Ranges {
    pub orders: (usize, usize),
    pub snr_db: (f64, f64),
    pub n: (usize, usize),
    /// Probability of each UDN effect being present.
    pub effect_prob: f64,
}

impl Default for Ranges {
    fn default() -> Self {
        Ranges {
            orders: (1, 4),
            snr_db: (15.0, 40.0),
            n: (1000, 5000),
            effect_prob: 0.5,
        }
    }
}

/// Polynomial product of monic factors given by roots (complex pairs given once, conjugate added).
fn poly_from_roots(real: &[f64], pairs: &[(f64, f64)]) -> Vec<f64> {
    let mut p = vec![1.0];
    let mul = |p: &Vec<f64>, f: &[f64]| {
        let mut out = vec![0.0; p.len() + f.len() - 1];
        for (i, a) in p.iter().enumerate() {
            for (j, b) in f.iter().enumerate() {
                out[i + j] += a * b;
            }
        }
        out
    };
    for &r in real {
        p = mul(&p, &[1.0, -r]);
    }
    for &(re, im) in pairs {
        p = mul(&p, &[1.0, -2.0 * re, re * re + im * im]);
    }
    p
}

/// A random strictly proper block of order n, scaled to unit H2 norm (impulse-response energy).
pub fn random_block(rng: &mut StdRng, n: usize, kind: PoleKind, nmp: bool) -> StateSpace<f64> {
    let mut real = Vec::new();
    let mut pairs = Vec::new();
    let mut left = n;
    while left > 0 {
        let pair = left >= 2
            && match kind {
                PoleKind::LightlyDamped => pairs.is_empty(),
                PoleKind::Slow => false,
                _ => rng.random_range(0.0..1.0) < 0.5,
            };
        let radius = match kind {
            PoleKind::LightlyDamped if pair => rng.random_range(0.85..0.97),
            PoleKind::LightlyDamped | PoleKind::Anywhere => rng.random_range(0.05..0.95),
            PoleKind::Slow => rng.random_range(0.8..0.97),
            PoleKind::Fast => rng.random_range(0.0..0.5),
        };
        if pair {
            let angle = rng.random_range(0.15..2.8);
            pairs.push((radius * f64::cos(angle), radius * f64::sin(angle)));
            left -= 2;
        } else {
            let sign = if kind == PoleKind::Slow || rng.random_range(0.0..1.0) < 0.75 {
                1.0
            } else {
                -1.0
            };
            real.push(sign * radius);
            left -= 1;
        }
    }
    let den = poly_from_roots(&real, &pairs);
    // numerator z⁻¹(b1 + b2 z⁻¹ + …), n coefficients; zeros real, one outside the circle if nmp
    let nz = n - 1;
    let mut zeros: Vec<f64> = (0..nz).map(|_| rng.random_range(-0.8..0.8)).collect();
    if nmp && nz > 0 {
        zeros[0] = if rng.random_range(0.0..1.0) < 0.5 {
            rng.random_range(1.3..3.0)
        } else {
            -rng.random_range(1.3..3.0)
        };
    }
    let num = poly_from_roots(&zeros, &[]);
    // observer canonical form: A = [−a | I; 0], B = b, C = e1ᵀ
    let a_rows: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if j == 0 {
                        -den[i + 1]
                    } else if j == i + 1 {
                        1.0
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let b_rows: Vec<Vec<f64>> = (0..n).map(|i| vec![num[i]]).collect();
    let c_row: Vec<f64> = (0..n).map(|j| if j == 0 { 1.0 } else { 0.0 }).collect();
    let ar: Vec<&[f64]> = a_rows.iter().map(|r| r.as_slice()).collect();
    let br: Vec<&[f64]> = b_rows.iter().map(|r| r.as_slice()).collect();
    let g = StateSpace::from_rows(&ar, &br, &[&c_row], &[&[0.0]]).unwrap();
    // unit H2 norm
    let mut imp = vec![0.0; 2000];
    imp[0] = 1.0;
    let h = g.simulate_siso(&imp, None).unwrap();
    let e: f64 = h.iter().map(|x| x * x).sum::<f64>().sqrt();
    let b_scaled: Vec<Vec<f64>> = (0..n).map(|i| vec![num[i] / e]).collect();
    let br: Vec<&[f64]> = b_scaled.iter().map(|r| r.as_slice()).collect();
    StateSpace::from_rows(&ar, &br, &[&c_row], &[&[0.0]]).unwrap()
}

/// A random UDN with `effects`, scaled to an input of amplitude `amp`.
pub fn random_udn(rng: &mut StdRng, effects: EffectSet, amp: f64) -> Udn {
    let p = rng.random_range(0.5..2.0);
    let mut t = Udn::linear(p);
    if effects.contains(Effect::Hysteresis) {
        t.a = amp * rng.random_range(0.05..0.25);
    }
    if effects.contains(Effect::DeadZone) {
        t.b = amp * rng.random_range(0.05..0.25);
    }
    if effects.contains(Effect::Saturation) {
        // limits reached by 10–40 % of an input that spans ±amp
        t.z1 = amp * rng.random_range(0.45..0.8);
        t.z2 = -amp * rng.random_range(0.45..0.8);
    }
    if effects.contains(Effect::Preload) {
        t.e1 = p * amp * rng.random_range(0.05..0.3);
        t.e2 = -p * amp * rng.random_range(0.05..0.3);
    }
    t
}

fn prbs(rng: &mut StdRng, n: usize, amp: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let level = rng.random_range(-amp..amp);
        let hold = rng.random_range(1..=20usize);
        for _ in 0..hold {
            out.push(level);
        }
    }
    out.truncate(n);
    out
}

/// `y0` plus `offset` plus white Gaussian noise at `snr_db` (relative to y0's variance), the
/// noise drawn from `rng`; returns the record and the noise variance.
pub fn noisy(y0: &[f64], snr_db: f64, offset: f64, rng: &mut StdRng) -> (Vec<f64>, f64) {
    let n = y0.len().max(1) as f64;
    let m = y0.iter().sum::<f64>() / n;
    let var = y0.iter().map(|y| (y - m).powi(2)).sum::<f64>() / n;
    let noise_var = var / 10f64.powf(snr_db / 10.0);
    let nd = Normal::new(0.0, noise_var.sqrt()).unwrap();
    let y = y0.iter().map(|y| y + offset + nd.sample(rng)).collect();
    (y, noise_var)
}

/// Draws one record from `seed`.
pub fn random_record(seed: u64, ranges: &Ranges) -> RandomRecord {
    let mut rng = StdRng::seed_from_u64(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x1234);
    let order = rng.random_range(ranges.orders.0..=ranges.orders.1);
    let poles = [
        PoleKind::LightlyDamped,
        PoleKind::Slow,
        PoleKind::Fast,
        PoleKind::Anywhere,
    ][rng.random_range(0..4usize)];
    let nmp_zero = order >= 2 && rng.random_range(0.0..1.0) < 0.25;
    let block = random_block(&mut rng, order, poles, nmp_zero);
    let mut effects = EffectSet::empty();
    for e in [
        Effect::Hysteresis,
        Effect::DeadZone,
        Effect::Saturation,
        Effect::Preload,
    ] {
        if rng.random_range(0.0..1.0) < ranges.effect_prob {
            effects = effects.with(e);
        }
    }
    let amp = 10f64.powf(rng.random_range(-0.5..0.7));
    let truth = random_udn(&mut rng, effects, amp);
    let excitation = Excitation::ALL[rng.random_range(0..4usize)];
    let snr_db = rng.random_range(ranges.snr_db.0..ranges.snr_db.1);
    let n = rng.random_range(ranges.n.0..=ranges.n.1);
    let offset = rng.random_range(-2.0..2.0);
    let u = match excitation {
        Excitation::Base(k) => input(k, n, amp, seed ^ 0x77),
        Excitation::Prbs => prbs(&mut rng, n, amp),
    };
    let v = truth.eval(&u);
    let y0 = block.simulate_siso(&v, None).unwrap();
    let (y, noise_var) = noisy(&y0, snr_db, offset, &mut rng);
    RandomRecord {
        seed,
        order,
        poles,
        nmp_zero,
        effects,
        truth,
        excitation,
        snr_db,
        n,
        offset,
        u,
        y,
        noise_var,
        block,
    }
}
