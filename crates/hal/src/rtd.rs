//! Platinum RTD resistance ⇄ temperature: the Callendar–Van Dusen equation (IEC 60751).
//!
//! A platinum resistance thermometer (PT100: R0 = 100 Ω, PT1000: R0 = 1000 Ω at 0 °C) follows
//!
//! ```text
//! R(T) = R0 · (1 + A·T + B·T²)                      for 0 °C ≤ T ≤ 850 °C
//! R(T) = R0 · (1 + A·T + B·T² + C·(T − 100)·T³)     for −200 °C ≤ T < 0 °C
//! ```
//!
//! with the IEC 60751 coefficients A = 3.9083·10⁻³ /°C, B = −5.775·10⁻⁷ /°C², C = −4.183·10⁻¹² /°C⁴
//! (individually calibrated sensors have their own, hence [`Rtd::with_coefficients`]).
//!
//! The inverse is what a thermometer needs. Above 0 °C the quadratic has a closed form; it is
//! evaluated as `T = 2x / (A + √(A² + 4B·x))` with `x = R/R0 − 1`, the form without the cancellation
//! of the textbook `(−A + √…)/(2B)` (which loses about 0.2 mK in `f32` near 0 °C). Below 0 °C the quartic
//! has no convenient closed form: Newton's method starts from the quadratic's root (within 2.5 K at
//! −200 °C) and runs a fixed [`NEWTON_STEPS`] steps — quadratic convergence makes that far below
//! `f32` resolution, and a fixed count keeps the time per sample bounded.
//!
//! Outside −200…850 °C the equation is not defined: both directions return
//! [`ErrorKind::OutOfRange`] rather than extrapolate.

use crate::error::ErrorKind;
use crate::is_positive;

/// Number of Newton steps of the inverse below 0 °C (fixed; there is no convergence loop).
pub const NEWTON_STEPS: usize = 4;

/// A platinum RTD: its resistance at 0 °C and its Callendar–Van Dusen coefficients.
#[derive(Debug, Copy, Clone, PartialEq)]
pub struct Rtd {
    r0: f32,
    a: f32,
    b: f32,
    c: f32,
}

impl Rtd {
    /// IEC 60751 coefficient A (/°C).
    pub const IEC_A: f32 = 3.9083e-3;
    /// IEC 60751 coefficient B (/°C²).
    pub const IEC_B: f32 = -5.775e-7;
    /// IEC 60751 coefficient C (/°C⁴), used below 0 °C only.
    pub const IEC_C: f32 = -4.183e-12;
    /// Lowest temperature the equation covers (°C).
    pub const T_MIN: f32 = -200.0;
    /// Highest temperature the equation covers (°C).
    pub const T_MAX: f32 = 850.0;

    /// PT100 with IEC 60751 coefficients.
    pub const PT100: Rtd = Rtd::iec60751(100.0);
    /// PT1000 with IEC 60751 coefficients.
    pub const PT1000: Rtd = Rtd::iec60751(1000.0);

    /// An IEC 60751 platinum RTD of nominal resistance `r0_ohm` at 0 °C.
    pub const fn iec60751(r0_ohm: f32) -> Self {
        Self::with_coefficients(r0_ohm, Self::IEC_A, Self::IEC_B, Self::IEC_C)
    }

    /// An RTD with individually calibrated coefficients.
    pub const fn with_coefficients(r0_ohm: f32, a: f32, b: f32, c: f32) -> Self {
        Self {
            r0: r0_ohm,
            a,
            b,
            c,
        }
    }

    /// Resistance at 0 °C (Ω).
    pub const fn r0(&self) -> f32 {
        self.r0
    }

    /// Resistance at the lowest temperature covered, [`Rtd::T_MIN`] (18.52 Ω for a PT100).
    pub fn r_min(&self) -> f32 {
        self.resistance_unchecked(Self::T_MIN)
    }

    /// Resistance at the highest temperature covered, [`Rtd::T_MAX`] (390.48 Ω for a PT100).
    pub fn r_max(&self) -> f32 {
        self.resistance_unchecked(Self::T_MAX)
    }

    /// `R/R0` by Callendar–Van Dusen, without a range check.
    fn ratio(&self, t: f32) -> f32 {
        if t >= 0.0 {
            1.0 + t * (self.a + t * self.b)
        } else {
            // C·(T − 100)·T³ folded into Horner's scheme.
            1.0 + t * (self.a + t * (self.b + self.c * (t - 100.0) * t))
        }
    }

    /// d(R/R0)/dT below 0 °C.
    fn ratio_slope_below_zero(&self, t: f32) -> f32 {
        // A + 2BT + C(4T³ − 300T²)
        self.a + t * (2.0 * self.b + t * self.c * (4.0 * t - 300.0))
    }

    fn resistance_unchecked(&self, t: f32) -> f32 {
        self.r0 * self.ratio(t)
    }

    /// Resistance (Ω) at temperature `t_c` (°C).
    ///
    /// `OutOfRange` outside −200…850 °C or for a non-finite input.
    pub fn resistance(&self, t_c: f32) -> Result<f32, ErrorKind> {
        if !(Self::T_MIN..=Self::T_MAX).contains(&t_c) {
            return Err(ErrorKind::OutOfRange);
        }
        Ok(self.resistance_unchecked(t_c))
    }

    /// Temperature (°C) of resistance `r_ohm` (Ω).
    ///
    /// `OutOfRange` if the resistance is not finite or corresponds to a temperature outside
    /// −200…850 °C.
    pub fn temperature(&self, r_ohm: f32) -> Result<f32, ErrorKind> {
        if !is_positive(self.r0) || !(self.r_min()..=self.r_max()).contains(&r_ohm) {
            return Err(ErrorKind::OutOfRange);
        }
        let x = r_ohm / self.r0 - 1.0;
        // Root of the quadratic (exact above 0 °C, the starting point below).
        let disc = self.a * self.a + 4.0 * self.b * x;
        if disc.is_nan() || disc < 0.0 {
            return Err(ErrorKind::OutOfRange);
        }
        let denom = self.a + libm::sqrtf(disc);
        if !is_positive(denom) {
            return Err(ErrorKind::OutOfRange);
        }
        let mut t = 2.0 * x / denom;
        if x < 0.0 {
            let target = r_ohm / self.r0;
            for _ in 0..NEWTON_STEPS {
                let slope = self.ratio_slope_below_zero(t);
                if !is_positive(slope) {
                    return Err(ErrorKind::OutOfRange);
                }
                t -= (self.ratio(t) - target) / slope;
            }
        }
        if !t.is_finite() {
            return Err(ErrorKind::OutOfRange);
        }
        // The range check above was on R; rounding may put T a hair outside.
        Ok(t.clamp(Self::T_MIN, Self::T_MAX))
    }
}
