//! Figures of merit, always measured by running the *decoded blob* through the core's f32
//! [`Channel`](tcomp_core::Channel) — what flies is what is measured.
//!
//! Why one module: `fit` (training residual), `eval` and the tests must report the same numbers the
//! same way. Error = target − reference; residual = compensated − reference. Reported: raw and
//! residual std, improvement %, max |residual|, the seed paper's MSD (mean square) before and after,
//! the same on non-overlapping bin means starting at the first sample (error and correction binned
//! alike, because bias instability makes 1 Hz samples strongly correlated), and a per-segment table of
//! holds, heating and cooling ramps detected from the temperature rate.

use crate::dataset::{Dataset, stretch_starts};

pub mod online;
pub(crate) mod step;
#[cfg(test)]
mod two_pass;
use crate::error::TrainError;
use serde::Serialize;
use tcomp_core::{HostModel, Model};

/// Which columns play which role when evaluating.
#[derive(Clone, Debug, Default)]
pub struct Roles {
    /// Time column.
    pub time: String,
    /// Sensor output column.
    pub target: String,
    /// Reference column.
    pub reference: Option<String>,
    /// Constant reference (used when there is no reference column).
    pub reference_value: Option<f64>,
    /// Time of power-on on the time column (`warmup` counts from it); `None`: the first row.
    pub power_on_s: Option<f64>,
}

impl Roles {
    /// The roles stored in a model blob.
    pub fn of_model(model: &HostModel<'_>) -> Self {
        let c = &model.meta.columns;
        Self {
            time: c.time.to_string(),
            target: c.target.to_string(),
            reference: (!c.reference.is_empty()).then(|| c.reference.to_string()),
            reference_value: c.reference_value.map(f64::from),
            power_on_s: None,
        }
    }

    /// The reference series for `data` (a column, a constant, or an error when neither is given).
    pub fn reference_series(&self, data: &Dataset) -> Result<Vec<f64>, TrainError> {
        match (&self.reference, self.reference_value) {
            (Some(col), _) => Ok(data.column(col)?.to_vec()),
            (None, Some(v)) => Ok(vec![crate::options::REFERENCE_VALUE.check(v)?; data.len()]),
            (None, None) => Err(TrainError::Missing {
                what: "reference",
                hint: "--reference COL or --reference-value X",
            }),
        }
    }
}

/// A model run over a dataset.
#[derive(Clone, Debug, Default)]
pub struct Run {
    /// Time (s).
    pub time: Vec<f64>,
    /// target − reference.
    pub error: Vec<f64>,
    /// compensated − reference.
    pub residual: Vec<f64>,
    /// Temperature used for segment detection.
    pub temperature: Vec<f64>,
    /// Samples flagged out of the trained range.
    pub out_of_range: usize,
    /// Samples flagged as input or model faults.
    pub faults: usize,
    /// Gaps in the record (the feature state carried across them, or restarted).
    pub gaps: usize,
    /// Those of the gaps that restarted the feature state (longer than 5× the program's longest
    /// time constant), as `(row, gap length s)`.
    pub restarted: Vec<(usize, f64)>,
}

impl Run {
    /// The rows with `lo ≤ time < hi`: a block of a run scored after the model ran over the whole
    /// run (its state continuous). The flag and gap counts stay the whole run's.
    pub fn window(self, lo: f64, hi: f64) -> Run {
        let keep: Vec<bool> = self.time.iter().map(|&t| t >= lo && t < hi).collect();
        let pick = |v: Vec<f64>| -> Vec<f64> {
            v.into_iter()
                .zip(&keep)
                .filter_map(|(x, &k)| k.then_some(x))
                .collect()
        };
        Run {
            time: pick(self.time),
            error: pick(self.error),
            residual: pick(self.residual),
            temperature: pick(self.temperature),
            ..self
        }
    }
}

/// Runs the model through a core [`Channel`](tcomp_core::Channel) over `data`, carrying the feature state across gaps
/// as the board does across missed periods (see [`crate::features`]). `temperature` names the
/// column used for segment detection (default: the program's first input).
///
/// A model of at most [`crate::features::FLIGHT_FEATURES`] features runs in the firmware's
/// feature capacity (re-decoded from its own blob into 4-feature types): it is the code path that
/// flies, and it does half the work of the host's 8-wide types. The two give the same numbers —
/// features past `n_features` are exact zeros, so they add exact zeros — which
/// `sim_accuracy`'s `narrow_and_wide_runs_agree` checks.
pub fn run_model(
    model: &HostModel<'_>,
    data: &Dataset,
    roles: &Roles,
    temperature: Option<&str>,
    gap_s: Option<f64>,
) -> Result<Run, TrainError> {
    run_rows(model, data, roles, temperature, gap_s, data.len())
}

/// [`run_model`] scored on the rows with `lo ≤ time < hi` only, as [`Run::window`] of the whole
/// run gives them: the model runs from the first row (its state continuous) and stops after the
/// last row before `hi`. The model is causal and the gaps are found over the whole time column, so
/// those rows' residuals are the whole run's, bit for bit; the flag counts are those of the rows
/// run. For a block of a run scored many times (the diagnosis's held-out refits).
pub fn run_model_window(
    model: &HostModel<'_>,
    data: &Dataset,
    roles: &Roles,
    temperature: Option<&str>,
    gap_s: Option<f64>,
    (lo, hi): (f64, f64),
) -> Result<Run, TrainError> {
    let time = data.time(&roles.time)?;
    let until = time.iter().rposition(|&t| t < hi).map_or(0, |i| i + 1);
    Ok(run_rows(model, data, roles, temperature, gap_s, until)?.window(lo, hi))
}

/// [`run_model`] over the first `until` rows (the gaps found over all of them).
fn run_rows(
    model: &HostModel<'_>,
    data: &Dataset,
    roles: &Roles,
    temperature: Option<&str>,
    gap_s: Option<f64>,
    until: usize,
) -> Result<Run, TrainError> {
    /// [`run_until`] with its arguments, for [`step::in_flight_capacity`].
    struct RunAt<'d> {
        data: &'d Dataset,
        roles: &'d Roles,
        temperature: Option<&'d str>,
        gap_s: Option<f64>,
        until: usize,
    }
    impl step::AtCapacity for RunAt<'_> {
        type Output = Result<Run, TrainError>;
        fn run<const C2: usize, const F2: usize, const N2: usize>(
            self,
            model: &Model<'_, C2, F2, N2>,
        ) -> Self::Output {
            run_until(
                model,
                self.data,
                self.roles,
                self.temperature,
                self.gap_s,
                self.until,
            )
        }
    }
    step::in_flight_capacity(
        model,
        RunAt {
            data,
            roles,
            temperature,
            gap_s,
            until,
        },
    )
}

/// [`run_model`] in the types `model` was decoded into, whatever their capacity.
pub fn run_at_capacity<const C2: usize, const F2: usize, const N2: usize>(
    model: &Model<'_, C2, F2, N2>,
    data: &Dataset,
    roles: &Roles,
    temperature: Option<&str>,
    gap_s: Option<f64>,
) -> Result<Run, TrainError> {
    run_until(model, data, roles, temperature, gap_s, data.len())
}

/// [`run_at_capacity`] over the first `until` rows of `data`, the gaps found over all of them.
fn run_until<const C2: usize, const F2: usize, const N2: usize>(
    model: &Model<'_, C2, F2, N2>,
    data: &Dataset,
    roles: &Roles,
    temperature: Option<&str>,
    gap_s: Option<f64>,
    until: usize,
) -> Result<Run, TrainError> {
    let time = data.time(&roles.time)?;
    let target = data.column(&roles.target)?;
    let reference = roles.reference_series(data)?;
    let cols = crate::features::input_columns(&model.program, data)?;
    let temp_name = temperature
        .map(str::to_string)
        .or_else(|| model.program.inputs.first().map(|s| s.to_string()));
    let temp = match &temp_name {
        Some(n) => data.column(n)?.to_vec(),
        None => vec![0.0; data.len()],
    };
    let starts = stretch_starts(time, gap_s);
    let mut stepper = step::Stepper::new(model);
    stepper.set_time_on(crate::features::time_on_s(time, roles.power_on_s)? as f32);
    let mut inputs = vec![0.0f32; cols.len()];
    let until = until.min(time.len());
    let mut temp = temp;
    temp.truncate(until);
    let mut run = Run {
        time: time.get(..until).unwrap_or(time).to_vec(),
        temperature: temp,
        gaps: starts.len().saturating_sub(1),
        restarted: crate::features::restarting_gaps(&model.program, time, &starts),
        ..Run::default()
    };
    let mut next = starts.iter().peekable();
    for i in 0..until {
        let gap = next.next_if(|&&s| s == i).is_some();
        for (v, c) in inputs.iter_mut().zip(&cols) {
            *v = c.get(i).copied().unwrap_or(f64::NAN) as f32;
        }
        let t = time.get(i).copied().unwrap_or(0.0);
        let raw = target.get(i).copied().unwrap_or(f64::NAN);
        let r = reference.get(i).copied().unwrap_or(f64::NAN);
        run.error.push(raw - r);
        run.residual.push(stepper.step(t, gap, &inputs, raw, r));
    }
    run.out_of_range = stepper.out_of_range;
    run.faults = stepper.faults;
    Ok(run)
}

/// Population standard deviation.
pub fn std(v: &[f64]) -> f64 {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n).sqrt()
}

fn improvement(raw: f64, res: f64) -> f64 {
    if raw > 0.0 {
        100.0 * (1.0 - res / raw)
    } else {
        0.0
    }
}

/// Figures on bin means.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Binned {
    /// Bin length (s).
    pub seconds: f64,
    /// Number of bins.
    pub bins: usize,
    /// Std of binned error.
    pub raw_std: f64,
    /// Std of binned residual.
    pub residual_std: f64,
    /// Improvement (%).
    pub improvement_pct: f64,
}

/// One hold or ramp.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SegmentStats {
    /// "hold", "heating" or "cooling".
    pub kind: String,
    /// Start time (s).
    pub start_s: f64,
    /// End time (s).
    pub end_s: f64,
    /// Samples.
    pub samples: usize,
    /// Mean temperature rate (°/min).
    pub rate_per_min: f64,
    /// Std of the error.
    pub raw_std: f64,
    /// Std of the residual.
    pub residual_std: f64,
}

/// Everything `tcomp eval` reports.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EvalReport {
    /// Samples evaluated.
    pub samples: usize,
    /// Std of target − reference.
    pub raw_std: f64,
    /// Std of compensated − reference.
    pub residual_std: f64,
    /// 100·(1 − residual_std/raw_std).
    pub improvement_pct: f64,
    /// Root mean square of the error (counts a constant offset, unlike the std).
    pub raw_rms: f64,
    /// Root mean square of the residual.
    pub residual_rms: f64,
    /// Largest |residual|.
    pub max_abs_residual: f64,
    /// Mean square of the error before compensation.
    pub msd_before: f64,
    /// Mean square of the residual.
    pub msd_after: f64,
    /// Figures on bin means.
    pub binned: Binned,
    /// Per-segment figures.
    pub segments: Vec<SegmentStats>,
    /// Percentage of samples flagged out of the trained range.
    pub out_of_range_pct: f64,
    /// Samples flagged as input faults (and model faults: a non-finite correction).
    pub input_faults: usize,
    /// Gaps in the record (the feature state carried across them, or restarted).
    pub gaps: usize,
    /// Gaps that restarted the feature state (longer than 5× the program's longest time constant).
    pub gaps_restarted: usize,
    /// What the loading policies did to the file ([`crate::Dataset::notes`]); printed as notes,
    /// not part of the JSON figures.
    #[serde(skip)]
    pub notes: Vec<String>,
}

/// Computes the report of a run with bins of `bin_s` seconds, by feeding its rows in order to the
/// [`online::Accumulator`] that the streaming evaluator feeds too.
pub fn report(run: &Run, bin_s: f64) -> EvalReport {
    let mut acc = online::Accumulator::new(bin_s);
    for (i, &t) in run.time.iter().enumerate() {
        let at = |v: &[f64]| v.get(i).copied().unwrap_or(0.0);
        acc.push(t, at(&run.error), at(&run.residual), at(&run.temperature));
    }
    let flags = online::Flags {
        out_of_range: run.out_of_range,
        faults: run.faults,
        gaps: run.gaps,
        restarted: run.restarted.len(),
    };
    acc.finish(crate::dataset::median_step(&run.time), flags)
}

/// Threshold between a hold and a ramp, in temperature units per minute.
pub const HOLD_RATE_PER_MIN: f64 = 0.1;

/// Splits a run into holds, heating and cooling ramps from the temperature rate (60 s bins, central
/// differences; runs shorter than 5 bins are merged into the previous one).
pub fn segment_table(run: &Run) -> Vec<SegmentStats> {
    report(run, 60.0).segments
}
