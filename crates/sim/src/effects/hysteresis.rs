//! `c·hyst(rate(T, window), threshold)`: a bias that differs after heating and after cooling.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::{Input, RowInputs};
use super::text::{check_finite, check_pos, num, rate_expr};
use tcomp_core::expr;
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use super::{default_input, default_window, per_sensor};
use crate::error::Result;
use super::{HystFilter as Hyst, RATE_WINDOW_S, RateFilter as Rate};

fn default_threshold() -> f64 {
    0.05
}

/// `c·hyst(rate(T, window), threshold)`: +c after heating, −c after cooling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hysteresis {
    /// Half the heating/cooling difference, output units.
    pub coefficient: f64,
    /// Rate threshold, °C/min.
    #[serde(default = "default_threshold")]
    pub threshold_c_per_min: f64,
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
    hyst: Hyst,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        self.coefficient * self.hyst.step(self.rate.step(row.read(self.input), dt))
    }
}

/// `hyst(rate(x), threshold)`.
fn expression(x: &str, window_s: f64, threshold: f64) -> String {
    expr::hyst(rate_expr(x, window_s), threshold).to_string()
}

impl EffectModel for Hysteresis {
    const KIND: EffectKind = EffectKind::Hysteresis;

    fn default_for(sensor: SensorKind) -> Self {
        Hysteresis {
            coefficient: per_sensor(sensor, 0.08, 50.0, 0.1),
            threshold_c_per_min: 0.05,
            window_s: RATE_WINDOW_S,
            input: default_input(),
        }
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        check_pos(
            self.threshold_c_per_min,
            format!("{at}.threshold_c_per_min"),
        )?;
        check_pos(self.window_s, format!("{at}.window_s"))?;
        ctx.input(&self.input, &format!("{at}.input"))?;
        Ok(())
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            input: ctx.input(&self.input, "input")?,
            coefficient: self.coefficient,
            rate: Rate::new(self.window_s),
            hyst: Hyst::new(self.threshold_c_per_min),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let x = ctx.input_expr(&self.input);
        Terms::single(
            self.coefficient,
            ctx.unit.to_string(),
            expression(&x, self.window_s, self.threshold_c_per_min),
            format!(
                "heating/cooling hysteresis: +c after d{x}/dt rose above {th} degC/min, -c after it fell below -{th}",
                th = num(self.threshold_c_per_min)
            ),
        )
        .into_truth(Self::KIND)
    }
}
