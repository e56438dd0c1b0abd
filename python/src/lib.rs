//! The compiled half of the Python package `hammerstein` (`hammerstein._hammerstein`): fit,
//! load, diagnose and subspace identification on numpy arrays, through the library's public
//! API. The Python half (`hammerstein/__init__.py` and its modules) checks and converts the
//! arguments, names them as the command line does and wraps the results; see docs/python.md.
//!
//! Files: `errors.rs` (the crate's errors as Python exceptions), `arrays.rs` (numpy ↔ faer),
//! `settings.rs` (the estimator's arguments → `Hammerstein`), `model.rs` (the fitted model),
//! `fit.rs` (fit, load), `diagnosis.rs` (diagnose, follow, HTML report), `subspace.rs`,
//! `structure.rs` (multisine design, BLA, structure verdict), `feedback.rs` (the feedback
//! model). Their Python wrappers are the modules of `hammerstein/`.

// the compiled functions take the Python functions' keyword arguments one by one
#![allow(clippy::too_many_arguments)]

mod arrays;
mod diagnosis;
mod errors;
mod feedback;
mod fit;
mod model;
mod settings;
mod structure;
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
    m.add_class::<feedback::Feedback>()?;
    m.add_function(wrap_pyfunction!(feedback::fit_feedback, m)?)?;
    m.add_function(wrap_pyfunction!(feedback::loads_feedback, m)?)?;
    m.add_function(wrap_pyfunction!(structure::design, m)?)?;
    m.add_function(wrap_pyfunction!(structure::bla_json, m)?)?;
    m.add_function(wrap_pyfunction!(structure::structure_json, m)?)?;
    m.add_function(wrap_pyfunction!(structure::structure_by_rms_json, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
