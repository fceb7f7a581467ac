//! The trainer's error type: one enum, so the CLI prints a single clear line per failure.

use crate::dataset::DataError;

/// Why training or evaluation failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrainError {
    /// A problem with the input data (file, line and column are in the message).
    #[error(transparent)]
    Data(#[from] DataError),
    /// A feature or signal expression does not compile.
    #[error("in `{expr}`: {message}")]
    Expr {
        /// The expression.
        expr: String,
        /// What is wrong, with a caret under the position.
        message: String,
    },
    /// The feature program failed on a sample (e.g. a division by zero).
    #[error("{at}: {message}")]
    Step {
        /// file:line.
        at: String,
        /// The step error.
        message: String,
    },
    /// A feature does not vary over the training data, so nothing can be learnt from it.
    #[error("feature `{expr}` is constant ({value}) over the training data: remove it")]
    ConstantFeature {
        /// The feature expression.
        expr: String,
        /// Its value.
        value: f64,
    },
    /// Two features carry the same information.
    #[error("features `{a}` and `{b}` are collinear (|correlation| = {corr:.6}): remove one")]
    Collinear {
        /// First feature.
        a: String,
        /// Second feature.
        b: String,
        /// Their correlation.
        corr: f64,
    },
    /// A spec file could not be read or parsed.
    #[error("{file}: {message}")]
    Spec {
        /// File name.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// The model blob could not be built, read or written.
    #[error("{0}")]
    Blob(String),
    /// An I/O error on a named file.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// The error.
        source: std::io::Error,
    },
    /// Anything else the user asked for that cannot be done.
    #[error("{0}")]
    Invalid(String),
}
