//! One JSON vocabulary for every command's `--json`: the same names for the same figures, what
//! the output is about in one [`Subject`], `null` where there is no data, and one sign for changes.
//!
//! Why: each command printed its own library struct, so `fit` named no target, `eval` no model or
//! file, `report` and `demo` printed no JSON at all, an empty set of bins came out as `-0.0`, and
//! "improvement" (positive when the residual fell) sat beside "change" (negative when it fell).
//! Here every output is an [`Output`]: `{"command": …, "subject": {…}, …its figures}`; the figures
//! of a run are a [`RunFigures`] wherever they appear (eval, compare's `a` and `b`, fit's `train`,
//! report's and demo's models); a change is `change_pct = 100·(after/before − 1)`, negative when
//! the residual fell (`improvement_pct`, its negation, stays for the scripts that read it).
//!
//! The vocabulary is written down once as a JSON Schema, `schema/tcomp-output.schema.json`, and
//! `host-tools/tests/json_schema.rs` validates every command's real output against it.

use crate::render::num;
use serde::Serialize;
use tcomp_train::EvalReport;
use tcomp_train::metrics::SegmentStats;

/// What an output is about.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Subject {
    /// The model blobs, in the order the command took them (compare: A then B; demo: before,
    /// after).
    pub models: Vec<String>,
    /// The target column: the channel.
    pub target: Option<String>,
    /// The output unit: the model's, else the one the target column's name carries.
    pub unit: Option<String>,
    /// The data file the figures are measured on.
    pub data: Option<String>,
    /// The held-out file, when one was given.
    pub verify: Option<String>,
}

impl Subject {
    /// A subject naming `models`, `target`, the unit (`unit`, else the target's) and `data`.
    pub fn new(models: Vec<String>, target: &str, unit: &str, data: &std::path::Path) -> Self {
        let unit = num::unit_or_column(unit, target);
        Self {
            models,
            target: (!target.is_empty()).then(|| target.to_string()),
            unit: (!unit.is_empty()).then_some(unit),
            data: Some(data.display().to_string()),
            verify: None,
        }
    }
}

/// Every command's JSON: the command, its subject, then its own fields.
#[derive(Serialize)]
pub struct Output<'a, T: Serialize> {
    /// The subcommand (`fit`, `eval`, …).
    pub command: &'static str,
    /// What the output is about.
    pub subject: &'a Subject,
    /// The command's fields, at the top level.
    #[serde(flatten)]
    pub body: &'a T,
}

/// Prints `body` as the JSON of `command` about `subject` (strings from blobs escaped as
/// everywhere: see [`super::printable::json`]).
pub fn print<T: Serialize>(
    command: &'static str,
    subject: &Subject,
    body: &T,
) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(&Output {
        command,
        subject,
        body,
    })?;
    outln!("{}", super::printable::json(&text));
    Ok(())
}

/// A figure, or `None` when there was no data to measure it on.
fn figure(v: f64, has_data: bool) -> Option<f64> {
    (has_data && v.is_finite()).then_some(v + 0.0)
}

/// `change_pct` of a residual from `before` to `after` (negative when it fell).
pub fn change(before: Option<f64>, after: Option<f64>) -> Option<f64> {
    num::change_pct(before?, after?)
}

/// Figures on bin means.
#[derive(Clone, Debug, Serialize)]
pub struct BinnedFigures {
    /// Bin length (s).
    pub seconds: f64,
    /// Bins that hold data.
    pub bins: usize,
    /// Std of the binned error (`null` with fewer than two bins).
    pub raw_std: Option<f64>,
    /// Std of the binned residual.
    pub residual_std: Option<f64>,
    /// Change from `raw_std` to `residual_std` (%; negative when the residual is smaller).
    pub change_pct: Option<f64>,
    /// `-change_pct`.
    pub improvement_pct: Option<f64>,
}

/// The figures of one model over one run.
#[derive(Clone, Debug, Serialize)]
pub struct RunFigures {
    /// Samples evaluated.
    pub samples: usize,
    /// Std of the error (target − reference).
    pub raw_std: Option<f64>,
    /// Std of the residual (compensated − reference).
    pub residual_std: Option<f64>,
    /// Change from `raw_std` to `residual_std` (%; negative when the residual is smaller).
    pub change_pct: Option<f64>,
    /// `-change_pct`.
    pub improvement_pct: Option<f64>,
    /// RMS of the error (counts a constant offset).
    pub raw_rms: Option<f64>,
    /// RMS of the residual.
    pub residual_rms: Option<f64>,
    /// Largest |residual|.
    pub max_abs_residual: Option<f64>,
    /// Mean square of the error.
    pub msd_before: Option<f64>,
    /// Mean square of the residual.
    pub msd_after: Option<f64>,
    /// Figures on bin means.
    pub binned: BinnedFigures,
    /// Holds and ramps.
    pub segments: Vec<SegmentStats>,
    /// Samples flagged out of the trained range (%).
    pub out_of_range_pct: Option<f64>,
    /// Samples flagged as input or model faults.
    pub input_faults: usize,
    /// Gaps in the run (the feature state carried across).
    pub gaps: usize,
    /// Gaps long enough that the feature state restarted.
    pub gaps_restarted: usize,
}

impl From<&EvalReport> for RunFigures {
    fn from(r: &EvalReport) -> Self {
        let any = r.samples > 0;
        let (raw, res) = (figure(r.raw_std, any), figure(r.residual_std, any));
        let binned = r.binned.bins > 1;
        let (braw, bres) = (
            figure(r.binned.raw_std, binned),
            figure(r.binned.residual_std, binned),
        );
        let (c, bc) = (change(raw, res), change(braw, bres));
        Self {
            samples: r.samples,
            raw_std: raw,
            residual_std: res,
            change_pct: c,
            improvement_pct: c.map(|v| -v + 0.0),
            raw_rms: figure(r.raw_rms, any),
            residual_rms: figure(r.residual_rms, any),
            max_abs_residual: figure(r.max_abs_residual, any),
            msd_before: figure(r.msd_before, any),
            msd_after: figure(r.msd_after, any),
            binned: BinnedFigures {
                seconds: r.binned.seconds,
                bins: r.binned.bins,
                raw_std: braw,
                residual_std: bres,
                change_pct: bc,
                improvement_pct: bc.map(|v| -v + 0.0),
            },
            segments: r.segments.clone(),
            out_of_range_pct: figure(r.out_of_range_pct, any),
            input_faults: r.input_faults,
            gaps: r.gaps,
            gaps_restarted: r.gaps_restarted,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_bins_is_null_not_minus_zero() {
        let mut r = EvalReport {
            samples: 10,
            raw_std: 2.0,
            residual_std: 1.0,
            ..EvalReport::default()
        };
        r.binned.raw_std = -0.0;
        r.binned.residual_std = -0.0;
        let f = RunFigures::from(&r);
        assert_eq!(f.binned.raw_std, None);
        assert_eq!(f.binned.change_pct, None);
        assert_eq!(f.change_pct, Some(-50.0));
        assert_eq!(f.improvement_pct, Some(50.0));
        let v = serde_json::to_value(&f).ok();
        let text = v.map(|v| v.to_string()).unwrap_or_default();
        assert!(
            text.contains("\"raw_std\":null") && !text.contains("-0.0"),
            "{text}"
        );
    }
}
