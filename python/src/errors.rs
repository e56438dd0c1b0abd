//! The crate's errors as Python exceptions: bad input is `hammerstein.InputError` (a
//! `ValueError` and a `HammersteinError`), a failed fit or identification is
//! `hammerstein.HammersteinError`, a file that cannot be read or written is an `OSError`. The
//! message is the crate's. The classes live in `hammerstein/_errors.py`.

use hammerstein::Error;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError};
use pyo3::prelude::*;

/// True when `e` says the caller's input or settings are wrong (not that the fit failed).
fn is_input(e: &Error) -> bool {
    matches!(
        e,
        Error::NonFinite { .. }
            | Error::LengthMismatch { .. }
            | Error::TooFewSamples { .. }
            | Error::ConstantInput { .. }
            | Error::ConstantOutput { .. }
            | Error::ConstantIn { .. }
            | Error::UnknownColumn { .. }
            | Error::ColumnOutOfRange { .. }
            | Error::OrderTooLarge { .. }
            | Error::InvalidParameter(_)
            | Error::UnknownName { .. }
            | Error::NoExperiment
            | Error::NoChannels { .. }
            | Error::NotUdn { .. }
            | Error::ZeroOrder
            | Error::SampleRange { .. }
            | Error::ValidationFraction(_)
            | Error::SampleTime(_)
            | Error::DuplicateRegressor { .. }
            | Error::BackendUnavailable { .. }
            | Error::UnknownCandidate { .. }
            | Error::NotApplicable { .. }
            | Error::Dimension(_)
            | Error::ModelFormat(_)
            | Error::HorizonTooSmall { .. }
            | Error::HorizonTooLarge { .. }
            | Error::RepeatedChannel { .. }
            | Error::UnsupportedVersion { .. }
            | Error::Csv { .. }
    )
}

/// The Python exception for the crate's error `e`.
pub fn to_py(py: Python<'_>, e: Error) -> PyErr {
    let msg = e.to_string();
    if let Some(io) = e.io_error() {
        return match io.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
            _ => PyOSError::new_err(msg),
        };
    }
    let class = if is_input(&e) {
        "InputError"
    } else {
        "HammersteinError"
    };
    match py
        .import("hammerstein._errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call1((msg.clone(),)))
    {
        Ok(value) => PyErr::from_value(value),
        Err(_) => PyRuntimeError::new_err(msg),
    }
}

/// `Result<T, Error>` → `PyResult<T>`.
pub trait IntoPy<T> {
    /// The error, if any, as a Python exception.
    fn py_err(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPy<T> for Result<T, Error> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}

/// A bad argument the binding itself finds: `InputError` with `msg`.
pub fn input_error(py: Python<'_>, msg: impl Into<String>) -> PyErr {
    to_py(py, Error::InvalidParameter(msg.into()))
}

/// A JSON (de)serialisation failure inside the binding (a bug, not the caller's input).
pub fn json_error(e: serde_json::Error) -> PyErr {
    PyRuntimeError::new_err(format!("internal JSON error: {e}"))
}
