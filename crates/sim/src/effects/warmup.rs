//! `c·warmup(tau)` = `c·exp(−t_on/tau)`: the warm-up transient after power-on, written with the
//! language's `warmup(τ)`, whose clock is the time since power-on: the board counts it from its
//! boot, the host from the file's first row unless told otherwise (`--power-on`). The simulator's
//! power-on is the first row's time, so the truth holds with the host's default.
//!
//! (Before `warmup` existed, the truth spelled the same transient through the time column,
//! `1 - (time_s - lag(time_s, tau)) / D`: exact, but the board has no time column.)

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::RowInputs;
use super::text::{check_finite, check_pos, num};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms, per_sensor};
use crate::error::Result;

/// `c·exp(−t_on/tau)`, `t_on` the seconds since the first row: written `warmup(tau)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Warmup {
    /// Amplitude at power-on, output units.
    pub coefficient: f64,
    /// Decay time constant, s.
    pub tau_s: f64,
}

struct State {
    coefficient: f64,
    tau_s: f64,
    first: Option<f64>,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, _dt: f64) -> f64 {
        let t0 = *self.first.get_or_insert(row.time_s);
        self.coefficient * (-(row.time_s - t0) / self.tau_s).exp()
    }
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

    fn state(&self, _ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            coefficient: self.coefficient,
            tau_s: self.tau_s,
            first: None,
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        Terms::single(
            self.coefficient,
            ctx.unit.to_string(),
            tcomp_core::expr::warmup(self.tau_s).to_string(),
            format!(
                "warm-up transient c * exp(-t_on/{} s), t_on the seconds since power-on at the \
                 first row (the host's default for --power-on)",
                num(self.tau_s)
            ),
        )
        .into_truth(Self::KIND)
    }
}
