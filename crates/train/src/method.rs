//! The fit-method trait and what every method needs: the one contract between the trainer and a
//! method, importing no method.
//!
//! Why a trait: a method used to be a `match` in many places (the name, the fewest samples, the
//! option checks, poly3's program rewrite, the fit itself, the summary's fields, the help text).
//! Now a method is one `impl FitMethod` in its own module ([`crate::bayes`], [`crate::mse`],
//! [`crate::gradient`], [`crate::poly3`]) on the struct of its own options, and one line of the
//! registry ([`crate::registry`], which knows every method; this module knows none);
//! [`crate::train`] only orchestrates: select the rows, let the method rewrite the program, compute
//! and average the features, let the method fit, store and measure the blob.
//!
//! A method reads the options it shares with the others ([`Shared`]: the time column, the program,
//! the number of centers, the seed, the pins) and its own, which are the fields of its struct.
//! What the summary shows of a fit ([`MethodDetails`]) is here too, with the few types it names.

use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::evidence::Evidence;
use crate::features::FeatureSpec;
use crate::options::{self, Bound};
use crate::pin::Pin;
use crate::progress::Progress;
use crate::rbf64::Rbf64;
use serde::Serialize;
use std::str::FromStr;
use tcomp_core::FeatureRange;

/// Default number of centers of the methods with a fixed number (`mse`, `gradient`).
pub const DEFAULT_CENTERS: usize = 16;

/// The options every method may read besides its own (a view of [`crate::FitOptions`]).
#[derive(Clone, Copy, Debug)]
pub struct Shared<'a> {
    /// Time column.
    pub time: &'a str,
    /// Signals and features, as given.
    pub spec: &'a FeatureSpec,
    /// Fixed number of centers.
    pub centers: Option<usize>,
    /// k-means seed.
    pub seed: u64,
    /// Per feature, how it may enter the Gaussians ([`crate::pin`]); empty: every feature free.
    pub pins: &'a [Pin],
    /// Time of power-on on the time column (s); default the first row read.
    pub power_on_s: Option<f64>,
}

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
    pub structure: Option<StructureReport>,
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
    /// Checks the method's own options alone (before any data are read; every method's, as the
    /// spec may set options of a method it does not select).
    fn check_settings(&self) -> Result<(), TrainError> {
        Ok(())
    }
    /// Checks the options as this method will use them (beyond the table's bounds).
    fn check(&self, _opts: &Shared<'_>) -> Result<(), TrainError> {
        self.check_settings()
    }
    /// The fewest training samples (after averaging) the method can be fitted on.
    fn min_samples(&self, opts: &Shared<'_>) -> usize;
    /// The number of features the method fits (for the memory estimate).
    fn features_fitted(&self, opts: &Shared<'_>) -> usize {
        opts.spec.features.len()
    }
    /// The program actually stored (poly3 rewrites it around one clamped temperature).
    fn program(
        &self,
        opts: &Shared<'_>,
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
        opts: &Shared<'_>,
        progress: &dyn Progress,
    ) -> Result<MethodFit, TrainError>;
}

/// Which basis a Bayesian fit uses besides the bias and the linear term.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Basis {
    /// Gaussian radial basis functions (possibly none: the linear term alone).
    #[default]
    Gaussians,
    /// `T²` and `T³` of the first feature clamped to its trained range (the PX4/ArduPilot cubic),
    /// under the same prior as the linear term, and no Gaussians.
    Cubic,
    /// The additive structure (`bayes::additive`): a sum of one-feature terms beside the linear
    /// term. Pinned, it is taken whenever its search finds a term; chosen, it beat the joint
    /// model by the Occam margin.
    Additive,
}

/// How the structure was chosen, for the report: each structure compared with its log evidence.
#[derive(Clone, Debug, Default, Serialize)]
pub struct StructureReport {
    /// The chosen structure, as a line ("joint: 8 Gaussians over (T, rate(T)), σ 0.70",
    /// "additive: 3 Gaussians over (T), σ 0.2–1.6 + linear in (supply_v)", "cubic …").
    pub chosen: String,
    /// Each structure compared and its log evidence (target units), best first.
    pub compared: Vec<(String, f64)>,
}

impl FromStr for Basis {
    type Err = TrainError;
    fn from_str(s: &str) -> Result<Self, TrainError> {
        match s {
            "gaussians" => Ok(Self::Gaussians),
            "cubic" => Ok(Self::Cubic),
            "additive" => Ok(Self::Additive),
            _ => Err(TrainError::Unknown {
                what: "basis",
                name: s.into(),
                known: "additive, cubic, gaussians".into(),
            }),
        }
    }
}

/// How the traditional RBF places its centers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CenterSelection {
    /// k-means++ then Lloyd iterations: where the data are.
    #[default]
    Kmeans,
    /// Orthogonal least squares forward selection among the training rows: where the error is.
    Ols,
}

impl FromStr for CenterSelection {
    type Err = TrainError;
    fn from_str(s: &str) -> Result<Self, TrainError> {
        match s {
            "kmeans" => Ok(Self::Kmeans),
            "ols" => Ok(Self::Ols),
            _ => Err(TrainError::Unknown {
                what: "center selection",
                name: s.into(),
                known: "kmeans, ols".into(),
            }),
        }
    }
}
