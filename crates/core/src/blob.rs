//! The model blob: what the host trainer writes and the firmware flies, as one serde type.
//!
//! Wire format (postcard is not self-describing, so the layout is fixed by this type and its version):
//! ```text
//! postcard(Model { magic: b"TCMB", version: u16, meta, program, ranges, rbf, residual })
//!   ++ postcard(rbf.masks: Vec<u8>)   (format 3 and later only)
//!   ++ postcard(rbf.kinds: Vec<u8>)   (format 4 and later only)
//!   ++ CRC-32 (LE)
//! ```
//! The magic is four raw bytes and the version a varint, so both are read before the structure and a
//! blob of another version is refused by number, not misread. The CRC-32 (ISO-HDLC, as zip/PNG) covers
//! every byte before it: any single corrupted byte, and any burst up to 32 bits, is detected.
//! Strings borrow from the blob (zero-copy), so a model decoded from flash costs RAM only for its
//! numbers. Decoding checks, in order: length, magic, checksum, version, structure (an unknown enum
//! tag is named, see the `tag` module), capacities, values (finite, positive widths, topologically
//! ordered program), plausibility (see [`crate::bound`]) — and returns the first failure as a
//! [`BlobError`]; it never panics on any byte string.

use crate::bound::Bound;
use crate::point::Point;
use crate::program::{Program, ProgramError};
use crate::rbf::{Rbf, RbfError};
use crate::{HOST_CENTERS, HOST_FEATURES, HOST_NODES};
use heapless::Vec;
use serde::{Deserialize, Serialize};

/// The four bytes every blob starts with.
pub const MAGIC: [u8; 4] = *b"TCMB";
/// The newest blob format version this build reads. A blob is stamped with the oldest version that
/// can read it: [`OLDEST_FORMAT_VERSION`], or the `since` of the newest operation its program uses
/// ([`Program::format_version`], from the table of [`crate::lang`]). So adding an operation to the
/// language raises this number (the assertion below insists) while every blob that does not use
/// it keeps its bytes, and a reader that predates the operation refuses such a blob as a version it
/// does not read ([`BlobError::UnsupportedVersion`]), never as a malformed one.
///
/// Version 2 added `warmup(tau_s)` (time since power-on); a model without it is still version 1,
/// bit for bit. Version 3 added the per-center feature masks of additive models ([`Rbf::masks`]),
/// written after the residual level; a model without masks keeps its older version and bytes.
/// Version 4 added the kind of each center ([`Rbf::kinds`]: Gaussian or logistic step), written
/// after the masks; a model without steps keeps its older version and bytes. Version 5 added the
/// saturating ramp kind ([`crate::rbf::KIND_RAMP`]) with no change of layout: a model without a
/// ramp keeps its older version and bytes, and a format-4 reader refuses one with a ramp by its
/// version instead of by an unknown kind.
pub const FORMAT_VERSION: u16 = 5;
/// The oldest blob format version this build reads: the layout of [`Model`] has not changed since
/// (formats 3 and 4 append fields after it; a blob of an older version has none).
pub const OLDEST_FORMAT_VERSION: u16 = 1;
/// The first format whose blobs carry [`Rbf::masks`] after the residual level.
pub const MASKS_SINCE: u16 = 3;
/// The first format whose blobs carry [`Rbf::kinds`] after the masks.
pub const KINDS_SINCE: u16 = 4;
/// The first format whose [`Rbf::kinds`] may hold [`crate::rbf::KIND_RAMP`].
pub const RAMPS_SINCE: u16 = 5;

const _: () = assert!(
    crate::lang::NEWEST_SINCE <= FORMAT_VERSION && OLDEST_FORMAT_VERSION <= FORMAT_VERSION,
    "an operation of the language is newer than the blob format this build reads"
);

/// Whether this build reads blobs of format `version`.
pub fn reads_version(version: u16) -> bool {
    (OLDEST_FORMAT_VERSION..=FORMAT_VERSION).contains(&version)
}

/// The instrument a model compensates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(remote = "Self")] // serde traits in `crate::tag`: an unknown tag is told apart
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SensorKind {
    /// Ring laser gyro.
    Rlg,
    /// Quartz (pendulous) accelerometer.
    Qma,
    /// Interferometric fiber-optic gyro.
    Ifog,
    /// MEMS gyro.
    MemsGyro,
    /// MEMS accelerometer.
    MemsAccel,
    /// Anything else.
    Other,
}

/// Which CSV columns played which role in training.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColumnRoles<'a> {
    /// Time column (seconds).
    pub time: &'a str,
    /// Sensor output column.
    pub target: &'a str,
    /// Reference column, or "" when a constant reference was used.
    pub reference: &'a str,
    /// The constant reference, when there was no reference column.
    pub reference_value: Option<f32>,
}

/// Descriptive metadata; nothing in it changes the numbers the model produces.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Meta<'a> {
    /// Instrument kind.
    pub sensor: SensorKind,
    /// Axis label, e.g. "x".
    #[serde(borrow)]
    pub axis: &'a str,
    /// Unit of the target and of the correction, e.g. "deg/h".
    pub unit: &'a str,
    /// Training method, e.g. "bayes".
    pub method: &'a str,
    /// Column roles.
    #[serde(borrow)]
    pub columns: ColumnRoles<'a>,
    /// What data it was trained on (file names, time span).
    pub trained_on: &'a str,
    /// Number of training samples (after averaging).
    pub train_samples: u32,
}

/// The range of one feature seen in training; inputs outside are clamped and flagged.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeatureRange {
    /// Lowest valid value.
    pub lo: f32,
    /// Highest valid value.
    pub hi: f32,
}

/// The residual seen on held-out data when the model was made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ResidualLevel {
    /// Residual std at the data's step, target units.
    pub std: f32,
    /// Residual std of bin means.
    pub binned_std: f32,
    /// Bin length in seconds for `binned_std`.
    pub bin_s: f32,
}

/// A compensation model: capacities `C` centers, `F` features, `N` program nodes.
/// The host uses the defaults; firmware picks what its channels need.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model<
    'a,
    const C: usize = HOST_CENTERS,
    const F: usize = HOST_FEATURES,
    const N: usize = HOST_NODES,
> {
    /// Always [`MAGIC`].
    pub magic: [u8; 4],
    /// The oldest format version that reads this model (see [`FORMAT_VERSION`]).
    pub version: u16,
    /// Metadata.
    #[serde(borrow)]
    pub meta: Meta<'a>,
    /// The feature program.
    #[serde(borrow)]
    pub program: Program<'a, N, F>,
    /// Valid range of each feature.
    pub ranges: Vec<FeatureRange, F>,
    /// RBF coefficients.
    pub rbf: Rbf<C, F>,
    /// Held-out residual level.
    pub residual: ResidualLevel,
}

/// Why a blob was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BlobError {
    /// Shorter than the smallest possible blob, or the structure ends early.
    Truncated,
    /// The first four bytes are not `TCMB`.
    BadMagic,
    /// A format version this build does not read: the blob is too new (or too old) for it.
    UnsupportedVersion(u16),
    /// The CRC-32 does not match the content.
    Checksum,
    /// A list or string is longer than this build's capacity.
    CapacityExceeded,
    /// The bytes do not form a model (bad UTF-8, bad option tag, bytes left over).
    Malformed,
    /// An enum tag past the enum's variants; names the field. The blob is malformed (or written by
    /// a build that knows more variants under the same format version).
    UnknownTag(&'static str),
    /// A number is NaN or infinite; names the field.
    NonFinite(&'static str),
    /// Sizes or values disagree; names the field.
    Inconsistent(&'static str),
    /// The feature program is invalid.
    Program(ProgramError),
    /// The output buffer is too small to encode into.
    BufferTooSmall,
    /// Every number is valid, but the model's evaluation over its range box could be non-finite, a
    /// Gaussian could exceed 2^1.5, or the correction exceed 1e12 (see [`crate::bound`]); says
    /// which field and how.
    Implausible(&'static str),
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated => write!(f, "truncated blob"),
            Self::BadMagic => write!(f, "not a tcomp model blob (bad magic)"),
            Self::UnsupportedVersion(v) => {
                write!(
                    f,
                    "unsupported blob format version {v} (this build reads {FORMAT_VERSION})"
                )
            }
            Self::Checksum => write!(f, "checksum mismatch: the blob is corrupt"),
            Self::CapacityExceeded => write!(f, "a size in the blob exceeds this build's capacity"),
            Self::Malformed => write!(f, "malformed blob content"),
            Self::UnknownTag(field) => {
                write!(f, "malformed blob content: unknown enum tag in {field}")
            }
            Self::NonFinite(field) => write!(f, "non-finite number in {field}"),
            Self::Inconsistent(field) => write!(f, "inconsistent field {field}"),
            Self::Program(e) => write!(f, "invalid feature program: {e}"),
            Self::BufferTooSmall => write!(f, "output buffer too small"),
            Self::Implausible(why) => write!(f, "implausible model: {why}"),
        }
    }
}

/// The blob's checksum: the core's one CRC-32 ([`crate::crc`]), here where the wire format names it.
pub use crate::crc::crc32;

impl From<RbfError> for BlobError {
    fn from(e: RbfError) -> Self {
        match e {
            RbfError::NonFinite(f) => Self::NonFinite(f),
            RbfError::Inconsistent(f) => Self::Inconsistent(f),
        }
    }
}

fn map_postcard(e: postcard::Error) -> BlobError {
    match e {
        postcard::Error::DeserializeUnexpectedEnd => BlobError::Truncated,
        // heapless (and `Point`) report a sequence longer than its capacity through serde's custom
        // error; unknown enum tags, which would arrive the same way, are diverted by the `tag` module.
        postcard::Error::SerdeDeCustom => BlobError::CapacityExceeded,
        postcard::Error::WontImplement => BlobError::UnknownTag("the model"),
        postcard::Error::SerializeBufferFull => BlobError::BufferTooSmall,
        _ => BlobError::Malformed,
    }
}

/// A postcard error of decoding `body` as a [`BlobError`], with an unknown tag located.
fn map_body_error(body: &[u8], e: postcard::Error) -> BlobError {
    match e {
        postcard::Error::WontImplement => locate_unknown_tag(body),
        e => map_postcard(e),
    }
}

/// Where in `body` (a blob without its CRC) the unknown tag `map_postcard` reported is. A blob holds
/// two enums: the sensor kind, the first field after magic and version, and the program's
/// operations. Reading that one varint (rather than decoding the metadata again) keeps the firmware's
/// flash small.
fn locate_unknown_tag(body: &[u8]) -> BlobError {
    // `Other` is the last variant: a tag past it is unknown.
    const SENSOR_KINDS: u32 = SensorKind::Other as u32 + 1;
    let tag = body
        .get(4..)
        .and_then(|b| postcard::take_from_bytes::<(u16, u32)>(b).ok());
    match tag {
        Some(((_, t), _)) if t >= SENSOR_KINDS => BlobError::UnknownTag("meta.sensor"),
        _ => BlobError::UnknownTag("program.nodes"),
    }
}

impl<'a, const C: usize, const F: usize, const N: usize> Model<'a, C, F, N> {
    /// A model from its parts, with magic and version set (the version its program needs).
    pub fn new(
        meta: Meta<'a>,
        program: Program<'a, N, F>,
        ranges: Vec<FeatureRange, F>,
        rbf: Rbf<C, F>,
        residual: ResidualLevel,
    ) -> Self {
        Self {
            magic: MAGIC,
            version: Self::version_for(&program, &rbf),
            meta,
            program,
            ranges,
            rbf,
            residual,
        }
    }

    /// The oldest format that can carry `program` and `rbf`: its newest operation's, and
    /// [`MASKS_SINCE`] for an additive model, [`KINDS_SINCE`] for one with steps,
    /// [`RAMPS_SINCE`] for one with ramps.
    pub fn version_for(program: &Program<'a, N, F>, rbf: &Rbf<C, F>) -> u16 {
        let masks = if rbf.masks.is_empty() { 0 } else { MASKS_SINCE };
        let kinds = if rbf.kinds.contains(&crate::rbf::KIND_RAMP) {
            RAMPS_SINCE
        } else if rbf.kinds.is_empty() {
            0
        } else {
            KINDS_SINCE
        };
        program
            .format_version()
            .max(OLDEST_FORMAT_VERSION)
            .max(masks)
            .max(kinds)
    }

    /// Number of features.
    pub fn n_features(&self) -> usize {
        self.program.n_features()
    }

    /// Checks everything a model must satisfy before it may fly.
    pub fn validate(&self) -> Result<(), BlobError> {
        if self.magic != MAGIC {
            return Err(BlobError::BadMagic);
        }
        if !reads_version(self.version) {
            return Err(BlobError::UnsupportedVersion(self.version));
        }
        self.program.validate().map_err(BlobError::Program)?;
        if self.program.format_version() > self.version {
            return Err(BlobError::Inconsistent(
                "version: older than an operation of the program",
            ));
        }
        self.rbf.validate()?;
        if !self.rbf.masks.is_empty() && self.version < MASKS_SINCE {
            return Err(BlobError::Inconsistent(
                "version: older than the additive model's masks (format 3)",
            ));
        }
        if !self.rbf.kinds.is_empty() && self.version < KINDS_SINCE {
            return Err(BlobError::Inconsistent(
                "version: older than the model's steps (format 4)",
            ));
        }
        if self.rbf.kinds.contains(&crate::rbf::KIND_RAMP) && self.version < RAMPS_SINCE {
            return Err(BlobError::Inconsistent(
                "version: older than the model's ramps (format 5)",
            ));
        }
        let nf = self.program.n_features();
        if self.rbf.n_features as usize != nf {
            return Err(BlobError::Inconsistent(
                "rbf.n_features differs from program.features",
            ));
        }
        if self.ranges.len() != nf {
            return Err(BlobError::Inconsistent("ranges: one per feature"));
        }
        for r in &self.ranges {
            if !(r.lo.is_finite() && r.hi.is_finite()) {
                return Err(BlobError::NonFinite("ranges"));
            }
            if r.lo > r.hi {
                return Err(BlobError::Inconsistent("ranges: lo > hi"));
            }
        }
        if self
            .meta
            .columns
            .reference_value
            .is_some_and(|v| !v.is_finite())
        {
            return Err(BlobError::NonFinite("meta.columns.reference_value"));
        }
        let res = &self.residual;
        if !(res.std.is_finite() && res.binned_std.is_finite() && res.bin_s.is_finite()) {
            return Err(BlobError::NonFinite("residual"));
        }
        self.bound().map(|_| ())
    }

    /// The plausibility bound of [`crate::bound`] over this model's range box: a bound on
    /// `|correction|` anywhere the compensator evaluates it, or why the model is implausible.
    /// [`Model::validate`] runs it last, so it may assume valid numbers.
    pub fn bound(&self) -> Result<Bound, BlobError> {
        crate::bound::check(&self.rbf, &self.ranges).map_err(BlobError::Implausible)
    }

    /// Writes the blob into `buf`, returning its length. Refuses a model that would not decode.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, BlobError> {
        self.validate()?;
        let mut used = postcard::to_slice(self, buf).map_err(map_postcard)?.len();
        if self.version >= MASKS_SINCE {
            let rest = buf.get_mut(used..).ok_or(BlobError::BufferTooSmall)?;
            used += postcard::to_slice(&self.rbf.masks, rest)
                .map_err(map_postcard)?
                .len();
        }
        if self.version >= KINDS_SINCE {
            let rest = buf.get_mut(used..).ok_or(BlobError::BufferTooSmall)?;
            used += postcard::to_slice(&self.rbf.kinds, rest)
                .map_err(map_postcard)?
                .len();
        }
        let crc = crc32(buf.get(..used).ok_or(BlobError::BufferTooSmall)?);
        let tail = buf
            .get_mut(used..used + 4)
            .ok_or(BlobError::BufferTooSmall)?;
        tail.copy_from_slice(&crc.to_le_bytes());
        Ok(used + 4)
    }

    /// Decodes and validates a blob. Never panics, whatever the bytes.
    ///
    /// The CRC is checked before the version: a corrupted version byte is corruption, and only an
    /// intact blob of another format is reported as [`BlobError::UnsupportedVersion`].
    pub fn decode(bytes: &'a [u8]) -> Result<Self, BlobError> {
        let body = Self::envelope(bytes)?;
        let (mut model, rest) =
            postcard::take_from_bytes::<Self>(body).map_err(|e| map_body_error(body, e))?;
        (model.rbf.masks, model.rbf.kinds) = Self::trailing(model.version, rest)?;
        model.validate()?;
        Ok(model)
    }

    /// [`decode`](Self::decode) straight into `place` (the same checks, errors and model): serde
    /// writes each field where it belongs instead of building the model on the stack and moving
    /// it, so a firmware decoding into a `static` needs a stack frame of a fraction of a model.
    /// On error `place` is `None`.
    pub fn decode_into(bytes: &'a [u8], place: &mut Option<Self>) -> Result<(), BlobError> {
        let result = Self::envelope(bytes).and_then(|body| {
            let model = place.insert(Self::placeholder());
            let mut de = postcard::Deserializer::from_bytes(body);
            <Self as Deserialize<'a>>::deserialize_in_place(&mut de, model)
                .map_err(|e| map_body_error(body, e))?;
            let rest = de.finalize().map_err(map_postcard)?;
            (model.rbf.masks, model.rbf.kinds) = Self::trailing(model.version, rest)?;
            model.validate()
        });
        if result.is_err() {
            *place = None;
        }
        result
    }

    /// The masks after the residual level (format 3 on; none before), then the kinds (format 4
    /// on; none before), and nothing after them.
    #[allow(clippy::type_complexity)]
    fn trailing(version: u16, rest: &[u8]) -> Result<(Vec<u8, C>, Vec<u8, C>), BlobError> {
        let mut rest = rest;
        let mut take = |since: u16| -> Result<Vec<u8, C>, BlobError> {
            if version < since {
                return Ok(Vec::new());
            }
            let (v, after) = postcard::take_from_bytes::<Vec<u8, C>>(rest).map_err(map_postcard)?;
            rest = after;
            Ok(v)
        };
        let masks = take(MASKS_SINCE)?;
        let kinds = take(KINDS_SINCE)?;
        if !rest.is_empty() {
            return Err(BlobError::Malformed);
        }
        Ok((masks, kinds))
    }

    /// An empty model for [`decode_into`](Self::decode_into) to overwrite field by field.
    fn placeholder() -> Self {
        Self {
            magic: MAGIC,
            version: FORMAT_VERSION,
            meta: Meta {
                sensor: SensorKind::Other,
                axis: "",
                unit: "",
                method: "",
                columns: ColumnRoles {
                    time: "",
                    target: "",
                    reference: "",
                    reference_value: None,
                },
                trained_on: "",
                train_samples: 0,
            },
            program: Program {
                inputs: Vec::new(),
                signals: Vec::new(),
                nodes: Vec::new(),
                features: Vec::new(),
                feature_exprs: Vec::new(),
            },
            ranges: Vec::new(),
            rbf: Rbf::default(),
            residual: ResidualLevel {
                std: 0.0,
                binned_std: 0.0,
                bin_s: 0.0,
            },
        }
    }

    /// Checks magic, length and CRC, then the version (so a corrupted version byte is corruption);
    /// returns the postcard body.
    fn envelope(bytes: &'a [u8]) -> Result<&'a [u8], BlobError> {
        let magic = bytes.get(..4).ok_or(BlobError::Truncated)?;
        if magic != MAGIC {
            return Err(BlobError::BadMagic);
        }
        // Magic, a version varint (at least one byte) and the CRC.
        if bytes.len() < 4 + 1 + 4 {
            return Err(BlobError::Truncated);
        }
        let body_len = bytes.len().checked_sub(4).ok_or(BlobError::Truncated)?;
        let (body, crc_bytes) = bytes
            .split_at_checked(body_len)
            .ok_or(BlobError::Truncated)?;
        let mut crc = [0u8; 4];
        crc.copy_from_slice(crc_bytes);
        if crc32(body) != u32::from_le_bytes(crc) {
            return Err(BlobError::Checksum);
        }
        let after_magic = body.get(4..).ok_or(BlobError::Truncated)?;
        let (version, _) = postcard::take_from_bytes::<u16>(after_magic).map_err(|e| match e {
            postcard::Error::DeserializeUnexpectedEnd => BlobError::Truncated,
            _ => BlobError::Malformed,
        })?;
        if !reads_version(version) {
            return Err(BlobError::UnsupportedVersion(version));
        }
        Ok(body)
    }

    /// The per-feature ranges as two points (lo, hi), for clamping.
    pub fn range_points(&self) -> (Point<F>, Point<F>) {
        let mut lo = Point::<F>::default();
        let mut hi = Point::<F>::default();
        for ((l, h), r) in lo.0.iter_mut().zip(hi.0.iter_mut()).zip(&self.ranges) {
            *l = r.lo;
            *h = r.hi;
        }
        (lo, hi)
    }
}
