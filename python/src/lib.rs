//! The compiled half of the Python package `hammerstein` (`hammerstein._hammerstein`): fit,
//! load, diagnose and subspace identification on numpy arrays, through the library's public
//! API. The Python half (`hammerstein/__init__.py` and its modules) checks and converts the
//! arguments, names them as the command line does and wraps the results; see docs/python.md.
//!
//! Files: `errors.rs` (the crate's errors as Python exceptions), `arrays.rs` (numpy ↔ faer),
//! `settings.rs` (the estimator's arguments → `Hammerstein`), `model.rs` (the fitted model),
//! `fit.rs` (fit, load), `diagnosis.rs` (diagnose, follow, HTML report), `subspace.rs`.
//! The structure tools (design, BLA, structure verdict) and the feedback models get one file
//! each here, registered in `_hammerstein` below, with their Python wrappers in
//! `hammerstein/`.

// the compiled functions take the Python functions' keyword arguments one by one
#![allow(clippy::too_many_arguments)]

mod arrays;
mod diagnosis;
mod errors;
mod fit;
mod model;
mod settings;
mod subspace;

use pyo3::prelude::*;

/// The compiled module.
#[pymodule]
fn _hammerstein(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::Model>()?;
    m.add_class::<diagnosis::Diagnosed>()?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(fit::load, m)?)?;
    m.add_function(wrap_pyfunction!(fit::loads, m)?)?;
    m.add_function(wrap_pyfunction!(diagnosis::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(subspace::subspace, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
