//! Training features computed by the core's own feature program, exactly as the firmware does.
//!
//! Why: a second implementation of `rate`, `lag` or `hyst` on the host would train a model on
//! numbers the IMU never sees. Here the user's expressions are compiled by `tcomp_core`'s
//! [`ProgramBuilder`] and stepped sample by sample in f32 by its [`ProgramState`]. At a gap in the
//! record (a logger dropout) the state is carried across by the core, as the board carries it
//! across missed periods: `lag` and `rate` exactly for an input that moved linearly over the gap,
//! or restarted when the gap is longer than the filters remember ([`gap_resets`]; the caller warns).
//! `warmup`'s clock starts at the first row's time on ([`time_on_s`]). Averaging into
//! non-overlapping bins (the `--average` option) happens afterwards, on these features
//! ([`crate::binning`]).

use crate::dataset::Dataset;
use crate::error::TrainError;
use serde::{Deserialize, Serialize};
use tcomp_core::stream::gap_resets;
use tcomp_core::{HOST_FEATURES, HOST_NODES, Program, ProgramBuilder, ProgramState};

/// Features per model on the host.
pub const F: usize = HOST_FEATURES;
/// Program nodes on the host.
pub const N: usize = HOST_NODES;

pub use tcomp_core::{FLIGHT_FEATURES, FLIGHT_NODES};

/// The time bins lived here before they had a module of their own ([`crate::binning`]); the old
/// paths keep working.
pub use crate::binning::{adaptive_bin, bin_mean, bins};

/// Whether `spec` compiles into the firmware's program capacity. The trainer only adds features of
/// its own (the cubic basis of `bayes`) when it does; what the user asks for is theirs to size.
pub fn fits_flight(spec: &FeatureSpec) -> bool {
    let mut b = ProgramBuilder::<FLIGHT_NODES, FLIGHT_FEATURES>::new();
    spec.signals.iter().all(|s| b.line(s).is_ok())
        && spec.features.iter().all(|f| b.feature(f).is_ok())
        && b.finish().is_ok()
}

/// The source of a feature program: named signals (`NAME = EXPR`) and feature expressions.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FeatureSpec {
    /// Signal definitions, each `NAME = EXPR`, in order.
    #[serde(default)]
    pub signals: Vec<String>,
    /// Feature expressions.
    #[serde(default)]
    pub features: Vec<String>,
}

impl FeatureSpec {
    /// Compiles the program (it borrows the strings of `self`).
    pub fn program(&self) -> Result<Program<'_, N, F>, TrainError> {
        let mut b = ProgramBuilder::<N, F>::new();
        for s in &self.signals {
            if !s.contains('=') {
                return Err(TrainError::SignalSyntax { line: s.clone() });
            }
            b.line(s).map_err(|e| expr_error(s, &e))?;
        }
        if self.features.is_empty() {
            return Err(TrainError::NoFeatures);
        }
        for f in &self.features {
            b.feature(f).map_err(|e| expr_error(f, &e))?;
        }
        b.finish().map_err(|e| TrainError::Program {
            source: crate::error::Core(e),
        })
    }
}

fn expr_error(expr: &str, e: &tcomp_core::ParseError) -> TrainError {
    let col = e.column();
    TrainError::Expr {
        expr: expr.to_string(),
        caret: " ".repeat(col.saturating_sub(1)),
        source: crate::error::Core(*e),
    }
}

/// Input columns of a program, as f64 slices of the dataset (in program input order).
pub fn input_columns<'d, const N2: usize, const F2: usize>(
    program: &Program<'_, N2, F2>,
    data: &'d Dataset,
) -> Result<Vec<&'d [f64]>, TrainError> {
    program
        .inputs
        .iter()
        .map(|name| data.column(name).map_err(TrainError::from))
        .collect()
}

/// The time since power-on of the first row of `time` (s): 0, or its distance from `power_on_s`
/// (`--power-on`), which must not be after it.
pub fn time_on_s(time: &[f64], power_on_s: Option<f64>) -> Result<f64, TrainError> {
    let first = time.first().copied().unwrap_or(0.0);
    match power_on_s {
        None => Ok(0.0),
        Some(p) if p <= first => Ok(first - p),
        Some(p) => Err(TrainError::PowerOnAfterStart {
            power_on: crate::num::exact(p),
            first: crate::num::exact(first),
        }),
    }
}

/// The gaps among `stretch_starts` (row indices where a gap-free stretch starts, 0 first) across which
/// `program`'s filters restart rather than carry on, as `(row, gap length s)`: longer than 5× its
/// longest time constant (the core's [`gap_resets`]).
pub fn restarting_gaps<const N2: usize, const F2: usize>(
    program: &Program<'_, N2, F2>,
    time: &[f64],
    stretch_starts: &[usize],
) -> Vec<(usize, f64)> {
    stretch_starts
        .iter()
        .filter(|&&s| s > 0)
        .filter_map(|&s| {
            let gap = time.get(s)? - time.get(s - 1)?;
            gap_resets(program, gap as f32).then_some((s, gap))
        })
        .collect()
}

/// Runs `program` over every row of `data` (f32, the core's code), each entry of `stretch_starts`
/// but the first a gap the core carries the state across (see the module doc), `warmup`'s clock
/// starting at the first row; returns one feature vector per row.
pub fn compute(
    program: &Program<'_, N, F>,
    data: &Dataset,
    time: &[f64],
    stretch_starts: &[usize],
) -> Result<Vec<[f32; F]>, TrainError> {
    compute_from(program, data, time, stretch_starts, 0.0)
}

/// [`compute`] with `warmup`'s clock starting at `time_on_s` seconds since power-on on the first
/// row ([`time_on_s`]).
pub fn compute_from(
    program: &Program<'_, N, F>,
    data: &Dataset,
    time: &[f64],
    stretch_starts: &[usize],
    time_on_s: f64,
) -> Result<Vec<[f32; F]>, TrainError> {
    let cols = input_columns(program, data)?;
    let mut state = ProgramState::<N>::new();
    state.set_time_on(time_on_s as f32);
    let mut inputs = vec![0.0f32; cols.len()];
    let mut out = Vec::with_capacity(time.len());
    let mut next_stretch = stretch_starts.iter().peekable();
    for i in 0..time.len() {
        let gap = next_stretch.peek().is_some_and(|&&s| s == i);
        if gap {
            next_stretch.next();
        }
        for (v, c) in inputs.iter_mut().zip(&cols) {
            *v = c.get(i).copied().unwrap_or(f64::NAN) as f32;
        }
        let dt = if i == 0 {
            1.0
        } else {
            (time.get(i).copied().unwrap_or(0.0) - time.get(i - 1).copied().unwrap_or(0.0)) as f32
        };
        let mut x = [0.0f32; F];
        let stepped = if gap {
            state.step_gap(program, &inputs, dt)
        } else {
            state.step(program, &inputs, dt)
        };
        stepped
            .and_then(|()| state.features(program, &mut x))
            .map_err(|e| TrainError::Step {
                at: format!("{}:{}", data.file(), data.line(i)),
                message: describe_step_error(e, program),
                source: crate::error::Core(e),
            })?;
        out.push(x);
    }
    Ok(out)
}

/// A step error in the user's terms: features and inputs numbered from 1 and named by their
/// expression or column (the core's error counts from 0 and knows no names).
pub fn describe_step_error<const N2: usize, const F2: usize>(
    e: tcomp_core::StepError,
    program: &Program<'_, N2, F2>,
) -> String {
    use tcomp_core::StepError;
    match e {
        StepError::NonFiniteFeature { feature } => {
            let k = usize::from(feature);
            match program.feature_exprs.get(k) {
                Some(expr) => format!(
                    "feature {} `{}` is NaN or infinite here (this is the first such row; a \
                     division by zero or a logarithm of a non-positive value?)",
                    k + 1,
                    crate::dataset::clip(expr)
                ),
                None => format!("feature {} is NaN or infinite here", k + 1),
            }
        }
        StepError::NonFiniteInput { index } => {
            let k = usize::from(index);
            match program.inputs.get(k) {
                Some(name) => format!(
                    "input column `{}` is NaN or infinite here",
                    crate::dataset::clip(name)
                ),
                None => format!("input {} is NaN or infinite here", k + 1),
            }
        }
        StepError::MissingInput { index } => format!("input {} is missing", usize::from(index) + 1),
        other => other.to_string(),
    }
}
