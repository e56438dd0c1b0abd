//! User-defined bases: columns given as closures of (u(k), s(k)), alone ([`UserBasis`]) or appended
//! to a built-in nonlinearity ([`Augmented`]).
//!
//! A user column is θ-free: its gain is estimated by the linear step and reported as a parameter.
//! The user is responsible for not adding columns collinear with the others (e.g. a constant
//! when the base already [`spans_constant`](StaticNonlinearity::spans_constant)).

use super::direction::DirectionTracker;
use super::{NonlinearitySpec, StaticNonlinearity, from_spec};
use crate::error::{Error, Result};
use crate::real::Real;
use faer::Mat;
use std::sync::Arc;

/// One user regressor column: a name and a function of (u(k), s(k)) with s the input direction.
#[derive(Clone)]
pub struct UserColumn<T: Real> {
    name: String,
    f: Arc<dyn Fn(T, T) -> T + Send + Sync>,
}

impl<T: Real> UserColumn<T> {
    /// A column `name` computed as f(u(k), s(k)).
    pub fn new(name: impl Into<String>, f: impl Fn(T, T) -> T + Send + Sync + 'static) -> Self {
        UserColumn {
            name: name.into(),
            f: Arc::new(f),
        }
    }
    /// The column's name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Evaluates the column at one sample.
    pub fn eval(&self, u: T, s: T) -> T {
        (self.f)(u, s)
    }
}

impl<T: Real> std::fmt::Debug for UserColumn<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "UserColumn({})", self.name)
    }
}

/// Fills columns `offset..offset + cols.len()` of `phi` with the user columns (no allocation).
fn fill_columns<T: Real>(phi: &mut Mat<T>, offset: usize, cols: &[UserColumn<T>], u: &[T]) {
    let mut dir = DirectionTracker::<T>::new();
    for (k, &uk) in u.iter().enumerate() {
        let s = dir.next(uk);
        for (j, c) in cols.iter().enumerate() {
            phi[(k, offset + j)] = c.eval(uk, s);
        }
    }
}

fn check_gains<T: Real>(g: &[T], n: usize, who: &str) -> Result<()> {
    if g.len() != n {
        return Err(Error::LengthMismatch {
            what: format!("{who} has {n} gains, got {}", g.len()),
        });
    }
    if let Some(i) = g.iter().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite {
            what: format!("{who} gains"),
            index: i,
        });
    }
    Ok(())
}

fn check_names<T: Real>(cols: &[UserColumn<T>], reserved: &[String]) -> Result<()> {
    for (i, c) in cols.iter().enumerate() {
        if c.name.trim().is_empty() {
            return Err(Error::InvalidParameter(format!(
                "user column {i} has an empty name"
            )));
        }
        if cols[..i].iter().any(|d| d.name == c.name) || reserved.contains(&c.name) {
            return Err(Error::DuplicateRegressor {
                name: c.name.clone(),
            });
        }
    }
    Ok(())
}

/// A basis made only of user columns: v = Σ g_j·f_j(u, s); parameters are the gains.
#[derive(Debug, Clone)]
pub struct UserBasis<T: Real> {
    name: String,
    effects: Vec<String>,
    cols: Vec<UserColumn<T>>,
    gains: Vec<T>,
}

impl<T: Real> UserBasis<T> {
    /// A basis `name` modelling `effects` (free-form names) with the given columns; initial gains
    /// are 1 for the first column and 0 for the others. Errors on no column or duplicate names.
    pub fn new(
        name: impl Into<String>,
        effects: &[&str],
        cols: Vec<UserColumn<T>>,
    ) -> Result<Self> {
        if cols.is_empty() {
            return Err(Error::InvalidParameter(
                "a user basis needs at least one column".into(),
            ));
        }
        check_names(&cols, &[])?;
        let mut gains = vec![T::zero(); cols.len()];
        gains[0] = T::one();
        Ok(UserBasis {
            name: name.into(),
            effects: effects.iter().map(|s| s.to_string()).collect(),
            cols,
            gains,
        })
    }

    /// Rebuilds from a spec written by [`spec`](StaticNonlinearity::spec), given the same columns
    /// (closures cannot be serialised); errors when the column names differ.
    pub fn from_spec(spec: &NonlinearitySpec, cols: Vec<UserColumn<T>>) -> Result<Self> {
        let names: Vec<String> = cols.iter().map(|c| c.name.clone()).collect();
        if spec.param_names != names {
            return Err(Error::ModelFormat(format!(
                "user basis '{}': saved columns {:?} differ from the supplied {:?}",
                spec.kind, spec.param_names, names
            )));
        }
        let effects: Vec<String> = spec
            .config
            .get("effects")
            .and_then(|e| e.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default();
        let refs: Vec<&str> = effects.iter().map(String::as_str).collect();
        let mut b = Self::new(spec.kind.clone(), &refs, cols)?;
        let g: Vec<T> = spec.params.iter().map(|&x| T::lit(x)).collect();
        b.set_params(&g)?;
        Ok(b)
    }
}

impl<T: Real> StaticNonlinearity<T> for UserBasis<T> {
    fn name(&self) -> String {
        self.name.clone()
    }
    fn effects(&self) -> Vec<String> {
        self.effects.clone()
    }
    fn param_names(&self) -> Vec<String> {
        self.cols.iter().map(|c| c.name.clone()).collect()
    }
    fn params(&self) -> Vec<T> {
        self.gains.clone()
    }
    fn set_params(&mut self, theta: &[T]) -> Result<()> {
        check_gains(theta, self.cols.len(), &self.name)?;
        self.gains.copy_from_slice(theta);
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        StaticNonlinearity::<T>::param_names(self)
    }
    fn n_regressors(&self) -> usize {
        self.cols.len()
    }
    fn regressors(&self, u: &[T]) -> Mat<T> {
        let mut phi = Mat::zeros(u.len(), self.cols.len());
        fill_columns(&mut phi, 0, &self.cols, u);
        phi
    }
    fn gains(&self) -> Vec<T> {
        self.gains.clone()
    }
    fn update_from_gains(&mut self, g: &[T], _u: &[T]) -> Result<()> {
        self.set_params(g)
    }
    fn initialize(&mut self, _u: &[T]) {
        self.gains.iter_mut().for_each(|g| *g = T::zero());
        self.gains[0] = T::one();
    }
    fn param_jacobian(&self, u: &[T]) -> Mat<T> {
        self.regressors(u)
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: self.name.clone(),
            config: serde_json::json!({"user": true, "effects": self.effects}),
            param_names: StaticNonlinearity::<T>::param_names(self),
            params: self.gains.iter().map(|x| x.as_f64()).collect(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>> {
        Box::new(self.clone())
    }
}

/// A built-in (or any) nonlinearity with extra user columns appended: v = φ_base·g_base + Σ k_j·f_j.
///
/// Parameters are the base's θ followed by the extra gains (named after their columns), so the
/// base's [`searched_params`](StaticNonlinearity::searched_params) indices stay valid.
#[derive(Debug, Clone)]
pub struct Augmented<T: Real> {
    base: Box<dyn StaticNonlinearity<T>>,
    extra: Vec<UserColumn<T>>,
    k: Vec<T>,
}

impl<T: Real> Augmented<T> {
    /// `base` plus the extra columns (gains start at 0). Errors on duplicate column names.
    pub fn new(
        base: impl StaticNonlinearity<T> + 'static,
        extra: Vec<UserColumn<T>>,
    ) -> Result<Self> {
        Self::from_box(Box::new(base), extra)
    }

    /// Same as [`new`](Self::new) with a boxed base.
    pub fn from_box(
        base: Box<dyn StaticNonlinearity<T>>,
        extra: Vec<UserColumn<T>>,
    ) -> Result<Self> {
        let mut reserved = base.regressor_names();
        reserved.extend(base.param_names());
        check_names(&extra, &reserved)?;
        let k = vec![T::zero(); extra.len()];
        Ok(Augmented { base, extra, k })
    }

    /// The base nonlinearity.
    pub fn base(&self) -> &dyn StaticNonlinearity<T> {
        self.base.as_ref()
    }

    /// Rebuilds from a spec of kind "augmented": the base from its own spec (built-in kinds), the
    /// extra columns from `extra` (names must match the saved ones).
    pub fn from_spec(spec: &NonlinearitySpec, extra: Vec<UserColumn<T>>) -> Result<Self> {
        let bad = |m: &str| Error::ModelFormat(format!("augmented spec: {m}"));
        let base_spec: NonlinearitySpec = spec
            .config
            .get("base")
            .cloned()
            .ok_or_else(|| bad("missing \"base\""))
            .and_then(|b| serde_json::from_value(b).map_err(|e| bad(&e.to_string())))?;
        let base = from_spec::<T>(&base_spec)?;
        let saved: Vec<String> = spec
            .config
            .get("columns")
            .and_then(|c| c.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default();
        let names: Vec<String> = extra.iter().map(|c| c.name.clone()).collect();
        if saved != names {
            return Err(bad(&format!(
                "saved columns {saved:?} differ from the supplied {names:?}"
            )));
        }
        let mut a = Self::from_box(base, extra)?;
        let theta: Vec<T> = spec.params.iter().map(|&x| T::lit(x)).collect();
        a.set_params(&theta)?;
        Ok(a)
    }
}

impl<T: Real> StaticNonlinearity<T> for Augmented<T> {
    fn name(&self) -> String {
        let extra: Vec<&str> = self.extra.iter().map(|c| c.name.as_str()).collect();
        format!("{}+{}", self.base.name(), extra.join("+"))
    }
    fn effects(&self) -> Vec<String> {
        self.base.effects()
    }
    fn param_names(&self) -> Vec<String> {
        let mut n = self.base.param_names();
        n.extend(self.extra.iter().map(|c| c.name.clone()));
        n
    }
    fn params(&self) -> Vec<T> {
        let mut p = self.base.params();
        p.extend_from_slice(&self.k);
        p
    }
    fn set_params(&mut self, theta: &[T]) -> Result<()> {
        let nb = self.base.param_names().len();
        if theta.len() != nb + self.k.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "{} has {} parameters, got {}",
                    StaticNonlinearity::<T>::name(self),
                    nb + self.k.len(),
                    theta.len()
                ),
            });
        }
        check_gains(&theta[nb..], self.k.len(), "extra columns")?;
        self.base.set_params(&theta[..nb])?;
        self.k.copy_from_slice(&theta[nb..]);
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        let mut n = self.base.regressor_names();
        n.extend(self.extra.iter().map(|c| c.name.clone()));
        n
    }
    fn n_regressors(&self) -> usize {
        self.base.n_regressors() + self.extra.len()
    }
    fn regressors(&self, u: &[T]) -> Mat<T> {
        let pb = self.base.regressors(u);
        let rb = pb.ncols();
        let mut phi = Mat::zeros(u.len(), rb + self.extra.len());
        phi.as_mut()
            .submatrix_mut(0, 0, u.len(), rb)
            .copy_from(pb.as_ref());
        fill_columns(&mut phi, rb, &self.extra, u);
        phi
    }
    fn gains(&self) -> Vec<T> {
        let mut g = self.base.gains();
        g.extend_from_slice(&self.k);
        g
    }
    fn update_from_gains(&mut self, g: &[T], u: &[T]) -> Result<()> {
        let rb = self.base.n_regressors();
        check_gains(g, rb + self.k.len(), &StaticNonlinearity::<T>::name(self))?;
        self.base.update_from_gains(&g[..rb], u)?;
        self.k.copy_from_slice(&g[rb..]);
        Ok(())
    }
    fn searched_params(&self) -> Vec<usize> {
        self.base.searched_params()
    }
    fn search_range(&self, index: usize, u: &[T]) -> (T, T) {
        self.base.search_range(index, u)
    }
    fn initialize(&mut self, u: &[T]) {
        self.base.initialize(u);
        self.k.iter_mut().for_each(|k| *k = T::zero());
    }
    fn param_jacobian(&self, u: &[T]) -> Mat<T> {
        let jb = self.base.param_jacobian(u);
        let nb = jb.ncols();
        let mut jac = Mat::zeros(u.len(), nb + self.extra.len());
        jac.as_mut()
            .submatrix_mut(0, 0, u.len(), nb)
            .copy_from(jb.as_ref());
        fill_columns(&mut jac, nb, &self.extra, u);
        jac
    }
    fn spans_constant(&self) -> bool {
        self.base.spans_constant()
    }
    fn constant_pair(&self) -> Option<(usize, usize)> {
        // the base's columns come first
        self.base.constant_pair()
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "augmented".into(),
            config: serde_json::json!({
                "base": self.base.spec(),
                "columns": self.extra.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
            }),
            param_names: StaticNonlinearity::<T>::param_names(self),
            params: self.params().iter().map(|x| x.as_f64()).collect(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>> {
        Box::new(self.clone())
    }
}
