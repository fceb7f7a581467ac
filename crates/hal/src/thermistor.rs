//! NTC thermistor resistance ⇄ temperature: the Steinhart–Hart equation.
//!
//! For boards that measure a thermistor rather than an RTD (cheaper, more sensitive, narrower
//! range), the standard three-term model is
//!
//! ```text
//! 1/T = a + b·ln R + c·(ln R)³        (T in kelvin, R in ohms)
//! ```
//!
//! with `a, b, c` fitted from three calibration points (the part's datasheet or a chamber run).
//! The inverse (temperature → resistance, used by tests and simulators) is the closed-form root of
//! the depressed cubic in `ln R`. The equation is only trusted between the calibration limits given
//! to [`SteinhartHart::new`]; outside them both directions return [`ErrorKind::OutOfRange`].

use crate::error::ErrorKind;
use crate::is_positive;

const KELVIN: f32 = 273.15;

/// Steinhart–Hart coefficients and the temperature range they were fitted over.
#[derive(Debug, Copy, Clone, PartialEq)]
pub struct SteinhartHart {
    a: f32,
    b: f32,
    c: f32,
    t_min: f32,
    t_max: f32,
}

impl SteinhartHart {
    /// A fit widely used in examples for a nominal 10 kΩ NTC (it gives 9.877 kΩ at 25 °C), taken as
    /// valid −40…125 °C. Replace it with the coefficients of the actual part.
    pub const EXAMPLE_10K: SteinhartHart =
        SteinhartHart::new(1.009_249_5e-3, 2.378_405_4e-4, 2.019_202_7e-7, -40.0, 125.0);

    /// Coefficients `a` (1/K), `b` (1/K), `c` (1/K), trusted from `t_min_c` to `t_max_c` (°C).
    pub const fn new(a: f32, b: f32, c: f32, t_min_c: f32, t_max_c: f32) -> Self {
        Self {
            a,
            b,
            c,
            t_min: t_min_c,
            t_max: t_max_c,
        }
    }

    /// Temperature (°C) of resistance `r_ohm`.
    pub fn temperature(&self, r_ohm: f32) -> Result<f32, ErrorKind> {
        if !is_positive(r_ohm) {
            return Err(ErrorKind::OutOfRange);
        }
        let l = libm::logf(r_ohm);
        let inv_t = self.a + l * (self.b + self.c * l * l);
        if !is_positive(inv_t) {
            return Err(ErrorKind::OutOfRange);
        }
        let t = 1.0 / inv_t - KELVIN;
        if !(self.t_min..=self.t_max).contains(&t) {
            return Err(ErrorKind::OutOfRange);
        }
        Ok(t)
    }

    /// Resistance (Ω) at temperature `t_c` (°C).
    pub fn resistance(&self, t_c: f32) -> Result<f32, ErrorKind> {
        if !(self.t_min..=self.t_max).contains(&t_c) || self.c == 0.0 {
            return Err(ErrorKind::OutOfRange);
        }
        // c·L³ + b·L + (a − 1/T) = 0  →  L = ∛(y − x/2) − ∛(y + x/2)
        let x = (self.a - 1.0 / (t_c + KELVIN)) / self.c;
        let p = self.b / (3.0 * self.c);
        let y = libm::sqrtf(p * p * p + 0.25 * x * x);
        let l = libm::cbrtf(y - 0.5 * x) - libm::cbrtf(y + 0.5 * x);
        let r = libm::expf(l);
        if r.is_finite() && r > 0.0 {
            Ok(r)
        } else {
            Err(ErrorKind::OutOfRange)
        }
    }
}
