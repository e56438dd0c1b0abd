//! `fit` and `load`: a model from a record and settings, or from a model file.

use hammerstein::fit::{HammersteinModel, ModelFile};
use hammerstein::miso::{MisoModel, MisoModelFile};
use hammerstein::regressors::from_spec;
use hammerstein::{Error, IoData, Real};
use numpy::Element;
use pyo3::prelude::*;

use crate::arrays::record;
use crate::errors::{IntoPy, input_error};
use crate::model::{Inner, Model};
use crate::settings::FitArgs;

/// The scalar types a model is fitted in, and how each is wrapped.
pub trait Precision: Real + Element {
    /// A single-input model wrapped.
    fn single(m: HammersteinModel<Self>) -> Inner;
    /// A several-input model wrapped.
    fn several(m: MisoModel<Self>) -> Inner;
}

impl Precision for f64 {
    fn single(m: HammersteinModel<f64>) -> Inner {
        Inner::Siso64(m)
    }
    fn several(m: MisoModel<f64>) -> Inner {
        Inner::Miso64(m)
    }
}

impl Precision for f32 {
    fn single(m: HammersteinModel<f32>) -> Inner {
        Inner::Siso32(m)
    }
    fn several(m: MisoModel<f32>) -> Inner {
        Inner::Miso32(m)
    }
}

/// The settings passed down as JSON by `hammerstein.Hammerstein`.
pub fn parse_args(py: Python<'_>, settings: &str) -> PyResult<FitArgs> {
    serde_json::from_str(settings).map_err(|e| input_error(py, format!("settings: {e}")))
}

fn fit_t<T: Precision>(
    py: Python<'_>,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
    args: &FitArgs,
) -> PyResult<Inner> {
    let data: IoData<T> = record(py, u, y, ts)?;
    if data.n_inputs() != args.effects.len() {
        return Err(input_error(
            py,
            format!(
                "{} effect lists for {} inputs",
                args.effects.len(),
                data.n_inputs()
            ),
        ));
    }
    if data.n_inputs() == 1 {
        let settings = args.single::<T>().py_err(py)?;
        let m = py.detach(|| settings.fit(&data)).py_err(py)?;
        Ok(T::single(m))
    } else {
        let settings = args.several::<T>().py_err(py)?;
        let m = py.detach(|| settings.fit(&data)).py_err(py)?;
        Ok(T::several(m))
    }
}

/// Fits a model to inputs `u` (N × m) and output `y` (N × 1) of sample time `ts` in
/// `precision` ("f32" or "f64") with `settings` (JSON of the estimator's arguments). The GIL is
/// released while the fit runs.
#[pyfunction]
pub fn fit(
    py: Python<'_>,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
    precision: &str,
    settings: &str,
) -> PyResult<Model> {
    let args = parse_args(py, settings)?;
    let inner = match precision {
        "f64" => fit_t::<f64>(py, u, y, ts, &args)?,
        "f32" => fit_t::<f32>(py, u, y, ts, &args)?,
        p => {
            return Err(input_error(
                py,
                format!("unknown precision '{p}' (f32 or f64)"),
            ));
        }
    };
    Ok(Model {
        inner,
        decimation: 1,
    })
}

/// A model from the text of a model file (`label` names it in errors), one input or several,
/// as `hammerstein compare` reads it.
pub fn from_text(text: &str, label: &str) -> Result<Model, Error> {
    let at = |e: Error| match e {
        Error::ModelFormat(m) => Error::ModelFormat(format!("{label}: {m}")),
        e => e,
    };
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| at(Error::ModelFormat(format!("not valid JSON: {e}"))))?;
    if MisoModelFile::is_miso_value(&value) {
        let file = MisoModelFile::from_value(value).map_err(at)?;
        return Ok(Model {
            inner: Inner::Miso64(MisoModel::from_file(&file, from_spec::<f64>)?),
            decimation: file.decimation.unwrap_or(1),
        });
    }
    let file = ModelFile::from_value(value).map_err(at)?;
    Ok(Model {
        inner: Inner::Siso64(HammersteinModel::from_file(&file, from_spec::<f64>)?),
        decimation: file.decimation.unwrap_or(1),
    })
}

/// Reads the model file at `path` (what `hammerstein fit --save` and `Model.save` write).
#[pyfunction]
pub fn load(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Model> {
    let text = std::fs::read_to_string(&path)
        .map_err(|e| Error::io(path.display(), e))
        .py_err(py)?;
    from_text(&text, &path.display().to_string()).py_err(py)
}

/// A model from the model file's JSON text.
#[pyfunction]
pub fn loads(py: Python<'_>, text: &str) -> PyResult<Model> {
    from_text(text, "model JSON").py_err(py)
}
