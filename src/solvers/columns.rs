//! Columns of faer matrices as plain slices, for the loops that build or scan them one column at
//! a time (owned faer matrices are column-major with contiguous columns; views may be strided).

use crate::real::Real;
use faer::{ColRef, Mat, MatRef};
use std::borrow::Cow;

/// Column `q` of `m` as a slice: borrowed when contiguous, copied otherwise.
pub(crate) fn column<T: Real>(m: MatRef<'_, T>, q: usize) -> Cow<'_, [T]> {
    col_slice(m.col(q))
}

/// A column view as a slice: borrowed when contiguous, copied otherwise.
pub(crate) fn col_slice<T: Real>(col: ColRef<'_, T>) -> Cow<'_, [T]> {
    match col.try_as_col_major() {
        Some(c) => Cow::Borrowed(c.as_slice()),
        None => Cow::Owned(col.iter().copied().collect()),
    }
}

/// Every column of an owned matrix as a mutable slice.
pub(crate) fn columns_mut<T: Real>(m: &mut Mat<T>) -> Vec<&mut [T]> {
    m.col_iter_mut()
        .map(|col| {
            col.try_as_col_major_mut()
                .expect("owned faer columns are contiguous")
                .as_slice_mut()
        })
        .collect()
}

/// An n×n matrix copied row-major (`out[i·n + j] = a[(i, j)]`), for tight inner loops.
pub(crate) fn row_major<T: Real>(a: MatRef<'_, T>) -> Vec<T> {
    let (r, c) = (a.nrows(), a.ncols());
    (0..r * c).map(|ij| a[(ij / c, ij % c)]).collect()
}

/// Whether every value is finite: 0·x is 0 for a finite x and NaN otherwise, and a sum with a
/// NaN stays NaN; eight independent sums without an early exit, so the loop vectorises.
pub(crate) fn all_finite<T: Real>(s: &[T]) -> bool {
    let mut acc = [T::zero(); 8];
    let chunks = s.chunks_exact(8);
    let rest = chunks.remainder();
    for c in chunks {
        for i in 0..8 {
            acc[i] += c[i] * T::zero();
        }
    }
    let mut t = acc.iter().fold(T::zero(), |x, &y| x + y);
    for &v in rest {
        t += v * T::zero();
    }
    t == T::zero()
}
