//! Balanced truncation of a stable discrete-time block (A, B, C) to a lower order: the
//! square-root method (Laub, Heath, Paige & Ward 1987; Tombs & Postlethwaite 1987; SLICOT AB09AD
//! with its SVD-based square roots), with the Gramians by Smith's doubling iteration
//! (Smith 1968), for the small orders of identified blocks.

use crate::real::Real;
use crate::solvers::LinAlg;
use faer::{Mat, MatRef};

/// Doublings of Smith's iteration at most (A^(2^k) → 0: enough for a spectral radius of 1 − 1e-9).
const MAX_DOUBLINGS: usize = 40;

/// The order-`n` balanced truncation (Aᵣ, Bᵣ, Cᵣ) of the stable block (`a`, `b`, `c`) and its
/// Hankel singular values (all of them, non-increasing); `None` when the block is not stable,
/// `n` is not below its order, or the `n`-th Hankel singular value is negligible (the block has
/// fewer than `n` states that matter).
#[allow(clippy::type_complexity)]
pub(crate) fn balanced_truncation<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b: MatRef<'_, T>,
    c: MatRef<'_, T>,
    n: usize,
) -> Option<(Mat<T>, Mat<T>, Mat<T>, Vec<T>)> {
    let m = a.nrows();
    if n == 0 || n >= m || a.ncols() != m || b.nrows() != m || c.ncols() != m {
        return None;
    }
    let (lc, lo, svd) = square_roots(la, a, b, c)?;
    let s = svd.s.clone();
    if !(s[0].is_finite() && s[0] > T::zero() && s[n - 1] > s[0] * T::epsilon().sqrt()) {
        return None;
    }
    // T = Lc V₁ Σ₁^(−½), T⁺ = Σ₁^(−½) U₁ᵀ Loᵀ
    let scale: Vec<T> = (0..n).map(|k| T::one() / s[k].sqrt()).collect();
    let v1 = Mat::from_fn(m, n, |i, k| svd.v[(i, k)] * scale[k]);
    let u1 = Mat::from_fn(m, n, |i, k| svd.u[(i, k)] * scale[k]);
    let t = mul(lc.as_ref(), v1.as_ref());
    let ti = mul(u1.transpose(), lo.transpose());
    let ar = mul(ti.as_ref(), mul(a, t.as_ref()).as_ref());
    let br = mul(ti.as_ref(), b);
    let cr = mul(c, t.as_ref());
    let finite = |x: &Mat<T>| (0..x.nrows()).all(|i| (0..x.ncols()).all(|j| x[(i, j)].is_finite()));
    (finite(&ar) && finite(&br) && finite(&cr)).then_some((ar, br, cr, s))
}

/// The Hankel singular values of the stable block (`a`, `b`, `c`), non-increasing; `None` when
/// the block is not stable.
pub(crate) fn hankel_singular_values<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b: MatRef<'_, T>,
    c: MatRef<'_, T>,
) -> Option<Vec<T>> {
    let m = a.nrows();
    if a.ncols() != m || b.nrows() != m || c.ncols() != m {
        return None;
    }
    square_roots(la, a, b, c).map(|(_, _, svd)| svd.s)
}

/// The Gramians' square roots Lc, Lo (Wc = Lc Lcᵀ, Wo = Lo Loᵀ) and the SVD of Loᵀ Lc, whose
/// singular values are the Hankel singular values.
fn square_roots<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b: MatRef<'_, T>,
    c: MatRef<'_, T>,
) -> Option<(Mat<T>, Mat<T>, crate::solvers::Svd<T>)> {
    // controllability Gramian: Wc = A Wc Aᵀ + B Bᵀ; observability: Wo = Aᵀ Wo A + Cᵀ C
    let wc = gramian(a, mul(b, b.transpose()).as_ref())?;
    let wo = gramian(a.transpose(), mul(c.transpose(), c).as_ref())?;
    let lc = psd_root(la, wc.as_ref())?;
    let lo = psd_root(la, wo.as_ref())?;
    let svd = la.svd(mul(lo.transpose(), lc.as_ref()).as_ref()).ok()?;
    Some((lc, lo, svd))
}

/// X = Σₖ Aᵏ Q (Aᵀ)ᵏ, the solution of X = A X Aᵀ + Q, by doubling (X ← X + Aₖ X Aₖᵀ, Aₖ ← Aₖ²);
/// `None` when it does not converge (A not stable) or overflows.
fn gramian<T: Real>(a: MatRef<'_, T>, q: MatRef<'_, T>) -> Option<Mat<T>> {
    let mut x = q.to_owned();
    let mut ak = a.to_owned();
    for _ in 0..MAX_DOUBLINGS {
        let add = mul(mul(ak.as_ref(), x.as_ref()).as_ref(), ak.transpose());
        let (mut big, mut small) = (T::zero(), T::zero());
        for i in 0..x.nrows() {
            for j in 0..x.ncols() {
                big = big.max(x[(i, j)].abs());
                small = small.max(add[(i, j)].abs());
                x[(i, j)] += add[(i, j)];
            }
        }
        if !(big.is_finite() && small.is_finite()) {
            return None;
        }
        if small <= big * T::epsilon() {
            // symmetric by construction up to round-off
            let sym = Mat::from_fn(x.nrows(), x.ncols(), |i, j| {
                (x[(i, j)] + x[(j, i)]) * T::lit(0.5)
            });
            return Some(sym);
        }
        ak = mul(ak.as_ref(), ak.as_ref());
    }
    None
}

/// L with L Lᵀ = W for a symmetric positive semidefinite W (W = U S Uᵀ by SVD, L = U S^½).
fn psd_root<T: Real>(la: &dyn LinAlg<T>, w: MatRef<'_, T>) -> Option<Mat<T>> {
    let svd = la.svd(w).ok()?;
    Some(Mat::from_fn(w.nrows(), svd.s.len(), |i, k| {
        svd.u[(i, k)] * svd.s[k].max(T::zero()).sqrt()
    }))
}

/// The product X Y of small matrices.
fn mul<T: Real>(x: MatRef<'_, T>, y: MatRef<'_, T>) -> Mat<T> {
    Mat::from_fn(x.nrows(), y.ncols(), |i, j| {
        let mut s = T::zero();
        for k in 0..x.ncols() {
            s += x[(i, k)] * y[(k, j)];
        }
        s
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::Faer;

    /// Markov parameters C Aᵏ B, k < len.
    fn markov(a: &Mat<f64>, b: &Mat<f64>, c: &Mat<f64>, len: usize) -> Vec<f64> {
        let mut x = b.clone();
        (0..len)
            .map(|_| {
                let h = mul(c.as_ref(), x.as_ref())[(0, 0)];
                x = mul(a.as_ref(), x.as_ref());
                h
            })
            .collect()
    }

    #[test]
    fn a_first_order_block_has_the_known_hankel_singular_value() {
        // one state: Wc = b²/(1 − ρ²), Wo = c²/(1 − ρ²), σ = |b c|/(1 − ρ²)
        let (rho, b, c): (f64, f64, f64) = (0.8, 2.0, -0.5);
        let a2 = Mat::from_fn(2, 2, |i, j| match (i, j) {
            (0, 0) => rho,
            (1, 1) => 0.1,
            _ => 0.0,
        });
        let b2 = Mat::from_fn(2, 1, |i, _| if i == 0 { b } else { 1e-3 });
        let c2 = Mat::from_fn(1, 2, |_, j| if j == 0 { c } else { 1e-3 });
        let (ar, br, cr, s) =
            balanced_truncation(&Faer::default(), a2.as_ref(), b2.as_ref(), c2.as_ref(), 1)
                .unwrap();
        assert!((ar[(0, 0)] - rho).abs() < 1e-5, "{:?}", ar);
        assert!((br[(0, 0)] * cr[(0, 0)] - b * c).abs() < 1e-4);
        assert!(
            (s[0] - (b * c).abs() / (1.0 - rho * rho)).abs() < 1e-4,
            "{s:?}"
        );
        assert!(s[1] < 1e-5);
        let hsv = hankel_singular_values(&Faer::default(), a2.as_ref(), b2.as_ref(), c2.as_ref());
        assert_eq!(hsv.unwrap(), s);
    }

    #[test]
    fn a_near_cancelled_pair_is_truncated_and_the_rest_kept() {
        // a lightly damped second-order block in series with a pole at 0.5 almost cancelled by
        // a zero (a tiny residue): order 3 truncated to 2 keeps the impulse response
        let a = Mat::from_fn(3, 3, |i, j| match (i, j) {
            (0, 0) => 1.2,
            (0, 1) => -0.72,
            (1, 0) => 1.0,
            (2, 2) => 0.5,
            _ => 0.0,
        });
        let b = Mat::from_fn(3, 1, |i, _| [1.0, 0.0, 1e-4][i]);
        let c = Mat::from_fn(1, 3, |_, j| [0.3, 0.2, 1e-4][j]);
        let (ar, br, cr, s) =
            balanced_truncation(&Faer::default(), a.as_ref(), b.as_ref(), c.as_ref(), 2).unwrap();
        assert!(s[2] < 1e-6 * s[0], "{s:?}");
        let (h, hr) = (markov(&a, &b, &c, 40), markov(&ar, &br, &cr, 40));
        for (x, y) in h.iter().zip(&hr) {
            assert!((x - y).abs() < 1e-6, "{x} {y}");
        }
        // an unstable block, or no reduction asked for, gives none
        let unstable = Mat::from_fn(3, 3, |i, j| if i == j { 1.01 } else { 0.0 });
        assert!(
            balanced_truncation(
                &Faer::default(),
                unstable.as_ref(),
                b.as_ref(),
                c.as_ref(),
                2
            )
            .is_none()
        );
        assert!(
            balanced_truncation(&Faer::default(), a.as_ref(), b.as_ref(), c.as_ref(), 3).is_none()
        );
    }
}
