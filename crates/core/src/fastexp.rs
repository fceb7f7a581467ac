//! The exponential of the Gaussian basis, `exp(-a)` for `a ≥ 0`, fast on a Cortex-M4F.
//!
//! The RBF evaluator calls it once per center per sample, so it is the hot spot. `libm::expf` is
//! accurate but branches heavily and handles the whole range; here `a` is never negative and a
//! result below `EXP_CUTOFF` is worthless next to the other centers, so a short branch-light form does:
//!
//! 1. `t = -a·log2(e)`, split into `t = n + r` with `n` an integer and `r ∈ [-0.5, 0.5]` by the
//!    round-to-nearest "magic number" addition (no float→int conversion instruction needed);
//! 2. `2^r` by a degree-5 polynomial fitted for relative error (1.0e-7 on the interval in exact
//!    arithmetic);
//! 3. `2^n` by writing `n + 127` into the exponent bits.
//!
//! Maximum error against `libm::expf` over `a ∈ [0, EXP_CUTOFF]`, on a grid of 2·10⁵ points (test
//! `max_error_against_libm`): 1.1e-6 relative, and below 1.5e-7 absolute. The relative error grows with
//! `a` because `a·log2(e)` is rounded to f32 (libm carries extra bits in its range reduction); it is
//! about 3e-7 for `a < 2`, where the Gaussians that matter live. Only f32 `+ - *` and bit moves are used
//! (no fused multiply-add), so host and target produce the same bits.

/// Arguments above this give `exp(-a) < 2.1e-9`, which the evaluator treats as zero.
pub const EXP_CUTOFF: f32 = 20.0;

/// 1.5 · 2^23: adding it rounds an f32 of magnitude < 2^22 to the nearest integer.
const ROUND_MAGIC: f32 = 12_582_912.0;
const LOG2_E: f32 = core::f32::consts::LOG2_E;
// 2^r ≈ 1 + Σ Ck·r^k on [-0.5, 0.5]: a relative least-squares fit on Chebyshev nodes
// (1.0e-7 relative in exact arithmetic; Taylor coefficients of the same degree give 3.7e-6).
const C1: f32 = 0.693_146_9;
const C2: f32 = 0.240_222_38;
const C3: f32 = 0.055_508_93;
const C4: f32 = 0.009_671_708;
const C5: f32 = 0.001_321_867_7;

/// `exp(-a)` for `a ∈ [0, EXP_CUTOFF]`; callers skip larger arguments. Outside that domain the result is
/// still finite and non-negative (never a panic), but not accurate.
#[inline(always)]
pub fn exp_neg(a: f32) -> f32 {
    // Keep 2^n a normal number (n ≥ -126) whatever the caller passes; NaN and negatives become 0.
    let a = if a > 87.0 {
        87.0
    } else if a >= 0.0 {
        a
    } else {
        0.0
    };
    let t = -a * LOG2_E;
    let shifted = t + ROUND_MAGIC;
    let n = shifted - ROUND_MAGIC; // nearest integer to t, exactly
    let r = t - n; // in [-0.5, 0.5]
    let p = 1.0 + r * (C1 + r * (C2 + r * (C3 + r * (C4 + r * C5))));
    // The low mantissa bits of `shifted` hold n in two's complement (|n| < 2^22).
    let n_int = (shifted.to_bits() as i32).wrapping_sub(ROUND_MAGIC.to_bits() as i32);
    let scale = f32::from_bits(((n_int + 127) as u32) << 23);
    p * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_error_against_libm() {
        let (mut worst_rel, mut worst_abs, mut worst_rel_small) = (0.0f32, 0.0f32, 0.0f32);
        for i in 0..=200_000 {
            let a = i as f32 * (EXP_CUTOFF / 200_000.0);
            let exact = libm::expf(-a);
            let err = (exp_neg(a) - exact).abs();
            worst_rel = worst_rel.max(err / exact);
            worst_abs = worst_abs.max(err);
            if a < 2.0 {
                worst_rel_small = worst_rel_small.max(err / exact);
            }
        }
        assert!(worst_rel < 1.5e-6, "max relative error {worst_rel}");
        assert!(worst_abs < 1.5e-7, "max absolute error {worst_abs}");
        assert!(
            worst_rel_small < 4.0e-7,
            "max relative error for a < 2: {worst_rel_small}"
        );
    }

    #[test]
    fn exact_at_zero_and_bounded_outside_domain() {
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-5.0), 1.0);
        assert!(exp_neg(1.0e30) > 0.0 && exp_neg(1.0e30) < 1.0e-37);
        assert_eq!(exp_neg(f32::NAN), 1.0);
    }
}
