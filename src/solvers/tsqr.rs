//! Chunked least squares: the R factor of a tall matrix accumulated block by block.
//!
//! Algorithm: sequential TSQR (Demmel, Grigori, Hoemmen & Langou, "Communication-optimal parallel
//! and sequential QR and LU factorizations", SIAM J. Sci. Comput. 34(1), 2012, §3 "sequential
//! TSQR"): the rows arrive in blocks of `BLOCK_ROWS`; each block is stacked under the current p×p
//! factor R and the (p + rows)×p stack is reduced by Householder QR to the next R. Q is never
//! formed. With the right-hand side appended as the last column, the last column of R holds Qᵀb
//! and its last diagonal entry ±‖b − A·x̂‖, so least squares needs O(p²) memory instead of
//! O(N·p), and the solution equals the one of a single QR of the whole matrix within rounding.

use super::LinAlg;
use super::backend::{full_rank, min_norm_solve};
use crate::error::Result;
use crate::real::Real;
use faer::Mat;

/// Rows per block (each block and the running R stay in cache for moderate p).
pub const BLOCK_ROWS: usize = 4096;

/// The R factor of a tall matrix built from rows pushed one at a time.
pub struct Tsqr<'a, T: Real> {
    la: &'a dyn LinAlg<T>,
    cols: usize,
    /// The running R (top `cols` rows) and the rows of the current block below it.
    buf: Mat<T>,
    /// Rows of `buf` in use (R's rows count once one block has been reduced).
    filled: usize,
    /// Rows pushed in total.
    rows: usize,
}

impl<'a, T: Real> Tsqr<'a, T> {
    /// An empty accumulator for rows of `cols` entries.
    pub fn new(la: &'a dyn LinAlg<T>, cols: usize) -> Self {
        Self {
            la,
            cols,
            buf: Mat::zeros(cols + BLOCK_ROWS, cols),
            filled: 0,
            rows: 0,
        }
    }

    /// Number of rows pushed so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Appends one row (its length must be the column count; extra entries are ignored, missing
    /// ones count as 0).
    pub fn push_row(&mut self, row: &[T]) -> Result<()> {
        if self.filled == self.buf.nrows() {
            self.reduce()?;
        }
        let i = self.filled;
        for j in 0..self.cols {
            self.buf[(i, j)] = row.get(j).copied().unwrap_or_else(T::zero);
        }
        self.filled += 1;
        self.rows += 1;
        Ok(())
    }

    /// Appends a block of rows (its column count must be the accumulator's), folded in
    /// `BLOCK_ROWS` rows at a time.
    pub fn push_block(&mut self, block: faer::MatRef<'_, T>) -> Result<()> {
        if block.ncols() != self.cols {
            return Err(crate::error::Error::Dimension(format!(
                "a block of {} columns pushed into a QR of {} columns",
                block.ncols(),
                self.cols
            )));
        }
        if self.filled > self.cols {
            self.reduce()?;
        }
        let mut start = 0;
        while start < block.nrows() {
            let m = BLOCK_ROWS.min(block.nrows() - start);
            self.buf
                .as_mut()
                .subrows_mut(self.cols, m)
                .copy_from(block.subrows(start, m));
            // rows of R not yet written are zero: harmless in the QR
            self.filled = self.cols + m;
            self.rows += m;
            self.reduce()?;
            start += m;
        }
        Ok(())
    }

    /// Folds the buffered rows into R.
    fn reduce(&mut self) -> Result<()> {
        let m = self.filled;
        if m == 0 {
            return Ok(());
        }
        let r = self.la.qr_r_in_place(self.buf.as_mut().subrows_mut(0, m))?;
        for j in 0..self.cols {
            for i in 0..self.cols {
                self.buf[(i, j)] = if i < r.nrows() && i <= j {
                    r[(i, j)]
                } else {
                    T::zero()
                };
            }
        }
        self.filled = self.cols;
        Ok(())
    }

    /// The upper-triangular factor R (cols × cols; zero rows when fewer rows than columns were
    /// pushed).
    pub fn finish(mut self) -> Result<Mat<T>> {
        self.reduce()?;
        let c = self.cols;
        Ok(Mat::from_fn(c, c, |i, j| {
            if i <= j && i < self.rows {
                self.buf[(i, j)]
            } else {
                T::zero()
            }
        }))
    }
}

/// Least-squares solution from the R factor of [A | b] (p + 1 columns; A had `rows` rows):
/// x with R₁₁x = r₁₂ by back substitution, or, when R₁₁ is numerically rank deficient by the
/// backends' rule for an `rows`-row problem (`full_rank`), the minimum-norm solution by the SVD
/// of R₁₁ (the same solution as the SVD of A, Q being orthogonal); and the residual sum of
/// squares r₂₂².
pub fn solve_from_r<T: Real>(la: &dyn LinAlg<T>, r: &Mat<T>, rows: usize) -> Result<(Vec<T>, T)> {
    let p = r.ncols().saturating_sub(1);
    let rss = if p < r.nrows() {
        r[(p, p)] * r[(p, p)]
    } else {
        T::zero()
    };
    if p == 0 {
        return Ok((Vec::new(), rss));
    }
    let rows = rows.max(p);
    if full_rank((0..p).map(|i| r[(i, i)]), rows) {
        let mut x = vec![T::zero(); p];
        for i in (0..p).rev() {
            let mut s = r[(i, p)];
            for j in i + 1..p {
                s -= r[(i, j)] * x[j];
            }
            x[i] = s / r[(i, i)];
        }
        return Ok((x, rss));
    }
    let r11 = r.as_ref().submatrix(0, 0, p, p);
    let rhs = r.as_ref().submatrix(0, p, p, 1);
    let x = min_norm_solve(&la.svd(r11)?, rhs, rows);
    Ok(((0..p).map(|i| x[(i, 0)]).collect(), rss))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::Faer;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    #[test]
    fn chunked_least_squares_matches_one_qr() {
        let la = Faer::default();
        let mut rng = StdRng::seed_from_u64(7);
        let (n, p) = (3 * BLOCK_ROWS + 123, 5);
        let a = Mat::<f64>::from_fn(n, p, |_, _| rng.random_range(-1.0..1.0));
        let b = Mat::<f64>::from_fn(n, 1, |k, _| {
            (0..p).map(|j| (j as f64 + 1.0) * a[(k, j)]).sum::<f64>()
                + 0.1 * rng.random_range(-1.0..1.0)
        });
        let mut t = Tsqr::new(&la, p + 1);
        let mut row = vec![0.0; p + 1];
        for k in 0..n {
            for j in 0..p {
                row[j] = a[(k, j)];
            }
            row[p] = b[(k, 0)];
            t.push_row(&row).unwrap();
        }
        assert_eq!(t.rows(), n);
        let r = t.finish().unwrap();
        let (x, rss) = solve_from_r(&la, &r, n).unwrap();
        let direct = la.lstsq(a.as_ref(), b.as_ref()).unwrap();
        let res: f64 = (0..n)
            .map(|k| (b[(k, 0)] - (0..p).map(|j| a[(k, j)] * direct[(j, 0)]).sum::<f64>()).powi(2))
            .sum();
        for j in 0..p {
            assert!(
                (x[j] - direct[(j, 0)]).abs() < 1e-12,
                "{j}: {} {}",
                x[j],
                direct[(j, 0)]
            );
        }
        assert!((rss - res).abs() < 1e-9 * res, "{rss} {res}");
    }

    #[test]
    fn blocks_and_rows_give_the_same_factor() {
        let la = Faer::default();
        let mut rng = StdRng::seed_from_u64(9);
        let (n, p) = (2 * BLOCK_ROWS + 77, 4);
        let a = Mat::<f64>::from_fn(n, p, |_, _| rng.random_range(-1.0..1.0));
        let mut by_rows = Tsqr::new(&la, p);
        for k in 0..n {
            let row: Vec<f64> = (0..p).map(|j| a[(k, j)]).collect();
            by_rows.push_row(&row).unwrap();
        }
        let mut by_blocks = Tsqr::new(&la, p);
        by_blocks.push_block(a.as_ref().subrows(0, 1000)).unwrap();
        by_blocks
            .push_block(a.as_ref().subrows(1000, n - 1000))
            .unwrap();
        assert_eq!(by_blocks.rows(), n);
        let (r1, r2) = (by_rows.finish().unwrap(), by_blocks.finish().unwrap());
        for i in 0..p {
            for j in i..p {
                // R is unique up to the signs of its rows
                assert!((r1[(i, j)].abs() - r2[(i, j)].abs()).abs() < 1e-10);
            }
        }
        assert!(Tsqr::new(&la, 3).push_block(a.as_ref()).is_err());
    }

    #[test]
    fn fewer_rows_than_columns_give_zero_rows() {
        let la = Faer::default();
        let mut t = Tsqr::new(&la, 3);
        t.push_row(&[1.0f64, 2.0, 3.0]).unwrap();
        let r = t.finish().unwrap();
        assert!((r[(0, 0)].abs() - 1.0).abs() < 1e-15);
        assert_eq!(r[(1, 1)], 0.0);
        assert_eq!(r[(2, 2)], 0.0);
    }
}
