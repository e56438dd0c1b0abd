//! Quantiles and input spread used by the zone guard and the data-driven initial values.

use crate::real::Real;

/// Fraction of the samples the zone guard keeps in every zone an effect claims (3 %).
pub const ZONE_FRACTION: f64 = 0.03;

/// Largest hysteresis / dead-zone half-width the guard allows, as a fraction of the input spread.
pub const MAX_WIDTH_FRACTION: f64 = 0.25;

/// The finite values of `v` (NaNs and infinities dropped), in their order.
pub fn finite<T: Real>(v: impl Iterator<Item = T>) -> Vec<T> {
    v.filter(|x| x.is_finite()).collect()
}

/// The q-quantile (0 ≤ q ≤ 1) of unsorted finite data: the value at nearest rank
/// round(q·(N − 1)) of the sorted data; zero for empty data. Selection (O(N)), reorders `v`.
pub fn select_quantile<T: Real>(v: &mut [T], q: f64) -> T {
    let Some(i) = quantile_index(v.len(), q) else {
        return T::zero();
    };
    let (_, x, _) = v.select_nth_unstable_by(i, |a, b| {
        a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal)
    });
    *x
}

/// The nearest rank round(q·(N − 1)) of the q-quantile (q clamped to [0, 1]) of N values;
/// `None` for no values.
pub fn quantile_index(n: usize, q: f64) -> Option<usize> {
    if n == 0 {
        return None;
    }
    let q = q.clamp(0.0, 1.0);
    Some(((q * (n - 1) as f64).round() as usize).min(n - 1))
}

/// max(u) − min(u) over the finite samples (zero for empty or constant input).
pub fn spread<T: Real>(u: &[T]) -> T {
    let mut lo = T::infinity();
    let mut hi = T::neg_infinity();
    for &x in u.iter().filter(|x| x.is_finite()) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if hi >= lo { hi - lo } else { T::zero() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sorts a copy of the finite values of `v` (NaNs dropped).
    fn sorted_finite<T: Real>(v: impl Iterator<Item = T>) -> Vec<T> {
        let mut s: Vec<T> = v.filter(|x| x.is_finite()).collect();
        s.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
        s
    }

    /// The q-quantile (0 ≤ q ≤ 1) of sorted data, nearest rank; zero for empty data.
    fn quantile<T: Real>(sorted: &[T], q: f64) -> T {
        if sorted.is_empty() {
            return T::zero();
        }
        let q = q.clamp(0.0, 1.0);
        let i = (q * (sorted.len() - 1) as f64).round() as usize;
        sorted[i.min(sorted.len() - 1)]
    }

    #[test]
    fn quantiles_and_spread() {
        let s = sorted_finite([3.0, f64::NAN, 1.0, 2.0, 0.0, 4.0].into_iter());
        assert_eq!(s, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(quantile(&s, 0.5), 2.0);
        assert_eq!(quantile(&s, 1.0), 4.0);
        assert_eq!(spread(&[1.0, -2.0, 0.5]), 3.0);
    }

    #[test]
    fn selection_matches_sorted_quantiles() {
        let v: Vec<f64> = (0..101).map(|k| ((k * 37) % 101) as f64 - 50.0).collect();
        let sorted = sorted_finite(v.iter().copied());
        for q in [0.0, 0.03, 0.1, 0.5, 0.9, 0.97, 1.0] {
            let mut w = finite(v.iter().copied());
            assert_eq!(select_quantile(&mut w, q), quantile(&sorted, q));
        }
        assert_eq!(select_quantile::<f64>(&mut [], 0.5), 0.0);
    }
}
