//! Sensor front ends of an IMU board, on embedded-hal 1.0 traits.
//!
//! The compensation loop needs two things from the hardware at every sample: the temperatures of the
//! instrument (°C) and the pulses its rate or acceleration outputs produced since the previous sample.
//! embedded-hal 1.0 has no ADC or counter trait, so this crate defines both in embedded-hal's shape
//! (an [`ErrorType`] whose error has a [`kind()`](Error::kind) in a small [`ErrorKind`]):
//!
//! - [`Thermometer`] — one temperature channel, in °C;
//! - [`PulseCounter`] — one up/down pulse channel, counts since the previous read;
//! - [`CounterSnapshot`] — a block of pulse channels latched together, read once per sample.
//!
//! and drivers for real parts on [`embedded_hal::spi::SpiDevice`]:
//!
//! - [`ads1220`] — TI ADS1220 24-bit delta-sigma ADC, measuring an RTD ratiometrically; [`rtd`] turns
//!   its resistance into °C with Callendar–Van Dusen (IEC 60751); [`thermistor`] offers Steinhart–Hart;
//! - [`pulse_counter`] — an FPGA/CPLD up/down counter block (register map documented there) that
//!   samples all RLG and QMA pulse channels at the same instant; [`scale`] turns counts per interval
//!   into deg/h or µg.
//!
//! Everything here is `no_std`, allocation-free and panic-free, and every driver is tested on the host
//! against `embedded-hal-mock` transaction queues. A board that replays recorded data (the QEMU run)
//! implements [`Thermometer`] and [`PulseCounter`] itself; nothing else is needed.
#![no_std]

pub mod ads1220;
pub mod counter;
pub mod error;
pub mod on_ready;
pub mod pulse_counter;
pub mod rtd;
pub mod scale;
pub mod thermistor;
pub mod thermometer;

pub use counter::{CounterSnapshot, Interval, PulseCounter, wrapping_delta};
pub use error::{Error, ErrorKind, ErrorType};
pub use on_ready::OnReady;
pub use thermometer::Thermometer;

/// `x` is a finite number greater than zero (false for NaN).
#[inline]
pub(crate) fn is_positive(x: f32) -> bool {
    x.is_finite() && x > 0.0
}
