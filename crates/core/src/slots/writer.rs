//! Writing one slot in the only order that survives a power cut: erase, header, payload in order,
//! read back and check, and the commit word last.
//!
//! The update receiver feeds the payload chunk by chunk as frames arrive, so the writer holds no
//! copy of the image (the firmware's RAM budget has room for one protocol frame, not an image). It
//! refuses anything that would break the order: a chunk that is not the next one, a misaligned
//! chunk, a payload larger than the slot, a commit before the last byte or over a payload whose
//! read-back CRC or validation fails. Nothing here touches the other slot.

use super::{COMMIT, COMMIT_AT, Header, Layout, PAYLOAD_AT, SlotId, flash_crc};
use embedded_storage::nor_flash::NorFlash;

/// The program granularity the writer works in (the STM32F4's x32 word); every flash it writes
/// must program in units dividing it.
pub const WORD: usize = 4;

/// Why a slot write stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum WriteError<E> {
    /// The flash refused an operation (or lost power).
    Flash(E),
    /// The payload does not fit the slot.
    TooLarge,
    /// A chunk other than the last is not a whole number of words, or the flash programs in units
    /// that do not divide a word.
    Misaligned,
    /// A chunk that does not start where the payload written so far ends.
    OutOfOrder {
        /// Where the next chunk must start.
        expected: u32,
    },
    /// A chunk past the announced length.
    PastEnd,
    /// Commit before the whole payload was written.
    Incomplete,
    /// The payload read back does not have the announced CRC.
    Crc,
    /// The payload does not validate (the caller's check, e.g. the image does not parse).
    Invalid,
}

/// A slot being written: created by [`SlotWriter::begin`] (which erases it and writes the header),
/// fed with [`SlotWriter::write`], ended by [`SlotWriter::commit`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotWriter {
    layout: Layout,
    slot: SlotId,
    header: Header,
    written: u32,
}

impl SlotWriter {
    /// Erases `slot` and writes `header` (not the commit word).
    pub fn begin<F: NorFlash>(
        flash: &mut F,
        layout: Layout,
        slot: SlotId,
        header: Header,
    ) -> Result<Self, WriteError<F::Error>> {
        if header.length > layout.capacity() {
            return Err(WriteError::TooLarge);
        }
        if F::WRITE_SIZE == 0 || !WORD.is_multiple_of(F::WRITE_SIZE) {
            return Err(WriteError::Misaligned);
        }
        let base = layout.base(slot);
        flash
            .erase(base, base + layout.size)
            .map_err(WriteError::Flash)?;
        flash
            .write(base, &header.encode())
            .map_err(WriteError::Flash)?;
        Ok(Self {
            layout,
            slot,
            header,
            written: 0,
        })
    }

    /// The slot being written.
    pub const fn slot(&self) -> SlotId {
        self.slot
    }

    /// Its header.
    pub const fn header(&self) -> Header {
        self.header
    }

    /// Payload bytes written so far.
    pub const fn written(&self) -> u32 {
        self.written
    }

    /// True once every payload byte is written.
    pub const fn is_complete(&self) -> bool {
        self.written == self.header.length
    }

    /// Programs `bytes` at payload offset `offset`, which must be [`written`](Self::written). Every
    /// chunk but the last is a whole number of words; the last one's tail word is padded with 0xFF.
    pub fn write<F: NorFlash>(
        &mut self,
        flash: &mut F,
        offset: u32,
        bytes: &[u8],
    ) -> Result<(), WriteError<F::Error>> {
        if offset != self.written {
            return Err(WriteError::OutOfOrder {
                expected: self.written,
            });
        }
        let len = u32::try_from(bytes.len()).map_err(|_| WriteError::PastEnd)?;
        let end = offset.checked_add(len).ok_or(WriteError::PastEnd)?;
        if end > self.header.length {
            return Err(WriteError::PastEnd);
        }
        let whole = bytes.len() - bytes.len() % WORD;
        if whole != bytes.len() && end != self.header.length {
            return Err(WriteError::Misaligned);
        }
        let at = self.layout.base(self.slot) + PAYLOAD_AT + offset;
        let (body, tail) = bytes.split_at(whole);
        if !body.is_empty() {
            flash.write(at, body).map_err(WriteError::Flash)?;
        }
        if !tail.is_empty() {
            let mut word = [0xFFu8; WORD];
            for (dst, src) in word.iter_mut().zip(tail) {
                *dst = *src;
            }
            flash
                .write(at + whole as u32, &word)
                .map_err(WriteError::Flash)?;
        }
        self.written = end;
        Ok(())
    }

    /// Reads the payload back, checks its CRC and `validate(flash, payload offset, len)`, and only
    /// then programs the commit word.
    pub fn commit<F: NorFlash>(
        &self,
        flash: &mut F,
        validate: impl FnOnce(&mut F, u32, u32) -> bool,
    ) -> Result<(), WriteError<F::Error>> {
        if !self.is_complete() {
            return Err(WriteError::Incomplete);
        }
        let base = self.layout.base(self.slot);
        let crc =
            flash_crc(flash, base + PAYLOAD_AT, self.header.length).map_err(WriteError::Flash)?;
        if crc != self.header.payload_crc {
            return Err(WriteError::Crc);
        }
        if !validate(flash, base + PAYLOAD_AT, self.header.length) {
            return Err(WriteError::Invalid);
        }
        flash
            .write(base + COMMIT_AT, &COMMIT.to_le_bytes())
            .map_err(WriteError::Flash)
    }
}
