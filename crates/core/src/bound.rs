//! Plausibility: a bound on everything the evaluator computes, over the whole range box.
//!
//! A blob can pass every per-number check (finite, positive widths) and still fly NaN: one center
//! with `q = 3.2e38` and `g = 1e-7` makes its exponent overflow (and the fast exponential of an
//! infinite exponent is NaN); a huge `scale` makes the normalised features overflow; weights of 3e38
//! make the sum overflow. So [`crate::Model::validate`] derives from the stored numbers a bound on
//! every f32 intermediate of [`crate::Rbf::eval_split`] over exactly the box the compensator feeds it
//! (the Gaussians see features clamped to `[lo, hi]`, the linear term to `[lo − span, hi + span]`,
//! computed in f32 as the compensator does), and refuses the model unless all of them stay finite
//! with a wide margin, every Gaussian stays an exponential, and the correction stays below
//! [`MAX_CORRECTION`]. It runs once per blob, at load.
//!
//! # The bound
//! With `ε = 2⁻²⁴` (f32 unit roundoff) and `n` features:
//!
//! * **Features.** Correctly rounded subtraction and multiplication are monotone, so every `zₖ` the
//!   evaluator computes for `xₖ` in the box lies between the two values it computes at the box's ends:
//!   the normalised box is exact, not estimated. Feature slots past `n_features` have zero scale and
//!   give exact zeros.
//! * **Exponent.** `u = fl(p + g·‖z‖² + Σ qₖzₖ)` (the evaluator's order, no FMA) is within
//!   `c·A(z)` of the exact value at the computed `z`, where `A(z) = p + g‖z‖² + Σ|qₖ||zₖ|` and
//!   `c = 1.01·(2n + 6)·ε` covers the `n` squares and `n` additions into `‖z‖²`, the product by `g`,
//!   and the `n + 1` products and additions of the rest (standard `γₘ = mε/(1 − mε)` bounds). The
//!   exact `u − c·A` is separable, `(1 − c)p + Σₖ [(1 − c)g·zₖ² + qₖzₖ − c|qₖ||zₖ|]`, so its minimum
//!   over the box is bounded from below one feature at a time, on each side of `zₖ = 0` (two
//!   parabolas: the vertex value `−β²/4α` when the vertex is inside, else the smaller end). Since
//!   `u = g‖z − z₀‖² + (p − ‖q‖²/4g)` with `z₀ = −q/2g`, a `p` inconsistent with `q` and `g` makes
//!   `u` negative, the Gaussian exceed 1 and, far enough, the fast exponential leave its table (whose
//!   domain ends at `u = −24`, see [`crate::fastexp`]). The model is refused unless the lower bound is
//!   at least [`MIN_EXPONENT`] = −24 eval units (a Gaussian of at most `2^1.5`, where a consistent
//!   model gives at most 1 plus rounding). A trained model's `p` is exact to f32 rounding, and its
//!   slack `c·A` near a center `z₀` is about `c·4g‖z₀‖²`: −24 is reached only by a center several
//!   hundred widths from the normalised origin, where the expanded form has lost all accuracy anyway.
//!   A center of an additive model ([`Rbf::masks`]) sums over its masked features only: the others
//!   contribute exactly zero and are left out of its bound (`‖z‖²` over every feature still bounds
//!   its largest `A` from above).
//! * **Fast exponential.** For `u ∈ [−24, EVAL_CUTOFF)` [`crate::fastexp::exp2_16_neg`] is within
//!   [`crate::fastexp::EXP2_REL_ERR`] of `2^(−u/16)`, so a Gaussian contributes at most
//!   `|w|·(1 + 1e-5)` when the bound is `≥ 0`, `|w|·2^1.5·(1 + 1e-5)` when it is in `[−24, 0)`, and
//!   nothing when it is `≥ EVAL_CUTOFF` (the evaluator skips it). Outside its domain the fast
//!   exponential returns garbage (up to ~1e11 for `|u| ≳ 2²²`), and NaN for an exponent that
//!   overflowed to ±inf: the checks above are what keep it an exponential.
//! * **Steps** ([`Rbf::kinds`]). A step's exponent `u = p + Σ qₖzₖ` only needs to stay finite:
//!   the evaluator takes the fast exponential of `|u|` (inside its domain below the cutoff, flushed
//!   to zero above) and returns `w/(1 + e)` or `w·e/(1 + e)`, at most `|w|·(1 + 1e-5)` with the
//!   division's rounding. So `|p| + Σ|qₖ|·max|zₖ|` must stay below `f32::MAX / 2`, and a step adds
//!   `|w|·(1 + 2·1e-5)` to the sum; it does not enter the lowest Gaussian exponent.
//! * **Powers** (kinds square and cube). `|u| ≤ A = |p| + Σ|qₖ|·max|zₖ|` (raised by the rounding
//!   of its `n + 1` operations), so a power adds at most `|w|·Aⁿ` (raised by its own two or three
//!   multiplications' rounding); `Aⁿ` must stay below `f32::MAX / 2`.
//! * **Sum.** `|correction| ≤ (|w₀| + Σₖ|lₖ|·Mₖ + Σⱼ|wⱼ|·eⱼ)·(1 + 1.01·(m + n + 4)·ε)` for `m`
//!   centers, `Mₖ` the largest `|zₖ|` of the linear box: every partial sum is below it.
//!
//! The bound is computed in f32, on the board's FPU (f64 would be software floating point there:
//! measured +8.7 KB of flash for the same check, against a 32 KiB budget). Every quantity that is
//! lowered (the exponent's minimum) or raised (magnitudes, the correction) is corrected for this
//! computation's own rounding as well, each step with its own allowance of a few ε (see the code), so
//! the f32 bound is a bound on the exact one. Every magnitude (`|x − o|`, `|zₖ|`, `Σ Mₖ²`, `A` at its
//! largest, the linear term) must stay below `f32::MAX / 2`: any intermediate of the evaluator is
//! within a factor `1 + 1e-5` of its bound here (at most ~150 roundings of `ε`), so a factor of 2 is
//! far more than enough.

use crate::blob::FeatureRange;
use crate::fastexp::{EVAL_CUTOFF, EXP2_REL_ERR};
use crate::rbf::{KIND_CUBE, KIND_GAUSSIAN, KIND_RAMP, KIND_SQUARE, KIND_STEP, Rbf};

/// The largest `|correction|` a model may produce anywhere in its range box, in target units: four
/// orders of magnitude above the largest full scale of any sensor in any unit the project uses
/// (±1.8e6 deg/h = ±500 deg/s; ±1e8 µg = ±100 g), and 26 orders below `f32::MAX`.
pub const MAX_CORRECTION: f32 = 1.0e12;
/// The lowest exponent (eval units) a Gaussian may reach in f32: the fast exponential's table domain.
pub const MIN_EXPONENT: f32 = -24.0;

/// f32 unit roundoff, 2⁻²⁴.
const EPS: f32 = f32::EPSILON / 2.0;
/// Magnitudes every f32 intermediate must stay below (see the module doc).
const F32_LIMIT: f32 = f32::MAX / 2.0;
/// Absolute slack for results near zero: covers underflow and a target that flushes subnormals to
/// zero (at most ~1.2e-38 per operation).
const TINY: f32 = 1.0e-30;
/// `2^1.5`, rounded up: the largest Gaussian value for exponents in `[−24, 0)`.
const NEG_EXP_FACTOR: f32 = 2.828_428;

/// What the plausibility check found for an accepted model.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bound {
    /// Upper bound of `|correction|` the evaluator can return for features in the range box (the
    /// compensator's clamping), f32 rounding included.
    pub correction: f32,
    /// Lower bound of any center's f32 exponent `u` (eval units) over the Gaussian box; `+inf`
    /// without centers.
    pub min_exponent: f32,
}

/// `a ≤ b`, false when either is NaN (a NaN anywhere in the bound refuses the model).
fn below(a: f32, b: f32) -> bool {
    a <= b
}

/// Rounding allowance of `n` f32 operations, with a 1 % margin for second-order terms.
fn rounding(n: usize) -> f32 {
    1.01 * n as f32 * EPS
}

/// The interval of every f32 `z = (x − offset)·scale` for `x ∈ [lo, hi]`, exactly: correctly
/// rounded subtraction and multiplication are monotone, so the evaluator's `z` lies between the
/// values it computes at the two ends. Refused if `x − offset` or `z` can overflow.
fn z_box(lo: f32, hi: f32, offset: f32, scale: f32) -> Result<(f32, f32), &'static str> {
    let (dlo, dhi) = (lo - offset, hi - offset);
    if !(below(dlo.abs(), F32_LIMIT) && below(dhi.abs(), F32_LIMIT)) {
        return Err("rbf.offset: feature minus offset overflows f32");
    }
    let (a, b) = (dlo * scale, dhi * scale);
    if !(below(a.abs(), F32_LIMIT) && below(b.abs(), F32_LIMIT)) {
        return Err("rbf.scale: normalised features overflow f32");
    }
    Ok(if a <= b { (a, b) } else { (b, a) })
}

/// A lower bound of `min α t² + β t` over `t ∈ [a, b]`, `α ≥ 0`, computed in f32 (`+inf` for an
/// empty interval). The vertex value `−β²/4α = β·t*/2` bounds the parabola everywhere, so it is
/// used whenever the computed vertex is inside the interval or within its rounding of an end
/// (a wrong call only loosens the bound); otherwise the smaller end value, each lowered by its own
/// rounding.
fn min_quadratic(alpha: f32, beta: f32, a: f32, b: f32) -> f32 {
    if a > b {
        return f32::INFINITY;
    }
    // An `α` of zero (or flushed to zero) gives an infinite or NaN `t`: the ends decide.
    let t = -(beta / alpha) * 0.5;
    let slack = 4.0 * EPS * t.abs() + TINY;
    if t.is_finite() && t >= a - slack && t <= b + slack {
        // `t` is within ε (relative) of t*, `β·t/2` within 2ε of the vertex value (≤ 0), and the
        // factor 1 + 8ε (exact in f32) more than covers both and its own rounding.
        return 0.5 * beta * t * (1.0 + 8.0 * EPS) - TINY;
    }
    // Three roundings in the value, one in its magnitude, one in the subtraction: 5ε covers them.
    let end = |t: f32| {
        let v = (alpha * t + beta) * t;
        let magnitude = (alpha * t.abs() + beta.abs()) * t.abs();
        v - 5.0 * EPS * magnitude - TINY
    };
    end(a).min(end(b))
}

/// The bound of the module doc for `rbf` over `ranges` (one per feature), or the field that makes the
/// model implausible. Expects a model that passed the per-number checks (finite values, `g > 0`,
/// `p ≥ 0`, one range per feature, `lo ≤ hi`).
pub fn check<const C: usize, const F: usize>(
    rbf: &Rbf<C, F>,
    ranges: &[FeatureRange],
) -> Result<Bound, &'static str> {
    let nf = usize::from(rbf.n_features).min(F).min(ranges.len());
    let mut gauss = [(0.0f32, 0.0f32); F];
    let mut linear_abs = rbf.bias.abs();
    let mut zz_max = 0.0f32;
    for (k, r) in ranges.iter().take(nf).enumerate() {
        let (o, s, l) = (
            rbf.offset.0.get(k).copied().unwrap_or(0.0),
            rbf.scale.0.get(k).copied().unwrap_or(0.0),
            rbf.linear.0.get(k).copied().unwrap_or(0.0),
        );
        // The linear box exactly as the compensator computes it.
        let span = r.hi - r.lo;
        let (llo, lhi) = (r.lo - span, r.hi + span);
        if !(span.is_finite() && llo.is_finite() && lhi.is_finite()) {
            return Err("ranges: the widened range overflows f32");
        }
        let g = z_box(r.lo, r.hi, o, s)?;
        let (la, lb) = z_box(llo, lhi, o, s)?;
        linear_abs += l.abs() * la.abs().max(lb.abs());
        let m = g.0.abs().max(g.1.abs());
        zz_max += m * m;
        if let Some(slot) = gauss.get_mut(k) {
            *slot = g;
        }
    }
    if !(below(zz_max, F32_LIMIT) && below(linear_abs, F32_LIMIT)) {
        return Err("rbf.scale: squared distance or linear term overflows f32");
    }
    // The evaluator's rounding of u, plus 3ε for rounding the coefficients below (each lowered).
    let c = rounding(2 * nf + 6) + 3.0 * EPS;
    let mut gauss_abs = 0.0f32;
    let mut min_exponent = f32::INFINITY;
    for (j, center) in rbf.centers.iter().enumerate() {
        let kind = rbf.kinds.get(j).copied().unwrap_or(KIND_GAUSSIAN);
        if kind != KIND_GAUSSIAN {
            let mut a_max = center.p.abs();
            for (&(a, b), &q) in gauss.iter().zip(&center.q.0).take(nf) {
                a_max += q.abs() * a.abs().max(b.abs());
            }
            // The evaluator's n + 1 roundings of u and this sum's own.
            a_max *= 1.0 + rounding(2 * nf + 4);
            if !below(a_max, F32_LIMIT) {
                return Err("rbf.centers: a step's or a power's argument overflows f32");
            }
            let value = match kind {
                KIND_STEP => 1.0 + 2.0 * EXP2_REL_ERR,
                KIND_SQUARE => a_max * a_max * (1.0 + rounding(4)),
                KIND_CUBE => a_max * a_max * a_max * (1.0 + rounding(6)),
                // `clamp(u, −1, 1)` is exact: at most 1 whatever `u`'s rounding.
                KIND_RAMP => 1.0,
                _ => return Err("rbf.kinds: unknown kind"),
            };
            if !below(value, F32_LIMIT) {
                return Err("rbf.centers: a power overflows f32");
            }
            gauss_abs += center.w.abs() * value;
            if !below(gauss_abs, F32_LIMIT) {
                return Err("rbf: the correction can exceed 1e12 in the range box");
            }
            continue;
        }
        let (p, g) = (center.p, center.g);
        let alpha = g * (1.0 - c);
        let mut a_max = p + g * zz_max;
        let mut lower = p * (1.0 - c);
        let mut magnitude = lower;
        for (k, (&(a, b), &q)) in gauss.iter().zip(&center.q.0).take(nf).enumerate() {
            // A feature outside the center's mask adds nothing to its exponent (`q` is zero there,
            // [`Rbf::validate`] insists, and the masked sum skips its square).
            if !rbf.spans(j, k) {
                continue;
            }
            a_max += q.abs() * a.abs().max(b.abs());
            // u − c·A on each side of zero: (1 − c)g·t² + (q ∓ c|q|)·t.
            let right = min_quadratic(alpha, q - c * q.abs(), a.max(0.0), b);
            let left = min_quadratic(alpha, q + c * q.abs(), a, b.min(0.0));
            let m = right.min(left);
            lower += m;
            magnitude += m.abs();
        }
        if !below(a_max, F32_LIMIT) {
            return Err("rbf.centers: a Gaussian's exponent overflows f32");
        }
        // The sum above, lowered by its own rounding.
        lower -= rounding(nf + 2) * magnitude + TINY;
        if !below(MIN_EXPONENT, lower) {
            return Err("rbf.centers: a Gaussian exceeds 2^1.5 (p inconsistent with q and g)");
        }
        min_exponent = min_exponent.min(lower);
        let e = if lower >= EVAL_CUTOFF {
            0.0
        } else if lower >= 0.0 {
            1.0 + EXP2_REL_ERR
        } else {
            NEG_EXP_FACTOR * (1.0 + EXP2_REL_ERR)
        };
        gauss_abs += center.w.abs() * e;
    }
    // The evaluator's summation (m + n + 4 roundings) and this function's own rounding of the
    // magnitudes (as many again).
    let n = 2 * (rbf.centers.len() + nf + 4);
    let correction = (linear_abs + gauss_abs) * (1.0 + rounding(n));
    if !below(correction, MAX_CORRECTION) {
        return Err("rbf: the correction can exceed 1e12 in the range box");
    }
    Ok(Bound {
        correction,
        min_exponent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The exact minimum in f64 (the inputs are f32, so this is exact to ~1e-16 relative).
    fn exact_min(alpha: f32, beta: f32, a: f32, b: f32) -> f64 {
        let (al, be, a, b) = (
            f64::from(alpha),
            f64::from(beta),
            f64::from(a),
            f64::from(b),
        );
        let f = |t: f64| al * t * t + be * t;
        let t = -be / (2.0 * al);
        if al > 0.0 && t >= a && t <= b {
            f(t)
        } else {
            f(a).min(f(b))
        }
    }

    fn magnitude() -> impl Strategy<Value = f32> {
        (-25i32..16, -1.0f32..1.0).prop_map(|(e, m)| m * 10f32.powi(e))
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 20_000,
            max_global_rejects: 200_000,
            ..ProptestConfig::default()
        })]

        #[test]
        fn min_quadratic_is_a_tight_lower_bound(
            alpha in magnitude().prop_map(f32::abs),
            beta in magnitude(),
            a in magnitude(),
            b in magnitude(),
        ) {
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            // `check` refuses a center before this could overflow (`A` at its largest ≤ MAX / 2).
            let m = f64::from(a.abs().max(b.abs()));
            prop_assume!(f64::from(alpha) * m * m + f64::from(beta.abs()) * m <= f64::from(F32_LIMIT));
            let got = min_quadratic(alpha, beta, a, b);
            let exact = exact_min(alpha, beta, a, b);
            prop_assert!(f64::from(got) <= exact, "{got} > {exact}");
            // Tight: within a few ε of the terms' largest magnitudes (plus the absolute slack).
            let scale = f64::from(alpha) * f64::from(a.abs().max(b.abs())).powi(2)
                + f64::from(beta.abs()) * f64::from(a.abs().max(b.abs()));
            let slack = 1e-6 * scale + 1e-29;
            prop_assert!(f64::from(got) >= exact - slack, "{got} ≪ {exact}");
        }
    }

    #[test]
    fn an_empty_side_is_infinite_and_a_zero_alpha_uses_the_ends() {
        assert_eq!(min_quadratic(1.0, 0.0, 1.0, -1.0), f32::INFINITY);
        let v = min_quadratic(0.0, 2.0, -3.0, 5.0);
        assert!(v <= -6.0 && v > -6.0001, "{v}");
    }
}
