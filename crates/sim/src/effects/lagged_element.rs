//! `c·(lag(T, tau) − t0)`: a sensing element whose temperature lags its thermometer.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::{Input, RowInputs};
use super::text::{check_finite, check_pos, num};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use super::{default_input, default_t0, per_sensor};
use crate::error::Result;
use super::LagFilter as Lag;

/// `c·(lag(T, tau) − t0)`: a sensing element lagging its thermometer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaggedElement {
    /// Output units per °C.
    pub coefficient: f64,
    /// Time constant of the element behind its thermometer, s.
    pub tau_s: f64,
    /// Reference temperature, °C.
    #[serde(default = "default_t0")]
    pub t0_c: f64,
    /// Temperature input.
    #[serde(default = "default_input")]
    pub input: String,
}

struct State {
    input: Input,
    coefficient: f64,
    t0: f64,
    lag: Lag,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        self.coefficient * (self.lag.step(row.read(self.input), dt) - self.t0)
    }
}

/// `lag(x, tau)`.
fn expression(x: &str, tau_s: f64) -> String {
    tcomp_core::expr::lag(tcomp_core::expr::name(x), tau_s).to_string()
}

impl EffectModel for LaggedElement {
    const KIND: EffectKind = EffectKind::LaggedElement;

    fn default_for(sensor: SensorKind) -> Self {
        LaggedElement {
            coefficient: per_sensor(sensor, 0.005, 8.0, 0.008),
            tau_s: 2400.0,
            t0_c: 20.0,
            input: default_input(),
        }
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        check_pos(self.tau_s, format!("{at}.tau_s"))?;
        check_finite(self.t0_c, format!("{at}.t0_c"))?;
        ctx.input(&self.input, &format!("{at}.input"))?;
        Ok(())
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            input: ctx.input(&self.input, "input")?,
            coefficient: self.coefficient,
            t0: self.t0_c,
            lag: Lag::new(self.tau_s),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let x = ctx.input_expr(&self.input);
        Terms::single(
            self.coefficient,
            format!("{} per degC", ctx.unit),
            expression(&x, self.tau_s),
            format!(
                "sensing element lagging its thermometer {x}, tau = {} s",
                num(self.tau_s)
            ),
        )
        .with_offset(-self.coefficient * self.t0_c)
        .into_truth(Self::KIND)
    }
}
