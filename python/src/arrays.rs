//! numpy arrays ↔ the library's matrices and vectors. The Python layer (`hammerstein/_data.py`)
//! has already checked shapes, dtypes and lengths and made the arrays 2-D (samples × channels)
//! of the chosen precision; the copies here are the only ones made.

use hammerstein::faer::Mat;
use hammerstein::{IoData, Real};
use numpy::{Element, PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::errors::IntoPy;

/// A samples × channels array as a faer matrix (one copy).
pub fn mat<T: Real + Element>(a: &Bound<'_, PyAny>) -> PyResult<Mat<T>> {
    let arr: PyReadonlyArray2<'_, T> = a.extract()?;
    let v = arr.as_array();
    Ok(Mat::from_fn(v.nrows(), v.ncols(), |i, j| v[[i, j]]))
}

/// The channels of a samples × channels array, one vector each.
pub fn columns<T: Real + Element>(a: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<T>>> {
    let arr: PyReadonlyArray2<'_, T> = a.extract()?;
    let v = arr.as_array();
    Ok((0..v.ncols()).map(|j| v.column(j).to_vec()).collect())
}

/// A record from inputs `u` (N × m), outputs `y` (N × l) and the sample time `ts`.
pub fn record<T: Real + Element>(
    py: Python<'_>,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
) -> PyResult<IoData<T>> {
    let (u, y) = (mat::<T>(u)?, mat::<T>(y)?);
    IoData::new(u, y)
        .and_then(|d| d.with_sample_time(ts))
        .py_err(py)
}

/// A vector as a 1-D numpy array (moved, not copied).
pub fn vector<'py, T: Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyAny> {
    PyArray1::from_vec(py, v).into_any()
}
