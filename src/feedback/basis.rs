//! The built-in bases of a nonlinearity in feedback, w = f(z): each a [`StaticNonlinearity`]
//! whose linear part is left out, because the linear block's A already holds any linear
//! feedback (a linear column would only duplicate A's parameters).
//!
//! | name | f(z) | parameters |
//! |---|---|---|
//! | `poly3` | c₃ z³ (cubic stiffness, a Duffing oscillator) | c3 |
//! | `poly5` | c₃ z³ + c₅ z⁵ | c3, c5 |
//! | `coulomb` | c tanh(z/δ): Coulomb friction's sign, smoothed over the width δ (searched on a grid of 0.3–30 % of z's RMS, then refined) so that the output-error refinement has a derivative | c, δ |
//! | `dead-zone` | c sgn(z) max(|z| − b, 0) (clearance, backlash's static part) | c, b |
//! | `saturation` | c clip(z, −s, s) (a spring that saturates) | c, s |
//! | `pwl:K` | Σ c_i max(z − t_i, 0), K − 1 hinges at quantiles of z: piecewise linear with K segments | c_1..c_{K−1} |
//!
//! The hinge positions of `pwl:K` are fixed when the basis is made for a record
//! ([`feedback_basis`]); the dead-zone's b, the saturation's s and the Coulomb width δ are
//! parameters the refinement moves.

use crate::error::{Error, Result};
use crate::regressors::{NonlinearitySpec, StaticNonlinearity};
use faer::Mat;

/// The width δ of `coulomb` the basis is made with, as a fraction of the spread (max − min) of
/// z (the fit then searches and refines it).
pub const COULOMB_SMOOTHING: f64 = 0.01;

/// Which built-in feedback nonlinearity (parsed from the command line's spelling).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeedbackKind {
    /// c₃ z³.
    Poly3,
    /// c₃ z³ + c₅ z⁵.
    Poly5,
    /// Smoothed Coulomb friction c tanh(z/δ).
    Coulomb,
    /// Dead-zone (clearance) c sgn(z) max(|z| − b, 0).
    DeadZone,
    /// Saturation c clip(z, −s, s).
    Saturation,
    /// Piecewise linear with K segments.
    Pwl(usize),
}

impl std::str::FromStr for FeedbackKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "poly3" => Self::Poly3,
            "poly5" => Self::Poly5,
            "coulomb" => Self::Coulomb,
            "dead-zone" | "deadzone" | "clearance" => Self::DeadZone,
            "saturation" => Self::Saturation,
            _ => {
                if let Some(k) = s.strip_prefix("pwl:") {
                    let k: usize = k.parse().map_err(|_| {
                        Error::InvalidParameter(format!("pwl:K needs a whole number K, got '{s}'"))
                    })?;
                    if !(2..=20).contains(&k) {
                        return Err(Error::InvalidParameter(format!(
                            "pwl:K needs 2 ≤ K ≤ 20 segments, got {k}"
                        )));
                    }
                    Self::Pwl(k)
                } else {
                    return Err(Error::InvalidParameter(format!(
                        "unknown feedback nonlinearity '{s}' (known: poly3, poly5, coulomb, \
                         dead-zone, saturation, pwl:K)"
                    )));
                }
            }
        })
    }
}

/// The basis of `kind` for a loop whose variable z visits the values `z` (the smoothing width,
/// hinge positions and start thresholds come from them). Errors when z does not vary.
pub fn feedback_basis(kind: FeedbackKind, z: &[f64]) -> Result<Box<dyn StaticNonlinearity<f64>>> {
    let (lo, hi) = z
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::InvalidParameter(
            "the feedback variable z is constant over the record: no nonlinearity of it can be identified".into(),
        ));
    }
    let mut abs: Vec<f64> = z
        .iter()
        .map(|v| v.abs())
        .filter(|v| v.is_finite())
        .collect();
    abs.sort_by(f64::total_cmp);
    let q = |p: f64| abs[((abs.len() - 1) as f64 * p) as usize];
    Ok(match kind {
        FeedbackKind::Poly3 => Box::new(Linear::new(OddPowers { powers: vec![3] })),
        FeedbackKind::Poly5 => Box::new(Linear::new(OddPowers { powers: vec![3, 5] })),
        FeedbackKind::Coulomb => Box::new(Coulomb {
            c: 0.0,
            delta: COULOMB_SMOOTHING * (hi - lo),
        }),
        FeedbackKind::DeadZone => Box::new(Zone {
            saturation: false,
            c: 0.0,
            t: q(0.3),
        }),
        FeedbackKind::Saturation => Box::new(Zone {
            saturation: true,
            c: 0.0,
            t: q(0.7),
        }),
        FeedbackKind::Pwl(k) => {
            let mut s: Vec<f64> = z.iter().copied().filter(|v| v.is_finite()).collect();
            s.sort_by(f64::total_cmp);
            let knots = (1..k)
                .map(|i| s[((s.len() - 1) as f64 * i as f64 / k as f64) as usize])
                .collect::<Vec<_>>();
            Box::new(Linear::new(Hinges { knots }))
        }
    })
}

/// Rebuilds a built-in feedback basis from its spec (kinds "feedback-poly", "coulomb",
/// "dead-zone", "saturation", "pwl"); `None` for other kinds.
pub fn feedback_from_spec(
    spec: &NonlinearitySpec,
) -> Option<Result<Box<dyn StaticNonlinearity<f64>>>> {
    let num = |key: &str| -> Result<f64> {
        spec.config
            .get(key)
            .and_then(|v| v.as_f64())
            .ok_or_else(|| {
                Error::ModelFormat(format!("{} spec: missing number \"{key}\"", spec.kind))
            })
    };
    let mut b: Box<dyn StaticNonlinearity<f64>> = match spec.kind.as_str() {
        "feedback-poly" => {
            let powers = spec
                .config
                .get("powers")
                .and_then(|v| v.as_array())
                .map(|a| {
                    a.iter()
                        .filter_map(|p| p.as_i64())
                        .map(|p| p as i32)
                        .collect::<Vec<_>>()
                });
            match powers {
                Some(p) if !p.is_empty() => Box::new(Linear::new(OddPowers { powers: p })),
                _ => {
                    return Some(Err(Error::ModelFormat(
                        "feedback-poly spec: missing \"powers\"".into(),
                    )));
                }
            }
        }
        // a file of the fixed-width basis holds c alone, its δ in the configuration
        "coulomb" if spec.params.len() == 1 => match num("delta") {
            Ok(delta) if delta > 0.0 => {
                let mut b = Coulomb { c: 0.0, delta };
                return Some(
                    b.update_from_gains(&spec.params, &[])
                        .map(|()| Box::new(b) as Box<dyn StaticNonlinearity<f64>>),
                );
            }
            Ok(_) => {
                return Some(Err(Error::ModelFormat(
                    "coulomb spec: delta must be positive".into(),
                )));
            }
            Err(e) => return Some(Err(e)),
        },
        "coulomb" => Box::new(Coulomb { c: 0.0, delta: 1.0 }),
        "dead-zone" | "saturation" => Box::new(Zone {
            saturation: spec.kind == "saturation",
            c: 0.0,
            t: 0.0,
        }),
        "pwl" => {
            let knots = spec
                .config
                .get("knots")
                .and_then(|v| v.as_array())
                .map(|a| a.iter().filter_map(|p| p.as_f64()).collect::<Vec<_>>())
                .unwrap_or_default();
            if knots.is_empty() {
                return Some(Err(Error::ModelFormat(
                    "pwl spec: missing \"knots\"".into(),
                )));
            }
            Box::new(Linear::new(Hinges { knots }))
        }
        _ => return None,
    };
    Some(b.set_params(&spec.params).map(|()| b))
}

fn check_len(what: &str, theta: &[f64], n: usize) -> Result<()> {
    if theta.len() != n {
        return Err(Error::LengthMismatch {
            what: format!("{what} has {n} parameters, got {}", theta.len()),
        });
    }
    if let Some(i) = theta.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: format!("{what} parameters"),
            index: i,
        });
    }
    Ok(())
}

/// The columns φ_j of a feedback basis linear in its coefficients, f(z) = Σ c_j φ_j(z): what
/// tells the built-in polynomial, Coulomb and hinge bases apart. [`Linear`] gives each the
/// trait methods they share (coefficients, regressors, gains, Jacobian, spec).
pub trait Columns: std::fmt::Debug + Clone + Send + Sync + 'static {
    /// The basis's name ("poly3", "coulomb", "pwl:K").
    fn name(&self) -> String;
    /// The physical effects it stands for.
    fn effects(&self) -> Vec<String>;
    /// What a parameter-count error calls it.
    fn what(&self) -> &'static str;
    /// The number of columns (and coefficients).
    fn count(&self) -> usize;
    /// The coefficients' names.
    fn param_names(&self) -> Vec<String>;
    /// The columns' names.
    fn regressor_names(&self) -> Vec<String>;
    /// Column `j` at `z`.
    fn column(&self, z: f64, j: usize) -> f64;
    /// The spec's kind and the configuration that rebuilds the columns.
    fn spec_of(&self) -> (&'static str, serde_json::Value);
    /// The columns for the argument measured in units `input` times larger: (φ′, m) with
    /// φ_j(z / input) = m_j φ′_j(z) for every z; `None` when the columns cannot say.
    fn input_scaled(&self, _input: f64) -> Option<(Self, Vec<f64>)> {
        None
    }
}

/// A feedback basis linear in its coefficients: the columns and their coefficients c.
#[derive(Debug, Clone)]
pub struct Linear<C: Columns> {
    cols: C,
    c: Vec<f64>,
}

impl<C: Columns> Linear<C> {
    /// The columns, coefficients zero.
    pub fn new(cols: C) -> Self {
        let n = cols.count();
        Self {
            cols,
            c: vec![0.0; n],
        }
    }
}

impl<C: Columns> StaticNonlinearity<f64> for Linear<C> {
    fn name(&self) -> String {
        self.cols.name()
    }
    fn effects(&self) -> Vec<String> {
        self.cols.effects()
    }
    fn param_names(&self) -> Vec<String> {
        self.cols.param_names()
    }
    fn params(&self) -> Vec<f64> {
        self.c.clone()
    }
    fn set_params(&mut self, theta: &[f64]) -> Result<()> {
        check_len(self.cols.what(), theta, self.c.len())?;
        self.c.copy_from_slice(theta);
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        self.cols.regressor_names()
    }
    fn regressors(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), self.c.len(), |k, j| self.cols.column(u[k], j))
    }
    fn gains(&self) -> Vec<f64> {
        self.c.clone()
    }
    fn update_from_gains(&mut self, g: &[f64], _u: &[f64]) -> Result<()> {
        self.set_params(g)
    }
    fn initialize(&mut self, _u: &[f64]) {
        self.c.iter_mut().for_each(|c| *c = 0.0);
    }
    fn param_jacobian(&self, u: &[f64]) -> Mat<f64> {
        self.regressors(u)
    }
    /// Σ_j c_j φ_j(z), summed from j = 0 as [`eval`](StaticNonlinearity::eval) does.
    fn eval_one(&self, z: f64) -> f64 {
        self.c
            .iter()
            .enumerate()
            .fold(0.0, |s, (j, c)| s + self.cols.column(z, j) * c)
    }
    fn param_jacobian_one(&self, z: f64, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate().take(self.c.len()) {
            *o = self.cols.column(z, j);
        }
    }
    fn rescaled(&self, input: f64, output: f64) -> Option<Box<dyn StaticNonlinearity<f64>>> {
        if !(input > 0.0 && output > 0.0 && input.is_finite() && output.is_finite()) {
            return None;
        }
        let (cols, m) = self.cols.input_scaled(input)?;
        let c = self.c.iter().zip(&m).map(|(c, m)| output * c * m).collect();
        Some(Box::new(Self { cols, c }))
    }
    fn spec(&self) -> NonlinearitySpec {
        let (kind, config) = self.cols.spec_of();
        NonlinearitySpec {
            kind: kind.into(),
            config,
            param_names: self.param_names(),
            params: self.c.clone(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<f64>> {
        Box::new(self.clone())
    }
}

/// Odd powers z^p (p ≥ 3) without the linear term.
#[derive(Debug, Clone)]
pub struct OddPowers {
    powers: Vec<i32>,
}

impl Columns for OddPowers {
    fn name(&self) -> String {
        format!("poly{}", self.powers.iter().max().copied().unwrap_or(3))
    }
    fn effects(&self) -> Vec<String> {
        vec!["stiffness".into()]
    }
    fn what(&self) -> &'static str {
        "feedback polynomial"
    }
    fn count(&self) -> usize {
        self.powers.len()
    }
    fn param_names(&self) -> Vec<String> {
        self.powers.iter().map(|p| format!("c{p}")).collect()
    }
    fn regressor_names(&self) -> Vec<String> {
        self.powers.iter().map(|p| format!("z^{p}")).collect()
    }
    fn column(&self, z: f64, j: usize) -> f64 {
        z.powi(self.powers[j])
    }
    fn spec_of(&self) -> (&'static str, serde_json::Value) {
        (
            "feedback-poly",
            serde_json::json!({ "powers": self.powers }),
        )
    }
    fn input_scaled(&self, input: f64) -> Option<(Self, Vec<f64>)> {
        let m = self.powers.iter().map(|&p| input.powi(-p)).collect();
        Some((self.clone(), m))
    }
}

/// Coulomb friction c·tanh(z/δ): the sign smoothed over the width δ, a parameter the fit
/// moves (a physical friction's pre-sliding transition, and the width a smooth model needs
/// so that the output-error refinement has a derivative). δ is a scale, not a threshold:
/// its start is searched on a geometric grid ([`search_range`](StaticNonlinearity::search_range)
/// starts above zero), then refined with c.
#[derive(Debug, Clone)]
pub struct Coulomb {
    c: f64,
    delta: f64,
}

/// The smallest width δ the fit keeps, relative to its start (a sign sharper than this has no
/// usable derivative).
const COULOMB_MIN_WIDTH: f64 = 1e-6;

impl Coulomb {
    fn column(&self, z: f64) -> f64 {
        (z / self.delta).tanh()
    }
    /// [∂f/∂c, ∂f/∂δ] at z: tanh(z/δ) and −c (z/δ²) sech²(z/δ).
    fn derivatives(&self, z: f64) -> [f64; 2] {
        let t = self.column(z);
        [t, -self.c * z / (self.delta * self.delta) * (1.0 - t * t)]
    }
}

impl StaticNonlinearity<f64> for Coulomb {
    fn name(&self) -> String {
        "coulomb".into()
    }
    fn effects(&self) -> Vec<String> {
        vec!["friction".into()]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["c".into(), "delta".into()]
    }
    fn params(&self) -> Vec<f64> {
        vec![self.c, self.delta]
    }
    fn set_params(&mut self, theta: &[f64]) -> Result<()> {
        check_len("coulomb", theta, 2)?;
        if theta[1] == 0.0 {
            return Err(Error::InvalidParameter(
                "coulomb: the width delta must not be zero".into(),
            ));
        }
        (self.c, self.delta) = (theta[0], theta[1].abs().max(COULOMB_MIN_WIDTH));
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        vec!["tanh(z/delta)".into()]
    }
    fn regressors(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), 1, |k, _| self.column(u[k]))
    }
    fn gains(&self) -> Vec<f64> {
        vec![self.c]
    }
    fn update_from_gains(&mut self, g: &[f64], _u: &[f64]) -> Result<()> {
        check_len("coulomb", g, 1)?;
        self.c = g[0];
        Ok(())
    }
    fn searched_params(&self) -> Vec<usize> {
        vec![1]
    }
    /// δ between 0.3 % and 30 % of z's RMS: the transition of a friction is narrow against
    /// the velocities the record visits, and a wider one is the viscous term's.
    fn search_range(&self, _index: usize, z: &[f64]) -> (f64, f64) {
        let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len().max(1) as f64).sqrt();
        (0.003 * rms, 0.3 * rms)
    }
    fn initialize(&mut self, _u: &[f64]) {
        self.c = 0.0;
    }
    fn param_jacobian(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), 2, |k, j| self.derivatives(u[k])[j])
    }
    fn eval_one(&self, z: f64) -> f64 {
        0.0 + self.column(z) * self.c
    }
    fn param_jacobian_one(&self, z: f64, out: &mut [f64]) {
        for (o, d) in out.iter_mut().zip(self.derivatives(z)) {
            *o = d;
        }
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "coulomb".into(),
            config: serde_json::json!({ "delta": self.delta }),
            param_names: self.param_names(),
            params: vec![self.c, self.delta],
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<f64>> {
        Box::new(self.clone())
    }
    /// output·c·tanh((z / input) / δ) = (output·c)·tanh(z / (input·δ)).
    fn rescaled(&self, input: f64, output: f64) -> Option<Box<dyn StaticNonlinearity<f64>>> {
        if !(input > 0.0 && output > 0.0 && input.is_finite() && output.is_finite()) {
            return None;
        }
        Some(Box::new(Self {
            c: output * self.c,
            delta: input * self.delta,
        }))
    }
}

/// Hinges Σ c_i max(z − t_i, 0) at fixed knots t_i.
#[derive(Debug, Clone)]
pub struct Hinges {
    knots: Vec<f64>,
}

impl Columns for Hinges {
    fn name(&self) -> String {
        format!("pwl:{}", self.knots.len() + 1)
    }
    fn effects(&self) -> Vec<String> {
        Vec::new()
    }
    fn what(&self) -> &'static str {
        "pwl"
    }
    fn count(&self) -> usize {
        self.knots.len()
    }
    fn param_names(&self) -> Vec<String> {
        (1..=self.knots.len()).map(|i| format!("c{i}")).collect()
    }
    fn regressor_names(&self) -> Vec<String> {
        self.knots
            .iter()
            .map(|t| format!("max(z-{t:.4},0)"))
            .collect()
    }
    fn column(&self, z: f64, j: usize) -> f64 {
        (z - self.knots[j]).max(0.0)
    }
    fn spec_of(&self) -> (&'static str, serde_json::Value) {
        ("pwl", serde_json::json!({ "knots": self.knots }))
    }
    fn input_scaled(&self, input: f64) -> Option<(Self, Vec<f64>)> {
        let knots = self.knots.iter().map(|t| t * input).collect();
        Some((Self { knots }, vec![1.0 / input; self.knots.len()]))
    }
}

/// A dead-zone c·sgn(z)·max(|z| − t, 0) or a saturation c·clip(z, −t, t).
#[derive(Debug, Clone)]
pub struct Zone {
    saturation: bool,
    c: f64,
    t: f64,
}

impl Zone {
    fn column(&self, z: f64) -> f64 {
        let t = self.t.abs();
        if self.saturation {
            z.clamp(-t, t)
        } else {
            z.signum() * (z.abs() - t).max(0.0)
        }
    }
    /// [∂f/∂c, ∂f/∂t] at z: the column, and beyond the threshold c·sgn(z) for the clip (∂/∂t
    /// of ±t is sgn(z)) or −c·sgn(z) for the dead-zone (∂/∂t of sgn(z)(|z| − t)); 0 inside it.
    fn derivatives(&self, z: f64) -> [f64; 2] {
        let slope = if z.abs() > self.t.abs() {
            if self.saturation {
                self.c * z.signum()
            } else {
                -self.c * z.signum()
            }
        } else {
            0.0
        };
        [self.column(z), slope]
    }
}

impl StaticNonlinearity<f64> for Zone {
    fn name(&self) -> String {
        if self.saturation {
            "saturation"
        } else {
            "dead-zone"
        }
        .into()
    }
    fn effects(&self) -> Vec<String> {
        vec![
            if self.saturation {
                "saturation"
            } else {
                "clearance"
            }
            .into(),
        ]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["c".into(), if self.saturation { "s" } else { "b" }.into()]
    }
    fn params(&self) -> Vec<f64> {
        vec![self.c, self.t]
    }
    fn set_params(&mut self, theta: &[f64]) -> Result<()> {
        check_len(&StaticNonlinearity::name(self), theta, 2)?;
        (self.c, self.t) = (theta[0], theta[1].abs());
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        vec![StaticNonlinearity::name(self)]
    }
    fn regressors(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), 1, |k, _| self.column(u[k]))
    }
    fn gains(&self) -> Vec<f64> {
        vec![self.c]
    }
    fn update_from_gains(&mut self, g: &[f64], _u: &[f64]) -> Result<()> {
        check_len(&StaticNonlinearity::name(self), g, 1)?;
        self.c = g[0];
        Ok(())
    }
    fn searched_params(&self) -> Vec<usize> {
        vec![1]
    }
    fn initialize(&mut self, _u: &[f64]) {
        self.c = 0.0;
    }
    fn param_jacobian(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), 2, |k, j| self.derivatives(u[k])[j])
    }
    fn eval_one(&self, z: f64) -> f64 {
        0.0 + self.column(z) * self.c
    }
    fn param_jacobian_one(&self, z: f64, out: &mut [f64]) {
        for (o, d) in out.iter_mut().zip(self.derivatives(z)) {
            *o = d;
        }
    }
    fn kink_params(&self) -> Vec<usize> {
        vec![1]
    }
    fn rescaled(&self, input: f64, output: f64) -> Option<Box<dyn StaticNonlinearity<f64>>> {
        if !(input > 0.0 && output > 0.0 && input.is_finite() && output.is_finite()) {
            return None;
        }
        // c·zone(z / input; t) = (c / input)·zone(z; input·t) for the dead-zone and the clip
        Some(Box::new(Self {
            saturation: self.saturation,
            c: output * self.c / input,
            t: self.t * input,
        }))
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: StaticNonlinearity::name(self),
            config: serde_json::json!({}),
            param_names: self.param_names(),
            params: vec![self.c, self.t],
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<f64>> {
        Box::new(self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every built-in feedback basis.
    const BUILTIN: [FeedbackKind; 6] = [
        FeedbackKind::Poly3,
        FeedbackKind::Poly5,
        FeedbackKind::Coulomb,
        FeedbackKind::DeadZone,
        FeedbackKind::Saturation,
        FeedbackKind::Pwl(3),
    ];

    /// Every built-in feedback basis says how it rescales: N'(z) = output·N(z / input).
    #[test]
    fn every_builtin_basis_rescales_exactly() {
        let z: Vec<f64> = (0..200).map(|k| (k as f64 * 0.37).sin() * 1.3).collect();
        let (input, output) = (2.5, 0.4);
        for kind in BUILTIN {
            let mut f = feedback_basis(kind, &z).unwrap();
            // nonzero parameters: each 0.3 + 0.1 j, the searched ones (widths, thresholds) kept
            let searched = f.searched_params();
            let p: Vec<f64> = f
                .params()
                .iter()
                .enumerate()
                .map(|(j, v)| {
                    if searched.contains(&j) {
                        *v
                    } else {
                        0.3 + 0.1 * j as f64
                    }
                })
                .collect();
            f.set_params(&p).unwrap();
            let g = f
                .rescaled(input, output)
                .unwrap_or_else(|| panic!("{kind:?} does not rescale"));
            let zs: Vec<f64> = z.iter().map(|v| v * input).collect();
            let (a, b) = (f.eval(&z), g.eval(&zs));
            for (x, y) in a.iter().zip(&b) {
                assert!(
                    (output * x - y).abs() <= 1e-12 * (1.0 + y.abs()),
                    "{kind:?}: {x} {y}"
                );
            }
        }
    }

    /// The one-sample evaluations the loop's simulation uses are the record's, bit for bit:
    /// `eval_one` the row of `eval`, `param_jacobian_one` the row of `param_jacobian`.
    #[test]
    fn one_sample_evaluations_are_the_records() {
        let z: Vec<f64> = (0..300).map(|k| (k as f64 * 0.23).sin() * 1.7).collect();
        for kind in BUILTIN {
            let mut f = feedback_basis(kind, &z).unwrap();
            let p: Vec<f64> = f
                .params()
                .iter()
                .enumerate()
                .map(|(j, v)| v + 0.3 - 0.2 * j as f64)
                .collect();
            f.set_params(&p).unwrap();
            let (v, jac) = (f.eval(&z), f.param_jacobian(&z));
            let mut row = vec![f64::NAN; jac.ncols()];
            for (k, &zk) in z.iter().enumerate() {
                assert_eq!(f.eval_one(zk).to_bits(), v[k].to_bits(), "{kind:?} at {zk}");
                f.param_jacobian_one(zk, &mut row);
                for (j, r) in row.iter().enumerate() {
                    assert_eq!(
                        r.to_bits(),
                        jac[(k, j)].to_bits(),
                        "{kind:?} ∂/∂θ{j} at {zk}"
                    );
                }
            }
        }
    }
}
