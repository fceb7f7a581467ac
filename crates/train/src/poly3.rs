//! The baseline every report compares against: a cubic polynomial in one temperature, clamped to the
//! trained range — what PX4 and ArduPilot fly.
//!
//! Why through the RBF evaluator: the cubic is written as three features of the core's language,
//! `Tclamped = clamp(T, lo, hi)`, `Tclamped`, `sq(Tclamped)`, `Tclamped * sq(Tclamped)`, with the linear
//! term and zero centers, so the same blob format, evaluator and firmware fly it and the comparison
//! with the RBF methods is on equal terms.

use crate::error::TrainError;
use crate::rbf64::{Rbf64, design, least_squares, mean_std, normalise_rows, split_weights};

/// Name of the clamped-temperature signal poly3 defines.
pub const SIGNAL: &str = "Tclamped";

/// The signal line and feature expressions of a cubic in `expr` clamped to `[lo, hi]`.
pub fn program_lines(expr: &str, lo: f64, hi: f64) -> (String, Vec<String>) {
    (
        format!("{SIGNAL} = clamp({expr}, {lo:e}, {hi:e})"),
        vec![
            SIGNAL.to_string(),
            format!("sq({SIGNAL})"),
            format!("{SIGNAL} * sq({SIGNAL})"),
        ],
    )
}

/// Least-squares cubic on the three features (rows `x` = [T, T², T³] as computed by the core).
pub fn fit(x: &[Vec<f64>], y: &[f64]) -> Result<Rbf64, TrainError> {
    let (xm, xs) = mean_std(x);
    let scale: Vec<f64> = xs.iter().map(|s| 1.0 / s.max(1e-300)).collect();
    let z = normalise_rows(x, &xm, &scale);
    let phi = design(&z, true, &[], &[]);
    let w = least_squares(&phi, y)?;
    let (bias, linear, _) = split_weights(&w, xm.len());
    Ok(Rbf64 {
        offset: xm,
        scale,
        centers: Vec::new(),
        gamma: Vec::new(),
        weights: Vec::new(),
        linear,
        bias,
    })
}
