//! `fit`: from a dataset and options to a blob, with a summary — the trainer's front door.
//!
//! Why here and not in the CLI: tests and benchmarks call exactly what `tcomp fit` runs. This module
//! only orchestrates; what differs between methods is the method's ([`crate::method::FitMethod`]).
//! The steps: select the window and check the column roles and time, split at gaps (warn; feature
//! state is reset there), let the method rewrite the program (poly3), run the core's feature
//! program over every row, check that features vary and are not collinear, record their ranges,
//! average into bins (`average_s`, default [`DEFAULT_AVERAGE_S`]), let the method fit in f64, store
//! f32 coefficients, then decode the blob and run it through the core's `Channel` over the
//! training data to report the training residual.

use crate::blob_io::OwnedModel;
use crate::dataset::{DataError, Dataset, segments};
use crate::error::TrainError;
use crate::features::{self, FeatureSpec, bin_mean, bins};
use crate::method::{FitMethod, MethodDetails, MethodFit, TrainingSet};
use crate::metrics::{self, EvalReport, Roles};
use crate::options;
use serde::Serialize;
use tcomp_core::{FeatureRange, ResidualLevel};

pub use crate::fit_options::{FitOptions, parse_sensor};
pub use crate::method::{DEFAULT_CENTERS, Method};

/// Default averaging bin before fitting (s), shortened to leave at least [`MIN_DEFAULT_BINS`] bins.
/// Bias instability makes 1 Hz samples strongly correlated, and the evidence computed as if they
/// were independent is overconfident: on the simulated QMA run, 30 s bins let the evidence pick 32
/// narrow centers that learn a spurious temperature × rate interaction (held-out residual 17× the
/// noise floor), while 120 s bins give 1.13× (measured). A 6-hour run still gives 180 bins.
pub const DEFAULT_AVERAGE_S: f64 = 120.0;
/// The default averaging is shortened on short runs so that at least this many bins remain.
pub const MIN_DEFAULT_BINS: f64 = 60.0;
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

fn check_features(
    spec: &FeatureSpec,
    columns: &[Vec<f64>],
    collinear: bool,
) -> Result<(), TrainError> {
    let stats: Vec<(f64, f64)> = columns
        .iter()
        .map(|c| {
            let n = c.len().max(1) as f64;
            let m = c.iter().sum::<f64>() / n;
            let var = c.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n;
            (m, var.sqrt())
        })
        .collect();
    for (k, (m, s)) in stats.iter().enumerate() {
        if *s <= 1e-9 * (1.0 + m.abs()) {
            return Err(TrainError::ConstantFeature {
                expr: spec.features.get(k).cloned().unwrap_or_default(),
                value: *m,
            });
        }
    }
    if !collinear {
        return Ok(());
    }
    for (a, (ca, (ma, sa))) in columns.iter().zip(&stats).enumerate() {
        for (b, (cb, (mb, sb))) in columns.iter().zip(&stats).enumerate().skip(a + 1) {
            let n = ca.len().max(1) as f64;
            let c: f64 = ca
                .iter()
                .zip(cb)
                .map(|(va, vb)| (va - ma) * (vb - mb))
                .sum();
            let corr = c / n / (sa * sb);
            if corr.abs() > 0.9999 {
                return Err(TrainError::Collinear {
                    a: spec.features.get(a).cloned().unwrap_or_default(),
                    b: spec.features.get(b).cloned().unwrap_or_default(),
                    corr,
                });
            }
        }
    }
    Ok(())
}

/// The rows a method is fitted on: features computed by the core's program over `data` (restricted
/// to `opts.from..opts.until`), averaged into `opts.average_s` bins — `(x, y)`, one row per bin.
/// Benchmarks and comparisons with other fitters use it to hand every fitter the same numbers.
pub fn training_rows(
    data: &Dataset,
    opts: &FitOptions,
) -> Result<(Vec<Vec<f64>>, Vec<f64>), TrainError> {
    let (set, _) = prepare(data, opts)?;
    Ok((set.x, set.y))
}

/// The selected rows with the error series and the reference used.
struct Selection {
    data: Dataset,
    error: Vec<f64>,
    reference_value: Option<f64>,
    warnings: Vec<String>,
}

/// Restricts `data` to the window and computes the error (target − reference); with no reference
/// at all, the training mean of the target is used (and said).
fn select(data: &Dataset, opts: &FitOptions) -> Result<Selection, TrainError> {
    let mut warnings = Vec::new();
    let data = if opts.from.is_some() || opts.until.is_some() {
        data.select_time(
            &opts.time,
            opts.from.unwrap_or(f64::NEG_INFINITY),
            opts.until.unwrap_or(f64::INFINITY),
        )?
    } else {
        data.clone()
    };
    data.time(&opts.time)?;
    let target = data.column(&opts.target)?;
    let reference_value = match (&opts.reference, opts.reference_value) {
        (Some(_), _) => None,
        (None, Some(v)) => Some(v),
        (None, None) => {
            let m = target.iter().sum::<f64>() / target.len().max(1) as f64;
            warnings.push(format!(
                "no reference given: errors are taken against the training mean of `{}` ({m})",
                opts.target
            ));
            Some(m)
        }
    };
    let roles = Roles {
        time: opts.time.clone(),
        target: opts.target.clone(),
        reference: opts.reference.clone(),
        reference_value,
    };
    let reference = roles.reference_series(&data)?;
    let error: Vec<f64> = target.iter().zip(&reference).map(|(a, b)| a - b).collect();
    Ok(Selection {
        data,
        error,
        reference_value,
        warnings,
    })
}

/// The averaging bin: the one asked for (checked against the sampling step), or the default,
/// shortened on short runs and adapted to bursty records.
fn averaging(opts: &FitOptions, data: &Dataset, time: &[f64]) -> Result<f64, TrainError> {
    let span = time.last().copied().unwrap_or(0.0) - time.first().copied().unwrap_or(0.0);
    let step = crate::dataset::median_step(time);
    match opts.average_s {
        Some(a) if a > 0.0 && a < step => Err(TrainError::AverageBelowStep {
            file: data.file().to_string(),
            average: options::num(a),
            step: options::num(step),
        }),
        Some(a) => Ok(a),
        // Bursty records (short bursts minutes apart) leave most default bins empty.
        None => Ok(crate::features::adaptive_bin(
            time,
            DEFAULT_AVERAGE_S.min(span / MIN_DEFAULT_BINS),
            MIN_DEFAULT_BINS as usize,
        )),
    }
}

/// Options built in code rather than by [`FitOptions::from_spec`] get the same checks.
fn check_options(opts: &FitOptions, method: &dyn FitMethod) -> Result<(), TrainError> {
    if let Some(a) = opts.average_s {
        options::AVERAGE.check(a)?;
    }
    if let Some(g) = opts.gap_s {
        options::GAP.check(g)?;
    }
    method.check(opts)
}

/// The feature columns of `spec` over the selected rows (one column per feature: a row per sample
/// would be 22,000 small allocations on a 6-hour run), and each feature's trained range.
fn feature_columns(
    spec: &FeatureSpec,
    data: &Dataset,
    time: &[f64],
    starts: &[usize],
) -> Result<(Vec<Vec<f64>>, Vec<FeatureRange>), TrainError> {
    let program = spec.program()?;
    let nf = program.n_features();
    let feats = features::compute(&program, data, time, starts)?;
    let columns: Vec<Vec<f64>> = (0..nf)
        .map(|k| {
            feats
                .iter()
                .map(|r| r.get(k).copied().map_or(0.0, f64::from))
                .collect()
        })
        .collect();
    let ranges = (0..nf)
        .map(|k| {
            let (lo, hi) = feats
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), r| {
                    let v = r.get(k).copied().unwrap_or(f32::NAN);
                    (l.min(v), h.max(v))
                });
            FeatureRange { lo, hi }
        })
        .collect();
    Ok((columns, ranges))
}

/// Refuses too few rows for the method (`after` says after what, e.g. averaging).
fn check_samples(
    method: &dyn FitMethod,
    opts: &FitOptions,
    data: &Dataset,
    have: usize,
    after: String,
) -> Result<(), TrainError> {
    let need = method.min_samples(opts);
    if have >= need {
        return Ok(());
    }
    Err(DataError::TooFewSamples {
        file: data.file().to_string(),
        have,
        need,
        after,
        why: format!("method {}", opts.method),
    }
    .into())
}

/// Everything `fit` derives from the data before the method runs, and the averaging bin used.
fn prepare(data: &Dataset, opts: &FitOptions) -> Result<(TrainingSet, Prepared), TrainError> {
    let method = opts.method.fitter();
    let Selection {
        data,
        error,
        reference_value,
        mut warnings,
    } = select(data, opts)?;
    let time = data.time(&opts.time)?;
    let starts = segments(time, opts.gap_s);
    for &s in starts.iter().skip(1) {
        let gap = time.get(s).copied().unwrap_or(0.0) - time.get(s - 1).copied().unwrap_or(0.0);
        warnings.push(format!(
            "{}:{}: gap of {gap:.3} s; feature state (rate, lag) reset there",
            data.file(),
            data.line(s)
        ));
    }
    check_options(opts, method)?;
    let average_s = averaging(opts, &data, time)?;
    let b = bins(time, average_s);
    check_memory(opts, time, b.len(), &data)?;
    let spec = method.program(opts, &data, &starts, &mut warnings)?;
    let (columns, ranges) = feature_columns(&spec, &data, time, &starts)?;
    // Too few rows is said as such (after any bad cell they hold), before a feature over them
    // looks constant.
    check_samples(method, opts, &data, time.len(), " (rows)".to_string())?;
    check_features(&spec, &columns, method.refuses_collinear())?;
    let y = bin_mean(&error, &b);
    let cols: Vec<Vec<f64>> = columns.iter().map(|c| bin_mean(c, &b)).collect();
    let x: Vec<Vec<f64>> = (0..y.len())
        .map(|i| {
            cols.iter()
                .map(|c| c.get(i).copied().unwrap_or(0.0))
                .collect()
        })
        .collect();
    let set = TrainingSet {
        data,
        starts,
        bins: b,
        spec,
        ranges,
        x,
        y,
        warnings,
    };
    Ok((
        set,
        Prepared {
            reference_value,
            average_s,
        },
    ))
}

/// What `prepare` resolved besides the training set.
struct Prepared {
    reference_value: Option<f64>,
    average_s: f64,
}

/// The shape of a fit of `samples` training samples over `rows` rows with `opts`.
fn shape(opts: &FitOptions, rows: usize, samples: usize) -> crate::budget::Shape {
    crate::budget::Shape {
        rows,
        samples,
        features: opts.method.fitter().features_fitted(opts),
        method: opts.method,
        centers: opts.centers,
        select: opts.select,
        threads: rayon::current_num_threads(),
    }
}

/// Refuses a fit whose estimated memory is over `opts.memory_budget`, suggesting the shortest
/// averaging bin that would fit.
fn check_memory(
    opts: &FitOptions,
    time: &[f64],
    samples: usize,
    data: &Dataset,
) -> Result<(), TrainError> {
    use crate::budget::{estimate, human};
    let need = estimate(&shape(opts, time.len(), samples));
    if need <= opts.memory_budget {
        return Ok(());
    }
    let step = crate::dataset::median_step(time);
    // From 1 s up: a bin that only just fits the budget would still be a fit of hours.
    let suggestion = [1.0, 2.0, 5.0, 10.0, 30.0, 60.0, 120.0, 300.0, 600.0]
        .into_iter()
        .filter(|&a| a >= step && a > opts.average_s.unwrap_or(0.0))
        .find(|&a| estimate(&shape(opts, time.len(), bins(time, a).len())) <= opts.memory_budget);
    let averaged = match opts.average_s {
        Some(a) if a > 0.0 => format!("averaged into {a} s bins"),
        Some(_) => "unaveraged".to_string(),
        None => "averaged".to_string(),
    };
    Err(TrainError::OverMemoryBudget(Box::new(
        crate::error::OverBudget {
            file: data.file().to_string(),
            method: opts.method.name(),
            rows: time.len(),
            averaged,
            samples,
            need: human(need),
            budget: human(opts.memory_budget),
            suggestion: match suggestion {
                Some(a) => format!(
                    "; average into bins (e.g. --average {a}, which needs {}; without --average \
                     the default is {DEFAULT_AVERAGE_S} s), or pick a shorter window with \
                     --from/--until",
                    human(estimate(&shape(opts, time.len(), bins(time, a).len())))
                ),
                None => "; pick a shorter window with --from/--until".to_string(),
            },
        },
    )))
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
    let method = opts.method.fitter();
    let (mut set, prepared) = prepare(data, opts)?;
    let after = if prepared.average_s > 0.0 {
        format!(" after averaging into {} s bins", prepared.average_s)
    } else {
        String::new()
    };
    check_samples(method, opts, &set.data, set.y.len(), after)?;
    let fitted = method.fit(&mut set, opts, progress)?;
    finish(set, prepared, fitted, opts)
}

/// The blob of a fitted method, measured through the decoded blob as it will fly, and the summary.
fn finish(
    set: TrainingSet,
    prepared: Prepared,
    fitted: MethodFit,
    opts: &FitOptions,
) -> Result<Fitted, TrainError> {
    let TrainingSet {
        data,
        spec,
        ranges,
        y,
        mut warnings,
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
    let mut model = OwnedModel {
        sensor: opts.sensor,
        axis: opts.axis.clone(),
        unit: opts.unit.clone(),
        method: opts.method.to_string(),
        time: opts.time.clone(),
        target: opts.target.clone(),
        reference: opts.reference.clone().unwrap_or_default(),
        reference_value: prepared.reference_value.map(|v| v as f32),
        trained_on: format!("{} t={t0}..{t1} s", data.file()),
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
    let train = measure(&model, &data, opts)?;
    model.residual.std = train.residual_std as f32;
    model.residual.binned_std = train.binned.residual_std as f32;
    let final_bytes = model.to_bytes()?;
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
        train_bins: y.len(),
        average_s: prepared.average_s,
        reference_value: prepared.reference_value,
        train,
        warnings,
        blob_bytes: final_bytes.len(),
    };
    Ok(Fitted { model, summary })
}

/// The training figures of `model`, through its decoded blob and the core's `Channel`.
fn measure(
    model: &OwnedModel,
    data: &Dataset,
    opts: &FitOptions,
) -> Result<EvalReport, TrainError> {
    let bytes = model.to_bytes()?;
    let decoded = crate::blob_io::decode(std::path::Path::new("<new model>"), &bytes)?;
    let run = metrics::run_model(&decoded, data, &Roles::of_model(&decoded), None, opts.gap_s)?;
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
