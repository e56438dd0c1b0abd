//! The built-in residual tests: whiteness and input cross-correlation (`checks/`), the linear
//! deficits (an FIR of v̂, a shifted response) and the nonlinear signatures (input level,
//! direction, extremes, small |u|, the step at 0, u², u³, output level).

use super::analysis::{BEYOND, ResidualAnalysis, ResidualTest, fmt_list, mean};
use super::checks::cross_correlation::cross_correlation_test;
use super::checks::signature::{
    Domain, centred_power, clip, direction_bins, hinges, lagged, level_bins, quantile_sorted, sign,
    sorted,
};
use super::checks::whiteness::ljung_box;
use super::checks::{TestFamily, TestResult};
use crate::diagnosis::ids::TestId;

/// One built-in residual test, by its id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BuiltinTest(pub TestId);

impl ResidualTest for BuiltinTest {
    fn id(&self) -> TestId {
        self.0.clone()
    }
    /// The test; a `User` id or the Prandtl–Ishlinskii candidate's own test (not a built-in
    /// of the registry) gives a "not applicable" result.
    fn run(&self, a: &ResidualAnalysis) -> TestResult {
        let o = &a.options;
        match self.0 {
            TestId::Whiteness => ljung_box(&a.residual, o.whiteness_lags),
            TestId::InputCrossCorrelation => cross_correlation_test(&a.residual, &a.u, o.max_lag),
            TestId::Dynamics => dynamics(a),
            TestId::Delay => delay(a),
            TestId::InputLevel => input_level(a),
            TestId::InputDirection => input_direction(a),
            TestId::InputExtremes => input_extremes(a),
            TestId::InputNearZero => input_near_zero(a),
            TestId::InputZeroStep => input_zero_step(a),
            TestId::InputSquare => input_power(a, 2),
            TestId::InputCube => input_power(a, 3),
            TestId::OutputLevel => output_level(a),
            TestId::PrandtlIshlinskii | TestId::FeedbackNonlinearity | TestId::User(_) => a.make(
                self.0.clone(),
                "not a built-in residual test",
                TestFamily::Nonlinear,
                None,
                |_| String::new(),
            ),
        }
    }
    fn model_classes(&self) -> Vec<String> {
        model_classes_for(&self.0)
    }
}

/// Model classes that address a failing built-in test when no candidate does.
fn model_classes_for(test: &TestId) -> Vec<String> {
    let classes: &[&str] = match test {
        TestId::Whiteness | TestId::Dynamics => &[
            "nonlinear feedback or dynamics the static nonlinearity cannot carry",
            "coloured noise (a noise model)",
        ],
        TestId::InputCrossCorrelation | TestId::Delay => &["a second input", "nonlinear feedback"],
        TestId::InputDirection => &["dynamic hysteresis (Prandtl–Ishlinskii, Bouc–Wen)"],
        TestId::InputLevel
        | TestId::InputExtremes
        | TestId::InputNearZero
        | TestId::InputZeroStep
        | TestId::InputSquare
        | TestId::InputCube => &[
            "an input nonlinearity outside the UDN family (a user basis)",
            "dynamic hysteresis (Prandtl–Ishlinskii, Bouc–Wen)",
        ],
        TestId::OutputLevel => &["an output nonlinearity (Hammerstein–Wiener)"],
        TestId::PrandtlIshlinskii | TestId::FeedbackNonlinearity | TestId::User(_) => &[BEYOND],
    };
    classes.iter().map(|c| c.to_string()).collect()
}

/// Linear dynamics: an FIR of v̂ beyond the model's own response.
fn dynamics(a: &ResidualAnalysis) -> TestResult {
    let fir: Vec<Vec<f64>> = (0..a.options.fir_length)
        .map(|d| lagged(&a.v_hat, d))
        .collect();
    let t = a.engine().test(&fir, &[], Domain::Output);
    a.make(
        TestId::Dynamics,
        "residual explained by an FIR of the nonlinearity output v̂ (linear dynamics missing)",
        TestFamily::Linear,
        t,
        |t| {
            format!(
                "an FIR of {} lags of v̂ explains {:.1} % of the residual variance",
                t.coefficients.len(),
                100.0 * (1.0 - t.rss_full / t.rss_base)
            )
        },
    )
}

/// Delay mismatch: the model's response shifted by the best of 1..=5 samples.
fn delay(a: &ResidualAnalysis) -> TestResult {
    let (d, t) = a.best_delay_test(5);
    a.make(
        TestId::Delay,
        "residual explained by the model's own response shifted in time (delay mismatch)",
        TestFamily::Linear,
        t,
        |t| {
            format!(
                "the model response delayed by {d} sample(s) explains {:.1} % of the residual variance",
                100.0 * (1.0 - t.rss_full / t.rss_base)
            )
        },
    )
}

/// Binned input level (input-referred ANOVA).
fn input_level(a: &ResidualAnalysis) -> TestResult {
    let lvl = level_bins(&a.u, a.options.bins);
    let t = a.engine().test(&lvl, a.lag_base(), Domain::Input);
    a.make(
        TestId::InputLevel,
        "residual against the input level (binned, input-referred ANOVA)",
        TestFamily::Nonlinear,
        t,
        |t| {
            format!(
                "bin means of the missing part of v: {}",
                fmt_list(&t.coefficients)
            )
        },
    )
}

/// Rising against falling input at equal level, beyond the level bins (hysteresis).
fn input_direction(a: &ResidualAnalysis) -> TestResult {
    let o = &a.options;
    let dirs = direction_bins(&a.u, &a.direction, o.direction_bins);
    let mut eb = a.lag_base().to_vec();
    eb.extend(level_bins(&a.u, o.bins));
    let t = a.engine().test(&dirs, &eb, Domain::Input);
    let gain = a.gain;
    a.make(
        TestId::InputDirection,
        "rising versus falling input at the same level (hysteresis signature)",
        TestFamily::Nonlinear,
        t,
        |t| {
            let m = mean(&t.coefficients);
            format!(
                "falling − rising difference of v at equal input: {:.3} (mean over {} bins), i.e. a half-width ≈ {:.3} in input units",
                -2.0 * m,
                t.coefficients.len(),
                if gain != 0.0 { -m / gain } else { f64::NAN }
            )
        },
    )
}

/// Slopes beyond the input's extreme deciles (saturation).
fn input_extremes(a: &ResidualAnalysis) -> TestResult {
    let s = sorted(&a.u);
    let (q10, q90) = (quantile_sorted(&s, 0.1), quantile_sorted(&s, 0.9));
    let t = a
        .engine()
        .test(&hinges(&a.u, q10, q90), a.lag_base(), Domain::Input);
    let gain = a.gain;
    a.make(
        TestId::InputExtremes,
        "slope of the residual against the input beyond its top and bottom deciles (saturation signature)",
        TestFamily::Nonlinear,
        t,
        |t| {
            format!(
                "extra slope of v above u = {q90:.3}: {:.3}, below u = {q10:.3}: {:.3} (model gain {gain:.3})",
                t.coefficients[0], -t.coefficients[1]
            )
        },
    )
}

/// Slope for small |u| (dead-zone).
fn input_near_zero(a: &ResidualAnalysis) -> TestResult {
    let abs_sorted = sorted(&a.u.iter().map(|x| x.abs()).collect::<Vec<_>>());
    let d20 = quantile_sorted(&abs_sorted, 0.2);
    let t = a
        .engine()
        .test(&[clip(&a.u, d20)], a.lag_base(), Domain::Input);
    let gain = a.gain;
    a.make(
        TestId::InputNearZero,
        "slope of the residual against the input for small |u| (dead-zone signature)",
        TestFamily::Nonlinear,
        t,
        |t| {
            format!(
                "extra slope of v for |u| < {d20:.3}: {:.3} (model gain {gain:.3})",
                t.coefficients[0]
            )
        },
    )
}

/// A step across u = 0 (preload).
fn input_zero_step(a: &ResidualAnalysis) -> TestResult {
    let t = a.engine().test(&[sign(&a.u)], a.lag_base(), Domain::Input);
    a.make(
        TestId::InputZeroStep,
        "a step of the residual across u = 0 (preload signature)",
        TestFamily::Nonlinear,
        t,
        |t| format!("step of v across u = 0: ±{:.3}", t.coefficients[0]),
    )
}

/// Correlation with u² or u³ (Billings-style).
fn input_power(a: &ResidualAnalysis, power: i32) -> TestResult {
    let t = a
        .engine()
        .test(&[centred_power(&a.u, power)], a.lag_base(), Domain::Input);
    let (id, description) = if power == 2 {
        (
            TestId::InputSquare,
            "correlation of the residual with u² (Billings-style)",
        )
    } else {
        (
            TestId::InputCube,
            "correlation of the residual with u³ (Billings-style)",
        )
    };
    a.make(id, description, TestFamily::Nonlinear, t, |t| {
        format!("coefficient of u^{power}: {:.4}", t.coefficients[0])
    })
}

/// Binned predicted output (output nonlinearity).
fn output_level(a: &ResidualAnalysis) -> TestResult {
    let out = level_bins(&a.y_hat, a.options.bins);
    let t = a
        .engine()
        .test_mixed(&out, Domain::Output, a.lag_base(), &[]);
    a.make(
        TestId::OutputLevel,
        "residual against the predicted output (binned; output-nonlinearity signature)",
        TestFamily::Nonlinear,
        t,
        |t| {
            format!(
                "bin means of the residual by ŷ: {}",
                fmt_list(&t.coefficients)
            )
        },
    )
}
