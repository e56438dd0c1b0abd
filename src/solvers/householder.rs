//! Unblocked Householder QR of a tall, narrow matrix in faer's storage: LAPACK's DGEQR2 (a
//! reflector per column, DLARFG, applied to the trailing columns, DLARF), written as faer 0.24's
//! `qr_in_place_unblocked` (whose reflector convention, H = I − v vᵀ/τ with v₀ = 1, and whose
//! skipping of negligible columns it keeps), with two changes for speed:
//! - a column's norm is the square root of its plain sum of squares (faer's SIMD `norm_l2_sqr`)
//!   whenever that sum can neither overflow nor lose its terms to underflow, and faer's scaled
//!   norm (Blue's algorithm) otherwise;
//! - each reflector is applied to the trailing columns by two matrix products (wᵀ = vᵀA, then
//!   A −= v wᵀ/τ), faer's SIMD kernels, instead of a dot product and a scalar update per column.

use crate::real::Real;
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, ColRef, MatMut, Par, Row, RowMut};

/// The 2-norm of `x`: √(Σ xᵢ²) when that sum is finite and not below √(smallest normal) — then no
/// square overflowed and the squares lost to underflow weigh at most n·tiny/√tiny relatively —
/// else faer's overflow- and underflow-safe norm.
pub(crate) fn norm2<T: Real>(x: ColRef<'_, T>) -> T {
    let s = x.squared_norm_l2();
    if s.is_finite() && s >= T::min_positive_value().sqrt() {
        s.sqrt()
    } else {
        x.norm_l2()
    }
}

/// Householder QR of `a` in place (R on and above the diagonal, the reflectors' essential parts
/// below it, their τ in `tau`), as faer's `qr_in_place` with block size 1 stores it; returns the
/// numerical rank faer's loop counts (columns whose remaining norm is negligible are skipped).
/// The τ of the rows past that rank are ∞ (identity reflectors).
pub(crate) fn qr_unblocked_in_place<T: Real>(
    mut a: MatMut<'_, T>,
    mut tau: RowMut<'_, T>,
) -> usize {
    let (m, n) = a.shape();
    let size = tau.ncols();
    let mut w = Row::<T>::zeros(n);
    let (mut row, mut col) = (0usize, 0usize);
    let eps = T::epsilon();
    let tiny = T::min_positive_value();
    while row < size.min(m) && col < n {
        let above = norm2(a.rb().col(col).get(..row));
        let (mut a00, a01, a10, a11) = a.rb_mut().split_at_mut(row + 1, col + 1);
        let (mut a10l, a10r) = a10.split_at_col_mut(col);
        let mut a10r = a10r.col_mut(0);
        let a01 = a01.row_mut(row);
        let head = &mut a00[(row, col)];
        // the reflector of the column's part from `row` down (DLARFG; faer's make_householder)
        let tail_norm = norm2(a10r.rb());
        let mut head_norm = head.abs();
        if head_norm < tiny {
            *head = T::zero();
            head_norm = T::zero();
        }
        let (t, norm) = if tail_norm < tiny {
            (T::infinity(), head_norm)
        } else {
            let norm = head_norm.hypot(tail_norm);
            let sign = if head_norm != T::zero() {
                head.signum()
            } else {
                T::one()
            };
            let signed = sign * norm;
            let inv = (*head + signed).recip();
            if row == col {
                a10r.rb_mut().iter_mut().for_each(|e| *e *= inv);
            } else {
                let dst = a10l.rb_mut().col_mut(row);
                dst.iter_mut()
                    .zip(a10r.rb().iter())
                    .for_each(|(o, e)| *o = *e * inv);
            }
            *head = -signed;
            let r = tail_norm * inv.abs();
            (T::lit(0.5) * (T::one() + r * r), norm)
        };
        if row != col {
            // the column's entries under the staircase's step (faer clears them in any case)
            let k = a10r.nrows().min(col - row);
            a10r.rb_mut().get_mut(..k).fill(T::zero());
        }
        let v = if row == col {
            a10r.rb()
        } else {
            a10l.rb().col(row)
        };
        let total = norm.hypot(above);
        let threshold = eps * T::from_usize((m - row) * 16) * total;
        let t_inv = t.recip();
        tau[row] = t;
        if t_inv < tiny {
            if norm > T::zero() {
                row += 1;
            }
        } else if norm > threshold {
            // DLARF: wᵀ = a01 + vᵀ a11, then a01 −= wᵀ/τ and a11 −= v wᵀ/τ
            let ncols = a01.ncols();
            if ncols > 0 {
                let mut wr = w.as_mut().get_mut(..ncols);
                wr.copy_from(a01.rb());
                matmul(
                    wr.rb_mut().as_mat_mut(),
                    Accum::Add,
                    v.transpose().as_mat(),
                    a11.rb(),
                    T::one(),
                    Par::Seq,
                );
                let k = -t_inv;
                wr.rb_mut().iter_mut().for_each(|x| *x *= k);
                a01.iter_mut()
                    .zip(wr.rb().iter())
                    .for_each(|(h, x)| *h += *x);
                let mut a11 = a11;
                matmul(
                    a11.rb_mut(),
                    Accum::Add,
                    v.as_mat(),
                    wr.rb().as_mat(),
                    T::one(),
                    Par::Seq,
                );
            }
            row += 1;
        }
        col += 1;
    }
    // the reflectors of the rows the loop never reached (a rank-deficient matrix) are the
    // identity, τ = ∞, as faer's `qr_in_place` sets them after its loop (left at 0, a later
    // Qᵀb is not finite)
    for k in row..size {
        tau[k] = T::infinity();
    }
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::qr::no_pivoting::factor::{qr_in_place, qr_in_place_scratch};

    /// faer's `qr_in_place` with block size 1: the reference this kernel reproduces.
    fn faer_qr<T: Real>(a: &Mat<T>) -> (Mat<T>, Mat<T>) {
        let mut a = a.clone();
        let (m, n) = a.shape();
        let mut q = Mat::<T>::zeros(1, m.min(n));
        let scratch = qr_in_place_scratch::<T>(m, n, 1, Par::Seq, Default::default());
        let mut mem = MemBuffer::new(scratch);
        let stack = MemStack::new(&mut mem);
        qr_in_place(a.as_mut(), q.as_mut(), Par::Seq, stack, Default::default());
        (a, q)
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    /// Every entry of the factors and every τ agrees with faer's to `tol` relative, on tall,
    /// square and wide matrices, with a repeated and a zero column (the rank handling), and at
    /// scales where the plain sum of squares would under- or overflow.
    fn agrees_with_faer<T: Real>(scales: &[f64], tol: f64) {
        let mut s = 7u64;
        let shapes = [
            (200usize, 12usize),
            (2000, 17),
            (50, 7),
            (31, 31),
            (9, 14),
            (1, 3),
        ];
        for &(m, n) in &shapes {
            for &scale in scales {
                let mut a = Mat::from_fn(m, n, |_, _| T::lit(lcg(&mut s) * scale));
                if n > 5 {
                    for i in 0..m {
                        a[(i, 3)] = a[(i, 1)];
                        a[(i, 5)] = T::zero();
                    }
                }
                let (fa, fq) = faer_qr(&a);
                let mut b = a.clone();
                let mut q = Mat::<T>::zeros(1, m.min(n));
                let rank = qr_unblocked_in_place(b.as_mut(), q.as_mut().row_mut(0));
                // past the rank: identity reflectors (τ = ∞), as faer's
                assert!((rank..m.min(n)).all(|j| {
                    q[(0, j)].as_f64() == f64::INFINITY && fq[(0, j)].as_f64() == f64::INFINITY
                }));
                let big = fa.norm_max().as_f64();
                for i in 0..m {
                    for j in 0..n {
                        let (x, y) = (fa[(i, j)].as_f64(), b[(i, j)].as_f64());
                        // R's entries scale with the matrix, the reflectors' are O(1) (below
                        // the diagonal, R's staircase after a skipped column is relative)
                        let unit = if i <= j { big } else { x.abs().max(1.0) };
                        assert!(
                            (x - y).abs() <= tol * unit,
                            "{m}x{n} at {scale:e}, ({i},{j}): {x} vs {y}"
                        );
                    }
                }
                for j in 0..rank {
                    let (x, y) = (fq[(0, j)].as_f64(), q[(0, j)].as_f64());
                    assert!(
                        x == y || (x.is_finite() && (x - y).abs() <= tol * x.abs()),
                        "{m}x{n} at {scale:e}, tau {j}: {x} vs {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn factors_agree_with_faers_unblocked_qr_in_f64() {
        agrees_with_faer::<f64>(&[1.0, 1e-170, 1e160, 1e300, 1e-310], 1e-12);
    }

    #[test]
    fn factors_agree_with_faers_unblocked_qr_in_f32() {
        agrees_with_faer::<f32>(&[1.0, 1e-25, 1e20], 2e-4);
    }

    #[test]
    fn the_norm_is_exact_where_the_sum_of_squares_would_fail() {
        let big = faer::col![3e200f64, 4e200];
        assert!((norm2(big.as_ref()) / 5e200 - 1.0).abs() < 1e-15);
        let small = faer::col![3e-200f64, 4e-200];
        assert!((norm2(small.as_ref()) / 5e-200 - 1.0).abs() < 1e-15);
        let zero = faer::col![0.0f64, 0.0];
        assert_eq!(norm2(zero.as_ref()), 0.0);
        let plain = faer::col![3.0f64, 4.0];
        assert_eq!(norm2(plain.as_ref()), 5.0);
    }
}
