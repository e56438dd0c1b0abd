//! Discrete-time linear state-space models: x(k+1) = A x(k) + B u(k), y(k) = C x(k) + D u(k).

use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::columns::{column, row_major};
use crate::solvers::recursion::{SumOrder, state_recursion};
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// A discrete-time state-space model (A, B, C, D) with its sample time.
#[derive(Debug, Clone)]
pub struct StateSpace<T: Real> {
    /// State matrix, n×n.
    pub a: Mat<T>,
    /// Input matrix, n×m.
    pub b: Mat<T>,
    /// Output matrix, l×n.
    pub c: Mat<T>,
    /// Feed-through matrix, l×m.
    pub d: Mat<T>,
    /// Sample time in seconds.
    pub ts: f64,
}

/// Transfer-function coefficients of a SISO model in powers of z⁻¹:
/// G(z) = (b0 + b1 z⁻¹ + … + bn z⁻ⁿ) / (1 + a1 z⁻¹ + … + an z⁻ⁿ).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransferFunction {
    /// Numerator b0..bn (b0 = D).
    pub numerator: Vec<f64>,
    /// Denominator 1, a1..an.
    pub denominator: Vec<f64>,
}

impl<T: Real> StateSpace<T> {
    /// Builds a model after checking that the shapes agree.
    pub fn new(a: Mat<T>, b: Mat<T>, c: Mat<T>, d: Mat<T>) -> Result<Self> {
        let n = a.nrows();
        if a.ncols() != n
            || b.nrows() != n
            || c.ncols() != n
            || d.nrows() != c.nrows()
            || d.ncols() != b.ncols()
        {
            return Err(Error::Dimension(format!(
                "A {}×{}, B {}×{}, C {}×{}, D {}×{} do not form a state-space model",
                a.nrows(),
                a.ncols(),
                b.nrows(),
                b.ncols(),
                c.nrows(),
                c.ncols(),
                d.nrows(),
                d.ncols()
            )));
        }
        Ok(Self {
            a,
            b,
            c,
            d,
            ts: 1.0,
        })
    }

    /// Builds a model from row-major nested slices (convenient in tests and examples).
    pub fn from_rows(a: &[&[f64]], b: &[&[f64]], c: &[&[f64]], d: &[&[f64]]) -> Result<Self> {
        fn m<T: Real>(r: &[&[f64]], cols_if_empty: usize) -> Result<Mat<T>> {
            let nc = r.first().map_or(cols_if_empty, |x| x.len());
            if r.iter().any(|x| x.len() != nc) {
                return Err(Error::Dimension("ragged matrix rows".into()));
            }
            Ok(Mat::from_fn(r.len(), nc, |i, j| T::lit(r[i][j])))
        }
        Self::new(
            m(a, 0)?,
            m(b, 0)?,
            m(c, a.len())?,
            m(d, b.first().map_or(0, |x| x.len()))?,
        )
    }

    /// Model order n.
    pub fn order(&self) -> usize {
        self.a.nrows()
    }
    /// Number of inputs m.
    pub fn n_inputs(&self) -> usize {
        self.b.ncols()
    }
    /// Number of outputs l.
    pub fn n_outputs(&self) -> usize {
        self.c.nrows()
    }

    /// Simulates the output for inputs `u` (N×m) from initial state `x0` (zero when `None`).
    pub fn simulate(&self, u: MatRef<'_, T>, x0: Option<&[T]>) -> Result<Mat<T>> {
        let (n, m, l) = (self.order(), self.n_inputs(), self.n_outputs());
        if u.ncols() != m {
            return Err(Error::Dimension(format!(
                "model has {m} inputs, data has {}",
                u.ncols()
            )));
        }
        let mut x: Vec<T> = match x0 {
            Some(x0) if x0.len() != n => {
                return Err(Error::Dimension(format!(
                    "initial state has {} entries, order is {n}",
                    x0.len()
                )));
            }
            Some(x0) => x0.to_vec(),
            None => vec![T::zero(); n],
        };
        // the crate's state-space kernel (`solvers::recursion`), sums from zero: C x then D u,
        // A x then B u
        let (a, b) = (row_major(self.a.as_ref()), row_major(self.b.as_ref()));
        let (c, d) = (row_major(self.c.as_ref()), row_major(self.d.as_ref()));
        let cols: Vec<Cow<'_, [T]>> = (0..m).map(|q| column(u, q)).collect();
        let cols: Vec<&[T]> = cols.iter().map(|c| c.as_ref()).collect();
        let mut y = Mat::<T>::zeros(u.nrows(), l);
        state_recursion(
            &a,
            &b,
            &cols,
            u.nrows(),
            SumOrder::StateFirst,
            &mut x,
            |k, x, uk| {
                for i in 0..l {
                    let mut s = T::zero();
                    for j in 0..n {
                        s += c[i * n + j] * x[j];
                    }
                    for j in 0..m {
                        s += d[i * m + j] * uk[j];
                    }
                    y[(k, i)] = s;
                }
            },
        );
        Ok(y)
    }

    /// Simulates a single-input single-output model on a slice.
    pub fn simulate_siso(&self, u: &[T], x0: Option<&[T]>) -> Result<Vec<T>> {
        let um = Mat::from_fn(u.len(), 1, |i, _| u[i]);
        let y = self.simulate(um.as_ref(), x0)?;
        Ok((0..u.len()).map(|i| y[(i, 0)]).collect())
    }

    /// Markov parameters C·A^k·B for k = 0..count (impulse response h(1..=count)); D is h(0).
    pub fn markov_parameters(&self, count: usize) -> Vec<Mat<T>> {
        let mut out = Vec::with_capacity(count);
        let mut akb = self.b.clone();
        for _ in 0..count {
            out.push(&self.c * &akb);
            akb = &self.a * &akb;
        }
        out
    }

    /// Eigenvalues of A as (re, im) pairs, sorted by real then imaginary part.
    pub fn poles(&self) -> Result<Vec<(f64, f64)>> {
        let n = self.order();
        if n == 0 {
            return Ok(vec![]);
        }
        let a64 = Mat::from_fn(n, n, |i, j| self.a[(i, j)].as_f64());
        let ev = a64
            .eigenvalues()
            .map_err(|e| Error::LinAlg(format!("eigenvalues of A: {e:?}")))?;
        let mut p: Vec<(f64, f64)> = ev.iter().map(|z| (z.re, z.im)).collect();
        p.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
        Ok(p)
    }

    /// Spectral radius of A.
    pub fn spectral_radius(&self) -> Result<f64> {
        spectral_radius_of(self.a.as_ref())
    }

    /// True when every pole lies strictly inside the unit circle.
    pub fn is_stable(&self) -> Result<bool> {
        Ok(self.spectral_radius()? < 1.0)
    }

    /// Transfer-function coefficients of input `input` to output `output`, in powers of z⁻¹.
    ///
    /// Denominator: characteristic polynomial of A (from its eigenvalues); numerator from the
    /// identity b_k = Σ_{j≤k} a_j h(k−j) with the Markov parameters h (exact for a realisation of order n).
    pub fn transfer_function(&self, input: usize, output: usize) -> Result<TransferFunction> {
        if input >= self.n_inputs() || output >= self.n_outputs() {
            return Err(Error::InvalidParameter(format!(
                "channel ({output}, {input}) outside {}×{}",
                self.n_outputs(),
                self.n_inputs()
            )));
        }
        let n = self.order();
        // characteristic polynomial from eigenvalues, complex product
        let poles = self.poles()?;
        let mut re = vec![1.0f64];
        let mut im = vec![0.0f64];
        for &(pr, pi) in &poles {
            let mut nre = vec![0.0; re.len() + 1];
            let mut nim = vec![0.0; im.len() + 1];
            for k in 0..re.len() {
                nre[k] += re[k];
                nim[k] += im[k];
                // multiply by -p, shift
                nre[k + 1] += -(re[k] * pr - im[k] * pi);
                nim[k + 1] += -(re[k] * pi + im[k] * pr);
            }
            re = nre;
            im = nim;
        }
        let den = re;
        let mut h = vec![self.d[(output, input)].as_f64()];
        for mk in self.markov_parameters(n) {
            h.push(mk[(output, input)].as_f64());
        }
        let num = (0..=n)
            .map(|k| (0..=k).map(|j| den[j] * h[k - j]).sum())
            .collect();
        Ok(TransferFunction {
            numerator: num,
            denominator: den,
        })
    }

    /// Frequency response G(e^{jω}) of channel (output, input) at normalised frequencies ω (rad/sample),
    /// as (re, im) pairs: C (e^{jω} I − A)⁻¹ B + D, solved by complex Gaussian elimination.
    pub fn frequency_response(
        &self,
        input: usize,
        output: usize,
        omegas: &[f64],
    ) -> Result<Vec<(f64, f64)>> {
        if input >= self.n_inputs() || output >= self.n_outputs() {
            return Err(Error::InvalidParameter("channel out of range".into()));
        }
        let n = self.order();
        let mut out = Vec::with_capacity(omegas.len());
        for &w in omegas {
            let (cw, sw) = (w.cos(), w.sin());
            // augmented complex matrix [zI - A | B]
            let mut mr = vec![vec![0.0; n + 1]; n];
            let mut mi = vec![vec![0.0; n + 1]; n];
            for i in 0..n {
                for j in 0..n {
                    mr[i][j] = -self.a[(i, j)].as_f64();
                }
                mr[i][i] += cw;
                mi[i][i] += sw;
                mr[i][n] = self.b[(i, input)].as_f64();
            }
            for col in 0..n {
                let piv = (col..n)
                    .max_by(|&p, &q| {
                        mr[p][col]
                            .hypot(mi[p][col])
                            .total_cmp(&mr[q][col].hypot(mi[q][col]))
                    })
                    .unwrap_or(col);
                mr.swap(col, piv);
                mi.swap(col, piv);
                let (pr, pi) = (mr[col][col], mi[col][col]);
                let den = pr * pr + pi * pi;
                if den == 0.0 {
                    return Err(Error::LinAlg(format!("pole on the unit circle at ω = {w}")));
                }
                for r in 0..n {
                    if r == col {
                        continue;
                    }
                    let (ar, ai) = (mr[r][col], mi[r][col]);
                    let fr = (ar * pr + ai * pi) / den;
                    let fi = (ai * pr - ar * pi) / den;
                    for k in col..=n {
                        let (br, bi) = (mr[col][k], mi[col][k]);
                        mr[r][k] -= fr * br - fi * bi;
                        mi[r][k] -= fr * bi + fi * br;
                    }
                }
            }
            let (mut gr, mut gi) = (self.d[(output, input)].as_f64(), 0.0);
            for i in 0..n {
                let (pr, pi) = (mr[i][i], mi[i][i]);
                let den = pr * pr + pi * pi;
                let (xr, xi) = (
                    (mr[i][n] * pr + mi[i][n] * pi) / den,
                    (mi[i][n] * pr - mr[i][n] * pi) / den,
                );
                let c = self.c[(output, i)].as_f64();
                gr += c * xr;
                gi += c * xi;
            }
            out.push((gr, gi));
        }
        Ok(out)
    }

    /// Converts to another scalar type.
    pub fn cast<S: Real>(&self) -> StateSpace<S> {
        let cv = |m: &Mat<T>| Mat::from_fn(m.nrows(), m.ncols(), |i, j| S::lit(m[(i, j)].as_f64()));
        StateSpace {
            a: cv(&self.a),
            b: cv(&self.b),
            c: cv(&self.c),
            d: cv(&self.d),
            ts: self.ts,
        }
    }

    /// Applies the state transformation x → T x (A → T A T⁻¹, B → T B, C → C T⁻¹) with T = diag(s).
    pub fn scale_states(&mut self, s: &[T]) {
        let n = self.order();
        for i in 0..n {
            for j in 0..n {
                self.a[(i, j)] = self.a[(i, j)] * s[i] / s[j];
            }
            for j in 0..self.n_inputs() {
                self.b[(i, j)] *= s[i];
            }
            for r in 0..self.n_outputs() {
                self.c[(r, i)] /= s[i];
            }
        }
    }
}

/// Row-major nested vectors of a matrix (for JSON output).
pub fn to_rows<T: Real>(m: MatRef<'_, T>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)].as_f64()).collect())
        .collect()
}

/// Spectral radius (largest eigenvalue magnitude, computed in f64) of a square matrix; 0 for an
/// empty one.
pub(crate) fn spectral_radius_of<T: Real>(a: MatRef<'_, T>) -> Result<f64> {
    let n = a.nrows();
    if n == 0 {
        return Ok(0.0);
    }
    let a64 = Mat::from_fn(n, n, |i, j| a[(i, j)].as_f64());
    let ev = a64
        .eigenvalues()
        .map_err(|e| Error::LinAlg(format!("eigenvalues of A: {e:?}")))?;
    Ok(ev.iter().map(|z| z.re.hypot(z.im)).fold(0.0, f64::max))
}
