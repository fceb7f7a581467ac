//! The baseline every report compares against: a cubic polynomial in one temperature, clamped to the
//! trained range — what PX4 and ArduPilot fly.
//!
//! Why through the RBF evaluator: the cubic is written as three features of the core's language,
//! `Tclamped = clamp(T, lo, hi)`, `Tclamped`, `sq(Tclamped)`, `Tclamped * sq(Tclamped)`, with the linear
//! term and zero centers, so the same blob format, evaluator and firmware fly it and the comparison
//! with the RBF methods is on equal terms.
//!
//! The same cubic is also a basis `bayes` may choose (`cubic_basis` builds its program and
//! columns): on a tie in evidence with the Gaussians it is the simpler model.

use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::features::{self, FeatureSpec, bin_mean};
use crate::rbf64::{Rbf64, design, least_squares, mean_std, normalise_rows, split_weights};
use tcomp_core::FeatureRange;
use tcomp_core::expr::{self, Expr};

/// Name of the clamped-temperature signal poly3 defines.
pub const SIGNAL: &str = "Tclamped";

/// The signal line and feature expressions of a cubic in `feature` (an expression's text) clamped
/// to `[lo, hi]` (written in scientific notation, as the blobs of earlier builds have them).
pub fn program_lines(feature: &str, lo: f64, hi: f64) -> (String, Vec<String>) {
    let clamped = expr::clamp(Expr::text(feature), Expr::sci(lo), Expr::sci(hi));
    let t = expr::name(SIGNAL);
    (
        expr::define(SIGNAL, &clamped),
        [t.clone(), expr::sq(t.clone()), t.clone() * expr::sq(t)]
            .iter()
            .map(Expr::to_string)
            .collect(),
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

/// The cubic in the first feature as `bayes` may choose it: the program with `Tclamped =
/// clamp(first feature, trained range)` and the features `sq(Tclamped)`, `Tclamped * sq(Tclamped)`
/// appended, their two ranges, and their binned values (computed by that program, like `x`).
pub(crate) struct CubicBasis {
    pub(crate) spec: FeatureSpec,
    pub(crate) ranges: [FeatureRange; 2],
    pub(crate) rows: Vec<Vec<f64>>,
}

/// The cubic basis for `spec`, or `None` when the program with it would not fit the firmware
/// ([`features::fits_flight`]) or the first feature does not vary.
pub(crate) fn cubic_basis(
    spec: &FeatureSpec,
    data: &Dataset,
    time: &[f64],
    starts: &[usize],
    ranges: &[FeatureRange],
    b: &[(usize, usize)],
) -> Result<Option<CubicBasis>, TrainError> {
    let (Some(expr), Some(r)) = (spec.features.first(), ranges.first()) else {
        return Ok(None);
    };
    if r.hi.is_nan() || r.lo.is_nan() || r.hi <= r.lo {
        return Ok(None);
    }
    let (sig, feats) = program_lines(expr, f64::from(r.lo), f64::from(r.hi));
    let mut augmented = spec.clone();
    augmented.signals.push(sig);
    augmented.features.extend(feats.into_iter().skip(1));
    if !features::fits_flight(&augmented) {
        return Ok(None);
    }
    let nf = spec.features.len();
    let feats = features::compute(&augmented.program()?, data, time, starts)?;
    let mut out = [FeatureRange { lo: 0.0, hi: 0.0 }; 2];
    let mut cols = Vec::with_capacity(2);
    for (k, range) in out.iter_mut().enumerate() {
        let c: Vec<f64> = feats
            .iter()
            .map(|r| r.get(nf + k).copied().map_or(f64::NAN, f64::from))
            .collect();
        let (lo, hi) = c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        *range = FeatureRange {
            lo: lo as f32,
            hi: hi as f32,
        };
        cols.push(bin_mean(&c, b));
    }
    let rows = (0..b.len())
        .map(|i| {
            cols.iter()
                .map(|c| c.get(i).copied().unwrap_or(0.0))
                .collect()
        })
        .collect();
    Ok(Some(CubicBasis {
        spec: augmented,
        ranges: out,
        rows,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn program_lines_spell_the_cubic_as_before() {
        let (signal, features) = program_lines("mean(t_a, t_b)", -10.0, 21.5);
        assert_eq!(signal, "Tclamped = clamp(mean(t_a, t_b), -1e1, 2.15e1)");
        assert_eq!(
            features,
            ["Tclamped", "sq(Tclamped)", "Tclamped * sq(Tclamped)"]
        );
    }
}
