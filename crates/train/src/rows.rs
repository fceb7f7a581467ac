//! From a dataset and fit options to the rows a method is fitted on ([`TrainingSet`]).
//!
//! Why apart from [`crate::train`]: this is everything the methods share before they differ —
//! select the window, compute the error against the reference, find the gaps, refuse a fit over
//! the memory budget, let the method rewrite the program, run the core's feature program over
//! every row, refuse constant or collinear features, record the ranges and average into bins —
//! and benchmarks reach it alone through [`training_rows`].

use crate::binning::{adaptive_bin, bin_mean, bins};
use crate::dataset::{DataError, Dataset, stretch_starts};
use crate::error::TrainError;
use crate::features::{self, FeatureSpec};
use crate::fit_options::FitOptions;
use crate::method::{FitMethod, TrainingSet};
use crate::metrics::Roles;
use crate::options;
use tcomp_core::{FeatureRange, Program};

/// Default averaging bin before fitting (s), shortened to leave at least [`MIN_DEFAULT_BINS`] bins.
/// Bias instability makes 1 Hz samples strongly correlated, and the evidence computed as if they
/// were independent is overconfident: on the simulated QMA run, 30 s bins let the evidence pick 32
/// narrow centers that learn a spurious temperature × rate interaction (held-out residual 17× the
/// noise floor), while 120 s bins give 1.13× (measured). A 6-hour run still gives 180 bins.
pub const DEFAULT_AVERAGE_S: f64 = 120.0;
/// The default averaging is shortened on short runs so that at least this many bins remain.
pub const MIN_DEFAULT_BINS: f64 = 60.0;

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
    let mut warnings: Vec<String> = data.notes().to_vec();
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
            if !m.is_finite() {
                // A value the data gave, not an option the user gave: said as itself.
                return Err(DataError::Derived {
                    file: data.file().to_string(),
                    what: format!(
                        "the training mean of `{}` is not finite (its cells sum past the largest                          number, e.g. cells near 1e308): with no reference given it would be the                          reference; give --reference COL or --reference-value X",
                        crate::dataset::clip(&opts.target)
                    ),
                }
                .into());
            }
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
        power_on_s: opts.power_on_s,
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
            average: crate::num::exact(a),
            step: crate::num::exact(step),
        }),
        Some(a) => Ok(a),
        // Bursty records (short bursts minutes apart) leave most default bins empty.
        None => Ok(adaptive_bin(
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
    method.check(&opts.shared())
}

/// The feature columns of `spec` over the selected rows (one column per feature: a row per sample
/// would be 22,000 small allocations on a 6-hour run), and each feature's trained range.
fn feature_columns(
    program: &Program<'_, { features::N }, { features::F }>,
    data: &Dataset,
    time: &[f64],
    starts: &[usize],
    time_on_s: f64,
) -> Result<(Vec<Vec<f64>>, Vec<FeatureRange>), TrainError> {
    let nf = program.n_features();
    let feats = features::compute_from(program, data, time, starts, time_on_s)?;
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
pub(crate) fn check_samples(
    method: &dyn FitMethod,
    opts: &FitOptions,
    data: &Dataset,
    have: usize,
    after: String,
) -> Result<(), TrainError> {
    let need = method.min_samples(&opts.shared());
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
pub(crate) fn prepare(
    data: &Dataset,
    opts: &FitOptions,
) -> Result<(TrainingSet, Prepared), TrainError> {
    let method = opts.fitter();
    let Selection {
        data,
        error,
        reference_value,
        mut warnings,
    } = select(data, opts)?;
    let time = data.time(&opts.time)?;
    let starts = stretch_starts(time, opts.gap_s);
    let time_on_s = features::time_on_s(time, opts.power_on_s)?;
    check_options(opts, method)?;
    let average_s = averaging(opts, &data, time)?;
    let b = bins(time, average_s);
    check_memory(opts, time, b.len(), &data)?;
    let spec = method.program(&opts.shared(), &data, &starts, &mut warnings)?;
    // Compiled once, for the gaps' warnings and the feature columns.
    let (columns, ranges) = {
        let program = spec.program()?;
        gap_warnings(&program, &data, time, &starts, &mut warnings)?;
        feature_columns(&program, &data, time, &starts, time_on_s)?
    };
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
    let sub_x = sub_rows(&columns, &b);
    let set = TrainingSet {
        data,
        starts,
        time_on_s,
        bins: b,
        spec,
        ranges,
        x,
        sub_x,
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

/// Parts of each averaging bin whose feature means [`TrainingSet::sub_x`] keeps: a 120 s bin on a
/// 3 °C/min ramp spans 6 °C, its eighths 0.75 °C — finer than any knee a thermometer resolves in
/// time, at 8 rows per bin of memory.
pub const SUB_BINS: usize = 8;

/// Per bin, the feature means over up to [`SUB_BINS`] equal parts of its rows.
fn sub_rows(columns: &[Vec<f64>], bins: &[(usize, usize)]) -> Vec<Vec<Vec<f64>>> {
    bins.iter()
        .map(|&(a, b)| {
            let len = b.saturating_sub(a);
            let parts = SUB_BINS.min(len).max(1);
            (0..parts)
                .map(|p| {
                    let (lo, hi) = (a + p * len / parts, a + (p + 1) * len / parts);
                    columns
                        .iter()
                        .map(|c| {
                            let s = c.get(lo..hi).unwrap_or(&[]);
                            s.iter().sum::<f64>() / s.len().max(1) as f64
                        })
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// The gaps of the record: one line for those the feature state is carried across, one per gap
/// that restarts it (longer than 5× the program's longest time constant), naming the row.
fn gap_warnings(
    program: &Program<'_, { features::N }, { features::F }>,
    data: &Dataset,
    time: &[f64],
    starts: &[usize],
    warnings: &mut Vec<String>,
) -> Result<(), TrainError> {
    let gaps = starts.len().saturating_sub(1);
    if gaps == 0 {
        return Ok(());
    }
    let restarting = features::restarting_gaps(program, time, starts);
    let carried = gaps - restarting.len();
    if carried > 0 {
        warnings.push(format!(
            "{}: {carried} gap(s) in the record; feature state (rate, lag, hyst) carried across \
             them as for inputs moving linearly",
            data.file()
        ));
    }
    let longest = program.longest_time_constant();
    for (s, gap) in restarting {
        warnings.push(format!(
            "{}:{}: gap of {gap:.3} s, longer than 5 × the longest time constant ({longest} s); \
             feature state (rate, lag, hyst) reset there",
            data.file(),
            data.line(s)
        ));
    }
    Ok(())
}

/// What `prepare` resolved besides the training set.
pub(crate) struct Prepared {
    pub(crate) reference_value: Option<f64>,
    pub(crate) average_s: f64,
}

/// The estimated peak memory of a fit of `samples` training samples over `rows` rows with `opts`
/// (see [`crate::budget::estimate`]), bytes.
fn estimate(opts: &FitOptions, rows: usize, samples: usize) -> u64 {
    let method = opts.fitter();
    let shape = crate::budget::Shape {
        rows,
        samples,
        features: method.features_fitted(&opts.shared()),
        centers: opts.centers,
        threads: rayon::current_num_threads(),
    };
    crate::budget::estimate(&shape, method.memory(&shape))
}

/// Refuses a fit whose estimated memory is over `opts.memory_budget`, suggesting the shortest
/// averaging bin that would fit.
fn check_memory(
    opts: &FitOptions,
    time: &[f64],
    samples: usize,
    data: &Dataset,
) -> Result<(), TrainError> {
    use crate::budget::human;
    let need = estimate(opts, time.len(), samples);
    if need <= opts.memory_budget {
        return Ok(());
    }
    let step = crate::dataset::median_step(time);
    // From 1 s up: a bin that only just fits the budget would still be a fit of hours.
    let suggestion = [1.0, 2.0, 5.0, 10.0, 30.0, 60.0, 120.0, 300.0, 600.0]
        .into_iter()
        .filter(|&a| a >= step && a > opts.average_s.unwrap_or(0.0))
        .find(|&a| estimate(opts, time.len(), bins(time, a).len()) <= opts.memory_budget);
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
                    human(estimate(opts, time.len(), bins(time, a).len()))
                ),
                None => "; pick a shorter window with --from/--until".to_string(),
            },
        },
    )))
}
