//! Reading a scenario file: the TOML shapes (every key optional but the sensor and the profile) laid
//! over the sensor's defaults, with errors that name the field.
//!
//! Why apart from [`crate::scenario`]: that module is the plain data and its validation; this one
//! is the file format (see the format in that module's documentation).

use std::collections::BTreeMap;

use serde::Deserialize;
use tcomp_core::SensorKind;

use crate::dropout::{Dropout, RandomDropouts};
use crate::effects::{self, Effect, EffectKind};
use crate::error::{Error, Result};
use crate::profile::{Profile, RandomProfile, Segment};
use crate::scenario::{Scenario, SupplySpec};
use crate::sensor::{SensorExt, check_simulated, simulated_names};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioToml {
    name: Option<String>,
    description: Option<String>,
    seed: Option<u64>,
    rate_hz: Option<f64>,
    step_s: Option<f64>,
    sensor: SensorToml,
    noise: Option<NoiseToml>,
    supply: Option<SupplySpec>,
    profile: Option<ProfileToml>,
    verify_profile: Option<ProfileToml>,
    #[serde(default)]
    effects: Vec<toml::Table>,
    dropouts: Option<Vec<Dropout>>,
    random_dropouts: Option<RandomDropouts>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorToml {
    kind: String,
    reference: Option<f64>,
    #[serde(default)]
    thermal: BTreeMap<String, ThermalToml>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ThermalToml {
    tau_s: Option<f64>,
    self_heating_c: Option<f64>,
    self_heating_tau_s: Option<f64>,
    noise_c: Option<f64>,
    lsb_c: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct NoiseToml {
    arw_deg_per_sqrt_h: Option<f64>,
    vrw_ug_per_sqrt_hz: Option<f64>,
    white_density: Option<f64>,
    bias_instability: Option<f64>,
    correlation_s: Option<f64>,
    pulse_weight: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileToml {
    start_c: Option<f64>,
    segments: Option<Vec<Segment>>,
    random: Option<RandomProfile>,
}

impl ProfileToml {
    fn build(self, at: &str) -> Result<Profile> {
        match (self.random, self.segments) {
            (Some(_), Some(_)) => Err(Error::invalid(
                format!("{at}.random"),
                "give either segments or random, not both",
            )),
            (Some(r), None) => {
                if self.start_c.is_some() {
                    return Err(Error::invalid(
                        format!("{at}.start_c"),
                        "a random profile takes its start from random.start_c",
                    ));
                }
                Profile::random(&r).map_err(|e| match e {
                    Error::Invalid { field, message } => Error::Invalid {
                        field: field.replacen("profile", at, 1),
                        message,
                    },
                    other => other,
                })
            }
            (None, segments) => {
                let start_c = self.start_c.ok_or_else(|| {
                    Error::invalid(format!("{at}.start_c"), "missing start temperature")
                })?;
                let p = Profile::new(start_c, segments.unwrap_or_default());
                p.validate(at)?;
                Ok(p)
            }
        }
    }
}

/// Parses a scenario file: the training scenario and, if given, the verification profile.
pub(crate) fn parse_toml(text: &str) -> Result<(Scenario, Option<Profile>)> {
    let raw: ScenarioToml = toml::from_str(text).map_err(|e| Error::Toml(e.to_string()))?;
    let sensor = sensor_kind(&raw.sensor.kind)?;
    let profile = raw
        .profile
        .ok_or_else(|| Error::invalid("profile", "missing: the chamber profile is required"))?
        .build("profile")?;
    let verify = raw
        .verify_profile
        .map(|p| p.build("verify_profile"))
        .transpose()?;
    let mut sc = Scenario::new(sensor, profile);
    if let Some(n) = raw.name {
        sc.name = n;
    }
    if let Some(d) = raw.description {
        sc.description = d;
    }
    if let Some(s) = raw.seed {
        sc.seed = s;
    }
    if let Some(r) = raw.rate_hz {
        sc.rate_hz = r;
    }
    sc.step_s = raw.step_s.unwrap_or(1.0f64.max(1.0 / sc.rate_hz));
    if let Some(r) = raw.sensor.reference {
        sc.reference = r;
    }
    for (name, t) in raw.sensor.thermal {
        apply_thermal(&mut sc, &name, t)?;
    }
    if let Some(n) = raw.noise {
        apply_noise(&mut sc, n)?;
    }
    if let Some(s) = raw.supply {
        sc.supply = s;
    }
    for (i, table) in raw.effects.into_iter().enumerate() {
        sc.effects.push(effect(table, &format!("effects[{i}]"))?);
    }
    sc.dropouts = match (raw.dropouts, raw.random_dropouts) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                "random_dropouts",
                "give either dropouts or random_dropouts, not both",
            ));
        }
        (Some(d), None) => d,
        (None, Some(r)) => r.resolve(sc.profile.duration_s())?,
        (None, None) => Vec::new(),
    };
    sc.validate()?;
    Ok((sc, verify))
}

/// The sensor kind named in `sensor.kind`: one the core knows and the simulator simulates.
fn sensor_kind(name: &str) -> Result<SensorKind> {
    let kind = SensorKind::from_name(name).ok_or_else(|| {
        Error::invalid(
            "sensor.kind",
            format!("unknown sensor \"{name}\" (known: {})", simulated_names()),
        )
    })?;
    check_simulated(kind, "sensor.kind")?;
    Ok(kind)
}

/// Lays `sensor.thermal.<name>` over that thermometer's defaults.
fn apply_thermal(sc: &mut Scenario, name: &str, t: ThermalToml) -> Result<()> {
    let known: Vec<String> = sc.thermometers.iter().map(|t| t.name.clone()).collect();
    let Some(spec) = sc.thermometers.iter_mut().find(|s| s.name == name) else {
        return Err(Error::invalid(
            format!("sensor.thermal.{name}"),
            format!(
                "sensor {} has no thermometer \"{name}\" (known: {})",
                sc.sensor.name(),
                known.join(", ")
            ),
        ));
    };
    if let Some(v) = t.tau_s {
        spec.tau_s = v;
    }
    if let Some(v) = t.self_heating_c {
        spec.self_heating_c = v;
    }
    if let Some(v) = t.self_heating_tau_s {
        spec.self_heating_tau_s = v;
    }
    if let Some(v) = t.noise_c {
        spec.noise_c = v;
    }
    if let Some(v) = t.lsb_c {
        spec.lsb_c = v;
    }
    Ok(())
}

/// Lays `[noise]` over the sensor's default noise; a random walk in the other kind of sensor's
/// unit is refused.
fn apply_noise(sc: &mut Scenario, n: NoiseToml) -> Result<()> {
    let gyro = !sc.sensor.is_accelerometer();
    if n.arw_deg_per_sqrt_h.is_some() && !gyro {
        return Err(Error::invalid(
            "noise.arw_deg_per_sqrt_h",
            "angle random walk is for gyros; use vrw_ug_per_sqrt_hz for the QMA",
        ));
    }
    if n.vrw_ug_per_sqrt_hz.is_some() && gyro {
        return Err(Error::invalid(
            "noise.vrw_ug_per_sqrt_hz",
            "velocity random walk is for accelerometers; use arw_deg_per_sqrt_h for gyros",
        ));
    }
    if let Some(v) = n.arw_deg_per_sqrt_h {
        sc.noise.white_density = 60.0 * v;
    }
    if let Some(v) = n.vrw_ug_per_sqrt_hz {
        sc.noise.white_density = v;
    }
    if let Some(v) = n.white_density {
        sc.noise.white_density = v;
    }
    if let Some(v) = n.bias_instability {
        sc.noise.bias_instability = v;
    }
    if let Some(v) = n.correlation_s {
        sc.noise.correlation_s = v;
    }
    if let Some(v) = n.pulse_weight {
        sc.noise.pulse_weight = v;
    }
    Ok(())
}

/// One `[[effects]]` table at `at`: its name must be a simulated effect's, its keys that effect's.
fn effect(table: toml::Table, at: &str) -> Result<Effect> {
    let name = match table.get("name") {
        Some(toml::Value::String(s)) => s.clone(),
        Some(_) => return Err(Error::invalid(format!("{at}.name"), "must be a string")),
        None => {
            return Err(Error::invalid(
                format!("{at}.name"),
                format!("missing (known: {})", effects::known()),
            ));
        }
    };
    if !EffectKind::from_name(&name).is_some_and(effects::is_simulated) {
        return Err(Error::invalid(
            format!("{at}.name"),
            format!("unknown effect \"{name}\" (known: {})", effects::known()),
        ));
    }
    table
        .try_into()
        .map_err(|e: toml::de::Error| Error::invalid(at, e.message().to_string()))
}
