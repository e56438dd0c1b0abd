//! `diagnose`: a model's settings fitted on the training part of a record, its residuals
//! analysed and the effects it is missing named (each checked by a refit); with `follow` the
//! guided loop. One input or several (each input's branch diagnosed on its partial residual).
//! The result keeps the models and diagnoses, for the steps' models and the HTML report.

use hammerstein::diagnosis::{
    Diagnoser, Diagnosis, InputDiagnosis, Metrics, MisoDiagnosis, Suggestion,
};
use hammerstein::fit::{Hammerstein, HammersteinModel};
use hammerstein::miso::{MisoHammerstein, MisoModel};
use hammerstein::{Error, IoData, Real};
use pyo3::prelude::*;
use serde_json::{Value, json};

use crate::arrays::record;
use crate::errors::{IntoPy, input_error, json_error};
use crate::fit::{Precision, parse_args};
use crate::model::{Inner, Model};

/// One diagnosed model: what changed to reach it ("start" for the first), the model `M`, its
/// diagnosis `D`.
pub struct Step<M, D> {
    change: String,
    model: M,
    diagnosis: D,
}

/// A diagnosis (one step) or a followed sequence (several), and why the sequence stopped.
pub struct Run<M, D> {
    steps: Vec<Step<M, D>>,
    stop: Option<Value>,
    validation_rose_at: Vec<usize>,
}

impl<M, D> Run<M, D> {
    /// One diagnosed model, labelled "start".
    fn single(model: M, diagnosis: D) -> Self {
        Run {
            steps: vec![Step {
                change: "start".into(),
                model,
                diagnosis,
            }],
            stop: None,
            validation_rose_at: Vec::new(),
        }
    }

    /// The steps of a guided loop (change, model, diagnosis), why it stopped and where the
    /// validation error rose.
    fn followed(
        steps: impl Iterator<Item = (String, M, D)>,
        stop: &hammerstein::diagnosis::FollowStop,
        validation_rose_at: Vec<usize>,
    ) -> Self {
        Run {
            steps: steps
                .map(|(change, model, diagnosis)| Step {
                    change,
                    model,
                    diagnosis,
                })
                .collect(),
            stop: Some(stop_json(stop)),
            validation_rose_at,
        }
    }
}

/// The run, by number of inputs and precision.
pub enum Runs {
    /// One input, double precision.
    F64(Run<HammersteinModel<f64>, Diagnosis<f64>>),
    /// One input, single precision.
    F32(Run<HammersteinModel<f32>, Diagnosis<f32>>),
    /// Several inputs, double precision, with the training and validation records (the
    /// report plots the whole model's output on them).
    Miso64(Run<MisoModel<f64>, MisoDiagnosis<f64>>, Records<f64>),
    /// Several inputs, single precision, with the records.
    Miso32(Run<MisoModel<f32>, MisoDiagnosis<f32>>, Records<f32>),
}

/// The training and validation records of a diagnosis.
pub type Records<T> = Box<(IoData<T>, IoData<T>)>;

/// The result of `diagnose` (wrapped by `hammerstein.Diagnosis` in Python).
#[pyclass(module = "hammerstein._hammerstein", frozen)]
pub struct Diagnosed {
    runs: Runs,
}

fn metrics_json(m: &Metrics) -> Value {
    serde_json::to_value(m).unwrap_or(Value::Null)
}

/// The diagnosis as JSON: verdict, unexplained tests, typed suggestions, tests, metrics.
/// One suggestion as JSON, naming the input it concerns.
fn suggestion_json(s: &Suggestion, input: &str) -> Value {
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
        "input": input,
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
}

/// The unexplained tests of a diagnosis as JSON (`input`: the input they concern).
fn unexplained_json<T: Real>(d: &Diagnosis<T>, input: &str) -> Vec<Value> {
    d.unexplained
        .iter()
        .map(|u| {
            json!({
                "input": input,
                "test": u.test.to_string(),
                "p_adjusted": u.p_adjusted,
                "model_classes": u.model_classes,
            })
        })
        .collect()
}

/// Candidates left out because their refit does not credit the effect, as JSON.
fn null_parameters_json<T: Real>(d: &Diagnosis<T>, input: &str) -> Vec<Value> {
    d.candidates
        .iter()
        .filter_map(|c| {
            let r = c.refit.as_ref()?.null_parameters.as_ref()?;
            Some(json!({"input": input, "effect": c.effect.to_string(), "reason": r}))
        })
        .collect()
}

/// The residual tests as JSON, each naming the input whose residual it tested.
fn tests_json<T: Real>(d: &Diagnosis<T>, input: &str) -> Vec<Value> {
    d.tests
        .iter()
        .map(|t| {
            let mut v = serde_json::to_value(t).unwrap_or(Value::Null);
            if let Value::Object(o) = &mut v {
                o.insert("input".into(), json!(input));
            }
            v
        })
        .collect()
}

/// The diagnosis as JSON: verdict, unexplained tests, typed suggestions, tests, metrics.
fn diagnosis_json<T: Real>(d: &Diagnosis<T>) -> Value {
    let input = "u";
    json!({
        "adequate": d.adequate,
        "summary": d.summary,
        "unexplained": unexplained_json(d, input),
        "suggestions": d.suggestions.iter().map(|s| suggestion_json(s, input)).collect::<Vec<_>>(),
        "null_parameters": null_parameters_json(d, input),
        "tests": tests_json(d, input),
        "generalisation": serde_json::to_value(&d.generalisation).unwrap_or(Value::Null),
        "train": metrics_json(&d.train.metrics),
        "validation": metrics_json(&d.validation.metrics),
        "screening_window": d.screening_window,
    })
}

/// A several-input diagnosis as JSON, in the single-input diagnosis' shape: the suggestions
/// across inputs (each naming its input), every input's unexplained and residual tests.
fn miso_diagnosis_json<T: Real>(d: &MisoDiagnosis<T>) -> Value {
    let each = |f: &dyn Fn(&InputDiagnosis<T>) -> Vec<Value>| -> Vec<Value> {
        d.inputs.iter().flat_map(f).collect()
    };
    json!({
        "adequate": d.adequate,
        "summary": d.summary,
        "unexplained": each(&|i| unexplained_json(&i.diagnosis, &i.input)),
        "suggestions": d
            .suggestions
            .iter()
            .map(|s| suggestion_json(&s.suggestion, &s.input))
            .collect::<Vec<_>>(),
        "outside_class": d
            .outside_class
            .iter()
            .map(|s| suggestion_json(&s.suggestion, &s.input))
            .collect::<Vec<_>>(),
        "null_parameters": each(&|i| null_parameters_json(&i.diagnosis, &i.input)),
        "tests": each(&|i| tests_json(&i.diagnosis, &i.input)),
        "generalisation": Value::Null,
        "train": metrics_json(&d.train),
        "validation": metrics_json(&d.validation),
        "screening_window": Value::Null,
    })
}

impl<M, D> Run<M, D> {
    /// Every step's diagnosis (by `diagnosis_json`), why the sequence stopped, where the
    /// validation error rose.
    fn json(&self, diagnosis_json: impl Fn(&D) -> Value) -> Value {
        let steps: Vec<Value> = self
            .steps
            .iter()
            .map(|s| json!({"change": s.change, "diagnosis": diagnosis_json(&s.diagnosis)}))
            .collect();
        json!({
            "steps": steps,
            "stop": self.stop,
            "validation_rose_at": self.validation_rose_at,
        })
    }

    /// Every step's model, wrapped by `wrap`.
    fn models(&self, wrap: impl Fn(&M) -> Inner) -> Vec<Model> {
        self.steps
            .iter()
            .map(|s| Model {
                inner: wrap(&s.model),
                decimation: 1,
            })
            .collect()
    }
}

impl<T: Real> Run<HammersteinModel<T>, Diagnosis<T>> {
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

impl<T: Real> Run<MisoModel<T>, MisoDiagnosis<T>> {
    /// The HTML report of the last step of a several-input diagnosis in `dir`, composed as the
    /// command line composes it (`hammerstein diagnose --input u1,u2 --report DIR`): the first
    /// input's branch's report (residual tests, order) with the whole model's output on the
    /// training and validation records `train`, `val` and every input's nonlinearity.
    fn write_html(
        &self,
        dir: &std::path::Path,
        title: &str,
        train: &IoData<T>,
        val: &IoData<T>,
    ) -> Result<std::path::PathBuf, Error> {
        use hammerstein::report::{
            Context, Step as ReportStep, Units, miso_report_input, write_report,
        };
        let last = self
            .steps
            .last()
            .ok_or_else(|| Error::InvalidParameter("no model was diagnosed".into()))?;
        let (model, d) = (&last.model, &last.diagnosis);
        let ts = model.branches()[0].linear().ts;
        let units = Units {
            sample_time: (ts != 1.0).then_some(ts),
            ..Default::default()
        };
        let steps = self
            .steps
            .iter()
            .map(|s| ReportStep {
                label: s.change.clone(),
                validation_mse: s.diagnosis.validation.mse,
                fit_percent: s.diagnosis.validation.fit_percent,
            })
            .collect();
        let ctx = Context {
            title: title.to_string(),
            dataset: title.to_string(),
            units,
            steps,
            ..Default::default()
        };
        let input = miso_report_input(model, d, train, val, ctx)?;
        write_report(dir, &input)
    }
}

/// Why a followed sequence stopped, as JSON (its code and its sentence).
fn stop_json(stop: &hammerstein::diagnosis::FollowStop) -> Value {
    json!({
        "code": serde_json::to_value(stop).unwrap_or(Value::Null),
        "text": stop.to_string(),
    })
}

/// Fits `settings` on `train` and diagnoses the model on `validation`; with `follow`, the
/// guided loop of at most `max_steps` steps.
fn run_single<T: Real>(
    settings: &Hammerstein<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
    follow: bool,
    max_steps: usize,
) -> Result<Run<HammersteinModel<T>, Diagnosis<T>>, Error> {
    let diagnoser = Diagnoser::<T>::new();
    if follow {
        let f = diagnoser.follow(settings, train, validation, max_steps)?;
        let rose = f.validation_rose();
        let steps = f
            .steps
            .into_iter()
            .map(|s| (s.change, s.model, s.diagnosis));
        return Ok(Run::followed(steps, &f.stop, rose));
    }
    let model = settings.fit(train)?;
    let diagnosis = diagnoser.diagnose(&model, train, validation)?;
    Ok(Run::single(model, diagnosis))
}

/// [`run_single`] for several inputs: one branch per input, each diagnosed on its partial
/// residual.
fn run_several<T: Real>(
    settings: &MisoHammerstein<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
    follow: bool,
    max_steps: usize,
) -> Result<Run<MisoModel<T>, MisoDiagnosis<T>>, Error> {
    let diagnoser = Diagnoser::<T>::new();
    if follow {
        let f = diagnoser.follow_miso(settings, train, validation, max_steps)?;
        let rose = f.validation_rose();
        let steps = f
            .steps
            .into_iter()
            .map(|s| (s.change, s.model, s.diagnosis));
        return Ok(Run::followed(steps, &f.stop, rose));
    }
    let model = settings.fit(train)?;
    let diagnosis = diagnoser.diagnose_miso(&model, train, validation)?;
    Ok(Run::single(model, diagnosis))
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

/// The settings a diagnosis fits: one input's or several inputs'.
enum Settings<T: Real> {
    Single(Hammerstein<T>),
    Several(MisoHammerstein<T>),
}

/// What a diagnosis is asked: the records, the validation, the loop.
struct Ask<'a, 'py> {
    data: (&'a Bound<'py, PyAny>, &'a Bound<'py, PyAny>),
    validation: Option<(&'a Bound<'py, PyAny>, &'a Bound<'py, PyAny>)>,
    fraction: Option<f64>,
    ts: f64,
    follow: bool,
    max_steps: usize,
}

fn diagnose_t<T: Precision>(
    py: Python<'_>,
    settings: Settings<T>,
    ask: &Ask<'_, '_>,
    single: impl FnOnce(Run<HammersteinModel<T>, Diagnosis<T>>) -> Runs,
    several: impl FnOnce(Run<MisoModel<T>, MisoDiagnosis<T>>, Records<T>) -> Runs,
) -> PyResult<Runs> {
    let (train, val) = records::<T>(py, ask.data, ask.validation, ask.fraction, ask.ts)?;
    let (follow, steps) = (ask.follow, ask.max_steps);
    match settings {
        Settings::Single(s) => {
            if train.n_inputs() != 1 {
                return Err(input_error(
                    py,
                    format!(
                        "u has {} columns: the model has one input",
                        train.n_inputs()
                    ),
                ));
            }
            let run = py
                .detach(|| run_single(&s, &train, &val, follow, steps))
                .py_err(py)?;
            Ok(single(run))
        }
        Settings::Several(s) => {
            if train.n_inputs() != s.branches().len() {
                return Err(input_error(
                    py,
                    format!(
                        "u has {} columns: the model has {} inputs",
                        train.n_inputs(),
                        s.branches().len()
                    ),
                ));
            }
            let run = py
                .detach(|| run_several(&s, &train, &val, follow, steps))
                .py_err(py)?;
            Ok(several(run, Box::new((train, val))))
        }
    }
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
    let ask = Ask {
        data: (u, y),
        validation,
        fraction,
        ts,
        follow,
        max_steps,
    };
    let runs = match (model, settings) {
        (Some(m), None) => match &m.inner {
            Inner::Siso64(m) => diagnose_t(
                py,
                Settings::Single(m.settings().clone()),
                &ask,
                Runs::F64,
                Runs::Miso64,
            )?,
            Inner::Siso32(m) => diagnose_t(
                py,
                Settings::Single(m.settings().clone()),
                &ask,
                Runs::F32,
                Runs::Miso32,
            )?,
            Inner::Miso64(m) => diagnose_t(
                py,
                Settings::Several(m.settings().clone()),
                &ask,
                Runs::F64,
                Runs::Miso64,
            )?,
            Inner::Miso32(m) => diagnose_t(
                py,
                Settings::Several(m.settings().clone()),
                &ask,
                Runs::F32,
                Runs::Miso32,
            )?,
        },
        (None, Some(s)) => {
            let args = parse_args(py, s)?;
            let several = args.effects.len() > 1;
            match precision {
                "f64" => {
                    let s = if several {
                        Settings::Several(args.several::<f64>().py_err(py)?)
                    } else {
                        Settings::Single(args.single::<f64>().py_err(py)?)
                    };
                    diagnose_t(py, s, &ask, Runs::F64, Runs::Miso64)?
                }
                "f32" => {
                    let s = if several {
                        Settings::Several(args.several::<f32>().py_err(py)?)
                    } else {
                        Settings::Single(args.single::<f32>().py_err(py)?)
                    };
                    diagnose_t(py, s, &ask, Runs::F32, Runs::Miso32)?
                }
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
            Runs::F64(r) => r.json(diagnosis_json),
            Runs::F32(r) => r.json(diagnosis_json),
            Runs::Miso64(r, _) => r.json(miso_diagnosis_json),
            Runs::Miso32(r, _) => r.json(miso_diagnosis_json),
        };
        serde_json::to_string(&v).map_err(json_error)
    }

    /// The model of every step, the first (the settings as given) first.
    fn models(&self) -> Vec<Model> {
        match &self.runs {
            Runs::F64(r) => r.models(|m| Inner::Siso64(m.clone())),
            Runs::F32(r) => r.models(|m| Inner::Siso32(m.clone())),
            Runs::Miso64(r, _) => r.models(|m| Inner::Miso64(m.clone())),
            Runs::Miso32(r, _) => r.models(|m| Inner::Miso32(m.clone())),
        }
    }

    /// Writes the HTML report (plots as SVG) of the last step into the directory `dir`; returns
    /// the page's path.
    fn write_html(&self, py: Python<'_>, dir: std::path::PathBuf, title: &str) -> PyResult<String> {
        let p = match &self.runs {
            Runs::F64(r) => r.write_html(&dir, title),
            Runs::F32(r) => r.write_html(&dir, title),
            Runs::Miso64(r, d) => r.write_html(&dir, title, &d.0, &d.1),
            Runs::Miso32(r, d) => r.write_html(&dir, title, &d.0, &d.1),
        }
        .py_err(py)?;
        Ok(p.display().to_string())
    }
}
