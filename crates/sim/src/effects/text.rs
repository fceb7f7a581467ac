//! The pieces of expression text the effects share, and the checks of their parameters.
//!
//! The effects' truth expressions are syntax trees of the core's feature language
//! ([`tcomp_core::expr`]), printed by its one printer; these helpers build the pieces the effects
//! share.

use super::RATE_WINDOW_S;
use crate::error::{Error, Result};
use tcomp_core::expr::{self, Expr};

/// A number as the expressions print it.
pub(crate) fn num(x: f64) -> String {
    Expr::num(x).to_string()
}

/// `x - c` written without unary minus.
pub(crate) fn shifted(x: &str, c: f64) -> Expr {
    if c == 0.0 {
        expr::name(x)
    } else if c > 0.0 {
        expr::name(x) - Expr::num(c)
    } else {
        expr::name(x) + Expr::num(-c)
    }
}

/// `rate(x)`, with the window only when it is not the core's default.
pub(crate) fn rate_expr(x: &str, window_s: f64) -> Expr {
    if window_s == RATE_WINDOW_S {
        expr::rate(expr::name(x))
    } else {
        expr::rate_window(expr::name(x), window_s)
    }
}

/// Refuses a non-finite value of `field`.
pub(crate) fn check_finite(v: f64, field: String) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(field, "must be finite"))
    }
}

/// Refuses a value of `field` that is not a finite positive number.
pub(crate) fn check_pos(v: f64, field: String) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(field, format!("must be > 0, got {v}")))
    }
}

/// The checks of an effect with a coefficient, a rate window and an input (`<at>.coefficient`
/// finite, `<at>.window_s` positive, `<at>.input` a column or signal of the run).
pub(crate) fn check_windowed(
    ctx: &super::Context<'_>,
    at: &str,
    coefficient: f64,
    window_s: f64,
    input: &str,
) -> Result<()> {
    check_finite(coefficient, format!("{at}.coefficient"))?;
    check_pos(window_s, format!("{at}.window_s"))?;
    ctx.input(input, &format!("{at}.input"))?;
    Ok(())
}
