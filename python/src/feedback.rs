//! The feedback model (a linear block with a static nonlinearity in feedback, src/feedback/):
//! fitted as `hammerstein fit --feedback-nonlinearity` fits it, simulated, compared, saved in
//! the same model file. Only the library's public feedback API is used; everything the Python
//! layer shows is read from the model file's JSON and the fit's report.

use hammerstein::feedback::{
    self, FeedbackKind, FeedbackModel, FeedbackModelFile, FeedbackOn, FeedbackSettings,
};
use hammerstein::fit::Feedthrough;
use hammerstein::{Error, IoData, Order};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use serde_json::json;

use crate::arrays::{record, vector};
use crate::errors::{IntoPy, json_error};
use crate::settings::FitArgs;
use hammerstein::regressors::output_map_from_name;

/// A fitted feedback model (wrapped by `hammerstein.FeedbackModel` in Python).
#[pyclass(module = "hammerstein._hammerstein", frozen)]
pub struct Feedback {
    model: FeedbackModel,
    /// The decimation factor its file records (1: none).
    decimation: usize,
    /// The columns its file names (the command line's), if any.
    columns: Option<(String, String)>,
}

impl Feedback {
    fn file(&self) -> FeedbackModelFile {
        let mut f = self.model.to_file();
        f.columns = self.columns.clone();
        f.decimation = Some(self.decimation).filter(|&k| k > 1);
        f
    }
}

/// A model of the model file's JSON value (of kind "feedback"); `label` names it in errors.
pub fn from_value(v: serde_json::Value, label: &str) -> Result<Feedback, Error> {
    let at = |e: Error| match e {
        Error::ModelFormat(m) => Error::ModelFormat(format!("{label}: {m}")),
        e => e,
    };
    let file = FeedbackModelFile::from_value(v).map_err(at)?;
    let model = FeedbackModel::from_file(&file, |spec| {
        Err(Error::ModelFormat(format!(
            "{label}: unknown feedback nonlinearity kind '{}'",
            spec.kind
        )))
    })?;
    Ok(Feedback {
        model,
        decimation: file.decimation.unwrap_or(1),
        columns: file.columns,
    })
}

/// Fits a feedback model to input `u` and output `y` (N × 1 each, float64) of sample time
/// `ts`: `nonlinearity` (poly3, poly5, coulomb, dead-zone, saturation, pwl:K) on `on` (output,
/// velocity or state), the linear block's `order` ("auto", "gap" or a number), `horizon`
/// (None: 10), `feedthrough` (auto and off: none; on: a D), the refinement's `max_iterations`
/// and `tolerance`; an input nonlinearity before the loop by `effects` (the UDN's, as
/// `--effects`) or `input_nonlinearity` (udn, sh, linear, poly3: `--nonlinearity`), and an
/// output map after it by `output_nonlinearity` (polyK, saturation, pwl:K:
/// `--output-nonlinearity`). With a validation record (u_val, y_val) the report holds its RMS
/// error and fit (an error when the model diverges there, as on the command line). Returns the
/// model and the report (JSON: the fields of `fit --feedback-nonlinearity --json`). The GIL is
/// released.
#[pyfunction]
#[pyo3(signature = (u, y, ts, nonlinearity, on, order, horizon, feedthrough, max_iterations, tolerance, u_val, y_val, effects=None, input_nonlinearity=None, output_nonlinearity=None))]
pub fn fit_feedback(
    py: Python<'_>,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
    nonlinearity: &str,
    on: &str,
    order: &str,
    horizon: Option<usize>,
    feedthrough: &str,
    max_iterations: usize,
    tolerance: f64,
    u_val: Option<&Bound<'_, PyAny>>,
    y_val: Option<&Bound<'_, PyAny>>,
    effects: Option<&str>,
    input_nonlinearity: Option<&str>,
    output_nonlinearity: Option<&str>,
) -> PyResult<(Feedback, String)> {
    let train: IoData<f64> = record(py, u, y, ts)?;
    let val: Option<IoData<f64>> = match (u_val, y_val) {
        (Some(a), Some(b)) => Some(record(py, a, b, ts)?),
        _ => None,
    };
    let settings = (|| -> Result<FeedbackSettings, Error> {
        let kind: FeedbackKind = nonlinearity.parse()?;
        let on: FeedbackOn = on.parse()?;
        let mut s = FeedbackSettings::new(kind, on);
        s.order = order.parse::<Order>()?;
        if let Some(h) = horizon {
            s.horizon = h;
        }
        s.with_d = matches!(feedthrough.parse::<Feedthrough>()?, Feedthrough::Present);
        s.max_iterations = max_iterations;
        s.tolerance = tolerance;
        // the input nonlinearity as the Hammerstein estimator builds it from the same names
        if effects.is_some() || input_nonlinearity.is_some() {
            let args = FitArgs {
                effects: vec![effects.map(str::to_string)],
                nonlinearity: input_nonlinearity.map(str::to_string),
                method: "moesp".into(),
                order: "auto".into(),
                horizon: None,
                delay: 0,
                refine: true,
                stable: false,
                feedthrough: "auto".into(),
                seed: 0,
                output_nonlinearity: None,
                backend: "faer".into(),
            };
            s.input = Some(args.single::<f64>()?.build_nonlinearity()?);
        }
        if let Some(name) = output_nonlinearity {
            s.output = Some(output_map_from_name::<f64>(name)?);
        }
        Ok(s)
    })()
    .py_err(py)?;
    let (fit, vc) = py
        .detach(|| -> Result<_, Error> {
            let fit = feedback::fit(&settings, &train)?;
            let vc = match &val {
                Some(v) => Some(fit.model.compare(v)?),
                None => None,
            };
            Ok((fit, vc))
        })
        .py_err(py)?;
    let m = &fit.model;
    let (lo, hi) = m.z_range();
    let report = json!({
        "kind": "feedback",
        "nonlinearity": m.nonlinearity().name(),
        "feedback_on": m.feedback_on().name(),
        "order": m.order(),
        "linear_rms": fit.linear_rms,
        "start_rms": fit.start_rms,
        "train_rms": fit.rms,
        "validation_rms": vc.as_ref().map(|c| c.rms),
        "validation_fit_percent": vc.as_ref().map(|c| c.fit_percent),
        "iterations": fit.refine.iterations,
        "refused_diverging_steps": fit.refine.diverged_steps,
        "z_range": [lo, hi],
        "state_combination": m.state_combination(),
        "input_nonlinearity": m.input_nonlinearity().map(|nl| nl.name()),
        "output_nonlinearity": m.output_map().map(|g| g.name()),
        "warnings": fit.warnings,
    });
    let text = serde_json::to_string(&report).map_err(json_error)?;
    Ok((
        Feedback {
            model: fit.model,
            decimation: 1,
            columns: None,
        },
        text,
    ))
}

#[pymethods]
impl Feedback {
    /// The model file's JSON (what `save` writes).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.file()).map_err(json_error)
    }

    /// Writes the model file (atomically) at `path`.
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        self.file().write(&path).py_err(py)
    }

    /// The decimation factor its file records (1: none).
    #[getter]
    fn decimation(&self) -> usize {
        self.decimation
    }

    /// The output for the input `u` (1-D float64, record units) from rest, as `hammerstein
    /// simulate` gives it; an error when the loop diverges.
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        u: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let u = u.as_array().to_vec();
        let y = py
            .detach(|| self.model.simulate(&u, None))
            .map_err(|e| match e {
                Error::Diverged { index, .. } => Error::Identification(format!(
                    "the feedback model's simulation diverges at sample {index}: the loop is \
                     unstable at this input's amplitude"
                )),
                e => e,
            })
            .py_err(py)?;
        Ok(vector(py, y))
    }

    /// The model on the record (u, y): the initial state estimated on it, as `hammerstein
    /// compare` does. Returns (JSON {n, rms, fit_percent}, the simulated output).
    fn compare<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        y: &Bound<'py, PyAny>,
        ts: f64,
    ) -> PyResult<(String, Bound<'py, PyAny>)> {
        let data: IoData<f64> = record(py, u, y, ts)?;
        let c = py.detach(|| self.model.compare(&data)).py_err(py)?;
        let j = json!({"n": c.simulated.len(), "rms": c.rms, "fit_percent": c.fit_percent});
        let text = serde_json::to_string(&j).map_err(json_error)?;
        Ok((text, vector(py, c.simulated)))
    }

    /// f over `z` in the record's units (z in the output's units, per sample for `velocity`;
    /// w as the input that acts the same way).
    fn f<'py>(&self, py: Python<'py>, z: PyReadonlyArray1<'py, f64>) -> Bound<'py, PyAny> {
        vector(py, self.model.eval_physical(&z.as_array().to_vec()))
    }

    /// The nonlinearity's name as the command line spells it (poly3, coulomb, …).
    #[getter]
    fn name(&self) -> String {
        self.model.nonlinearity().name()
    }

    /// The range of z the training record visited, in the output's units.
    #[getter]
    fn z_range(&self) -> (f64, f64) {
        self.model.z_range()
    }

    /// The input nonlinearity's name before the loop (None without one).
    #[getter]
    fn input_name(&self) -> Option<String> {
        self.model.input_nonlinearity().map(|nl| nl.name())
    }

    /// The output map's name after the loop (None without one).
    #[getter]
    fn output_name(&self) -> Option<String> {
        self.model.output_map().map(|g| g.name())
    }

    /// The input nonlinearity's values v = N(u) over `u` (record units; None without one).
    fn input_map<'py>(
        &self,
        py: Python<'py>,
        u: PyReadonlyArray1<'py, f64>,
    ) -> Option<Bound<'py, PyAny>> {
        let v = self.model.eval_input(&u.as_array().to_vec())?;
        Some(vector(py, v))
    }

    /// The output map's values g(ℓ) over the linear output `l` (the output's units; None
    /// without one).
    fn output_map<'py>(
        &self,
        py: Python<'py>,
        l: PyReadonlyArray1<'py, f64>,
    ) -> Option<Bound<'py, PyAny>> {
        let g = self.model.eval_output(&l.as_array().to_vec())?;
        Some(vector(py, g))
    }
}

/// A feedback model from the text of its model file (`label` names it in errors).
#[pyfunction]
pub fn loads_feedback(py: Python<'_>, text: &str, label: &str) -> PyResult<Feedback> {
    let v: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| Error::ModelFormat(format!("{label}: not valid JSON: {e}")))
        .py_err(py)?;
    from_value(v, label).py_err(py)
}
