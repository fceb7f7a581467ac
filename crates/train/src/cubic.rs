//! The cubic in the first feature as a basis `bayes` may choose: the program with `Tclamped =
//! clamp(first feature, trained range)` and `sq(Tclamped)`, `Tclamped * sq(Tclamped)` appended,
//! their ranges and their binned values.
//!
//! Why apart from [`crate::poly3`] and [`crate::bayes`]: it is built from the data like the
//! features (by the core's program, so what is fitted is what flies), while `bayes` only sees its
//! rows; and it is the same cubic poly3 flies ([`crate::poly3::program_lines`]).

use crate::binning::bin_mean;
use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::features::{self, FeatureSpec};
use crate::poly3::program_lines;
use tcomp_core::FeatureRange;

/// The cubic in the first feature as `bayes` may choose it: the program with `Tclamped =
/// clamp(first feature, trained range)` and the features `sq(Tclamped)`, `Tclamped * sq(Tclamped)`
/// appended, their two ranges, and their binned values (computed by that program, like `x`).
pub struct CubicBasis {
    /// The program with the two features appended.
    pub spec: FeatureSpec,
    /// The ranges of the two features.
    pub ranges: [FeatureRange; 2],
    /// Their binned values, `[T², T³]` per bin.
    pub rows: Vec<Vec<f64>>,
}

/// The cubic basis for `spec`, or `None` when the program with it would not fit the firmware
/// ([`features::fits_flight`]) or the first feature does not vary.
pub fn cubic_basis(
    spec: &FeatureSpec,
    data: &Dataset,
    time: &[f64],
    starts: &[usize],
    time_on_s: f64,
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
    let feats = features::compute_from(&augmented.program()?, data, time, starts, time_on_s)?;
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
