#![allow(
    clippy::needless_range_loop,
    clippy::too_many_arguments,
    clippy::type_complexity
)]
//! # hammerstein
//!
//! Identification of Hammerstein systems — a static, often discontinuous actuator nonlinearity
//! followed by a linear state-space block — from measured input/output data, and diagnosis of
//! what the identified model still gets wrong.

pub mod atomic;
pub mod data;
pub mod diagnosis;
pub mod error;
pub mod hammerstein;
pub mod real;
pub mod regressors;
pub mod report;
pub mod solvers;
pub mod statespace;
pub mod study;
pub mod subspace;

pub use data::{CsvTable, IoData, IoView};
pub use error::{Error, Result};
pub use hammerstein::{FitReport, Hammerstein, HammersteinModel, Init, Normalization, Termination};
pub use real::Real;
pub use solvers::{BackendKind, Faer, LinAlg, Svd};
pub use statespace::{StateSpace, TransferFunction};
pub use subspace::{MethodKind, Moesp, Order, SubspaceMethod, SubspaceOptions};
