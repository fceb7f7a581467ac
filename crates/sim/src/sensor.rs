//! What the simulator knows about each sensor kind it simulates: thermometers, output column and
//! unit, noise, reference.
//!
//! Why a trait on the core's [`SensorKind`]: the sensor kinds and their text names are defined
//! once, in the core (the blob carries them); the simulator adds only its physics. It simulates
//! the RLG, the QMA and the IFOG ([`SIMULATED`]); a scenario of any other kind is refused by
//! [`check_simulated`], naming the field.

use tcomp_core::SensorKind;

use crate::error::{Error, Result};
use crate::noise::NoiseSpec;
use crate::thermal::ThermometerSpec;

/// Earth rate, °/h.
pub const EARTH_RATE_DPH: f64 = 15.041;

/// The sensor kinds the simulator simulates.
pub const SIMULATED: [SensorKind; 3] = [SensorKind::Rlg, SensorKind::Qma, SensorKind::Ifog];

/// Whether the simulator simulates `kind`.
pub fn is_simulated(kind: SensorKind) -> bool {
    SIMULATED.contains(&kind)
}

/// The names of the simulated kinds, comma-separated (for error messages).
pub fn simulated_names() -> String {
    SIMULATED.map(|k| k.name()).join(", ")
}

/// Refuses a sensor kind the simulator does not simulate; the error names `field`.
pub fn check_simulated(kind: SensorKind, field: &str) -> Result<()> {
    if is_simulated(kind) {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!(
                "sensor \"{}\" is not simulated (the simulator simulates {})",
                kind.name(),
                simulated_names()
            ),
        ))
    }
}

/// The simulator's view of a sensor kind. For a kind it does not simulate, the values are those of
/// the nearest simulated one (accelerometers: the QMA's outputs, gyros: the IFOG's) and there are
/// no thermometers; such a scenario never runs (see [`check_simulated`]).
pub trait SensorExt: Copy {
    /// Output unit as written in the truth file (`deg/h` or `ug`).
    fn unit(self) -> &'static str;
    /// Output column (`gyro_dph` or `accel_ug`).
    fn output_column(self) -> &'static str;
    /// Reference column (`ref_dph` or `ref_ug`).
    fn reference_column(self) -> &'static str;
    /// Decimals written for the output and reference columns.
    fn output_decimals(self) -> usize;
    /// Default thermometers with realistic time constants and self-heating.
    fn default_thermometers(self) -> Vec<ThermometerSpec>;
    /// Default output noise: navigation grade.
    fn default_noise(self) -> NoiseSpec;
    /// Default reference: vertical earth-rate component at 45° latitude for gyros, 1 g for
    /// accelerometers.
    fn default_reference(self) -> f64;
    /// Whether the output is an acceleration (µg) rather than a rate (°/h).
    fn is_accelerometer(self) -> bool;
}

impl SensorExt for SensorKind {
    fn is_accelerometer(self) -> bool {
        matches!(self, SensorKind::Qma | SensorKind::MemsAccel)
    }

    fn unit(self) -> &'static str {
        if self.is_accelerometer() {
            "ug"
        } else {
            "deg/h"
        }
    }

    fn output_column(self) -> &'static str {
        if self.is_accelerometer() {
            "accel_ug"
        } else {
            "gyro_dph"
        }
    }

    fn reference_column(self) -> &'static str {
        if self.is_accelerometer() {
            "ref_ug"
        } else {
            "ref_dph"
        }
    }

    fn output_decimals(self) -> usize {
        if self.is_accelerometer() { 3 } else { 6 }
    }

    fn default_thermometers(self) -> Vec<ThermometerSpec> {
        match self {
            SensorKind::Rlg => vec![
                ThermometerSpec::new("t_anode_c", 1100.0, 3.0, 900.0),
                ThermometerSpec::new("t_cathode_c", 1300.0, 2.0, 1200.0),
                ThermometerSpec::new("t_shell_c", 800.0, 0.8, 1800.0),
            ],
            SensorKind::Qma => vec![ThermometerSpec::new("t_qma_c", 900.0, 0.6, 1200.0)],
            SensorKind::Ifog => vec![ThermometerSpec::new("t_coil_c", 1200.0, 1.0, 1800.0)],
            SensorKind::MemsGyro | SensorKind::MemsAccel | SensorKind::Other => Vec::new(),
        }
    }

    fn default_noise(self) -> NoiseSpec {
        match self {
            // ARW 0.003 °/√h, BI 0.003 °/h, 0.5″ pulses (after 4× interpolation).
            SensorKind::Rlg => NoiseSpec::gyro(0.003, 0.003, 600.0, 0.5),
            // VRW 10 µg/√Hz, BI 5 µg, 50 µg·s pulses.
            SensorKind::Qma | SensorKind::MemsAccel => NoiseSpec::accel(10.0, 5.0, 600.0, 50.0),
            // ARW 0.005 °/√h, BI 0.01 °/h, closed-loop digital output (no pulse quantisation).
            SensorKind::Ifog | SensorKind::MemsGyro | SensorKind::Other => {
                NoiseSpec::gyro(0.005, 0.01, 600.0, 0.0)
            }
        }
    }

    fn default_reference(self) -> f64 {
        if self.is_accelerometer() {
            1.0e6
        } else {
            EARTH_RATE_DPH * 45f64.to_radians().sin()
        }
    }
}
