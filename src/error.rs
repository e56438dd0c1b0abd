//! The crate's error type: every failure on user data is one of these variants.

/// Errors returned by identification, data handling and model I/O.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A value is NaN or infinite.
    #[error("non-finite value (NaN or infinity) in {what} at sample {index}")]
    NonFinite { what: String, index: usize },
    /// Input and output records have different lengths.
    #[error("length mismatch: {what}")]
    LengthMismatch { what: String },
    /// The record is too short for what was asked.
    #[error("not enough samples: {needed} needed ({reason}), got {got}")]
    TooFewSamples {
        needed: usize,
        got: usize,
        reason: String,
    },
    /// An input channel is constant, so nothing can be identified from it.
    #[error("input '{name}' is constant: it excites nothing and carries no information")]
    ConstantInput { name: String },
    /// A requested CSV column does not exist.
    #[error("unknown column '{name}' (available: {available})")]
    UnknownColumn { name: String, available: String },
    /// A CSV file could not be parsed.
    #[error("malformed CSV {path}: {msg}")]
    Csv { path: String, msg: String },
    /// A file could not be read or written.
    #[error("cannot access {path}: {msg}")]
    Io { path: String, msg: String },
    /// The requested model order exceeds what the data and horizon support.
    #[error(
        "model order {requested} is larger than possible (at most {max} with this horizon and data)"
    )]
    OrderTooLarge { requested: usize, max: usize },
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
    /// The subspace horizon (number of block rows) is below the method's minimum.
    #[error(
        "horizon {horizon} is too small: at least {min} (A comes from the shift of i block rows)"
    )]
    HorizonTooSmall { horizon: usize, min: usize },
    /// The subspace horizon is so large that the block-Hankel matrix could never be formed
    /// (its size overflows, or exceeds [`MAX_HORIZON`](crate::subspace::MAX_HORIZON)).
    #[error(
        "horizon {horizon} is too large (at most {max}): the block-Hankel matrix cannot be formed"
    )]
    HorizonTooLarge { horizon: usize, max: usize },
    /// An output channel is constant: there is nothing to identify.
    #[error("output '{name}' is constant: there is no response to identify")]
    ConstantOutput { name: String },
    /// A channel is constant in one part of the record (e.g. the validation part).
    #[error("{channel} '{name}' is constant in {part}")]
    ConstantIn {
        channel: String,
        name: String,
        part: String,
    },
    /// A CSV header names the same column twice and that column was asked for.
    #[error("column '{name}' appears {count} times in the header of {path}: rename one of them")]
    DuplicateColumn {
        name: String,
        count: usize,
        path: String,
    },
    /// A finite CSV value does not fit the requested precision.
    #[error(
        "value {value:e} in column '{column}' row {row} overflows {precision}: use --precision f64"
    )]
    PrecisionOverflow {
        value: f64,
        column: String,
        row: usize,
        precision: &'static str,
    },
    /// A simulation diverged (non-finite or beyond 1e150 in magnitude) where a finite answer is
    /// required.
    #[error(
        "the simulation diverges (output {} at sample {index}): the model is unstable or its entries are too large",
        describe(*.value)
    )]
    Diverged { index: usize, value: f64 },
    /// A saved model has a format version this build cannot read.
    #[error(
        "model file format version {found} is not supported (this build reads version {supported})"
    )]
    UnsupportedVersion { found: u64, supported: u32 },
}

/// Result alias with the crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// A diverged value in words: "not a number", "+infinity", or the number.
fn describe(v: f64) -> String {
    if v.is_nan() {
        "not a number".into()
    } else if v.is_infinite() {
        format!("{}infinity", if v > 0.0 { "+" } else { "-" })
    } else {
        format!("{v:e}")
    }
}
