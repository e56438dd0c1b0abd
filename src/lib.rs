#![allow(
    clippy::needless_range_loop,
    clippy::too_many_arguments,
    clippy::type_complexity
)]
#![warn(missing_docs)]
#![doc = include_str!("../README.md")]
//!
//! ## Cargo features
//!
//! All on by default. With `default-features = false` the crate is the numerical library alone
//! (identification, regressors, diagnosis, state-space models; no clap, indicatif, plotters or csv).
//!
//! | feature | what it adds |
//! |---|---|
//! | `csv` | reading records from CSV: `data::CsvTable`, `IoData::from_csv` |
//! | `report` | `report`: SVG plots and a self-contained HTML report (plotters) |
//! | `study` | `study`: the paper's Example 1 Monte Carlo study with the Cramér–Rao bound |
//! | `cli` | the `hammerstein` binary (clap, indicatif); implies `csv`, `report`, `study` |
//! | `lapack` | the LAPACK backend (nalgebra-lapack; links OpenBLAS), off by default |
//!
//! ## The faer version
//!
//! Matrices in the public API ([`IoData::new`], [`StateSpace`], regressor matrices, the
//! [`LinAlg`] backend trait) are [`faer`] 0.24 types. The crate re-exports that faer as
//! [`hammerstein::faer`](crate::faer): use it (`use hammerstein::faer::Mat;`) rather than adding
//! your own `faer` dependency, whose version could differ and whose `Mat` would then be a
//! different type. Under the `lapack` feature `hammerstein::nalgebra` is re-exported likewise.

pub use faer;
#[cfg(feature = "lapack")]
pub use nalgebra;

pub mod atomic;
pub mod data;
pub mod decimation;
pub mod diagnosis;
pub mod diebold_mariano;
pub mod error;
pub mod feedback;
pub mod fit;
pub mod magnitude;
pub mod miso;
pub mod real;
pub mod regressors;
#[cfg(feature = "report")]
pub mod report;
pub mod solvers;
pub mod statespace;
pub mod structure;
#[cfg(feature = "study")]
pub mod study;
pub mod subspace;
pub mod units;

#[cfg(feature = "csv")]
pub use data::CsvTable;
pub use data::{IoData, IoView};
pub use error::{Error, Result};
pub use fit::{
    FitOptions, FitReport, Hammerstein, HammersteinModel, Init, Normalization, Termination,
};
pub use miso::{MisoHammerstein, MisoModel};
pub use real::Real;
pub use solvers::{BackendKind, Faer, LinAlg, Svd};
pub use statespace::{StateSpace, TransferFunction};
pub use subspace::{MethodKind, Moesp, Order, SubspaceMethod, SubspaceOptions};
