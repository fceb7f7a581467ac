//! The pieces of expression text the effects share, and the checks of their parameters.
//!
//! The effects' truth expressions are text in the core's feature language; these helpers are the
//! only places that print numbers and operators into it.

use super::RATE_WINDOW_S;
use crate::error::{Error, Result};

/// A number as the expressions print it.
pub(crate) fn num(x: f64) -> String {
    format!("{x}")
}

/// `x - c` written without unary minus.
pub(crate) fn shifted(x: &str, c: f64) -> String {
    if c == 0.0 {
        x.to_string()
    } else if c > 0.0 {
        format!("{x} - {}", num(c))
    } else {
        format!("{x} + {}", num(-c))
    }
}

/// `rate(x)`, with the window only when it is not the core's default.
pub(crate) fn rate_expr(x: &str, window_s: f64) -> String {
    if window_s == RATE_WINDOW_S {
        format!("rate({x})")
    } else {
        format!("rate({x}, {})", num(window_s))
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
