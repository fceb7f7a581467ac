//! The discovery loop's error type: one enum so the CLI prints a single clear line per failure.
//!
//! Why: diagnosis touches data files and the trainer; the user must see which of them failed and
//! why, without a backtrace.

use tcomp_train::{DataError, TrainError};

/// Why a diagnosis failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DiscoverError {
    /// Training or evaluation failed (the message names file, line, expression).
    #[error(transparent)]
    Train(#[from] TrainError),
    /// The data could not be used.
    #[error(transparent)]
    Data(#[from] DataError),
    /// Anything else, with the reason.
    #[error("{0}")]
    Invalid(String),
}

/// Result with [`DiscoverError`].
pub type Result<T> = std::result::Result<T, DiscoverError>;
