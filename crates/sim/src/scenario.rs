//! Scenarios: what to simulate (sensor, chamber profile, effects, noise, rates, seed), from Rust or
//! TOML, with validation errors that name the field.
//!
//! Why: one plain data type drives the simulator, whether it comes from a preset, a test that hides
//! one effect, or a user's TOML file; validation happens once, here, so the simulator can assume
//! sane values.
//!
//! # TOML format
//!
//! ```toml
//! name = "ifog-custom"          # optional
//! description = "..."           # optional
//! seed = 7                      # optional, default 1
//! rate_hz = 1.0                 # internal sensor rate, optional, default 1 Hz
//! step_s = 1.0                  # output step (averaging), optional, default 1 s; a multiple of 1/rate_hz
//!
//! [sensor]
//! kind = "ifog"                 # rlg | qma | ifog (the core's other kinds are not simulated)
//! reference = 10.6357           # optional: constant true input, output units (default: earth rate
//!                               # at 45° latitude for gyros, 1 g = 1e6 µg for the QMA)
//! [sensor.thermal.t_coil_c]     # optional overrides of a thermometer's defaults
//! tau_s = 1200                  # lag behind chamber air, s
//! self_heating_c = 1.0          # final self-heating rise, °C
//! self_heating_tau_s = 1800     # its time constant, s
//! noise_c = 0.005               # thermometer white noise, °C
//! lsb_c = 0.01                  # thermometer quantisation, °C
//!
//! [noise]                       # optional; each key overrides the sensor's default
//! arw_deg_per_sqrt_h = 0.005    # gyros: angle random walk (or vrw_ug_per_sqrt_hz for the QMA,
//!                               # or white_density in output units·√s)
//! bias_instability = 0.01       # Gauss–Markov std, output units
//! correlation_s = 600           # its correlation time, s
//! pulse_weight = 0.0            # output units·s per pulse (″ for gyros, µg·s for the QMA); 0 = none
//!
//! [supply]                      # optional: the recorded supply voltage `supply_v`
//! nominal_v = 28.0
//! wander_v = 0.5                # std of its slow Gauss–Markov wander, V
//! wander_tau_s = 1800
//! noise_v = 0.002
//!
//! [profile]                     # chamber air: start and segments ...
//! start_c = 10
//! segments = [
//!   { kind = "hold", duration_s = 3600 },
//!   { kind = "ramp", to_c = 40, rate_c_per_min = 0.5 },
//!   { kind = "hold", duration_s = 7200 },
//! ]
//! # ... or a seeded random profile instead of start_c/segments:
//! # random = { seed = 3, start_c = 20, min_c = -10, max_c = 40, max_rate_c_per_min = 1, duration_s = 21600 }
//!
//! [verify_profile]              # optional, same shape: the verification run (default: a seeded
//!                               # random profile over the training range)
//!
//! dropouts = [{ start_s = 7200, length_s = 300 }]   # optional: rows not written (or
//!                               # random_dropouts = { count = 5, length_s = 300, seed = 3 }),
//!                               # see `crate::dropout`
//!
//! [[effects]]                   # any number; see `Effect` for each one's keys
//! name = "poly"
//! coefficients = [0.005, 1e-4, 2e-6]
//! [[effects]]
//! name = "shupe"
//! coefficient = 0.01
//! ```

use serde::{Deserialize, Serialize};

pub use tcomp_core::SensorKind;

use crate::dropout::Dropout;
use crate::effects::{Context, Effect, EffectKind};
use crate::error::{Error, Result};
use crate::noise::NoiseSpec;
use crate::profile::Profile;
pub use crate::sensor::EARTH_RATE_DPH;
use crate::sensor::{SensorExt, check_simulated};
use crate::thermal::ThermometerSpec;

/// The recorded supply voltage `supply_v`: nominal plus a slow Gauss–Markov wander and white noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupplySpec {
    /// Nominal voltage, V.
    pub nominal_v: f64,
    /// Std of the slow wander, V.
    pub wander_v: f64,
    /// Correlation time of the wander, s.
    pub wander_tau_s: f64,
    /// White noise of the reading, V.
    pub noise_v: f64,
}

impl SupplySpec {
    /// Checks every field; the error names the first bad one (`supply.<field>`).
    pub fn validate(&self) -> Result<()> {
        if !self.nominal_v.is_finite() {
            return Err(Error::invalid("supply.nominal_v", "must be finite"));
        }
        if !(self.wander_v.is_finite() && self.wander_v >= 0.0) {
            return Err(Error::invalid("supply.wander_v", "must be >= 0"));
        }
        Error::positive("supply.wander_tau_s", self.wander_tau_s)?;
        if !(self.noise_v.is_finite() && self.noise_v >= 0.0) {
            return Err(Error::invalid("supply.noise_v", "must be >= 0"));
        }
        Ok(())
    }
}

impl Default for SupplySpec {
    fn default() -> Self {
        SupplySpec {
            nominal_v: 28.0,
            wander_v: 0.5,
            wander_tau_s: 1800.0,
            noise_v: 0.002,
        }
    }
}

/// Everything the simulator needs for one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    /// Short name (used in the truth file).
    pub name: String,
    /// One-line description.
    pub description: String,
    /// Sensor kind.
    pub sensor: SensorKind,
    /// Constant true input in output units (earth-rate or gravity component), written as the
    /// reference column.
    pub reference: f64,
    /// Thermometers, in column order (names fixed by the sensor kind).
    pub thermometers: Vec<ThermometerSpec>,
    /// Output noise.
    pub noise: NoiseSpec,
    /// Supply voltage.
    pub supply: SupplySpec,
    /// Chamber air profile.
    pub profile: Profile,
    /// Bias effects (any combination, including none).
    pub effects: Vec<Effect>,
    /// Internal sensor rate, Hz.
    pub rate_hz: f64,
    /// Output step, s (a whole multiple of `1/rate_hz`; rows are averages over it).
    pub step_s: f64,
    /// Seed of all random draws.
    pub seed: u64,
    /// Logger dropouts: rows not written while the physics runs on (see [`crate::dropout`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dropouts: Vec<Dropout>,
}

/// The fastest internal rate accepted, Hz. The sensors simulated deliver their pulse or digital
/// output at up to about 1 kHz (navigation-grade RLG, IFOG and QMA electronics), and the firmware
/// compensates at 100–200 Hz; a faster internal rate models nothing more, it only costs time.
pub const MAX_RATE_HZ: f64 = 1000.0;

/// The most internal samples one run may take. The simulator does about 15 M internal samples per
/// second for the three-thermometer RLG (measured, one core, 1000 Hz with 1 s rows), so this is a
/// minute or two per run, shown with a progress bar; a 6-hour profile at [`MAX_RATE_HZ`] is
/// 2.2·10⁷. Anything beyond is almost surely a mistyped rate or duration that would run for hours.
pub const MAX_INTERNAL_SAMPLES: f64 = 1.0e9;

/// The most output rows one run may write: 5·10⁷ rows are about 3.5 GB of CSV, and loading them
/// takes about as much memory, more than the trainer accepts; the 100 Hz, 6-hour RLG run written
/// row per sample is 2.2·10⁶.
pub const MAX_ROWS: f64 = 5.0e7;

impl Scenario {
    /// A scenario with the sensor's defaults, no effects, 1 Hz output, seed 1.
    pub fn new(sensor: SensorKind, profile: Profile) -> Self {
        Scenario {
            name: sensor.name().to_string(),
            description: String::new(),
            sensor,
            reference: sensor.default_reference(),
            thermometers: sensor.default_thermometers(),
            noise: sensor.default_noise(),
            supply: SupplySpec::default(),
            profile,
            effects: Vec::new(),
            rate_hz: 1.0,
            step_s: 1.0,
            seed: 1,
            dropouts: Vec::new(),
        }
    }

    /// Sets the logger dropouts.
    pub fn with_dropouts(mut self, dropouts: Vec<Dropout>) -> Self {
        self.dropouts = dropouts;
        self
    }

    /// Replaces the effects.
    pub fn with_effects(mut self, effects: Vec<Effect>) -> Self {
        self.effects = effects;
        self
    }

    /// Adds the sensor's default effect of each kind in `kinds` (see [`Effect::default_for`]); an
    /// error names a kind the simulator does not simulate.
    pub fn with_default_effects(mut self, kinds: &[EffectKind]) -> Result<Self> {
        for &k in kinds {
            self.effects.push(Effect::default_for(k, self.sensor)?);
        }
        Ok(self)
    }

    /// Keeps only the effects of the given kinds.
    pub fn retain_effects(mut self, kinds: &[EffectKind]) -> Self {
        self.effects.retain(|e| kinds.contains(&e.kind()));
        self
    }

    /// Removes every effect of `kind` (to "hide" it from a model).
    pub fn without_effect(mut self, kind: EffectKind) -> Self {
        self.effects.retain(|e| e.kind() != kind);
        self
    }

    /// Sets the seed.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Sets the internal rate and the output step.
    pub fn with_rate(mut self, rate_hz: f64, step_s: f64) -> Self {
        self.rate_hz = rate_hz;
        self.step_s = step_s;
        self
    }

    /// Internal samples per output row. Assumes a validated scenario.
    pub fn samples_per_row(&self) -> u64 {
        (self.step_s * self.rate_hz).round().max(1.0) as u64
    }

    /// Number of output rows (complete output steps within the profile).
    pub fn rows(&self) -> u64 {
        let k = self.samples_per_row();
        let samples = (self.profile.duration_s() * self.rate_hz + 1e-6).floor() as u64;
        samples / k
    }

    /// Column names of the output file, in order.
    pub fn columns(&self) -> Vec<String> {
        let mut c = vec!["time_s".to_string(), "t_chamber_c".to_string()];
        c.extend(self.thermometers.iter().map(|t| t.name.clone()));
        c.push("supply_v".into());
        c.push(self.sensor.output_column().into());
        c.push(self.sensor.reference_column().into());
        c
    }

    pub(crate) fn context(&self) -> (Vec<String>, &'static str) {
        (
            self.thermometers.iter().map(|t| t.name.clone()).collect(),
            self.sensor.unit(),
        )
    }

    /// Internal samples of the whole run: the work the simulator does (each costs a few random
    /// draws and one lag step per thermometer). Assumes a validated rate.
    pub fn internal_samples(&self) -> f64 {
        self.profile.duration_s() * self.rate_hz
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        check_simulated(self.sensor, "sensor.kind")?;
        self.validate_rate_and_step()?;
        if !self.reference.is_finite() {
            return Err(Error::invalid("sensor.reference", "must be finite"));
        }
        self.profile.validate("profile")?;
        self.validate_size()?;
        self.validate_thermometers()?;
        self.noise.validate("noise")?;
        self.supply.validate()?;
        crate::dropout::validate(&self.dropouts, self.profile.duration_s(), self.step_s)?;
        let (names, unit) = self.context();
        let ctx = Context {
            sensor: self.sensor,
            therm_names: &names,
            unit,
        };
        for (i, e) in self.effects.iter().enumerate() {
            e.validate(&ctx, &format!("effects[{i}]"))?;
        }
        Ok(())
    }

    /// The internal rate, and the output step as a whole number of its periods.
    fn validate_rate_and_step(&self) -> Result<()> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= MAX_RATE_HZ) {
            return Err(Error::invalid(
                "rate_hz",
                format!(
                    "must be greater than 0 and at most {MAX_RATE_HZ} Hz (the fastest output of the \
                     sensors simulated), got {}",
                    self.rate_hz
                ),
            ));
        }
        if !(self.step_s.is_finite() && self.step_s > 0.0) {
            return Err(Error::invalid(
                "step_s",
                format!(
                    "must be a positive number of seconds, at least the sample period 1/rate_hz = \
                     {} s, got {}",
                    1.0 / self.rate_hz,
                    self.step_s
                ),
            ));
        }
        let k = self.step_s * self.rate_hz;
        if k < 1.0 - 1e-9 || (k - k.round()).abs() > 1e-6 * k.max(1.0) {
            return Err(Error::invalid(
                "step_s",
                format!(
                    "must be a whole multiple of the sample period 1/rate_hz = {} s, got {}",
                    1.0 / self.rate_hz,
                    self.step_s
                ),
            ));
        }
        Ok(())
    }

    /// The run's size: at least one row, at most [`MAX_ROWS`] rows and [`MAX_INTERNAL_SAMPLES`]
    /// internal samples.
    fn validate_size(&self) -> Result<()> {
        if self.profile.duration_s() < self.step_s {
            return Err(Error::invalid(
                "step_s",
                format!(
                    "{} s is longer than the whole profile ({} s): not one output row",
                    self.step_s,
                    self.profile.duration_s()
                ),
            ));
        }
        let rows = self.profile.duration_s() / self.step_s;
        if rows > MAX_ROWS {
            return Err(Error::invalid(
                "step_s",
                format!(
                    "{} s rows over the {:.0} s profile are {rows:.3e} rows, more than the \
                     {MAX_ROWS:.0e} a file may hold (gigabytes of CSV): use a longer step",
                    self.step_s,
                    self.profile.duration_s()
                ),
            ));
        }
        if self.internal_samples() > MAX_INTERNAL_SAMPLES {
            return Err(Error::invalid(
                "rate_hz",
                format!(
                    "{} Hz over the {:.0} s profile is {:.3e} internal samples, more than the \
                     {MAX_INTERNAL_SAMPLES:.0e} a run may take: lower the rate or shorten the \
                     profile",
                    self.rate_hz,
                    self.profile.duration_s(),
                    self.internal_samples()
                ),
            ));
        }
        Ok(())
    }

    /// The thermometers: the sensor's own, in order, each with sane parameters.
    fn validate_thermometers(&self) -> Result<()> {
        let expect: Vec<String> = self
            .sensor
            .default_thermometers()
            .into_iter()
            .map(|t| t.name)
            .collect();
        let got: Vec<String> = self.thermometers.iter().map(|t| t.name.clone()).collect();
        if got != expect {
            return Err(Error::invalid(
                "sensor.thermal",
                format!(
                    "sensor {} has thermometers {}, got {}",
                    self.sensor.name(),
                    expect.join(", "),
                    got.join(", ")
                ),
            ));
        }
        for t in &self.thermometers {
            t.validate(&format!("sensor.thermal.{}", t.name))?;
        }
        Ok(())
    }

    /// Parses and validates a scenario from TOML (the training run if the file also has a
    /// `verify_profile`). See the module documentation for the format.
    pub fn from_toml_str(text: &str) -> Result<Scenario> {
        Ok(crate::scenario_file::parse_toml(text)?.0)
    }
}
