//! The TOML fit spec: the same keys as the `tcomp fit` flags, so adding an effect is one more line.
//!
//! ```toml
//! time = "time_s"
//! target = "gyro_dph"
//! reference = "ref_dph"
//! signal = ["T = mean(t_anode_c, t_cathode_c, t_shell_c)"]
//! feature = ["T", "rate(T)", "t_anode_c - t_shell_c"]
//! average = 30
//! method = "bayes"
//! ```
//! Unknown keys are errors (a typo must not be silently ignored). Command-line flags override
//! single values and add to the `feature`/`signal` lists.

use crate::error::TrainError;
use serde::Deserialize;
use std::path::Path;

/// A fit spec; every field optional.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Spec {
    /// Time column.
    pub time: Option<String>,
    /// Target column.
    pub target: Option<String>,
    /// Reference column.
    pub reference: Option<String>,
    /// Constant reference.
    pub reference_value: Option<f64>,
    /// Feature expressions.
    #[serde(default)]
    pub feature: Vec<String>,
    /// Signals `NAME = EXPR`.
    #[serde(default)]
    pub signal: Vec<String>,
    /// Averaging bin (s) before fitting; 0 = none.
    pub average: Option<f64>,
    /// Method name.
    pub method: Option<String>,
    /// Number of centers (fixed).
    pub centers: Option<usize>,
    /// Linear term on/off.
    pub linear: Option<bool>,
    /// Offer `bayes` the cubic basis (default true).
    pub cubic: Option<bool>,
    /// Center selection of `mse`: `kmeans` (default) or `ols`.
    pub select: Option<String>,
    /// Gap threshold (s).
    pub gap: Option<f64>,
    /// k-means seed.
    pub seed: Option<u64>,
    /// Gradient iterations.
    pub iterations: Option<usize>,
    /// Sensor kind name.
    pub sensor: Option<String>,
    /// Axis label.
    pub axis: Option<String>,
    /// Target unit.
    pub unit: Option<String>,
    /// Train only on rows with time ≥ this (s).
    pub from: Option<f64>,
    /// Train only on rows with time < this (s).
    pub until: Option<f64>,
}

impl Spec {
    /// Reads a TOML spec file.
    pub fn load(path: &Path) -> Result<Self, TrainError> {
        let text = std::fs::read_to_string(path).map_err(|source| TrainError::Io {
            file: path.display().to_string(),
            source,
        })?;
        toml::from_str(&text).map_err(|e| TrainError::Spec {
            file: path.display().to_string(),
            source: Box::new(e),
        })
    }

    /// `other` laid over `self`: its single values win, its lists are appended.
    #[must_use]
    pub fn merged(mut self, other: Spec) -> Spec {
        macro_rules! take {
            ($($f:ident),*) => { $( if other.$f.is_some() { self.$f = other.$f; } )* };
        }
        take!(
            time,
            target,
            reference,
            reference_value,
            average,
            method,
            centers,
            linear,
            cubic,
            select,
            gap,
            seed,
            iterations,
            sensor,
            axis,
            unit,
            from,
            until
        );
        self.feature.extend(other.feature);
        self.signal.extend(other.signal);
        self
    }
}
