//! The discovery loop's error type: one enum so the CLI prints a single clear line per failure.
//!
//! Why: diagnosis touches data files, the trainer, the simulator and the file system; the user must
//! see which of them failed and why, without a backtrace.

use tcomp_train::{DataError, TrainError};

/// Why a diagnosis, comparison, report or demo failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DiscoverError {
    /// Training or evaluation failed (the message names file, line, expression).
    #[error(transparent)]
    Train(#[from] TrainError),
    /// The data could not be used.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The simulator failed (demo).
    #[error("simulator: {0}")]
    Sim(String),
    /// A file could not be written.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Anything else, with the reason.
    #[error("{0}")]
    Invalid(String),
}

impl From<tcomp_sim::Error> for DiscoverError {
    fn from(e: tcomp_sim::Error) -> Self {
        Self::Sim(e.to_string())
    }
}

/// Result with [`DiscoverError`].
pub type Result<T> = std::result::Result<T, DiscoverError>;
