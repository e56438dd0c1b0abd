//! The residual analysis of one model on one record: the signals, the prewhitened regression
//! engine the signature tests share, the size estimates the missing-effect candidates quote, and
//! the [`ResidualTest`] trait every residual test implements. Which tests run is the
//! [`TestRegistry`](crate::diagnosis::TestRegistry)'s business (`test_registry.rs`).

use super::checks::signature::{Domain, SignatureEngine, clip, direction, hinges, lagged};
use super::checks::signature::{quantile_sorted, sorted};
use super::checks::{TestFamily, TestResult};
use super::regression::NestedTest;
use crate::diagnosis::ids::TestId;
use crate::error::{Error, Result};
use crate::statespace::StateSpace;
use serde::Serialize;

/// Settings of the residual analysis.
#[derive(Debug, Clone, Serialize)]
pub struct AnalysisOptions {
    /// Family-wise significance level (Bonferroni over all tests).
    pub alpha: f64,
    /// Number of quantile bins for the level and output tests.
    pub bins: usize,
    /// Number of quantile bins for the rising/falling split.
    pub direction_bins: usize,
    /// Largest lag of the input cross-correlation test.
    pub max_lag: usize,
    /// Lags of the Ljung–Box test.
    pub whiteness_lags: usize,
    /// Length of the FIR used by the linear-dynamics test.
    pub fir_length: usize,
    /// Largest order of the AR prewhitening filter.
    pub max_ar: usize,
    /// The structure verdict of the record's levels when one is at hand (a multisine record at
    /// several levels): poles that move with the level are evidence for a nonlinearity in
    /// feedback beside the residual's. `None` by default.
    pub structure: Option<super::structure_evidence::StructureEvidence>,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        Self {
            alpha: 0.01,
            bins: 8,
            direction_bins: 6,
            max_lag: 25,
            whiteness_lags: 20,
            fir_length: 16,
            max_ar: 20,
            structure: None,
        }
    }
}

/// Residual analysis: signals, test results and size estimates (all in f64).
#[derive(Debug, Clone)]
pub struct ResidualAnalysis {
    /// Input u(k).
    pub u: Vec<f64>,
    /// Measured output y(k).
    pub y: Vec<f64>,
    /// Simulated output ŷ(k).
    pub y_hat: Vec<f64>,
    /// Residual e(k) = y(k) − ŷ(k).
    pub residual: Vec<f64>,
    /// The model's nonlinearity output v̂(k).
    pub v_hat: Vec<f64>,
    /// Direction of motion s(k) of the input.
    pub direction: Vec<f64>,
    /// Average slope of v̂ against u (the model's gain, for input-referred sizes).
    pub gain: f64,
    /// All tests, with Bonferroni-adjusted p-values.
    pub tests: Vec<TestResult>,
    /// Options used.
    pub options: AnalysisOptions,
    engine: SignatureEngine,
    lag_base: Vec<Vec<f64>>,
}

const N_LAG_BASE: usize = 4;

/// A residual test: a statistic and a p-value computed from a [`ResidualAnalysis`]'s signals.
///
/// Register your own with [`TestRegistry::register`](crate::diagnosis::TestRegistry::register) (and
/// [`Diagnoser::register_test`](crate::diagnosis::Diagnoser::register_test)); it then runs with the
/// built-ins, its p-value Bonferroni-adjusted over all of them, and its failure reported like
/// theirs. [`ResidualAnalysis::signature_test`] is the usual way to compute one.
pub trait ResidualTest: Send + Sync {
    /// Which test (a user's: `TestId::User(name)`).
    fn id(&self) -> TestId;
    /// Runs the test on the analysis' signals (its `p_adjusted` and `significant` are set by
    /// the analysis afterwards).
    fn run(&self, analysis: &ResidualAnalysis) -> TestResult;
    /// The model classes beyond the current one that would address this test's failure when
    /// no candidate explains it (reported in `Diagnosis::unexplained`; default: "a model class
    /// beyond the Hammerstein structure").
    fn model_classes(&self) -> Vec<String> {
        vec![BEYOND.to_string()]
    }
}

/// The model class a failing test points to when it names none.
pub(crate) const BEYOND: &str = "a model class beyond the Hammerstein structure";

impl ResidualAnalysis {
    /// The signals and the regression engine of the residual of a model with linear block
    /// `linear` (SISO), before any test has run.
    pub(crate) fn prepare(
        u: &[f64],
        y: &[f64],
        y_hat: &[f64],
        v_hat: &[f64],
        linear: &StateSpace<f64>,
        options: AnalysisOptions,
    ) -> Result<Self> {
        let n = u.len();
        if y.len() != n || y_hat.len() != n || v_hat.len() != n {
            return Err(Error::LengthMismatch {
                what: "residual analysis needs u, y, ŷ and v̂ of one length".into(),
            });
        }
        let needed = 100.max(2 * (options.fir_length + options.max_ar + 2 * options.bins + 10));
        if n < needed {
            return Err(Error::TooFewSamples {
                needed,
                got: n,
                reason: "residual tests".into(),
            });
        }
        if linear.n_inputs() != 1 || linear.n_outputs() != 1 {
            return Err(Error::Dimension(
                "the residual analysis handles single-input single-output models".into(),
            ));
        }
        for (name, s) in [("u", u), ("y", y), ("ŷ", y_hat), ("v̂", v_hat)] {
            if let Some(i) = s.iter().position(|x| !x.is_finite()) {
                return Err(Error::NonFinite {
                    what: name.into(),
                    index: i,
                });
            }
        }
        let residual: Vec<f64> = y.iter().zip(y_hat).map(|(a, b)| a - b).collect();
        let dir = direction(u);
        let gain = {
            let mu = u.iter().sum::<f64>() / n as f64;
            let mv = v_hat.iter().sum::<f64>() / n as f64;
            let suv: f64 = u.iter().zip(v_hat).map(|(a, b)| (a - mu) * (b - mv)).sum();
            let suu: f64 = u.iter().map(|a| (a - mu).powi(2)).sum();
            if suu > 0.0 { suv / suu } else { 0.0 }
        };
        let g_v = linear.simulate_siso(v_hat, None)?;
        let base = vec![vec![1.0; n], g_v];
        let burn = (n / 20).clamp(10, 100);
        let engine = SignatureEngine::new(&residual, &base, linear.clone(), burn, options.max_ar);
        let lag_base: Vec<Vec<f64>> = (0..N_LAG_BASE).map(|d| lagged(v_hat, d)).collect();
        Ok(Self {
            u: u.to_vec(),
            y: y.to_vec(),
            y_hat: y_hat.to_vec(),
            residual,
            v_hat: v_hat.to_vec(),
            direction: dir,
            gain,
            tests: Vec::new(),
            options,
            engine,
            lag_base,
        })
    }

    /// Runs `tests` in order and adjusts their p-values over all of them.
    pub(crate) fn run_tests(&mut self, tests: &[Box<dyn ResidualTest>]) {
        self.tests = tests.iter().map(|t| t.run(self)).collect();
        self.adjust();
    }

    /// The prewhitened regression engine shared by the signature tests.
    pub(crate) fn engine(&self) -> &SignatureEngine {
        &self.engine
    }

    /// The lagged v̂ columns every input-domain signature test has in its null model.
    pub(crate) fn lag_base(&self) -> &[Vec<f64>] {
        &self.lag_base
    }

    /// The result of a nested F test `t` (not applicable when `None`), with `detail` as the
    /// numbers that matter.
    pub(crate) fn make(
        &self,
        name: impl Into<TestId>,
        description: &str,
        family: TestFamily,
        t: Option<NestedTest>,
        detail: impl Fn(&NestedTest) -> String,
    ) -> TestResult {
        let name = name.into();
        match t {
            Some(t) => {
                let mut r = TestResult::new(
                    name,
                    description,
                    family,
                    "F",
                    t.f,
                    vec![t.df1, t.df2],
                    t.p_value,
                );
                r.detail = format!("F({}, {}) = {:.2}; {}", t.df1, t.df2, t.f, detail(&t));
                r.coefficients = t.coefficients.clone();
                r
            }
            None => {
                let mut r = TestResult::new(name, description, family, "F", 0.0, Vec::new(), 1.0);
                r.detail = "not applicable (columns dependent on the model's own response)".into();
                r
            }
        }
    }

    /// Recomputes the Bonferroni-adjusted p-values over all tests.
    fn adjust(&mut self) {
        let m = self.tests.len() as f64;
        let alpha = self.options.alpha;
        for t in &mut self.tests {
            t.p_adjusted = (t.p_value * m).min(1.0);
            t.significant = t.p_adjusted < alpha;
        }
    }

    /// The test `id` (a [`TestId`], or its name), when it ran.
    pub fn test(&self, id: impl Into<TestId>) -> Option<&TestResult> {
        let id = id.into();
        self.tests.iter().find(|t| t.name == id)
    }

    /// True when at least one test is significant after the multiple-testing correction.
    pub fn any_significant(&self) -> bool {
        self.tests.iter().any(|t| t.significant)
    }

    /// Residual mean square.
    pub fn residual_mse(&self) -> f64 {
        self.residual.iter().map(|e| e * e).sum::<f64>() / self.residual.len() as f64
    }

    /// Number of samples entering the signature regressions (after burn-in and prewhitening).
    pub fn regression_samples(&self) -> usize {
        self.engine.n_samples()
    }

    /// Order of the AR prewhitening filter.
    pub fn prewhitening_order(&self) -> usize {
        self.engine.ar_order()
    }

    /// A user's signature test: do these columns (functions of u for [`Domain::Input`], of ŷ for
    /// [`Domain::Output`]) explain part of the residual? Its p-value is Bonferroni-adjusted as one
    /// more test of the analysis.
    pub fn signature_test(
        &self,
        name: impl Into<TestId>,
        description: &str,
        columns: &[Vec<f64>],
        domain: Domain,
    ) -> TestResult {
        self.signature_test_beyond(name, description, columns, domain, &[])
    }

    /// [`signature_test`](Self::signature_test) with more columns in the null model: do
    /// `columns` explain part of the residual beyond `beyond` (functions of u, filtered through
    /// the linear block like the input-domain columns)?
    pub fn signature_test_beyond(
        &self,
        name: impl Into<TestId>,
        description: &str,
        columns: &[Vec<f64>],
        domain: Domain,
        beyond: &[Vec<f64>],
    ) -> TestResult {
        let mut base = self.lag_base.clone();
        base.extend(beyond.iter().cloned());
        let t = match domain {
            Domain::Input => self.engine.test(columns, &base, domain),
            Domain::Output => self.engine.test_mixed(columns, domain, &base, &[]),
        };
        let mut r = self.make(name, description, TestFamily::Nonlinear, t, |t| {
            format!("coefficients {}", fmt_list(&t.coefficients))
        });
        let m = self.tests.len() as f64 + 1.0;
        r.p_adjusted = (r.p_value * m).min(1.0);
        r.significant = r.p_adjusted < self.options.alpha;
        r
    }

    /// Best shift d in 1..=max of the model response as an extra regressor (largest F) and its test.
    pub(crate) fn best_delay_test(&self, max: usize) -> (usize, Option<NestedTest>) {
        let mut best: (usize, Option<NestedTest>) = (1, None);
        for d in 1..=max {
            let col = lagged(&self.v_hat, d);
            let t = self.engine.test(&[col], &[], Domain::Input);
            if let Some(t) = t
                && best.1.as_ref().is_none_or(|b| t.f > b.f)
            {
                best = (d, Some(t));
            }
        }
        // the best of `max` shifts: Bonferroni over them
        if let Some(t) = best.1.as_mut() {
            t.p_value = (t.p_value * max as f64).min(1.0);
        }
        best
    }

    /// Extra delay (samples) whose shifted model response best explains the residual.
    pub fn delay_estimate(&self) -> usize {
        self.best_delay_test(5).0
    }

    /// Hysteresis half-width in input units from the rising/falling split (input-referred).
    pub fn hysteresis_half_width(&self) -> Option<f64> {
        let t = self.test(TestId::InputDirection)?;
        if t.coefficients.is_empty() || self.gain == 0.0 {
            return None;
        }
        Some(-mean(&t.coefficients) / self.gain)
    }

    /// Step of v across u = 0 (input-referred; positive = a preload pushing away from zero).
    pub fn preload_step(&self) -> Option<f64> {
        let t = self.test(TestId::InputZeroStep)?;
        let c = *t.coefficients.first()?;
        Some(if self.gain < 0.0 { -c } else { c })
    }

    /// Dead-zone half-width: the clip level d in the quantiles of |u| whose clip(u, ±d) column
    /// explains the residual best (scan over 5 %..60 % of |u|).
    pub fn dead_zone_width(&self) -> Option<f64> {
        let a = sorted(&self.u.iter().map(|x| x.abs()).collect::<Vec<_>>());
        let mut best: Option<(f64, f64)> = None;
        for j in 1..=12 {
            let d = quantile_sorted(&a, 0.05 * j as f64);
            if d <= 0.0 {
                continue;
            }
            if let Some(t) = self
                .engine
                .test(&[clip(&self.u, d)], &self.lag_base, Domain::Input)
                && best.is_none_or(|b| t.f > b.1)
            {
                best = Some((d, t.f));
            }
        }
        best.map(|b| b.0)
    }

    /// Saturation thresholds (upper, lower) in input units where the residual departs: the knots
    /// of hinge columns (u − κ)₊ and (κ − u)₊ that explain the residual best (scan over the input's
    /// 50 %..98 % and 2 %..50 % quantiles).
    pub fn saturation_levels(&self) -> (Option<f64>, Option<f64>) {
        let s = sorted(&self.u);
        // coordinate scans: each side's knot with the other side's hinge in the base
        let scan = |upper: bool, other: f64| -> Option<f64> {
            let mut best: Option<(f64, f64)> = None;
            for j in 0..=12 {
                let q = 0.5 + 0.04 * j as f64;
                let kappa = quantile_sorted(&s, if upper { q } else { 1.0 - q });
                let (hi, lo) = if upper {
                    (kappa, other)
                } else {
                    (other, kappa)
                };
                let h = hinges(&self.u, lo, hi);
                let (col, fixed) = if upper {
                    (h[0].clone(), h[1].clone())
                } else {
                    (h[1].clone(), h[0].clone())
                };
                let mut eb = self.lag_base.clone();
                eb.push(fixed);
                if let Some(t) = self.engine.test(&[col], &eb, Domain::Input)
                    && best.is_none_or(|b| t.f > b.1)
                {
                    best = Some((kappa, t.f));
                }
            }
            best.map(|b| b.0)
        };
        let hi0 = scan(true, quantile_sorted(&s, 0.1));
        let lo = hi0.and_then(|h| scan(false, h));
        let hi = lo.and_then(|l| scan(true, l)).or(hi0);
        (hi, lo)
    }
}

pub(crate) fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        0.0
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

pub(crate) fn fmt_list(x: &[f64]) -> String {
    let v: Vec<String> = x.iter().map(|c| format!("{c:.3}")).collect();
    format!("[{}]", v.join(", "))
}
