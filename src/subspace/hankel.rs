//! Data compression: the R factor of the block-Hankel matrix, accumulated block by block so that
//! the Hankel matrix is never formed (memory O((2i(m+l))²), time linear in N).

use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::Mat;

/// Rows of the transposed block-Hankel matrix processed per QR update.
const CHUNK: usize = 4096;

/// Upper-triangular R (K×K, K = 2i(m+l)) with Rᵀ R = Hᵀ H, where row k of H is
/// [u(k+i..k+2i), u(k..k+i), y(k..k+i), y(k+i..k+2i)] (U_f, U_p, Y_p, Y_f; samples flattened
/// time-major). Several experiments are stacked, i.e. their R factors accumulated
/// (MOESP/N4SID multi-experiment form, as SLICOT IB01MD with BATCH = 'F','I','L').
pub fn accumulate_r<T: Real>(
    la: &dyn LinAlg<T>,
    data: &[IoView<'_, T>],
    i: usize,
) -> Result<(Mat<T>, usize)> {
    if i == 0 {
        return Err(Error::InvalidParameter("horizon must be at least 1".into()));
    }
    let m = data[0].u.ncols();
    let l = data[0].y.ncols();
    let kc = 2 * i * (m + l);
    let mut r: Mat<T> = Mat::zeros(0, kc);
    let mut total = 0usize;
    for (e, d) in data.iter().enumerate() {
        if d.u.ncols() != m || d.y.ncols() != l {
            return Err(Error::Dimension(format!(
                "experiment {e} has different channel counts"
            )));
        }
        let n = d.len();
        if n < 2 * i {
            return Err(Error::TooFewSamples {
                needed: 2 * i,
                got: n,
                reason: format!("experiment {e} with horizon {i}"),
            });
        }
        total += n;
        let rows = n - 2 * i + 1;
        let mut start = 0;
        while start < rows {
            let len = CHUNK.min(rows - start);
            let prev = r.nrows();
            let mut blk = Mat::<T>::zeros(prev + len, kc);
            for a in 0..prev {
                for b in a..kc {
                    blk[(a, b)] = r[(a, b)];
                }
            }
            for kk in 0..len {
                let k = start + kk;
                let row = prev + kk;
                let mut c = 0;
                for t in 0..i {
                    for q in 0..m {
                        blk[(row, c)] = d.u[(k + i + t, q)];
                        c += 1;
                    }
                }
                for t in 0..i {
                    for q in 0..m {
                        blk[(row, c)] = d.u[(k + t, q)];
                        c += 1;
                    }
                }
                for t in 0..i {
                    for q in 0..l {
                        blk[(row, c)] = d.y[(k + t, q)];
                        c += 1;
                    }
                }
                for t in 0..i {
                    for q in 0..l {
                        blk[(row, c)] = d.y[(k + i + t, q)];
                        c += 1;
                    }
                }
            }
            r = la.qr_r(blk.as_ref())?;
            start += len;
        }
    }
    // pad to K×K when there were fewer rows than columns
    if r.nrows() < kc {
        let mut full = Mat::<T>::zeros(kc, kc);
        for a in 0..r.nrows() {
            for b in 0..kc {
                full[(a, b)] = r[(a, b)];
            }
        }
        r = full;
    }
    Ok((r, total))
}
