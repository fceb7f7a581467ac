//! `c·exp(−(t − t_first)/tau)`: the warm-up transient after power-on, written exactly with the time
//! column as `1 - (time_s - lag(time_s, tau)) / D`, `D = dt·e^(−dt/τ)/(1 − e^(−dt/τ))`.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::RowInputs;
use super::text::{check_finite, check_pos, num};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms, per_sensor};
use crate::error::Result;
use super::LagFilter as Lag;

/// `c·exp(−(t − t_first)/tau)`: a warm-up transient, written exactly as
/// `1 - (time_s - lag(time_s, tau)) / D` with `D = dt·e^(−dt/τ)/(1 − e^(−dt/τ))`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Warmup {
    /// Amplitude at power-on, output units.
    pub coefficient: f64,
    /// Decay time constant, s.
    pub tau_s: f64,
}

/// The constant `D = dt·e^(−dt/τ)/(1 − e^(−dt/τ))` of the warm-up expression.
pub(crate) fn warmup_d(dt: f64, tau_s: f64) -> f64 {
    let e = (-dt / tau_s).exp();
    dt * e / (1.0 - e)
}

struct State {
    coefficient: f64,
    d: f64,
    lag: Lag,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        let l = self.lag.step(row.time_s, dt);
        self.coefficient * (1.0 - (row.time_s - l) / self.d)
    }
}

/// `1 - (time_s - lag(time_s, tau)) / D`.
fn expression(tau_s: f64, d: f64) -> String {
    use tcomp_core::expr::{self, Expr};
    let time = || expr::name("time_s");
    (Expr::num(1.0) - (time() - expr::lag(time(), tau_s)) / Expr::num(d)).to_string()
}

impl EffectModel for Warmup {
    const KIND: EffectKind = EffectKind::Warmup;

    fn default_for(sensor: SensorKind) -> Self {
        Warmup {
            coefficient: per_sensor(sensor, 0.5, 200.0, 0.6),
            tau_s: 1200.0,
        }
    }

    fn validate(&self, _ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        check_pos(self.tau_s, format!("{at}.tau_s"))
    }

    fn state(&self, _ctx: &Context<'_>, dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            coefficient: self.coefficient,
            d: warmup_d(dt, self.tau_s),
            lag: Lag::new(self.tau_s),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, dt: f64) -> EffectTruth {
        Terms::single(
            self.coefficient,
            ctx.unit.to_string(),
            expression(self.tau_s, warmup_d(dt, self.tau_s)),
            format!(
                "warm-up transient c * exp(-(t - t_first)/{} s), written with the time column (exact at this file's step of {} s)",
                num(self.tau_s),
                num(dt)
            ),
        )
        .into_truth(Self::KIND)
    }
}
