//! Signature tests: does a given function of the input (or of the predicted output) explain part of
//! the residual?
//!
//! A Hammerstein model that misses part Δv(u) of its nonlinearity leaves the residual
//! e = G·Δv(u) + noise, where G is the linear block. For a strictly proper G (no feed-through) e(k)
//! does not depend on u(k) at all, so binning e(k) by u(k) — the textbook residual-versus-input plot —
//! has no power on white inputs. Instead, each candidate shape z(u) (input-level bins, rising and
//! falling halves of each bin, hinges at the extreme deciles, a clip at small |u|, the sign step, u²,
//! u³) is filtered through the model's own linear block, and the residual is regressed on G·z: the
//! coefficients are *input-referred* (in units of the nonlinearity's output v), so binned
//! coefficients are the binned means of Δv, and a rising/falling split measures the hysteresis width
//! directly. Output-side shapes (bins of ŷ) are used unfiltered. The test of the added columns is a
//! nested F test after prewhitening all series with an AR model of the residual (the residual of a
//! simulation is coloured even for a correct model), see [`crate::diagnosis::regression`].

use crate::diagnosis::regression::{ArFilter, NestedTest, least_squares, nested_f_test};
use crate::statespace::StateSpace;

/// Where the columns of a signature test live.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Domain {
    /// Functions of the input u(k): filtered through the linear block before the regression.
    Input,
    /// Functions of the predicted output ŷ(k) (or already filtered columns): used as they are.
    Output,
}

/// The prewhitened regression set-up shared by all signature tests of one residual series.
#[derive(Debug, Clone)]
pub struct SignatureEngine {
    linear: StateSpace<f64>,
    burn: usize,
    ar: ArFilter,
    e_w: Vec<f64>,
    base_w: Vec<Vec<f64>>,
}

impl SignatureEngine {
    /// Sets up the engine: `base` are the always-included regressors (output domain, full length);
    /// the first `burn` samples are skipped (transients of filtering from a zero state).
    pub fn new(
        residual: &[f64],
        base: &[Vec<f64>],
        linear: StateSpace<f64>,
        burn: usize,
        max_ar: usize,
    ) -> Self {
        let burn = burn.min(residual.len() / 4);
        let e = &residual[burn..];
        let cut: Vec<&[f64]> = base.iter().map(|c| &c[burn..]).collect();
        let r = least_squares(e, &cut).residuals;
        let ar = ArFilter::fit_bic(&r, max_ar);
        let e_w = ar.apply(e);
        let base_w = cut.iter().map(|c| ar.apply(c)).collect();
        Self {
            linear,
            burn,
            ar,
            e_w,
            base_w,
        }
    }

    /// The linear block's response G·z to a column z from a zero initial state.
    pub fn filter(&self, z: &[f64]) -> Vec<f64> {
        self.linear
            .simulate_siso(z, None)
            .unwrap_or_else(|_| vec![0.0; z.len()])
    }

    /// Order of the AR prewhitening filter.
    pub fn ar_order(&self) -> usize {
        self.ar.order()
    }

    /// Number of samples entering the regressions.
    pub fn n_samples(&self) -> usize {
        self.e_w.len()
    }

    fn prepare(&self, col: &[f64], domain: Domain) -> Vec<f64> {
        let c = match domain {
            Domain::Input => self.filter(col),
            Domain::Output => col.to_vec(),
        };
        self.ar.apply(&c[self.burn..])
    }

    /// F test of the `extra` columns given the base and `extra_base` (both in `domain`).
    pub fn test(
        &self,
        extra: &[Vec<f64>],
        extra_base: &[Vec<f64>],
        domain: Domain,
    ) -> Option<NestedTest> {
        let eb: Vec<Vec<f64>> = extra_base.iter().map(|c| self.prepare(c, domain)).collect();
        let ex: Vec<Vec<f64>> = extra.iter().map(|c| self.prepare(c, domain)).collect();
        self.test_prepared(&ex, &eb)
    }

    /// Like [`test`](Self::test) with an extra base in the output domain and extra columns in `domain`.
    pub fn test_mixed(
        &self,
        extra: &[Vec<f64>],
        domain: Domain,
        extra_base_input: &[Vec<f64>],
        extra_base_output: &[Vec<f64>],
    ) -> Option<NestedTest> {
        let mut eb: Vec<Vec<f64>> = extra_base_input
            .iter()
            .map(|c| self.prepare(c, Domain::Input))
            .collect();
        eb.extend(
            extra_base_output
                .iter()
                .map(|c| self.prepare(c, Domain::Output)),
        );
        let ex: Vec<Vec<f64>> = extra.iter().map(|c| self.prepare(c, domain)).collect();
        self.test_prepared(&ex, &eb)
    }

    fn test_prepared(&self, ex: &[Vec<f64>], eb: &[Vec<f64>]) -> Option<NestedTest> {
        let mut base: Vec<&[f64]> = self.base_w.iter().map(|c| c.as_slice()).collect();
        base.extend(eb.iter().map(|c| c.as_slice()));
        let extra: Vec<&[f64]> = ex.iter().map(|c| c.as_slice()).collect();
        nested_f_test(&self.e_w, &base, &extra)
    }
}

/// Direction of motion s(k): +1 rising, −1 falling, the previous direction when the input is held
/// (NOTES.md's corrected UDN); before the first move, the direction of the first move.
pub fn direction(u: &[f64]) -> Vec<f64> {
    let first = u
        .windows(2)
        .find(|w| w[1] != w[0])
        .map_or(1.0, |w| if w[1] > w[0] { 1.0 } else { -1.0 });
    let mut s = first;
    let mut out = Vec::with_capacity(u.len());
    out.push(s);
    for w in u.windows(2) {
        if w[1] > w[0] {
            s = 1.0;
        } else if w[1] < w[0] {
            s = -1.0;
        }
        out.push(s);
    }
    out
}

/// Empirical quantile (linear interpolation) of already sorted values.
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    let t = pos - lo as f64;
    sorted[lo] * (1.0 - t) + sorted[hi] * t
}

/// Sorted copy of finite values.
pub fn sorted(x: &[f64]) -> Vec<f64> {
    let mut s: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    s.sort_by(|a, b| a.total_cmp(b));
    s
}

/// Bin edges at the quantiles j/k, j = 1..k−1 (interior edges only).
pub fn quantile_edges(x: &[f64], k: usize) -> Vec<f64> {
    let s = sorted(x);
    (1..k)
        .map(|j| quantile_sorted(&s, j as f64 / k as f64))
        .collect()
}

/// Index of the bin of `v` given interior edges.
pub fn bin_of(v: f64, edges: &[f64]) -> usize {
    edges.iter().take_while(|&&e| v > e).count()
}

/// Indicator columns of the k quantile bins of `x`, the middle bin left out (it is spanned by the
/// constant and the others).
pub fn level_bins(x: &[f64], k: usize) -> Vec<Vec<f64>> {
    let edges = quantile_edges(x, k);
    let skip = k / 2;
    (0..k)
        .filter(|&j| j != skip)
        .map(|j| {
            x.iter()
                .map(|&v| if bin_of(v, &edges) == j { 1.0 } else { 0.0 })
                .collect()
        })
        .collect()
}

/// Columns I_j(u)·s for the k quantile bins of u: the rising-minus-falling split inside each bin.
pub fn direction_bins(u: &[f64], s: &[f64], k: usize) -> Vec<Vec<f64>> {
    let edges = quantile_edges(u, k);
    (0..k)
        .map(|j| {
            u.iter()
                .zip(s)
                .map(|(&v, &d)| if bin_of(v, &edges) == j { d } else { 0.0 })
                .collect()
        })
        .collect()
}

/// Hinge columns (u − hi)₊ and (lo − u)₊.
pub fn hinges(u: &[f64], lo: f64, hi: f64) -> Vec<Vec<f64>> {
    vec![
        u.iter().map(|&v| (v - hi).max(0.0)).collect(),
        u.iter().map(|&v| (lo - v).max(0.0)).collect(),
    ]
}

/// Column clip(u, −d, d).
pub fn clip(u: &[f64], d: f64) -> Vec<f64> {
    u.iter().map(|&v| v.clamp(-d, d)).collect()
}

/// Column sign(u) (0 at 0).
pub fn sign(u: &[f64]) -> Vec<f64> {
    u.iter()
        .map(|&v| {
            if v > 0.0 {
                1.0
            } else if v < 0.0 {
                -1.0
            } else {
                0.0
            }
        })
        .collect()
}

/// Column x(k − d) (zeros before the start).
pub fn lagged(x: &[f64], d: usize) -> Vec<f64> {
    (0..x.len())
        .map(|k| if k >= d { x[k - d] } else { 0.0 })
        .collect()
}

/// Column (x − mean(x))^power.
pub fn centred_power(x: &[f64], power: i32) -> Vec<f64> {
    let m = x.iter().sum::<f64>() / x.len().max(1) as f64;
    let c: Vec<f64> = x.iter().map(|v| (v - m).powi(power)).collect();
    let mc = c.iter().sum::<f64>() / c.len().max(1) as f64;
    c.iter().map(|v| v - mc).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_holds_previous_on_equal_samples() {
        let s = direction(&[0.0, 0.0, 1.0, 1.0, 0.5, 0.5, 0.7]);
        assert_eq!(s, vec![1.0, 1.0, 1.0, 1.0, -1.0, -1.0, 1.0]);
        assert_eq!(direction(&[2.0, 2.0, 1.0]), vec![-1.0, -1.0, -1.0]);
    }

    #[test]
    fn bins_partition_the_samples() {
        let x: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let b = level_bins(&x, 5);
        assert_eq!(b.len(), 4);
        let per_sample: Vec<f64> = (0..100).map(|k| b.iter().map(|c| c[k]).sum()).collect();
        // every sample is in exactly one bin; the skipped middle bin holds 20 of them
        assert_eq!(per_sample.iter().filter(|&&v| v == 0.0).count(), 20);
        assert!(per_sample.iter().all(|&v| v == 0.0 || v == 1.0));
    }
}
