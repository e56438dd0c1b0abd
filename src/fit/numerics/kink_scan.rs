//! Restarts of the refinement from other values of the kink parameters (the saturation limits),
//! beside the jump parameters' (`jump_scan.rs`), where the residual says the kink is misplaced.
//!
//! The loop's zone guard keeps a saturation limit inside the 3 %/97 % quantiles of the signal it
//! clips (`udn.rs`, `saturation_guard`), so a limit the record barely reaches starts the
//! refinement clipping 3 % of the samples, and Levenberg–Marquardt can stop there with the other
//! parameters compensating: on the battery's seeds 601–1400 records 694, 1048, 1310 and 1389
//! ended 1.3–7.4× the noise in training while a restart with the limit moved by 10–25 % reached
//! 0.92–1.10× (the limit alone wrong, every other parameter at the truth's to 3 digits on 1310).
//! The training error is continuous but only piecewise smooth in a limit (a sample changes side
//! at every value of the clipped signal), so, as for a threshold (Chan 1993, Ann. Statist. 21(1),
//! 520–533), the starts are taken between order statistics of that signal: clipping the current
//! share of samples times 1/8, 1/4, 1/2 and 2, and a single sample (a limit just reached).
//!
//! The restarts run only where the residual is larger near the kink than on the record: on the
//! samples the limit clips, as many just inside it, and `GATE_LAG` samples after each (the
//! block's delay), its mean square above `MIN_NEAR_KINK_RATIO` times the record's. A limit in
//! its place leaves the noise there, and the restarts (≈ 30 LM iterations) would cost a fixed-
//! order fit more than half its time for nothing.

use crate::real::Real;

/// Factors of the currently clipped share tried as starts (looser, then tighter).
const SHARE_FACTORS: [f64; 4] = [0.125, 0.25, 0.5, 2.0];
/// The clipped share taken as the current one when the limit clips no sample.
const IDLE_SHARE: f64 = 0.01;
/// The largest share of the samples a start clips.
const MAX_SHARE: f64 = 0.5;
/// Samples after a sample near the kink whose residual the gate also reads.
const GATE_LAG: usize = 3;
/// Fewest samples near the kink the gate reads; fewer: the kink is not judged.
const MIN_NEAR: usize = 5;
/// The residual's mean square near the kink over the record's above which the restarts run.
pub(crate) const MIN_NEAR_KINK_RATIO: f64 = 1.2;

/// The finite positions sorted, and whether the limit `z` clips their upper tail (it lies above
/// their median) rather than the lower one.
fn sorted_side<T: Real>(positions: &[T], z: T) -> (Vec<f64>, bool) {
    let mut s: Vec<f64> = positions
        .iter()
        .map(|x| x.as_f64())
        .filter(|x| x.is_finite())
        .collect();
    s.sort_by(f64::total_cmp);
    let upper = s.get(s.len() / 2).is_none_or(|&m| z.as_f64() > m);
    (s, upper)
}

/// How many of the sorted positions `s` the limit `z` clips (above it for an upper limit).
fn clipped(s: &[f64], z: f64, upper: bool) -> usize {
    if upper {
        s.len() - s.partition_point(|&x| x <= z)
    } else {
        s.partition_point(|&x| x < z)
    }
}

/// The limit that clips exactly `m` of the sorted positions `s` (1 ≤ m < len): the midpoint
/// between the order statistics on either side of it.
fn clipping(s: &[f64], m: usize, upper: bool) -> f64 {
    let n = s.len();
    if upper {
        0.5 * (s[n - m - 1] + s[n - m])
    } else {
        0.5 * (s[m - 1] + s[m])
    }
}

/// Start values of the kink parameter now at `z` over `positions` (the signal it clips): the
/// limits clipping the current share of samples times `SHARE_FACTORS`, and one sample; values
/// that fail `admissible` or equal `z` are dropped.
pub(crate) fn kink_values<T: Real>(
    positions: &[T],
    z: T,
    mut admissible: impl FnMut(T) -> bool,
) -> Vec<T> {
    let (s, upper) = sorted_side(positions, z);
    let n = s.len();
    if n < 4 {
        return Vec::new();
    }
    let c = clipped(&s, z.as_f64(), upper);
    let share = if c == 0 {
        IDLE_SHARE
    } else {
        c as f64 / n as f64
    };
    let most = ((MAX_SHARE * n as f64) as usize).clamp(1, n - 1);
    let mut counts: Vec<usize> = SHARE_FACTORS
        .iter()
        .map(|f| ((f * share * n as f64).round() as usize).clamp(1, most))
        .chain(std::iter::once(1))
        .filter(|&m| m != c)
        .collect();
    counts.sort_unstable();
    counts.dedup();
    counts
        .into_iter()
        .map(|m| T::lit(clipping(&s, m, upper)))
        .filter(|&x| x != z && admissible(x))
        .collect()
}

/// The residual's mean square on the samples near the kink at `z` (those it clips, as many just
/// inside it, and `GATE_LAG` samples after each) over its mean square on the whole record; 0
/// when fewer than `MIN_NEAR` samples are near it.
pub(crate) fn near_kink_ratio<T: Real>(positions: &[T], z: T, residual: &[T]) -> f64 {
    let n = positions.len().min(residual.len());
    let (s, upper) = sorted_side(&positions[..n], z);
    if s.len() < 4 {
        return 0.0;
    }
    let c = clipped(&s, z.as_f64(), upper);
    let reach = if c == 0 {
        (IDLE_SHARE * s.len() as f64).ceil() as usize
    } else {
        2 * c
    }
    .clamp(1, s.len() - 1);
    let edge = clipping(&s, reach, upper);
    let mut near = vec![false; n];
    for (k, x) in positions[..n].iter().enumerate() {
        let x = x.as_f64();
        if (upper && x > edge) || (!upper && x < edge) {
            for flag in near.iter_mut().skip(k).take(GATE_LAG + 1) {
                *flag = true;
            }
        }
    }
    let (mut sn, mut cn, mut sa) = (0.0, 0usize, 0.0);
    for (k, r) in residual[..n].iter().enumerate() {
        let r2 = r.as_f64() * r.as_f64();
        sa += r2;
        if near[k] {
            sn += r2;
            cn += 1;
        }
    }
    if cn < MIN_NEAR || sa <= 0.0 || !sa.is_finite() {
        return 0.0;
    }
    (sn / cn as f64) / (sa / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_clip_fractions_of_the_current_share_and_one_sample() {
        // positions 0, 1, …, 999; an upper limit at 969.5 clips 30 samples (3 %)
        let pos: Vec<f64> = (0..1000).map(|i| i as f64).collect();
        let v = kink_values(&pos, 969.5, |_| true);
        let clipped_by = |z: f64| pos.iter().filter(|&&x| x > z).count();
        let counts: Vec<usize> = v.iter().map(|&z| clipped_by(z)).collect();
        assert_eq!(counts, vec![1, 4, 8, 15, 60]);
        // between samples, never on one
        assert!(v.iter().all(|z| z.fract() == 0.5));
        // a lower limit clips the lower tail
        let v = kink_values(&pos, 29.5, |_| true);
        let below: Vec<usize> = v
            .iter()
            .map(|&z| pos.iter().filter(|&&x| x < z).count())
            .collect();
        assert_eq!(below, vec![1, 4, 8, 15, 60]);
        // an idle limit (above every sample) starts from 1 % of them
        let v = kink_values(&pos, 2000.0, |_| true);
        assert_eq!(
            v.iter().map(|&z| clipped_by(z)).collect::<Vec<_>>(),
            vec![1, 3, 5, 20]
        );
        // inadmissible values are dropped
        assert_eq!(kink_values(&pos, 969.5, |z| z > 990.0).len(), 3);
        assert!(kink_values(&[1.0, 2.0], 1.5, |_| true).is_empty());
    }

    #[test]
    fn the_gate_reads_the_residual_near_the_kink() {
        let pos: Vec<f64> = (0..1000).map(|i| ((i * 37) % 1000) as f64).collect();
        let z = 969.5;
        // white residual: the same near the kink as elsewhere
        let flat: Vec<f64> = (0..1000)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let r = near_kink_ratio(&pos, z, &flat);
        assert!((r - 1.0).abs() < 1e-12, "{r}");
        // a residual 5× larger on the samples the limit clips and just after them
        let mut big = flat.clone();
        for k in 0..1000 {
            if pos[k] > z {
                for j in k..(k + 2).min(1000) {
                    big[j] = 5.0;
                }
            }
        }
        let r = near_kink_ratio(&pos, z, &big);
        assert!(r > MIN_NEAR_KINK_RATIO, "{r}");
        assert_eq!(near_kink_ratio(&pos[..3], z, &flat[..3]), 0.0);
    }
}
