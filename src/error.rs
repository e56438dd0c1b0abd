//! The crate's error type: every failure on user data is one of these variants.

use std::sync::Arc;

/// Errors returned by identification, data handling and model I/O.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A value is NaN or infinite.
    #[error("non-finite value (NaN or infinity) in {what} at sample {index}")]
    NonFinite {
        /// Which series or channel.
        what: String,
        /// Sample index of the first bad value.
        index: usize,
    },
    /// Input and output records have different lengths.
    #[error("length mismatch: {what}")]
    LengthMismatch {
        /// What differs, with both lengths.
        what: String,
    },
    /// The record is too short for what was asked.
    #[error("not enough samples: {needed} needed ({reason}), got {got}")]
    TooFewSamples {
        /// Samples required.
        needed: usize,
        /// Samples available.
        got: usize,
        /// What needed them.
        reason: String,
    },
    /// An input channel is constant, so nothing can be identified from it.
    #[error("input '{name}' is constant: it excites nothing and carries no information")]
    ConstantInput {
        /// The input channel's name.
        name: String,
    },
    /// An output channel is constant, so there is no response to identify.
    #[error("output '{name}' is constant: there is no response to identify")]
    ConstantOutput {
        /// The output channel's name.
        name: String,
    },
    /// A requested CSV column does not exist.
    #[error("unknown column '{name}' (available: {available})")]
    UnknownColumn {
        /// The requested column.
        name: String,
        /// The columns the file has, comma-separated.
        available: String,
    },
    /// A CSV file could not be parsed.
    #[error("malformed CSV {path}: {msg}")]
    Csv {
        /// The file.
        path: String,
        /// What is wrong, with the line where known.
        msg: String,
    },
    /// A file could not be read or written; the [`std::io::Error`] is kept as the cause
    /// ([`Error::io_error`], or [`source`](std::error::Error::source) then its source).
    #[error("cannot access {path}: {source}")]
    Io {
        /// The file or directory.
        path: String,
        /// The I/O error.
        #[source]
        source: IoCause,
    },
    /// The requested model order exceeds what the data and horizon support.
    #[error(
        "model order {requested} is larger than possible (at most {max} with this horizon and data)"
    )]
    OrderTooLarge {
        /// The order asked for.
        requested: usize,
        /// The largest order possible.
        max: usize,
    },
    /// A setting or argument is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// Matrix shapes do not agree.
    #[error("dimension mismatch: {0}")]
    Dimension(String),
    /// A factorisation failed (rank deficiency, non-convergence).
    #[error("linear algebra failure: {0}")]
    LinAlg(String),
    /// An iterative estimate failed to produce a usable model.
    #[error("identification failed: {0}")]
    Identification(String),
    /// A saved model could not be read.
    #[error("model file: {0}")]
    ModelFormat(String),
}

impl Error {
    /// An [`Error::Io`] for `path` caused by `e`.
    pub fn io(path: impl std::fmt::Display, e: std::io::Error) -> Self {
        Error::Io {
            path: path.to_string(),
            source: IoCause::from(e),
        }
    }

    /// The underlying I/O error of an [`Error::Io`] (its kind, its OS code).
    pub fn io_error(&self) -> Option<&std::io::Error> {
        match self {
            Error::Io { source, .. } => Some(source.get()),
            _ => None,
        }
    }
}

/// The cause of an [`Error::Io`]: the [`std::io::Error`], shared so that [`Error`] stays `Clone`
/// and compared by kind and message so that it stays `PartialEq`. Its
/// [`source`](std::error::Error::source) is the `std::io::Error` itself.
#[derive(Debug, Clone)]
pub struct IoCause(Arc<std::io::Error>);

impl IoCause {
    /// The I/O error.
    pub fn get(&self) -> &std::io::Error {
        &self.0
    }

    /// Its kind (`NotFound`, `PermissionDenied`, …).
    pub fn kind(&self) -> std::io::ErrorKind {
        self.0.kind()
    }
}

impl From<std::io::Error> for IoCause {
    fn from(e: std::io::Error) -> Self {
        Self(Arc::new(e))
    }
}

impl PartialEq for IoCause {
    fn eq(&self, other: &Self) -> bool {
        self.kind() == other.kind() && self.0.to_string() == other.0.to_string()
    }
}

impl std::fmt::Display for IoCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for IoCause {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&*self.0)
    }
}

/// Result alias with the crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
