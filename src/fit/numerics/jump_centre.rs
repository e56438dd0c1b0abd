//! Jump positions placed where the training record leaves them most likely, not at an edge.
//!
//! A jump parameter (the position of a discontinuity of N: `StaticNonlinearity::jump_params`,
//! e.g. the UDN's dead-zone width b when preload steps sit at its edges) is resolved by the
//! training samples only to the interval between the two nearest values at which some sample
//! changes side of the jump (`StaticNonlinearity::jump_positions`): least-squares estimates of a
//! threshold are intervals between order statistics (Chan 1993, Ann. Statist. 21(1), 520–533).
//! Inside the interval the training error moves only through the smooth part of N, and the
//! refinement stops anywhere in it — often at an edge, a training sample sitting exactly on the
//! jump. Every new sample that falls between the estimate and the true position is then
//! simulated on the wrong side of the jump (on the battery's development seeds every record
//! above the noise floor carries a preload).
//!
//! The estimate is therefore replaced by the median of the parameter's posterior over the
//! interval holding it and its two neighbours (flat prior; Gaussian likelihood of the training
//! error, profiled over the rest of the model by the caller's `cost`, `refine::centre_jumps`):
//! exp(−N/2 · ln MSE(θ_j)). The median minimises the
//! expected distance to the true position, hence the expected number of new samples placed on
//! the wrong side. Inside one interval no sample changes side, v is affine in the parameter (a
//! shift of the sloped branch) and the MSE a quadratic: three evaluations per interval give it
//! exactly, and the posterior is integrated numerically on it. A flat MSE gives the interval's
//! midpoint, a steep one the optimum. The median is kept when its training MSE stays within the
//! 95 % likelihood-ratio bound of the refinement's, N·ln(MSE/MSE_opt) ≤ 3.84; one jump parameter
//! at a time, the others held.

use crate::real::Real;
use crate::regressors::StaticNonlinearity;

/// Sub-intervals of the numerical integration of the posterior in each interval.
const STEPS: usize = 256;
/// N·ln(MSE/MSE_opt) allowed for the moved parameter (χ²₁ at 95 %, Wilks 1938); also the gain
/// a slow block's refit must beat (`slow_horizon::clearly_lower`).
pub(crate) const LR_BOUND: f64 = 3.84;

/// θ with its jump parameters moved to the posterior medians over the intervals the record `u`
/// resolves, and its MSE by `cost` (θ → training MSE, the jump parameters held); `None` when no
/// jump moved (no jump parameter, positions unknown, or the median's MSE beyond the bound).
pub(crate) fn centred_theta<T: Real>(
    nl: &dyn StaticNonlinearity<T>,
    u: &[T],
    theta: &[T],
    mse: f64,
    mut cost: impl FnMut(&[T]) -> Option<f64>,
) -> Option<(Vec<T>, f64)> {
    let jumps = nl.jump_params();
    if jumps.is_empty() || !(mse > 0.0 && mse.is_finite()) {
        return None;
    }
    let n = u.len().max(1) as f64;
    let limit = mse * (LR_BOUND / n).exp();
    let mut work = nl.clone_box();
    let mut theta = theta.to_vec();
    let mut moved = None;
    for &j in &jumps {
        if j >= theta.len() || work.set_params(&theta).is_err() {
            continue;
        }
        let intervals = intervals(&work.jump_positions(j, u), theta[j]);
        let mut at = |x: T| {
            let mut t = theta.clone();
            t[j] = x;
            cost(&t)
        };
        let Some(m) = posterior_median(&intervals, n, mse, &mut at) else {
            continue;
        };
        match at(m) {
            Some(c) if c <= limit => {
                theta[j] = m;
                moved = Some(c);
            }
            _ => {}
        }
    }
    moved.map(|m| (theta, m))
}

/// The median of the density exp(−n/2 · ln(MSE(x)/`mse`)) over `intervals` (each MSE a quadratic
/// through three evaluations of `at`); `None` when no interval could be evaluated.
fn posterior_median<T: Real>(
    intervals: &[(T, T)],
    n: f64,
    mse: f64,
    at: &mut impl FnMut(T) -> Option<f64>,
) -> Option<T> {
    // per interval: its ends and the density at STEPS + 1 points
    let mut dens: Vec<(f64, f64, Vec<f64>)> = Vec::new();
    for &(l, r) in intervals {
        let (l, r) = (l.as_f64(), r.as_f64());
        let w = r - l;
        let mut q = |f: f64| at(T::lit(l + f * w));
        let (Some(m1), Some(m2), Some(m3)) = (q(0.25), q(0.5), q(0.75)) else {
            continue;
        };
        // m(t) = m2 + β(t − ½) + γ(t − ½)² through the three points
        let (beta, gamma) = (2.0 * (m3 - m1), 8.0 * (m1 + m3 - 2.0 * m2));
        let d = (0..=STEPS)
            .map(|i| {
                let t = i as f64 / STEPS as f64 - 0.5;
                let m = (m2 + beta * t + gamma * t * t).max(mse * 1e-3);
                (-0.5 * n * (m / mse).ln()).exp()
            })
            .collect();
        dens.push((l, r, d));
    }
    // trapezoid masses, then the point where the cumulative mass reaches half
    let masses: Vec<Vec<f64>> = dens
        .iter()
        .map(|(l, r, d)| {
            let h = (r - l) / STEPS as f64;
            d.windows(2).map(|p| 0.5 * (p[0] + p[1]) * h).collect()
        })
        .collect();
    let total: f64 = masses.iter().flatten().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut acc = 0.0;
    for ((l, r, _), ms) in dens.iter().zip(&masses) {
        let h = (r - l) / STEPS as f64;
        for (i, &m) in ms.iter().enumerate() {
            if acc + m >= 0.5 * total && m > 0.0 {
                let f = (0.5 * total - acc) / m;
                return Some(T::lit(l + (i as f64 + f) * h));
            }
            acc += m;
        }
    }
    dens.last().map(|(_, r, _)| T::lit(*r))
}

/// The interval between consecutive distinct `positions` that holds `x` (its lower end ≤ x <
/// its upper end) and the intervals on either side of it, in increasing order.
fn intervals<T: Real>(positions: &[T], x: T) -> Vec<(T, T)> {
    // the two nearest distinct positions at or below x and the two above it
    let (mut lo, mut hi): ([Option<T>; 2], [Option<T>; 2]) = ([None; 2], [None; 2]);
    for &p in positions.iter().filter(|p| p.is_finite()) {
        if p <= x {
            insert(&mut lo, p, |a, b| a > b);
        } else {
            insert(&mut hi, p, |a, b| a < b);
        }
    }
    let edges = [lo[1], lo[0], hi[0], hi[1]];
    edges
        .windows(2)
        .filter_map(|w| match (w[0], w[1]) {
            (Some(a), Some(b)) => Some((a, b)),
            _ => None,
        })
        .collect()
}

/// Keeps in `best` the two distinct values that come first by `before` (best[0] first).
fn insert<T: Real>(best: &mut [Option<T>; 2], p: T, before: impl Fn(T, T) -> bool) {
    if best.contains(&Some(p)) {
        return;
    }
    match best[0] {
        None => best[0] = Some(p),
        Some(b0) if before(p, b0) => *best = [Some(p), Some(b0)],
        Some(_) => {
            if best[1].is_none_or(|b1| before(p, b1)) {
                best[1] = Some(p);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_holding_x_and_its_neighbours() {
        let pos: [f64; 6] = [0.1, 0.5, 0.3, 0.3, 0.9, 0.7];
        // x = 0.4 lies in [0.3, 0.5): neighbours [0.1, 0.3] and [0.5, 0.7]
        assert_eq!(
            intervals(&pos, 0.4),
            vec![(0.1, 0.3), (0.3, 0.5), (0.5, 0.7)]
        );
        // on an edge (x = 0.5): [0.3, 0.5], [0.5, 0.7], [0.7, 0.9]
        assert_eq!(
            intervals(&pos, 0.5),
            vec![(0.3, 0.5), (0.5, 0.7), (0.7, 0.9)]
        );
        // beyond every position: only the interval below
        assert_eq!(intervals(&pos, 2.0), vec![(0.7, 0.9)]);
        assert!(intervals::<f64>(&[], 0.4).is_empty());
    }

    #[test]
    fn flat_error_gives_the_midpoint_steep_error_the_optimum() {
        // one interval [0, 1]; a flat MSE: the median is the midpoint
        let flat = posterior_median(&[(0.0, 1.0)], 1000.0, 1.0, &mut |_x: f64| Some(1.0));
        assert!((flat.unwrap() - 0.5).abs() < 1e-9);
        // MSE = 1 + (x − 0.2)²: with n = 1e6 the posterior is a narrow peak at 0.2
        let steep = posterior_median(&[(0.0, 1.0)], 1e6, 1.0, &mut |x: f64| {
            Some(1.0 + (x - 0.2) * (x - 0.2))
        });
        assert!((steep.unwrap() - 0.2).abs() < 0.01, "{steep:?}");
        // an interval much worse than the other carries no mass
        let two = posterior_median(&[(0.0, 1.0), (1.0, 2.0)], 1000.0, 1.0, &mut |x: f64| {
            Some(if x < 1.0 { 1.0 } else { 2.0 })
        });
        assert!((two.unwrap() - 0.5).abs() < 1e-6, "{two:?}");
    }
}
