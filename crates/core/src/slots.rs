//! Two model slots (A/B) in NOR flash with a commit marker written last, and the boot's choice.
//!
//! A power cut while the one model region is rewritten leaves a torn or silently mixed image: the
//! old one half erased, the new one half written. Two slots fix that: an update only ever erases and
//! writes the slot the unit is *not* running from, and a slot counts only once its commit word — the
//! last thing written, after the payload has been read back and its CRC checked — holds [`COMMIT`].
//! A cut at any earlier point leaves an uncommitted slot that the boot skips, so the next boot runs
//! the old image, complete; a cut after the commit word leaves the new one, complete.
//!
//! # Slot layout (little-endian, offsets from the slot's start)
//!
//! ```text
//! offset  size  field
//! 0       4     magic b"TCSL"
//! 4       4     generation u32: 1 for the first image, +1 per update (the newest wins)
//! 8       4     payload length in bytes
//! 12      4     CRC-32 of the payload (the core's `crc32`)
//! 16      4     CRC-32 of bytes 0..16 (the header above)
//! 20      4     commit word: erased (0xFFFF_FFFF) until the payload is verified, then COMMIT
//! 24      4     trial word: erased until the first boot that runs the slot, then TRIAL
//! 28      4     confirm word: erased until that boot has run correctly, then CONFIRM
//! 32      len   payload: the model image, opaque here, checked by the caller's validator
//! ```
//!
//! # Trial boot, confirm, rollback (what [`boot`] does, before the watchdog starts)
//! A newly committed slot is not trusted yet: the first boot that runs it programs its trial word
//! and keeps the other slot — the last confirmed image — untouched. Once that boot has run
//! correctly the firmware programs the confirm word ([`confirm`]). A later boot that finds the
//! trial word set but no confirm word knows the trial ended without proving the image (a reset,
//! a power cut, a crash, the firmware's own rollback request): [`select`] skips such a slot, so the
//! unit runs the old image again, and the boot erases the failed one. The boot erases the slot an
//! update will write only once the running slot is confirmed (or there is none), so the old image
//! stays recoverable until the new one is confirmed, and nothing is ever erased while the loop
//! runs. Every step is one word program or one sector erase at boot: `tests/power_cut.rs` cuts each
//! of them as it cuts the update's.
//!
//! # Why the commit word cannot lie
//! NOR flash programs by clearing bits. An interrupted program of the commit word leaves a value
//! between 0xFFFF_FFFF and [`COMMIT`] with only some of COMMIT's zero bits cleared: never COMMIT
//! itself, which needs all of them. An interrupted erase of the slot leaves arbitrary bits, but the
//! slot erased is never the one running, and a half-erased slot with a surviving commit word fails
//! its payload CRC or its header CRC; the boot then takes the other slot.
//!
//! # Boot
//! [`select`] reads both headers and takes the committed slot with the highest generation whose
//! header CRC, payload CRC and validator (the caller's: "does this image parse") pass; failing that,
//! the other slot; failing both, none (every channel then runs `NO_MODEL`). The writer is
//! [`writer::SlotWriter`]; a NOR flash model with power-cut injection for host tests is [`sim`].

pub mod sim;
pub mod writer;

use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};

pub use writer::SlotWriter;

/// The four bytes a slot starts with.
pub const MAGIC: [u8; 4] = *b"TCSL";
/// The commit word's committed value (mixed bits: a torn program of it cannot reach it by chance).
pub const COMMIT: u32 = 0x3C5A_A5C3;
/// The erased commit word.
pub const ERASED: u32 = 0xFFFF_FFFF;
/// Offset of the commit word in the slot.
pub const COMMIT_AT: u32 = 20;
/// Offset of the trial word.
pub const TRIAL_AT: u32 = 24;
/// The trial word's programmed value. Any bit of it cleared counts: a torn program of it still
/// says a boot began to run the slot.
pub const TRIAL: u32 = 0x5AA5_3CC3;
/// Offset of the confirm word.
pub const CONFIRM_AT: u32 = 28;
/// The confirm word's value: only this exact value confirms (a torn program does not).
pub const CONFIRM: u32 = 0xC33C_A55A;
/// Offset of the payload in the slot.
pub const PAYLOAD_AT: u32 = 32;
/// Bytes of the header covered by its CRC.
const HEADER_CRC_SPAN: usize = 16;
/// Read-back chunk for CRCs over flash (stack use, not speed, decides it).
const CHUNK: usize = 64;

/// One of the two slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlotId {
    /// The first slot.
    A,
    /// The second slot.
    B,
}

impl SlotId {
    /// The other slot.
    pub const fn other(self) -> Self {
        match self {
            Self::A => Self::B,
            Self::B => Self::A,
        }
    }

    /// 0 for A, 1 for B (the wire's and the report's number).
    pub const fn index(self) -> u8 {
        match self {
            Self::A => 0,
            Self::B => 1,
        }
    }
}

/// Where the two slots lie, as offsets into the flash the [`ReadNorFlash`] addresses, and their
/// size (each a whole number of erase sectors).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Offset of slot A.
    pub a: u32,
    /// Offset of slot B.
    pub b: u32,
    /// Bytes per slot, header included.
    pub size: u32,
}

impl Layout {
    /// Offset of `slot`.
    pub const fn base(&self, slot: SlotId) -> u32 {
        match slot {
            SlotId::A => self.a,
            SlotId::B => self.b,
        }
    }

    /// The largest payload a slot holds.
    pub const fn capacity(&self) -> u32 {
        self.size.saturating_sub(PAYLOAD_AT)
    }
}

/// A slot's header as read from flash.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Header {
    /// The update counter: the newest committed slot wins.
    pub generation: u32,
    /// Payload bytes.
    pub length: u32,
    /// CRC-32 of the payload.
    pub payload_crc: u32,
}

impl Header {
    /// The first 16 bytes plus their CRC: the 20 bytes written before the payload.
    pub fn encode(&self) -> [u8; 20] {
        let mut out = [0u8; 20];
        let words = [
            u32::from_le_bytes(MAGIC),
            self.generation,
            self.length,
            self.payload_crc,
        ];
        for (dst, w) in out.chunks_exact_mut(4).zip(words) {
            dst.copy_from_slice(&w.to_le_bytes());
        }
        let crc = crate::crc::crc32(out.get(..HEADER_CRC_SPAN).unwrap_or(&[]));
        if let Some(dst) = out.get_mut(HEADER_CRC_SPAN..) {
            dst.copy_from_slice(&crc.to_le_bytes());
        }
        out
    }

    /// Reads the header bytes back: `None` without the magic or with a bad header CRC.
    pub fn decode(bytes: &[u8; 24]) -> Option<(Self, u32)> {
        let word = |i: usize| -> Option<u32> {
            let s: [u8; 4] = bytes.get(4 * i..4 * i + 4)?.try_into().ok()?;
            Some(u32::from_le_bytes(s))
        };
        if word(0)? != u32::from_le_bytes(MAGIC)
            || crate::crc::crc32(bytes.get(..HEADER_CRC_SPAN)?) != word(4)?
        {
            return None;
        }
        let header = Self {
            generation: word(1)?,
            length: word(2)?,
            payload_crc: word(3)?,
        };
        Some((header, word(5)?))
    }
}

/// The slots' incremental checksum: the core's one CRC-32 ([`crate::crc`]).
pub use crate::crc::Crc32;

/// CRC-32 of `len` bytes of flash from `offset`, read [`CHUNK`] bytes at a time.
pub fn flash_crc<F: ReadNorFlash>(flash: &mut F, offset: u32, len: u32) -> Result<u32, F::Error> {
    let mut crc = Crc32::new();
    let mut buf = [0u8; CHUNK];
    let mut done = 0u32;
    while done < len {
        let n = (len - done).min(CHUNK as u32);
        let chunk = buf.get_mut(..n as usize).unwrap_or(&mut []);
        flash.read(offset + done, chunk)?;
        crc.update(chunk);
        done += n;
    }
    Ok(crc.finish())
}

/// A slot that passed every check at boot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Active {
    /// Which slot.
    pub slot: SlotId,
    /// Its header.
    pub header: Header,
}

/// How far a committed slot has proven itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Trial {
    /// Committed, never booted (trial and confirm words erased).
    Fresh,
    /// A boot began to run it (trial word programmed, even partly) and it is not confirmed: that
    /// boot is running it now, or it ended without proving it.
    Running,
    /// Confirmed by a boot that ran it correctly.
    Confirmed,
}

/// Reads a slot's trial state from its trial and confirm words.
pub fn trial<F: ReadNorFlash>(
    flash: &mut F,
    layout: &Layout,
    slot: SlotId,
) -> Result<Trial, F::Error> {
    let mut words = [0u8; 8];
    flash.read(layout.base(slot) + TRIAL_AT, &mut words)?;
    let word = |i: usize| {
        let mut w = [0u8; 4];
        if let Some(b) = words.get(4 * i..4 * i + 4) {
            w.copy_from_slice(b);
        }
        u32::from_le_bytes(w)
    };
    Ok(match (word(0), word(1)) {
        (_, CONFIRM) => Trial::Confirmed,
        (ERASED, ERASED) => Trial::Fresh,
        _ => Trial::Running,
    })
}

impl Active {
    /// Offset of its payload in the flash.
    pub const fn payload(&self, layout: &Layout) -> u32 {
        layout.base(self.slot) + PAYLOAD_AT
    }
}

/// What one slot holds, as the boot sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlotState {
    /// No magic or a bad header CRC (erased, half erased, or never written).
    Empty,
    /// A good header without the commit word: an update that did not finish.
    Uncommitted(Header),
    /// Committed, but the payload CRC or the validator fails (or it does not fit the slot).
    Corrupt(Header),
    /// Committed, run by a boot that never confirmed it: rolled back from.
    FailedTrial(Header),
    /// Committed and valid.
    Valid(Header),
}

/// Checks one slot: header, commit word, payload CRC, then `validate(flash, payload offset, len)`.
pub fn inspect<F: ReadNorFlash>(
    flash: &mut F,
    layout: &Layout,
    slot: SlotId,
    validate: &mut impl FnMut(&mut F, u32, u32) -> bool,
) -> Result<SlotState, F::Error> {
    let base = layout.base(slot);
    let mut raw = [0u8; 24];
    flash.read(base, &mut raw)?;
    let Some((header, commit)) = Header::decode(&raw) else {
        return Ok(SlotState::Empty);
    };
    if commit != COMMIT {
        return Ok(SlotState::Uncommitted(header));
    }
    if trial(flash, layout, slot)? == Trial::Running {
        // A boot began to run it and never confirmed it: its trial failed (see [`boot`]).
        return Ok(SlotState::FailedTrial(header));
    }
    if header.length > layout.capacity()
        || flash_crc(flash, base + PAYLOAD_AT, header.length)? != header.payload_crc
        || !validate(flash, base + PAYLOAD_AT, header.length)
    {
        return Ok(SlotState::Corrupt(header));
    }
    Ok(SlotState::Valid(header))
}

/// The slot to boot: the valid slot with the highest generation, or `None` (no models).
pub fn select<F: ReadNorFlash>(
    flash: &mut F,
    layout: &Layout,
    mut validate: impl FnMut(&mut F, u32, u32) -> bool,
) -> Result<Option<Active>, F::Error> {
    let a = inspect(flash, layout, SlotId::A, &mut validate)?;
    let b = inspect(flash, layout, SlotId::B, &mut validate)?;
    Ok(match (a, b) {
        (SlotState::Valid(ha), SlotState::Valid(hb)) if hb.generation > ha.generation => {
            Some(Active {
                slot: SlotId::B,
                header: hb,
            })
        }
        (SlotState::Valid(header), _) => Some(Active {
            slot: SlotId::A,
            header,
        }),
        (_, SlotState::Valid(header)) => Some(Active {
            slot: SlotId::B,
            header,
        }),
        _ => None,
    })
}

/// What the boot found and did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BootSlots {
    /// The slot to run, if any.
    pub active: Option<Active>,
    /// It runs on trial: a boot that ends before [`confirm`] rolls it back.
    pub trial: bool,
    /// A slot whose trial failed was found (and is erased now unless the run needs it).
    pub rolled_back: bool,
    /// The slot an update writes was erased.
    pub erased: bool,
}

/// The boot, before the watchdog starts: selects the slot to run ([`select`]); a freshly committed
/// one gets its trial word (this boot is its trial); then the slot an update will write is erased
/// if it is not blank — but only when the running slot is confirmed, or there is none, so the old
/// image survives a trial. `external` names a slot holding an image the caller runs without a
/// header (a probe's bare image at slot A) when no committed slot is selected: it is kept too.
pub fn boot<F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    external: Option<SlotId>,
    mut validate: impl FnMut(&mut F, u32, u32) -> bool,
) -> Result<BootSlots, F::Error> {
    let a = inspect(flash, layout, SlotId::A, &mut validate)?;
    let b = inspect(flash, layout, SlotId::B, &mut validate)?;
    let rolled_back =
        matches!(a, SlotState::FailedTrial(_)) || matches!(b, SlotState::FailedTrial(_));
    let active = select(flash, layout, &mut validate)?;
    let mut trial_run = false;
    if let Some(act) = active {
        match trial(flash, layout, act.slot)? {
            Trial::Fresh => {
                flash.write(layout.base(act.slot) + TRIAL_AT, &TRIAL.to_le_bytes())?;
                trial_run = true;
            }
            Trial::Running => trial_run = true,
            Trial::Confirmed => {}
        }
    }
    let external = if active.is_none() { external } else { None };
    let keep = active.map(|a| a.slot).or(external);
    let target = keep.map_or(SlotId::A, SlotId::other);
    let mut erased = false;
    if !trial_run {
        let from = layout.base(target);
        if !blank(flash, from, layout.size)? {
            flash.erase(from, from + layout.size)?;
            erased = true;
        }
    }
    Ok(BootSlots {
        active,
        trial: trial_run,
        rolled_back,
        erased,
    })
}

/// Confirms the running slot: its trial boot has run correctly. One word program; call it from
/// the running firmware (it never erases).
pub fn confirm<F: NorFlash>(flash: &mut F, layout: &Layout, slot: SlotId) -> Result<(), F::Error> {
    flash.write(layout.base(slot) + CONFIRM_AT, &CONFIRM.to_le_bytes())
}

/// Whether `len` bytes of flash from `offset` read erased, read [`CHUNK`] bytes at a time.
fn blank<F: ReadNorFlash>(flash: &mut F, offset: u32, len: u32) -> Result<bool, F::Error> {
    let mut buf = [0u8; CHUNK];
    let mut done = 0u32;
    while done < len {
        let n = (len - done).min(CHUNK as u32);
        let chunk = buf.get_mut(..n as usize).unwrap_or(&mut []);
        flash.read(offset + done, chunk)?;
        if chunk.iter().any(|&b| b != 0xFF) {
            return Ok(false);
        }
        done += n;
    }
    Ok(true)
}
