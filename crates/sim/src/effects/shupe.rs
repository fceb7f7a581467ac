//! `c·T·rate(T, window)`: the Shupe-type product of a fiber coil's temperature and its rate.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::{Input, RowInputs};
use super::text::{check_windowed, rate_expr};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use super::{default_input, default_window, per_sensor};
use crate::error::Result;
use super::{RATE_WINDOW_S, RateFilter as Rate};

/// `c·T·rate(T, window)` (Shupe-type product).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shupe {
    /// Output units per °C·°C/min.
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
    rate: Rate,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        let t = row.read(self.input);
        self.coefficient * t * self.rate.step(t, dt)
    }
}

/// `x * rate(x)`.
fn expression(x: &str, window_s: f64) -> String {
    (tcomp_core::expr::name(x) * rate_expr(x, window_s)).to_string()
}

impl EffectModel for Shupe {
    const KIND: EffectKind = EffectKind::Shupe;

    fn default_for(sensor: SensorKind) -> Self {
        Shupe {
            coefficient: per_sensor(sensor, 0.006, 3.0, 0.02),
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
            rate: Rate::new(self.window_s),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let x = ctx.input_expr(&self.input);
        Terms::single(
            self.coefficient,
            format!("{} per (degC * degC/min)", ctx.unit),
            expression(&x, self.window_s),
            format!("Shupe-type product {x} * d{x}/dt"),
        )
        .into_truth(Self::KIND)
    }
}
