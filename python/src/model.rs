//! `hammerstein._hammerstein.Model`: a fitted model (one input or several, f32 or f64) and what
//! it answers — simulation, comparison, its description as JSON, its model file.

use hammerstein::diagnosis::{compare, compare_miso};
use hammerstein::fit::{HammersteinModel, divergence};
use hammerstein::miso::MisoModel;
use hammerstein::statespace::to_rows;
use hammerstein::{Error, IoData, Real};
use numpy::Element;
use pyo3::prelude::*;
use serde_json::{Value, json};

use crate::arrays::{columns, mat, record, vector};
use crate::errors::{IntoPy, json_error};

/// The model, by number of inputs and precision.
#[derive(Clone)]
pub enum Inner {
    /// One input, double precision.
    Siso64(HammersteinModel<f64>),
    /// One input, single precision.
    Siso32(HammersteinModel<f32>),
    /// Several inputs, double precision.
    Miso64(MisoModel<f64>),
    /// Several inputs, single precision.
    Miso32(MisoModel<f32>),
}

/// Runs `$body` on the model whatever its kind: `$s` binds a single-input model, `$m` a
/// several-input one.
macro_rules! each {
    ($inner:expr, $s:ident => $sbody:expr, $m:ident => $mbody:expr) => {
        match $inner {
            Inner::Siso64($s) => $sbody,
            Inner::Siso32($s) => $sbody,
            Inner::Miso64($m) => $mbody,
            Inner::Miso32($m) => $mbody,
        }
    };
}

/// A fitted Hammerstein model (wrapped by `hammerstein.Model` in Python).
#[pyclass(module = "hammerstein._hammerstein", frozen)]
pub struct Model {
    /// The model.
    pub inner: Inner,
    /// The decimation factor its file records (1: none): the records it was fitted on kept
    /// every K-th sample.
    pub decimation: usize,
}

/// What `Model.describe()` returns for a single-input model: everything but the data.
pub fn siso_json<T: Real>(m: &HammersteinModel<T>) -> Result<Value, Error> {
    let lin = m.linear();
    let poles = lin.poles()?;
    let tf = m.transfer_function()?;
    let report = m.report();
    let output_map = m.output_map().map(|g| {
        json!({
            "name": g.name(),
            "parameters": m
                .output_map_parameters_with_errors()
                .into_iter()
                .map(|(k, v, se)| json!([k, v, se]))
                .collect::<Vec<_>>(),
        })
    });
    Ok(json!({
        "inputs": 1,
        "precision": T::NAME,
        "nonlinearity": m.nonlinearity().name(),
        "effects": m.nonlinearity().effects(),
        "parameters": m
            .parameters_with_errors()
            .into_iter()
            .map(|(k, v, se)| json!([k, v, se]))
            .collect::<Vec<_>>(),
        "output_nonlinearity": output_map,
        "order": lin.order(),
        "delay": m.delay(),
        "feedthrough": m.has_feedthrough(),
        "output_offset": m.output_offset(),
        "sample_time": lin.ts,
        "A": to_rows(lin.a.as_ref()),
        "B": to_rows(lin.b.as_ref()),
        "C": to_rows(lin.c.as_ref()),
        "D": to_rows(lin.d.as_ref()),
        "poles": poles.iter().map(|(re, im)| json!([re, im])).collect::<Vec<_>>(),
        "spectral_radius": lin.spectral_radius()?,
        "numerator": tf.numerator,
        "denominator": tf.denominator,
        "settings": serde_json::to_value(m.settings().options()).unwrap_or(Value::Null),
        "report": {
            "train_mse": report.train_mse,
            "order": report.order,
            "termination": report.termination.name(),
            "converged": report.converged,
            "iterations": report.iterations.len(),
            "best_iteration": report.best_iteration,
            "refined": report.refinement.as_ref().is_some_and(|r| r.accepted),
            "horizon": m.settings().options().horizon,
            "horizon_raised_from": report.horizon_raised_from,
            "screening_window": report.screening_window,
            "singular_values": report.singular_values,
            "stabilised_from": report.stabilised.map(|b| b.spectral_radius),
            "order_selection": report
                .order_selection
                .iter()
                .map(|c| json!({
                    "order": c.order,
                    "feedthrough": c.feedthrough,
                    "criterion": c.criterion,
                    "train_mse": c.train_mse,
                }))
                .collect::<Vec<_>>(),
        },
    }))
}

/// What `Model.describe()` returns for a several-input model: each branch as a single-input
/// model, and the sum's order, offset and backfitting report.
pub fn miso_json<T: Real>(m: &MisoModel<T>) -> Result<Value, Error> {
    let branches = m
        .branches()
        .iter()
        .map(siso_json)
        .collect::<Result<Vec<_>, _>>()?;
    let lin = m.linear()?;
    Ok(json!({
        "inputs": m.input_names().len(),
        "input_names": m.input_names(),
        "precision": T::NAME,
        "branches": branches,
        "order": m.order(),
        "output_offset": m.output_offset(),
        "sample_time": lin.ts,
        "A": to_rows(lin.a.as_ref()),
        "B": to_rows(lin.b.as_ref()),
        "C": to_rows(lin.c.as_ref()),
        "D": to_rows(lin.d.as_ref()),
        "poles": lin.poles()?.iter().map(|(re, im)| json!([re, im])).collect::<Vec<_>>(),
        "parameters": m
            .parameters_with_errors()
            .into_iter()
            .map(|(input, k, v, se)| json!([format!("{input}.{k}"), v, se]))
            .collect::<Vec<_>>(),
        "report": serde_json::to_value(m.report()).unwrap_or(Value::Null),
    }))
}

/// The model's output for the inputs `u` (N × m) from a zero state; a diverging simulation is
/// `Error::Diverged`.
fn simulate_t<'py, T: Real + Element>(
    py: Python<'py>,
    inner: Simulate<'_, T>,
    u: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let y = match inner {
        Simulate::Single(m) => {
            let u = columns::<T>(u)?.remove(0);
            py.detach(|| m.simulate_finite(&u)).py_err(py)?
        }
        Simulate::Several(m) => {
            let u = mat::<T>(u)?;
            let y = py.detach(|| m.simulate(u.as_ref())).py_err(py)?;
            if let Some((index, value)) = divergence(&y) {
                return Err(crate::errors::to_py(py, Error::Diverged { index, value }));
            }
            y
        }
    };
    Ok(vector(py, y))
}

enum Simulate<'a, T: Real> {
    Single(&'a HammersteinModel<T>),
    Several(&'a MisoModel<T>),
}

/// The comparison on a record: metrics as JSON and ŷ.
fn compare_t<'py, T: Real + Element>(
    py: Python<'py>,
    inner: Simulate<'_, T>,
    u: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    ts: f64,
) -> PyResult<(String, Bound<'py, PyAny>)> {
    let data: IoData<T> = record(py, u, y, ts)?;
    let (metrics, y_hat) = match inner {
        Simulate::Single(m) => {
            let c = py.detach(|| compare(m, &data)).py_err(py)?;
            (c.metrics, c.y_hat)
        }
        Simulate::Several(m) => {
            let c = py.detach(|| compare_miso(m, &data)).py_err(py)?;
            (c.metrics, c.y_hat)
        }
    };
    let j = serde_json::to_string(&metrics).map_err(json_error)?;
    Ok((j, vector(py, y_hat)))
}

#[pymethods]
impl Model {
    /// The model as JSON (parameters, linear block, poles, transfer function, fit report).
    fn describe(&self, py: Python<'_>) -> PyResult<String> {
        let v = each!(&self.inner, m => siso_json(m), m => miso_json(m)).py_err(py)?;
        serde_json::to_string(&v).map_err(json_error)
    }

    /// "f32" or "f64".
    #[getter]
    fn precision(&self) -> &'static str {
        each!(&self.inner, _m => Self::name_of(&self.inner), _m => Self::name_of(&self.inner))
    }

    /// Number of inputs.
    #[getter]
    fn n_inputs(&self) -> usize {
        each!(&self.inner, _m => 1, m => m.input_names().len())
    }

    /// Simulated output for inputs `u` (N × m array of the model's precision), from a zero
    /// state.
    fn simulate<'py>(&self, py: Python<'py>, u: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        match &self.inner {
            Inner::Siso64(m) => simulate_t(py, Simulate::Single(m), u),
            Inner::Siso32(m) => simulate_t(py, Simulate::Single(m), u),
            Inner::Miso64(m) => simulate_t(py, Simulate::Several(m), u),
            Inner::Miso32(m) => simulate_t(py, Simulate::Several(m), u),
        }
    }

    /// Fit %, MSE, NRMSE (JSON) and ŷ on the record (u, y) of sample time `ts`, the initial
    /// state estimated.
    fn compare<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        y: &Bound<'py, PyAny>,
        ts: f64,
    ) -> PyResult<(String, Bound<'py, PyAny>)> {
        match &self.inner {
            Inner::Siso64(m) => compare_t(py, Simulate::Single(m), u, y, ts),
            Inner::Siso32(m) => compare_t(py, Simulate::Single(m), u, y, ts),
            Inner::Miso64(m) => compare_t(py, Simulate::Several(m), u, y, ts),
            Inner::Miso32(m) => compare_t(py, Simulate::Several(m), u, y, ts),
        }
    }

    /// The decimation factor the model file records (1: none).
    #[getter]
    fn decimation(&self) -> usize {
        self.decimation
    }

    /// The model file's JSON (what `hammerstein fit --save` writes).
    fn to_json(&self) -> PyResult<String> {
        let k = Some(self.decimation).filter(|&k| k > 1);
        each!(&self.inner,
            m => { let mut f = m.to_file(); f.decimation = k; serde_json::to_string_pretty(&f) },
            m => { let mut f = m.to_file(); f.decimation = k; serde_json::to_string_pretty(&f) })
        .map_err(json_error)
    }

    /// Writes the model file to `path` (atomically; the same file as `hammerstein fit --save`).
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        let k = Some(self.decimation).filter(|&k| k > 1);
        each!(&self.inner,
            m => { let mut f = m.to_file(); f.decimation = k; f.write(&path) },
            m => { let mut f = m.to_file(); f.decimation = k; f.write(&path) })
        .py_err(py)
    }
}

impl Model {
    fn name_of(inner: &Inner) -> &'static str {
        match inner {
            Inner::Siso64(_) | Inner::Miso64(_) => "f64",
            Inner::Siso32(_) | Inner::Miso32(_) => "f32",
        }
    }
}
