//! `c·lag(a − b, tau)`: a bias that follows a thermal gradient with a delay — the part of the
//! sensor the gradient strains sits behind the thermometers that measure it.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::LagFilter as Lag;
use super::context::RowInputs;
use super::pair::{Pair, default_between, gradient_expr};
use super::text::{check_finite, check_pos, num};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use crate::error::Result;

/// `c·lag(a − b, tau)` (RLG: two of its thermometers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradientLag {
    /// Output units per °C of the lagged gradient.
    pub coefficient: f64,
    /// Time constant of the lag, s.
    pub tau_s: f64,
    /// The gradient's thermometers `[a, b]`.
    #[serde(default = "default_between")]
    pub between: [String; 2],
}

struct State {
    pair: Pair,
    coefficient: f64,
    lag: Lag,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        self.coefficient * self.lag.step(self.pair.value(row), dt)
    }
}

impl EffectModel for GradientLag {
    const KIND: EffectKind = EffectKind::GradientLag;

    fn default_for(_sensor: SensorKind) -> Self {
        GradientLag {
            coefficient: 0.3,
            tau_s: 1800.0,
            between: default_between(),
        }
    }

    fn applies_to(sensor: SensorKind) -> bool {
        sensor == SensorKind::Rlg
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        check_pos(self.tau_s, format!("{at}.tau_s"))?;
        Pair::resolve(ctx, &self.between, at).map(|_| ())
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            pair: Pair::resolve(ctx, &self.between, "effects")?,
            coefficient: self.coefficient,
            lag: Lag::new(self.tau_s),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let g = gradient_expr(&self.between);
        Terms::single(
            self.coefficient,
            format!("{} per degC", ctx.unit),
            tcomp_core::expr::lag(g.clone(), self.tau_s).to_string(),
            format!(
                "thermal gradient {g} felt through a lag, tau = {} s",
                num(self.tau_s)
            ),
        )
        .into_truth(Self::KIND)
    }
}
