//! The number type a feature program is compiled and evaluated in: `f32` on the board, `f64` on the
//! host.
//!
//! Why a trait: the board evaluates its features in f32, and the simulator must compute the same
//! features exactly (its truth file promises the bias *is* the listed expressions), where f32 would
//! lose the time column and the slow lags to rounding. Rather than a second implementation of the
//! operators, the program, its compiler and its streaming evaluator are generic over [`Real`], as
//! idsp's filters are over their sample type; each precision is monomorphised, so the f32 code the
//! firmware runs is the same as a hand-written f32 version. Only the operations the language needs
//! are here, all from `libm` so `no_std` builds have them.

use core::fmt::Debug;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// A floating-point type a feature program can be compiled and evaluated in.
pub trait Real:
    Copy
    + Debug
    + Default
    + PartialEq
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// A quiet NaN.
    const NAN: Self;
    /// The value of an `f32` (exact: every f32 is representable).
    fn from_f32(v: f32) -> Self;
    /// A small count (argument counts of `mean`), exactly.
    fn from_u8(v: u8) -> Self;
    /// `e^self`.
    fn exp(self) -> Self;
    /// `e^self − 1`, accurate near 0.
    fn exp_m1(self) -> Self;
    /// `|self|`.
    fn abs(self) -> Self;
    /// Neither NaN nor infinite.
    fn is_finite(self) -> bool;
    /// A decimal number as Rust's `str::parse` reads it (nearest value), or `None`.
    fn parse(text: &str) -> Option<Self>;
    /// The whole number `m` (1 ≤ m ≤ 2²⁴) that `self` is within `10⁻³ + 10⁻⁶·m` of (rounding, not
    /// jitter), if any: a gap of `Δ/δ` nominal steps that is a run of whole missed steps (see
    /// [`crate::eval`]).
    fn whole(self) -> Option<u32>;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const NAN: Self = f32::NAN;
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn from_u8(v: u8) -> Self {
        f32::from(v)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        libm::expf(self)
    }
    #[inline(always)]
    fn exp_m1(self) -> Self {
        libm::expm1f(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    fn parse(text: &str) -> Option<Self> {
        text.parse().ok()
    }
    fn whole(self) -> Option<u32> {
        let m = libm::roundf(self);
        ((1.0..=16_777_216.0).contains(&m) && libm::fabsf(self - m) <= 1e-3 + 1e-6 * m)
            .then_some(m as u32)
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const NAN: Self = f64::NAN;
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        f64::from(v)
    }
    #[inline(always)]
    fn from_u8(v: u8) -> Self {
        f64::from(v)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        libm::exp(self)
    }
    #[inline(always)]
    fn exp_m1(self) -> Self {
        libm::expm1(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    fn parse(text: &str) -> Option<Self> {
        text.parse().ok()
    }
    fn whole(self) -> Option<u32> {
        let m = libm::round(self);
        ((1.0..=16_777_216.0).contains(&m) && libm::fabs(self - m) <= 1e-3 + 1e-6 * m)
            .then_some(m as u32)
    }
}
