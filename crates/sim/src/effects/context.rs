//! What an effect reads: the names it may refer to (for validation and expression text) and one
//! recorded row (for its streaming state).

use tcomp_core::SensorKind;

use crate::error::{Error, Result};

/// How an effect's input temperature is read from a row.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Input {
    Mean,
    Column(usize),
}

/// One output row's inputs (recorded, rounded values).
#[derive(Debug, Clone, Copy)]
pub(crate) struct RowInputs<'a> {
    pub time_s: f64,
    pub therms: &'a [f64],
    pub supply_v: f64,
}

impl RowInputs<'_> {
    /// The value of `input` in this row.
    pub fn read(&self, input: Input) -> f64 {
        match input {
            Input::Column(i) => self.therm(i),
            Input::Mean => {
                let n = self.therms.len().max(1) as f64;
                self.therms.iter().sum::<f64>() / n
            }
        }
    }

    /// Thermometer `i` (NaN if there is none: a validated effect never asks for it).
    pub fn therm(&self, i: usize) -> f64 {
        self.therms.get(i).copied().unwrap_or(f64::NAN)
    }
}

/// Resolves the names the effects refer to, for one sensor.
#[derive(Debug, Clone)]
pub(crate) struct Context<'a> {
    pub sensor: SensorKind,
    pub therm_names: &'a [String],
    pub unit: &'a str,
}

impl Context<'_> {
    /// The input `name` (`"T"` or a thermometer column); an error names `field`.
    pub fn input(&self, name: &str, field: &str) -> Result<Input> {
        if name == "T" {
            return Ok(if self.therm_names.len() == 1 {
                Input::Column(0)
            } else {
                Input::Mean
            });
        }
        self.therm_names
            .iter()
            .position(|n| n == name)
            .map(Input::Column)
            .ok_or_else(|| {
                Error::invalid(
                    field,
                    format!(
                        "unknown input \"{name}\" (use \"T\" or one of: {})",
                        self.therm_names.join(", ")
                    ),
                )
            })
    }

    /// The thermometer column `name`.
    pub fn column(&self, name: &str) -> Result<usize> {
        self.therm_names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| Error::invalid("effects", format!("no column {name}")))
    }

    /// Expression text of an input.
    pub fn input_expr(&self, name: &str) -> String {
        if name == "T" && self.therm_names.len() == 1 {
            self.therm_names.first().cloned().unwrap_or_default()
        } else {
            name.to_string()
        }
    }

    /// Named signals the expressions use (the RLG's `T`).
    pub fn signals(&self) -> Vec<(String, String)> {
        if self.therm_names.len() > 1 {
            vec![(
                "T".to_string(),
                tcomp_core::expr::mean(self.therm_names.iter().map(|n| tcomp_core::expr::name(n)))
                    .to_string(),
            )]
        } else {
            Vec::new()
        }
    }
}
