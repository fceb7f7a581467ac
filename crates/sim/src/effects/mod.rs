//! Named bias effects and their exact feature expressions: one module per effect behind
//! [`EffectModel`], listed once in the registry below.
//!
//! Why: tests and demos need a bias whose parts are known by name, so that a diagnosis can be checked
//! against "the effect that is really there". Each effect is evaluated from the *recorded* columns of
//! the output file, sample by sample with the core's own streaming filters in f64 (the aliases below), so the
//! expressions written to the truth file reproduce the bias exactly (to float rounding): a perfect
//! model is limited only by the noise.
//!
//! Adding an effect: a module here with a struct (its TOML keys, serde), its [`EffectModel`] impl
//! (validation, streaming state, default for a sensor, truth description), one line in the
//! registry, and its name in [`EffectKind`] (the core's vocabulary, which the diagnosis shares).

mod context;
mod pair;
mod text;

use serde::{Deserialize, Serialize};
pub use tcomp_core::EffectKind;
use tcomp_core::SensorKind;

pub(crate) use context::{Context, RowInputs};

use crate::error::{Error, Result};

/// The rate window an effect uses when its file gives none: the feature language's default.
pub(crate) const RATE_WINDOW_S: f64 = tcomp_core::lang::DEFAULT_RATE_WINDOW_S as f64;
/// The core's first-order lag in f64: the same code the board runs in f32.
pub(crate) type LagFilter = tcomp_core::eval::Lag<f64>;
/// The core's windowed rate in f64.
pub(crate) type RateFilter = tcomp_core::eval::Rate<f64>;
/// The core's hysteresis relay in f64.
pub(crate) type HystFilter = tcomp_core::eval::Hyst<f64>;

/// What one effect does; each effect module implements it for its parameter struct.
pub(crate) trait EffectModel: Sized {
    /// Which effect this is.
    const KIND: EffectKind;

    /// A realistic default for `sensor`: well above the noise floor of that sensor (°/h for the
    /// gyros, µg for the accelerometers).
    fn default_for(sensor: SensorKind) -> Self;

    /// Whether the effect can be applied to this sensor.
    fn applies_to(_sensor: SensorKind) -> bool {
        true
    }

    /// Checks the parameters for the sensor in `ctx`; errors name `<at>.<field>`.
    fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()>;

    /// The streaming state computing the effect from rows of period `dt`. Assumes a validated effect.
    fn state(&self, ctx: &Context<'_>, dt: f64) -> Result<Box<dyn EffectState>>;

    /// The truth entry: exact expressions over the file's columns (step `dt`).
    fn truth(&self, ctx: &Context<'_>, dt: f64) -> EffectTruth;
}

/// Streaming state of one effect.
pub(crate) trait EffectState {
    /// Contribution of this effect for one row of period `dt`.
    fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64;
}

/// The registry: one line per effect, `Variant => module::Type`. The variant's snake_case name is
/// the effect's `name` in TOML and in the truth file (the same as its [`EffectKind::name`]).
macro_rules! registry {
    ($($variant:ident => $module:ident :: $ty:ident,)+) => {
        $(pub mod $module;)+
        $(pub use $module::$ty;)+

        /// One bias effect with its coefficients (see each effect's type for its keys and formula).
        /// Coefficients are in output units (°/h or µg) per unit of their feature.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(tag = "name", rename_all = "snake_case")]
        pub enum Effect {
            $(
                #[doc = concat!("See [`", stringify!($ty), "`].")]
                $variant($ty),
            )+
        }

        /// The effects the simulator simulates, in registry order.
        pub const SIMULATED: &[EffectKind] = &[$(<$ty as EffectModel>::KIND,)+];

        impl Effect {
            /// Which effect this is.
            pub fn kind(&self) -> EffectKind {
                match self {
                    $(Effect::$variant(_) => <$ty as EffectModel>::KIND,)+
                }
            }

            /// A realistic default of `kind` for `sensor`, or `None` when the simulator does not
            /// simulate `kind`.
            fn try_default(kind: EffectKind, sensor: SensorKind) -> Option<Effect> {
                $(
                    if kind == <$ty as EffectModel>::KIND {
                        return Some(Effect::$variant(<$ty as EffectModel>::default_for(sensor)));
                    }
                )+
                None
            }

            /// Whether an effect of `kind` can be applied to `sensor` (false if not simulated).
            fn kind_applies_to(kind: EffectKind, sensor: SensorKind) -> bool {
                $(
                    if kind == <$ty as EffectModel>::KIND {
                        return <$ty as EffectModel>::applies_to(sensor);
                    }
                )+
                false
            }

            fn validate_params(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
                match self {
                    $(Effect::$variant(e) => e.validate(ctx, at),)+
                }
            }

            /// The streaming state computing this effect from rows. Assumes a validated effect.
            pub(crate) fn state(&self, ctx: &Context<'_>, dt: f64) -> Result<Box<dyn EffectState>> {
                match self {
                    $(Effect::$variant(e) => e.state(ctx, dt),)+
                }
            }

            /// The truth entry of this effect: exact expressions over the file's columns (step `dt`).
            pub(crate) fn truth(&self, ctx: &Context<'_>, dt: f64) -> EffectTruth {
                match self {
                    $(Effect::$variant(e) => e.truth(ctx, dt),)+
                }
            }
        }
    };
}

registry! {
    Poly => poly::Poly,
    Rate => rate::Rate,
    Gradient => gradient::Gradient,
    Shupe => shupe::Shupe,
    LaggedElement => lagged_element::LaggedElement,
    Hysteresis => hysteresis::Hysteresis,
    Warmup => warmup::Warmup,
    SupplyVoltage => supply_voltage::SupplyVoltage,
    GradientRate => gradient_rate::GradientRate,
    GradientLag => gradient_lag::GradientLag,
    TempGradientProduct => temp_gradient_product::TempGradientProduct,
}

/// Whether the simulator simulates effects of `kind`.
pub fn is_simulated(kind: EffectKind) -> bool {
    SIMULATED.contains(&kind)
}

/// Comma-separated names of the simulated effects (for error messages).
pub fn known() -> String {
    SIMULATED
        .iter()
        .map(|k| k.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether an effect of `kind` can be applied to `sensor` (the gradients need the RLG's three
/// thermometers; an effect the simulator does not simulate applies to nothing).
pub fn applies_to(kind: EffectKind, sensor: SensorKind) -> bool {
    Effect::kind_applies_to(kind, sensor)
}

impl Effect {
    /// A realistic default of `kind` for `sensor`: well above the noise floor of that sensor. An
    /// error names `effects` when the simulator does not simulate `kind`.
    pub fn default_for(kind: EffectKind, sensor: SensorKind) -> Result<Effect> {
        Effect::try_default(kind, sensor).ok_or_else(|| {
            Error::invalid(
                "effects",
                format!("\"{}\" is not simulated (known: {})", kind.name(), known()),
            )
        })
    }

    /// Checks the effect for the sensor in `ctx`; errors name `effects[i].<field>`.
    pub(crate) fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        if !applies_to(self.kind(), ctx.sensor) {
            return Err(Error::invalid(
                format!("{at}.name"),
                format!(
                    "\"{}\" needs anode, cathode and shell thermometers; sensor {} has {}",
                    self.kind().name(),
                    ctx.sensor.name(),
                    ctx.therm_names.join(", ")
                ),
            ));
        }
        self.validate_params(ctx, at)
    }
}

/// What the truth file says about one effect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectTruth {
    /// Effect name (see [`EffectKind`]).
    pub name: String,
    /// The main coefficient (the first of `coefficients`).
    pub coefficient: f64,
    /// Unit of `coefficient`.
    pub unit: String,
    /// The effect equals `offset + Σ coefficients[i] · expressions[i]` over the file's columns.
    pub expressions: Vec<String>,
    /// One coefficient per expression.
    pub coefficients: Vec<f64>,
    /// Unit of each coefficient.
    pub coefficient_units: Vec<String>,
    /// Constant part of the effect, output units.
    pub offset: f64,
    /// The inputs a model needs to represent this effect (what to pass as `--feature`).
    pub features: Vec<String>,
    /// Physical meaning.
    pub description: String,
    /// Std of this effect's contribution over the run, output units (filled after the run).
    pub contribution_std: f64,
    /// Peak-to-peak of this effect's contribution over the run, output units (filled after the run).
    pub contribution_p2p: f64,
}

impl EffectTruth {
    /// The effect this entry describes (`None` for a name outside the vocabulary, which only a
    /// hand-edited truth file can have).
    pub fn kind(&self) -> Option<EffectKind> {
        EffectKind::from_name(&self.name)
    }
}

/// The terms of one effect's truth entry, before the run's statistics.
pub(crate) struct Terms {
    /// One coefficient per expression.
    pub coefficients: Vec<f64>,
    /// Unit of each coefficient.
    pub units: Vec<String>,
    /// The expressions.
    pub expressions: Vec<String>,
    /// Constant part, output units.
    pub offset: f64,
    /// The features a model needs.
    pub features: Vec<String>,
    /// Physical meaning.
    pub description: String,
}

impl Terms {
    /// One term `coefficient · expression`, which is also the feature a model needs.
    pub fn single(coefficient: f64, unit: String, expression: String, description: String) -> Self {
        Terms {
            coefficients: vec![coefficient],
            units: vec![unit],
            expressions: vec![expression.clone()],
            offset: 0.0,
            features: vec![expression],
            description,
        }
    }

    /// The same terms with a constant part.
    pub fn with_offset(mut self, offset: f64) -> Self {
        self.offset = offset;
        self
    }

    /// The truth entry of effect `kind`.
    pub fn into_truth(self, kind: EffectKind) -> EffectTruth {
        EffectTruth {
            name: kind.name().to_string(),
            coefficient: self.coefficients.first().copied().unwrap_or(0.0),
            unit: self.units.first().cloned().unwrap_or_default(),
            expressions: self.expressions,
            coefficients: self.coefficients,
            coefficient_units: self.units,
            offset: self.offset,
            features: self.features,
            description: self.description,
            contribution_std: 0.0,
            contribution_p2p: 0.0,
        }
    }
}

/// The value for `sensor` among the three simulated sensors' (a sensor the simulator does not
/// simulate takes the nearest one's: accelerometers the QMA's, gyros the IFOG's).
fn per_sensor<T>(sensor: SensorKind, rlg: T, qma: T, ifog: T) -> T {
    match sensor {
        SensorKind::Rlg => rlg,
        SensorKind::Qma | SensorKind::MemsAccel => qma,
        SensorKind::Ifog | SensorKind::MemsGyro | SensorKind::Other => ifog,
    }
}

/// Default expansion point and reference temperature, °C.
fn default_t0() -> f64 {
    20.0
}

/// Default input: the sensor's temperature `T`.
fn default_input() -> String {
    "T".to_string()
}

/// Default rate window: the core's.
fn default_window() -> f64 {
    RATE_WINDOW_S
}

#[cfg(test)]
#[allow(clippy::panic, clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn registry_names_are_the_vocabulary() {
        for &kind in SIMULATED {
            let e = Effect::default_for(kind, SensorKind::Rlg).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(e.kind(), kind);
            let v = serde_json::to_value(&e).unwrap_or_default();
            assert_eq!(v.get("name").and_then(|n| n.as_str()), Some(kind.name()));
        }
        assert!(!is_simulated(EffectKind::Square));
        assert!(Effect::default_for(EffectKind::NonThermal, SensorKind::Ifog).is_err());
    }
}

#[cfg(test)]
mod filter_tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::{HystFilter as Hyst, RateFilter as Rate};

    #[test]
    fn rate_of_a_ramp_is_exact_after_transient() {
        let mut r = Rate::new(60.0);
        let mut last = 0.0;
        for n in 0..2000 {
            last = r.step(20.0 + 0.05 * n as f64, 1.0); // 3 °C/min
        }
        assert!((last - 3.0).abs() < 1e-9, "{last}");
    }

    #[test]
    fn hysteresis_holds_state() {
        let mut h = Hyst::new(0.5);
        let out: Vec<f64> = [0.0, 0.6, 0.1, -0.4, -0.6, 0.2]
            .iter()
            .map(|&x| h.step(x))
            .collect();
        assert_eq!(out, vec![0.0, 1.0, 1.0, 1.0, -1.0, -1.0]);
    }
}
