//! Test helpers shared by the integration tests.
#![allow(dead_code)]

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

/// embedded-hal-mock 0.11's SPI mock cannot inject an error, so this wrapper fails the
/// `fail_on`-th `transaction` (0-based) with `ErrorKind::Other` *before* it reaches the mock — like a
/// bus that faults before chip select is asserted. The mock therefore expects every transaction
/// except the failing one, and its `done()` still checks the rest.
pub struct FailAt<S> {
    pub inner: S,
    pub fail_on: usize,
    count: usize,
}

impl<S> FailAt<S> {
    pub fn new(inner: S, fail_on: usize) -> Self {
        Self {
            inner,
            fail_on,
            count: 0,
        }
    }
}

impl<S> ErrorType for FailAt<S> {
    type Error = ErrorKind;
}

impl<S: SpiDevice<Error = ErrorKind>> SpiDevice for FailAt<S> {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        let n = self.count;
        self.count += 1;
        if n == self.fail_on {
            return Err(ErrorKind::Other);
        }
        self.inner.transaction(operations)
    }
}
