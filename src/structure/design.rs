//! Random-phase multisine experiments (Pintelon & Schoukens, *System Identification: A Frequency
//! Domain Approach*, 2nd ed. 2012, §3.4 and §4.3): a flat amplitude spectrum on the excited lines
//! of a period of `samples` samples, a uniformly random phase per line, scaled to each level's RMS.
//!
//! Full grid: every line of the band. Random odd: the odd lines of the band only, in groups of
//! `group` consecutive odd lines of which one, drawn at random, is left out as a detection line
//! for odd distortion; the even lines detect even distortion. The excited lines are drawn once
//! (all levels and realizations share them, so the best linear approximation can be averaged
//! over realizations); each (level, realization) gets its own phases. Every block is one
//! transient period followed by `periods` steady ones.

use super::record::{Block, Record};
use crate::error::{Error, Result};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

/// Which lines of the band a multisine excites.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MultisineKind {
    /// Every line of the band.
    Full,
    /// Odd lines only, one odd line per group of `group` left out at random.
    RandomOdd {
        /// Odd lines per group (one of them is the group's detection line); at least 2.
        group: usize,
    },
}

/// A multisine experiment: lines, levels, realizations and periods, seeded.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct MultisineDesign {
    /// Full grid or random odd.
    pub kind: MultisineKind,
    /// Samples per period N.
    pub samples: usize,
    /// Band edges as fractions of the sampling frequency, 0 < lo ≤ hi < 0.5.
    pub band: (f64, f64),
    /// RMS value of each level, increasing.
    pub levels: Vec<f64>,
    /// Realizations M per level (a new random phase each).
    pub realizations: usize,
    /// Steady periods P per block (one transient period comes before them).
    pub periods: usize,
    /// Seed of the line selection and the phases.
    pub seed: u64,
}

impl Default for MultisineDesign {
    fn default() -> Self {
        Self {
            kind: MultisineKind::RandomOdd { group: 4 },
            samples: 1024,
            band: (0.01, 0.2),
            levels: vec![0.25, 0.5, 1.0],
            realizations: 4,
            periods: 2,
            seed: 7,
        }
    }
}

impl MultisineDesign {
    /// Checks the design's numbers; the error says which one is wrong.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(m));
        if self.samples < 8 {
            return bad(format!(
                "--samples must be at least 8, got {}",
                self.samples
            ));
        }
        let (lo, hi) = self.band;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi && hi < 0.5) {
            return bad(format!(
                "--band must satisfy 0 < lo <= hi < 0.5 (fractions of the sampling frequency), got {lo},{hi}"
            ));
        }
        if self.levels.is_empty() {
            return bad("--levels needs at least one RMS value".into());
        }
        if self.levels.iter().any(|&l| !(l.is_finite() && l > 0.0)) {
            return bad(format!(
                "--levels must be positive RMS values, got {:?}",
                self.levels
            ));
        }
        if self.levels.windows(2).any(|w| w[1] <= w[0]) {
            return bad(format!("--levels must increase, got {:?}", self.levels));
        }
        if self.realizations == 0 || self.periods == 0 {
            return bad("--realizations and --periods must be at least 1".into());
        }
        if let MultisineKind::RandomOdd { group } = self.kind
            && group < 2
        {
            return bad(format!("--group must be at least 2, got {group}"));
        }
        if self.excited_lines().is_empty() {
            return bad(format!(
                "the band {lo},{hi} holds no excitable line for {} samples per period \
                 (line spacing 1/{} of the sampling frequency)",
                self.samples, self.samples
            ));
        }
        Ok(())
    }

    /// Lines of the band `k` (frequency k/N of the sampling frequency), before the random-odd
    /// selection.
    fn band_lines(&self) -> Vec<usize> {
        let n = self.samples as f64;
        let lo = (self.band.0 * n).ceil().max(1.0) as usize;
        let hi = ((self.band.1 * n).floor() as usize).min((self.samples - 1) / 2);
        (lo..=hi).collect()
    }

    /// The excited lines, drawn from the seed (the same for every level and realization).
    pub fn excited_lines(&self) -> Vec<usize> {
        let lines = self.band_lines();
        match self.kind {
            MultisineKind::Full => lines,
            MultisineKind::RandomOdd { group } => {
                let odd: Vec<usize> = lines.into_iter().filter(|k| k % 2 == 1).collect();
                let mut rng = StdRng::seed_from_u64(self.seed ^ 0x5eed_11e5);
                let mut out = Vec::with_capacity(odd.len());
                for chunk in odd.chunks(group.max(2)) {
                    // a group too short to spare a line keeps them all
                    let skip = if chunk.len() == group {
                        rng.random_range(0..chunk.len())
                    } else {
                        usize::MAX
                    };
                    out.extend(
                        chunk
                            .iter()
                            .enumerate()
                            .filter(|(i, _)| *i != skip)
                            .map(|(_, &k)| k),
                    );
                }
                out
            }
        }
    }

    /// The record of inputs (no output yet): per level, per realization, `periods + 1` periods.
    pub fn generate(&self) -> Result<Record> {
        self.validate()?;
        let n = self.samples;
        let lines = self.excited_lines();
        let mut planner = RealFftPlanner::<f64>::new();
        let ifft = planner.plan_fft_inverse(n);
        let mut rng = StdRng::seed_from_u64(self.seed);
        let mut blocks = Vec::with_capacity(self.levels.len() * self.realizations);
        for (level, &rms) in self.levels.iter().enumerate() {
            for realization in 0..self.realizations {
                let mut spec = vec![Complex::new(0.0, 0.0); n / 2 + 1];
                for &k in &lines {
                    let phi = rng.random_range(0.0..std::f64::consts::TAU);
                    spec[k] = Complex::from_polar(1.0, phi);
                }
                let mut period = vec![0.0; n];
                ifft.process(&mut spec, &mut period)
                    .map_err(|e| Error::LinAlg(format!("inverse FFT: {e}")))?;
                let r = (period.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
                period.iter_mut().for_each(|v| *v *= rms / r);
                let u: Vec<f64> = (0..=self.periods)
                    .flat_map(|_| period.iter().copied())
                    .collect();
                blocks.push(Block {
                    level,
                    realization,
                    u,
                    y: None,
                });
            }
        }
        Record::new(n, blocks)
    }
}
