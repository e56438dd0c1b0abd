//! Random block-oriented plants for the structure tests: second-order blocks, polynomial static
//! nonlinearities, six families; a plant replays a design's record with output noise at a given SNR.
#![allow(dead_code)]

use hammerstein::structure::{Block, MultisineDesign, MultisineKind, Record, Verdict};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// A second-order discrete block b(z⁻¹)/a(z⁻¹) with unit DC gain.
#[derive(Debug, Clone)]
pub struct Iir {
    pub b: [f64; 3],
    pub a: [f64; 3],
}

impl Iir {
    /// Random: poles r·e^{±jθ} with r in [0.6, 0.93], θ/2π in [0.03, 0.17]; numerator
    /// 1 + β₁z⁻¹ + β₂z⁻² (or z⁻¹(1 + β₁z⁻¹) when `delayed`), β in ±0.5.
    pub fn random(rng: &mut StdRng, delayed: bool) -> Self {
        let r: f64 = rng.random_range(0.6..0.93);
        let th = std::f64::consts::TAU * rng.random_range(0.03..0.17);
        let a = [1.0, -2.0 * r * th.cos(), r * r];
        let (b1, b2): (f64, f64) = (rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
        let mut b = if delayed {
            [0.0, 1.0, b1]
        } else {
            [1.0, b1, b2]
        };
        let dc = (b[0] + b[1] + b[2]) / (a[0] + a[1] + a[2]);
        b.iter_mut().for_each(|v| *v /= dc);
        Self { b, a }
    }

    pub fn filter(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for t in 0..x.len() {
            let mut v = self.b[0] * x[t];
            if t >= 1 {
                v += self.b[1] * x[t - 1] - self.a[1] * y[t - 1];
            }
            if t >= 2 {
                v += self.b[2] * x[t - 2] - self.a[2] * y[t - 2];
            }
            y[t] = v;
        }
        y
    }
}

/// x + s·(c₂x²/σ + c₃x³/σ²): σ the RMS at the nonlinearity's input at the top level.
#[derive(Debug, Clone, Copy)]
pub struct Poly {
    pub c2: f64,
    pub c3: f64,
    pub sigma: f64,
}

impl Poly {
    pub fn random(rng: &mut StdRng, strength: f64, hardening: bool) -> Self {
        let c3 = rng.random_range(0.2..0.5)
            * if hardening || rng.random_bool(0.5) {
                1.0
            } else {
                -1.0
            };
        let c2 = if rng.random_bool(0.5) {
            rng.random_range(-0.4..0.4)
        } else {
            0.0
        };
        Self {
            c2: strength * c2,
            c3: strength * c3 * if hardening { 1.0 } else { 0.6 },
            sigma: 1.0,
        }
    }
    pub fn apply(&self, x: f64) -> f64 {
        let z = x / self.sigma;
        x + self.sigma * (self.c2 * z * z + self.c3 * z * z * z)
    }
    /// The nonlinear part only (for the feedback loop).
    pub fn nonlinear(&self, x: f64) -> f64 {
        self.apply(x) - x
    }
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// The six families of the battery.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    Linear,
    Hammerstein,
    Wiener,
    WienerHammerstein,
    Parallel,
    Feedback,
}

impl Family {
    pub const ALL: [Family; 6] = [
        Family::Linear,
        Family::Hammerstein,
        Family::Wiener,
        Family::WienerHammerstein,
        Family::Parallel,
        Family::Feedback,
    ];
    pub fn expected(self) -> Verdict {
        match self {
            Family::Linear => Verdict::Linear,
            Family::Hammerstein | Family::Wiener | Family::WienerHammerstein => {
                Verdict::SingleBranch
            }
            Family::Parallel => Verdict::Parallel,
            Family::Feedback => Verdict::Feedback,
        }
    }
}

/// A random plant of a family.
#[derive(Debug, Clone)]
pub struct Plant {
    pub family: Family,
    pub g1: Iir,
    pub g2: Iir,
    pub f: Poly,
}

impl Plant {
    /// A random plant; `strength` scales the nonlinearity (1 at 40 dB, 0.25 at 20 dB in the
    /// battery); `top_rms` the input RMS of the highest level (σ of the nonlinearity is set there).
    pub fn random(family: Family, rng: &mut StdRng, strength: f64, top_rms: f64) -> Self {
        let delayed = family == Family::Feedback;
        let g1 = Iir::random(rng, delayed);
        let g2 = Iir::random(rng, false);
        let mut f = Poly::random(rng, strength, family == Family::Feedback);
        // σ of the nonlinearity's input at the top level, from a white-noise proxy of that RMS
        let mut nrng = StdRng::seed_from_u64(rng.random());
        let n = Normal::new(0.0, top_rms).unwrap();
        let u: Vec<f64> = (0..4096).map(|_| n.sample(&mut nrng)).collect();
        f.sigma = match family {
            Family::Linear | Family::Hammerstein | Family::Parallel => top_rms,
            Family::Wiener | Family::WienerHammerstein | Family::Feedback => rms(&g1.filter(&u)),
        };
        if family == Family::Feedback {
            // the loop's nonlinearity: 2·c₃ of hardening, no linear feedback
            f.c2 = 0.0;
            f.c3 *= 2.0;
        }
        Self { family, g1, g2, f }
    }

    /// Noise-free response to an input.
    pub fn respond(&self, u: &[f64]) -> Vec<f64> {
        let f = self.f;
        match self.family {
            Family::Linear => self.g1.filter(u),
            Family::Hammerstein => {
                let x: Vec<f64> = u.iter().map(|&v| f.apply(v)).collect();
                self.g1.filter(&x)
            }
            Family::Wiener => self.g1.filter(u).iter().map(|&v| f.apply(v)).collect(),
            Family::WienerHammerstein => {
                let x: Vec<f64> = self.g1.filter(u).iter().map(|&v| f.apply(v)).collect();
                self.g2.filter(&x)
            }
            Family::Parallel => {
                let y1 = self.g1.filter(u);
                let x: Vec<f64> = u.iter().map(|&v| f.nonlinear(v) * 3.0).collect();
                let y2 = self.g2.filter(&x);
                y1.iter().zip(&y2).map(|(a, b)| a + b).collect()
            }
            Family::Feedback => {
                // y = G1 (u − g(y)), G1 strictly proper
                let (b, a) = (self.g1.b, self.g1.a);
                let mut y = vec![0.0; u.len()];
                let mut e = vec![0.0; u.len()];
                for t in 0..u.len() {
                    let mut v = 0.0;
                    if t >= 1 {
                        v += b[1] * e[t - 1] - a[1] * y[t - 1];
                    }
                    if t >= 2 {
                        v += b[2] * e[t - 2] - a[2] * y[t - 2];
                    }
                    y[t] = v;
                    e[t] = u[t] - f.nonlinear(y[t]);
                }
                y
            }
        }
    }
}

/// The battery's experiment: random odd, 1024 samples, band 0.01–0.2, levels 0.25/0.5/1, four
/// realizations of two steady periods.
pub fn battery_design(seed: u64) -> MultisineDesign {
    MultisineDesign {
        kind: MultisineKind::RandomOdd { group: 4 },
        samples: 1024,
        band: (0.01, 0.2),
        levels: vec![0.25, 0.5, 1.0],
        realizations: 4,
        periods: 2,
        seed,
    }
}

/// The design's record replayed on the plant with white output noise at `snr_db` (per level,
/// relative to that level's noise-free output RMS).
pub fn replay(design: &Record, plant: &Plant, snr_db: f64, seed: u64) -> Option<Record> {
    let mut rng = StdRng::seed_from_u64(seed);
    let clean: Vec<Vec<f64>> = design
        .blocks()
        .iter()
        .map(|b| plant.respond(&b.u))
        .collect();
    if clean
        .iter()
        .flatten()
        .any(|v| !v.is_finite() || v.abs() > 1e6)
    {
        return None;
    }
    let levels = design.levels();
    let level_rms: Vec<f64> = (0..levels)
        .map(|l| {
            let ys: Vec<f64> = design
                .blocks()
                .iter()
                .zip(&clean)
                .filter(|(b, _)| b.level == l)
                .flat_map(|(_, y)| y.iter().copied())
                .collect();
            rms(&ys)
        })
        .collect();
    let mut i = 0;
    design
        .replayed(|b: &Block| {
            let sd = level_rms[b.level] * 10f64.powf(-snr_db / 20.0);
            let n = Normal::new(0.0, sd.max(1e-300)).unwrap();
            let y = clean[i].iter().map(|v| v + n.sample(&mut rng)).collect();
            i += 1;
            y
        })
        .ok()
}
