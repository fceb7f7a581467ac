//! The model-blob image: one binary holding a blob per channel, flashed into the `MODELS` region.
//!
//! The image is written on the host by `tcomp image --model CH=FILE.tcm …` and placed at the start
//! of the `MODELS` flash region (`0x003F_0000`, 64 KiB, see `memory.x`) by a flashing tool, without
//! rebuilding the firmware. Everything is little-endian:
//!
//! ```text
//! offset  size      field
//! 0       4         magic  b"TCMI"
//! 4       2         version (1)
//! 6       2         count: entries in the table (≤ MAX_ENTRIES)
//! 8       4         CRC-32 (ISO-HDLC, as zip/PNG) of the table bytes [12, 12 + 12·count)
//! 12      12·count  table: channel id u16, reserved u16 (0), offset u32, length u32
//! …                 blobs (each a tcomp-core model blob with its own CRC), 4-byte aligned;
//!                   offsets are from the start of the image
//! ```
//!
//! The header CRC protects the table only: every blob carries its own CRC-32, so one corrupt blob
//! disables one channel (which then runs with `NO_MODEL`, raw passed through) and not the image.
//! Erased flash (`0xFF…`) or an empty region (zeros) has no magic and reads as "no image".

/// The four bytes an image starts with.
pub const MAGIC: [u8; 4] = *b"TCMI";
/// The image format version this build reads.
pub const VERSION: u16 = 1;
/// Bytes before the table.
pub const HEADER_LEN: usize = 12;
/// Bytes per table entry.
pub const ENTRY_LEN: usize = 12;
/// Most entries an image may list.
pub const MAX_ENTRIES: usize = 32;

/// Why an image or one of its entries is unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
#[non_exhaustive]
pub enum ImageError {
    /// No magic: the region is erased, empty, or holds something else.
    NoImage,
    /// A version this build does not read.
    UnsupportedVersion(u16),
    /// More entries than [`MAX_ENTRIES`], or a table past the end of the region.
    BadTable,
    /// The table's CRC does not match.
    Checksum,
    /// The image has no entry for the channel.
    Missing,
    /// The entry's blob lies (partly) outside the image region.
    OutOfBounds,
}

impl core::fmt::Display for ImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NoImage => "no model image (erased or empty region)",
            Self::UnsupportedVersion(_) => "unsupported image version",
            Self::BadTable => "image table too long",
            Self::Checksum => "image table checksum mismatch",
            Self::Missing => "no blob for this channel in the image",
            Self::OutOfBounds => "blob outside the image region",
        })
    }
}

/// CRC-32/ISO-HDLC of the table: the core's, the same as every blob's.
pub use tcomp_core::blob::crc32;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    let s = b.get(at..at + 2)?;
    Some(u16::from_le_bytes([s[0], s[1]]))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at + 4)?;
    Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

/// A validated image header and table over the bytes of the `MODELS` region.
#[derive(Clone, Copy, Debug)]
pub struct Image<'a> {
    bytes: &'a [u8],
    count: usize,
}

impl<'a> Image<'a> {
    /// Checks magic, version, table size and table CRC. Never panics.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ImageError> {
        if bytes.get(..4) != Some(&MAGIC[..]) {
            return Err(ImageError::NoImage);
        }
        let version = u16_at(bytes, 4).ok_or(ImageError::NoImage)?;
        if version != VERSION {
            return Err(ImageError::UnsupportedVersion(version));
        }
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
        Ok(Self { bytes, count })
    }

    /// Number of table entries.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when the table is empty.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// `(channel id, blob bytes)` of entry `i`.
    pub fn entry(&self, i: usize) -> Result<(u16, &'a [u8]), ImageError> {
        if i >= self.count {
            return Err(ImageError::Missing);
        }
        let at = HEADER_LEN + ENTRY_LEN * i;
        let id = u16_at(self.bytes, at).ok_or(ImageError::BadTable)?;
        let offset = u32_at(self.bytes, at + 4).ok_or(ImageError::BadTable)? as usize;
        let len = u32_at(self.bytes, at + 8).ok_or(ImageError::BadTable)? as usize;
        let blob = offset
            .checked_add(len)
            .and_then(|end| self.bytes.get(offset..end))
            .ok_or(ImageError::OutOfBounds)?;
        Ok((id, blob))
    }

    /// The blob of channel `id` (the first entry with that id).
    pub fn blob(&self, id: u16) -> Result<&'a [u8], ImageError> {
        for i in 0..self.count {
            let (entry_id, blob) = self.entry(i)?;
            if entry_id == id {
                return Ok(blob);
            }
        }
        Err(ImageError::Missing)
    }
}
