//! `c·rate(a − b, window)`: a bias that follows how fast a thermal gradient changes — a gradient
//! building up across the block strains the sensor while heat flows, more than the gradient
//! itself once it has settled.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::RowInputs;
use super::pair::{Pair, default_between, gradient_expr};
use super::text::{check_finite, check_pos, num};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms, default_window};
use super::{RATE_WINDOW_S, RateFilter as RateOp};
use crate::error::Result;

/// `c·rate(a − b, window)`, the rate in °C/min (RLG: two of its thermometers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradientRate {
    /// Output units per °C/min of the gradient's rate.
    pub coefficient: f64,
    /// Window of the rate, s.
    #[serde(default = "default_window")]
    pub window_s: f64,
    /// The gradient's thermometers `[a, b]`.
    #[serde(default = "default_between")]
    pub between: [String; 2],
}

struct State {
    pair: Pair,
    coefficient: f64,
    rate: RateOp,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        self.coefficient * self.rate.step(self.pair.value(row), dt)
    }
}

impl EffectModel for GradientRate {
    const KIND: EffectKind = EffectKind::GradientRate;

    fn default_for(_sensor: SensorKind) -> Self {
        GradientRate {
            coefficient: 3.0,
            window_s: RATE_WINDOW_S,
            between: default_between(),
        }
    }

    fn applies_to(sensor: SensorKind) -> bool {
        sensor == SensorKind::Rlg
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        check_pos(self.window_s, format!("{at}.window_s"))?;
        Pair::resolve(ctx, &self.between, at).map(|_| ())
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            pair: Pair::resolve(ctx, &self.between, "effects")?,
            coefficient: self.coefficient,
            rate: RateOp::new(self.window_s),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let g = gradient_expr(&self.between);
        Terms::single(
            self.coefficient,
            format!("{} per (degC/min)", ctx.unit),
            tcomp_core::expr::rate_window(g.clone(), self.window_s).to_string(),
            format!(
                "rate of the thermal gradient {g} (degC/min, window {} s)",
                num(self.window_s)
            ),
        )
        .into_truth(Self::KIND)
    }
}
