//! Errors of the simulator.
//!
//! Why: a scenario is usually hand-written TOML, so every validation error names the field it is
//! about (`profile.segments[2].rate_c_per_min: a ramp needs a non-zero rate`) instead of just saying
//! "invalid input".

use std::path::Path;

/// Everything that can go wrong when building or running a simulation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scenario field has an invalid value; `field` is its path, e.g. `sensor.thermal.t_coil_c.tau_s`.
    #[error("{field}: {message}")]
    Invalid {
        /// Path of the offending field in the scenario (TOML keys, `[i]` for array elements).
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// The TOML text could not be parsed or has the wrong shape.
    #[error("scenario TOML: {0}")]
    Toml(String),
    /// No preset has this name.
    #[error("unknown preset \"{name}\" (known: {known})")]
    UnknownPreset {
        /// The requested name.
        name: String,
        /// Comma-separated list of known presets.
        known: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file (or `<writer>` for a caller-provided writer).
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A feature expression could not be parsed or evaluated by the reference evaluator.
    #[error("expression `{expr}`: {message}")]
    Expr {
        /// The expression text.
        expr: String,
        /// Where and why it failed.
        message: String,
    },
}

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An [`Error::Invalid`] for `field`.
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid {
            field: field.into(),
            message: message.into(),
        }
    }

    /// `Ok` when `v` is finite and > 0, else an [`Error::Invalid`] naming `field`.
    pub fn positive(field: impl Into<String>, v: f64) -> Result<()> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(Error::invalid(field, format!("must be > 0, got {v}")))
        }
    }

    /// `Ok` when `v` is finite and ≥ 0, else an [`Error::Invalid`] naming `field`.
    pub fn non_negative(field: impl Into<String>, v: f64) -> Result<()> {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(Error::invalid(field, format!("must be >= 0, got {v}")))
        }
    }

    /// An [`Error::Io`] about `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.display().to_string(),
            source,
        }
    }

    /// An [`Error::Io`] about a caller-provided writer.
    pub fn writer(source: std::io::Error) -> Self {
        Error::Io {
            path: "<writer>".into(),
            source,
        }
    }
}
