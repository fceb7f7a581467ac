//! The rows of a version-2 image: the board's thermometers, its channel table and the per-channel
//! provenance of the blobs, as plain `Copy` values the writer takes and the reader hands back.
//!
//! They live apart from the byte layout (in [`super`] and [`super::write`]) so the host's board
//! description, the writer and the firmware all speak in the same types, and so the one canonical
//! serialisation of a board description, [`board_hash`], is computed from exactly what the image
//! carries: the host hashes what it is about to write, the firmware can recompute it from what it
//! read, and comments or whitespace in the TOML the user wrote cannot change it.

use crate::blob::{Meta, SensorKind};

/// Named thermometer inputs one channel may bind (an RLG has three, a QMA, an IFOG or a MEMS IMU
/// one; a fourth leaves room for a supply voltage or a second coil sensor).
pub const MAX_ROW_INPUTS: usize = 4;

/// How a thermometer's raw reading becomes °C.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ThermKind {
    /// A platinum RTD (Callendar–Van Dusen above 0 °C): R(T) = r0·(1 + a·T + b·T²).
    Rtd {
        /// Resistance at 0 °C, Ω (100 for a PT100, 1000 for a PT1000).
        r0: f32,
        /// Linear coefficient, 1/°C (3.9083e-3 for IEC 60751).
        a: f32,
        /// Quadratic coefficient, 1/°C² (−5.775e-7 for IEC 60751).
        b: f32,
    },
    /// An NTC thermistor, beta model: R(T) = r0·exp(beta·(1/T − 1/t0)), T in kelvin.
    Ntc {
        /// Resistance at `t0`, Ω.
        r0: f32,
        /// Beta constant, K.
        beta: f32,
        /// Reference temperature, K (298.15 for 25 °C).
        t0_k: f32,
    },
    /// A digital sensor that reports °C itself (a MEMS IMU's temperature register): `scale` °C
    /// per LSB around `offset_c`.
    Digital {
        /// °C per LSB.
        scale: f32,
        /// °C at a reading of zero.
        offset_c: f32,
    },
}

impl ThermKind {
    /// The kind's code in the image.
    pub const fn code(&self) -> u8 {
        match self {
            Self::Rtd { .. } => 1,
            Self::Ntc { .. } => 2,
            Self::Digital { .. } => 3,
        }
    }

    /// Its three constants in the image's order.
    pub const fn constants(&self) -> [f32; 3] {
        match *self {
            Self::Rtd { r0, a, b } => [r0, a, b],
            Self::Ntc { r0, beta, t0_k } => [r0, beta, t0_k],
            Self::Digital { scale, offset_c } => [scale, offset_c, 0.0],
        }
    }

    /// The kind of `code` with constants `c`; `None` for an unknown code or a non-finite constant.
    pub fn from_code(code: u8, c: [f32; 3]) -> Option<Self> {
        if !c.iter().all(|v| v.is_finite()) {
            return None;
        }
        let [c0, c1, c2] = c;
        match code {
            1 => Some(Self::Rtd {
                r0: c0,
                a: c1,
                b: c2,
            }),
            2 => Some(Self::Ntc {
                r0: c0,
                beta: c1,
                t0_k: c2,
            }),
            3 => Some(Self::Digital {
                scale: c0,
                offset_c: c1,
            }),
            _ => None,
        }
    }
}

/// One thermometer of the board: where it is read and how its reading converts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thermometer<'a> {
    /// The description's name for it (e.g. `rlg-x-anode`), for reports.
    pub name: &'a str,
    /// Which converter (ADC index, or the digital sensor's index) on the board.
    pub adc: u8,
    /// Which input (multiplexer setting) of that converter.
    pub input: u8,
    /// The sensing element and its constants.
    pub kind: ThermKind,
}

/// Where a channel's raw value comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Source {
    /// Pulse counter `n` of the counter block: rate = counts × scale / interval.
    Counter(u8),
    /// Sample source `n` (a digital IMU's register): value = register × scale.
    Sample(u8),
}

impl Source {
    /// `(kind code, index)` in the image: 0 counter, 1 sample.
    pub const fn code(&self) -> (u8, u8) {
        match *self {
            Self::Counter(n) => (0, n),
            Self::Sample(n) => (1, n),
        }
    }

    /// The source of `(kind, index)`; `None` for an unknown kind.
    pub const fn from_code(kind: u8, n: u8) -> Option<Self> {
        match kind {
            0 => Some(Self::Counter(n)),
            1 => Some(Self::Sample(n)),
            _ => None,
        }
    }
}

/// One named input of a channel: the model's input column `name` reads thermometer `thermometer`
/// (an index into the image's thermometer list).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Input<'a> {
    /// The input column name a model reads (e.g. `t_anode_c`).
    pub name: &'a str,
    /// Index of the thermometer in the board's list.
    pub thermometer: u8,
}

/// One row of the channel table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelRow<'a> {
    /// Channel id: the key of its blob and its position in the frames' order of the table.
    pub id: u16,
    /// Short name for logs and reports.
    pub name: &'a str,
    /// The instrument.
    pub sensor: SensorKind,
    /// Axis label, as a model's metadata names it (`x`, `y`, `z`).
    pub axis: &'a str,
    /// The output unit, as a model's metadata names it (`deg/h`, `ug`, `rad/s`, `m/s^2`).
    pub unit: &'a str,
    /// Counter or sample source.
    pub source: Source,
    /// Output unit per pulse (counter: arcsec or µg·s per pulse, as `tcomp_hal::scale`) or per LSB.
    pub scale: f32,
    /// The named thermometer inputs; the first `n_inputs` are used.
    pub inputs: [Input<'a>; MAX_ROW_INPUTS],
    /// How many of `inputs` are set.
    pub n_inputs: u8,
}

impl<'a> ChannelRow<'a> {
    /// The inputs that are set.
    pub fn inputs(&self) -> &[Input<'a>] {
        self.inputs
            .get(..usize::from(self.n_inputs))
            .unwrap_or(&self.inputs)
    }

    /// The thermometer index bound to input column `name`.
    pub fn thermometer_for(&self, name: &str) -> Option<u8> {
        self.inputs()
            .iter()
            .find(|i| i.name == name)
            .map(|i| i.thermometer)
    }

    /// Whether a model with metadata `meta` and input columns `inputs` can run on this channel:
    /// the same sensor kind, axis and unit, and every input column bound to a thermometer.
    pub fn accepts<'s>(
        &self,
        meta: &Meta<'_>,
        inputs: impl IntoIterator<Item = &'s str>,
    ) -> Result<(), Mismatch<'s>> {
        if meta.sensor != self.sensor {
            return Err(Mismatch::Sensor(meta.sensor));
        }
        if meta.unit != self.unit {
            return Err(Mismatch::Unit);
        }
        if meta.axis != self.axis {
            return Err(Mismatch::Axis);
        }
        for name in inputs {
            if self.thermometer_for(name).is_none() {
                return Err(Mismatch::Input(name));
            }
        }
        Ok(())
    }
}

/// Why a model does not belong on a channel ([`ChannelRow::accepts`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mismatch<'s> {
    /// The model is for another kind of instrument.
    Sensor(SensorKind),
    /// The model's unit is not the channel's.
    Unit,
    /// The model's axis is not the channel's.
    Axis,
    /// The model reads an input column the channel has no thermometer for.
    Input(&'s str),
}

/// Where a channel's blob came from, kept beside it in the image so `tcomp inspect` and the boot
/// report can say what a unit runs without decoding the blob.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Provenance<'a> {
    /// The training data's file name.
    pub data: &'a str,
    /// FNV-1a 64 of the training data file's bytes (0: not known).
    pub data_hash: u64,
    /// The training window, seconds of the data's time column (NaN: not known).
    pub window: [f32; 2],
    /// The training method (`bayes`, `poly3`, …).
    pub method: &'a str,
}

/// FNV-1a 64: the identity hash of the image (board description, training data). Eight bytes
/// make an accidental match between two descriptions a 2⁻⁶⁴ event, where CRC-32's 2⁻³² is not
/// far-fetched over a fleet; it is not a defence against a forger, which a checksum in the same
/// file could not be anyway. Small enough for the firmware to recompute at boot.
#[derive(Clone, Copy, Debug)]
pub struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv64 {
    /// The offset basis.
    pub const fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    /// Feeds `bytes`.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// Feeds a string with its length first, so `("ab","c")` and `("a","bc")` differ.
    pub fn write_str(&mut self, s: &str) {
        self.write(&(s.len() as u32).to_le_bytes());
        self.write(s.as_bytes());
    }

    /// The hash so far.
    pub const fn finish(&self) -> u64 {
        self.0
    }
}

/// The board-description hash: FNV-1a 64 over the canonical serialisation of the thermometers and
/// the channel table — every field in a fixed order, numbers little-endian, strings
/// length-prefixed, floats by their bits. Two descriptions that differ in anything the firmware
/// uses hash differently; comments, key order and whitespace of the TOML do not enter.
///
/// Each row is preceded by a tag byte (`T`, `C`), so the row sequence needs no counts and the
/// firmware hashes the rows as it reads them, without collecting them first.
pub fn board_hash<'t, 'c>(
    thermometers: impl IntoIterator<Item = Thermometer<'t>>,
    channels: impl IntoIterator<Item = ChannelRow<'c>>,
) -> u64 {
    let mut h = Fnv64::new();
    h.write(b"tcomp-board-v1");
    for t in thermometers {
        h.write(b"T");
        h.write_str(t.name);
        h.write(&[t.adc, t.input, t.kind.code()]);
        for c in t.kind.constants() {
            h.write(&c.to_bits().to_le_bytes());
        }
    }
    for c in channels {
        h.write(b"C");
        h.write(&c.id.to_le_bytes());
        h.write_str(c.name);
        h.write(&[sensor_code(c.sensor)]);
        h.write_str(c.axis);
        h.write_str(c.unit);
        let (kind, n) = c.source.code();
        h.write(&[kind, n]);
        h.write(&c.scale.to_bits().to_le_bytes());
        h.write(&[c.n_inputs]);
        for i in c.inputs() {
            h.write_str(i.name);
            h.write(&[i.thermometer]);
        }
    }
    h.finish()
}

/// A sensor kind's code in the image (its order in [`SensorKind`]).
pub const fn sensor_code(s: SensorKind) -> u8 {
    match s {
        SensorKind::Rlg => 0,
        SensorKind::Qma => 1,
        SensorKind::Ifog => 2,
        SensorKind::MemsGyro => 3,
        SensorKind::MemsAccel => 4,
        SensorKind::Other => 5,
    }
}

/// The sensor kind of `code`, `None` for an unknown one.
pub const fn sensor_from_code(code: u8) -> Option<SensorKind> {
    match code {
        0 => Some(SensorKind::Rlg),
        1 => Some(SensorKind::Qma),
        2 => Some(SensorKind::Ifog),
        3 => Some(SensorKind::MemsGyro),
        4 => Some(SensorKind::MemsAccel),
        5 => Some(SensorKind::Other),
        _ => None,
    }
}
