//! The fitted model: simulation and parameters (`model.rs`), its JSON file (`model_file.rs`) and
//! the parameters' covariance (`covariance.rs`).

pub(crate) mod covariance;
pub(crate) mod model;
pub(crate) mod model_file;
