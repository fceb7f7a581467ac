//! The board description: a small TOML file the user writes once per IMU design, read here and
//! compiled into the rows the calibration image carries ([`tcomp_core::image::table`]).
//!
//! One reader for both sides: `tcomp image --board` checks models against it, and the firmware's
//! `build.rs` generates the loop's channel tables from the same files, so the wiring is written once
//! (in TOML) and the image is checked against exactly what the firmware runs.
//!
//! It says, per channel, what the firmware needs to run a model there — id, name, sensor kind,
//! axis, output unit, the pulse counter or sample source and its scale, and which thermometer
//! feeds each input column a model may read — and, per thermometer, where it is read (converter,
//! input) and how (RTD, NTC thermistor, digital register). `tcomp image --board` checks every
//! model against it before anything is written; the firmware runs the table it finds in the image.
//! Shipped descriptions: `firmware/descriptions/*.toml`.
//!
//! ```toml
//! name = "imu6-rlg-qma"
//!
//! [[thermometer]]
//! name = "rlg-x-anode"
//! adc = 0            # which converter
//! input = 0          # which input (multiplexer setting) of it
//! type = "pt1000"    # pt100, pt1000, rtd (r0, a, b), ntc (r0, beta, t0_c), digital (scale, offset_c)
//!
//! [[channel]]
//! id = 0
//! name = "rlg-x"
//! sensor = "rlg"     # rlg, qma, ifog, mems-gyro, mems-accel, other
//! axis = "x"
//! unit = "deg/h"
//! counter = 0        # or `sample = N` for a digital IMU's register
//! scale = 1.0e-5     # arcsec per pulse (RLG, IFOG), µg per Hz (QMA), unit per LSB (sample)
//! inputs = { t_anode_c = "rlg-x-anode" }
//!
//! [link]
//! baud = 921600      # the unit's serial link: its frames out, `tcomp flash` in
//! ```
//!
//! The link's baud rate is written here once: the board binary's UART is configured from it (a
//! constant `build.rs` generates), and `tcomp flash --board FILE` opens the port at it, so the
//! firmware, the tool and the board's README cannot disagree. A description without `[link]`
//! describes a design no board binary runs yet; `tcomp flash` then needs `--baud`.
//!
//! Where a unit keeps its models (the `MODELS` region of each board's memory map) is not part of
//! a description, which the QEMU board and the STM32F407 board share: it is [`targets::TARGETS`].
pub mod targets;

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tcomp_core::SensorKind;
use tcomp_core::image::{
    ChannelRow, Input, MAX_CHANNEL_ROWS, MAX_ROW_INPUTS, MAX_THERMOMETER_ROWS, Source, ThermKind,
    Thermometer,
};

/// IEC 60751 platinum RTD coefficients.
const IEC_A: f32 = 3.9083e-3;
const IEC_B: f32 = -5.775e-7;

/// Why a board description is unusable; every message names the file and the place in it.
#[derive(Debug, thiserror::Error)]
pub enum BoardError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// The reader's error.
        #[source]
        source: std::io::Error,
    },
    /// Not TOML of the expected shape (the message has the line and column).
    #[error("{file}: {source}")]
    Toml {
        /// The file.
        file: String,
        /// The parser's error.
        #[source]
        source: toml::de::Error,
    },
    /// A value the firmware could not use.
    #[error("{file}: {place}: {message}")]
    Invalid {
        /// The file.
        file: String,
        /// Which table and field, e.g. `channel 3 (qma-x)`.
        place: String,
        /// What is wrong.
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBoard {
    name: String,
    #[serde(default, rename = "thermometer")]
    thermometers: Vec<RawTherm>,
    #[serde(default, rename = "channel")]
    channels: Vec<RawChannel>,
    link: Option<RawLink>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLink {
    baud: u32,
}

/// The slowest and fastest baud rates a description may give: 300 (the slowest rate a serial
/// port names) to 10.5 Mbaud (the STM32F407's USART1 on its 84 MHz bus, oversampling by 8).
pub const BAUD_RANGE: std::ops::RangeInclusive<u32> = 300..=10_500_000;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTherm {
    name: String,
    adc: u8,
    input: u8,
    #[serde(rename = "type")]
    kind: String,
    r0: Option<f32>,
    a: Option<f32>,
    b: Option<f32>,
    beta: Option<f32>,
    t0_c: Option<f32>,
    scale: Option<f32>,
    offset_c: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawChannel {
    id: u16,
    name: String,
    sensor: String,
    axis: String,
    unit: String,
    counter: Option<u8>,
    sample: Option<u8>,
    scale: f32,
    inputs: BTreeMap<String, String>,
}

/// A checked board description.
#[derive(Debug)]
pub struct Board {
    /// Where it was read from.
    pub path: PathBuf,
    /// The design's name.
    pub name: String,
    /// The serial link's baud rate (`[link] baud`), if the description gives one.
    pub baud: Option<u32>,
    thermometers: Vec<(String, u8, u8, ThermKind)>,
    channels: Vec<Channel>,
}

#[derive(Debug)]
struct Channel {
    id: u16,
    name: String,
    sensor: SensorKind,
    axis: String,
    unit: String,
    source: Source,
    scale: f32,
    /// (input column, thermometer index), sorted by column name.
    inputs: Vec<(String, u8)>,
}

impl Board {
    /// Reads and checks a description.
    pub fn load(path: &Path) -> Result<Self, BoardError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| BoardError::Io {
            file: file.clone(),
            source,
        })?;
        let raw: RawBoard = toml::from_str(&text).map_err(|source| BoardError::Toml {
            file: file.clone(),
            source,
        })?;
        let invalid = |place: String, message: String| BoardError::Invalid {
            file: file.clone(),
            place,
            message,
        };
        if raw.thermometers.len() > MAX_THERMOMETER_ROWS {
            return Err(invalid(
                "thermometer".into(),
                format!("at most {MAX_THERMOMETER_ROWS} thermometers"),
            ));
        }
        if raw.channels.is_empty() || raw.channels.len() > MAX_CHANNEL_ROWS {
            return Err(invalid(
                "channel".into(),
                format!("1 to {MAX_CHANNEL_ROWS} channels"),
            ));
        }
        let mut thermometers: Vec<(String, u8, u8, ThermKind)> = Vec::new();
        for t in &raw.thermometers {
            let place = format!("thermometer `{}`", t.name);
            if thermometers.iter().any(|(n, ..)| *n == t.name) {
                return Err(invalid(place, "named twice".into()));
            }
            let kind = therm_kind(t).map_err(|m| invalid(place, m))?;
            thermometers.push((t.name.clone(), t.adc, t.input, kind));
        }
        let mut channels: Vec<Channel> = Vec::new();
        for c in &raw.channels {
            let place = format!("channel {} ({})", c.id, c.name);
            if channels.iter().any(|o| o.id == c.id) {
                return Err(invalid(place, "channel id given twice".into()));
            }
            let ch = channel(c, &thermometers).map_err(|m| invalid(place, m))?;
            channels.push(ch);
        }
        let baud = match raw.link {
            Some(RawLink { baud }) if !BAUD_RANGE.contains(&baud) => {
                return Err(invalid(
                    "link".into(),
                    format!(
                        "`baud` {baud} is outside {}..={}",
                        BAUD_RANGE.start(),
                        BAUD_RANGE.end()
                    ),
                ));
            }
            link => link.map(|l| l.baud),
        };
        Ok(Self {
            path: path.to_path_buf(),
            name: raw.name,
            baud,
            thermometers,
            channels,
        })
    }

    /// The thermometer rows, in file order.
    pub fn thermometer_rows(&self) -> Vec<Thermometer<'_>> {
        self.thermometers
            .iter()
            .map(|(name, adc, input, kind)| Thermometer {
                name,
                adc: *adc,
                input: *input,
                kind: *kind,
            })
            .collect()
    }

    /// The channel table, in file order.
    pub fn channel_rows(&self) -> Vec<ChannelRow<'_>> {
        self.channels
            .iter()
            .map(|c| {
                let mut inputs = [Input::default(); MAX_ROW_INPUTS];
                for (d, (name, t)) in inputs.iter_mut().zip(&c.inputs) {
                    *d = Input {
                        name,
                        thermometer: *t,
                    };
                }
                ChannelRow {
                    id: c.id,
                    name: &c.name,
                    sensor: c.sensor,
                    axis: &c.axis,
                    unit: &c.unit,
                    source: c.source,
                    scale: c.scale,
                    inputs,
                    // `channel` refused more than MAX_ROW_INPUTS.
                    n_inputs: c.inputs.len() as u8,
                }
            })
            .collect()
    }

    /// The description's hash (FNV-1a 64 of the canonical rows, as the image carries it).
    pub fn hash(&self) -> u64 {
        tcomp_core::image::board_hash(self.thermometer_rows(), self.channel_rows())
    }
}

fn therm_kind(t: &RawTherm) -> Result<ThermKind, String> {
    let need = |v: Option<f32>, field: &str| -> Result<f32, String> {
        match v {
            Some(x) if x.is_finite() => Ok(x),
            Some(_) => Err(format!("`{field}` must be finite")),
            None => Err(format!("type `{}` needs `{field}`", t.kind)),
        }
    };
    let kind = match t.kind.as_str() {
        "pt100" | "pt1000" => ThermKind::Rtd {
            r0: if t.kind == "pt100" { 100.0 } else { 1000.0 },
            a: IEC_A,
            b: IEC_B,
        },
        "rtd" => ThermKind::Rtd {
            r0: need(t.r0, "r0")?,
            a: need(t.a, "a")?,
            b: need(t.b, "b")?,
        },
        "ntc" => ThermKind::Ntc {
            r0: need(t.r0, "r0")?,
            beta: need(t.beta, "beta")?,
            t0_k: need(t.t0_c, "t0_c")? + 273.15,
        },
        "digital" => ThermKind::Digital {
            scale: need(t.scale, "scale")?,
            offset_c: need(t.offset_c, "offset_c")?,
        },
        other => {
            return Err(format!(
                "unknown type `{other}` (known: pt100, pt1000, rtd, ntc, digital)"
            ));
        }
    };
    let c = kind.constants();
    if c[0] <= 0.0 || (matches!(kind, ThermKind::Ntc { .. }) && (c[1] <= 0.0 || c[2] <= 0.0)) {
        return Err("`r0`, `beta`, `t0_c` + 273.15 and `scale` must be positive".into());
    }
    Ok(kind)
}

fn channel(c: &RawChannel, therms: &[(String, u8, u8, ThermKind)]) -> Result<Channel, String> {
    let sensor = SensorKind::from_name(&c.sensor).ok_or_else(|| {
        let known: Vec<&str> = SensorKind::ALL.iter().map(|k| k.name()).collect();
        format!(
            "unknown sensor `{}` (known: {})",
            c.sensor,
            known.join(", ")
        )
    })?;
    let source = match (c.counter, c.sample) {
        (Some(n), None) => Source::Counter(n),
        (None, Some(n)) => Source::Sample(n),
        _ => return Err("give exactly one of `counter` and `sample`".into()),
    };
    if !(c.scale.is_finite() && c.scale > 0.0) {
        return Err(format!(
            "`scale` must be positive and finite, not {}",
            c.scale
        ));
    }
    if c.inputs.len() > MAX_ROW_INPUTS {
        return Err(format!("at most {MAX_ROW_INPUTS} inputs"));
    }
    let mut inputs = Vec::new();
    for (column, therm) in &c.inputs {
        let t = therms
            .iter()
            .position(|(n, ..)| n == therm)
            .ok_or_else(|| format!("input `{column}`: no thermometer named `{therm}`"))?;
        // At most MAX_THERMOMETER_ROWS (32) thermometers.
        inputs.push((column.clone(), t as u8));
    }
    for (field, s) in [("name", &c.name), ("axis", &c.axis), ("unit", &c.unit)] {
        if s.is_empty() {
            return Err(format!("`{field}` is empty"));
        }
    }
    Ok(Channel {
        id: c.id,
        name: c.name.clone(),
        sensor,
        axis: c.axis.clone(),
        unit: c.unit.clone(),
        source,
        scale: c.scale,
        inputs,
    })
}
