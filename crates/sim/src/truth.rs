//! The truth file: what was simulated, and the noise floor actually drawn.
//!
//! Why: downstream tools (fit, diagnose, demo, tests) need to know which effects are in a file, in
//! the core's expression language, and how low a residual can possibly go. Serialised as JSON
//! beside the CSV. [`evaluate`] computes an expression of the truth over a file's columns with the
//! core's own compiler and streaming evaluator, in f64: the check that the truth is exact uses the
//! very code that trains and flies, not a second implementation of the language.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use tcomp_core::lang::{FUNCTIONS, SYNTAX};
use tcomp_core::{ProgramBuilder, ProgramState};

use crate::error::{Error, Result};
use crate::writer::Table;

use crate::effects::EffectTruth;
use crate::noise::NoiseSpec;
use crate::profile::ResolvedSegment;
use crate::scenario::SensorKind;
use crate::thermal::ThermometerSpec;

/// Roles of the file's columns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Columns {
    /// Time column (`time_s`).
    pub time: String,
    /// Sensor output (`gyro_dph` or `accel_ug`).
    pub target: String,
    /// Reference column (`ref_dph` or `ref_ug`); error = target − reference.
    pub reference: String,
    /// Thermometer columns of the sensor.
    pub thermometers: Vec<String>,
    /// Chamber air temperature (`t_chamber_c`); not a sensor thermometer.
    pub chamber: String,
    /// Non-thermal inputs (`supply_v`).
    pub inputs: Vec<String>,
    /// Every column, in file order.
    pub all: Vec<String>,
}

/// The chamber profile as run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProfileTruth {
    /// Start temperature, °C.
    pub start_c: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Segments with absolute times.
    pub segments: Vec<ResolvedSegment>,
}

/// The minimal features a model needs to represent the whole bias.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrueFeatures {
    /// Named signals used by the features (`NAME = expr`), e.g. the RLG's `T`.
    pub signals: BTreeMap<String, String>,
    /// Feature expressions.
    pub features: Vec<String>,
}

/// The noise drawn, in output units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseTruth {
    /// Std of the drawn white noise at the output step.
    pub white_std_raw: f64,
    /// Std of the total drawn noise (white + bias instability + quantisation) at the output step.
    pub std_raw: f64,
    /// Std of the total drawn noise averaged over complete non-overlapping 100 s bins from the first
    /// sample.
    pub std_100s: f64,
    /// The same over 1000 s bins.
    pub std_1000s: f64,
    /// Number of complete 100 s bins.
    pub bins_100s: u64,
    /// Number of complete 1000 s bins.
    pub bins_1000s: u64,
    /// Mean of the drawn noise (bias-instability offset), output units.
    pub mean: f64,
    /// Std of the drawn Gauss–Markov bias instability at the output step.
    pub bias_instability_std: f64,
    /// Std of the quantisation error at the output step.
    pub quantisation_std: f64,
    /// Expected white std at the output step, from the specification.
    pub expected_white_std_raw: f64,
    /// Expected quantisation std at the output step, from the specification.
    pub expected_quantisation_std: f64,
    /// The specification.
    pub spec: NoiseSpec,
    /// Specification in the sensor's customary units (ARW °/√h or VRW µg/√Hz, BI, pulse weight).
    pub spec_customary: BTreeMap<String, f64>,
}

/// Everything known about one simulated run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Scenario name.
    pub scenario: String,
    /// Scenario description.
    pub description: String,
    /// Sensor kind.
    pub sensor: SensorKind,
    /// Output unit (`deg/h` or `ug`).
    pub unit: String,
    /// Seed.
    pub seed: u64,
    /// Internal sensor rate, Hz.
    pub rate_hz: f64,
    /// Output step, s.
    pub step_s: f64,
    /// Data rows in the file.
    pub rows: u64,
    /// Constant reference value, output units.
    pub reference_value: f64,
    /// Column roles.
    pub columns: Columns,
    /// Chamber profile.
    pub profile: ProfileTruth,
    /// Thermometer physics.
    pub thermal: Vec<ThermometerSpec>,
    /// Effects; the bias is the sum of their contributions.
    pub effects: Vec<EffectTruth>,
    /// Signals the effects' expressions use.
    pub signals: BTreeMap<String, String>,
    /// The minimal feature set.
    pub true_features: TrueFeatures,
    /// Std of the total bias over the run.
    pub bias_std: f64,
    /// Peak-to-peak of the total bias over the run.
    pub bias_p2p: f64,
    /// Noise drawn.
    pub noise: NoiseTruth,
    /// Discrete-time definitions of the operators the expressions were evaluated with.
    pub operators: BTreeMap<String, String>,
    /// Logger dropouts: stretches whose rows are missing from the file (the physics ran on).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dropouts: Vec<crate::dropout::Dropout>,
    /// How the effects relate to the columns.
    pub notes: Vec<String>,
}

/// The truth file of a preset or scenario file: shared facts plus one [`Truth`] per run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthFile {
    /// Preset or scenario name.
    pub name: String,
    /// Description.
    pub description: String,
    /// Sensor kind.
    pub sensor: SensorKind,
    /// Column roles (same in both files).
    pub columns: Columns,
    /// Effects of the training run (same coefficients in both).
    pub effects: Vec<EffectTruth>,
    /// The minimal feature set.
    pub true_features: TrueFeatures,
    /// Chamber profile of the training run (the verification run's is `verify.profile`).
    pub profile: ProfileTruth,
    /// Noise drawn in the training run (compare held-out residuals with `verify.noise`).
    pub noise: NoiseTruth,
    /// File names: `train`, `verify`.
    pub files: BTreeMap<String, String>,
    /// The training run.
    pub train: Truth,
    /// The verification run.
    pub verify: Truth,
}

/// Operations a truth expression may compile to (the host's capacity, above the firmware's).
const NODES: usize = 128;

fn expr_error(expr: &str, message: impl std::fmt::Display) -> Error {
    Error::Expr {
        expr: expr.to_string(),
        message: message.to_string(),
    }
}

/// Evaluates `expr` over every row of `table` with sample period `dt_s`, compiled and stepped by
/// the core in f64 (a step of the `time_s` column longer than 1.5 `dt_s`, a logger dropout, is a
/// gap the state is carried across); `signals` maps names to their defining expressions (which may use earlier
/// signals in name order). Every name must be a signal or a column of `table`.
pub fn evaluate(
    table: &Table,
    signals: &BTreeMap<String, String>,
    expr: &str,
    dt_s: f64,
) -> Result<Vec<f64>> {
    let mut b = ProgramBuilder::<NODES, 1, f64>::new();
    for (name, text) in signals {
        b.signal(name, text)
            .map_err(|e| expr_error(&format!("{name} = {text}"), e))?;
    }
    b.feature(expr).map_err(|e| expr_error(expr, e))?;
    let program = b.finish().map_err(|e| expr_error(expr, e))?;
    let columns = program
        .inputs
        .iter()
        .map(|name| {
            table.column(name).ok_or_else(|| {
                expr_error(
                    expr,
                    format!(
                        "unknown column or signal \"{name}\" (columns: {})",
                        table.names.join(", ")
                    ),
                )
            })
        })
        .collect::<Result<Vec<&[f64]>>>()?;
    let node = program.features.first().copied().unwrap_or(0) as usize;
    let rows = table.rows();
    let time = table.column("time_s");
    let mut state = ProgramState::<NODES, f64>::new();
    let mut inputs = vec![0.0; columns.len()];
    let mut out = Vec::with_capacity(rows);
    for r in 0..rows {
        for (slot, col) in inputs.iter_mut().zip(&columns) {
            *slot = col.get(r).copied().unwrap_or(f64::NAN);
        }
        // A step longer than one and a half rows is a logger dropout: carried across, as the
        // trainer does.
        let gap = r.checked_sub(1).and_then(|p| {
            let t = time?;
            Some(t.get(r)? - t.get(p)?).filter(|&d| d > 1.5 * dt_s)
        });
        match gap {
            Some(d) => state.step_gap(&program, &inputs, d),
            None => state.step(&program, &inputs, dt_s),
        }
        .map_err(|e| expr_error(expr, format!("row {r}: {e}")))?;
        out.push(state.value(node));
    }
    Ok(out)
}

/// The language's operators and their exact definitions, from the core's table, for the truth
/// file (`operators`).
pub fn operator_definitions() -> BTreeMap<String, String> {
    let syntax = SYNTAX
        .iter()
        .map(|s| (s.syntax.replace('`', ""), s.definition.to_string()));
    let functions = FUNCTIONS.iter().map(|f| {
        let mut call = String::new();
        // Writing into a String cannot fail.
        let _ = f.write_syntax(&mut call);
        (call, f.definition.to_string())
    });
    syntax.chain(functions).collect()
}
