//! The exponential of the Gaussian basis, fast on a Cortex-M4F.
//!
//! The RBF evaluator needs one `exp(-a)` per center per sample, so this is the hot spot. `libm::expf`
//! is accurate but branchy and covers the whole range; here the argument is bounded (the evaluator
//! skips `a ≥ EXP_CUTOFF`, where `e^-a < 2.1e-9`). The evaluator works in *eval units*
//! `u = a·16·log2(e)` (the factor is folded into the stored coefficients, see [`crate::rbf`]), so
//! that `exp(-a) = 2^(-u/16)`:
//!
//! 1. `m = round(u)` by the "magic number" addition (no float→int conversion), `d = u − m ∈ [−½, ½]`;
//! 2. `2^(-m/16)` from a 512-entry table (2 KiB of flash), indexed by the low mantissa bits of the
//!    rounded sum — no exponent arithmetic; the top 24 entries hold `2^(+i/16)` so that the slightly
//!    negative `u` that rounding in the expanded distance can produce still index correctly;
//! 3. `2^(-d/16)` by a degree-2 polynomial (|d/16| ≤ 1/32: truncation error 1.7e-6).
//!
//! The table size trades flash against accuracy: 1,024 entries at 1/32 steps gave 2e-7 but cost 4 KiB
//! of the firmware's 32 KiB; 1.7e-6 of one Gaussian's value is far below the f32 rounding of the
//! expanded distance (see [`crate::rbf`]) and any sensor's noise.
//!
//! About 12 instructions and no branch. Maximum error against `libm::expf` over
//! `a ∈ [0, EXP_CUTOFF]` on a grid of 2·10⁵ points (test `max_error_against_libm`): see the
//! constants asserted there (3e-6 relative — 2.6e-6 measured —, 2e-6 absolute). The relative error grows with `a`
//! only because `u` itself is an f32 (libm carries extra bits in its range reduction).
//! Only f32 `+ - *`, a bit mask and a table load are used (no fused multiply-add), so host and target
//! produce the same bits.

/// Natural-exponent arguments at or above this give `exp(-a) < 2.1e-9`: treated as zero.
pub const EXP_CUTOFF: f32 = 20.0;
/// `16·log2(e)`: natural exponent → eval units.
pub const EVAL_UNITS_PER_NAT: f32 = 23.08312;
/// [`EXP_CUTOFF`] in eval units (≈ 462, inside the table's 488 non-negative entries).
pub const EVAL_CUTOFF: f32 = EXP_CUTOFF * EVAL_UNITS_PER_NAT;
/// Relative error bound of [`exp2_16_neg`] against `2^(−u/16)` on `u ∈ [−24, EVAL_CUTOFF)`, with a
/// margin over the measured 2.6e-6 (test `relative_error_bound_holds_on_the_whole_domain`); the
/// plausibility bound of [`crate::bound`] relies on it.
pub const EXP2_REL_ERR: f32 = 1.0e-5;

/// 1.5 · 2^23: adding it rounds an f32 of magnitude < 2^22 to the nearest integer, which then sits
/// in the low mantissa bits (offset by 2^22, a multiple of the table size).
const ROUND_MAGIC: f32 = 12_582_912.0;
/// `2^(-d/16) ≈ 1 + d·(K1 + d·K2)`, `K1 = −ln2/16`, `K2 = (ln2/16)²/2`.
const K1: f32 = -0.043_321_7;
const K2: f32 = 0.000_938_384_8;
const TABLE_LEN: usize = 512;
/// Entries from here on stand for negative `m` (wrapped indices).
const NEGATIVE_FROM: usize = 488;

/// `T[j] = 2^(-j/16)` for `j < 488`, and `2^((512 − j)/16)` above (negative `m` wrapped).
/// Computed in f64 at compile time and rounded once.
static EXP2_TABLE: [f32; TABLE_LEN] = {
    let mut t = [0.0f32; TABLE_LEN];
    // 2^(-1/16) and its inverse in f64; repeated multiplication in f64 loses < 1e-13 over 488 steps.
    const STEP_DOWN: f64 = 0.957_603_280_698_573_7;
    const STEP_UP: f64 = 1.044_273_782_427_413_8;
    let mut v = 1.0f64;
    let mut j = 0;
    while j < NEGATIVE_FROM {
        t[j] = v as f32;
        v *= STEP_DOWN;
        j += 1;
    }
    let mut v = STEP_UP;
    let mut j = TABLE_LEN - 1;
    while j >= NEGATIVE_FROM {
        t[j] = v as f32;
        v *= STEP_UP;
        j -= 1;
    }
    t
};

/// `2^(-u/16)` for `u ∈ [−24, 487]` (eval units). Nothing panics outside that domain, but the result
/// is wrong there: down to `u ≈ −2²²` it is a wrapped table entry (finite, at most ~2.9); beyond, the
/// rounding trick fails and it is any finite value up to ~1e11; a NaN or infinite `u` (an exponent
/// that overflowed) gives NaN. The evaluator skips `u ≥ EVAL_CUTOFF`, and decoding refuses a model
/// whose `u` can overflow or fall below −24 in its range box (see [`crate::bound`]).
#[inline(always)]
pub fn exp2_16_neg(u: f32) -> f32 {
    let shifted = ROUND_MAGIC + u;
    let m = shifted - ROUND_MAGIC; // nearest integer to u, exactly
    let d = u - m; // in [−½, ½]
    let index = (shifted.to_bits() as usize) & (TABLE_LEN - 1);
    let base = EXP2_TABLE.get(index).copied().unwrap_or(0.0);
    // base·(1 + d·q) written as base + (base·d)·q: the multiply-add then accumulates into `base`,
    // which is dead afterwards, so the M4's destructive VMLA needs no register copy.
    let q = K1 + d * K2;
    base + (base * d) * q
}

/// `exp(-a)`: 1 for NaN and `a ≤ 0`, 0 for `a ≥ EXP_CUTOFF` (the evaluator's flush to zero).
#[inline]
pub fn exp_neg(a: f32) -> f32 {
    if a >= EXP_CUTOFF {
        return 0.0;
    }
    let a = if a >= 0.0 { a } else { 0.0 };
    exp2_16_neg(a * EVAL_UNITS_PER_NAT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_error_against_libm() {
        let (mut worst_rel, mut worst_abs, mut worst_rel_small) = (0.0f32, 0.0f32, 0.0f32);
        for i in 0..200_000 {
            let a = i as f32 * (EXP_CUTOFF / 200_000.0);
            let exact = libm::expf(-a);
            let err = (exp_neg(a) - exact).abs();
            worst_rel = worst_rel.max(err / exact);
            worst_abs = worst_abs.max(err);
            if a < 2.0 {
                worst_rel_small = worst_rel_small.max(err / exact);
            }
        }
        assert!(worst_rel < 3.0e-6, "max relative error {worst_rel}");
        assert!(worst_abs < 2.0e-6, "max absolute error {worst_abs}");
        assert!(
            worst_rel_small < 2.0e-6,
            "max relative error for a < 2: {worst_rel_small}"
        );
    }

    #[test]
    fn table_is_exact_powers() {
        for (j, v) in EXP2_TABLE.iter().enumerate() {
            let e = if j < NEGATIVE_FROM {
                -(j as f64)
            } else {
                (TABLE_LEN - j) as f64
            };
            let exact = libm::exp2(e / 16.0);
            assert!(((*v as f64 - exact) / exact).abs() < 6.0e-8, "j = {j}");
        }
    }

    #[test]
    fn defined_outside_the_domain() {
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-5.0), 1.0);
        assert_eq!(exp_neg(f32::NAN), 1.0);
        assert_eq!(exp_neg(1.0e30), 0.0);
        // Slightly negative eval-unit arguments (rounding in the expanded distance) stay accurate.
        for u in [-0.4f32, -3.0, -23.5] {
            let exact = libm::exp2f(-u / 16.0);
            assert!(((exp2_16_neg(u) - exact) / exact).abs() < 2e-6, "u = {u}");
        }
        assert!(exp2_16_neg(5.0e6).is_finite());
    }

    #[test]
    fn relative_error_bound_holds_on_the_whole_domain() {
        // Every f32 step of 1/64 over [−24, EVAL_CUTOFF), plus the exact ends.
        let mut u = -24.0f32;
        let mut worst = 0.0f64;
        while u < EVAL_CUTOFF {
            let exact = libm::exp2(-f64::from(u) / 16.0);
            let rel = (f64::from(exp2_16_neg(u)) - exact) / exact;
            worst = worst.max(rel);
            u += 1.0 / 64.0;
        }
        assert!(worst < f64::from(EXP2_REL_ERR), "worst excess {worst}");
        assert!(worst > 0.0, "the check could fail");
    }

    #[test]
    fn outside_the_domain_it_is_finite_but_wrong_and_nan_for_non_finite_arguments() {
        // What the plausibility bound must keep the evaluator away from.
        assert!(exp2_16_neg(f32::NAN).is_nan());
        assert!(exp2_16_neg(f32::NEG_INFINITY).is_nan());
        assert!(exp2_16_neg(f32::INFINITY).is_nan());
        // Down to −2²² the rounding trick works: a wrapped table entry, at most 2^1.5·(1 + 1/45).
        let mut u = -24.0f32;
        while u > -4.0e6 {
            let v = exp2_16_neg(u);
            assert!(v.is_finite() && v <= 2.9, "u = {u}: {v}");
            u *= 1.01;
        }
        // Beyond, still finite but not an exponential at all.
        let mut u = -4.2e6f32;
        while u > -3.0e38 {
            assert!(exp2_16_neg(u).is_finite(), "u = {u}");
            u *= 1.37;
        }
        assert!(exp2_16_neg(-f32::MAX).is_finite());
    }
}
