//! The thermometer pair of a gradient effect (`between = ["t_anode_c", "t_shell_c"]`): its check,
//! its value in a row and its expression text, shared by the effects built on a gradient.

use super::Context;
use super::context::RowInputs;
use crate::error::{Error, Result};
use tcomp_core::expr::{self, Expr};

/// The default pair: the RLG's anode and shell, the largest of its gradients.
pub(crate) fn default_between() -> [String; 2] {
    ["t_anode_c".to_string(), "t_shell_c".to_string()]
}

/// A resolved pair: the columns of `a` and `b` in a row.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pair {
    a: usize,
    b: usize,
}

impl Pair {
    /// Resolves `between` against the run's thermometers; an error names `<at>.between`.
    pub fn resolve(ctx: &Context<'_>, between: &[String; 2], at: &str) -> Result<Pair> {
        let column = |name: &String| {
            ctx.therm_names
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| {
                    Error::invalid(
                        format!("{at}.between"),
                        format!(
                            "unknown thermometer \"{name}\" (sensor {} has: {})",
                            ctx.sensor.name(),
                            ctx.therm_names.join(", ")
                        ),
                    )
                })
        };
        let (a, b) = (column(&between[0])?, column(&between[1])?);
        if a == b {
            return Err(Error::invalid(
                format!("{at}.between"),
                "a gradient needs two different thermometers",
            ));
        }
        Ok(Pair { a, b })
    }

    /// `a − b` in this row.
    pub fn value(&self, row: &RowInputs<'_>) -> f64 {
        row.therm(self.a) - row.therm(self.b)
    }
}

/// The expression `a - b`.
pub(crate) fn gradient_expr(between: &[String; 2]) -> Expr {
    expr::name(&between[0]) - expr::name(&between[1])
}
