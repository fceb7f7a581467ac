//! The fit-method trait and its registry: the one place a new method goes.
//!
//! Why a trait: a method used to be a `match` in many places (the name, the fewest samples, the
//! option checks, poly3's program rewrite, the fit itself, the summary's fields, the help text).
//! Now a method is one `impl FitMethod` in its own module ([`crate::bayes`], [`crate::mse`],
//! [`crate::gradient`], [`crate::poly3`]) and one line in [`Method::fitter`]; [`crate::train`] only
//! orchestrates: select the rows, let the method rewrite the program, compute and average the
//! features, let the method fit, store and measure the blob.

use crate::bayes::{Basis, Evidence};
use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::features::FeatureSpec;
use crate::mse::CenterSelection;
use crate::options::{self, Bound};
use crate::progress::Progress;
use crate::rbf64::Rbf64;
use crate::train::FitOptions;
use serde::Serialize;
use std::fmt;
use std::str::FromStr;
use tcomp_core::FeatureRange;

/// Default number of centers of the methods with a fixed number (`mse`, `gradient`).
pub const DEFAULT_CENTERS: usize = 16;

/// What a method is fitted on: the selected rows, the stored program, and the (binned) training
/// rows. A method may change the program and its ranges (`bayes` choosing the cubic basis) and add
/// warnings.
#[derive(Clone, Debug)]
pub struct TrainingSet {
    /// The selected rows (`--from/--until`).
    pub data: Dataset,
    /// Row indices where a segment starts: 0, then the row after each gap.
    pub starts: Vec<usize>,
    /// Time since power-on of the first row (s): where `warmup`'s clock starts.
    pub time_on_s: f64,
    /// The averaging bins, as `(first row, end row)` ranges.
    pub bins: Vec<(usize, usize)>,
    /// The program stored in the blob.
    pub spec: FeatureSpec,
    /// The trained range of each of its features.
    pub ranges: Vec<FeatureRange>,
    /// Training rows (raw feature units), one per bin.
    pub x: Vec<Vec<f64>>,
    /// Per bin, the means of its features over up to [`crate::rows::SUB_BINS`] equal parts of it
    /// (raw units): what a fit averages a nonlinear basis over, so that a bin's model is the mean
    /// of the model over the bin, as its target is the mean of the error (see [`crate::bayes`]).
    pub sub_x: Vec<Vec<Vec<f64>>>,
    /// Error (target − reference), one per bin.
    pub y: Vec<f64>,
    /// Warnings for the summary.
    pub warnings: Vec<String>,
}

/// What the summary shows of how a method chose its model (fields a method does not have stay at
/// their defaults and are left out of the JSON when empty).
#[derive(Clone, Debug, Default, Serialize)]
pub struct MethodDetails {
    /// Per-feature length scales (bayes).
    pub length_scales: Vec<f64>,
    /// Evidence figures (bayes).
    pub evidence: Option<Evidence>,
    /// Settings whose evidence was compared (bayes).
    pub settings_evaluated: usize,
    /// How the centers were placed (mse).
    pub select: Option<CenterSelection>,
    /// The basis the evidence chose (bayes): Gaussians, or the cubic in the first feature.
    pub basis: Option<Basis>,
    /// Log evidence of the best model of the other basis (bayes, when the cubic was offered).
    pub other_basis_log_evidence: Option<f64>,
    /// The structure the evidence chose and every structure compared (bayes).
    pub structure: Option<crate::bayes::StructureReport>,
}

/// A method's result.
#[derive(Clone, Debug)]
pub struct MethodFit {
    /// The network in f64.
    pub rbf: Rbf64,
    /// The Gaussian width σ in normalised units, when the method knows it better than the first
    /// center's γ says.
    pub width: Option<f64>,
    /// For the summary.
    pub details: MethodDetails,
}

/// A fit method.
pub trait FitMethod: Sync {
    /// The name `--method` takes.
    fn name(&self) -> &'static str;
    /// One line for `--method`'s help.
    fn about(&self) -> &'static str;
    /// The valid range of `--centers` with this method.
    fn centers_bound(&self) -> &'static Bound {
        &options::CENTERS_BAYES
    }
    /// Checks the options only this method uses (beyond the table's bounds).
    fn check(&self, _opts: &FitOptions) -> Result<(), TrainError> {
        Ok(())
    }
    /// The fewest training samples (after averaging) the method can be fitted on.
    fn min_samples(&self, opts: &FitOptions) -> usize;
    /// The number of features the method fits (for the memory estimate).
    fn features_fitted(&self, opts: &FitOptions) -> usize {
        opts.spec.features.len()
    }
    /// The program actually stored (poly3 rewrites it around one clamped temperature).
    fn program(
        &self,
        opts: &FitOptions,
        _data: &Dataset,
        _starts: &[usize],
        _warnings: &mut Vec<String>,
    ) -> Result<FeatureSpec, TrainError> {
        Ok(opts.spec.clone())
    }
    /// Whether collinear features are refused (poly3's T, T², T³ are collinear on purpose).
    fn refuses_collinear(&self) -> bool {
        true
    }
    /// The memory the method itself holds during a fit of this shape, bytes (its design matrices,
    /// copies and candidates; [`crate::budget::estimate`] adds what every fit holds).
    fn memory(&self, shape: &crate::budget::Shape) -> f64;
    /// Fits the model.
    fn fit(
        &self,
        set: &mut TrainingSet,
        opts: &FitOptions,
        progress: &dyn Progress,
    ) -> Result<MethodFit, TrainError>;
}

/// A training method: the registry's key (a plain `Copy` value for options and the memory
/// estimate); [`Method::fitter`] is the implementation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Bayesian-regularised RBF with evidence-chosen structure.
    Bayes,
    /// k-means + width heuristic + least squares.
    Mse,
    /// Gradient descent on weights, centers and widths.
    Gradient,
    /// Cubic in one clamped temperature.
    Poly3,
}

impl Method {
    /// Every method, the default first.
    pub const ALL: [Method; 4] = [Method::Bayes, Method::Mse, Method::Gradient, Method::Poly3];

    /// The implementation: the registry's one `match`.
    pub fn fitter(self) -> &'static dyn FitMethod {
        match self {
            Method::Bayes => &crate::bayes::Bayes,
            Method::Mse => &crate::mse::Mse,
            Method::Gradient => &crate::gradient::Gradient,
            Method::Poly3 => &crate::poly3::Poly3,
        }
    }

    /// The method's name, as `--method` takes it.
    pub fn name(self) -> &'static str {
        self.fitter().name()
    }

    /// The known names, comma-separated.
    pub fn names() -> String {
        Self::ALL.map(Method::name).join(", ")
    }

    /// `--method`'s help, from the registry: each name with its line, the default first.
    pub fn help() -> String {
        let list: Vec<String> = Self::ALL
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let default = if i == 0 { " (default)" } else { "" };
                format!("  {}{default}: {}", m.name(), m.fitter().about())
            })
            .collect();
        format!("Method:\n{}", list.join("\n"))
    }
}

impl Default for Method {
    fn default() -> Self {
        Method::ALL[0]
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = TrainError;
    fn from_str(s: &str) -> Result<Self, TrainError> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| TrainError::Unknown {
                what: "method",
                name: s.into(),
                known: Self::names(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_parses_back_from_its_name_and_is_in_the_help() {
        let help = Method::help();
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>().ok(), Some(m));
            assert!(help.contains(m.name()), "{help}");
        }
        assert!(help.starts_with("Method:\n  bayes (default): "), "{help}");
        let e = "magic".parse::<Method>().err().map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some("unknown method `magic` (known: bayes, mse, gradient, poly3)")
        );
    }
}
