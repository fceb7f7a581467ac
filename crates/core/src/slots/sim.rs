//! A NOR flash model for host tests, with a power cut injected at any single write step.
//!
//! It behaves as the STM32F4's flash does at 2.7–3.6 V with x32 parallelism, the granularity the
//! power-loss proof needs to be honest about: an erase sets a whole sector to 0xFF; a program
//! writes 4-byte words and can only clear bits (the word becomes `old & new`); each sector erase
//! and each word program is one *step*. A cut [`Cut::After`] step `k` lets step `k` complete and
//! fails every later operation; a cut [`Cut::Torn`] at step `k` leaves that step half done — a
//! word with only some of its bits cleared, or a sector erased up to an arbitrary byte and the
//! rest with arbitrary bits set — and fails it and every later one. [`SimNor::power_on`] is the
//! reboot. The torn patterns come from a fixed generator seeded by the step, so a run repeats.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// Where the power fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    /// After step `k` (counted from 1) completed.
    After(u32),
    /// In the middle of step `k`.
    Torn(u32),
}

/// What the model's operations fail with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimError {
    /// The power is off (a cut happened).
    PowerLost,
    /// Outside the flash.
    OutOfBounds,
    /// Not on a word (program) or sector (erase) boundary.
    NotAligned,
}

impl NorFlashError for SimError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            Self::PowerLost => NorFlashErrorKind::Other,
            Self::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            Self::NotAligned => NorFlashErrorKind::NotAligned,
        }
    }
}

/// `SIZE` bytes of NOR flash in sectors of `SECTOR` bytes, erased at creation.
#[derive(Clone, Debug)]
pub struct SimNor<const SIZE: usize, const SECTOR: usize> {
    bytes: [u8; SIZE],
    steps: u32,
    cut: Option<Cut>,
    dead: bool,
}

impl<const SIZE: usize, const SECTOR: usize> Default for SimNor<SIZE, SECTOR> {
    fn default() -> Self {
        Self::new()
    }
}

/// xorshift32 of the step number: the torn pattern of that step.
fn pattern(step: u32) -> u32 {
    let mut x = step.wrapping_mul(0x9E37_79B9) | 1;
    for _ in 0..3 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
    }
    x
}

impl<const SIZE: usize, const SECTOR: usize> SimNor<SIZE, SECTOR> {
    const SHAPE: () =
        assert!(SECTOR > 0 && SECTOR.is_multiple_of(4) && SIZE.is_multiple_of(SECTOR));

    /// Erased flash, power on, no cut planned.
    pub const fn new() -> Self {
        let () = Self::SHAPE;
        Self {
            bytes: [0xFF; SIZE],
            steps: 0,
            cut: None,
            dead: false,
        }
    }

    /// Plans a cut, counting steps from now (the step counter restarts at zero).
    pub fn plan(&mut self, cut: Cut) {
        self.cut = Some(cut);
        self.steps = 0;
    }

    /// The reboot: power back, no cut planned, the step counter at zero.
    pub fn power_on(&mut self) {
        self.cut = None;
        self.dead = false;
        self.steps = 0;
    }

    /// Steps since the last [`plan`](Self::plan) or [`power_on`](Self::power_on).
    pub const fn steps(&self) -> u32 {
        self.steps
    }

    /// True once a planned cut has happened.
    pub const fn is_dead(&self) -> bool {
        self.dead
    }

    /// The whole flash, as a memory-mapped read would see it.
    pub const fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Counts one step; `Ok(torn)` says whether this step is the torn one, `Err` that the power is
    /// already off.
    fn step(&mut self) -> Result<bool, SimError> {
        if self.dead {
            return Err(SimError::PowerLost);
        }
        self.steps += 1;
        match self.cut {
            Some(Cut::Torn(k)) if k == self.steps => {
                self.dead = true;
                Ok(true)
            }
            Some(Cut::After(k)) if k == self.steps => {
                self.dead = true;
                Ok(false)
            }
            _ => Ok(false),
        }
    }

    fn program_word(&mut self, at: usize, word: [u8; 4]) -> Result<(), SimError> {
        let torn = self.step()?;
        let noise = pattern(self.steps).to_le_bytes();
        let dst = self
            .bytes
            .get_mut(at..at + 4)
            .ok_or(SimError::OutOfBounds)?;
        for ((d, w), n) in dst.iter_mut().zip(word).zip(noise) {
            let target = *d & w;
            // Torn: only the bits of `noise` among those to clear are cleared.
            *d = if torn {
                *d & !((*d & !target) & n)
            } else {
                target
            };
        }
        if torn {
            return Err(SimError::PowerLost);
        }
        Ok(())
    }

    fn erase_sector(&mut self, at: usize) -> Result<(), SimError> {
        let torn = self.step()?;
        let noise = pattern(self.steps);
        let sector = self
            .bytes
            .get_mut(at..at + SECTOR)
            .ok_or(SimError::OutOfBounds)?;
        if !torn {
            sector.fill(0xFF);
            return Ok(());
        }
        // Torn: erased up to an arbitrary byte, arbitrary bits set in the rest.
        let split = noise as usize % SECTOR;
        let (done, rest) = sector.split_at_mut(split);
        done.fill(0xFF);
        for (i, b) in rest.iter_mut().enumerate() {
            *b |= pattern(noise ^ i as u32) as u8;
        }
        Err(SimError::PowerLost)
    }
}

impl<const SIZE: usize, const SECTOR: usize> ErrorType for SimNor<SIZE, SECTOR> {
    type Error = SimError;
}

impl<const SIZE: usize, const SECTOR: usize> ReadNorFlash for SimNor<SIZE, SECTOR> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), SimError> {
        let at = offset as usize;
        let src = at
            .checked_add(bytes.len())
            .and_then(|end| self.bytes.get(at..end))
            .ok_or(SimError::OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        SIZE
    }
}

impl<const SIZE: usize, const SECTOR: usize> NorFlash for SimNor<SIZE, SECTOR> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = SECTOR;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), SimError> {
        let (from, to) = (from as usize, to as usize);
        if !from.is_multiple_of(SECTOR) || !to.is_multiple_of(SECTOR) {
            return Err(SimError::NotAligned);
        }
        if from > to || to > SIZE {
            return Err(SimError::OutOfBounds);
        }
        (from..to)
            .step_by(SECTOR)
            .try_for_each(|at| self.erase_sector(at))
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), SimError> {
        let at = offset as usize;
        if !at.is_multiple_of(4) || !bytes.len().is_multiple_of(4) {
            return Err(SimError::NotAligned);
        }
        if at.checked_add(bytes.len()).is_none_or(|end| end > SIZE) {
            return Err(SimError::OutOfBounds);
        }
        for (i, w) in bytes.chunks_exact(4).enumerate() {
            let word: [u8; 4] = w.try_into().map_err(|_| SimError::NotAligned)?;
            self.program_word(at + 4 * i, word)?;
        }
        Ok(())
    }
}
