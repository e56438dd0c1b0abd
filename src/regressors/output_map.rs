//! Static output maps y = g(x) after the linear block (the Wiener side of a Hammerstein–Wiener
//! model): the [`OutputMap`] trait and the built-ins — a polynomial of degree K
//! ([`PolynomialMap`], `poly3` by default), a saturation ([`SaturationMap`]) and a
//! piecewise-linear map with K knots ([`PiecewiseLinearMap`], `pwl:K`).
//!
//! Identifiability: in u → N → G → g → y the gain is shared three ways (N·G by the settings'
//! normalisation, and G·g: g(x) and g(x/α) after G·α give the same y). Every built-in map is
//! normalised to **unit slope and zero value at the operating point x = 0** (the linear block's
//! output when N(u) = 0 and the free response has died out): g(x) = x + (terms whose value and
//! slope vanish at 0). Then the small-signal gain from u to y is carried by N·G alone and the map
//! only describes the departure from it; an output offset c is added after the map
//! (y = g(x) + c). A user's map must fix the same two degrees of freedom (or the refinement's
//! Jacobian is rank deficient and the standard errors of its parameters are +∞).

use super::NonlinearitySpec;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::{BackendKind, backend};
use faer::Mat;

/// A static output map y = g(x; w) applied to the linear block's output x, with its parameters w.
///
/// The fit starts it with [`initialize`](Self::initialize) and refines w with the rest of the
/// model by Levenberg–Marquardt (it needs [`derivative`](Self::derivative) for the chain rule
/// and [`param_jacobian`](Self::param_jacobian)).
pub trait OutputMap<T: Real>: Send + Sync + std::fmt::Debug {
    /// Short name as given on the command line ("poly3", "saturation", "pwl:5", or a user's).
    fn name(&self) -> String;
    /// Names of the parameters, in the order of [`params`](Self::params).
    fn param_names(&self) -> Vec<String>;
    /// Current parameters w.
    fn params(&self) -> Vec<T>;
    /// Sets the parameters; errors on a wrong length or an inadmissible value.
    fn set_params(&mut self, w: &[T]) -> Result<()>;
    /// Evaluates y = g(x) sample by sample.
    fn eval(&self, x: &[T]) -> Vec<T>;
    /// The slope g'(x) sample by sample (almost everywhere).
    fn derivative(&self, x: &[T]) -> Vec<T>;
    /// ∂g/∂w, N×(number of parameters).
    fn param_jacobian(&self, x: &[T]) -> Mat<T>;
    /// Starts the map from the linear block's output `x` (offset removed) and the measured
    /// output `y`: sets w and returns (s, c) with y ≈ g(s·x) + c (s rescales the linear block).
    /// Default: parameters unchanged, (s, c) by least squares of y on (x, 1).
    fn initialize(&mut self, x: &[T], y: &[T]) -> Result<(T, T)> {
        let (coef, _) = least_squares(y, &[x.to_vec(), vec![T::one(); x.len()]])?;
        Ok((coef[0], coef[1]))
    }
    /// The same map for other units: g'(x) = s·g(x/s) (s > 0; the map's input and output are
    /// both in the output's units). `None` when the map cannot express it; the fit then works in
    /// the record's units.
    fn rescaled(&self, _s: T) -> Option<Box<dyn OutputMap<T>>> {
        None
    }
    /// A serialisable description (kind, configuration, parameters).
    fn spec(&self) -> NonlinearitySpec;
    /// Clones into a box.
    fn clone_box(&self) -> Box<dyn OutputMap<T>>;
}

impl<T: Real> Clone for Box<dyn OutputMap<T>> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// Least squares of `y` on the columns `cols`: the coefficients and the residual sum of squares.
fn least_squares<T: Real>(y: &[T], cols: &[Vec<T>]) -> Result<(Vec<T>, f64)> {
    let nn = y.len();
    let p = cols.len();
    if nn < p + 1 {
        return Err(Error::TooFewSamples {
            needed: p + 1,
            got: nn,
            reason: "initialising the output map".into(),
        });
    }
    let a = Mat::from_fn(nn, p, |k, j| cols[j][k]);
    let b = Mat::from_fn(nn, 1, |k, _| y[k]);
    let sol = backend::<T>(BackendKind::Faer)?.lstsq(a.as_ref(), b.as_ref())?;
    let coef: Vec<T> = (0..p).map(|j| sol[(j, 0)]).collect();
    if coef.iter().any(|c| !c.is_finite()) {
        return Err(Error::Identification(
            "the output map's least squares is not finite".into(),
        ));
    }
    let sse = (0..nn)
        .map(|k| {
            let f = (0..p).fold(T::zero(), |s, j| s + coef[j] * cols[j][k]);
            (y[k] - f).as_f64().powi(2)
        })
        .sum();
    Ok((coef, sse))
}

/// The slope s from a least-squares fit with a free linear coefficient; an error when it is zero
/// or not finite (the linear block's output does not explain y).
fn usable_slope<T: Real>(s: T) -> Result<T> {
    if s.is_finite() && s != T::zero() {
        Ok(s)
    } else {
        Err(Error::Identification(
            "the output map's initial slope is zero: the linear block's output does not explain \
             the output"
                .into(),
        ))
    }
}

fn check_len<T>(w: &[T], n: usize, what: &str) -> Result<()> {
    if w.len() != n {
        return Err(Error::LengthMismatch {
            what: format!("{what} has {n} parameter(s), got {}", w.len()),
        });
    }
    Ok(())
}

fn check_finite<T: Real>(w: &[T], what: &str) -> Result<()> {
    match w.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(Error::NonFinite {
            what: format!("the parameters of the output map '{what}'"),
            index,
        }),
        None => Ok(()),
    }
}

/// Polynomial map g(x) = x + c₂x² + … + c_K x^K (unit slope and zero value at x = 0).
#[derive(Debug, Clone, PartialEq)]
pub struct PolynomialMap<T: Real> {
    coef: Vec<T>,
}

impl<T: Real> PolynomialMap<T> {
    /// Degree `degree` (2..=9), starting as the identity.
    pub fn new(degree: usize) -> Result<Self> {
        if !(2..=9).contains(&degree) {
            return Err(Error::InvalidParameter(format!(
                "output polynomial degree must be 2..=9, got {degree}"
            )));
        }
        Ok(Self {
            coef: vec![T::zero(); degree - 1],
        })
    }
    /// The degree K.
    pub fn degree(&self) -> usize {
        self.coef.len() + 1
    }
    fn powers(x: &[T], d: usize) -> Vec<T> {
        x.iter().map(|&v| v.powi(d as i32)).collect()
    }
}

impl<T: Real> OutputMap<T> for PolynomialMap<T> {
    fn name(&self) -> String {
        format!("poly{}", self.degree())
    }
    fn param_names(&self) -> Vec<String> {
        (2..=self.degree()).map(|d| format!("c{d}")).collect()
    }
    fn params(&self) -> Vec<T> {
        self.coef.clone()
    }
    fn set_params(&mut self, w: &[T]) -> Result<()> {
        check_len(w, self.coef.len(), "the polynomial output map")?;
        check_finite(w, &self.name())?;
        self.coef = w.to_vec();
        Ok(())
    }
    fn eval(&self, x: &[T]) -> Vec<T> {
        x.iter()
            .map(|&v| {
                let mut s = v;
                let mut p = v;
                for &c in &self.coef {
                    p *= v;
                    s += c * p;
                }
                s
            })
            .collect()
    }
    fn derivative(&self, x: &[T]) -> Vec<T> {
        x.iter()
            .map(|&v| {
                let mut s = T::one();
                let mut p = T::one();
                for (i, &c) in self.coef.iter().enumerate() {
                    p *= v;
                    s += c * T::lit((i + 2) as f64) * p;
                }
                s
            })
            .collect()
    }
    fn param_jacobian(&self, x: &[T]) -> Mat<T> {
        Mat::from_fn(x.len(), self.coef.len(), |k, j| x[k].powi(j as i32 + 2))
    }
    /// Least squares of y on (1, x, x², …, x^K) gives the slope s = a₁ and c = a₀; then, in
    /// x' = s·x, least squares of y − x' on (1, x'², …, x'^K) — the same fit in the normalised
    /// form (c_d = a_d/s^d).
    fn initialize(&mut self, x: &[T], y: &[T]) -> Result<(T, T)> {
        let k = self.degree();
        let mut cols = vec![vec![T::one(); x.len()], x.to_vec()];
        cols.extend((2..=k).map(|d| Self::powers(x, d)));
        let (a, _) = least_squares(y, &cols)?;
        let s = usable_slope(a[1])?;
        let xs: Vec<T> = x.iter().map(|&v| v * s).collect();
        let r: Vec<T> = y.iter().zip(&xs).map(|(&y, &x)| y - x).collect();
        let mut cols = vec![vec![T::one(); x.len()]];
        cols.extend((2..=k).map(|d| Self::powers(&xs, d)));
        let (w, _) = least_squares(&r, &cols)?;
        self.set_params(&w[1..])?;
        Ok((s, w[0]))
    }
    fn rescaled(&self, s: T) -> Option<Box<dyn OutputMap<T>>> {
        // s·g(x/s) = x + Σ c_d s^{1−d} x^d
        let coef = self
            .coef
            .iter()
            .enumerate()
            .map(|(i, &c)| c / s.powi(i as i32 + 1))
            .collect();
        Some(Box::new(Self { coef }))
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "poly".into(),
            config: serde_json::json!({ "degree": self.degree() }),
            param_names: OutputMap::<T>::param_names(self),
            params: self.coef.iter().map(|c| c.as_f64()).collect(),
        }
    }
    fn clone_box(&self) -> Box<dyn OutputMap<T>> {
        Box::new(self.clone())
    }
}

/// True when `v` (a saturation limit read as f64) stands for no limit: ± the largest value of
/// f64 or f32, which [`SaturationMap`] keeps on an unbounded side.
pub fn is_unbounded_limit(v: f64) -> bool {
    v.abs() == f64::MAX || v.abs() == f64::from(f32::MAX)
}

/// A saturation limit as text: `-inf` / `inf` for an unbounded side ([`is_unbounded_limit`]),
/// else `v` with `decimals` decimals.
pub fn limit_text(v: f64, decimals: usize) -> String {
    if is_unbounded_limit(v) {
        if v < 0.0 { "-inf" } else { "inf" }.to_string()
    } else {
        format!("{v:.decimals$}")
    }
}

/// Saturation g(x) = min(max(x, lower), upper): slope 1 between the limits, flat outside.
#[derive(Debug, Clone, PartialEq)]
pub struct SaturationMap<T: Real> {
    lower: T,
    upper: T,
}

/// Fractions of the samples a saturation limit's initial grid leaves beyond it (0: no saturation).
const SATURATION_GRID: [f64; 9] = [0.0, 0.01, 0.03, 0.06, 0.1, 0.15, 0.2, 0.3, 0.4];

impl<T: Real> SaturationMap<T> {
    /// Limits `lower` < `upper` (either may be infinite: no saturation on that side).
    pub fn new(lower: T, upper: T) -> Result<Self> {
        let mut m = Self {
            lower: -T::max_value(),
            upper: T::max_value(),
        };
        m.set_params(&[lower, upper])?;
        Ok(m)
    }
    /// No saturation yet (the limits at ±the largest value; set by `initialize`).
    pub fn unbounded() -> Self {
        Self {
            lower: -T::max_value(),
            upper: T::max_value(),
        }
    }
    fn clamp(&self, v: T) -> T {
        v.max(self.lower).min(self.upper)
    }
}

/// The q-quantile of sorted data.
fn quantile<T: Real>(sorted: &[T], q: f64) -> T {
    let i = ((sorted.len().saturating_sub(1)) as f64 * q).round() as usize;
    sorted[i.min(sorted.len().saturating_sub(1))]
}

fn sorted<T: Real>(x: &[T]) -> Vec<T> {
    let mut s = x.to_vec();
    s.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    s
}

impl<T: Real> OutputMap<T> for SaturationMap<T> {
    fn name(&self) -> String {
        "saturation".into()
    }
    fn param_names(&self) -> Vec<String> {
        vec!["lower".into(), "upper".into()]
    }
    fn params(&self) -> Vec<T> {
        vec![self.lower, self.upper]
    }
    fn set_params(&mut self, w: &[T]) -> Result<()> {
        check_len(w, 2, "the saturation output map")?;
        if w.iter().any(|x| x.is_nan()) || w[0] >= w[1] {
            return Err(Error::InvalidParameter(format!(
                "the output saturation needs lower < upper, got {} and {}",
                w[0].as_f64(),
                w[1].as_f64()
            )));
        }
        (self.lower, self.upper) = (w[0], w[1]);
        Ok(())
    }
    fn eval(&self, x: &[T]) -> Vec<T> {
        x.iter().map(|&v| self.clamp(v)).collect()
    }
    fn derivative(&self, x: &[T]) -> Vec<T> {
        x.iter()
            .map(|&v| {
                if v > self.lower && v < self.upper {
                    T::one()
                } else {
                    T::zero()
                }
            })
            .collect()
    }
    fn param_jacobian(&self, x: &[T]) -> Mat<T> {
        Mat::from_fn(x.len(), 2, |k, j| {
            let hit = if j == 0 {
                x[k] <= self.lower
            } else {
                x[k] >= self.upper
            };
            if hit { T::one() } else { T::zero() }
        })
    }
    /// A grid over the limits at quantiles of x (0–40 % of the samples beyond each), with
    /// (s, c) by least squares of y on (clamp(x), 1) at every grid point; the best is kept and
    /// mapped to x' = s·x (the limits times s, swapped when s < 0).
    fn initialize(&mut self, x: &[T], y: &[T]) -> Result<(T, T)> {
        if x.is_empty() {
            return Err(Error::TooFewSamples {
                needed: 3,
                got: 0,
                reason: "initialising the output saturation".into(),
            });
        }
        let xs = sorted(x);
        let mut best: Option<(f64, T, T, T, T)> = None;
        for &fl in &SATURATION_GRID {
            for &fu in &SATURATION_GRID {
                let lo = if fl == 0.0 {
                    -T::max_value()
                } else {
                    quantile(&xs, fl)
                };
                let hi = if fu == 0.0 {
                    T::max_value()
                } else {
                    quantile(&xs, 1.0 - fu)
                };
                if lo >= hi {
                    continue;
                }
                let col: Vec<T> = x.iter().map(|&v| v.max(lo).min(hi)).collect();
                let Ok((a, sse)) = least_squares(y, &[col, vec![T::one(); x.len()]]) else {
                    continue;
                };
                if a[0] != T::zero() && best.as_ref().is_none_or(|b| sse < b.0) {
                    best = Some((sse, lo, hi, a[0], a[1]));
                }
            }
        }
        let (_, lo, hi, s, c) = best.ok_or_else(|| {
            Error::Identification("no saturation start explains the output".into())
        })?;
        let s = usable_slope(s)?;
        let scale = |v: T| {
            if v.abs() == T::max_value() { v } else { v * s }
        };
        let (l, h) = if s > T::zero() {
            (scale(lo), scale(hi))
        } else {
            (-scale(hi), -scale(lo))
        };
        // an infinite limit stays infinite under a negative s, with its sign flipped
        let fix = |v: T, upper: bool| {
            if v.abs() == T::max_value() {
                if upper {
                    T::max_value()
                } else {
                    -T::max_value()
                }
            } else {
                v
            }
        };
        self.set_params(&[fix(l, false), fix(h, true)])?;
        Ok((s, c))
    }
    fn rescaled(&self, s: T) -> Option<Box<dyn OutputMap<T>>> {
        let f = |v: T| {
            if v.abs() == T::max_value() { v } else { v * s }
        };
        Some(Box::new(Self {
            lower: f(self.lower),
            upper: f(self.upper),
        }))
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "saturation".into(),
            config: serde_json::Value::Null,
            param_names: OutputMap::<T>::param_names(self),
            params: vec![self.lower.as_f64(), self.upper.as_f64()],
        }
    }
    fn clone_box(&self) -> Box<dyn OutputMap<T>> {
        Box::new(self.clone())
    }
}

/// Piecewise-linear map with K knots t_j: g(x) = x + Σ_j w_j·h_j(x), with the hinge
/// h_j(x) = max(0, x − t_j) for a knot above 0 and max(0, t_j − x) for one at or below 0, so
/// that g has slope 1 and value 0 on the segment around x = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct PiecewiseLinearMap<T: Real> {
    knots: Vec<T>,
    weights: Vec<T>,
}

impl<T: Real> PiecewiseLinearMap<T> {
    /// K knots (1..=20), placed at x's quantiles j/(K+1) by `initialize` (until then at
    /// evenly spaced points of [−1, 1]).
    pub fn new(k: usize) -> Result<Self> {
        if !(1..=20).contains(&k) {
            return Err(Error::InvalidParameter(format!(
                "a piecewise-linear output map needs 1..=20 knots, got {k}"
            )));
        }
        let knots = (0..k)
            .map(|j| T::lit(2.0 * (j + 1) as f64 / (k + 1) as f64 - 1.0))
            .collect();
        Ok(Self {
            knots,
            weights: vec![T::zero(); k],
        })
    }
    /// With given knots and weights (same length, knots finite).
    pub fn with_knots(knots: Vec<T>, weights: Vec<T>) -> Result<Self> {
        if knots.is_empty() || knots.len() != weights.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "a piecewise-linear output map needs as many weights as knots (≥ 1), got {} \
                     knots and {} weights",
                    knots.len(),
                    weights.len()
                ),
            });
        }
        check_finite(&knots, "pwl knots")?;
        check_finite(&weights, "pwl")?;
        Ok(Self { knots, weights })
    }
    /// The knots t_j.
    pub fn knots(&self) -> &[T] {
        &self.knots
    }
    fn hinge(t: T, v: T) -> T {
        if t > T::zero() {
            (v - t).max(T::zero())
        } else {
            (t - v).max(T::zero())
        }
    }
    fn hinge_slope(t: T, v: T) -> T {
        if t > T::zero() {
            if v > t { T::one() } else { T::zero() }
        } else if v < t {
            -T::one()
        } else {
            T::zero()
        }
    }
    fn columns(&self, x: &[T]) -> Vec<Vec<T>> {
        self.knots
            .iter()
            .map(|&t| x.iter().map(|&v| Self::hinge(t, v)).collect())
            .collect()
    }
}

impl<T: Real> OutputMap<T> for PiecewiseLinearMap<T> {
    fn name(&self) -> String {
        format!("pwl:{}", self.knots.len())
    }
    fn param_names(&self) -> Vec<String> {
        (1..=self.knots.len()).map(|j| format!("w{j}")).collect()
    }
    fn params(&self) -> Vec<T> {
        self.weights.clone()
    }
    fn set_params(&mut self, w: &[T]) -> Result<()> {
        check_len(w, self.knots.len(), "the piecewise-linear output map")?;
        check_finite(w, &self.name())?;
        self.weights = w.to_vec();
        Ok(())
    }
    fn eval(&self, x: &[T]) -> Vec<T> {
        x.iter()
            .map(|&v| {
                self.knots
                    .iter()
                    .zip(&self.weights)
                    .fold(v, |s, (&t, &w)| s + w * Self::hinge(t, v))
            })
            .collect()
    }
    fn derivative(&self, x: &[T]) -> Vec<T> {
        x.iter()
            .map(|&v| {
                self.knots
                    .iter()
                    .zip(&self.weights)
                    .fold(T::one(), |s, (&t, &w)| s + w * Self::hinge_slope(t, v))
            })
            .collect()
    }
    fn param_jacobian(&self, x: &[T]) -> Mat<T> {
        Mat::from_fn(x.len(), self.knots.len(), |k, j| {
            Self::hinge(self.knots[j], x[k])
        })
    }
    /// Knots at x's quantiles j/(K+1); least squares of y on (1, x, h₁(x), …, h_K(x)) gives the
    /// slope s; then knots ← s·t_j and least squares of y − x' on (1, h_j(x')) in x' = s·x.
    fn initialize(&mut self, x: &[T], y: &[T]) -> Result<(T, T)> {
        if x.is_empty() {
            return Err(Error::TooFewSamples {
                needed: self.knots.len() + 3,
                got: 0,
                reason: "initialising the piecewise-linear output map".into(),
            });
        }
        let xs = sorted(x);
        let k = self.knots.len();
        self.knots = (1..=k)
            .map(|j| quantile(&xs, j as f64 / (k + 1) as f64))
            .collect();
        let mut cols = vec![vec![T::one(); x.len()], x.to_vec()];
        cols.extend(self.columns(x));
        let (a, _) = least_squares(y, &cols)?;
        let s = usable_slope(a[1])?;
        self.knots = self.knots.iter().map(|&t| t * s).collect();
        let xp: Vec<T> = x.iter().map(|&v| v * s).collect();
        let r: Vec<T> = y.iter().zip(&xp).map(|(&y, &x)| y - x).collect();
        let mut cols = vec![vec![T::one(); x.len()]];
        cols.extend(self.columns(&xp));
        let (w, _) = least_squares(&r, &cols)?;
        self.set_params(&w[1..])?;
        Ok((s, w[0]))
    }
    fn rescaled(&self, s: T) -> Option<Box<dyn OutputMap<T>>> {
        // s·h(x/s; t) = h(x; s·t), so the weights stay
        Some(Box::new(Self {
            knots: self.knots.iter().map(|&t| t * s).collect(),
            weights: self.weights.clone(),
        }))
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "pwl".into(),
            config: serde_json::json!({
                "knots": self.knots.iter().map(|t| t.as_f64()).collect::<Vec<_>>()
            }),
            param_names: OutputMap::<T>::param_names(self),
            params: self.weights.iter().map(|w| w.as_f64()).collect(),
        }
    }
    fn clone_box(&self) -> Box<dyn OutputMap<T>> {
        Box::new(self.clone())
    }
}

/// A built-in output map from its command-line name: `poly` / `polyK` (K = 2..9; `poly` is
/// `poly3`), `saturation`, `pwl:K`.
pub fn output_map_from_name<T: Real>(name: &str) -> Result<Box<dyn OutputMap<T>>> {
    let s = name.trim().to_ascii_lowercase();
    if s == "saturation" || s == "sat" {
        return Ok(Box::new(SaturationMap::<T>::unbounded()));
    }
    if let Some(k) = s.strip_prefix("pwl:").or_else(|| s.strip_prefix("pwl")) {
        let k: usize = k.parse().map_err(|_| {
            Error::InvalidParameter(format!("'{name}': pwl needs a knot count, e.g. pwl:5"))
        })?;
        return Ok(Box::new(PiecewiseLinearMap::<T>::new(k)?));
    }
    if let Some(d) = s.strip_prefix("poly") {
        let d = if d.is_empty() {
            3
        } else {
            d.trim_start_matches(':').parse().map_err(|_| {
                Error::InvalidParameter(format!("'{name}': poly needs a degree, e.g. poly3"))
            })?
        };
        return Ok(Box::new(PolynomialMap::<T>::new(d)?));
    }
    Err(Error::UnknownName {
        kind: crate::error::NameKind::OutputNonlinearity,
        name: name.to_string(),
        expected: "poly3|saturation|pwl:K",
    })
}

/// Rebuilds a built-in output map ("poly", "saturation", "pwl") from its spec.
pub fn output_map_from_spec<T: Real>(spec: &NonlinearitySpec) -> Result<Box<dyn OutputMap<T>>> {
    let w: Vec<T> = spec.params.iter().map(|&x| T::lit(x)).collect();
    let mut map: Box<dyn OutputMap<T>> = match spec.kind.as_str() {
        "poly" => {
            let d = spec
                .config
                .get("degree")
                .and_then(|d| d.as_u64())
                .ok_or_else(|| {
                    Error::ModelFormat("output poly spec: missing integer \"degree\"".into())
                })?;
            Box::new(PolynomialMap::<T>::new(d as usize)?)
        }
        "saturation" => Box::new(SaturationMap::<T>::unbounded()),
        "pwl" => {
            let knots: Vec<T> = spec
                .config
                .get("knots")
                .and_then(|k| k.as_array())
                .ok_or_else(|| Error::ModelFormat("output pwl spec: missing \"knots\"".into()))?
                .iter()
                .map(|t| {
                    t.as_f64().map(T::lit).ok_or_else(|| {
                        Error::ModelFormat("output pwl spec: a knot is not a number".into())
                    })
                })
                .collect::<Result<_>>()?;
            let k = knots.len();
            Box::new(PiecewiseLinearMap::with_knots(knots, vec![T::zero(); k])?)
        }
        other => {
            return Err(Error::ModelFormat(format!(
                "unknown output map kind '{other}' (built-in: poly, saturation, pwl)"
            )));
        }
    };
    if w.len() != map.params().len() {
        return Err(Error::ModelFormat(format!(
            "the output map '{}' has {} parameter(s), the file gives {}",
            spec.kind,
            map.params().len(),
            w.len()
        )));
    }
    map.set_params(&w)?;
    Ok(map)
}
