//! What the UDN computes of one input record again and again while the loop fits it, computed
//! once per record: the directions s(k) (they depend on u alone), the input spread and each
//! branch's inputs sorted (rising s = +1, falling s = −1).
//!
//! In the Shift form x = u − a·s is u shifted by the same −a·s on a whole branch, and rounding
//! is monotone, so the q-quantile of a branch's x is the branch's sorted u at the same rank
//! shifted (`Branches::quantile`), and the sorted x of the whole record is the merge of the two
//! shifted sorted branches, whose k-th value and whose count below a threshold are binary
//! searches (`Branches::kth_x`, `count_x`): the zone guard's quantiles and zone counts in
//! O(log N) per call instead of a selection over the record, the same values (up to the sign
//! of a zero) as before.
//!
//! The cache lives in the nonlinearity (`InputCache`, shared by its clones) and is keyed by the
//! record's values, compared in full on every use: a different record recomputes it. Records
//! longer than `MAX_CACHED` samples and records with non-finite values are not cached (the
//! callers fall back to their direct computation), so a fitted model keeps at most a few
//! arrays of the window it was fitted on.

use super::direction::DirectionTracker;
use super::zone::{quantile_index, spread};
use crate::real::Real;
use std::sync::{Arc, Mutex};

/// Longest record the cache keeps (longer records are screened on a shorter window).
pub(crate) const MAX_CACHED: usize = 1 << 16;

/// The per-record data of the UDN's zone guard and evaluation.
#[derive(Debug)]
pub(crate) struct InputStats<T: Real> {
    /// The record (the cache's key).
    u: Vec<T>,
    /// The initial direction (the cache's key with `u`).
    s0: T,
    /// Directions s(k) from the initial direction `s0`.
    pub s: Vec<T>,
    /// max(u) − min(u).
    pub spread: T,
    /// The inputs of the rising (s = +1) and falling (s = −1) samples, each sorted.
    pub branches: Branches<T>,
}

/// Each branch's inputs, sorted ascending.
#[derive(Debug)]
pub(crate) struct Branches<T: Real> {
    /// The rising samples' inputs (s = +1), sorted.
    pub rise: Vec<T>,
    /// The falling samples' inputs (s = −1), sorted.
    pub fall: Vec<T>,
}

impl<T: Real> Branches<T> {
    /// The branch's (`rising`) x = u − a·s at rank round(q·(len − 1)) of its sorted values: the
    /// q-quantile of `select_quantile` over the branch's x.
    pub fn quantile(&self, rising: bool, a: T, q: f64) -> T {
        let (v, s) = self.branch(rising);
        match quantile_index(v.len(), q) {
            Some(i) => v[i] - a * s,
            None => T::zero(),
        }
    }

    /// The branch's sorted inputs and its sign s.
    fn branch(&self, rising: bool) -> (&[T], T) {
        if rising {
            (&self.rise, T::one())
        } else {
            (&self.fall, -T::one())
        }
    }

    /// The k-th smallest (0-based) x = u − a·s of the whole record: a binary search for how
    /// many of the first k + 1 come from the rising branch (both shifted branches are sorted).
    pub fn kth_x(&self, a: T, k: usize) -> T {
        let ((r, sr), (f, sf)) = (self.branch(true), self.branch(false));
        let xr = |i: usize| r[i] - a * sr;
        let xf = |j: usize| f[j] - a * sf;
        let take = k + 1;
        let (mut lo, mut hi) = (take.saturating_sub(f.len()), take.min(r.len()));
        // the least i such that the first i rising and take − i falling values are the smallest
        while lo < hi {
            let i = lo + (hi - lo) / 2;
            let j = take - i;
            if j > 0 && xr(i) < xf(j - 1) {
                lo = i + 1;
            } else {
                hi = i;
            }
        }
        let (i, j) = (lo, take - lo);
        match (i > 0, j > 0) {
            (true, true) => xr(i - 1).max(xf(j - 1)),
            (true, false) => xr(i - 1),
            _ => xf(j - 1),
        }
    }

    /// How many samples' x = u − a·s satisfy `pred`, a predicate true on a prefix of the sorted
    /// x (e.g. w(x) ≤ c for a non-decreasing w).
    pub fn count_x(&self, a: T, pred: impl Fn(T) -> bool) -> usize {
        [true, false]
            .into_iter()
            .map(|rising| {
                let (v, s) = self.branch(rising);
                v.partition_point(|&u| pred(u - a * s))
            })
            .sum()
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.rise.len() + self.fall.len()
    }
}

impl<T: Real> InputStats<T> {
    fn new(u: &[T], s0: T) -> Self {
        let mut dir = DirectionTracker::<T>::with_initial(s0);
        let s: Vec<T> = u.iter().map(|&x| dir.next(x)).collect();
        let (mut rise, mut fall) = (Vec::new(), Vec::new());
        for (&uk, &sk) in u.iter().zip(&s) {
            if sk > T::zero() {
                rise.push(uk)
            } else {
                fall.push(uk)
            }
        }
        let cmp = |a: &T, b: &T| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal);
        rise.sort_unstable_by(cmp);
        fall.sort_unstable_by(cmp);
        InputStats {
            u: u.to_vec(),
            s0,
            s,
            spread: spread(u),
            branches: Branches { rise, fall },
        }
    }

    /// True when `u` is this record, value by value (the sign of zero included), with the
    /// initial direction `s0`.
    fn is_for(&self, u: &[T], s0: T) -> bool {
        // chunk by chunk without short-circuit inside a chunk (vectorised), stopping at the
        // first chunk that differs; equal bits (of the exact f64 value) are equal values of
        // the same sign, and the cached record is finite, so a NaN in `u` never matches
        self.s0 == s0
            && self.u.len() == u.len()
            && self.u.chunks(64).zip(u.chunks(64)).all(|(p, q)| {
                p.iter().zip(q).fold(0u64, |diff, (&a, &b)| {
                    diff | (a.as_f64().to_bits() ^ b.as_f64().to_bits())
                }) == 0
            })
    }
}

/// The last record's `InputStats`, shared by the clones of a nonlinearity (not part of its
/// value: every cache compares equal, and `Debug` does not print the record).
#[derive(Default)]
pub(crate) struct InputCache<T: Real>(Mutex<Option<Arc<InputStats<T>>>>);

impl<T: Real> std::fmt::Debug for InputCache<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("InputCache")
    }
}

impl<T: Real> InputCache<T> {
    /// The stats of `u` with the initial direction `s0`, computed now unless the cache holds
    /// them; `None` when `u` is empty, longer than `MAX_CACHED` or not finite.
    pub fn get(&self, u: &[T], s0: T) -> Option<Arc<InputStats<T>>> {
        if u.is_empty() || u.len() > MAX_CACHED {
            return None;
        }
        let mut slot = self.0.lock().ok()?;
        if let Some(st) = slot.as_ref().filter(|st| st.is_for(u, s0)) {
            return Some(Arc::clone(st));
        }
        if !u.iter().all(|x| x.is_finite()) {
            return None;
        }
        let st = Arc::new(InputStats::new(u, s0));
        *slot = Some(Arc::clone(&st));
        Some(st)
    }
}

impl<T: Real> Clone for InputCache<T> {
    fn clone(&self) -> Self {
        let held = self.0.lock().ok().and_then(|s| s.clone());
        InputCache(Mutex::new(held))
    }
}

impl<T: Real> PartialEq for InputCache<T> {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regressors::zone::{finite, select_quantile};

    fn record() -> Vec<f64> {
        (0..400)
            .map(|k| {
                let t = k as f64;
                (0.05 * t).sin() * 2.0
                    + 0.3 * ((7.3 * t).sin())
                    + if k % 37 == 0 { 0.0 } else { 0.1 }
            })
            .collect()
    }

    #[test]
    fn branch_quantiles_and_sorted_x_match_selection() {
        let u = record();
        let cache = InputCache::<f64>::default();
        let st = cache.get(&u, 1.0).expect("finite record");
        for a in [0.0, 0.137, 0.5] {
            let x: Vec<(f64, f64)> = u
                .iter()
                .zip(&st.s)
                .map(|(&uk, &s)| (uk - a * s, s))
                .collect();
            for (rising, sign) in [(true, 1.0), (false, -1.0)] {
                let mut br = finite(x.iter().filter(|p| p.1 == sign).map(|p| p.0));
                for q in [0.03, 0.5, 0.97] {
                    let want = select_quantile(&mut br, q);
                    assert_eq!(st.branches.quantile(rising, a, q), want);
                }
            }
            let mut all: Vec<f64> = x.iter().map(|p| p.0).collect();
            all.sort_by(|p, q| p.partial_cmp(q).unwrap());
            assert_eq!(st.branches.len(), all.len());
            for k in 0..all.len() {
                assert_eq!(st.branches.kth_x(a, k), all[k]);
            }
            for c in [-3.0, -0.2, 0.0, 0.4, 3.0] {
                let want = all.iter().filter(|&&x| x <= c).count();
                assert_eq!(st.branches.count_x(a, |x| x <= c), want);
            }
        }
        // the same record again: the same stats; another record: new ones
        assert!(Arc::ptr_eq(&st, &cache.get(&u, 1.0).expect("cached")));
        let mut v = u.clone();
        v[3] += 1.0;
        assert!(!Arc::ptr_eq(&st, &cache.get(&v, 1.0).expect("recomputed")));
        assert!(cache.get(&[f64::NAN, 1.0], 1.0).is_none());
    }

    #[test]
    fn a_record_too_long_for_the_cache_evaluates_the_same() {
        use crate::regressors::{StaticNonlinearity, Udn};
        let long: Vec<f64> = (0..MAX_CACHED + 100)
            .map(|k| 2.0 * (0.01 * k as f64).sin() + 0.3 * (1.7 * k as f64).sin())
            .collect();
        let short = &long[..3000];
        let theta = [1.5, 0.2, 0.1, 1.2, -1.0, 0.1, -0.2];
        let udn = Udn::<f64>::with_params(crate::regressors::EffectSet::all(), &theta).unwrap();
        // directions are causal: the long record's first samples are the short record's
        assert_eq!(&udn.eval(&long)[..short.len()], udn.eval(short).as_slice());
        let (pl, ps) = (udn.regressors(&long), udn.regressors(short));
        for j in 0..ps.ncols() {
            for k in 0..ps.nrows() {
                assert_eq!(pl[(k, j)], ps[(k, j)]);
            }
        }
    }
}
