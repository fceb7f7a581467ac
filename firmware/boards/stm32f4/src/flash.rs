//! The model slots' flash (sectors 10 and 11) on the STM32F407, as the update task and the boot
//! use it: written against the PAC's registers rather than stm32f4xx-hal's flash driver, which
//! never clears a stuck error flag (one failed program then fails every later one), waits for
//! BSY without bound (inside the update task's interrupt), `assert!`s in its unlock (a panic in an
//! interrupt handler), and programs one byte at a time.
//!
//! Here: every operation clears the error flags first and reports the ones it raised ([`Error`]);
//! every wait is bounded by the DWT cycle counter (a word program: 100 µs at most by DS8626,
//! bounded at 1 ms; a 128 KiB sector erase at x32 parallelism: 1–2 s typically, 4 s at most,
//! bounded at 8 s and run only at boot, before the watchdog starts); words are programmed at x32
//! parallelism (2.7–3.6 V); the flash is locked again after each operation; and the data cache is
//! reset after a program or an erase, so a read of the slot sees the new bytes (RM0090 §3.5.5).
//!
//! The part's flash size is checked at boot ([`ModelFlash::new`]): sectors 10 and 11 exist only on
//! a 1 MiB part. On a smaller one (an STM32F405RG with 512 KiB, …) the region is empty: no image
//! is found, every channel runs `NO_MODEL`, and every update is refused — where the old driver's
//! erase of a sector that does not exist silently did nothing.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use stm32f4xx_hal::pac::FLASH;
use stm32f4xx_hal::pac::flash::cr::PSIZE;
use tcomp_firmware::slots::MappedFlash;

/// Where `MODELS` starts (sector 10).
pub const MODELS_ADDRESS: usize = 0x080C_0000;
/// Its size: sectors 10 and 11, 128 KiB each.
pub const MODELS_LEN: usize = 256 * 1024;
/// Sector 10's number, slot A's.
const FIRST_SECTOR: u8 = 10;
/// One sector.
const SECTOR: u32 = 128 * 1024;
/// The part's flash size in KiB, programmed by ST (RM0090 §39.2).
const FLASH_SIZE_REGISTER: usize = 0x1FFF_7A22;
/// The flash the layout needs: 1 MiB.
const NEEDED_KIB: u16 = 1024;
/// Core cycles (168 MHz) a word program may take before it counts as failed: 1 ms, ten times the
/// datasheet's worst case.
const PROGRAM_BOUND: u32 = 168_000;
/// … and a sector erase: 8 s, twice the datasheet's worst case (x32).
const ERASE_BOUND: u32 = 8 * 168_000_000;
const KEY1: u32 = 0x4567_0123;
const KEY2: u32 = 0xCDEF_89AB;

/// Why a flash operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Error {
    /// The part has less flash than the two slots need (its size in KiB).
    Size(u16),
    /// Outside the region.
    OutOfBounds,
    /// Not on a word (program) or sector (erase) boundary.
    NotAligned,
    /// The control register stayed locked after the unlock sequence.
    Locked,
    /// BSY did not clear within the bound.
    Timeout,
    /// The status register's error flags the operation raised (PGSERR, PGPERR, PGAERR, WRPERR,
    /// OPERR bits, as in FLASH_SR), cleared since.
    Status(u32),
}

impl NorFlashError for Error {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            Self::OutOfBounds | Self::Size(_) => NorFlashErrorKind::OutOfBounds,
            Self::NotAligned => NorFlashErrorKind::NotAligned,
            _ => NorFlashErrorKind::Other,
        }
    }
}

/// The error flags of FLASH_SR: OPERR (1), WRPERR (4), PGAERR (5), PGPERR (6), PGSERR (7).
const ERROR_FLAGS: u32 = (1 << 1) | (1 << 4) | (1 << 5) | (1 << 6) | (1 << 7);

/// Sectors 10 and 11.
pub struct ModelFlash {
    regs: FLASH,
    /// The region's usable length: [`MODELS_LEN`], or 0 on a part without sectors 10–11.
    len: usize,
    /// The part's flash size, KiB.
    part_kib: u16,
}

impl ModelFlash {
    /// The region, after checking the part's flash size.
    pub fn new(regs: FLASH) -> Self {
        // SAFETY: the flash-size word of the system memory is always mapped and readable.
        let part_kib = unsafe { core::ptr::read_volatile(FLASH_SIZE_REGISTER as *const u16) };
        let len = if part_kib >= NEEDED_KIB {
            MODELS_LEN
        } else {
            0
        };
        Self {
            regs,
            len,
            part_kib,
        }
    }

    /// The part's flash size (KiB) and whether it holds the slots.
    pub fn part(&self) -> (u16, bool) {
        (self.part_kib, self.len > 0)
    }

    /// The bytes `[offset, offset + len)` for the rest of the run: the loop's models borrow the
    /// active slot's payload this way. Empty outside the region.
    ///
    /// # Safety
    /// Nothing may erase or program the range for the rest of the run (the active slot's payload:
    /// an update writes only the other slot, the boot erases only that one).
    pub unsafe fn map_static(&self, offset: u32, len: u32) -> &'static [u8] {
        match (offset as usize).checked_add(len as usize) {
            // SAFETY: inside sectors 10–11, which exist on this part (checked) and are always
            // readable; the caller's contract keeps the range unwritten.
            Some(end) if end <= self.len => unsafe {
                core::slice::from_raw_parts(
                    (MODELS_ADDRESS + offset as usize) as *const u8,
                    len as usize,
                )
            },
            _ => &[],
        }
    }

    fn check(&self, offset: u32, len: usize, align: usize) -> Result<usize, Error> {
        if self.len == 0 {
            return Err(Error::Size(self.part_kib));
        }
        let at = offset as usize;
        if !at.is_multiple_of(align) || !len.is_multiple_of(align) {
            return Err(Error::NotAligned);
        }
        match at.checked_add(len) {
            Some(end) if end <= self.len => Ok(MODELS_ADDRESS + at),
            _ => Err(Error::OutOfBounds),
        }
    }

    /// Clears the error flags, unlocks the control register (no `assert!`: a refusal is an
    /// error) and waits, bounded, for a previous operation.
    fn begin(&mut self) -> Result<(), Error> {
        self.wait(PROGRAM_BOUND)?;
        // SAFETY: writing ones to the error flags of FLASH_SR clears them; no other bit of the
        // register is writable.
        self.regs.sr().write(|w| unsafe { w.bits(ERROR_FLAGS | 1) });
        if self.regs.cr().read().lock().bit_is_set() {
            // SAFETY: the unlock sequence's two keys (RM0090 §3.5.1).
            self.regs.keyr().write(|w| unsafe { w.key().bits(KEY1) });
            // SAFETY: as above.
            self.regs.keyr().write(|w| unsafe { w.key().bits(KEY2) });
        }
        if self.regs.cr().read().lock().bit_is_set() {
            return Err(Error::Locked);
        }
        Ok(())
    }

    /// Waits for BSY to clear for at most `bound` core cycles.
    fn wait(&self, bound: u32) -> Result<(), Error> {
        let start = cortex_m::peripheral::DWT::cycle_count();
        while self.regs.sr().read().bsy().bit_is_set() {
            if cortex_m::peripheral::DWT::cycle_count().wrapping_sub(start) > bound {
                return Err(Error::Timeout);
            }
        }
        Ok(())
    }

    /// Ends an operation: the error flags it raised (then cleared), the control register cleared
    /// and locked, the data cache reset.
    fn end(&mut self, waited: Result<(), Error>) -> Result<(), Error> {
        let flags = self.regs.sr().read().bits() & ERROR_FLAGS;
        // SAFETY: as in `begin`.
        self.regs.sr().write(|w| unsafe { w.bits(ERROR_FLAGS | 1) });
        self.regs.cr().modify(|_, w| {
            w.pg().clear_bit();
            w.ser().clear_bit();
            w.lock().set_bit()
        });
        self.reset_data_cache();
        waited?;
        if flags != 0 {
            return Err(Error::Status(flags));
        }
        Ok(())
    }

    /// RM0090 §3.5.5: the data cache may hold the old bytes of a range just programmed or erased.
    fn reset_data_cache(&mut self) {
        let acr = &self.regs.acr();
        let on = acr.read().dcen().bit_is_set();
        acr.modify(|_, w| w.dcen().clear_bit());
        acr.modify(|_, w| w.dcrst().set_bit());
        acr.modify(|_, w| w.dcrst().clear_bit());
        if on {
            acr.modify(|_, w| w.dcen().set_bit());
        }
    }

    /// Programs one word at `address`.
    fn program_word(&mut self, address: usize, word: u32) -> Result<(), Error> {
        self.regs.cr().modify(|_, w| {
            w.psize().variant(PSIZE::Psize32);
            w.ser().clear_bit();
            w.pg().set_bit()
        });
        // SAFETY: `address` is a word of sectors 10–11 (checked by the caller), the flash is
        // unlocked with PG set: the write starts the word's program; no Rust reference covers a
        // range being programmed (`MappedFlash::mapped` borrows `self`).
        unsafe { core::ptr::write_volatile(address as *mut u32, word) };
        self.wait(PROGRAM_BOUND)
    }
}

impl ErrorType for ModelFlash {
    type Error = Error;
}

impl ReadNorFlash for ModelFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Error> {
        let src = self
            .mapped(offset, bytes.len() as u32)
            .ok_or(Error::OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.len
    }
}

impl MappedFlash for ModelFlash {
    fn mapped(&self, offset: u32, len: u32) -> Option<&[u8]> {
        let end = (offset as usize).checked_add(len as usize)?;
        if end > self.len {
            return None;
        }
        // SAFETY: inside sectors 10–11 (checked), always readable; the slice borrows `self`, so
        // no erase or program (`&mut self`) happens while it lives.
        Some(unsafe {
            core::slice::from_raw_parts(
                (MODELS_ADDRESS + offset as usize) as *const u8,
                len as usize,
            )
        })
    }
}

impl NorFlash for ModelFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = SECTOR as usize;

    /// Erases whole sectors. Stalls every fetch from flash for seconds: the boot calls it before
    /// the watchdog starts; at run time the application's `RunTime` wrapper never does.
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Error> {
        let len = to.checked_sub(from).ok_or(Error::OutOfBounds)? as usize;
        self.check(from, len, SECTOR as usize)?;
        let mut sector = from;
        while sector < to {
            let snb = FIRST_SECTOR + (sector / SECTOR) as u8;
            self.begin()?;
            self.regs.cr().modify(|_, w| {
                w.psize().variant(PSIZE::Psize32);
                w.pg().clear_bit();
                // SAFETY: sector 10 or 11 of a 1 MiB part (checked).
                unsafe { w.snb().bits(snb) };
                w.ser().set_bit()
            });
            self.regs.cr().modify(|_, w| w.strt().set_bit());
            let waited = self.wait(ERASE_BOUND);
            self.end(waited)?;
            sector += SECTOR;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Error> {
        let base = self.check(offset, bytes.len(), 4)?;
        self.begin()?;
        let mut result = Ok(());
        for (i, w) in bytes.chunks_exact(4).enumerate() {
            let word = u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
            result = self.program_word(base + 4 * i, word);
            if result.is_err() || self.regs.sr().read().bits() & ERROR_FLAGS != 0 {
                break;
            }
        }
        self.end(result)
    }
}
