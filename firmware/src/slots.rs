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
//!
//! Every candidate also passes the unit's trust check (`accept`: [`crate::trust::Trust::check`],
//! made for this unit and signed by a provisioned key) before it is chosen: a slot that fails it
//! counts as corrupt (so a trial never starts on it), a probe's image that fails it does not run
//! (but is kept, like any probe image, and the update writes slot B). Each image is verified once
//! per boot however often the slot logic reads its state, and the last refusal is kept for the
//! boot report.

use crate::trust::Signer;
use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use tcomp_core::image::Image;
use tcomp_core::slots::{Active, Header, Layout, SlotId, select};
pub use tcomp_core::slots::{BootSlots, confirm};
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Choice {
    /// The image to load the models from: its offset and length in the `MODELS` region (`None`
    /// without one). The board maps exactly these bytes for the loop's models; an update never
    /// writes them.
    pub image: Option<(u32, u32)>,
    /// What the update receiver must treat as active (never to be erased).
    pub active: Option<Active>,
    /// Where the image came from.
    pub source: Source,
    /// The image runs on trial (a newly committed slot's first boot): the application confirms it
    /// once it has run correctly; a boot that ends before rolls it back.
    pub trial: bool,
    /// A slot whose trial failed was found: this boot runs the one before it.
    pub rolled_back: bool,
    /// Who vouches for the image that runs (`None` without one).
    pub signer: Option<Signer>,
    /// Why the last readable image the boot considered was refused by the trust check (another
    /// unit's, unsigned, an unknown key, a bad signature), for the boot report.
    pub refused: Option<Reason>,
}

/// A board's `MODELS` region read as a [`ReadNorFlash`] (offsets from its start), and its bytes as
/// the CPU reads them, borrowed from the flash: no erase or program (`&mut self`) can happen while
/// such a borrow lives, so no reference ever aliases a range being written.
pub trait MappedFlash: ReadNorFlash {
    /// The bytes `[offset, offset + len)`; `None` outside the region.
    fn mapped(&self, offset: u32, len: u32) -> Option<&[u8]>;
}

/// Does `bytes[offset..offset + len]` hold an image the loop can read.
pub fn validates(bytes: &[u8], offset: u32, len: u32) -> bool {
    let (at, len) = (offset as usize, len as usize);
    at.checked_add(len)
        .and_then(|end| bytes.get(at..end))
        .is_some_and(|b| Image::parse(b).is_ok())
}

/// Whether `flash` maps `[offset, offset + len)` as a readable image.
fn holds_image<F: MappedFlash>(flash: &F, offset: u32, len: u32) -> bool {
    flash
        .mapped(offset, len)
        .is_some_and(|b| Image::parse(b).is_ok())
}

/// A candidate's offset and length, and the trust check's verdict on it.
type Verdict = (u32, u32, Result<Signer, Reason>);

/// The trust check of one boot over the images it reads: each candidate (a slot's payload, a
/// probe's region) verified once, however often the slot logic inspects its slot, and the last
/// refusal kept.
struct Trusted<A> {
    accept: A,
    /// Verdicts by (offset, length): slot A's payload, slot B's, a probe's region.
    seen: [Option<Verdict>; 3],
    refused: Option<Reason>,
}

impl<A: Fn(&[u8]) -> Result<Signer, Reason>> Trusted<A> {
    const fn new(accept: A) -> Self {
        Self {
            accept,
            seen: [None; 3],
            refused: None,
        }
    }

    /// The verdict on `[offset, offset + len)`; `None` when it holds no readable image.
    fn verdict<F: MappedFlash>(
        &mut self,
        flash: &F,
        offset: u32,
        len: u32,
    ) -> Option<Result<Signer, Reason>> {
        let bytes = flash.mapped(offset, len)?;
        if Image::parse(bytes).is_err() {
            return None;
        }
        if let Some((_, _, v)) = self
            .seen
            .iter()
            .flatten()
            .find(|(o, l, _)| *o == offset && *l == len)
        {
            return Some(*v);
        }
        let v = (self.accept)(bytes);
        if let Some(free) = self.seen.iter_mut().find(|s| s.is_none()) {
            *free = Some((offset, len, v));
        }
        if let Err(why) = v {
            self.refused = Some(why);
        }
        Some(v)
    }

    /// Whether `[offset, offset + len)` holds an image this unit may run.
    fn accepts<F: MappedFlash>(&mut self, flash: &F, offset: u32, len: u32) -> bool {
        matches!(self.verdict(flash, offset, len), Some(Ok(_)))
    }
}

/// Chooses the image to run from the `MODELS` region `flash` (read only: what [`boot`] would run,
/// without its trial and erase work); `accept` is the unit's trust check of a candidate. A flash
/// read error counts as "no slot". A slot on trial reads as a failed trial here (only the boot
/// that programs the trial word runs it).
pub fn choose<F: MappedFlash>(
    flash: &mut F,
    layout: &Layout,
    accept: impl Fn(&[u8]) -> Result<Signer, Reason>,
) -> Choice {
    let mut trusted = Trusted::new(accept);
    let active = select(flash, layout, |f: &mut F, off, len| {
        trusted.accepts(f, off, len)
    })
    .ok()
    .flatten();
    choice(flash, layout, active, &mut trusted)
}

/// The choice for the committed slot `active`, or failing one a probe's bare image at slot A that
/// passes the trust check, or nothing. A probe's image that fails it still counts as the active
/// slot A for the update receiver (kept; an update writes slot B), but does not run.
fn choice<F: MappedFlash, A: Fn(&[u8]) -> Result<Signer, Reason>>(
    flash: &F,
    layout: &Layout,
    active: Option<Active>,
    trusted: &mut Trusted<A>,
) -> Choice {
    if let Some(active) = active {
        let (at, len) = (active.payload(layout), active.header.length);
        return Choice {
            image: Some((at, len)),
            active: Some(active),
            source: Source::Slot(active.slot, active.header.generation),
            trial: false,
            rolled_back: false,
            signer: trusted.verdict(flash, at, len).and_then(Result::ok),
            refused: trusted.refused,
        };
    }
    let probe = Active {
        slot: SlotId::A,
        header: Header {
            generation: 0,
            length: layout.size,
            payload_crc: 0,
        },
    };
    match trusted.verdict(flash, layout.a, layout.size) {
        Some(Ok(signer)) => Choice {
            image: Some((layout.a, layout.size)),
            active: Some(probe),
            source: Source::Probe,
            trial: false,
            rolled_back: false,
            signer: Some(signer),
            refused: trusted.refused,
        },
        refused => Choice {
            image: None,
            active: refused.is_some().then_some(probe),
            source: Source::None,
            trial: false,
            rolled_back: false,
            signer: None,
            refused: trusted.refused,
        },
    }
}

/// The boot's work on the slots, before the watchdog starts ([`tcomp_core::slots::boot`]): the
/// image to run (each candidate through `accept`, the unit's trust check, before a slot is
/// chosen: a slot it refuses is never put on trial), a newly committed slot's trial begun, the
/// slot an update will write erased unless the running image is on trial (the old one is then the
/// rollback). A bare image a probe wrote at slot A counts as confirmed and is kept while it runs.
pub fn boot<F: NorFlash + MappedFlash>(
    flash: &mut F,
    layout: &Layout,
    accept: impl Fn(&[u8]) -> Result<Signer, Reason>,
) -> Result<Choice, F::Error> {
    let probe = holds_image(flash, layout.a, layout.size);
    let mut trusted = Trusted::new(accept);
    let slots =
        tcomp_core::slots::boot(flash, layout, probe.then_some(SlotId::A), |f, off, len| {
            trusted.accepts(f, off, len)
        })?;
    let mut choice = choice(flash, layout, slots.active, &mut trusted);
    choice.trial = slots.trial;
    choice.rolled_back = slots.rolled_back;
    Ok(choice)
}

/// Memory-mapped flash read as a [`MappedFlash`] (a read-only view: host tests, tools).
#[derive(Clone, Copy, Debug)]
pub struct Mapped<'a>(pub &'a [u8]);

impl ErrorType for Mapped<'_> {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Mapped<'_> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        let src = self
            .mapped(offset, bytes.len() as u32)
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.0.len()
    }
}

impl MappedFlash for Mapped<'_> {
    fn mapped(&self, offset: u32, len: u32) -> Option<&[u8]> {
        let at = offset as usize;
        self.0.get(at..at.checked_add(len as usize)?)
    }
}

/// Whether `[from, to)` reads erased (all 0xFF).
fn blank<F: MappedFlash>(flash: &F, from: u32, to: u32) -> bool {
    flash
        .mapped(from, to.saturating_sub(from))
        .is_some_and(|r| r.iter().all(|&b| b == 0xFF))
}

/// Why a run-time flash operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunTimeError<E> {
    /// The flash refused it.
    Flash(E),
    /// An erase of a range that is not blank: refused while the loop runs (it would stall every
    /// fetch from a single-bank flash for seconds); the boot erases it
    /// ([`RunTime::erase_requested`]).
    NotErased,
}

impl<E: NorFlashError> NorFlashError for RunTimeError<E> {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            Self::Flash(e) => e.kind(),
            Self::NotErased => NorFlashErrorKind::Other,
        }
    }
}

/// The model flash while the loop runs: programs pass through; an erase is only ever of a range
/// that is already blank (then nothing happens: it is exactly what the erase would leave) and
/// refused otherwise, with the range recorded for the board to erase at its next boot, before the
/// watchdog starts. So no flash operation that stalls the loop for more than a word's program
/// time can happen at run time, whatever the host sends.
pub struct RunTime<F> {
    flash: F,
    requested: Option<(u32, u32)>,
}

impl<F> RunTime<F> {
    /// `flash` for the run.
    pub const fn new(flash: F) -> Self {
        Self {
            flash,
            requested: None,
        }
    }

    /// A range an update needed erased and the run refused: the board erases it at its next boot.
    pub const fn erase_requested(&self) -> Option<(u32, u32)> {
        self.requested
    }

    /// The flash.
    pub fn inner(&mut self) -> &mut F {
        &mut self.flash
    }
}

impl<F: ErrorType> ErrorType for RunTime<F> {
    type Error = RunTimeError<F::Error>;
}

impl<F: ReadNorFlash> ReadNorFlash for RunTime<F> {
    const READ_SIZE: usize = F::READ_SIZE;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.flash.read(offset, bytes).map_err(RunTimeError::Flash)
    }

    fn capacity(&self) -> usize {
        self.flash.capacity()
    }
}

impl<F: MappedFlash> MappedFlash for RunTime<F> {
    fn mapped(&self, offset: u32, len: u32) -> Option<&[u8]> {
        self.flash.mapped(offset, len)
    }
}

impl<F: NorFlash + MappedFlash> NorFlash for RunTime<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if blank(&self.flash, from, to) {
            return Ok(());
        }
        self.requested = Some((from, to));
        Err(RunTimeError::NotErased)
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.flash.write(offset, bytes).map_err(RunTimeError::Flash)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    extern crate std;
    use super::*;
    use crate::test_flash::{Flash, Sim};
    use crate::update::{MAX_REPLY, UpdateTask};
    use std::vec;
    use std::vec::Vec;
    use tcomp_core::image::write_image;
    use tcomp_core::update::wire::{Decoder, MAX_FRAME};
    use tcomp_core::update::{Sender, Status};

    /// Accepts any readable image (the trust checks have their own tests, `trust_tests.rs`).
    fn any(_: &[u8]) -> Result<Signer, tcomp_core::update::Reason> {
        Ok(Signer::Unsigned)
    }

    fn image(seed: u8) -> Vec<u8> {
        let blob: Vec<u8> = (0..500u32).map(|i| (i as u8) ^ seed).collect();
        let mut buf = vec![0u8; 4096];
        let n = write_image(&[(0, &blob), (1, &blob)], &mut buf).unwrap();
        buf.truncate(n);
        buf
    }

    /// The image the boot would run.
    fn booted(flash: &mut Flash) -> (Source, Vec<u8>) {
        let c = choose(flash, &QEMU_LAYOUT, any);
        let bytes = c
            .image
            .and_then(|(off, len)| flash.mapped(off, len))
            .unwrap_or(&[])
            .to_vec();
        (c.source, bytes)
    }

    /// A boot (the erase of the inactive slot), then the update task over the run-time flash,
    /// driven by the core's sender. Returns the sender's status and whether the run asked the
    /// boot for an erase.
    fn update(flash: &mut Flash, new: &[u8]) -> (Status, bool) {
        let choice = choose(flash, &QEMU_LAYOUT, any);
        let mut task = UpdateTask::new(QEMU_LAYOUT, choice.active);
        let mut run = RunTime::new(flash.clone());
        let mut tx = Sender::new(new, 1);
        let mut host = Decoder::new();
        let mut frame = [0u8; MAX_FRAME];
        while let Some(n) = tx.request(&mut frame) {
            for &b in &frame[..n] {
                let mut reply = [0u8; MAX_REPLY];
                let validate = |f: &mut RunTime<Flash>, off, len| {
                    f.mapped(off, len)
                        .filter(|b| validates(b, 0, len))
                        .map(|_| ())
                        .ok_or(tcomp_core::update::Reason::Invalid)
                };
                if let Some(m) = task.push(b, &mut run, b"SN", validate, &mut reply) {
                    for &r in &reply[..m] {
                        if let Some(p) = host.push(r) {
                            tx.on_reply(&p);
                        }
                    }
                }
            }
        }
        let requested = run.erase_requested().is_some();
        *flash = run.inner().clone();
        (tx.status(), requested)
    }

    /// A boot: the slots' trial and erase work; returns the choice.
    fn boot_now(flash: &mut Flash) -> Choice {
        boot(flash, &QEMU_LAYOUT, any).unwrap()
    }

    /// The application's confirm of the slot a boot runs on trial.
    fn confirm_trial(flash: &mut Flash, c: &Choice) {
        assert!(c.trial);
        confirm(flash, &QEMU_LAYOUT, c.active.unwrap().slot).unwrap();
    }

    #[test]
    fn erased_flash_runs_no_models() {
        let mut flash = Flash(Sim::new());
        let c = choose(&mut flash, &QEMU_LAYOUT, any);
        assert_eq!((c.source, c.active, c.image), (Source::None, None, None));
    }

    #[test]
    fn a_probe_image_runs_as_generation_0_and_an_update_writes_slot_b() {
        let (old, new) = (image(1), image(2));
        let mut flash = Flash(Sim::new());
        let mut padded = old.clone();
        padded.resize(old.len().next_multiple_of(4), 0);
        flash.write(0, &padded).unwrap();
        let (source, bytes) = booted(&mut flash);
        assert_eq!(source, Source::Probe);
        assert_eq!(&bytes[..old.len()], &old[..]);
        assert_eq!(
            boot_now(&mut flash).source,
            Source::Probe,
            "slot B is blank"
        );
        let (status, requested) = update(&mut flash, &new);
        assert_eq!(
            status,
            Status::Done {
                slot: SlotId::B,
                generation: 1
            }
        );
        assert!(!requested);
        assert_eq!(
            booted(&mut flash),
            (Source::Slot(SlotId::B, 1), new.clone())
        );
        // The new image's first boot is its trial: the probe's image is kept for a rollback, so
        // no update can be written yet.
        let c = boot_now(&mut flash);
        assert_eq!((c.source, c.trial), (Source::Slot(SlotId::B, 1), true));
        assert_eq!(&flash.0.bytes()[..old.len()], &old[..]);
        let (status, requested) = update(&mut flash, &image(3));
        assert!(!matches!(status, Status::Done { .. }) && requested);
        // Confirmed, the next boot erases the probe's image and the update goes through.
        confirm_trial(&mut flash, &c);
        let c = boot_now(&mut flash);
        assert_eq!((c.source, c.trial), (Source::Slot(SlotId::B, 1), false));
        let third = image(3);
        assert!(matches!(
            update(&mut flash, &third).0,
            Status::Done {
                slot: SlotId::A,
                generation: 2
            }
        ));
        assert_eq!(booted(&mut flash).1, third);
    }

    #[test]
    fn a_corrupt_probe_image_runs_no_models() {
        let mut old = image(1);
        old[9] ^= 0x40; // inside the table's CRC field
        old.resize(old.len().next_multiple_of(4), 0);
        let mut flash = Flash(Sim::new());
        flash.write(0, &old).unwrap();
        assert_eq!(booted(&mut flash).0, Source::None);
    }

    /// At run time nothing is erased: an update onto a slot the boot left written (a failed
    /// session's, an old image's) is refused before a byte of it is touched, the run asks the
    /// boot for the erase, and after that boot the same update goes through without one.
    #[test]
    fn a_run_time_erase_is_refused_and_left_to_the_boot() {
        let mut flash = Flash(Sim::new());
        assert!(matches!(
            update(&mut flash, &image(1)).0,
            Status::Done { .. }
        ));
        let c = boot_now(&mut flash);
        confirm_trial(&mut flash, &c);
        // Slot B holds garbage (a session that stopped half way).
        flash.write(32 * 1024, &[0u8; 64]).unwrap();
        let before = flash.0.bytes().to_vec();
        let (status, requested) = update(&mut flash, &image(2));
        assert!(!matches!(status, Status::Done { .. }), "{status:?}");
        assert!(requested, "the run must ask the boot for the erase");
        assert_eq!(
            flash.0.bytes(),
            &before[..],
            "the refused update wrote nothing"
        );
        assert_eq!(booted(&mut flash).1, image(1));

        boot_now(&mut flash);
        let (status, requested) = update(&mut flash, &image(2));
        assert!(matches!(status, Status::Done { .. }), "{status:?}");
        assert!(!requested);
        assert_eq!(booted(&mut flash).1, image(2));
    }

    /// A trial that ends before its confirm (a reset, a crash, a power cut, the application's
    /// rollback) is rolled back at the next boot: the old image runs, whole, and the failed one is
    /// erased for the next update.
    #[test]
    fn a_trial_that_never_confirms_is_rolled_back() {
        let mut flash = Flash(Sim::new());
        assert!(matches!(
            update(&mut flash, &image(1)).0,
            Status::Done { .. }
        ));
        let c = boot_now(&mut flash);
        confirm_trial(&mut flash, &c);
        assert!(!boot_now(&mut flash).trial);
        assert!(matches!(
            update(&mut flash, &image(2)).0,
            Status::Done { .. }
        ));
        let c = boot_now(&mut flash);
        assert_eq!((c.source, c.trial), (Source::Slot(SlotId::B, 2), true));
        let (off, len) = c.image.unwrap();
        assert_eq!(flash.mapped(off, len).unwrap(), &image(2)[..]);
        // No confirm: the next boot runs image 1 again and erases slot B.
        let c = boot_now(&mut flash);
        assert_eq!(
            (c.source, c.trial, c.rolled_back),
            (Source::Slot(SlotId::A, 1), false, true)
        );
        assert_eq!(booted(&mut flash).1, image(1));
        assert!(flash.0.bytes()[32 * 1024..].iter().all(|&b| b == 0xFF));
        // And an update after it writes B again, as generation 2.
        assert!(matches!(
            update(&mut flash, &image(3)).0,
            Status::Done {
                slot: SlotId::B,
                generation: 2
            }
        ));
    }
}
