//! The model image: the blobs of one unit behind a small table, defined once for every side.
//!
//! `tcomp image` writes it with [`write_image`], the firmware reads it from flash with
//! [`Image::parse`], and the tests use both; a second copy of the layout could drift from this one
//! without any test noticing, so there is none. Both halves are `no_std`, allocation-free and never
//! panic: the reader takes any bytes (erased flash, a truncated upload, garbage), the writer any
//! caller's buffer.
//!
//! # Format, version 1
//! Everything is little-endian:
//!
//! ```text
//! offset  size      field
//! 0       4         magic  b"TCMI"
//! 4       2         version (1)
//! 6       2         count: entries in the table (≤ MAX_ENTRIES)
//! 8       4         CRC-32 (ISO-HDLC, as zip/PNG) of the table bytes [12, 12 + 12·count)
//! 12      12·count  table: channel id u16, reserved u16 (0), offset u32, length u32
//! …                 zeros up to a multiple of 4, then the blobs in table order, each followed by
//!                   zeros up to a multiple of 4; offsets are from the start of the image
//! ```
//!
//! The header CRC protects the table only: every blob carries its own CRC-32 (see [`crate::blob`]),
//! so one corrupt blob disables one channel and not the image. Erased flash (`0xFF…`) or an empty
//! region (zeros) has no magic and reads as "no image".
//!
//! The writer lays the blobs out exactly as above (so the same blobs always give the same bytes);
//! the reader checks the header and the table and then only that each entry lies inside the bytes
//! it was given, so it also reads images whose blobs are placed otherwise.

use crate::blob::crc32;

/// The four bytes an image starts with.
pub const MAGIC: [u8; 4] = *b"TCMI";
/// The image format version written and read here.
pub const VERSION: u16 = 1;
/// Bytes before the table.
pub const HEADER_LEN: usize = 12;
/// Bytes per table entry.
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
    /// The table's CRC does not match.
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
    /// Writing: an offset or a length does not fit the table's 32-bit fields.
    TooLarge,
}

impl core::fmt::Display for ImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoImage => f.write_str("no model image (erased or empty region)"),
            Self::UnsupportedVersion(v) => write!(f, "unsupported image version {v}"),
            Self::BadTable => f.write_str("image table too long"),
            Self::Checksum => f.write_str("image table checksum mismatch"),
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
            Self::TooLarge => f.write_str("the image is too large for its 32-bit offsets"),
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

/// A validated image header and table over the bytes of an image (e.g. a whole flash region).
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

    /// `(channel id, blob bytes)` of entry `i`; the blob always lies inside the parsed bytes.
    pub fn entry(&self, i: usize) -> Result<(u16, &'a [u8]), ImageError> {
        if i >= self.count {
            return Err(ImageError::Missing);
        }
        let at = HEADER_LEN + ENTRY_LEN * i;
        let id = u16_at(self.bytes, at).ok_or(ImageError::BadTable)?;
        let offset = u32_at(self.bytes, at + 4).ok_or(ImageError::BadTable)?;
        let len = u32_at(self.bytes, at + 8).ok_or(ImageError::BadTable)?;
        let offset = usize::try_from(offset).map_err(|_| ImageError::OutOfBounds)?;
        let len = usize::try_from(len).map_err(|_| ImageError::OutOfBounds)?;
        let blob = offset
            .checked_add(len)
            .and_then(|end| self.bytes.get(offset..end))
            .ok_or(ImageError::OutOfBounds)?;
        Ok((id, blob))
    }

    /// Every entry in table order, each as [`Image::entry`] gives it.
    pub fn entries(&self) -> impl Iterator<Item = Result<(u16, &'a [u8]), ImageError>> + '_ {
        (0..self.count).map(|i| self.entry(i))
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
