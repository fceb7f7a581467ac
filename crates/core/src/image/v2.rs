//! The version-2 layout: offsets of the header fields and rows, and the reader's checks.
//!
//! Kept apart from [`super`]'s entry points so the byte offsets are written down once, next to
//! the one function that validates them ([`parse`]) and the row readers that rely on it.

use super::table::{
    ChannelRow, Input, MAX_ROW_INPUTS, Provenance, Source, ThermKind, Thermometer, board_hash,
    sensor_from_code,
};
use super::{ImageError, MAX_ENTRIES, u16_at, u32_at};
use crate::crc::crc32;

/// Bytes of the version-2 header.
pub const HEADER_LEN: usize = 64;
/// Bytes per thermometer row.
pub const THERM_LEN: usize = 20;
/// Bytes per channel row.
pub const CHANNEL_LEN: usize = 24 + 8 * MAX_ROW_INPUTS;
/// Bytes per entry (blob) row.
pub const ENTRY_LEN: usize = 40;
/// Most thermometers a board description may list.
pub const MAX_THERMOMETER_ROWS: usize = 32;
/// Most channels a board description may list.
pub const MAX_CHANNEL_ROWS: usize = 16;
/// Bytes of the tool-version field.
pub const TOOL_LEN: usize = 16;
/// Where the whole-image CRC is; it covers every byte after it up to the image length.
pub const CRC_AT: usize = 12;

/// The version-2 header's identity fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header<'a> {
    /// The unit the image was made for.
    pub serial: u64,
    /// FNV-1a 64 of the board description ([`board_hash`]).
    pub board_hash: u64,
    /// Creation time, seconds since 1970-01-01 UTC.
    pub created: u64,
    /// The version of the tool that wrote it (`0.1.0+abc1234`).
    pub tool: &'a str,
    /// The whole-image CRC-32.
    pub crc: u32,
}

/// Where the sections of a parsed version-2 image start, and their counts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Layout {
    pub n_therm: usize,
    pub n_chan: usize,
    pub n_entries: usize,
    pub pool_at: usize,
    pub pool_len: usize,
    pub len: usize,
}

impl Layout {
    pub fn therm_at(&self, i: usize) -> usize {
        HEADER_LEN + THERM_LEN * i
    }
    pub fn chan_at(&self, i: usize) -> usize {
        HEADER_LEN + THERM_LEN * self.n_therm + CHANNEL_LEN * i
    }
    pub fn entry_at(&self, i: usize) -> usize {
        HEADER_LEN + THERM_LEN * self.n_therm + CHANNEL_LEN * self.n_chan + ENTRY_LEN * i
    }
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    let s: [u8; 8] = b.get(at..at.checked_add(8)?)?.try_into().ok()?;
    Some(u64::from_le_bytes(s))
}

fn f32_at(b: &[u8], at: usize) -> Option<f32> {
    u32_at(b, at).map(f32::from_bits)
}

/// A string of the pool by its reference at `at` (u16 offset, u16 length).
fn str_at<'a>(b: &'a [u8], l: &Layout, at: usize) -> Option<&'a str> {
    let off = usize::from(u16_at(b, at)?);
    let len = usize::from(u16_at(b, at + 2)?);
    let end = off.checked_add(len)?;
    if end > l.pool_len {
        return None;
    }
    let s = b.get(l.pool_at + off..l.pool_at + end)?;
    core::str::from_utf8(s).ok()
}

/// Checks the header, the whole-image CRC and every row of a version-2 image.
pub(super) fn parse(bytes: &[u8]) -> Result<Layout, ImageError> {
    let header_len = u16_at(bytes, 6).ok_or(ImageError::BadTable)?;
    if usize::from(header_len) != HEADER_LEN {
        return Err(ImageError::BadTable);
    }
    let len = u32_at(bytes, 8).ok_or(ImageError::BadTable)?;
    let len = usize::try_from(len).map_err(|_| ImageError::BadTable)?;
    let image = bytes.get(..len).ok_or(ImageError::BadTable)?;
    let crc = u32_at(image, CRC_AT).ok_or(ImageError::BadTable)?;
    if crc32(image.get(CRC_AT + 4..).ok_or(ImageError::BadTable)?) != crc {
        return Err(ImageError::Checksum);
    }
    let n = |at| {
        image
            .get(at)
            .copied()
            .map(usize::from)
            .ok_or(ImageError::BadTable)
    };
    let (n_therm, n_chan, n_entries) = (n(56)?, n(57)?, n(58)?);
    if n_therm > MAX_THERMOMETER_ROWS || n_chan > MAX_CHANNEL_ROWS || n_entries > MAX_ENTRIES {
        return Err(ImageError::BadTable);
    }
    let pool_len = usize::from(u16_at(image, 60).ok_or(ImageError::BadTable)?);
    let pool_at = HEADER_LEN + THERM_LEN * n_therm + CHANNEL_LEN * n_chan + ENTRY_LEN * n_entries;
    if pool_at + pool_len > len {
        return Err(ImageError::BadTable);
    }
    let layout = Layout {
        n_therm,
        n_chan,
        n_entries,
        pool_at,
        pool_len,
        len,
    };
    tool(image).ok_or(ImageError::BadRow)?;
    for i in 0..n_therm {
        thermometer(image, &layout, i).ok_or(ImageError::BadRow)?;
    }
    for i in 0..n_chan {
        let row = channel(image, &layout, i).ok_or(ImageError::BadRow)?;
        if (0..i).any(|j| channel(image, &layout, j).is_some_and(|r| r.id == row.id)) {
            return Err(ImageError::DuplicateId(row.id));
        }
    }
    let first_blob = (pool_at + pool_len).next_multiple_of(super::ALIGN);
    for i in 0..n_entries {
        let (id, off, blen) = entry_span(image, &layout, i).ok_or(ImageError::BadTable)?;
        provenance(image, &layout, i).ok_or(ImageError::BadRow)?;
        if !(0..n_chan).any(|j| channel(image, &layout, j).is_some_and(|r| r.id == id)) {
            return Err(ImageError::UnknownChannel(id));
        }
        if (0..i).any(|j| entry_span(image, &layout, j).is_some_and(|(e, _, _)| e == id)) {
            return Err(ImageError::DuplicateId(id));
        }
        let end = off.checked_add(blen).ok_or(ImageError::OutOfBounds)?;
        if off < first_blob || end > len {
            return Err(ImageError::OutOfBounds);
        }
    }
    let hash = board_hash(
        (0..n_therm).filter_map(|i| thermometer(image, &layout, i)),
        (0..n_chan).filter_map(|i| channel(image, &layout, i)),
    );
    if u64_at(image, 24) != Some(hash) {
        return Err(ImageError::BoardHash);
    }
    Ok(layout)
}

/// The tool-version field without its zero padding.
pub(super) fn tool(b: &[u8]) -> Option<&str> {
    let field = b.get(40..40 + TOOL_LEN)?;
    let end = field.iter().position(|&c| c == 0).unwrap_or(TOOL_LEN);
    core::str::from_utf8(field.get(..end)?).ok()
}

pub(super) fn header(b: &[u8]) -> Option<Header<'_>> {
    Some(Header {
        serial: u64_at(b, 16)?,
        board_hash: u64_at(b, 24)?,
        created: u64_at(b, 32)?,
        tool: tool(b)?,
        crc: u32_at(b, CRC_AT)?,
    })
}

pub(super) fn thermometer<'a>(b: &'a [u8], l: &Layout, i: usize) -> Option<Thermometer<'a>> {
    if i >= l.n_therm {
        return None;
    }
    let at = l.therm_at(i);
    let c = [f32_at(b, at + 8)?, f32_at(b, at + 12)?, f32_at(b, at + 16)?];
    Some(Thermometer {
        name: str_at(b, l, at)?,
        adc: *b.get(at + 4)?,
        input: *b.get(at + 5)?,
        kind: ThermKind::from_code(*b.get(at + 6)?, c)?,
    })
}

pub(super) fn channel<'a>(b: &'a [u8], l: &Layout, i: usize) -> Option<ChannelRow<'a>> {
    if i >= l.n_chan {
        return None;
    }
    let at = l.chan_at(i);
    let n_inputs = *b.get(at + 5)?;
    if usize::from(n_inputs) > MAX_ROW_INPUTS {
        return None;
    }
    let mut inputs = [Input::default(); MAX_ROW_INPUTS];
    for (k, input) in inputs.iter_mut().enumerate().take(usize::from(n_inputs)) {
        let at = at + 24 + 8 * k;
        let thermometer = *b.get(at + 4)?;
        if usize::from(thermometer) >= l.n_therm {
            return None;
        }
        *input = Input {
            name: str_at(b, l, at)?,
            thermometer,
        };
    }
    let scale = f32_at(b, at + 8)?;
    if !scale.is_finite() {
        return None;
    }
    Some(ChannelRow {
        id: u16_at(b, at)?,
        sensor: sensor_from_code(*b.get(at + 2)?)?,
        source: Source::from_code(*b.get(at + 3)?, *b.get(at + 4)?)?,
        scale,
        name: str_at(b, l, at + 12)?,
        axis: str_at(b, l, at + 16)?,
        unit: str_at(b, l, at + 20)?,
        inputs,
        n_inputs,
    })
}

/// `(channel id, offset, length)` of entry `i`.
pub(super) fn entry_span(b: &[u8], l: &Layout, i: usize) -> Option<(u16, usize, usize)> {
    if i >= l.n_entries {
        return None;
    }
    let at = l.entry_at(i);
    Some((
        u16_at(b, at)?,
        usize::try_from(u32_at(b, at + 4)?).ok()?,
        usize::try_from(u32_at(b, at + 8)?).ok()?,
    ))
}

/// The blob CRC the entry records.
pub(super) fn entry_crc(b: &[u8], l: &Layout, i: usize) -> Option<u32> {
    (i < l.n_entries).then_some(())?;
    u32_at(b, l.entry_at(i) + 12)
}

pub(super) fn provenance<'a>(b: &'a [u8], l: &Layout, i: usize) -> Option<Provenance<'a>> {
    if i >= l.n_entries {
        return None;
    }
    let at = l.entry_at(i);
    Some(Provenance {
        data: str_at(b, l, at + 16)?,
        data_hash: u64_at(b, at + 20)?,
        window: [f32_at(b, at + 28)?, f32_at(b, at + 32)?],
        method: str_at(b, l, at + 36)?,
    })
}
