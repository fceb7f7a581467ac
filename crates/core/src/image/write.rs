//! The version-2 writer: a board's rows, the blobs and their provenance into a caller's buffer.
//!
//! Two passes over the same description, no allocation: [`ImageSpec::image_len`] checks everything and
//! sizes the image, [`ImageSpec::write`] lays it out (rows, then the string pool in row order, then
//! the blobs, each 4-byte aligned), seals it with the whole-image CRC and reads it back with
//! [`Image::parse`], so nothing the reader would refuse leaves the writer.

use super::table::{ChannelRow, Provenance, Thermometer, board_hash, sensor_code};
use super::v2::{
    CHANNEL_LEN, CRC_AT, ENTRY_LEN, HEADER_LEN, MAX_CHANNEL_ROWS, MAX_THERMOMETER_ROWS, THERM_LEN,
    TOOL_LEN,
};
use super::{ALIGN, Image, ImageError, MAGIC, MAX_ENTRIES, VERSION_2, put};
use crate::crc::crc32;

/// One blob of the image, for the channel `channel` of the table.
#[derive(Clone, Copy, Debug)]
pub struct Entry<'a> {
    /// The channel id (a row of the table).
    pub channel: u16,
    /// The blob's bytes.
    pub blob: &'a [u8],
    /// Where it came from.
    pub provenance: Provenance<'a>,
}

/// Everything a version-2 image holds.
#[derive(Clone, Copy, Debug)]
pub struct ImageSpec<'a> {
    /// The unit it is made for.
    pub serial: u64,
    /// Creation time, seconds since 1970-01-01 UTC.
    pub created: u64,
    /// The writing tool's version (at most 16 bytes).
    pub tool: &'a str,
    /// The board's thermometers.
    pub thermometers: &'a [Thermometer<'a>],
    /// The board's channel table.
    pub channels: &'a [ChannelRow<'a>],
    /// The blobs.
    pub entries: &'a [Entry<'a>],
}

impl ImageSpec<'_> {
    /// The board-description hash the header will carry.
    pub fn board_hash(&self) -> u64 {
        board_hash(
            self.thermometers.iter().copied(),
            self.channels.iter().copied(),
        )
    }

    /// Every string of the pool, in pool order.
    fn strings(&self, mut f: impl FnMut(&str)) {
        self.thermometers.iter().for_each(|t| f(t.name));
        for c in self.channels {
            f(c.name);
            f(c.axis);
            f(c.unit);
            c.inputs().iter().for_each(|i| f(i.name));
        }
        for e in self.entries {
            f(e.provenance.data);
            f(e.provenance.method);
        }
    }

    /// The string pool's length.
    fn pool_len(&self) -> Result<usize, ImageError> {
        let mut len = 0usize;
        let mut long = false;
        self.strings(|s| {
            long |= s.len() > usize::from(u16::MAX);
            len = len.saturating_add(s.len());
        });
        if long || len > usize::from(u16::MAX) {
            return Err(ImageError::TooLarge);
        }
        Ok(len)
    }

    fn rows_len(&self) -> usize {
        HEADER_LEN
            + THERM_LEN * self.thermometers.len()
            + CHANNEL_LEN * self.channels.len()
            + ENTRY_LEN * self.entries.len()
    }

    /// Checks the description (counts, distinct channel ids, every entry on a channel of the table
    /// and at most one per channel, thermometer indices, string and image sizes) and returns the
    /// image's length in bytes.
    pub fn image_len(&self) -> Result<usize, ImageError> {
        if self.thermometers.len() > MAX_THERMOMETER_ROWS
            || self.channels.len() > MAX_CHANNEL_ROWS
            || self.entries.len() > MAX_ENTRIES
        {
            return Err(ImageError::TooManyEntries);
        }
        if self.tool.len() > TOOL_LEN || self.tool.contains('\0') {
            return Err(ImageError::TooLarge);
        }
        for (i, c) in self.channels.iter().enumerate() {
            if self.channels.iter().take(i).any(|e| e.id == c.id) {
                return Err(ImageError::DuplicateId(c.id));
            }
            let bad = c
                .inputs()
                .iter()
                .any(|i| usize::from(i.thermometer) >= self.thermometers.len());
            if bad || c.inputs().len() != usize::from(c.n_inputs) || !c.scale.is_finite() {
                return Err(ImageError::BadRow);
            }
        }
        for (i, e) in self.entries.iter().enumerate() {
            if !self.channels.iter().any(|c| c.id == e.channel) {
                return Err(ImageError::UnknownChannel(e.channel));
            }
            if self.entries.iter().take(i).any(|o| o.channel == e.channel) {
                return Err(ImageError::DuplicateId(e.channel));
            }
        }
        let mut end = (self.rows_len() + self.pool_len()?).next_multiple_of(ALIGN);
        for e in self.entries {
            end = end
                .checked_add(e.blob.len())
                .and_then(|e| e.checked_next_multiple_of(ALIGN))
                .ok_or(ImageError::TooLarge)?;
        }
        u32::try_from(end).map_err(|_| ImageError::TooLarge)?;
        Ok(end)
    }

    /// Writes the image into the start of `buf` and returns its length; bytes past it are left as
    /// they were. The same description always gives the same bytes. Never panics.
    pub fn write(&self, buf: &mut [u8]) -> Result<usize, ImageError> {
        let needed = self.image_len()?;
        let image = buf
            .get_mut(..needed)
            .ok_or(ImageError::BufferTooSmall { needed })?;
        image.fill(0);
        let pool_at = self.rows_len();
        let mut pool = Pool {
            at: pool_at,
            used: 0,
        };
        for (i, t) in self.thermometers.iter().enumerate() {
            let at = HEADER_LEN + THERM_LEN * i;
            pool.put_ref(image, at, t.name)?;
            put(image, at + 4, &[t.adc, t.input, t.kind.code()])?;
            for (k, c) in t.kind.constants().iter().enumerate() {
                put(image, at + 8 + 4 * k, &c.to_bits().to_le_bytes())?;
            }
        }
        let chan0 = HEADER_LEN + THERM_LEN * self.thermometers.len();
        for (i, c) in self.channels.iter().enumerate() {
            let at = chan0 + CHANNEL_LEN * i;
            let (kind, n) = c.source.code();
            put(image, at, &c.id.to_le_bytes())?;
            put(image, at + 2, &[sensor_code(c.sensor), kind, n, c.n_inputs])?;
            put(image, at + 8, &c.scale.to_bits().to_le_bytes())?;
            pool.put_ref(image, at + 12, c.name)?;
            pool.put_ref(image, at + 16, c.axis)?;
            pool.put_ref(image, at + 20, c.unit)?;
            for (k, input) in c.inputs().iter().enumerate() {
                pool.put_ref(image, at + 24 + 8 * k, input.name)?;
                put(image, at + 28 + 8 * k, &[input.thermometer])?;
            }
        }
        let entry0 = chan0 + CHANNEL_LEN * self.channels.len();
        let mut offset = (pool_at + self.pool_len()?).next_multiple_of(ALIGN);
        for (i, e) in self.entries.iter().enumerate() {
            let at = entry0 + ENTRY_LEN * i;
            let p = &e.provenance;
            put(image, at, &e.channel.to_le_bytes())?;
            put(image, at + 4, &to_u32(offset)?.to_le_bytes())?;
            put(image, at + 8, &to_u32(e.blob.len())?.to_le_bytes())?;
            put(image, at + 12, &crc32(e.blob).to_le_bytes())?;
            pool.put_ref(image, at + 16, p.data)?;
            put(image, at + 20, &p.data_hash.to_le_bytes())?;
            put(image, at + 28, &p.window[0].to_bits().to_le_bytes())?;
            put(image, at + 32, &p.window[1].to_bits().to_le_bytes())?;
            pool.put_ref(image, at + 36, p.method)?;
            put(image, offset, e.blob)?;
            offset = (offset + e.blob.len()).next_multiple_of(ALIGN);
        }
        put(image, 0, &MAGIC)?;
        put(image, 4, &VERSION_2.to_le_bytes())?;
        put(image, 6, &(HEADER_LEN as u16).to_le_bytes())?;
        put(image, 8, &to_u32(needed)?.to_le_bytes())?;
        put(image, 16, &self.serial.to_le_bytes())?;
        put(image, 24, &self.board_hash().to_le_bytes())?;
        put(image, 32, &self.created.to_le_bytes())?;
        put(image, 40, self.tool.as_bytes())?;
        // `len` refused counts past the maxima, all below 256.
        let counts = [
            self.thermometers.len() as u8,
            self.channels.len() as u8,
            self.entries.len() as u8,
        ];
        put(image, 56, &counts)?;
        put(image, 60, &(pool.used as u16).to_le_bytes())?;
        seal(image)?;
        Image::parse(image)?;
        Ok(needed)
    }
}

fn to_u32(n: usize) -> Result<u32, ImageError> {
    u32::try_from(n).map_err(|_| ImageError::TooLarge)
}

/// The string pool as it is filled: each string is appended where the last one ended.
struct Pool {
    at: usize,
    used: usize,
}

impl Pool {
    /// Appends `s` to the pool and writes its reference (offset, length) at `at`.
    fn put_ref(&mut self, image: &mut [u8], at: usize, s: &str) -> Result<(), ImageError> {
        let off = u16::try_from(self.used).map_err(|_| ImageError::TooLarge)?;
        let len = u16::try_from(s.len()).map_err(|_| ImageError::TooLarge)?;
        put(image, at, &off.to_le_bytes())?;
        put(image, at + 2, &len.to_le_bytes())?;
        put(image, self.at + self.used, s.as_bytes())?;
        self.used += s.len();
        Ok(())
    }
}

/// Recomputes the whole-image CRC of a version-2 image (the bytes after the CRC field up to the
/// image length in its header) and stores it. The writer's last step; tests use it to get a
/// mutation past the checksum.
pub fn seal(image: &mut [u8]) -> Result<(), ImageError> {
    let len = super::u32_at(image, 8).ok_or(ImageError::BadTable)?;
    let len = usize::try_from(len).map_err(|_| ImageError::BadTable)?;
    let body = image.get(CRC_AT + 4..len).ok_or(ImageError::BadTable)?;
    let crc = crc32(body);
    put(image, CRC_AT, &crc.to_le_bytes())
}
