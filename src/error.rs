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
    /// A CSV column was given by a position (a number no header name matches) outside
    /// 1..=columns.
    #[error(
        "column {position} is out of range: the file has {columns} column(s) ({available}); \
         give a column's name or its position from 1 to {columns}"
    )]
    ColumnOutOfRange {
        /// The 1-based position asked for.
        position: usize,
        /// The number of columns in the header.
        columns: usize,
        /// The columns the file has, comma-separated.
        available: String,
    },
    /// A CSV file could not be parsed; the CSV reader's error is kept as the cause when it
    /// raised one ([`Error::csv_error`] under feature `csv`, or
    /// [`source`](std::error::Error::source) then its source).
    #[error("malformed CSV {path}: {msg}")]
    Csv {
        /// The file.
        path: String,
        /// What is wrong, with the line where known.
        msg: String,
        /// The reader's error (`None`: a check of this crate, e.g. a cell that is not a number).
        #[source]
        source: Option<CsvCause>,
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
        "model order {requested} is larger than possible (at most {max} with this horizon and data): \
         choose a lower order, or a horizon above the order (--horizon) on a record long enough for it"
    )]
    OrderTooLarge {
        /// The order asked for.
        requested: usize,
        /// The largest order possible.
        max: usize,
    },
    /// A setting or argument is out of its valid range (the catch-all: the specific variants
    /// below say which when a caller would match on it).
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// A name (of an effect, a subspace method, a backend, …) is not one this build knows.
    #[error("invalid parameter: unknown {kind} '{name}' ({expected})")]
    UnknownName {
        /// What was named.
        kind: NameKind,
        /// The name given.
        name: String,
        /// The names accepted.
        expected: &'static str,
    },
    /// No experiment (record) was given where at least one is needed.
    #[error("invalid parameter: no experiment given")]
    NoExperiment,
    /// A record or table has no input or no output channel.
    #[error("invalid parameter: {what}")]
    NoChannels {
        /// What lacks them, in words.
        what: &'static str,
    },
    /// An effect or effect choice was asked of a nonlinearity that is not a UDN (a user basis,
    /// a polynomial).
    #[error("invalid parameter: {what} the nonlinearity '{name}', which is not a UDN")]
    NotUdn {
        /// What was asked, in words ("cannot add the effect 'hysteresis' to").
        what: String,
        /// The nonlinearity's name.
        name: String,
    },
    /// A model order of 0 was asked for.
    #[error("invalid parameter: model order must be at least 1")]
    ZeroOrder,
    /// A sample range lies outside the record.
    #[error("invalid parameter: sample range {start}..{end} outside 0..{len}")]
    SampleRange {
        /// First sample asked for.
        start: usize,
        /// One past the last sample asked for.
        end: usize,
        /// The record's length.
        len: usize,
    },
    /// A validation fraction outside (0, 1).
    #[error("invalid parameter: validation fraction must lie in (0, 1), got {0}")]
    ValidationFraction(f64),
    /// A sample time that is not positive and finite.
    #[error("invalid parameter: sample time must be positive and finite, got {0}")]
    SampleTime(f64),
    /// A user basis names two regressor columns alike.
    #[error("invalid parameter: duplicate regressor column name '{name}'")]
    DuplicateRegressor {
        /// The name used twice.
        name: String,
    },
    /// A backend was asked for that this build does not contain.
    #[error(
        "invalid parameter: the {name} backend is not compiled in; rebuild with `--features {feature}`"
    )]
    BackendUnavailable {
        /// The backend ("LAPACK").
        name: &'static str,
        /// The Cargo feature that adds it.
        feature: &'static str,
    },
    /// A diagnosis suggestion names no candidate of the registry in use.
    #[error("invalid parameter: no candidate named '{name}' is registered")]
    UnknownCandidate {
        /// The suggestion's effect.
        name: String,
    },
    /// A diagnosis suggestion changes something outside the model class (an output map, a
    /// user's candidate without a refitted model), so there are no settings to apply.
    #[error(
        "invalid parameter: the suggestion '{effect}' ({change}) changes something outside this model class; it cannot be applied to the settings"
    )]
    NotApplicable {
        /// The suggestion's effect.
        effect: String,
        /// Its change, as labelled ("output-nonlinearity").
        change: String,
    },
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
    HorizonTooSmall {
        /// The horizon asked for.
        horizon: usize,
        /// The smallest admissible horizon.
        min: usize,
    },
    /// The subspace horizon is so large that the block-Hankel matrix could never be formed
    /// (its size overflows, or exceeds [`MAX_HORIZON`](crate::subspace::MAX_HORIZON)).
    #[error(
        "horizon {horizon} is too large (at most {max}): the block-Hankel matrix cannot be formed"
    )]
    HorizonTooLarge {
        /// The horizon asked for.
        horizon: usize,
        /// The largest admissible horizon.
        max: usize,
    },
    /// A channel is constant in one part of the record (e.g. the validation part).
    #[error("{channel} '{name}' is constant in {part}")]
    ConstantIn {
        /// "input" or "output".
        channel: String,
        /// The channel's name.
        name: String,
        /// Which part of the record ("the validation part (last 30 % of the record)").
        part: String,
    },
    /// A CSV header names the same column twice and that column was asked for.
    #[error("column '{name}' appears {count} times in the header of {path}: rename one of them")]
    DuplicateColumn {
        /// The column name.
        name: String,
        /// How often the header names it.
        count: usize,
        /// The file.
        path: String,
    },
    /// One column was chosen for two channels (an input that is also the output, or an input
    /// listed twice): the model would be fitted to itself.
    #[error(
        "column '{name}' is chosen as {roles}: each input and output needs a column of its own"
    )]
    RepeatedChannel {
        /// The column name.
        name: String,
        /// The two roles ("input and output", "two inputs", "two outputs").
        roles: &'static str,
    },
    /// A finite CSV value does not fit the requested precision.
    #[error(
        "value {value:e} in column '{column}' row {row} overflows {precision}: use --precision f64"
    )]
    PrecisionOverflow {
        /// The value read.
        value: f64,
        /// Its column.
        column: String,
        /// Its row (1-based, after the header).
        row: usize,
        /// The requested precision ("f32").
        precision: &'static str,
    },
    /// A column's values lose their detail in the requested precision: the largest rounding
    /// error of its values exceeds [`crate::data::PRECISION_LOSS_LIMIT`] of its spread (a large
    /// offset with a small signal on it, e.g. 1e6 + a signal of spread 10 in f32).
    #[error(
        "column '{column}' loses its detail in {precision}: its values (up to {magnitude:.4e} in \
         magnitude) are rounded by up to {rounding:.1e}, {relative:.1e} of its spread {spread:.4e} \
         (more than the limit 1e-4); use --precision f64, or subtract the column's offset (e.g. \
         its mean) before fitting",
        relative = rounding / spread
    )]
    PrecisionLoss {
        /// The column.
        column: String,
        /// The requested precision ("f32").
        precision: &'static str,
        /// The largest |x − round(x)| over the column.
        rounding: f64,
        /// max − min of the column.
        spread: f64,
        /// The largest |x| of the column.
        magnitude: f64,
    },
    /// A simulation diverged (non-finite or beyond 1e150 in magnitude) where a finite answer is
    /// required.
    #[error(
        "the simulation diverges (output {} at sample {index}): the model is unstable or its entries are too large",
        describe(*.value)
    )]
    Diverged {
        /// First sample where the output is non-finite or too large.
        index: usize,
        /// The output there.
        value: f64,
    },
    /// A channel's values lie outside the magnitudes the scalar type's computations on the
    /// record hold: their sums of squares overflow, or they are subnormal
    /// ([`IoData::check_magnitude`](crate::data::IoData::check_magnitude)).
    #[error("{channel} '{name}' reaches {magnitude:.3e} in magnitude, {why}")]
    Magnitude {
        /// "input" or "output".
        channel: String,
        /// The channel's name.
        name: String,
        /// Its largest |value|.
        magnitude: f64,
        /// What is wrong with it and what to do.
        why: String,
    },
    /// A saved model has a format version this build cannot read.
    #[error(
        "model file format version {found} is not supported (this build reads versions 1 to {supported})"
    )]
    UnsupportedVersion {
        /// The file's version.
        found: u64,
        /// The newest version this build reads (it reads every version from 1 on).
        supported: u32,
    },
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

    /// The CSV reader's error of an [`Error::Csv`], when the reader raised one.
    #[cfg(feature = "csv")]
    pub fn csv_error(&self) -> Option<&csv::Error> {
        match self {
            Error::Csv {
                source: Some(c), ..
            } => c.0.downcast_ref::<csv::Error>(),
            _ => None,
        }
    }
}

/// What an [`Error::UnknownName`] names.
#[non_exhaustive]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameKind {
    /// A nonlinearity effect ("hysteresis", …).
    Effect,
    /// A subspace method ("moesp", …).
    SubspaceMethod,
    /// A compression of the block-Hankel data ("qr", …).
    Compression,
    /// A linear-algebra backend ("faer", "lapack").
    Backend,
    /// An output nonlinearity ("poly3", …).
    OutputNonlinearity,
    /// A normalisation of the rank-one factorisation ("markov-one", …).
    Normalization,
    /// A feed-through choice ("auto", "on", "off").
    Feedthrough,
}

impl std::fmt::Display for NameKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NameKind::Effect => "effect",
            NameKind::SubspaceMethod => "subspace method",
            NameKind::Compression => "compression",
            NameKind::Backend => "backend",
            NameKind::OutputNonlinearity => "output nonlinearity",
            NameKind::Normalization => "normalisation",
            NameKind::Feedthrough => "feed-through",
        })
    }
}

/// The cause of an [`Error::Csv`]: the CSV reader's error, shared so that [`Error`] stays
/// `Clone` and compared by message so that it stays `PartialEq`.
#[derive(Debug, Clone)]
pub struct CsvCause(Arc<dyn std::error::Error + Send + Sync>);

impl CsvCause {
    /// The cause of a CSV reader's error `e`.
    #[cfg(feature = "csv")]
    pub fn new(e: csv::Error) -> Self {
        Self(Arc::new(e))
    }
}

impl PartialEq for CsvCause {
    fn eq(&self, other: &Self) -> bool {
        self.0.to_string() == other.0.to_string()
    }
}

impl std::fmt::Display for CsvCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for CsvCause {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&*self.0)
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

#[cfg(test)]
mod unit {
    use super::*;
    use std::error::Error as _;

    #[test]
    fn io_keeps_its_source_and_kind() {
        let e = Error::io(
            "data.csv",
            std::io::Error::new(std::io::ErrorKind::PermissionDenied, "denied"),
        );
        assert_eq!(
            e.io_error().map(|io| io.kind()),
            Some(std::io::ErrorKind::PermissionDenied)
        );
        let Error::Io { source, .. } = &e else {
            panic!("{e:?}")
        };
        assert_eq!(source.kind(), std::io::ErrorKind::PermissionDenied);
        let cause = e.source().expect("a source");
        let io = cause
            .source()
            .and_then(|s| s.downcast_ref::<std::io::Error>())
            .expect("the io::Error behind it");
        assert_eq!(io.kind(), std::io::ErrorKind::PermissionDenied);
        assert_eq!(e.to_string(), "cannot access data.csv: denied");
    }

    #[test]
    fn specific_variants_keep_the_catch_all_texts() {
        assert_eq!(
            Error::ZeroOrder.to_string(),
            "invalid parameter: model order must be at least 1"
        );
        assert_eq!(
            Error::NoExperiment.to_string(),
            "invalid parameter: no experiment given"
        );
        let e = Error::UnknownName {
            kind: NameKind::Backend,
            name: "x".into(),
            expected: "faer|lapack",
        };
        assert_eq!(
            e.to_string(),
            "invalid parameter: unknown backend 'x' (faer|lapack)"
        );
    }
}
