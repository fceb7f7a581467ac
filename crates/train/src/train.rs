//! `fit`: from a dataset and options to a blob, with a summary — the trainer's front door.
//!
//! Why here and not in the CLI: tests and benchmarks call exactly what `tcomp fit` runs. The steps:
//! check the column roles and time, split at gaps (warn; feature state is reset there), run the core's
//! feature program over every row, check that features vary and are not collinear, record their
//! ranges, average into bins (`average_s`, default [`DEFAULT_AVERAGE_S`]), fit by the chosen method in
//! f64, store f32 coefficients, then decode the blob and run it through the core's `Channel` over the
//! training data to report the training residual.

use crate::bayes::{self, Basis, BayesOptions, Evidence};
use crate::blob_io::OwnedModel;
use crate::dataset::{DataError, Dataset, segments};
use crate::error::TrainError;
use crate::features::{self, FeatureSpec, bin_mean, bins};
use crate::metrics::{self, EvalReport, Roles};
use crate::mse::CenterSelection;
use crate::options;
use crate::rbf64::Rbf64;
use crate::spec::Spec;
use serde::Serialize;
use std::fmt;
use std::str::FromStr;
use tcomp_core::{FeatureRange, ResidualLevel, SensorKind};

/// Default averaging bin before fitting (s), shortened to leave at least [`MIN_DEFAULT_BINS`] bins.
/// Bias instability makes 1 Hz samples strongly correlated, and the evidence computed as if they
/// were independent is overconfident: on the simulated QMA run, 30 s bins let the evidence pick 32
/// narrow centers that learn a spurious temperature × rate interaction (held-out residual 17× the
/// noise floor), while 120 s bins give 1.13× (measured). A 6-hour run still gives 180 bins.
pub const DEFAULT_AVERAGE_S: f64 = 120.0;
/// The default averaging is shortened on short runs so that at least this many bins remain.
pub const MIN_DEFAULT_BINS: f64 = 60.0;
/// Default number of centers of `mse` and `gradient`.
pub const DEFAULT_CENTERS: usize = 16;
/// Bin length of the residual level stored in the blob and of binned figures (s).
pub const REPORT_BIN_S: f64 = 100.0;

/// A training method.
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
    /// The method's name, as `--method` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bayes => "bayes",
            Self::Mse => "mse",
            Self::Gradient => "gradient",
            Self::Poly3 => "poly3",
        }
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
        match s {
            "bayes" => Ok(Self::Bayes),
            "mse" => Ok(Self::Mse),
            "gradient" => Ok(Self::Gradient),
            "poly3" => Ok(Self::Poly3),
            _ => Err(TrainError::Unknown {
                what: "method",
                name: s.into(),
                known: "bayes, mse, gradient, poly3".into(),
            }),
        }
    }
}

/// Parses a sensor kind name (rlg, qma, ifog, mems-gyro, mems-accel, other).
pub fn parse_sensor(s: &str) -> Result<SensorKind, TrainError> {
    Ok(match s {
        "rlg" => SensorKind::Rlg,
        "qma" => SensorKind::Qma,
        "ifog" => SensorKind::Ifog,
        "mems-gyro" => SensorKind::MemsGyro,
        "mems-accel" => SensorKind::MemsAccel,
        "other" => SensorKind::Other,
        _ => {
            return Err(TrainError::Unknown {
                what: "sensor",
                name: s.into(),
                known: "rlg, qma, ifog, mems-gyro, mems-accel, other".into(),
            });
        }
    })
}

/// Resolved fit options.
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Time column.
    pub time: String,
    /// Target column.
    pub target: String,
    /// Reference column.
    pub reference: Option<String>,
    /// Constant reference; with neither, the training mean of the target is used (and stored).
    pub reference_value: Option<f64>,
    /// Signals and features.
    pub spec: FeatureSpec,
    /// Method.
    pub method: Method,
    /// Averaging bin (s), 0 for none; `None`: [`DEFAULT_AVERAGE_S`], shortened on short runs to
    /// leave [`MIN_DEFAULT_BINS`] bins.
    pub average_s: Option<f64>,
    /// Fixed number of centers.
    pub centers: Option<usize>,
    /// Linear term (bayes).
    pub linear: bool,
    /// Offer `bayes` the cubic in the first feature as a basis (chosen only by evidence).
    pub cubic: bool,
    /// How `mse` places its centers.
    pub select: CenterSelection,
    /// Gap threshold (s); default 10× the median step.
    pub gap_s: Option<f64>,
    /// k-means seed.
    pub seed: u64,
    /// Gradient iterations.
    pub iterations: usize,
    /// Sensor kind.
    pub sensor: SensorKind,
    /// Axis label.
    pub axis: String,
    /// Target unit.
    pub unit: String,
    /// Train on time ≥ this.
    pub from: Option<f64>,
    /// Train on time < this.
    pub until: Option<f64>,
    /// The most memory the fit may take (bytes, estimated before allocating; see [`crate::budget`]).
    pub memory_budget: u64,
}

impl FitOptions {
    /// Options with defaults for the given target and features.
    pub fn new(target: &str, features: &[&str]) -> Self {
        Self {
            time: "time_s".into(),
            target: target.into(),
            reference: None,
            reference_value: None,
            spec: FeatureSpec {
                signals: Vec::new(),
                features: features.iter().map(|s| s.to_string()).collect(),
            },
            method: Method::Bayes,
            average_s: None,
            centers: None,
            linear: true,
            cubic: true,
            select: CenterSelection::Kmeans,
            gap_s: None,
            seed: 1,
            iterations: 2000,
            sensor: SensorKind::Other,
            axis: String::new(),
            unit: String::new(),
            from: None,
            until: None,
            memory_budget: crate::budget::DEFAULT_BUDGET_BYTES,
        }
    }

    /// Options from a spec (file and flags merged). Every number is range-checked here, with a
    /// message naming both the flag and the spec key (see [`crate::options`] for the bounds).
    pub fn from_spec(spec: &Spec) -> Result<Self, TrainError> {
        let target = spec.target.clone().ok_or(TrainError::Missing {
            what: "target",
            hint: "--target COL",
        })?;
        let mut o = Self::new(&target, &[]);
        o.spec = FeatureSpec {
            signals: spec.signal.clone(),
            features: spec.feature.clone(),
        };
        if let Some(t) = &spec.time {
            o.time.clone_from(t);
        }
        o.reference.clone_from(&spec.reference);
        if let Some(v) = spec.reference_value {
            o.reference_value = Some(options::REFERENCE_VALUE.check(v)?);
        }
        if let Some(m) = &spec.method {
            o.method = m.parse()?;
        }
        if let Some(a) = spec.average {
            o.average_s = Some(options::AVERAGE.check(a)?);
        }
        if let Some(c) = spec.centers {
            let bound = match o.method {
                Method::Mse | Method::Gradient => &options::CENTERS,
                Method::Bayes | Method::Poly3 => &options::CENTERS_BAYES,
            };
            bound.check_count(c, &format!(" with --method {}", o.method))?;
        }
        o.centers = spec.centers;
        if let Some(l) = spec.linear {
            o.linear = l;
        }
        if let Some(c) = spec.cubic {
            o.cubic = c;
        }
        if let Some(s) = &spec.select {
            o.select = s.parse()?;
        }
        if let Some(g) = spec.gap {
            o.gap_s = Some(options::GAP.check(g)?);
        }
        if let Some(s) = spec.seed {
            o.seed = s;
        }
        if let Some(i) = spec.iterations {
            options::ITERATIONS.check_count(i, "")?;
            o.iterations = i;
        }
        if let Some(s) = &spec.sensor {
            o.sensor = parse_sensor(s)?;
        }
        if let Some(a) = &spec.axis {
            o.axis.clone_from(a);
        }
        if let Some(u) = &spec.unit {
            o.unit.clone_from(u);
        }
        if let Some(f) = spec.from {
            o.from = Some(options::FROM.check(f)?);
        }
        if let Some(u) = spec.until {
            o.until = Some(options::UNTIL.check(u)?);
        }
        if let (Some(f), Some(u)) = (o.from, o.until)
            && f >= u
        {
            return Err(TrainError::EmptyWindow {
                from: options::num(f),
                until: options::num(u),
            });
        }
        Ok(o)
    }
}

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
    /// Per-feature length scales (bayes).
    pub length_scales: Vec<f64>,
    /// Linear weights in normalised units (shows which features the model uses).
    pub linear: Vec<f64>,
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

/// Everything `fit` derives from the data before a method runs: the selected rows, the stored
/// program, feature ranges, and the (binned) training rows the method sees.
struct Prepared {
    data: Dataset,
    spec: FeatureSpec,
    ranges: Vec<FeatureRange>,
    reference_value: Option<f64>,
    average_s: f64,
    /// Training rows (raw feature units), one per bin.
    x: Vec<Vec<f64>>,
    /// Error (target − reference), one per bin.
    y: Vec<f64>,
    /// The cubic basis offered to `bayes`, when it is and fits the firmware.
    cubic: Option<crate::poly3::CubicBasis>,
    warnings: Vec<String>,
}

/// The rows a method is fitted on: features computed by the core's program over `data` (restricted
/// to `opts.from..opts.until`), averaged into `opts.average_s` bins — `(x, y)`, one row per bin.
/// Benchmarks and comparisons with other fitters use it to hand every fitter the same numbers.
pub fn training_rows(
    data: &Dataset,
    opts: &FitOptions,
) -> Result<(Vec<Vec<f64>>, Vec<f64>), TrainError> {
    let p = prepare(data, opts)?;
    Ok((p.x, p.y))
}

fn prepare(data: &Dataset, opts: &FitOptions) -> Result<Prepared, TrainError> {
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
    let time = data.time(&opts.time)?;
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
    let starts = segments(time, opts.gap_s);
    for &s in starts.iter().skip(1) {
        let gap = time.get(s).copied().unwrap_or(0.0) - time.get(s - 1).copied().unwrap_or(0.0);
        warnings.push(format!(
            "{}:{}: gap of {gap:.3} s; feature state (rate, lag) reset there",
            data.file(),
            data.line(s)
        ));
    }
    // Options built in code rather than by `from_spec` get the same checks.
    if let Some(a) = opts.average_s {
        options::AVERAGE.check(a)?;
    }
    if let Some(g) = opts.gap_s {
        options::GAP.check(g)?;
    }
    if matches!(opts.method, Method::Mse | Method::Gradient) {
        let centers = opts.centers.unwrap_or(DEFAULT_CENTERS);
        options::CENTERS.check_count(centers, &format!(" with --method {}", opts.method))?;
    }
    if opts.method == Method::Gradient {
        options::ITERATIONS.check_count(opts.iterations, "")?;
    }
    let span = time.last().copied().unwrap_or(0.0) - time.first().copied().unwrap_or(0.0);
    let step = crate::dataset::median_step(time);
    if let Some(a) = opts.average_s
        && a > 0.0
        && a < step
    {
        return Err(TrainError::AverageBelowStep {
            file: data.file().to_string(),
            average: options::num(a),
            step: options::num(step),
        });
    }
    let mut average_s = opts
        .average_s
        .unwrap_or_else(|| DEFAULT_AVERAGE_S.min(span / MIN_DEFAULT_BINS));
    if opts.average_s.is_none() {
        // Bursty records (short bursts minutes apart) leave most default bins empty.
        average_s = crate::features::adaptive_bin(time, average_s, MIN_DEFAULT_BINS as usize);
    }
    let b = bins(time, average_s);
    check_memory(opts, time, b.len(), &data)?;
    // The program actually stored (poly3 rewrites it around one clamped temperature).
    let spec = if opts.method == Method::Poly3 {
        let expr = opts.spec.features.first().ok_or(TrainError::MethodNeeds {
            method: "poly3",
            what: "one feature: the temperature expression",
        })?;
        if opts.spec.features.len() > 1 {
            warnings.push(format!(
                "poly3 uses only the first feature `{expr}`; the others are ignored"
            ));
        }
        let probe = FeatureSpec {
            signals: opts.spec.signals.clone(),
            features: vec![expr.clone()],
        };
        let t = features::compute(&probe.program()?, &data, time, &starts)?;
        let (lo, hi) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
                (l.min(f64::from(r[0])), h.max(f64::from(r[0])))
            });
        let (sig, feats) = crate::poly3::program_lines(expr, lo, hi);
        let mut signals = opts.spec.signals.clone();
        signals.push(sig);
        FeatureSpec {
            signals,
            features: feats,
        }
    } else {
        opts.spec.clone()
    };
    let (nf, feats) = {
        let program = spec.program()?;
        let feats = features::compute(&program, &data, time, &starts)?;
        (program.n_features(), feats)
    };
    // One column per feature (a row per sample would be 22,000 small allocations on a 6-hour run).
    let columns: Vec<Vec<f64>> = (0..nf)
        .map(|k| {
            feats
                .iter()
                .map(|r| r.get(k).copied().map_or(0.0, f64::from))
                .collect()
        })
        .collect();
    // Too few rows is said as such (after any bad cell they hold), before a feature over them
    // looks constant.
    let need = min_samples(opts);
    if time.len() < need {
        return Err(DataError::TooFewSamples {
            file: data.file().to_string(),
            have: time.len(),
            need,
            after: " (rows)".to_string(),
            why: format!("method {}", opts.method),
        }
        .into());
    }
    check_features(&spec, &columns, opts.method != Method::Poly3)?;
    let mut ranges = Vec::with_capacity(nf);
    for k in 0..nf {
        let (lo, hi) = feats
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), r| {
                (l.min(r[k]), h.max(r[k]))
            });
        ranges.push(FeatureRange { lo, hi });
    }
    let y = bin_mean(&error, &b);
    let cols: Vec<Vec<f64>> = columns.iter().map(|c| bin_mean(c, &b)).collect();
    let x: Vec<Vec<f64>> = (0..y.len())
        .map(|i| {
            cols.iter()
                .map(|c| c.get(i).copied().unwrap_or(0.0))
                .collect()
        })
        .collect();
    let cubic =
        if opts.method == Method::Bayes && opts.linear && opts.cubic && opts.centers.is_none() {
            crate::poly3::cubic_basis(&spec, &data, time, &starts, &ranges, &b)?
        } else {
            None
        };
    Ok(Prepared {
        data,
        spec,
        ranges,
        reference_value,
        average_s,
        x,
        y,
        cubic,
        warnings,
    })
}

/// The fewest training samples (after averaging) the method can be fitted on.
fn min_samples(opts: &FitOptions) -> usize {
    match opts.method {
        Method::Bayes => 10,
        Method::Poly3 => 8,
        Method::Mse | Method::Gradient => 2 * opts.centers.unwrap_or(DEFAULT_CENTERS) + 2,
    }
}

/// The shape of a fit of `samples` training samples over `rows` rows with `opts`.
fn shape(opts: &FitOptions, rows: usize, samples: usize) -> crate::budget::Shape {
    crate::budget::Shape {
        rows,
        samples,
        features: if opts.method == Method::Poly3 {
            1
        } else {
            opts.spec.features.len()
        },
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
                    "; average into bins (e.g. --average {a}, which needs {}; without --average the \
                 default is {DEFAULT_AVERAGE_S} s), or pick a shorter window with --from/--until",
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
    let Prepared {
        data,
        mut spec,
        mut ranges,
        reference_value,
        average_s,
        x,
        y,
        cubic,
        mut warnings,
    } = prepare(data, opts)?;
    let time = data.time(&opts.time)?;
    let centers = opts.centers.unwrap_or(DEFAULT_CENTERS);
    let need = min_samples(opts);
    if y.len() < need {
        return Err(DataError::TooFewSamples {
            file: data.file().to_string(),
            have: y.len(),
            need,
            after: if average_s > 0.0 {
                format!(" after averaging into {average_s} s bins")
            } else {
                String::new()
            },
            why: format!("method {}", opts.method),
        }
        .into());
    }
    let mut evidence = None;
    let mut length_scales = Vec::new();
    let mut settings_evaluated = 0;
    let mut width = 0.0;
    let mut basis = None;
    let rbf: Rbf64 = match opts.method {
        Method::Bayes => {
            let bo = BayesOptions {
                linear: opts.linear,
                centers: opts.centers,
                seed: opts.seed,
            };
            let offered = cubic.as_ref().map(|c| c.rows.as_slice());
            let f =
                bayes::fit_offering_cubic(&x, &y, offered, &bo).ok_or(TrainError::FitFailed {
                    method: "bayes",
                    what: "the evidence iteration failed on every setting",
                })?;
            if let (Basis::Cubic, Some(c)) = (f.basis, cubic) {
                spec = c.spec;
                ranges.extend(c.ranges);
            }
            basis = Some((f.basis, f.other_basis_log_evidence));
            evidence = Some(f.evidence);
            length_scales = f.length_scales;
            settings_evaluated = f.evaluated;
            width = f.width;
            f.rbf
        }
        Method::Mse => {
            let f = crate::mse::fit_selecting(&x, &y, centers, opts.seed, opts.select)?;
            if f.centers.len() < centers {
                warnings.push(format!(
                    "{} of the {centers} centers asked for: every further candidate was a \
                     combination of those chosen, or the error was used up",
                    f.centers.len()
                ));
            }
            f
        }
        Method::Gradient => {
            let f = crate::gradient::fit_with_progress(
                &x,
                &y,
                centers,
                opts.seed,
                opts.iterations,
                progress,
            )?;
            progress.start("measuring the fit", 0, crate::progress::Unit::Iterations);
            f
        }
        Method::Poly3 => crate::poly3::fit(&x, &y)?,
    };
    if width == 0.0 {
        width = rbf.gamma.first().map_or(0.0, |g| (0.5 / g).sqrt());
    }
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
        reference_value: reference_value.map(|v| v as f32),
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
    // Measure through the decoded blob, as it will fly.
    let bytes = model.to_bytes()?;
    let decoded = crate::blob_io::decode(std::path::Path::new("<new model>"), &bytes)?;
    let run = metrics::run_model(
        &decoded,
        &data,
        &Roles::of_model(&decoded),
        None,
        opts.gap_s,
    )?;
    let train = metrics::report(&run, REPORT_BIN_S);
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
    let blob_bytes = final_bytes.len();
    let summary = FitSummary {
        method: opts.method,
        signals: model.spec.signals.clone(),
        features: model.spec.features.clone(),
        centers: rbf.centers.len(),
        width,
        length_scales,
        linear: rbf.linear.clone(),
        evidence,
        settings_evaluated,
        select: (opts.method == Method::Mse).then_some(opts.select),
        basis: basis.map(|b| b.0),
        other_basis_log_evidence: basis.and_then(|b| b.1),
        train_rows: data.len(),
        train_bins: y.len(),
        average_s,
        reference_value,
        train,
        warnings,
        blob_bytes,
    };
    Ok(Fitted { model, summary })
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
