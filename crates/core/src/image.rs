//! The calibration image: the blobs of one unit, the board's channel table they run on, and who
//! made them for which unit — defined once for every side.
//!
//! `tcomp image --board FILE` writes it with [`ImageSpec::write`], the firmware reads it from flash
//! with [`Image::parse`] (zero-copy: rows and strings are read from the image bytes when asked
//! for), `tcomp inspect` prints it, and the tests use all three; a second copy of the layout could
//! drift from this one without any test noticing, so there is none. Everything here is `no_std`,
//! allocation-free and never panics: the reader takes any bytes (erased flash, a truncated upload,
//! garbage), the writer any caller's buffer.
//!
//! # Why the channel table travels in the image
//! The board description (which thermometer and which counter or sample source feed which
//! channel, sensor kind, axis, unit, scale) is data the user writes once per IMU design. Carrying
//! its compiled form in the image, next to the models that must agree with it, means one firmware
//! runs an RLG/QMA IMU, an IFOG triad or a MEMS IMU: the board crate keeps only the hardware (which
//! SPI, which chip selects). Generating it into the board crate instead would need a firmware
//! build per design and would let an image meet a table it was not checked against. The image's
//! board hash lets the firmware and `tcomp inspect` say which description an image was built for.
//!
//! # Format, version 2 (written by `tcomp image`)
//! Everything is little-endian. Strings are references `(u16 offset into the pool, u16 length)`,
//! UTF-8.
//!
//! ```text
//! offset  size  field
//! 0       4     magic b"TCMI"
//! 4       2     version (2)
//! 6       2     header length (64)
//! 8       4     image length L (a multiple of 4)
//! 12      4     CRC-32 (ISO-HDLC) of bytes [16, L): everything after this field
//! 16      8     unit serial number
//! 24      8     board-description hash: FNV-1a 64 of its canonical serialisation (table::board_hash)
//! 32      8     creation time, seconds since 1970-01-01 UTC
//! 40      16    tool version, UTF-8, zero-padded ("0.1.0+1a2b3c4")
//! 56      1     thermometers nt (≤ 32)
//! 57      1     channels nc (≤ 16)
//! 58      1     entries ne (≤ 32)
//! 59      1     0
//! 60      2     string pool length P
//! 62      2     0
//! 64      20·nt thermometer rows: name str, adc u8, input u8, kind u8 (1 RTD, 2 NTC, 3 digital),
//!               0 u8, three f32 constants (RTD r0, a, b; NTC r0, beta, t0 in K; digital
//!               °C/LSB, offset °C, 0)
//! …       56·nc channel rows: id u16, sensor u8 (0 RLG, 1 QMA, 2 IFOG, 3 MEMS gyro, 4 MEMS
//!               accel, 5 other), source kind u8 (0 pulse counter, 1 sample source), source index
//!               u8, inputs n u8 (≤ 4), 0 u16, scale f32, name str, axis str, unit str, then 4 ×
//!               (input column name str, thermometer index u8, 3 × 0)
//! …       40·ne entries: channel id u16, 0 u16, offset u32, length u32, blob CRC-32 u32,
//!               training data file str, its FNV-1a 64 u64, training window start f32, end f32
//!               (s, NaN when unknown), method str
//! …       P     string pool, in row order; zeros up to a multiple of 4
//! …             the blobs in entry order, each followed by zeros up to a multiple of 4
//! ```
//!
//! The whole-image CRC covers every row and every blob, so a partial upload or a flipped bit is
//! refused as a whole (the A/B slots keep the last good image); every blob still carries its own
//! CRC-32 (see [`crate::blob`]). The reader also checks every row (strings inside the pool and
//! UTF-8, known codes, thermometer indices, distinct channel ids, each entry on a channel of the
//! table and at most one per channel, blobs inside the image after the pool) and that the board
//! hash in the header is the hash of the rows it carries. It does not decode blobs: whether a blob
//! belongs on its row (sensor kind, axis, unit, inputs) is [`ChannelRow::accepts`], which the tool
//! runs before writing and the firmware at boot, so an entry pointing at another channel's valid
//! blob is refused.
//!
//! # Version 1 (read only)
//! Images written before the channel table existed: magic, version u16 (1), entry count u16,
//! CRC-32 of the table; then per entry channel id u16, 0 u16, offset u32, length u32; then the
//! blobs, 4-byte aligned. [`write_image`] still writes it for the reader's tests. It has no table,
//! serial or provenance; [`Image::header`] and [`Image::channel`] give `None` for it.
//!
//! Erased flash (`0xFF…`) or an empty region (zeros) has no magic and reads as "no image".
//!
//! # Signature
//! A signed image is followed, at its length L, by an 80-byte Ed25519 signature block over bytes
//! `[0, L + 16)` ([`sign`]: the block's layout, the key store a unit is provisioned with, the
//! verifier). The reader above ignores what follows the image, so a signed image parses as the
//! image it signs.

pub mod sign;
pub mod table;
mod v2;
mod write;

pub use table::{
    ChannelRow, Fnv64, Input, MAX_ROW_INPUTS, Mismatch, Provenance, Source, ThermKind, Thermometer,
    board_hash,
};
pub use v2::{Header, MAX_CHANNEL_ROWS, MAX_THERMOMETER_ROWS};
pub use write::{Entry, ImageSpec, seal};

use crate::crc::crc32;

/// The four bytes an image starts with.
pub const MAGIC: [u8; 4] = *b"TCMI";
/// The first image format version: a table of blobs only (read, and written for tests).
pub const VERSION: u16 = 1;
/// The image format version `tcomp image` writes: header, channel table, provenance.
pub const VERSION_2: u16 = 2;
/// Bytes before the table (version 1).
pub const HEADER_LEN: usize = 12;
/// Bytes per table entry (version 1).
pub const ENTRY_LEN: usize = 12;
/// Most entries an image may list.
pub const MAX_ENTRIES: usize = 32;
/// The alignment of the first blob and of each blob's length with its padding.
pub const ALIGN: usize = 4;

/// Why an image, one of its entries, or an image to be written is unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ImageError {
    /// No magic: the region is erased, empty, or holds something else.
    NoImage,
    /// A version this build does not read.
    UnsupportedVersion(u16),
    /// More entries than [`MAX_ENTRIES`], or a table past the end of the region.
    BadTable,
    /// The CRC does not match: the table's (version 1) or the whole image's (version 2).
    Checksum,
    /// The image has no entry for the channel.
    Missing,
    /// The entry's blob lies (partly) outside the image region.
    OutOfBounds,
    /// Writing: more than [`MAX_ENTRIES`] blobs.
    TooManyEntries,
    /// Writing: two blobs for the same channel id.
    DuplicateId(u16),
    /// Writing: the image needs `needed` bytes and the buffer is shorter.
    BufferTooSmall {
        /// Bytes the image needs.
        needed: usize,
    },
    /// Writing: an offset or a length does not fit the table's 32-bit fields, or a string its
    /// 16-bit fields.
    TooLarge,
    /// A thermometer, channel or entry row holds an unknown code, a string outside the pool or
    /// not UTF-8, a thermometer index past the list, or a non-finite number.
    BadRow,
    /// An entry names a channel the table does not have.
    UnknownChannel(u16),
    /// The header's board hash is not the hash of the rows the image carries.
    BoardHash,
    /// The image was made for another unit. The serials are in the image's header and the
    /// boot report; not carried here, so that the error stays as small as the others (the
    /// firmware keeps one per channel on its boot stack).
    OtherUnit,
}

impl core::fmt::Display for ImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoImage => f.write_str("no model image (erased or empty region)"),
            Self::UnsupportedVersion(v) => write!(f, "unsupported image version {v}"),
            Self::BadTable => f.write_str("image table too long"),
            Self::Checksum => {
                f.write_str("image checksum mismatch (the table; in version 2 the whole image)")
            }
            Self::Missing => f.write_str("no blob for this channel in the image"),
            Self::OutOfBounds => f.write_str("blob outside the image region"),
            Self::TooManyEntries => write!(f, "at most {MAX_ENTRIES} blobs fit the image table"),
            Self::DuplicateId(id) => write!(f, "channel {id} is given twice"),
            Self::BufferTooSmall { needed } => {
                write!(
                    f,
                    "the image needs {needed} bytes, more than the buffer holds"
                )
            }
            Self::TooLarge => f.write_str("the image or one of its strings is too large"),
            Self::BadRow => f.write_str("malformed row in the image's channel table"),
            Self::UnknownChannel(id) => write!(f, "channel {id} is not in the board's table"),
            Self::BoardHash => f.write_str("board hash does not match the image's table"),
            Self::OtherUnit => f.write_str("image made for another unit"),
        }
    }
}

/// So host code can keep it as the `source` of its own error.
impl core::error::Error for ImageError {}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    let s = b.get(at..at.checked_add(2)?)?;
    Some(u16::from_le_bytes([*s.first()?, *s.get(1)?]))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s: [u8; 4] = b.get(at..at.checked_add(4)?)?.try_into().ok()?;
    Some(u32::from_le_bytes(s))
}

/// Which layout a parsed image has.
#[derive(Clone, Copy, Debug)]
enum Layout {
    V1 { count: usize },
    V2(v2::Layout),
}

/// A validated image over its bytes (e.g. a whole flash region): header, table and rows checked,
/// nothing copied; rows and blobs are read from the bytes when asked for.
#[derive(Clone, Copy, Debug)]
pub struct Image<'a> {
    bytes: &'a [u8],
    layout: Layout,
}

impl<'a> Image<'a> {
    /// Checks magic and version, then (version 2) the whole-image CRC, every row and the board
    /// hash, or (version 1) the table's size and CRC. Never panics.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ImageError> {
        if bytes.get(..4) != Some(&MAGIC[..]) {
            return Err(ImageError::NoImage);
        }
        let version = u16_at(bytes, 4).ok_or(ImageError::NoImage)?;
        let layout = match version {
            VERSION => Layout::V1 {
                count: parse_v1(bytes)?,
            },
            VERSION_2 => Layout::V2(v2::parse(bytes)?),
            v => return Err(ImageError::UnsupportedVersion(v)),
        };
        Ok(Self { bytes, layout })
    }

    /// The format version (1 or 2).
    pub fn version(&self) -> u16 {
        match self.layout {
            Layout::V1 { .. } => VERSION,
            Layout::V2(_) => VERSION_2,
        }
    }

    /// The image's length in bytes (version 1: up to the end of its last blob).
    pub fn byte_len(&self) -> usize {
        match self.layout {
            Layout::V1 { .. } => self
                .entries()
                .filter_map(Result::ok)
                .map(|(_, b)| {
                    let start = b.as_ptr() as usize - self.bytes.as_ptr() as usize;
                    (start + b.len()).next_multiple_of(ALIGN)
                })
                .max()
                .unwrap_or(first_blob_at(self.len())),
            Layout::V2(l) => l.len,
        }
    }

    /// Number of blob entries.
    pub fn len(&self) -> usize {
        match self.layout {
            Layout::V1 { count } => count,
            Layout::V2(l) => l.n_entries,
        }
    }

    /// True when the image holds no blob.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The identity fields of a version-2 image (`None` for version 1).
    pub fn header(&self) -> Option<Header<'a>> {
        match self.layout {
            Layout::V1 { .. } => None,
            Layout::V2(_) => v2::header(self.bytes),
        }
    }

    /// Rows of the channel table (0 for version 1).
    pub fn n_channels(&self) -> usize {
        match self.layout {
            Layout::V1 { .. } => 0,
            Layout::V2(l) => l.n_chan,
        }
    }

    /// Thermometers of the board (0 for version 1).
    pub fn n_thermometers(&self) -> usize {
        match self.layout {
            Layout::V1 { .. } => 0,
            Layout::V2(l) => l.n_therm,
        }
    }

    /// Row `i` of the channel table.
    pub fn channel(&self, i: usize) -> Option<ChannelRow<'a>> {
        match &self.layout {
            Layout::V1 { .. } => None,
            Layout::V2(l) => v2::channel(self.bytes, l, i),
        }
    }

    /// The row of channel `id`.
    pub fn channel_by_id(&self, id: u16) -> Option<ChannelRow<'a>> {
        (0..self.n_channels())
            .filter_map(|i| self.channel(i))
            .find(|r| r.id == id)
    }

    /// Thermometer `i` of the board.
    pub fn thermometer(&self, i: usize) -> Option<Thermometer<'a>> {
        match &self.layout {
            Layout::V1 { .. } => None,
            Layout::V2(l) => v2::thermometer(self.bytes, l, i),
        }
    }

    /// The provenance of entry `i` (version 2).
    pub fn provenance(&self, i: usize) -> Option<Provenance<'a>> {
        match &self.layout {
            Layout::V1 { .. } => None,
            Layout::V2(l) => v2::provenance(self.bytes, l, i),
        }
    }

    /// The blob CRC entry `i` records (version 2).
    pub fn entry_crc(&self, i: usize) -> Option<u32> {
        match &self.layout {
            Layout::V1 { .. } => None,
            Layout::V2(l) => v2::entry_crc(self.bytes, l, i),
        }
    }

    /// Whether the image may run on the unit with serial `unit`: a version-2 image names its unit
    /// ([`ImageError::OtherUnit`] otherwise); a version-1 image names none and is accepted.
    pub fn check_unit(&self, unit: u64) -> Result<(), ImageError> {
        match self.header() {
            Some(h) if h.serial != unit => Err(ImageError::OtherUnit),
            _ => Ok(()),
        }
    }

    /// `(channel id, blob bytes)` of entry `i`; the blob always lies inside the parsed bytes.
    pub fn entry(&self, i: usize) -> Result<(u16, &'a [u8]), ImageError> {
        if i >= self.len() {
            return Err(ImageError::Missing);
        }
        let (id, offset, len) = match &self.layout {
            Layout::V1 { .. } => {
                let at = HEADER_LEN + ENTRY_LEN * i;
                let id = u16_at(self.bytes, at).ok_or(ImageError::BadTable)?;
                let offset = u32_at(self.bytes, at + 4).ok_or(ImageError::BadTable)?;
                let len = u32_at(self.bytes, at + 8).ok_or(ImageError::BadTable)?;
                let offset = usize::try_from(offset).map_err(|_| ImageError::OutOfBounds)?;
                let len = usize::try_from(len).map_err(|_| ImageError::OutOfBounds)?;
                (id, offset, len)
            }
            Layout::V2(l) => v2::entry_span(self.bytes, l, i).ok_or(ImageError::BadTable)?,
        };
        let blob = offset
            .checked_add(len)
            .and_then(|end| self.bytes.get(offset..end))
            .ok_or(ImageError::OutOfBounds)?;
        Ok((id, blob))
    }

    /// Every entry in table order, each as [`Image::entry`] gives it.
    pub fn entries(&self) -> impl Iterator<Item = Result<(u16, &'a [u8]), ImageError>> + '_ {
        (0..self.len()).map(|i| self.entry(i))
    }

    /// The blob of channel `id` (the first entry with that id).
    pub fn blob(&self, id: u16) -> Result<&'a [u8], ImageError> {
        for entry in self.entries() {
            let (entry_id, blob) = entry?;
            if entry_id == id {
                return Ok(blob);
            }
        }
        Err(ImageError::Missing)
    }
}

/// Checks a version-1 header and table; returns the entry count.
fn parse_v1(bytes: &[u8]) -> Result<usize, ImageError> {
    let count = usize::from(u16_at(bytes, 6).ok_or(ImageError::BadTable)?);
    let crc = u32_at(bytes, 8).ok_or(ImageError::BadTable)?;
    if count > MAX_ENTRIES {
        return Err(ImageError::BadTable);
    }
    let table = bytes
        .get(HEADER_LEN..HEADER_LEN + ENTRY_LEN * count)
        .ok_or(ImageError::BadTable)?;
    if crc32(table) != crc {
        return Err(ImageError::Checksum);
    }
    Ok(count)
}

/// Where the first blob starts for `count` entries.
fn first_blob_at(count: usize) -> usize {
    (HEADER_LEN + ENTRY_LEN * count).next_multiple_of(ALIGN)
}

/// Checks `entries` for writing (count, distinct ids, 32-bit offsets) and returns the image size.
pub fn image_len(entries: &[(u16, &[u8])]) -> Result<usize, ImageError> {
    if entries.len() > MAX_ENTRIES {
        return Err(ImageError::TooManyEntries);
    }
    for (i, (id, _)) in entries.iter().enumerate() {
        if entries.iter().take(i).any(|(earlier, _)| earlier == id) {
            return Err(ImageError::DuplicateId(*id));
        }
    }
    let mut end = first_blob_at(entries.len());
    for (_, blob) in entries {
        if u32::try_from(end).is_err() || u32::try_from(blob.len()).is_err() {
            return Err(ImageError::TooLarge);
        }
        end = end
            .checked_add(blob.len())
            .and_then(|e| e.checked_next_multiple_of(ALIGN))
            .ok_or(ImageError::TooLarge)?;
    }
    Ok(end)
}

/// Writes the image of `entries` (channel id, blob) into the start of `buf`, padding with zeros,
/// and returns its length; bytes of `buf` past it are left as they were. Refuses more than
/// [`MAX_ENTRIES`] blobs, a repeated id, and a buffer shorter than [`image_len`]; on an error
/// `buf` may be partly written. Never panics.
pub fn write_image(entries: &[(u16, &[u8])], buf: &mut [u8]) -> Result<usize, ImageError> {
    let needed = image_len(entries)?;
    let too_small = ImageError::BufferTooSmall { needed };
    let image = buf.get_mut(..needed).ok_or(too_small)?;
    image.fill(0);
    let table_end = HEADER_LEN + ENTRY_LEN * entries.len();
    let mut offset = first_blob_at(entries.len());
    for (i, (id, blob)) in entries.iter().enumerate() {
        let at = HEADER_LEN + ENTRY_LEN * i;
        let offset32 = u32::try_from(offset).map_err(|_| ImageError::TooLarge)?;
        let len32 = u32::try_from(blob.len()).map_err(|_| ImageError::TooLarge)?;
        put(image, at, &id.to_le_bytes())?;
        put(image, at + 2, &0u16.to_le_bytes())?;
        put(image, at + 4, &offset32.to_le_bytes())?;
        put(image, at + 8, &len32.to_le_bytes())?;
        put(image, offset, blob)?;
        offset = (offset + blob.len()).next_multiple_of(ALIGN);
    }
    let crc = crc32(image.get(HEADER_LEN..table_end).ok_or(too_small)?);
    put(image, 0, &MAGIC)?;
    put(image, 4, &VERSION.to_le_bytes())?;
    // `image_len` refused more than MAX_ENTRIES, so the count fits.
    put(image, 6, &(entries.len() as u16).to_le_bytes())?;
    put(image, 8, &crc.to_le_bytes())?;
    Ok(needed)
}

/// Copies `bytes` into `image` at `at`; the sizes were checked by [`image_len`], so an error here
/// would be a bug in this module, reported rather than panicking.
fn put(image: &mut [u8], at: usize, bytes: &[u8]) -> Result<(), ImageError> {
    let needed = image.len();
    at.checked_add(bytes.len())
        .and_then(|end| image.get_mut(at..end))
        .ok_or(ImageError::BufferTooSmall { needed })?
        .copy_from_slice(bytes);
    Ok(())
}
