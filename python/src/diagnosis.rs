//! `diagnose`: a model's settings fitted on the training part of a record, its residuals
//! analysed and the effects it is missing named (each checked by a refit); with `follow` the
//! guided loop. The result keeps the models and diagnoses, for the steps' models and the HTML
//! report.

use hammerstein::diagnosis::{Diagnoser, Diagnosis, Metrics};
use hammerstein::fit::{Hammerstein, HammersteinModel};
use hammerstein::{Error, IoData, Real};
use pyo3::exceptions::PyNotImplementedError;
use pyo3::prelude::*;
use serde_json::{Value, json};

use crate::arrays::record;
use crate::errors::{IntoPy, input_error, json_error};
use crate::fit::{Precision, parse_args};
use crate::model::{Inner, Model};

/// One diagnosed model: what changed to reach it ("start" for the first), the model, its
/// diagnosis.
pub struct Step<T: Real> {
    change: String,
    model: HammersteinModel<T>,
    diagnosis: Diagnosis<T>,
}

/// A diagnosis (one step) or a followed sequence (several), and why the sequence stopped.
pub struct Run<T: Real> {
    steps: Vec<Step<T>>,
    stop: Option<Value>,
    validation_rose_at: Vec<usize>,
}

/// The run, by precision.
pub enum Runs {
    /// Double precision.
    F64(Run<f64>),
    /// Single precision.
    F32(Run<f32>),
}

/// The result of `diagnose` (wrapped by `hammerstein.Diagnosis` in Python).
#[pyclass(module = "hammerstein._hammerstein", frozen)]
pub struct Diagnosed {
    runs: Runs,
}

fn metrics_json(m: &Metrics) -> Value {
    serde_json::to_value(m).unwrap_or(Value::Null)
}

/// The diagnosis as JSON: verdict, unexplained tests, typed suggestions, tests, metrics.
fn diagnosis_json<T: Real>(d: &Diagnosis<T>) -> Value {
    let suggestions: Vec<Value> = d
        .suggestions
        .iter()
        .map(|s| {
            let estimates: Vec<Value> = s
                .estimate
                .iter()
                .map(|e| {
                    json!({
                        "key": e.key(),
                        "quantity": e.quantity.name(),
                        "source": serde_json::to_value(e.source).unwrap_or(Value::Null),
                        "value": e.value,
                        "standard_error": e.standard_error,
                    })
                })
                .collect();
            json!({
                "effect": s.effect.to_string(),
                "score": s.score,
                "evidence": s.evidence,
                "estimates": estimates,
                "train_mse_before": s.train_mse_before,
                "train_mse_after": s.train_mse_after,
                "criterion_change": s.criterion_change,
                "validation_mse_before": s.validation_mse_before,
                "validation_mse_after": s.validation_mse_after,
                "p_value": s.p_value,
                "change": s.change,
                "action": serde_json::to_value(&s.action).unwrap_or(Value::Null),
            })
        })
        .collect();
    let null_parameters: Vec<Value> = d
        .candidates
        .iter()
        .filter_map(|c| {
            let r = c.refit.as_ref()?.null_parameters.as_ref()?;
            Some(json!({"effect": c.effect.to_string(), "reason": r}))
        })
        .collect();
    json!({
        "adequate": d.adequate,
        "summary": d.summary,
        "unexplained": d
            .unexplained
            .iter()
            .map(|u| json!({
                "test": u.test.to_string(),
                "p_adjusted": u.p_adjusted,
                "model_classes": u.model_classes,
            }))
            .collect::<Vec<_>>(),
        "suggestions": suggestions,
        "null_parameters": null_parameters,
        "tests": serde_json::to_value(&d.tests).unwrap_or(Value::Null),
        "generalisation": serde_json::to_value(&d.generalisation).unwrap_or(Value::Null),
        "train": metrics_json(&d.train.metrics),
        "validation": metrics_json(&d.validation.metrics),
        "screening_window": d.screening_window,
    })
}

impl<T: Real> Run<T> {
    fn json(&self) -> Value {
        let steps: Vec<Value> = self
            .steps
            .iter()
            .map(|s| {
                json!({
                    "change": s.change,
                    "diagnosis": diagnosis_json(&s.diagnosis),
                })
            })
            .collect();
        json!({
            "steps": steps,
            "stop": self.stop,
            "validation_rose_at": self.validation_rose_at,
        })
    }

    /// The HTML report of the last step (with every step's validation error) in `dir`.
    fn write_html(&self, dir: &std::path::Path, title: &str) -> Result<std::path::PathBuf, Error> {
        use hammerstein::report::{Context, Step as ReportStep, Units, report_input, write_report};
        let last = self
            .steps
            .last()
            .ok_or_else(|| Error::InvalidParameter("no model was diagnosed".into()))?;
        let steps = self
            .steps
            .iter()
            .enumerate()
            .map(|(i, s)| ReportStep {
                label: if i == 0 {
                    format!(
                        "{}, order {}",
                        s.model.nonlinearity().name(),
                        s.model.linear().order()
                    )
                } else {
                    s.change.clone()
                },
                validation_mse: s.diagnosis.validation.metrics.mse,
                fit_percent: s.diagnosis.validation.metrics.fit_percent,
            })
            .collect();
        let ts = last.model.linear().ts;
        let ctx = Context {
            title: title.to_string(),
            dataset: title.to_string(),
            units: Units {
                sample_time: (ts != 1.0).then_some(ts),
                ..Default::default()
            },
            steps,
            ..Default::default()
        };
        let input = report_input(&last.model, &last.diagnosis, ctx)?;
        write_report(dir, &input)
    }
}

/// Fits `settings` on `train` and diagnoses the model on `validation`; with `follow`, the
/// guided loop of at most `max_steps` steps.
fn run_t<T: Real>(
    settings: &Hammerstein<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
    follow: bool,
    max_steps: usize,
) -> Result<Run<T>, Error> {
    let diagnoser = Diagnoser::<T>::new();
    if follow {
        let f = diagnoser.follow(settings, train, validation, max_steps)?;
        let validation_rose_at = f.validation_rose();
        let stop = serde_json::to_value(&f.stop).unwrap_or(Value::Null);
        let text = f.stop.to_string();
        return Ok(Run {
            steps: f
                .steps
                .into_iter()
                .map(|s| Step {
                    change: s.change,
                    model: s.model,
                    diagnosis: s.diagnosis,
                })
                .collect(),
            stop: Some(json!({"code": stop, "text": text})),
            validation_rose_at,
        });
    }
    let model = settings.fit(train)?;
    let diagnosis = diagnoser.diagnose(&model, train, validation)?;
    Ok(Run {
        steps: vec![Step {
            change: "start".into(),
            model,
            diagnosis,
        }],
        stop: None,
        validation_rose_at: Vec::new(),
    })
}

/// The training and validation records: the last `fraction` of (u, y) held out, or (u, y) and
/// (u_val, y_val).
fn records<T: Precision>(
    py: Python<'_>,
    data: (&Bound<'_, PyAny>, &Bound<'_, PyAny>),
    validation: Option<(&Bound<'_, PyAny>, &Bound<'_, PyAny>)>,
    fraction: Option<f64>,
    ts: f64,
) -> PyResult<(IoData<T>, IoData<T>)> {
    let all: IoData<T> = record(py, data.0, data.1, ts)?;
    match (validation, fraction) {
        (Some((u, y)), None) => Ok((all, record(py, u, y, ts)?)),
        (None, Some(f)) => all.split_validation(f).py_err(py),
        _ => Err(input_error(
            py,
            "give either a validation fraction or a validation record, not both",
        )),
    }
}

fn diagnose_t<T: Precision>(
    py: Python<'_>,
    settings: Hammerstein<T>,
    data: (&Bound<'_, PyAny>, &Bound<'_, PyAny>),
    validation: Option<(&Bound<'_, PyAny>, &Bound<'_, PyAny>)>,
    fraction: Option<f64>,
    ts: f64,
    follow: bool,
    max_steps: usize,
) -> PyResult<Run<T>> {
    let (train, val) = records::<T>(py, data, validation, fraction, ts)?;
    if train.n_inputs() != 1 {
        return Err(PyNotImplementedError::new_err(
            "diagnose: several-input records are diagnosed by the command line \
             (`hammerstein diagnose --input u1,u2`); the Python binding diagnoses one input",
        ));
    }
    py.detach(|| run_t(&settings, &train, &val, follow, max_steps))
        .py_err(py)
}

/// Diagnoses the settings of `model` (refitted on the training part) or, without a model, the
/// settings `settings` (JSON of the estimator's arguments), on the record (u, y) of sample time
/// `ts`: the last `fraction` held out for validation, or the record (u_val, y_val). With
/// `follow`, the guided loop of at most `max_steps` steps. The GIL is released meanwhile.
#[pyfunction]
#[pyo3(signature = (model, settings, precision, u, y, ts, fraction, u_val, y_val, follow, max_steps))]
pub fn diagnose(
    py: Python<'_>,
    model: Option<&Model>,
    settings: Option<&str>,
    precision: &str,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
    fraction: Option<f64>,
    u_val: Option<&Bound<'_, PyAny>>,
    y_val: Option<&Bound<'_, PyAny>>,
    follow: bool,
    max_steps: usize,
) -> PyResult<Diagnosed> {
    let validation = match (u_val, y_val) {
        (Some(a), Some(b)) => Some((a, b)),
        (None, None) => None,
        _ => return Err(input_error(py, "a validation record needs both u and y")),
    };
    let data = (u, y);
    let runs = match (model, settings) {
        (Some(m), None) => match &m.inner {
            Inner::Siso64(m) => Runs::F64(diagnose_t(
                py,
                m.settings().clone(),
                data,
                validation,
                fraction,
                ts,
                follow,
                max_steps,
            )?),
            Inner::Siso32(m) => Runs::F32(diagnose_t(
                py,
                m.settings().clone(),
                data,
                validation,
                fraction,
                ts,
                follow,
                max_steps,
            )?),
            Inner::Miso64(_) | Inner::Miso32(_) => {
                return Err(PyNotImplementedError::new_err(
                    "diagnose: several-input models are diagnosed by the command line \
                     (`hammerstein diagnose --input u1,u2`); the Python binding diagnoses one \
                     input",
                ));
            }
        },
        (None, Some(s)) => {
            let args = parse_args(py, s)?;
            match precision {
                "f64" => Runs::F64(diagnose_t(
                    py,
                    args.single::<f64>().py_err(py)?,
                    data,
                    validation,
                    fraction,
                    ts,
                    follow,
                    max_steps,
                )?),
                "f32" => Runs::F32(diagnose_t(
                    py,
                    args.single::<f32>().py_err(py)?,
                    data,
                    validation,
                    fraction,
                    ts,
                    follow,
                    max_steps,
                )?),
                p => return Err(input_error(py, format!("unknown precision '{p}'"))),
            }
        }
        _ => return Err(input_error(py, "give a model or settings, not both")),
    };
    Ok(Diagnosed { runs })
}

#[pymethods]
impl Diagnosed {
    /// Every step's diagnosis, why the sequence stopped, where the validation error rose (JSON).
    fn describe(&self) -> PyResult<String> {
        let v = match &self.runs {
            Runs::F64(r) => r.json(),
            Runs::F32(r) => r.json(),
        };
        serde_json::to_string(&v).map_err(json_error)
    }

    /// The model of every step, the first (the settings as given) first.
    fn models(&self) -> Vec<Model> {
        match &self.runs {
            Runs::F64(r) => r
                .steps
                .iter()
                .map(|s| Model {
                    inner: Inner::Siso64(s.model.clone()),
                    decimation: 1,
                })
                .collect(),
            Runs::F32(r) => r
                .steps
                .iter()
                .map(|s| Model {
                    inner: Inner::Siso32(s.model.clone()),
                    decimation: 1,
                })
                .collect(),
        }
    }

    /// Writes the HTML report (plots as SVG) of the last step into the directory `dir`; returns
    /// the page's path.
    fn write_html(&self, py: Python<'_>, dir: std::path::PathBuf, title: &str) -> PyResult<String> {
        let p = match &self.runs {
            Runs::F64(r) => r.write_html(&dir, title),
            Runs::F32(r) => r.write_html(&dir, title),
        }
        .py_err(py)?;
        Ok(p.display().to_string())
    }
}
