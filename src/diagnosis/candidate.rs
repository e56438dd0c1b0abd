//! Missing-effect candidates: the [`MissingEffect`] trait a user can implement, the evidence a
//! candidate reads from the residual analysis, and the built-in candidates (hysteresis, dead-zone,
//! saturation, preload, dynamics, delay, output-nonlinearity).

use super::analysis::ResidualAnalysis;
use super::compare::{Comparison, compare};
use super::regression::least_squares;
use super::tests::TestResult;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::hammerstein::{Hammerstein, HammersteinModel};
use crate::real::Real;
use crate::regressors::Effect;
use crate::subspace::Order;
use std::collections::BTreeMap;

/// What the residual analysis says about one candidate.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Evidence {
    /// Name of the test the evidence comes from.
    pub test: String,
    /// p-value of that test alone.
    pub p_value: f64,
    /// p-value after the multiple-testing correction.
    pub p_adjusted: f64,
    /// True when significant after the correction.
    pub significant: bool,
    /// One sentence with the numbers.
    pub sentence: String,
    /// Size estimates read from the residual (input units unless named otherwise).
    pub estimate: BTreeMap<String, f64>,
}

impl Evidence {
    /// Evidence from a test result, with a sentence and size estimates.
    pub fn from_test(t: &TestResult, sentence: String, estimate: BTreeMap<String, f64>) -> Self {
        Self {
            test: t.name.clone(),
            p_value: t.p_value,
            p_adjusted: t.p_adjusted,
            significant: t.significant,
            sentence,
            estimate,
        }
    }
}

/// Everything a candidate's refit may use.
pub struct RefitContext<'a, T: Real> {
    /// The fitted model under diagnosis (its settings are `model.settings()`).
    pub model: &'a HammersteinModel<T>,
    /// Estimation data.
    pub train: &'a IoData<T>,
    /// Validation data.
    pub validation: &'a IoData<T>,
    /// The model's comparison on the validation data.
    pub validation_comparison: &'a Comparison,
    /// The residual analysis (training data).
    pub analysis: &'a ResidualAnalysis,
}

/// The outcome of refitting with a candidate added.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Refit {
    /// Validation MSE of the refitted model.
    pub validation_mse: f64,
    /// Validation MSE the improvement is measured against (the current model's, unless a
    /// candidate needs a fairer reference, e.g. an affine output map for the output nonlinearity).
    pub reference_mse: f64,
    /// What changed ("order 2 → 3", "effects linear → hysteresis").
    pub change: String,
    /// Size estimates from the refitted model's parameters.
    pub estimate: BTreeMap<String, f64>,
}

/// A physical effect (or linear deficit) a model may be missing: reads its evidence from the
/// residual analysis and refits the model with the effect added.
///
/// Register your own with [`crate::diagnosis::Registry::register`]; it is then tried and ranked
/// like the built-ins.
pub trait MissingEffect<T: Real>: Send + Sync {
    /// Name shown to the user ("hysteresis", "dead-zone", …, or a user's).
    fn name(&self) -> String;
    /// False when the model already has the effect (no refit is tried).
    fn applies_to(&self, _model: &HammersteinModel<T>) -> bool {
        true
    }
    /// The evidence for this effect in the residuals (`None`: the candidate has no test of its own).
    fn evidence(&self, analysis: &ResidualAnalysis) -> Option<Evidence>;
    /// Settings with the effect added.
    fn apply(
        &self,
        model: &HammersteinModel<T>,
        analysis: &ResidualAnalysis,
    ) -> Result<Hammerstein<T>>;
    /// Refits with the effect added and measures the validation MSE (default: [`apply`](Self::apply),
    /// fit on the training data, simulate the validation data).
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let refit = settings.fit(ctx.train)?;
        let c = compare(&refit, ctx.validation)?;
        let params: BTreeMap<String, f64> = refit.parameters().into_iter().collect();
        Ok(Refit {
            validation_mse: c.metrics.mse,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: change_text(ctx.model, &refit),
            estimate: self.refit_estimate(&params),
        })
    }
    /// The size estimates to quote from a refitted model's parameters (default: none).
    fn refit_estimate(&self, _params: &BTreeMap<String, f64>) -> BTreeMap<String, f64> {
        BTreeMap::new()
    }
}

fn change_text<T: Real>(before: &HammersteinModel<T>, after: &HammersteinModel<T>) -> String {
    let eb = before.nonlinearity().effects().join(",");
    let ea = after.nonlinearity().effects().join(",");
    let (nb, na) = (before.linear().order(), after.linear().order());
    let mut parts = Vec::new();
    if eb != ea {
        let f = |s: String| {
            if s.is_empty() {
                "linear".to_string()
            } else {
                s
            }
        };
        parts.push(format!("effects {} → {}", f(eb), f(ea)));
    }
    if nb != na {
        parts.push(format!("order {nb} → {na}"));
    }
    if parts.is_empty() {
        "same structure".into()
    } else {
        parts.join("; ")
    }
}

fn pick(params: &BTreeMap<String, f64>, names: &[&str]) -> BTreeMap<String, f64> {
    names
        .iter()
        .filter_map(|n| params.get(*n).map(|v| (n.to_string(), *v)))
        .collect()
}

fn est(pairs: &[(&str, Option<f64>)]) -> BTreeMap<String, f64> {
    pairs
        .iter()
        .filter_map(|(k, v)| v.filter(|x| x.is_finite()).map(|x| (k.to_string(), x)))
        .collect()
}

fn p_text(p: f64) -> String {
    if p < 1e-4 {
        format!("p = {p:.1e}")
    } else {
        format!("p = {p:.4}")
    }
}

fn stat_text(t: &TestResult) -> String {
    if t.df.len() == 2 {
        format!(
            "F({}, {}) = {:.1}, {}",
            t.df[0],
            t.df[1],
            t.statistic,
            p_text(t.p_value)
        )
    } else {
        format!(
            "{} = {:.2}, {}",
            t.statistic_name,
            t.statistic,
            p_text(t.p_value)
        )
    }
}

/// True when the model's nonlinearity already has this effect.
fn has_effect<T: Real>(model: &HammersteinModel<T>, e: Effect) -> bool {
    model.nonlinearity().effects().iter().any(|s| s == e.name())
}

/// One of the four UDN effects, added with `settings.with_effect(e)`.
#[derive(Debug, Clone, Copy)]
pub struct UdnEffect(pub Effect);

impl<T: Real> MissingEffect<T> for UdnEffect {
    fn name(&self) -> String {
        self.0.name().to_string()
    }
    fn applies_to(&self, model: &HammersteinModel<T>) -> bool {
        !has_effect(model, self.0) && model.settings().with_effect(self.0).is_ok()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        match self.0 {
            Effect::Hysteresis => {
                let t = a.test("input-direction")?;
                let w = a.hysteresis_half_width();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "at equal input level, rising and falling samples leave different residuals \
                         (input-referred falling − rising gap {}; {}): hysteresis half-width ≈ {}",
                        readable(-2.0 * mean(&t.coefficients)),
                        stat_text(t),
                        width(w)
                    ),
                    est(&[("half_width", w)]),
                ))
            }
            Effect::Saturation => {
                let t = a.test("input-extremes")?;
                let (hi, lo) = a.saturation_levels();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "beyond the input's extreme deciles the response flattens (extra slope {} above, \
                         {} below, model gain {}; {}): saturation from u ≈ {} and u ≈ {}",
                        readable(t.coefficients.first().copied().unwrap_or(f64::NAN)),
                        readable(-t.coefficients.get(1).copied().unwrap_or(f64::NAN)),
                        readable(a.gain),
                        stat_text(t),
                        readable(hi.unwrap_or(f64::NAN)),
                        readable(lo.unwrap_or(f64::NAN))
                    ),
                    est(&[("upper_input", hi), ("lower_input", lo)]),
                ))
            }
            Effect::DeadZone => {
                let t = a.test("input-near-zero")?;
                let w = a.dead_zone_width();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "for small |u| the response is weaker than the model's (extra slope {} against \
                         gain {}; {}): dead-zone half-width ≈ {}",
                        readable(t.coefficients.first().copied().unwrap_or(f64::NAN)),
                        readable(a.gain),
                        stat_text(t),
                        width(w)
                    ),
                    est(&[("half_width", w)]),
                ))
            }
            Effect::Preload => {
                let t = a.test("input-zero-step")?;
                let e = a.preload_step();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "the residual steps across u = 0 (input-referred step ±{}; {}): preload ≈ {}",
                        readable(e.unwrap_or(f64::NAN).abs()),
                        stat_text(t),
                        readable(e.unwrap_or(f64::NAN))
                    ),
                    est(&[("step", e)]),
                ))
            }
        }
    }
    /// The model's settings with the effect added and the model's order and feed-through kept (adding a static
    /// effect does not change the dynamics; re-selecting the order after adding one collapsed
    /// real fits, e.g. an MR-damper sine test from 74.9 % to −67 % validation fit).
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let n = model.linear().order();
        Ok(model
            .settings()
            .with_effect(self.0)?
            .order(Order::Fixed(n))
            .with_d(model.has_feedthrough()))
    }
    /// Refits with the effect added at the model's order.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let refit = settings.fit(ctx.train)?;
        let mse = compare(&refit, ctx.validation)?.metrics.mse;
        let params: BTreeMap<String, f64> = refit.parameters().into_iter().collect();
        Ok(Refit {
            validation_mse: mse,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: change_text(ctx.model, &refit),
            estimate: MissingEffect::<T>::refit_estimate(self, &params),
        })
    }
    fn refit_estimate(&self, params: &BTreeMap<String, f64>) -> BTreeMap<String, f64> {
        match self.0 {
            Effect::Hysteresis => pick(params, &["a"]),
            Effect::DeadZone => pick(params, &["b"]),
            Effect::Saturation => pick(params, &["z1", "z2"]),
            Effect::Preload => pick(params, &["e1", "e2"]),
        }
    }
}

/// Linear dynamics deficit: the order is too low (refit with order + 1).
#[derive(Debug, Clone, Copy, Default)]
pub struct Dynamics;

impl<T: Real> MissingEffect<T> for Dynamics {
    fn name(&self) -> String {
        "dynamics".into()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test("dynamics")?;
        let w = a.test("whiteness");
        Some(Evidence::from_test(
            t,
            format!(
                "a linear filter of the nonlinearity's output still explains part of the residual ({}){}",
                stat_text(t),
                w.map(|w| format!("; whiteness: {}", w.detail))
                    .unwrap_or_default()
            ),
            BTreeMap::new(),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let n = model.linear().order();
        Ok(model
            .settings()
            .clone()
            .order(Order::Fixed(n + 1))
            .with_d(model.has_feedthrough()))
    }
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let refit = settings.fit(ctx.train)?;
        let c = compare(&refit, ctx.validation)?;
        let mut estimate = BTreeMap::new();
        estimate.insert("order".into(), refit.linear().order() as f64);
        Ok(Refit {
            validation_mse: c.metrics.mse,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: change_text(ctx.model, &refit),
            estimate,
        })
    }
}

/// Time delay: refit with the input delayed by the shift whose model response best explains the
/// residual.
#[derive(Debug, Clone, Copy, Default)]
pub struct Delay;

impl<T: Real> MissingEffect<T> for Delay {
    fn name(&self) -> String {
        "delay".into()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test("delay")?;
        let d = a.delay_estimate();
        let x = a.test("input-cross-correlation");
        Some(Evidence::from_test(
            t,
            format!(
                "the model's response shifted by {d} sample(s) explains part of the residual ({}){}",
                stat_text(t),
                x.map(|x| format!("; cross-correlation with u: {}", x.detail))
                    .unwrap_or_default()
            ),
            est(&[("extra_delay", Some(d as f64))]),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let current = model.settings().delay_value();
        Ok(model
            .settings()
            .clone()
            .delay(current + a.delay_estimate().max(1)))
    }
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let d = settings.delay_value();
        let refit = settings.fit(ctx.train)?;
        let c = compare(&refit, ctx.validation)?;
        let mut estimate = BTreeMap::new();
        estimate.insert("delay".into(), d as f64);
        Ok(Refit {
            validation_mse: c.metrics.mse,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: format!("delay {} → {d}", ctx.model.settings().delay_value()),
            estimate,
        })
    }
}

/// Output nonlinearity: the residual follows the predicted output; a static cubic map ŷ → y is
/// fitted by least squares on the training data on top of the model.
#[derive(Debug, Clone, Copy, Default)]
pub struct OutputNonlinearity;

impl OutputNonlinearity {
    fn columns(y_hat: &[f64], degree: usize, centre: f64, scale: f64) -> Vec<Vec<f64>> {
        (0..=degree)
            .map(|d| {
                y_hat
                    .iter()
                    .map(|y| ((y - centre) / scale).powi(d as i32))
                    .collect()
            })
            .collect()
    }
    /// Training-fitted polynomial map of the given degree, evaluated as validation MSE.
    fn map_mse(train: &Comparison, val: &Comparison, degree: usize) -> (f64, Vec<f64>) {
        let n = train.y_hat.len() as f64;
        let centre = train.y_hat.iter().sum::<f64>() / n;
        let scale = (train
            .y_hat
            .iter()
            .map(|y| (y - centre).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
            .max(1e-300);
        let cols = Self::columns(&train.y_hat, degree, centre, scale);
        let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
        let ls = least_squares(&train.y, &refs);
        let vcols = Self::columns(&val.y_hat, degree, centre, scale);
        let mse = (0..val.y.len())
            .map(|k| {
                let f: f64 = (0..=degree).map(|d| ls.coefficients[d] * vcols[d][k]).sum();
                (val.y[k] - f).powi(2)
            })
            .sum::<f64>()
            / val.y.len() as f64;
        (mse, ls.coefficients)
    }
}

impl<T: Real> MissingEffect<T> for OutputNonlinearity {
    fn name(&self) -> String {
        "output-nonlinearity".into()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test("output-level")?;
        let lvl = a.test("input-level");
        Some(Evidence::from_test(
            t,
            format!(
                "the residual follows the predicted output ({}){}",
                stat_text(t),
                lvl.map(|l| format!("; against the input level: {}", stat_text(l)))
                    .unwrap_or_default()
            ),
            BTreeMap::new(),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        // the model itself is kept; the refit adds a static map on its output
        Ok(model.settings().clone())
    }
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit> {
        let train = compare(ctx.model, ctx.train)?;
        let val = ctx.validation_comparison;
        let (cubic, coef) = Self::map_mse(&train, val, 3);
        let (affine, _) = Self::map_mse(&train, val, 1);
        if !cubic.is_finite() {
            return Err(Error::Identification(
                "output polynomial map is not finite".into(),
            ));
        }
        let mut estimate = BTreeMap::new();
        for (d, c) in coef.iter().enumerate() {
            estimate.insert(format!("c{d}"), *c);
        }
        Ok(Refit {
            validation_mse: cubic,
            // an affine map only corrects gain and offset: the nonlinearity must beat it
            reference_mse: affine.min(val.metrics.mse),
            change: "static cubic map ŷ → y on the model output (coefficients in standardised ŷ)"
                .into(),
            estimate,
        })
    }
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        0.0
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

/// A number as a person reads it: three decimals in the everyday range, scientific notation
/// for very large or small magnitudes, "n/a" when it could not be estimated.
pub fn readable(x: f64) -> String {
    if !x.is_finite() {
        "n/a".into()
    } else if x != 0.0 && (x.abs() >= 1e4 || x.abs() < 1e-3) {
        format!("{x:.3e}")
    } else {
        format!("{x:.3}")
    }
}

/// A half-width estimate: "none" when the residuals give no positive width.
fn width(w: Option<f64>) -> String {
    match w {
        Some(w) if w.is_finite() && w > 0.0 => readable(w),
        Some(w) if w.is_finite() => "none (the estimate is not positive)".into(),
        _ => "n/a".into(),
    }
}
