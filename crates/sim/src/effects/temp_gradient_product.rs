//! `c·T·(a − b)`: a gradient whose effect scales with the temperature — the stiffness or the
//! expansion mismatch behind a gradient's strain is itself temperature dependent.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::{Input, RowInputs};
use super::pair::{Pair, default_between, gradient_expr};
use super::text::check_finite;
use super::{Context, EffectModel, EffectState, EffectTruth, Terms, default_input};
use crate::error::Result;

/// `c·T·(a − b)` (RLG: two of its thermometers; `T` their mean by default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TempGradientProduct {
    /// Output units per °C².
    pub coefficient: f64,
    /// The gradient's thermometers `[a, b]`.
    #[serde(default = "default_between")]
    pub between: [String; 2],
    /// Temperature input.
    #[serde(default = "default_input")]
    pub input: String,
}

struct State {
    input: Input,
    pair: Pair,
    coefficient: f64,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, _dt: f64) -> f64 {
        self.coefficient * row.read(self.input) * self.pair.value(row)
    }
}

impl EffectModel for TempGradientProduct {
    const KIND: EffectKind = EffectKind::TempGradientProduct;

    fn default_for(_sensor: SensorKind) -> Self {
        TempGradientProduct {
            coefficient: 0.01,
            between: default_between(),
            input: default_input(),
        }
    }

    fn applies_to(sensor: SensorKind) -> bool {
        sensor == SensorKind::Rlg
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        ctx.input(&self.input, &format!("{at}.input"))?;
        Pair::resolve(ctx, &self.between, at).map(|_| ())
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            input: ctx.input(&self.input, "input")?,
            pair: Pair::resolve(ctx, &self.between, "effects")?,
            coefficient: self.coefficient,
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let x = ctx.input_expr(&self.input);
        let g = gradient_expr(&self.between);
        let product = tcomp_core::expr::name(&x) * g.clone();
        Terms::single(
            self.coefficient,
            format!("{} per degC^2", ctx.unit),
            product.to_string(),
            format!("temperature {x} times the thermal gradient {g}"),
        )
        .into_truth(Self::KIND)
    }
}
