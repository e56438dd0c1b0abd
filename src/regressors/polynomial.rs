//! A polynomial basis v = Σ c_j·u^j (no thresholds): a continuous baseline to compare the UDN with.
//!
//! The gains are the coefficients themselves. The loop scales g so that the linear block's first
//! Markov parameter is 1, so the coefficients are reported in that normalisation. For large |u|
//! the columns u^j are badly scaled; the loop's QR-based least squares tolerates it up to degree
//! ~7 on data in [−10, 10], but normalising the input first is advisable for higher degrees.

use super::{NonlinearitySpec, StaticNonlinearity};
use crate::error::{Error, Result};
use crate::real::Real;
use faer::Mat;

/// Polynomial basis v = Σ_{j} c_j u^j over j = 1..=degree (all powers or odd powers only).
#[derive(Debug, Clone, PartialEq)]
pub struct Polynomial<T: Real> {
    degree: usize,
    odd: bool,
    coef: Vec<T>,
}

impl<T: Real> Polynomial<T> {
    /// All powers u, u², …, u^degree; starts as v = u. Errors on degree 0.
    pub fn new(degree: usize) -> Result<Self> {
        Self::build(degree, false)
    }

    /// Odd powers only (u, u³, …, up to `degree`); starts as v = u. Errors on degree 0.
    pub fn odd(degree: usize) -> Result<Self> {
        Self::build(degree, true)
    }

    fn build(degree: usize, odd: bool) -> Result<Self> {
        if degree == 0 || degree > 15 {
            return Err(Error::InvalidParameter(format!(
                "polynomial degree must be 1..=15, got {degree}"
            )));
        }
        let n = Self::powers_of(degree, odd).len();
        let mut coef = vec![T::zero(); n];
        coef[0] = T::one();
        Ok(Polynomial { degree, odd, coef })
    }

    fn powers_of(degree: usize, odd: bool) -> Vec<i32> {
        (1..=degree as i32).filter(|j| !odd || j % 2 == 1).collect()
    }

    /// The powers used, in column order.
    pub fn powers(&self) -> Vec<i32> {
        Self::powers_of(self.degree, self.odd)
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Rebuilds from a spec of kind "poly" (config {"degree": d, "odd": bool}).
    pub fn from_spec(spec: &NonlinearitySpec) -> Result<Self> {
        let degree = spec
            .config
            .get("degree")
            .and_then(|d| d.as_u64())
            .ok_or_else(|| Error::ModelFormat("poly spec: missing integer \"degree\"".into()))?;
        let odd = spec
            .config
            .get("odd")
            .and_then(|x| x.as_bool())
            .unwrap_or(false);
        let mut p = Self::build(degree as usize, odd)?;
        if !spec.params.is_empty() {
            let c: Vec<T> = spec.params.iter().map(|&x| T::lit(x)).collect();
            p.set_params(&c)?;
        }
        Ok(p)
    }

    fn check(&self, c: &[T], what: &str) -> Result<()> {
        if c.len() != self.coef.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "{what}: {} has {} coefficients, got {}",
                    StaticNonlinearity::<T>::name(self),
                    self.coef.len(),
                    c.len()
                ),
            });
        }
        if let Some(i) = c.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                what: format!("{what} (polynomial coefficients)"),
                index: i,
            });
        }
        Ok(())
    }
}

impl<T: Real> StaticNonlinearity<T> for Polynomial<T> {
    fn name(&self) -> String {
        if self.odd {
            format!("poly{}-odd", self.degree)
        } else {
            format!("poly{}", self.degree)
        }
    }

    fn effects(&self) -> Vec<String> {
        Vec::new()
    }

    fn param_names(&self) -> Vec<String> {
        self.powers().iter().map(|j| format!("c{j}")).collect()
    }

    fn params(&self) -> Vec<T> {
        self.coef.clone()
    }

    fn rescaled(&self, input: T, output: T) -> Option<Box<dyn StaticNonlinearity<T>>> {
        let mut out = self.clone();
        for (c, &j) in out.coef.iter_mut().zip(&self.powers()) {
            *c = *c * output / input.powi(j);
        }
        Some(Box::new(out))
    }

    fn set_params(&mut self, theta: &[T]) -> Result<()> {
        self.check(theta, "parameters")?;
        self.coef.copy_from_slice(theta);
        Ok(())
    }

    fn regressor_names(&self) -> Vec<String> {
        self.powers()
            .iter()
            .map(|&j| if j == 1 { "u".into() } else { format!("u^{j}") })
            .collect()
    }

    fn n_regressors(&self) -> usize {
        self.coef.len()
    }

    fn regressors(&self, u: &[T]) -> Mat<T> {
        let pw = self.powers();
        Mat::from_fn(u.len(), pw.len(), |k, j| u[k].powi(pw[j]))
    }

    fn gains(&self) -> Vec<T> {
        self.coef.clone()
    }

    fn update_from_gains(&mut self, g: &[T], _u: &[T]) -> Result<()> {
        self.check(g, "gain vector")?;
        self.coef.copy_from_slice(g);
        Ok(())
    }

    fn initialize(&mut self, _u: &[T]) {
        self.coef.iter_mut().for_each(|c| *c = T::zero());
        self.coef[0] = T::one();
    }

    fn param_jacobian(&self, u: &[T]) -> Mat<T> {
        self.regressors(u)
    }

    fn memoryless(&self) -> bool {
        true
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "poly".into(),
            config: serde_json::json!({"degree": self.degree, "odd": self.odd}),
            param_names: StaticNonlinearity::<T>::param_names(self),
            params: self.coef.iter().map(|x| x.as_f64()).collect(),
        }
    }

    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>> {
        Box::new(self.clone())
    }
}
