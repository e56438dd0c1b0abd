//! The report's input: plain data (no model types), so a report can be drawn from any fit, and its
//! validation (finite numbers, matching lengths).

use crate::error::{Error, Result};

/// One record (training or validation): input, measured and simulated output.
#[derive(Debug, Clone, Default)]
pub struct Record {
    /// Input u(k).
    pub u: Vec<f64>,
    /// Measured output y(k).
    pub y: Vec<f64>,
    /// Simulated output ŷ(k) (free-run simulation, not a one-step prediction).
    pub y_hat: Vec<f64>,
}

impl Record {
    /// A record from its three series.
    pub fn new(u: Vec<f64>, y: Vec<f64>, y_hat: Vec<f64>) -> Self {
        Self { u, y, y_hat }
    }
    /// Residual e(k) = y(k) − ŷ(k).
    pub fn residual(&self) -> Vec<f64> {
        self.y.iter().zip(&self.y_hat).map(|(a, b)| a - b).collect()
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.y.len()
    }
    /// True when the record has no samples.
    pub fn is_empty(&self) -> bool {
        self.y.is_empty()
    }
}

/// Units and sampling of the signals, for axis labels.
#[derive(Debug, Clone, Default)]
pub struct Units {
    /// Unit of the input ("V", "mm"); empty when unknown.
    pub input: String,
    /// Unit of the output; empty when unknown.
    pub output: String,
    /// Sampling time in seconds; `None` plots against the sample index.
    pub sample_time: Option<f64>,
}

/// The estimated static nonlinearity: its two branches on a grid, and the data around it.
#[derive(Debug, Clone, Default)]
pub struct NonlinearityCurve {
    /// Name of the nonlinearity and its effects ("udn: hysteresis, saturation").
    pub name: String,
    /// Input grid.
    pub u_grid: Vec<f64>,
    /// v on the grid for a rising input (direction +1).
    pub v_rising: Vec<f64>,
    /// v on the grid for a falling input (direction −1).
    pub v_falling: Vec<f64>,
    /// Input of the data points.
    pub data_u: Vec<f64>,
    /// v of the data points (e.g. v̂(k) plus the residual referred to the input).
    pub data_v: Vec<f64>,
    /// Direction of motion of each data point (+1 rising, −1 falling).
    pub data_direction: Vec<f64>,
    /// How `data_v` was obtained, for the caption.
    pub data_note: String,
}

/// The estimated output map y = g(x) of a Hammerstein–Wiener model, over the data.
#[derive(Debug, Clone, Default)]
pub struct OutputMapCurve {
    /// Name of the map ("poly3", "saturation", "pwl:5").
    pub name: String,
    /// Grid of the linear block's output x (offset removed).
    pub x_grid: Vec<f64>,
    /// g(x) + offset on the grid.
    pub y_grid: Vec<f64>,
    /// The linear block's output along the training record.
    pub data_x: Vec<f64>,
    /// The measured output along the training record.
    pub data_y: Vec<f64>,
}

/// A nonlinearity in feedback w = f(z) over the range z visits, with its standard error.
#[derive(Debug, Clone, Default)]
pub struct FeedbackCurve {
    /// Name of the basis and what z is ("coulomb on the velocity").
    pub name: String,
    /// z on a grid over the visited range.
    pub z_grid: Vec<f64>,
    /// w = f(z) on the grid.
    pub w: Vec<f64>,
    /// The standard error of w on the grid.
    pub se: Vec<f64>,
    /// z along the training record (its spread shows where the curve rests on data).
    pub data_z: Vec<f64>,
    /// How the band was computed (the caption says it).
    pub method: String,
}

/// A correlation function with its confidence bound.
#[derive(Debug, Clone, Default)]
pub struct Correlation {
    /// Lags (samples).
    pub lags: Vec<i64>,
    /// Normalised correlation at each lag.
    pub values: Vec<f64>,
    /// Half-width of the confidence band (values outside ±bound are significant at `level`).
    pub bound: f64,
    /// Confidence level of the band (e.g. 0.99).
    pub level: f64,
}

/// Singular values behind the order choice.
#[derive(Debug, Clone, Default)]
pub struct OrderChoice {
    /// Singular values, largest first.
    pub singular_values: Vec<f64>,
    /// The chosen order n (the first n values are kept).
    pub chosen: usize,
    /// The automatic selection's candidates: (order, with feed-through, criterion), empty when
    /// the order was fixed.
    pub criterion: Vec<(usize, bool, f64)>,
}

/// One step of the "add the named effect and refit" sequence.
#[derive(Debug, Clone, Default)]
pub struct Step {
    /// Label ("linear", "+ saturation", …).
    pub label: String,
    /// Validation MSE of the model of this step.
    pub validation_mse: f64,
    /// Validation fit % of the model of this step.
    pub fit_percent: f64,
}

/// One row of the diagnosis table.
#[derive(Debug, Clone, Default)]
pub struct DiagnosisRow {
    /// Effect name.
    pub effect: String,
    /// Ranking score.
    pub score: f64,
    /// One sentence of evidence.
    pub evidence: String,
    /// Size estimates, formatted.
    pub estimate: String,
    /// Validation MSE after adding the effect and refitting.
    pub validation_mse_after: f64,
}

/// One residual test of the diagnosis.
#[derive(Debug, Clone, Default)]
pub struct TestRow {
    /// Test name.
    pub name: String,
    /// What it checks.
    pub description: String,
    /// Multiple-testing adjusted p-value.
    pub p_adjusted: f64,
    /// True when significant.
    pub significant: bool,
}

/// One named parameter value.
#[derive(Debug, Clone, Default)]
pub struct Parameter {
    /// Parameter name.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Short note (unit, meaning); may be empty.
    pub note: String,
}

/// Everything a report shows, as plain numbers and strings.
#[derive(Debug, Clone, Default)]
pub struct ReportInput {
    /// Page title.
    pub title: String,
    /// Data-set name (and where it comes from).
    pub dataset: String,
    /// Units and sampling time.
    pub units: Units,
    /// Training (estimation) record.
    pub train: Record,
    /// Validation record, if any.
    pub validation: Option<Record>,
    /// The estimated nonlinearity, if the model has one.
    pub nonlinearity: Option<NonlinearityCurve>,
    /// The estimated output map, if the model has one (Hammerstein–Wiener).
    pub output_map: Option<OutputMapCurve>,
    /// The nonlinearity in feedback, if the model has one.
    pub feedback: Option<FeedbackCurve>,
    /// A several-input model's other inputs' nonlinearities (`nonlinearity` is the first
    /// input's), each with the input's name and unit.
    pub other_inputs: Vec<(String, String, NonlinearityCurve)>,
    /// Residual autocorrelation (training residual).
    pub autocorrelation: Option<Correlation>,
    /// Cross-correlation of the residual with the input.
    pub cross_correlation: Option<Correlation>,
    /// Singular values and the chosen order.
    pub order: Option<OrderChoice>,
    /// Validation error before and after each added effect.
    pub steps: Vec<Step>,
    /// Noise floor of the validation MSE (noise variance), when known.
    pub noise_floor: Option<f64>,
    /// One-line diagnosis summary.
    pub diagnosis_summary: String,
    /// Ranked missing-effect suggestions.
    pub diagnosis: Vec<DiagnosisRow>,
    /// Residual tests.
    pub tests: Vec<TestRow>,
    /// Model parameters.
    pub parameters: Vec<Parameter>,
    /// The training residual referred to the input (an estimate of the missing part of v, aligned
    /// with u(k)); when given, the residual-by-direction plot uses it instead of y − ŷ.
    pub referred_residual: Option<Vec<f64>>,
    /// Free text notes (data handling: offsets, decimation, …), one paragraph each.
    pub notes: Vec<String>,
}

fn finite(what: &str, xs: &[f64]) -> Result<()> {
    match xs.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(Error::NonFinite {
            what: what.to_string(),
            index,
        }),
        None => Ok(()),
    }
}

fn same_len(what: &str, a: usize, b: usize) -> Result<()> {
    if a == b {
        Ok(())
    } else {
        Err(Error::LengthMismatch {
            what: format!("{what}: {a} vs {b} samples"),
        })
    }
}

fn check_record(name: &str, r: &Record) -> Result<()> {
    if r.y.len() < 2 {
        return Err(Error::TooFewSamples {
            needed: 2,
            got: r.y.len(),
            reason: format!("plotting the {name} record"),
        });
    }
    same_len(&format!("{name} u and y"), r.u.len(), r.y.len())?;
    same_len(&format!("{name} y and ŷ"), r.y_hat.len(), r.y.len())?;
    finite(&format!("{name} u"), &r.u)?;
    finite(&format!("{name} y"), &r.y)?;
    finite(&format!("{name} ŷ"), &r.y_hat)
}

fn check_correlation(name: &str, c: &Correlation) -> Result<()> {
    same_len(name, c.lags.len(), c.values.len())?;
    finite(name, &c.values)?;
    finite(&format!("{name} bound"), &[c.bound, c.level])
}

impl ReportInput {
    /// Checks that every number is finite and that paired series have one length.
    pub fn validate(&self) -> Result<()> {
        check_record("training", &self.train)?;
        if let Some(v) = &self.validation {
            check_record("validation", v)?;
        }
        if let Some(nl) = &self.nonlinearity {
            same_len(
                "nonlinearity grid and rising branch",
                nl.u_grid.len(),
                nl.v_rising.len(),
            )?;
            same_len(
                "nonlinearity grid and falling branch",
                nl.u_grid.len(),
                nl.v_falling.len(),
            )?;
            same_len(
                "nonlinearity data u and v",
                nl.data_u.len(),
                nl.data_v.len(),
            )?;
            same_len(
                "nonlinearity data u and direction",
                nl.data_u.len(),
                nl.data_direction.len(),
            )?;
            for (w, s) in [
                ("nonlinearity grid", &nl.u_grid),
                ("nonlinearity rising branch", &nl.v_rising),
                ("nonlinearity falling branch", &nl.v_falling),
                ("nonlinearity data u", &nl.data_u),
                ("nonlinearity data v", &nl.data_v),
                ("nonlinearity data direction", &nl.data_direction),
            ] {
                finite(w, s)?;
            }
        }
        if let Some(f) = &self.feedback {
            same_len("feedback grid and f(z)", f.z_grid.len(), f.w.len())?;
            same_len("feedback grid and its band", f.z_grid.len(), f.se.len())?;
            for (w, s) in [
                ("feedback grid", &f.z_grid),
                ("feedback f(z)", &f.w),
                ("feedback band", &f.se),
                ("feedback data z", &f.data_z),
            ] {
                finite(w, s)?;
            }
        }
        if let Some(r) = &self.referred_residual {
            same_len(
                "referred residual and training record",
                r.len(),
                self.train.len(),
            )?;
            finite("referred residual", r)?;
        }
        if let Some(c) = &self.autocorrelation {
            check_correlation("residual autocorrelation", c)?;
        }
        if let Some(c) = &self.cross_correlation {
            check_correlation("input cross-correlation", c)?;
        }
        if let Some(o) = &self.order {
            finite("singular values", &o.singular_values)?;
            if o.chosen > o.singular_values.len() {
                return Err(Error::InvalidParameter(format!(
                    "chosen order {} exceeds the {} singular values given",
                    o.chosen,
                    o.singular_values.len()
                )));
            }
        }
        for s in &self.steps {
            finite(
                &format!("step '{}'", s.label),
                &[s.validation_mse, s.fit_percent],
            )?;
        }
        if let Some(f) = self.noise_floor {
            finite("noise floor", &[f])?;
        }
        Ok(())
    }
}
