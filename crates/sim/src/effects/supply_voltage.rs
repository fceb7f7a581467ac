//! `c·(supply_v − nominal)`: sensitivity to the supply voltage, a non-thermal input.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::RowInputs;
use super::text::{check_finite, num};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms, per_sensor};
use crate::error::Result;

fn default_nominal_v() -> f64 {
    28.0
}

/// `c·(supply_v − nominal)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupplyVoltage {
    /// Output units per volt.
    pub coefficient: f64,
    /// Nominal supply, V.
    #[serde(default = "default_nominal_v")]
    pub nominal_v: f64,
}

struct State {
    coefficient: f64,
    nominal_v: f64,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, _dt: f64) -> f64 {
        self.coefficient * (row.supply_v - self.nominal_v)
    }
}

impl EffectModel for SupplyVoltage {
    const KIND: EffectKind = EffectKind::SupplyVoltage;

    fn default_for(sensor: SensorKind) -> Self {
        SupplyVoltage {
            coefficient: per_sensor(sensor, 0.2, 200.0, 0.3),
            nominal_v: 28.0,
        }
    }

    fn validate(&self, _ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.coefficient, format!("{at}.coefficient"))?;
        check_finite(self.nominal_v, format!("{at}.nominal_v"))
    }

    fn state(&self, _ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            coefficient: self.coefficient,
            nominal_v: self.nominal_v,
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        Terms::single(
            self.coefficient,
            format!("{} per V", ctx.unit),
            "supply_v".into(),
            format!("supply-voltage sensitivity about {} V", num(self.nominal_v)),
        )
        .with_offset(-self.coefficient * self.nominal_v)
        .into_truth(Self::KIND)
    }
}
