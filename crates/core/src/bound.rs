//! Plausibility: a bound on everything the evaluator computes, over the whole range box.
//!
//! A blob can pass every per-number check (finite, positive widths) and still fly NaN: one center
//! with `q = 3.2e38` and `g = 1e-7` makes its exponent overflow; a huge `scale` makes the normalised
//! features overflow; weights of 3e38 make the sum overflow. So [`crate::Model::validate`] derives, in
//! f64 from the stored f32 numbers, a bound on every f32 intermediate of [`crate::Rbf::eval_split`]
//! over exactly the box the compensator feeds it (the Gaussians see features clamped to
//! `[lo, hi]`, the linear term to `[lo − span, hi + span]`, computed in f32 as the compensator does),
//! and refuses the model unless all of them stay finite with a wide margin and the correction stays
//! below [`MAX_CORRECTION`]. It runs once per blob, at load.
//!
//! # The bound
//! With `ε = 2⁻²⁴` (f32 unit roundoff):
//!
//! * **Features.** `zₖ = fl(fl(xₖ − oₖ)·sₖ)` is the exact `(xₖ − oₖ)·sₖ` times `(1 + δ)`,
//!   `|δ| ≤ 2ε + ε²`, plus at most 2⁻¹⁵⁰ of underflow. So every computed `zₖ` lies in the exact image
//!   of the box widened by `2.01·ε·Mₖ + 1e-44`, `Mₖ` its largest magnitude. Feature slots past
//!   `n_features` have zero scale and compute exact zeros.
//! * **Exponent.** `u = fl(p + g·‖z‖² + Σ qₖzₖ)` (the evaluator's order, no FMA) is within
//!   `c·A(z)` of the exact value at the computed `z`, where `A(z) = p + g‖z‖² + Σ|qₖ||zₖ|` and
//!   `c = 1.01·(2n + 6)·ε` covers the `n` squares, `n` additions into `‖z‖²`, the product by `g`, and
//!   the `n + 1` products and additions of the linear part (standard `γₘ = mε/(1 − mε)` bounds). The
//!   exact `u − c·A` is a separable function of `z`, `(1 − c)p + Σₖ [(1 − c)g·zₖ² + qₖzₖ − c|qₖ||zₖ|]`,
//!   so its minimum over the box is found exactly, one feature at a time, on each side of
//!   `zₖ = 0` (two convex quadratics). Since `u = g‖z − z₀‖² + (p − ‖q‖²/4g)` with `z₀ = −q/2g`, a `p`
//!   inconsistent with `q` and `g` makes `u` negative, the Gaussian exceed 1 and, far enough, the
//!   fast exponential leave its table (whose domain ends at `u = −24`, see [`crate::fastexp`]). The
//!   model is refused unless this lower bound is at least [`MIN_EXPONENT`] = −24 eval units (a
//!   Gaussian of at most `2^1.5`, where a consistent model is at most 1 plus rounding). A trained
//!   model's `p` is exact to f32 rounding, and its slack `c·A` near a center `z₀` is about
//!   `c·4g‖z₀‖²`: −24 is reached only by a center more than ~700 widths from the normalised origin,
//!   where the expanded form has lost all accuracy anyway.
//! * **Fast exponential.** For `u ∈ [−24, EVAL_CUTOFF)` [`crate::fastexp::exp2_16_neg`] is within
//!   [`crate::fastexp::EXP2_REL_ERR`] of `2^(−u/16)`, so a Gaussian contributes at most
//!   `|w|·(1 + 1e-5)` when the bound is `≥ 0`, `|w|·2^1.5·(1 + 1e-5)` when it is in `[−24, 0)`, and
//!   nothing when it is `≥ EVAL_CUTOFF` (the evaluator skips it). Outside its domain the fast
//!   exponential returns garbage (up to ~1e11 for `|u| ≳ 2²²`), and NaN for an exponent that
//!   overflowed to ±inf: the two checks above are what keep it an exponential.
//! * **Sum.** `|correction| ≤ (|w₀| + Σₖ|lₖ|·Mₖ + Σⱼ|wⱼ|·eⱼ)·(1 + 1.01·(m + n + 4)·ε)` for `m`
//!   centers, with `Mₖ` from the widened linear box: every partial sum is below it.
//!
//! Every magnitude (`|x − o|`, `Mₖ`, `Σ Mₖ²`, `A` at its largest, the final bound) must stay below
//! `f32::MAX / 2`: the f32 value of any intermediate is within a factor `1 + 1e-5` of its bound here
//! (at most ~80 roundings of `ε`), so a factor of 2 is far more than enough. The correction itself
//! must stay below [`MAX_CORRECTION`].

use crate::blob::FeatureRange;
use crate::fastexp::{EVAL_CUTOFF, EXP2_REL_ERR};
use crate::rbf::Rbf;

/// The largest `|correction|` a model may produce anywhere in its range box, in target units: four
/// orders of magnitude above the largest full scale of any sensor in any unit the project uses
/// (±1.8e6 deg/h = ±500 deg/s; ±1e8 µg = ±100 g), and 26 orders below `f32::MAX`.
pub const MAX_CORRECTION: f64 = 1.0e12;
/// The lowest exponent (eval units) a Gaussian may reach in f32: the fast exponential's table domain.
pub const MIN_EXPONENT: f64 = -24.0;

/// f32 unit roundoff, 2⁻²⁴.
const EPS: f64 = 1.0 / 16_777_216.0;
/// Magnitudes every f32 intermediate must stay below (see the module doc).
const F32_LIMIT: f64 = f32::MAX as f64 * 0.5;
/// Bounds the absolute rounding of an f32 product that underflows (2⁻¹⁵⁰ ≈ 7e-46).
const TINY: f64 = 1.0e-44;
/// `2^1.5`: the largest Gaussian value for exponents in `[−24, 0)`.
const NEG_EXP_FACTOR: f64 = 2.828_427_124_746_19;

/// What the plausibility check found for an accepted model.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bound {
    /// Upper bound of `|correction|` the evaluator can return for features in the range box (the
    /// compensator's clamping), f32 rounding included.
    pub correction: f64,
    /// Lower bound of any center's f32 exponent `u` (eval units) over the Gaussian box; `+inf`
    /// without centers.
    pub min_exponent: f64,
}

/// `a ≤ b`, false when either is NaN (a NaN anywhere in the bound refuses the model).
fn below(a: f64, b: f64) -> bool {
    a <= b
}

/// Rounding factor of `n` f32 operations, with a 1 % margin for second-order terms.
fn rounding(n: usize) -> f64 {
    1.01 * n as f64 * EPS
}

/// An interval holding every f32 `z = (x − offset)·scale` the evaluator computes for `x ∈ [lo, hi]`.
fn z_interval(lo: f32, hi: f32, offset: f32, scale: f32) -> Result<(f64, f64), &'static str> {
    let (o, s) = (f64::from(offset), f64::from(scale));
    let (dlo, dhi) = (f64::from(lo) - o, f64::from(hi) - o);
    if !(below(dlo.abs(), F32_LIMIT) && below(dhi.abs(), F32_LIMIT)) {
        return Err("rbf.offset: feature minus offset overflows f32");
    }
    let (a, b) = (dlo * s, dhi * s);
    let (a, b) = if a <= b { (a, b) } else { (b, a) };
    let m = a.abs().max(b.abs());
    if !below(m, F32_LIMIT) {
        return Err("rbf.scale: normalised features overflow f32");
    }
    let widen = 2.01 * EPS * m + TINY;
    Ok((a - widen, b + widen))
}

/// `min α t² + β t` over `t ∈ [a, b]`, `α > 0` (`+inf` for an empty interval).
fn min_quadratic(alpha: f64, beta: f64, a: f64, b: f64) -> f64 {
    if a > b {
        return f64::INFINITY;
    }
    let t = (-beta / (2.0 * alpha)).max(a).min(b);
    alpha * t * t + beta * t
}

/// `min α t² + β t − δ|t|` over `t ∈ [a, b]`, `α > 0`, `δ ≥ 0`: a convex quadratic on each side of 0.
fn min_piecewise(alpha: f64, beta: f64, delta: f64, a: f64, b: f64) -> f64 {
    let right = min_quadratic(alpha, beta - delta, a.max(0.0), b);
    let left = min_quadratic(alpha, beta + delta, a, b.min(0.0));
    right.min(left)
}

/// The bound of the module doc for `rbf` over `ranges` (one per feature), or the field that makes the
/// model implausible. Expects a model that passed the per-number checks (finite values, `g > 0`,
/// `p ≥ 0`, one range per feature, `lo ≤ hi`).
pub fn check<const C: usize, const F: usize>(
    rbf: &Rbf<C, F>,
    ranges: &[FeatureRange],
) -> Result<Bound, &'static str> {
    let nf = usize::from(rbf.n_features).min(F).min(ranges.len());
    let mut gauss = [(0.0f64, 0.0f64); F];
    let mut linear_abs = f64::from(rbf.bias).abs();
    let mut zz_max = 0.0f64;
    for (k, r) in ranges.iter().take(nf).enumerate() {
        let (o, s, l) = (
            rbf.offset.0.get(k).copied().unwrap_or(0.0),
            rbf.scale.0.get(k).copied().unwrap_or(0.0),
            rbf.linear.0.get(k).copied().unwrap_or(0.0),
        );
        // The linear box exactly as the compensator computes it, in f32.
        let span = r.hi - r.lo;
        let (llo, lhi) = (r.lo - span, r.hi + span);
        if !(span.is_finite() && llo.is_finite() && lhi.is_finite()) {
            return Err("ranges: the widened range overflows f32");
        }
        let g = z_interval(r.lo, r.hi, o, s)?;
        let (la, lb) = z_interval(llo, lhi, o, s)?;
        let lin = f64::from(l).abs() * la.abs().max(lb.abs());
        if !below(lin, F32_LIMIT) {
            return Err("rbf.linear: linear term overflows f32");
        }
        linear_abs += lin;
        let m = g.0.abs().max(g.1.abs());
        zz_max += m * m;
        if let Some(slot) = gauss.get_mut(k) {
            *slot = g;
        }
    }
    if !below(zz_max, F32_LIMIT) {
        return Err("rbf.scale: squared distance overflows f32");
    }
    let c = rounding(2 * nf + 6);
    let mut gauss_abs = 0.0f64;
    let mut min_exponent = f64::INFINITY;
    for center in &rbf.centers {
        let (p, g) = (f64::from(center.p), f64::from(center.g));
        let mut a_max = p + g * zz_max;
        let mut lower = (1.0 - c) * p;
        for (&(a, b), &q) in gauss.iter().zip(&center.q.0).take(nf) {
            let q = f64::from(q);
            a_max += q.abs() * a.abs().max(b.abs());
            lower += min_piecewise((1.0 - c) * g, q, c * q.abs(), a, b);
        }
        if !below(a_max, F32_LIMIT) {
            return Err("rbf.centers: a Gaussian's exponent overflows f32");
        }
        if !below(MIN_EXPONENT, lower) {
            return Err("rbf.centers: a Gaussian exceeds 2^1.5 (p inconsistent with q and g)");
        }
        min_exponent = min_exponent.min(lower);
        let e = if lower >= f64::from(EVAL_CUTOFF) {
            0.0
        } else if lower >= 0.0 {
            1.0 + f64::from(EXP2_REL_ERR)
        } else {
            NEG_EXP_FACTOR * (1.0 + f64::from(EXP2_REL_ERR))
        };
        gauss_abs += f64::from(center.w).abs() * e;
    }
    let correction = (linear_abs + gauss_abs) * (1.0 + rounding(rbf.centers.len() + nf + 4));
    if !below(correction, MAX_CORRECTION) {
        return Err("rbf: the correction can exceed 1e12 in the range box");
    }
    Ok(Bound {
        correction,
        min_exponent,
    })
}
