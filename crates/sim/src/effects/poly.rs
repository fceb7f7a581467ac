//! `Σ c_k·(T − t0)^k`, k = 1..=5: the polynomial in temperature every sensor has.

use serde::{Deserialize, Serialize};
use tcomp_core::expr::{self, Expr};
use tcomp_core::{EffectKind, SensorKind};

use super::context::{Input, RowInputs};
use super::text::{check_finite, shifted};
use super::{Context, EffectModel, EffectState, EffectTruth, Terms};
use super::{default_input, default_t0, per_sensor};
use crate::error::{Error, Result};

/// `Σ c_k·(T − t0)^k`, k = 1..=len (at most 5 coefficients).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Poly {
    /// Coefficients of (T − t0), (T − t0)², … in output units per °C^k.
    pub coefficients: Vec<f64>,
    /// Expansion point, °C.
    #[serde(default = "default_t0")]
    pub t0_c: f64,
    /// Temperature input.
    #[serde(default = "default_input")]
    pub input: String,
}

struct State {
    input: Input,
    t0: f64,
    coefficients: Vec<f64>,
}

impl EffectState for State {
    fn step(&mut self, row: &RowInputs<'_>, _dt: f64) -> f64 {
        let x = row.read(self.input) - self.t0;
        let mut p = 1.0;
        let mut sum = 0.0;
        for ck in self.coefficients.iter() {
            p *= x;
            sum += ck * p;
        }
        sum
    }
}

/// The expressions of the powers 1..=`degree` of `base` (`x - t0`).
fn power_exprs(base: &Expr, degree: usize) -> Vec<String> {
    (1..=degree)
        .map(|k| match k {
            1 => base.to_string(),
            _ => {
                let mut e = expr::sq(base.clone());
                for _ in 2..k {
                    e = base.clone() * e;
                }
                e.to_string()
            }
        })
        .collect()
}

impl EffectModel for Poly {
    const KIND: EffectKind = EffectKind::Poly;

    fn default_for(sensor: SensorKind) -> Self {
        Poly {
            coefficients: per_sensor(
                sensor,
                vec![0.004, 5e-5, 1e-6],
                vec![15.0, 0.2, 0.005],
                vec![0.01, 2e-4, 4e-6],
            ),
            t0_c: 20.0,
            input: default_input(),
        }
    }

    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        if self.coefficients.is_empty() || self.coefficients.len() > 5 {
            return Err(Error::invalid(
                format!("{at}.coefficients"),
                "give 1 to 5 coefficients (linear, quadratic, ...)",
            ));
        }
        for (i, c) in self.coefficients.iter().enumerate() {
            check_finite(*c, format!("{at}.coefficients[{i}]"))?;
        }
        check_finite(self.t0_c, format!("{at}.t0_c"))?;
        ctx.input(&self.input, &format!("{at}.input"))?;
        Ok(())
    }

    fn state(&self, ctx: &Context<'_>, _dt: f64) -> Result<Box<dyn EffectState>> {
        Ok(Box::new(State {
            input: ctx.input(&self.input, "input")?,
            t0: self.t0_c,
            coefficients: self.coefficients.clone(),
        }))
    }

    fn truth(&self, ctx: &Context<'_>, _dt: f64) -> EffectTruth {
        let u = ctx.unit;
        let x = ctx.input_expr(&self.input);
        let n = self.coefficients.len();
        let units = (1..=n)
            .map(|k| {
                if k == 1 {
                    format!("{u} per degC")
                } else {
                    format!("{u} per degC^{k}")
                }
            })
            .collect();
        Terms {
            coefficients: self.coefficients.clone(),
            units,
            expressions: power_exprs(&shifted(&x, self.t0_c), n),
            offset: 0.0,
            features: vec![x.clone()],
            description: format!(
                "polynomial in temperature {x} about {} degC (degree {n})",
                self.t0_c
            ),
        }
        .into_truth(Self::KIND)
    }
}
