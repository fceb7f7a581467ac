//! From pulse counts to rate or acceleration: the channel's scale factor.
//!
//! Both instruments the counter reads are *incremental*: every pulse is a fixed quantum, so a count
//! over an interval is an increment, and the increment over the interval's length is the mean rate.
//!
//! **Ring laser gyro.** The two counter-propagating beams of a ring of enclosed area `A`, perimeter
//! `L` and wavelength `λ` beat at the Sagnac frequency `Δf = (4A / λL)·Ω`; each fringe counted is
//! an angle increment `λL / 4A` rad — typically 1–3 arcsec (an equilateral ring of 10 cm sides at
//! 632.8 nm gives 2.26″). The scale factor is therefore given in **arcsec per pulse**, and conveniently
//! `1 arcsec/s = (1/3600)° / (1/3600) h = 1 °/h`, so `rate [°/h] = counts · SF[″] / Δt [s]`.
//!
//! **Quartz accelerometer with a current-to-frequency converter.** The pendulum's rebalance current
//! is `I = K1·a` (K1 ≈ 1.2–1.4 mA/g); the I/F converter emits one pulse per charge quantum `q`, so
//! the pulse frequency is `f = K1·a / q` and `a = f · q / K1`. The scale factor is therefore given in
//! **µg per Hz** (µg per pulse-per-second, i.e. µg·s per pulse: each pulse is a velocity
//! increment), `accel [µg] = counts / Δt · SF[µg/Hz]`. With K1 = 1.25 mA/g and q = 312.5 nC the
//! converter runs at 4000 Hz/g and SF = 250 µg/Hz.
//!
//! A negative scale factor flips the axis (a sensor mounted the other way round).

use crate::error::ErrorKind;

/// Radians to arcseconds.
const ARCSEC_PER_RAD: f64 = 206_264.806_247_096_36;

/// The unit of a channel's output.
#[derive(Debug, Copy, Clone, Eq, PartialEq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unit {
    /// Angular rate, degrees per hour (a gyro channel). Increments are in arcsec.
    DegPerHour,
    /// Specific force, micro-g (an accelerometer channel). Increments are in µg·s.
    MicroG,
}

/// Scale factor of one pulse channel.
#[derive(Debug, Copy, Clone, PartialEq)]
pub struct ChannelScale {
    /// Increment per pulse: arcsec for a gyro, µg·s for an accelerometer.
    per_pulse: f32,
    unit: Unit,
}

impl ChannelScale {
    /// Any gyro channel (output in °/h) whose count — a pulse of a counter, or one LSB of a
    /// sampled rate register integrated over its period — stands for `arcsec` of rotation.
    pub const fn gyro_arcsec_per_count(arcsec: f32) -> Self {
        Self {
            per_pulse: arcsec,
            unit: Unit::DegPerHour,
        }
    }

    /// Any accelerometer channel (output in µg) whose count stands for `ug_s` µg·s of velocity
    /// change (a pulse of an I/F converter, or one LSB of a sampled register over its period).
    pub const fn accel_ug_s_per_count(ug_s: f32) -> Self {
        Self {
            per_pulse: ug_s,
            unit: Unit::MicroG,
        }
    }

    /// A ring laser gyro channel with `arcsec_per_pulse` (output in °/h).
    pub const fn rlg_arcsec_per_pulse(arcsec_per_pulse: f32) -> Self {
        Self::gyro_arcsec_per_count(arcsec_per_pulse)
    }

    /// A ring laser gyro channel from its geometry: enclosed area (m²), perimeter (m) and laser
    /// wavelength (m); one pulse is `λL / 4A` rad.
    pub fn rlg_from_geometry(area_m2: f64, perimeter_m: f64, wavelength_m: f64) -> Self {
        let rad = wavelength_m * perimeter_m / (4.0 * area_m2);
        Self::rlg_arcsec_per_pulse((rad * ARCSEC_PER_RAD) as f32)
    }

    /// A quartz accelerometer channel behind an I/F converter, with `ug_per_hz` µg per pulse/s
    /// (output in µg).
    pub const fn qma_ug_per_hz(ug_per_hz: f32) -> Self {
        Self::accel_ug_s_per_count(ug_per_hz)
    }

    /// A quartz accelerometer channel from its current scale factor `k1` (A/g) and the converter's
    /// charge quantum `q` (C per pulse): `SF = 10⁶ · q / K1` µg/Hz.
    pub fn qma_from_converter(k1_amp_per_g: f64, coulomb_per_pulse: f64) -> Self {
        Self::qma_ug_per_hz((1.0e6 * coulomb_per_pulse / k1_amp_per_g) as f32)
    }

    /// The output unit.
    pub const fn unit(&self) -> Unit {
        self.unit
    }

    /// The increment one pulse stands for (arcsec, or µg·s).
    pub const fn per_pulse(&self) -> f32 {
        self.per_pulse
    }

    /// The increment `counts` stand for: arcsec for a gyro, µg·s for an accelerometer.
    pub fn increment(&self, counts: i32) -> f32 {
        counts as f32 * self.per_pulse
    }

    /// Mean rate (°/h) or acceleration (µg) over an interval of `dt_s` seconds that produced
    /// `counts` pulses.
    ///
    /// `OutOfRange` if `dt_s` is not a positive finite number.
    pub fn rate(&self, counts: i32, dt_s: f32) -> Result<f32, ErrorKind> {
        if !crate::is_positive(dt_s) {
            return Err(ErrorKind::OutOfRange);
        }
        Ok(self.increment(counts) / dt_s)
    }
}
