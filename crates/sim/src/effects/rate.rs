//! `c·rate(T, window)`: a bias that follows how fast the temperature changes.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::{Input, RowInputs};
use super::text::{check_windowed, rate_expr};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use super::{default_input, default_window, per_sensor};
use crate::error::Result;
use super::{RATE_WINDOW_S, RateFilter as RateOp};

/// `c·rate(T, window)` with the rate in °C/min.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rate {
    /// Output units per °C/min.
    pub coefficient: f64,
    /// Window of the rate, s.
    #[serde(default = "default_window")]
    pub window_s: f64,
    /// Temperature input.
    #[serde(default = "default_input")]
    pub input: String,
}

struct State {
    input: Input,
    coefficient: f64,
    rate: RateOp,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        self.coefficient * self.rate.step(row.read(self.input), dt)
    }
}

impl EffectModel for Rate {
    const KIND: EffectKind = EffectKind::Rate;

    fn default_for(sensor: SensorKind) -> Self {
        Rate {
            coefficient: per_sensor(sensor, 0.15, 60.0, 0.3),
            window_s: RATE_WINDOW_S,
            input: default_input(),
        }
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        check_windowed(ctx, at, self.coefficient, self.window_s, &self.input)
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            input: ctx.input(&self.input, "input")?,
            coefficient: self.coefficient,
            rate: RateOp::new(self.window_s),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let x = ctx.input_expr(&self.input);
        Terms::single(
            self.coefficient,
            format!("{} per (degC/min)", ctx.unit),
            rate_expr(&x, self.window_s).to_string(),
            format!("rate of temperature d{x}/dt (degC/min)"),
        )
        .into_truth(Self::KIND)
    }
}
