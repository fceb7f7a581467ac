//! Where the firmware finds its models: the two slots of [`tcomp_core::slots`] in its `MODELS`
//! region, chosen at boot, plus the one image a debug probe may have put there by hand.
//!
//! `MODELS` holds slot A then slot B, each a whole number of erase sectors ([`QEMU_LAYOUT`]: two
//! 32 KiB halves of the last 64 KiB of mps2-an386's SSRAM; [`STM32F4_LAYOUT`]: sectors 10 and 11
//! of an STM32F407). The boot takes the newest committed slot that validates
//! ([`tcomp_core::slots::select`]). Failing that, a bare image (`tcomp image`'s output, magic
//! `TCMI`, no slot header) at the start of slot A is used as generation 0: that is what
//! `probe-rs download` or QEMU's loader put there, and an update then writes slot B and wins.
//! Failing both, no models: every channel runs `NO_MODEL`.

use crate::trust::Signer;
use core::cell::Cell;
use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use tcomp_core::image::Image;
use tcomp_core::slots::{Active, Header, Layout, SlotId, select};
use tcomp_core::update::Reason;

/// mps2-an386: `MODELS` is 64 KiB at `0x003F_0000`: slot A at its start, slot B at `0x003F_8000`.
pub const QEMU_LAYOUT: Layout = Layout {
    a: 0,
    b: 32 * 1024,
    size: 32 * 1024,
};

/// STM32F407: `MODELS` is sectors 10 and 11 (`0x080C_0000`, `0x080E_0000`), 128 KiB each.
pub const STM32F4_LAYOUT: Layout = Layout {
    a: 0,
    b: 128 * 1024,
    size: 128 * 1024,
};

/// Where the running image came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Source {
    /// A committed slot: which, and its generation.
    Slot(SlotId, u32),
    /// A bare image at slot A's start, written by a probe (generation 0).
    Probe,
    /// Nothing valid: no models.
    None,
}

/// The boot's choice.
#[derive(Clone, Copy, Debug)]
pub struct Choice<'a> {
    /// The image bytes to load the models from (empty without one).
    pub image: &'a [u8],
    /// What the update receiver must treat as active (never to be erased).
    pub active: Option<Active>,
    /// Where the image came from.
    pub source: Source,
    /// Who vouches for it (`None` without an image).
    pub signer: Option<Signer>,
    /// Why the last image considered and passed over was refused (a slot or a probe's image
    /// that reads but fails the caller's check: another unit, unsigned, an unknown key, a bad
    /// signature), for the boot report when nothing runs.
    pub refused: Option<Reason>,
}

/// Does `bytes[offset..offset + len]` hold an image the loop can read.
pub fn validates(bytes: &[u8], offset: u32, len: u32) -> bool {
    let (at, len) = (offset as usize, len as usize);
    at.checked_add(len)
        .and_then(|end| bytes.get(at..end))
        .is_some_and(|b| Image::parse(b).is_ok())
}

/// Chooses the image to run from `region` (the whole `MODELS` region, memory-mapped), reading
/// headers through `flash` (the same memory as a [`ReadNorFlash`]). `accept(image)` is the unit's
/// check of a candidate ([`crate::trust::Trust::check`]: made for this unit, signed by a trusted
/// key), made before a slot is chosen: a slot that fails it is passed over like a corrupt one.
/// A flash read error counts as "no slot".
pub fn choose<'a, F: ReadNorFlash>(
    flash: &mut F,
    layout: &Layout,
    region: &'a [u8],
    accept: impl Fn(&[u8]) -> Result<Signer, Reason>,
) -> Choice<'a> {
    let refused = Cell::new(None);
    // The signer of what was accepted last, and of each slot (by its payload's offset).
    let signer = Cell::new(None);
    let signers = [Cell::new(None), Cell::new(None)];
    let check = |bytes: &[u8]| match accept(bytes) {
        Ok(s) => {
            signer.set(Some(s));
            true
        }
        Err(why) => {
            refused.set(Some(why));
            false
        }
    };
    let validate = |_: &mut F, off: u32, len: u32| {
        let (at, n) = (off as usize, len as usize);
        signer.set(None);
        let ok = at
            .checked_add(n)
            .and_then(|end| region.get(at..end))
            .is_some_and(|b| Image::parse(b).is_ok() && check(b));
        let slot = usize::from(off != layout.a.saturating_add(tcomp_core::slots::PAYLOAD_AT));
        if let Some(c) = signers.get(slot) {
            c.set(signer.get());
        }
        ok
    };
    if let Ok(Some(active)) = select(flash, layout, validate) {
        let at = active.payload(layout) as usize;
        let image = at
            .checked_add(active.header.length as usize)
            .and_then(|end| region.get(at..end))
            .unwrap_or(&[]);
        let signer = signers
            .get(usize::from(active.slot.index()))
            .and_then(Cell::get);
        return Choice {
            image,
            active: Some(active),
            source: Source::Slot(active.slot, active.header.generation),
            signer,
            refused: refused.get(),
        };
    }
    let a = layout.a as usize;
    let slot_a = region
        .get(a..a.saturating_add(layout.size as usize))
        .unwrap_or(&[]);
    signer.set(None);
    if Image::parse(slot_a).is_ok() && check(slot_a) {
        let header = Header {
            generation: 0,
            length: layout.size,
            payload_crc: 0,
        };
        return Choice {
            image: slot_a,
            active: Some(Active {
                slot: SlotId::A,
                header,
            }),
            source: Source::Probe,
            signer: signer.get(),
            refused: refused.get(),
        };
    }
    Choice {
        image: &[],
        active: None,
        source: Source::None,
        signer: None,
        refused: refused.get(),
    }
}

/// Memory-mapped flash read as a [`ReadNorFlash`] (the boot's view: no writes).
#[derive(Clone, Copy, Debug)]
pub struct Mapped<'a>(pub &'a [u8]);

impl ErrorType for Mapped<'_> {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Mapped<'_> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        let at = offset as usize;
        let src = at
            .checked_add(bytes.len())
            .and_then(|end| self.0.get(at..end))
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.0.len()
    }
}

/// [`choose`] over memory-mapped flash alone.
pub fn choose_mapped<'a>(
    layout: &Layout,
    region: &'a [u8],
    accept: impl Fn(&[u8]) -> Result<Signer, Reason>,
) -> Choice<'a> {
    choose(&mut Mapped(region), layout, region, accept)
}

/// A part's flash seen as its `MODELS` region: offsets from the region's start (`base` in the
/// part's flash), with an erase of an already-erased range skipped.
///
/// Why the skip: on a single-bank part (the STM32F407) a sector erase stalls every flash fetch for
/// 1–2 s, so the 200 Hz loop would stop. The board erases the inactive slot at boot
/// ([`erase_inactive`], before the loop and the watchdog start), so the erase an update begins with
/// finds it blank and costs a read of the region instead; programming stalls the loop for one word
/// at a time (microseconds). Skipping the erase of a blank range changes nothing the power-loss
/// proof relies on: the range is exactly what the erase would have left.
pub struct Windowed<'m, F> {
    /// The part's flash (offsets from its start).
    pub flash: F,
    /// Where the region starts in it.
    pub base: u32,
    /// The region, memory-mapped, for the blank check.
    pub mapped: &'m [u8],
}

impl<F: ErrorType> ErrorType for Windowed<'_, F> {
    type Error = F::Error;
}

impl<F: ReadNorFlash> ReadNorFlash for Windowed<'_, F> {
    const READ_SIZE: usize = F::READ_SIZE;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.flash.read(self.base.saturating_add(offset), bytes)
    }

    fn capacity(&self) -> usize {
        self.mapped.len()
    }
}

impl<F: NorFlash> NorFlash for Windowed<'_, F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let blank = self
            .mapped
            .get(from as usize..to as usize)
            .is_some_and(|r| r.iter().all(|&b| b == 0xFF));
        if blank {
            return Ok(());
        }
        self.flash
            .erase(self.base.saturating_add(from), self.base.saturating_add(to))
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.flash.write(self.base.saturating_add(offset), bytes)
    }
}

/// Erases the slot an update would write (the one that is not `active`, A when none is) unless it is blank, so
/// that an update never has to erase while the loop runs. Call it at boot, before the loop and
/// the watchdog start. Returns whether an erase was needed.
pub fn erase_inactive<F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    active: Option<Active>,
    mapped: &[u8],
) -> Result<bool, F::Error> {
    // The receiver's target ([`tcomp_core::update::Receiver::target`]): the other slot, or A when
    // nothing is active (then nothing valid is lost).
    let slot = active.map_or(SlotId::A, |a| a.slot.other());
    let from = layout.base(slot);
    let to = from.saturating_add(layout.size);
    let blank = mapped
        .get(from as usize..to as usize)
        .is_some_and(|r| r.iter().all(|&b| b == 0xFF));
    if blank {
        return Ok(false);
    }
    flash.erase(from, to)?;
    Ok(true)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    extern crate std;
    use super::*;
    use crate::update::{MAX_REPLY, UpdateTask};
    use std::vec;
    use std::vec::Vec;
    use tcomp_core::image::write_image;
    use tcomp_core::slots::sim::SimNor;
    use tcomp_core::update::wire::{Decoder, MAX_FRAME};
    use tcomp_core::update::{Sender, Status};

    type Flash = SimNor<{ 64 * 1024 }, { 32 * 1024 }>;

    /// Accepts any readable image (the trust checks have their own tests, `trust_tests.rs`).
    fn any(_: &[u8]) -> Result<Signer, tcomp_core::update::Reason> {
        Ok(Signer::Unsigned)
    }

    /// [`validates`] as the update receiver's check before the commit.
    fn check(bytes: &[u8], off: u32, len: u32) -> Result<(), tcomp_core::update::Reason> {
        validates(bytes, off, len)
            .then_some(())
            .ok_or(tcomp_core::update::Reason::Invalid)
    }

    fn image(seed: u8) -> Vec<u8> {
        let blob: Vec<u8> = (0..500u32).map(|i| (i as u8) ^ seed).collect();
        let mut buf = vec![0u8; 4096];
        let n = write_image(&[(0, &blob), (1, &blob)], &mut buf).unwrap();
        buf.truncate(n);
        buf
    }

    /// The update task over the flash model, driven by the core's sender.
    fn update(flash: &mut Flash, new: &[u8]) -> Status {
        let region = flash.bytes().to_vec();
        let choice = choose(&mut Mapped(&region), &QEMU_LAYOUT, &region, any);
        let mut task = UpdateTask::new(QEMU_LAYOUT, choice.active);
        let mut tx = Sender::new(new, 1);
        let mut host = Decoder::new();
        let mut frame = [0u8; MAX_FRAME];
        while let Some(n) = tx.request(&mut frame) {
            for &b in &frame[..n] {
                let mut reply = [0u8; MAX_REPLY];
                let validate = |f: &mut Flash, off, len| check(f.bytes(), off, len);
                if let Some(m) = task.push(b, flash, b"SN", validate, &mut reply) {
                    for &r in &reply[..m] {
                        if let Some(p) = host.push(r) {
                            tx.on_reply(&p);
                        }
                    }
                }
            }
        }
        tx.status()
    }

    #[test]
    fn erased_flash_runs_no_models() {
        let flash = Flash::new();
        let c = choose_mapped(&QEMU_LAYOUT, flash.bytes(), any);
        assert_eq!((c.source, c.active, c.image.len()), (Source::None, None, 0));
    }

    #[test]
    fn a_probe_image_runs_as_generation_0_and_an_update_writes_slot_b() {
        let (old, new) = (image(1), image(2));
        let mut flash = Flash::new();
        use embedded_storage::nor_flash::NorFlash;
        let mut padded = old.clone();
        padded.resize(old.len().next_multiple_of(4), 0);
        flash.write(0, &padded).unwrap();
        let c = choose_mapped(&QEMU_LAYOUT, flash.bytes(), any);
        assert_eq!(c.source, Source::Probe);
        assert_eq!(&c.image[..old.len()], &old[..]);
        assert_eq!(
            update(&mut flash, &new),
            Status::Done {
                slot: SlotId::B,
                generation: 1
            }
        );
        let c = choose_mapped(&QEMU_LAYOUT, flash.bytes(), any);
        assert_eq!(c.source, Source::Slot(SlotId::B, 1));
        assert_eq!(c.image, &new[..]);
        // The probe's image is untouched; the next update writes slot A over it.
        assert_eq!(&flash.bytes()[..old.len()], &old[..]);
        let third = image(3);
        assert!(matches!(
            update(&mut flash, &third),
            Status::Done {
                slot: SlotId::A,
                generation: 2
            }
        ));
        assert_eq!(
            choose_mapped(&QEMU_LAYOUT, flash.bytes(), any).image,
            &third[..]
        );
    }

    #[test]
    fn a_corrupt_probe_image_runs_no_models() {
        let mut old = image(1);
        old[9] ^= 0x40; // inside the table's CRC field
        old.resize(old.len().next_multiple_of(4), 0);
        let mut flash = Flash::new();
        use embedded_storage::nor_flash::NorFlash;
        flash.write(0, &old).unwrap();
        assert_eq!(
            choose_mapped(&QEMU_LAYOUT, flash.bytes(), any).source,
            Source::None
        );
    }

    /// A flash that counts its erases.
    struct Counting<'a> {
        inner: &'a mut Flash,
        erases: usize,
    }

    impl ErrorType for Counting<'_> {
        type Error = <Flash as ErrorType>::Error;
    }

    impl ReadNorFlash for Counting<'_> {
        const READ_SIZE: usize = 1;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            self.inner.read(offset, bytes)
        }
        fn capacity(&self) -> usize {
            self.inner.capacity()
        }
    }

    impl NorFlash for Counting<'_> {
        const WRITE_SIZE: usize = <Flash as NorFlash>::WRITE_SIZE;
        const ERASE_SIZE: usize = <Flash as NorFlash>::ERASE_SIZE;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            self.erases += 1;
            self.inner.erase(from, to)
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            self.inner.write(offset, bytes)
        }
    }

    /// After the boot's erase of the inactive slot, a whole update through the window erases
    /// nothing (no stall of a single-bank part's loop) and ends with the new image committed.
    #[test]
    fn an_update_after_the_boot_erase_erases_nothing() {
        let mut flash = Flash::new();
        assert!(matches!(update(&mut flash, &image(1)), Status::Done { .. }));
        // Slot B holds garbage (a previous, older image): the boot erases it once.
        flash.erase(32 * 1024, 64 * 1024).unwrap();
        flash.write(32 * 1024, &[0u8; 64]).unwrap();
        let region = flash.bytes().to_vec();
        let active = choose(&mut Mapped(&region), &QEMU_LAYOUT, &region, any).active;
        let mut counting = Counting {
            inner: &mut flash,
            erases: 0,
        };
        assert!(erase_inactive(&mut counting, &QEMU_LAYOUT, active, &region).unwrap());
        assert_eq!(counting.erases, 1);
        let region = flash.bytes().to_vec();
        assert!(!erase_inactive(&mut flash, &QEMU_LAYOUT, active, &region).unwrap());

        let mut task = UpdateTask::new(QEMU_LAYOUT, active);
        let new = image(2);
        let mut tx = Sender::new(&new, 1);
        let mut host = Decoder::new();
        let mut frame = [0u8; MAX_FRAME];
        let mut erases = 0;
        while let Some(n) = tx.request(&mut frame) {
            for &b in &frame[..n] {
                let mapped = flash.bytes().to_vec();
                let mut counting = Counting {
                    inner: &mut flash,
                    erases: 0,
                };
                let mut window = Windowed {
                    flash: &mut counting,
                    base: 0,
                    mapped: &mapped,
                };
                let mut reply = [0u8; MAX_REPLY];
                let validate = |f: &mut Windowed<'_, &mut Counting<'_>>, off, len| {
                    check(f.flash.inner.bytes(), off, len)
                };
                let answer = task.push(b, &mut window, b"SN", validate, &mut reply);
                erases += counting.erases;
                if let Some(m) = answer {
                    for &r in &reply[..m] {
                        if let Some(p) = host.push(r) {
                            tx.on_reply(&p);
                        }
                    }
                }
            }
        }
        assert!(
            matches!(tx.status(), Status::Done { .. }),
            "{:?}",
            tx.status()
        );
        assert_eq!(erases, 0, "the update erased while the loop would run");
        let region = flash.bytes().to_vec();
        let chosen = choose(&mut Mapped(&region), &QEMU_LAYOUT, &region, any);
        assert_eq!(chosen.image, &new[..]);
    }
}
