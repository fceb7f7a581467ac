//! Built-in scenarios: the seed experiments of the RLG/QMA and IFOG papers, a Shupe demo, and a
//! helper that builds a run with any subset of the named effects.
//!
//! Why: tests, the demo and users without a chamber need ready-made train/verify pairs whose
//! profiles match the published experiments, and diagnosis tests need to "hide" one effect at a time
//! with everything else held equal.

use crate::effects::{Effect, EffectKind};
use crate::error::{Error, Result};
use crate::profile::{Profile, RandomProfile, Segment};
use crate::scenario::{Scenario, SensorKind};
use crate::scenario_file::parse_toml;

/// Name and one-line description of a preset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PresetInfo {
    /// Name to pass to [`preset`].
    pub name: &'static str,
    /// One line.
    pub description: &'static str,
}

/// A training run and a verification run on a different profile, same sensor and effects.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    /// Name.
    pub name: String,
    /// One line.
    pub description: String,
    /// The training run.
    pub train: Scenario,
    /// The verification run (different profile and seed).
    pub verify: Scenario,
}

impl Preset {
    /// Sets the seeds: `seed` for training, `seed + 1` for verification.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.train.seed = seed;
        self.verify.seed = seed.wrapping_add(1);
        self
    }

    /// Sets the internal rate and output step of both runs.
    pub fn with_rate(mut self, rate_hz: f64, step_s: f64) -> Self {
        self.train = self.train.with_rate(rate_hz, step_s);
        self.verify = self.verify.with_rate(rate_hz, step_s);
        self
    }

    /// Applies `f` to both scenarios (e.g. to hide an effect in both).
    pub fn map(mut self, f: impl Fn(Scenario) -> Scenario) -> Self {
        self.train = f(self.train);
        self.verify = f(self.verify);
        self
    }

    /// A preset from a scenario TOML file: its profile trains; its `verify_profile`, or else a
    /// seeded random profile over the same temperature range, verifies.
    pub fn from_toml_str(text: &str) -> Result<Preset> {
        let (train, verify_profile) = parse_toml(text)?;
        let verify_profile = match verify_profile {
            Some(p) => p,
            None => {
                let (lo, hi) = train.profile.range_c();
                let (lo, hi) = if hi - lo < 1.0 {
                    (lo - 5.0, hi + 5.0)
                } else {
                    (lo, hi)
                };
                let max_rate = train
                    .profile
                    .resolved()
                    .iter()
                    .map(|s| s.rate_c_per_min.abs())
                    .fold(0.0, f64::max)
                    .max(0.5);
                let mut spec = RandomProfile::new(
                    train.seed.wrapping_add(1),
                    lo,
                    hi,
                    max_rate,
                    train.profile.duration_s().max(7200.0),
                );
                spec.start_c = train.profile.start_c;
                Profile::random(&spec)?
            }
        };
        let mut verify = train.clone();
        verify.profile = verify_profile;
        verify.seed = train.seed.wrapping_add(1);
        verify.name = format!("{}-verify", train.name);
        Ok(Preset {
            name: train.name.clone(),
            description: train.description.clone(),
            train,
            verify,
        })
    }
}

/// RLG/QMA training run: 20 °C held 1.5 h; +3 °C/min to 50 °C; held 2 h; −3 °C/min to −30 °C;
/// held 2 h.
pub fn rlg_qma_train_profile() -> Profile {
    Profile::new(
        20.0,
        vec![
            Segment::hold_h(1.5),
            Segment::ramp(50.0, 3.0),
            Segment::hold_h(2.0),
            Segment::ramp(-30.0, 3.0),
            Segment::hold_h(2.0),
        ],
    )
}

/// RLG/QMA verification run: 20 °C held 1 h; −1 °C/min to −30 °C; held 1 h; +2 °C/min to 30 °C;
/// held 1 h; −3 °C/min to −30 °C; held 1 h.
pub fn rlg_qma_verify_profile() -> Profile {
    Profile::new(
        20.0,
        vec![
            Segment::hold_h(1.0),
            Segment::ramp(-30.0, 1.0),
            Segment::hold_h(1.0),
            Segment::ramp(30.0, 2.0),
            Segment::hold_h(1.0),
            Segment::ramp(-30.0, 3.0),
            Segment::hold_h(1.0),
        ],
    )
}

/// IFOG training run: 10 °C held 1 h; +0.5 °C/min to 40 °C; held 2 h.
pub fn ifog_train_profile() -> Profile {
    Profile::new(
        10.0,
        vec![
            Segment::hold_h(1.0),
            Segment::ramp(40.0, 0.5),
            Segment::hold_h(2.0),
        ],
    )
}

/// IFOG verification run spanning −10 to 40 °C: 20 °C held 1 h; −0.5 °C/min to −10 °C; held 1 h;
/// +1 °C/min to 40 °C; held 1.5 h.
pub fn ifog_verify_profile() -> Profile {
    Profile::new(
        20.0,
        vec![
            Segment::hold_h(1.0),
            Segment::ramp(-10.0, 0.5),
            Segment::hold_h(1.0),
            Segment::ramp(40.0, 1.0),
            Segment::hold_h(1.5),
        ],
    )
}

/// A seeded random verification profile within the RLG/QMA range (−30…50 °C, ≤ 3 °C/min, 6 h).
pub fn random_profile(seed: u64) -> Result<Profile> {
    Profile::random(&RandomProfile::new(seed, -30.0, 50.0, 3.0, 6.0 * 3600.0))
}

const PRESETS: [PresetInfo; 5] = [
    PresetInfo {
        name: "rlg",
        description: "RLG seed experiment: bias = poly(T) + rate(T) + gradients anode-shell, cathode-shell; train/verify chamber profiles of the RLG/QMA paper",
    },
    PresetInfo {
        name: "qma",
        description: "QMA seed experiment: bias = poly(T) + rate(T); train/verify chamber profiles of the RLG/QMA paper",
    },
    PresetInfo {
        name: "ifog",
        description: "IFOG seed experiment: bias = poly(T) + rate(T); 10->40 degC training run, -10..40 degC verification run",
    },
    PresetInfo {
        name: "ifog-shupe",
        description: "the demo: IFOG bias = poly(T) + rate(T) + Shupe-type T*dT/dt; (T, dT) alone cannot generalise",
    },
    PresetInfo {
        name: "rlg-random",
        description: "RLG effects as in `rlg`; verification on a seeded random profile (-30..50 degC, <= 3 degC/min)",
    },
];

/// The presets with a one-line description each.
pub fn list() -> Vec<PresetInfo> {
    PRESETS.to_vec()
}

fn pair(
    name: &str,
    description: &str,
    sensor: SensorKind,
    train: Profile,
    verify: Profile,
    effects: Vec<Effect>,
) -> Preset {
    let mut t = Scenario::new(sensor, train).with_effects(effects);
    t.name = format!("{name}-train");
    t.description = description.to_string();
    let mut v = t.clone();
    v.profile = verify;
    v.name = format!("{name}-verify");
    Preset {
        name: name.to_string(),
        description: description.to_string(),
        train: t,
        verify: v,
    }
    .with_seed(1)
}

fn defaults(sensor: SensorKind, kinds: &[EffectKind]) -> Result<Vec<Effect>> {
    kinds
        .iter()
        .map(|&k| Effect::default_for(k, sensor))
        .collect()
}

/// The preset of this name (seed 1 for training, 2 for verification; 1 Hz, 1 s rows).
pub fn preset(name: &str) -> Result<Preset> {
    use EffectKind::*;
    let info = PRESETS
        .iter()
        .find(|p| p.name == name)
        .ok_or_else(|| Error::UnknownPreset {
            name: name.to_string(),
            known: PRESETS.map(|p| p.name).join(", "),
        })?;
    let d = info.description;
    Ok(match name {
        "rlg" => pair(
            name,
            d,
            SensorKind::Rlg,
            rlg_qma_train_profile(),
            rlg_qma_verify_profile(),
            defaults(SensorKind::Rlg, &[Poly, Rate, Gradient])?,
        ),
        "qma" => pair(
            name,
            d,
            SensorKind::Qma,
            rlg_qma_train_profile(),
            rlg_qma_verify_profile(),
            defaults(SensorKind::Qma, &[Poly, Rate])?,
        ),
        "ifog" => pair(
            name,
            d,
            SensorKind::Ifog,
            ifog_train_profile(),
            ifog_verify_profile(),
            defaults(SensorKind::Ifog, &[Poly, Rate])?,
        ),
        "ifog-shupe" => pair(
            name,
            d,
            SensorKind::Ifog,
            ifog_train_profile(),
            ifog_verify_profile(),
            defaults(SensorKind::Ifog, &[Poly, Rate, Shupe])?,
        ),
        _ => pair(
            name,
            d,
            SensorKind::Rlg,
            rlg_qma_train_profile(),
            random_profile(2)?,
            defaults(SensorKind::Rlg, &[Poly, Rate, Gradient])?,
        ),
    })
}

/// A train/verify pair for `sensor` with the sensor's default coefficients of exactly the effects
/// in `kinds` (train on the RLG/QMA training profile, verify on its verification profile, which
/// both heat and cool). Effects that do not apply to the sensor (gradient without three
/// thermometers) are an error naming them.
pub fn with_effects(sensor: SensorKind, kinds: &[EffectKind]) -> Result<Preset> {
    let name = format!(
        "{}-{}",
        sensor.name(),
        if kinds.is_empty() {
            "none".to_string()
        } else {
            kinds.iter().map(|k| k.name()).collect::<Vec<_>>().join("+")
        }
    );
    let p = pair(
        &name,
        "custom set of effects at default strengths",
        sensor,
        rlg_qma_train_profile(),
        rlg_qma_verify_profile(),
        defaults(sensor, kinds)?,
    );
    p.train.validate()?;
    Ok(p)
}
