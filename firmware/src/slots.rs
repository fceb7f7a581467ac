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

use embedded_storage::nor_flash::{ErrorType, NorFlashErrorKind, ReadNorFlash};
use tcomp_core::image::Image;
use tcomp_core::slots::{Active, Header, Layout, SlotId, select};

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
}

/// Does `bytes[offset..offset + len]` hold an image the loop can read.
pub fn validates(bytes: &[u8], offset: u32, len: u32) -> bool {
    let (at, len) = (offset as usize, len as usize);
    at.checked_add(len)
        .and_then(|end| bytes.get(at..end))
        .is_some_and(|b| Image::parse(b).is_ok())
}

/// Chooses the image to run from `region` (the whole `MODELS` region, memory-mapped), reading
/// headers through `flash` (the same memory as a [`ReadNorFlash`]). A flash read error counts as
/// "no slot".
pub fn choose<'a, F: ReadNorFlash>(flash: &mut F, layout: &Layout, region: &'a [u8]) -> Choice<'a> {
    if let Ok(Some(active)) = select(flash, layout, |_, off, len| validates(region, off, len)) {
        let at = active.payload(layout) as usize;
        let image = at
            .checked_add(active.header.length as usize)
            .and_then(|end| region.get(at..end))
            .unwrap_or(&[]);
        return Choice {
            image,
            active: Some(active),
            source: Source::Slot(active.slot, active.header.generation),
        };
    }
    let a = layout.a as usize;
    let slot_a = region
        .get(a..a.saturating_add(layout.size as usize))
        .unwrap_or(&[]);
    if Image::parse(slot_a).is_ok() {
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
        };
    }
    Choice {
        image: &[],
        active: None,
        source: Source::None,
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
pub fn choose_mapped<'a>(layout: &Layout, region: &'a [u8]) -> Choice<'a> {
    choose(&mut Mapped(region), layout, region)
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
        let choice = choose(&mut Mapped(&region), &QEMU_LAYOUT, &region);
        let mut task = UpdateTask::new(QEMU_LAYOUT, choice.active);
        let mut tx = Sender::new(new);
        let mut host = Decoder::new();
        let mut frame = [0u8; MAX_FRAME];
        while let Some(n) = tx.request(&mut frame) {
            for &b in &frame[..n] {
                let mut reply = [0u8; MAX_REPLY];
                let validate = |f: &mut Flash, off, len| validates(f.bytes(), off, len);
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
        let c = choose_mapped(&QEMU_LAYOUT, flash.bytes());
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
        let c = choose_mapped(&QEMU_LAYOUT, flash.bytes());
        assert_eq!(c.source, Source::Probe);
        assert_eq!(&c.image[..old.len()], &old[..]);
        assert_eq!(
            update(&mut flash, &new),
            Status::Done {
                slot: SlotId::B,
                generation: 1
            }
        );
        let c = choose_mapped(&QEMU_LAYOUT, flash.bytes());
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
        assert_eq!(choose_mapped(&QEMU_LAYOUT, flash.bytes()).image, &third[..]);
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
            choose_mapped(&QEMU_LAYOUT, flash.bytes()).source,
            Source::None
        );
    }
}
