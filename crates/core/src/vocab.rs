//! The names several crates must agree on: the kinds of sensor and the physical effects.
//!
//! Why here: the sensor kind travels in the blob's metadata, so the board needs it and it must live
//! in the core; the physical effects are the feature language's vocabulary (a rate, a Shupe-type
//! product, a lag, a hysteresis state are what the language's operators spell), and two host crates
//! that must not depend on each other use them: the simulator hides effects by kind, the diagnosis
//! names the missing one by kind. One enum each, with one spelling of each name, so a name cannot
//! drift between the crates.

use serde::{Deserialize, Serialize};

use crate::blob::SensorKind;

impl SensorKind {
    /// Every sensor kind, in wire-tag order.
    pub const ALL: [SensorKind; 6] = [
        SensorKind::Rlg,
        SensorKind::Qma,
        SensorKind::Ifog,
        SensorKind::MemsGyro,
        SensorKind::MemsAccel,
        SensorKind::Other,
    ];

    /// The text name (`rlg`, `qma`, `ifog`, `mems-gyro`, `mems-accel`, `other`): in command-line
    /// options, scenario files and JSON.
    pub const fn name(self) -> &'static str {
        match self {
            SensorKind::Rlg => "rlg",
            SensorKind::Qma => "qma",
            SensorKind::Ifog => "ifog",
            SensorKind::MemsGyro => "mems-gyro",
            SensorKind::MemsAccel => "mems-accel",
            SensorKind::Other => "other",
        }
    }

    /// The sensor kind of this text name, if any.
    pub fn from_name(name: &str) -> Option<SensorKind> {
        SensorKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// A physical mechanism of temperature-induced (or other) bias: what the simulator can put into a
/// run and hide, and what the diagnosis can name as missing.
///
/// The simulator simulates all but [`EffectKind::Square`] and [`EffectKind::NonThermal`], the
/// diagnosis's general forms of two of them (the curvature a polynomial lacks, any non-thermal
/// input column of which the supply voltage is one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// Polynomial in temperature.
    Poly,
    /// Rate of temperature.
    Rate,
    /// Thermal gradients between thermometers (anode−shell and cathode−shell on an RLG).
    Gradient,
    /// Shupe-type product T·dT/dt.
    Shupe,
    /// A sensing element whose temperature lags its thermometer.
    LaggedElement,
    /// Heating/cooling hysteresis.
    Hysteresis,
    /// Warm-up transient after power-on.
    Warmup,
    /// Sensitivity to the supply voltage (a non-thermal input).
    SupplyVoltage,
    /// Square of a temperature (curvature a model lacks).
    Square,
    /// A non-thermal input column (supply voltage, another channel). Serialised as
    /// `non_thermal`, as the diagnosis's JSON always has; [`EffectKind::name`] says
    /// `non_thermal_input`.
    NonThermal,
    /// Rate of a thermal gradient, d(Ta − Ts)/dt.
    GradientRate,
    /// A thermal gradient felt through a lag, lag(Ta − Ts, τ).
    GradientLag,
    /// Temperature times a thermal gradient, T·(Ta − Ts).
    TempGradientProduct,
}

impl EffectKind {
    /// Every effect, in a fixed order.
    pub const ALL: [EffectKind; 13] = [
        EffectKind::Poly,
        EffectKind::Rate,
        EffectKind::Gradient,
        EffectKind::Shupe,
        EffectKind::LaggedElement,
        EffectKind::Hysteresis,
        EffectKind::Warmup,
        EffectKind::SupplyVoltage,
        EffectKind::Square,
        EffectKind::NonThermal,
        EffectKind::GradientRate,
        EffectKind::GradientLag,
        EffectKind::TempGradientProduct,
    ];

    /// The snake_case name used in scenario files, the truth file and the diagnosis.
    pub const fn name(self) -> &'static str {
        match self {
            EffectKind::Poly => "poly",
            EffectKind::Rate => "rate",
            EffectKind::Gradient => "gradient",
            EffectKind::Shupe => "shupe",
            EffectKind::LaggedElement => "lagged_element",
            EffectKind::Hysteresis => "hysteresis",
            EffectKind::Warmup => "warmup",
            EffectKind::SupplyVoltage => "supply_voltage",
            EffectKind::Square => "square",
            EffectKind::NonThermal => "non_thermal_input",
            EffectKind::GradientRate => "gradient_rate",
            EffectKind::GradientLag => "gradient_lag",
            EffectKind::TempGradientProduct => "temp_gradient_product",
        }
    }

    /// The effect of this name, if any.
    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_are_distinct() {
        for (i, k) in SensorKind::ALL.into_iter().enumerate() {
            assert_eq!(SensorKind::from_name(k.name()), Some(k));
            assert!(SensorKind::ALL[..i].iter().all(|o| o.name() != k.name()));
        }
        for (i, k) in EffectKind::ALL.into_iter().enumerate() {
            assert_eq!(EffectKind::from_name(k.name()), Some(k));
            assert!(EffectKind::ALL[..i].iter().all(|o| o.name() != k.name()));
        }
        assert_eq!(SensorKind::from_name("RLG"), None);
        assert_eq!(EffectKind::from_name(""), None);
    }

    #[test]
    fn the_blob_keeps_the_sensor_kind_as_its_wire_tag() {
        // postcard is not human-readable: the tag is the variant index, as before the names.
        for (i, k) in SensorKind::ALL.into_iter().enumerate() {
            let mut buf = [0u8; 4];
            let bytes = postcard::to_slice(&k, &mut buf).unwrap();
            assert_eq!(bytes, &[i as u8][..]);
            assert_eq!(postcard::from_bytes::<SensorKind>(bytes).unwrap(), k);
        }
    }
}
