//! `a·(t_anode_c − t_shell_c) + c·(t_cathode_c − t_shell_c)`: an RLG's thermal gradients.

use serde::{Deserialize, Serialize};
use tcomp_core::{EffectKind, SensorKind};

use super::context::RowInputs;
use super::text::check_finite;
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use crate::error::Result;

/// `a·(t_anode_c − t_shell_c) + c·(t_cathode_c − t_shell_c)` (RLG only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gradient {
    /// Output units per °C of anode−shell.
    pub anode_shell: f64,
    /// Output units per °C of cathode−shell.
    pub cathode_shell: f64,
}

struct State {
    anode: usize,
    cathode: usize,
    shell: usize,
    anode_shell: f64,
    cathode_shell: f64,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, _dt: f64) -> f64 {
        let s = row.therm(self.shell);
        self.anode_shell * (row.therm(self.anode) - s)
            + self.cathode_shell * (row.therm(self.cathode) - s)
    }
}

/// The two gradient expressions.
fn expressions() -> [String; 2] {
    [
        "t_anode_c - t_shell_c".to_string(),
        "t_cathode_c - t_shell_c".to_string(),
    ]
}

impl EffectModel for Gradient {
    const KIND: EffectKind = EffectKind::Gradient;

    fn default_for(_sensor: SensorKind) -> Self {
        Gradient {
            anode_shell: 0.25,
            cathode_shell: -0.15,
        }
    }

    fn applies_to(sensor: SensorKind) -> bool {
        sensor == SensorKind::Rlg
    }

    fn validate(&self, _ctx: &Context<'_>, at: &str) -> Result<()> {
        check_finite(self.anode_shell, format!("{at}.anode_shell"))?;
        check_finite(self.cathode_shell, format!("{at}.cathode_shell"))
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            anode: ctx.column("t_anode_c")?,
            cathode: ctx.column("t_cathode_c")?,
            shell: ctx.column("t_shell_c")?,
            anode_shell: self.anode_shell,
            cathode_shell: self.cathode_shell,
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let u = ctx.unit;
        let exprs = expressions().to_vec();
        Terms {
            coefficients: vec![self.anode_shell, self.cathode_shell],
            units: vec![format!("{u} per degC"), format!("{u} per degC")],
            expressions: exprs.clone(),
            offset: 0.0,
            features: exprs,
            description: "thermal gradients anode-shell and cathode-shell".into(),
        }
        .into_truth(Self::KIND)
    }
}
