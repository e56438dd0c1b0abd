//! Decimation of an oversampled record ([`IoData::decimate`]): every K-th sample kept, the
//! outputs low-pass filtered first (zero-phase FIR, in stages), the inputs taken as they are.
//!
//! Why the inputs are not filtered: a Hammerstein model's nonlinearity acts on the input's own
//! values. A low-pass input would be another input to it (a held step becomes a ramp that a
//! dead-zone or a hysteresis sees otherwise), while the input of an oversampled record changes
//! little between two kept samples, or is held (a PRBS), which keeping every K-th sample
//! preserves exactly. The outputs carry the measurement noise, whose band above the new Nyquist
//! frequency would otherwise fold into the kept samples: they are filtered, with unit gain at 0
//! (offsets and drifts kept) and no phase shift (no delay added between input and output).
//!
//! The filter: windowed sinc with a Kaiser window of β = [`KAISER_BETA`] (80 dB stopband, ripple
//! 1e-4: the Kaiser design formulas of Oppenheim & Schafer, *Discrete-Time Signal Processing*,
//! 3rd ed., §7.6), half-length [`HALF_TAPS_PER_FACTOR`]·k taps (a transition band of 0.21/k
//! cycles per sample), cutoff [`CUTOFF`] of the stage's new Nyquist frequency (MATLAB's
//! `decimate` puts its filter's edge at 0.8 too): flat to 0.59 of the new Nyquist frequency, 80
//! dB down from just above it. Factors above [`STAGE_MAX`] are split into stages (as MATLAB
//! advises for factors above 13), each filter evaluated only at the samples it keeps:
//! O(N·HALF_TAPS_PER_FACTOR) per stage. The record's ends are extended by odd reflection about
//! the end values (as SciPy's and MATLAB's `filtfilt` do), which a straight line passes through
//! unchanged.
//!
//! [`suggested_factor`] is the factor a fitted block's band allows (what `fit` and `diagnose`
//! print as "oversampled: … --decimate K").

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::statespace::StateSpace;
use faer::Mat;

/// Largest factor of one stage (a prime factor above it is a stage of its own).
pub const STAGE_MAX: usize = 10;
/// Half-length of a stage's filter in multiples of its factor.
pub const HALF_TAPS_PER_FACTOR: usize = 12;
/// The Kaiser window's β: 0.1102·(A − 8.7) for a stopband of A = 80 dB.
pub const KAISER_BETA: f64 = 0.1102 * (80.0 - 8.7);
/// A stage's cutoff as a fraction of its output's Nyquist frequency.
pub const CUTOFF: f64 = 0.8;

/// The stages of a decimation by `factor`: its prime factors, largest first, multiplied
/// together while the product stays within [`STAGE_MAX`] (500 → [10, 10, 5]; 1 → none).
pub fn stages(factor: usize) -> Vec<usize> {
    let mut primes = Vec::new();
    let mut k = factor;
    let mut p = 2;
    while k > 1 && p * p <= k {
        while k.is_multiple_of(p) {
            primes.push(p);
            k /= p;
        }
        p += 1;
    }
    if k > 1 {
        primes.push(k);
    }
    primes.sort_unstable_by(|a, b| b.cmp(a));
    // first fit of the largest primes: each prime joins the first stage it fits into
    let mut out: Vec<usize> = Vec::new();
    for p in primes {
        match out.iter_mut().find(|s| **s * p <= STAGE_MAX) {
            Some(s) => *s *= p,
            None => out.push(p),
        }
    }
    out.sort_unstable_by(|a, b| b.cmp(a));
    out
}

/// The taps h[0..=2M] (M = [`HALF_TAPS_PER_FACTOR`]·k, centre at M) of one stage's low-pass
/// filter for factor `k`: windowed sinc, Kaiser window ([`KAISER_BETA`]), cutoff [`CUTOFF`]/(2k)
/// cycles per sample, scaled to unit gain at frequency 0.
pub fn lowpass_taps(k: usize) -> Vec<f64> {
    let m = HALF_TAPS_PER_FACTOR * k;
    let fc = CUTOFF * 0.5 / k as f64;
    let mut h: Vec<f64> = (0..=2 * m)
        .map(|i| {
            let n = i as f64 - m as f64;
            let sinc = if n == 0.0 {
                2.0 * fc
            } else {
                (2.0 * std::f64::consts::PI * fc * n).sin() / (std::f64::consts::PI * n)
            };
            let r = n / m as f64;
            let w = bessel_i0(KAISER_BETA * (1.0 - r * r).max(0.0).sqrt()) / bessel_i0(KAISER_BETA);
            sinc * w
        })
        .collect();
    let sum: f64 = h.iter().sum();
    h.iter_mut().for_each(|x| *x /= sum);
    h
}

/// The modified Bessel function of the first kind of order 0 (its power series, summed until
/// a term no longer changes the sum; the Kaiser window's β ≤ 20 needs about 30 terms).
fn bessel_i0(x: f64) -> f64 {
    let (mut sum, mut term, mut k) = (1.0, 1.0, 1.0);
    loop {
        term *= (x / (2.0 * k)) * (x / (2.0 * k));
        if term < sum * f64::EPSILON {
            return sum + term;
        }
        sum += term;
        k += 1.0;
    }
}

/// Sample `j` of `x` extended by odd reflection about its end values (2·x₀ − x₋ⱼ before the
/// start, 2·x_{N−1} − x_{2(N−1)−j} after the end; clamped to the record when the reflection
/// would leave it, on records shorter than the filter).
fn extended(x: &[f64], j: isize) -> f64 {
    let last = x.len() as isize - 1;
    if j < 0 {
        2.0 * x[0] - x[(-j).min(last) as usize]
    } else if j > last {
        2.0 * x[last as usize] - x[(2 * last - j).max(0) as usize]
    } else {
        x[j as usize]
    }
}

/// One stage: `x` filtered by [`lowpass_taps`]`(k)` (zero phase: centred) at samples 0, k, 2k, …
fn filter_stage(x: &[f64], k: usize) -> Vec<f64> {
    let h = lowpass_taps(k);
    let m = (h.len() / 2) as isize;
    let n = x.len();
    (0..n.div_ceil(k))
        .map(|o| {
            let c = (o * k) as isize;
            // the interior without the reflection's branches
            if c >= m && c + m < n as isize {
                let s = &x[(c - m) as usize..=(c + m) as usize];
                s.iter().zip(&h).map(|(a, b)| a * b).sum()
            } else {
                h.iter()
                    .enumerate()
                    .map(|(i, w)| w * extended(x, c - m + i as isize))
                    .sum()
            }
        })
        .collect()
}

/// `x` low-pass filtered and decimated by `factor` (the stages of [`stages`]): its samples 0,
/// factor, 2·factor, … of the filtered signal.
pub fn decimate_filtered(x: &[f64], factor: usize) -> Vec<f64> {
    let mut out = x.to_vec();
    for k in stages(factor) {
        out = filter_stage(&out, k);
    }
    out
}

/// Samples 0, `factor`, 2·`factor`, … of `x`, unfiltered (a held or slowly varying input).
pub fn pick<T: Copy>(x: &[T], factor: usize) -> Vec<T> {
    x.iter().step_by(factor.max(1)).copied().collect()
}

/// The level, relative to the block's largest gain, that bounds its band for
/// [`suggested_factor`] (−20 dB).
pub const SUGGEST_LEVEL: f64 = 0.1;
/// How many times the block's band the decimated Nyquist frequency keeps for
/// [`suggested_factor`].
pub const SUGGEST_MARGIN: f64 = 2.0;
/// Fewest samples a decimated record keeps for [`suggested_factor`].
pub const SUGGEST_MIN_SAMPLES: usize = 1000;
/// Points of the logarithmic frequency grid (10⁻⁶·π … π) [`suggested_factor`] evaluates.
const SUGGEST_GRID: usize = 600;

/// The decimation factor an `n`-sample record fitted by the block `g` (one output; with several
/// inputs the widest of their bands counts) allows, from
/// the 1-2-5 series: the largest K whose decimated Nyquist frequency π/K is at least
/// [`SUGGEST_MARGIN`] times the block's band (the highest frequency, on a logarithmic grid, at
/// which |G(e^{jω})| reaches [`SUGGEST_LEVEL`] of its largest value) and that keeps at least
/// [`SUGGEST_MIN_SAMPLES`] samples; `None` below 5 (not worth decimating) or when the response
/// cannot be evaluated. The band is read from the gain, not the poles: a fitted block's fast
/// poles of negligible residue (fitted noise) do not hold it back.
pub fn suggested_factor<T: Real>(g: &StateSpace<T>, n: usize) -> Option<usize> {
    if g.order() == 0 || g.n_outputs() != 1 {
        return None;
    }
    let pi = std::f64::consts::PI;
    let omegas: Vec<f64> = (0..SUGGEST_GRID)
        .map(|i| pi * 10f64.powf(-6.0 * (1.0 - i as f64 / (SUGGEST_GRID - 1) as f64)))
        .collect();
    // several inputs: the widest of their bands
    let mut band = 0.0_f64;
    for j in 0..g.n_inputs() {
        let gains: Vec<f64> = g
            .frequency_response(j, 0, &omegas)
            .ok()?
            .into_iter()
            .map(|(re, im)| re.hypot(im))
            .collect();
        let peak = gains.iter().copied().fold(0.0_f64, f64::max);
        if !(peak.is_finite() && peak > 0.0) {
            return None;
        }
        band = omegas
            .iter()
            .zip(&gains)
            .filter(|(_, g)| **g >= SUGGEST_LEVEL * peak)
            .map(|(w, _)| *w)
            .fold(band, f64::max);
    }
    let by_band = pi / (SUGGEST_MARGIN * band);
    let by_length = (n / SUGGEST_MIN_SAMPLES) as f64;
    let limit = by_band.min(by_length);
    // the largest of 1, 2, 5, 10, 20, 50, … within the limit
    let mut best = None;
    let mut decade = 1_usize;
    'series: loop {
        for m in [1, 2, 5] {
            let Some(k) = decade.checked_mul(m) else {
                break 'series;
            };
            if k as f64 > limit {
                break 'series;
            }
            best = Some(k);
        }
        match decade.checked_mul(10) {
            Some(d) => decade = d,
            None => break,
        }
    }
    best.filter(|&k| k >= 5)
}

impl<T: Real> IoData<T> {
    /// The record decimated by `factor` (every `factor`-th sample kept from the first; sample
    /// time × `factor`): its outputs low-pass filtered before (zero-phase FIR, unit gain at 0),
    /// its inputs kept as they are (see the module's text). `factor` 1 gives the record as it is.
    pub fn decimate(&self, factor: usize) -> Result<Self> {
        if factor == 0 {
            return Err(Error::InvalidParameter(
                "decimation factor 0: give a whole number ≥ 1".into(),
            ));
        }
        if factor == 1 {
            return Ok(self.clone());
        }
        let n = self.len();
        let kept = n.div_ceil(factor);
        if kept < 2 {
            // no record holds factor + 1 samples when that overflows
            return Err(match factor.checked_add(1) {
                Some(needed) => Error::TooFewSamples {
                    needed,
                    got: n,
                    reason: format!("decimating by {factor} (two samples must remain)"),
                },
                None => Error::InvalidParameter(format!(
                    "decimation factor {factor} leaves one sample of any record (two must \
                     remain): give a factor below the record's length"
                )),
            });
        }
        let u = Mat::from_fn(kept, self.n_inputs(), |i, j| self.u()[(i * factor, j)]);
        let ys: Vec<Vec<f64>> = (0..self.n_outputs())
            .map(|j| {
                let y: Vec<f64> = self.output_slice(j).iter().map(|v| v.as_f64()).collect();
                decimate_filtered(&y, factor)
            })
            .collect();
        let y = Mat::from_fn(kept, self.n_outputs(), |i, j| T::lit(ys[j][i]));
        let ts = self.sample_time() * factor as f64;
        IoData::with_names(
            u,
            y,
            self.input_names().to_vec(),
            self.output_names().to_vec(),
        )
        .and_then(|d| d.with_sample_time(ts))
        .map_err(|e| match e {
            // the record was valid: what is constant now, the decimation made so
            Error::ConstantInput { name } | Error::ConstantOutput { name } => {
                Error::InvalidParameter(format!(
                    "decimating by {factor} leaves '{name}' constant ({kept} samples kept of \
                     {n}): choose a smaller factor"
                ))
            }
            e => e,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bessel_i0_matches_known_values() {
        // Abramowitz & Stegun, table 9.8: I0(1) = 1.266065878, I0(5) = 27.23987182
        assert!((bessel_i0(0.0) - 1.0).abs() < 1e-15);
        assert!((bessel_i0(1.0) - 1.266_065_878).abs() < 1e-9);
        assert!((bessel_i0(5.0) - 27.239_871_82).abs() < 1e-7);
    }

    #[test]
    fn stages_split_the_factor_within_the_stage_limit() {
        assert_eq!(stages(1), Vec::<usize>::new());
        assert_eq!(stages(7), vec![7]);
        assert_eq!(stages(10), vec![10]);
        assert_eq!(stages(12), vec![6, 2]);
        assert_eq!(stages(13), vec![13]);
        assert_eq!(stages(500), vec![10, 10, 5]);
        for k in 1..200 {
            let s = stages(k);
            assert_eq!(s.iter().product::<usize>(), k, "{k}");
        }
    }

    #[test]
    fn taps_are_symmetric_with_unit_gain_at_zero() {
        for k in [2, 5, 10, 13] {
            let h = lowpass_taps(k);
            assert_eq!(h.len(), 2 * HALF_TAPS_PER_FACTOR * k + 1);
            assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for i in 0..h.len() {
                assert!((h[i] - h[h.len() - 1 - i]).abs() < 1e-16);
            }
        }
    }

    /// Gain of the whole decimation at `f` cycles per sample of the input rate: a sine through
    /// it, amplitude and phase read from the kept samples away from the ends.
    fn through(f: f64, factor: usize) -> (f64, f64) {
        let n = 40_000;
        let x: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 + 0.3).sin())
            .collect();
        let d = decimate_filtered(&x, factor);
        let mid = d.len() / 4..3 * d.len() / 4;
        let (mut err, mut amp) = (0.0_f64, 0.0_f64);
        for o in mid {
            err = err.max((d[o] - x[o * factor]).abs());
            amp = amp.max(d[o].abs());
        }
        (amp, err)
    }

    #[test]
    fn passes_the_band_without_phase_and_stops_above_the_new_nyquist() {
        for factor in [2, 5, 10, 50] {
            // a sine at a quarter of the new Nyquist frequency: the same samples
            let (_, err) = through(0.25 * 0.5 / factor as f64, factor);
            assert!(err < 5e-4, "factor {factor}: passband error {err}");
            // a sine above the new Nyquist frequency folds in 70 dB down at most
            let (amp, _) = through(0.6 / factor as f64, factor);
            assert!(amp < 3e-4, "factor {factor}: alias amplitude {amp}");
        }
    }

    #[test]
    fn straight_lines_pass_unchanged_to_the_ends() {
        let x: Vec<f64> = (0..997).map(|i| 3.0 - 0.01 * i as f64).collect();
        for factor in [3, 10, 40] {
            let d = decimate_filtered(&x, factor);
            assert_eq!(d.len(), 997_usize.div_ceil(factor));
            for (o, v) in d.iter().enumerate() {
                assert!((v - x[o * factor]).abs() < 1e-11, "factor {factor} at {o}");
            }
        }
    }

    #[test]
    fn the_record_keeps_its_inputs_and_multiplies_its_sample_time() {
        let n = 1003;
        let u = Mat::from_fn(n, 1, |i, _| ((i / 7) % 3) as f64 - 1.0);
        let y = Mat::from_fn(n, 1, |i, _| (i as f64 * 0.01).sin() + 2.0);
        let d = IoData::new(u, y).unwrap().with_sample_time(0.5).unwrap();
        let k = d.decimate(4).unwrap();
        assert_eq!(k.len(), 251);
        assert_eq!(k.sample_time(), 2.0);
        for i in 0..k.len() {
            assert_eq!(k.input_slice(0)[i], d.input_slice(0)[4 * i]);
        }
        assert_eq!(k.input_names(), d.input_names());
        assert_eq!(d.decimate(1).unwrap().len(), n);
    }

    /// A first-order block b/(z − p).
    fn first_order(p: f64) -> StateSpace<f64> {
        StateSpace::from_rows(&[&[p]], &[&[1.0 - p]], &[&[1.0]], &[&[0.0]]).unwrap()
    }

    #[test]
    fn the_suggestion_keeps_the_band_inside_the_new_nyquist_frequency() {
        // a pole at 0.999: corner 0.001 rad/sample, −20 dB near 0.00995; π/(2·0.00995) = 158
        // → 100; the record's length caps it
        assert_eq!(suggested_factor(&first_order(0.999), 1_000_000), Some(100));
        assert_eq!(suggested_factor(&first_order(0.999), 60_000), Some(50));
        // a pole at 0.99: −20 dB at 0.1415 rad/sample, π/0.283 = 11.1 → 10
        assert_eq!(suggested_factor(&first_order(0.99), 100_000), Some(10));
        // a pole at 0.9 is 20 dB down only from 1.1 rad/sample on: nothing to suggest
        assert_eq!(suggested_factor(&first_order(0.9), 100_000), None);
        // a fast pole of small residue beside the slow one does not hold it back
        let g = StateSpace::<f64>::from_rows(
            &[&[0.999, 0.0], &[0.0, -0.3]],
            &[&[0.001], &[0.001]],
            &[&[1.0, 1.0]],
            &[&[0.0]],
        )
        .unwrap();
        assert_eq!(suggested_factor(&g, 1_000_000), Some(100));
        // two inputs: the wider band counts
        let two = StateSpace::<f64>::from_rows(
            &[&[0.999, 0.0], &[0.0, 0.99]],
            &[&[0.001, 0.0], &[0.0, 0.01]],
            &[&[1.0, 1.0]],
            &[&[0.0, 0.0]],
        )
        .unwrap();
        assert_eq!(suggested_factor(&two, 1_000_000), Some(10));
    }

    #[test]
    fn bad_factors_are_refused_with_their_cause() {
        let u = Mat::from_fn(20, 1, |i, _| if i % 10 == 0 { 1.0 } else { 0.0 });
        let y = Mat::from_fn(20, 1, |i, _| i as f64);
        let d = IoData::new(u, y).unwrap();
        assert!(matches!(d.decimate(0), Err(Error::InvalidParameter(_))));
        assert!(matches!(d.decimate(20), Err(Error::TooFewSamples { .. })));
        // every 10th sample of an input that pulses every 10th: constant
        let e = d.decimate(10).unwrap_err().to_string();
        assert!(
            e.contains("decimating by 10") && e.contains("constant"),
            "{e}"
        );
    }
}
