//! The host tests' model flash: the core's simulated NOR flash (`tcomp_core::slots::sim::SimNor`)
//! seen as a board's mapped `MODELS` region ([`MappedFlash`]), as the boards' drivers present
//! theirs. One adapter for every firmware test that boots, chooses slots or updates over it
//! (`slots.rs`'s tests, `trust_tests.rs`).

use crate::slots::MappedFlash;
use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use tcomp_core::slots::sim::SimNor;

/// Two 32 KiB sectors: the two slots of `QEMU_LAYOUT`'s size in the tests.
pub(crate) type Sim = SimNor<{ 64 * 1024 }, { 32 * 1024 }>;

/// The flash model seen as a board's mapped region.
#[derive(Clone)]
pub(crate) struct Flash(pub(crate) Sim);

impl ErrorType for Flash {
    type Error = <Sim as ErrorType>::Error;
}

impl ReadNorFlash for Flash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes)
    }
    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl NorFlash for Flash {
    const WRITE_SIZE: usize = <Sim as NorFlash>::WRITE_SIZE;
    const ERASE_SIZE: usize = <Sim as NorFlash>::ERASE_SIZE;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0.erase(from, to)
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.write(offset, bytes)
    }
}

impl MappedFlash for Flash {
    fn mapped(&self, offset: u32, len: u32) -> Option<&[u8]> {
        let at = offset as usize;
        self.0.bytes().get(at..at.checked_add(len as usize)?)
    }
}
