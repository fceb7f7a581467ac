//! `fit`: from a dataset and options to a blob, with a summary — the trainer's front door.
//!
//! Why here and not in the CLI: tests and benchmarks call exactly what `tcomp fit` runs. This module
//! only orchestrates; what differs between methods is the method's ([`crate::method::FitMethod`], found in
//! [`crate::registry`]).
//! The steps: select the window and check the column roles and time, find the gaps (warn; feature
//! state is carried across them, or restarted after a long one), let the method rewrite the program (poly3), run the core's feature
//! program over every row, check that features vary and are not collinear, record their ranges,
//! average into bins (`average_s`, default [`DEFAULT_AVERAGE_S`]), let the method fit in f64, store
//! f32 coefficients, then decode the blob and run it through the core's `Channel` over the
//! training data to report the training residual.

use crate::blob_io::OwnedModel;
use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::features;
use crate::method::{MethodDetails, MethodFit, TrainingSet};
use crate::metrics::{self, EvalReport, Roles};
use crate::rows::{Prepared, check_samples, prepare};
use serde::Serialize;
use tcomp_core::ResidualLevel;

pub use crate::fit_options::{FitOptions, parse_sensor};
pub use crate::method::DEFAULT_CENTERS;
pub use crate::registry::{Method, MethodSettings};
pub use crate::rows::{DEFAULT_AVERAGE_S, MIN_DEFAULT_BINS, training_rows};

/// Bin length of the residual level stored in the blob and of binned figures (s).
pub const REPORT_BIN_S: f64 = 100.0;

/// What `fit` reports besides the blob.
#[derive(Clone, Debug, Serialize)]
pub struct FitSummary {
    /// Method.
    pub method: Method,
    /// Signals.
    pub signals: Vec<String>,
    /// Features as stored.
    pub features: Vec<String>,
    /// Number of Gaussian centers.
    pub centers: usize,
    /// Gaussian width σ in normalised units (first center; 0 without centers).
    pub width: f64,
    /// How the method chose its model (length scales, evidence, basis, center selection).
    #[serde(flatten)]
    pub details: MethodDetails,
    /// Linear weights in normalised units (shows which features the model uses).
    pub linear: Vec<f64>,
    /// Training rows.
    pub train_rows: usize,
    /// Training samples after averaging.
    pub train_bins: usize,
    /// Averaging bin (s).
    pub average_s: f64,
    /// The constant reference used, when there was no reference column.
    pub reference_value: Option<f64>,
    /// Figures on the training data (through the core).
    pub train: EvalReport,
    /// Warnings (gaps, defaults taken).
    pub warnings: Vec<String>,
    /// Blob size in bytes.
    pub blob_bytes: usize,
}

/// A trained model: the owned description (encode it with [`OwnedModel::to_bytes`]) and its summary.
#[derive(Clone, Debug)]
pub struct Fitted {
    /// The model.
    pub model: OwnedModel,
    /// The summary.
    pub summary: FitSummary,
}

/// Trains a model on `data` (restricted to `opts.from..opts.until` when given).
pub fn fit(data: &Dataset, opts: &FitOptions) -> Result<Fitted, TrainError> {
    fit_with_progress(data, opts, &crate::progress::Silent)
}

/// [`fit`], reporting long steps (gradient iterations) to `progress`.
pub fn fit_with_progress(
    data: &Dataset,
    opts: &FitOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Fitted, TrainError> {
    progress.start(
        &format!("fitting ({})", opts.method),
        0,
        crate::progress::Unit::Iterations,
    );
    let (set, prepared, fitted) = fit_parts(data, opts, progress)?;
    finish(set, prepared, fitted, opts)
}

/// [`fit`] without the training figures: the model, its residual level left at zero (the
/// compensator never reads it), and how the method chose it. For callers that measure a refit
/// themselves on other rows — the diagnosis's held-out refits, where running each refit over its
/// own training rows took a sixth of the time and its figures were never read.
pub fn fit_unmeasured(
    data: &Dataset,
    opts: &FitOptions,
) -> Result<(OwnedModel, MethodDetails), TrainError> {
    let (set, prepared, fitted) = fit_parts(data, opts, &crate::progress::Silent)?;
    let (model, _, details) = assemble(set, &prepared, fitted, opts)?;
    Ok((model, details))
}

/// The training set, its preparation and the method's fit (what [`finish`] turns into a blob).
/// The structure pins (`linear:`, `additive:`) come off the feature expressions here; the options
/// [`finish`] reads do not depend on them.
fn fit_parts(
    data: &Dataset,
    opts: &FitOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<(TrainingSet, Prepared, MethodFit), TrainError> {
    let (features, pins) = crate::pin::split(&opts.spec.features)?;
    let mut stripped;
    let opts = if pins.iter().any(|p| *p != crate::pin::Pin::Free) {
        stripped = opts.clone();
        stripped.spec.features = features;
        stripped.pins = pins;
        &stripped
    } else {
        opts
    };
    let (mut set, prepared) = prepare(data, opts)?;
    let after = if prepared.average_s > 0.0 {
        format!(" after averaging into {} s bins", prepared.average_s)
    } else {
        String::new()
    };
    let method = opts.fitter();
    check_samples(method, opts, &set.data, set.y.len(), after)?;
    let fitted = method.fit(&mut set, &opts.shared(), progress)?;
    Ok((set, prepared, fitted))
}

/// The blob of a fitted method, measured through the decoded blob as it will fly, and the summary.
fn finish(
    set: TrainingSet,
    prepared: Prepared,
    fitted: MethodFit,
    opts: &FitOptions,
) -> Result<Fitted, TrainError> {
    let (mut model, rest, details) = assemble(set, &prepared, fitted, opts)?;
    let Assembled {
        data,
        y_len,
        mut warnings,
        rbf,
        width,
    } = rest;
    // The stored program, compiled once for both encodings (the method may have replaced the
    // one the rows were computed with: bayes choosing the cubic).
    let program = model.spec.program()?;
    let train = measure(&model.to_bytes_with(&program)?, &data, opts)?;
    model.residual.std = train.residual_std as f32;
    model.residual.binned_std = train.binned.residual_std as f32;
    let final_bytes = model.to_bytes_with(&program)?;
    drop(program);
    if let Err(e) =
        crate::blob_io::check_flight(std::path::Path::new("the new model"), &final_bytes)
    {
        warnings.push(format!(
            "{e}; it runs on the host, not on the reference board"
        ));
    }
    let summary = FitSummary {
        method: opts.method,
        signals: model.spec.signals.clone(),
        features: model.spec.features.clone(),
        centers: rbf.centers.len(),
        width,
        details,
        linear: rbf.linear.clone(),
        train_rows: data.len(),
        train_bins: y_len,
        average_s: prepared.average_s,
        reference_value: prepared.reference_value,
        train,
        warnings,
        blob_bytes: final_bytes.len(),
    };
    Ok(Fitted { model, summary })
}

/// What [`assemble`] leaves besides the model and the method's details, for the summary.
struct Assembled {
    data: Dataset,
    y_len: usize,
    warnings: Vec<String>,
    rbf: crate::rbf64::Rbf64,
    width: f64,
}

/// The blob of a fitted method (residual level zero until measured).
fn assemble(
    set: TrainingSet,
    prepared: &Prepared,
    fitted: MethodFit,
    opts: &FitOptions,
) -> Result<(OwnedModel, Assembled, MethodDetails), TrainError> {
    let TrainingSet {
        data,
        spec,
        ranges,
        y,
        warnings,
        ..
    } = set;
    let MethodFit {
        rbf,
        width,
        details,
    } = fitted;
    let width = width
        .filter(|w| *w != 0.0)
        .unwrap_or_else(|| rbf.gamma.first().map_or(0.0, |g| (0.5 / g).sqrt()));
    let time = data.time(&opts.time)?;
    let t0 = time.first().copied().unwrap_or(0.0);
    let t1 = time.last().copied().unwrap_or(0.0);
    let model = OwnedModel {
        sensor: opts.sensor,
        axis: opts.axis.clone(),
        unit: opts.unit.clone(),
        method: opts.method.to_string(),
        time: opts.time.clone(),
        target: opts.target.clone(),
        reference: opts.reference.clone().unwrap_or_default(),
        reference_value: prepared.reference_value.map(|v| v as f32),
        trained_on: crate::blob_io::TrainedOn::text(data.file(), t0, t1),
        train_samples: y.len() as u32,
        spec,
        ranges,
        rbf: rbf.to_core()?,
        residual: ResidualLevel {
            std: 0.0,
            binned_std: 0.0,
            bin_s: REPORT_BIN_S as f32,
        },
    };
    let rest = Assembled {
        data,
        y_len: y.len(),
        warnings,
        rbf,
        width,
    };
    Ok((model, rest, details))
}

/// The training figures of the model encoded as `bytes`, through its decoded blob and the core's
/// `Channel`.
fn measure(bytes: &[u8], data: &Dataset, opts: &FitOptions) -> Result<EvalReport, TrainError> {
    let decoded = crate::blob_io::decode(std::path::Path::new("<new model>"), bytes)?;
    let roles = Roles {
        power_on_s: opts.power_on_s,
        ..Roles::of_model(&decoded)
    };
    let run = metrics::run_model(&decoded, data, &roles, None, opts.gap_s)?;
    Ok(metrics::report(&run, REPORT_BIN_S))
}

/// Evaluates a decoded model on `data`: runs it through the core and computes the report.
pub fn evaluate(
    model: &tcomp_core::Model<'_, { crate::rbf64::C }, { features::F }, { features::N }>,
    data: &Dataset,
    roles: &Roles,
    bin_s: f64,
    temperature: Option<&str>,
    gap_s: Option<f64>,
) -> Result<EvalReport, TrainError> {
    if let Some(g) = gap_s {
        crate::options::GAP.check(g)?;
    }
    let run = metrics::run_model(model, data, roles, temperature, gap_s)?;
    // After the run, so that a bad cell is reported before the bin it would have been binned in.
    crate::options::check_bin("--bin", bin_s, &run.time)?;
    Ok(metrics::report(&run, bin_s))
}
