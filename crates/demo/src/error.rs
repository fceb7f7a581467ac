//! The scenario's error type: the simulator's or the trainer's, kept as the source so the tool
//! prints one line naming which of them failed.

use tcomp_train::TrainError;

/// Why simulating, fitting or evaluating the demo's scenario failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DemoError {
    /// The simulator failed.
    #[error("simulator: {0}")]
    Sim(#[from] tcomp_sim::Error),
    /// Training or evaluation failed (the message names file, line, expression).
    #[error(transparent)]
    Train(#[from] TrainError),
}

/// Result with [`DemoError`].
pub type Result<T> = std::result::Result<T, DemoError>;
