//! Linear-algebra backends (faer by default, LAPACK behind the `lapack` feature) and the
//! numerical kernels the iterative Hammerstein loop shares.

mod backend;
pub(crate) mod channel_filter;
pub(crate) mod columns;
mod faer_backend;
pub(crate) mod householder;
#[cfg(feature = "lapack")]
mod lapack_backend;
pub(crate) mod recursion;
pub(crate) mod schur_cohn;
pub mod tsqr;

pub use backend::{LinAlg, Svd};
pub use faer_backend::Faer;
#[cfg(feature = "lapack")]
pub use lapack_backend::Lapack;

/// Which backend to use, as chosen on the command line or in settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// Pure-Rust faer (default).
    #[default]
    Faer,
    /// LAPACK through nalgebra-lapack (needs the `lapack` cargo feature).
    Lapack,
}

impl std::str::FromStr for BackendKind {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "faer" => Ok(Self::Faer),
            "lapack" => Ok(Self::Lapack),
            _ => Err(crate::Error::UnknownName {
                kind: crate::error::NameKind::Backend,
                name: s.to_string(),
                expected: "faer|lapack",
            }),
        }
    }
}

/// A boxed backend of the requested kind for scalar `T`, or an error when it is not compiled in.
pub fn backend<T: crate::Real>(kind: BackendKind) -> crate::Result<Box<dyn LinAlg<T>>> {
    match kind {
        BackendKind::Faer => Ok(Box::new(Faer::default())),
        #[cfg(feature = "lapack")]
        BackendKind::Lapack => lapack_backend::boxed::<T>(),
        #[cfg(not(feature = "lapack"))]
        BackendKind::Lapack => Err(crate::Error::BackendUnavailable {
            name: "LAPACK",
            feature: "lapack",
        }),
    }
}
