//! The fitted model: simulation and parameters (`model.rs`), its JSON file (`model_file.rs`),
//! the parameters' covariance (`covariance.rs`) and the initial state through an output map
//! (`initial_map.rs`).

pub(crate) mod covariance;
pub(crate) mod initial_map;
pub(crate) mod model;
pub(crate) mod model_file;
