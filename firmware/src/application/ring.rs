//! Reading a receive ring that a circular DMA fills (the STM32F407's USART1 → DMA2 stream 2): the
//! DMA never waits for the CPU, so no byte is lost to a busy or interrupt-masked core, a flash
//! program's stall or a long sample task; the update task reads behind it.
//!
//! The reader knows how far the DMA has written from its position in the ring and the number of
//! half rings it has completed, which the DMA's half- and full-transfer interrupt counts
//! ([`RingWriter::halves`]). It reads up to there. If it ever fell more than a ring behind, the
//! oldest bytes were overwritten: it skips them and counts them lost ([`RxSource::lost`]). The
//! ring is sized so that this cannot happen while the unit runs: 2 KiB are 22 ms of a 921,600-baud
//! line, and the update task is never held off for longer than the watchdog policy's 20 ms
//! without the unit being reset (`liveness`).

use super::serial::RxSource;

/// The DMA side of a ring.
pub trait RingWriter {
    /// The ring's length in bytes (even).
    fn ring_len(&self) -> usize;
    /// Half rings completed so far (wrapping), counted by the DMA's interrupt.
    fn halves(&self) -> u32;
    /// Where the DMA writes next, bytes from the ring's start.
    fn position(&self) -> usize;
    /// The byte at `index` (< `len`), as the DMA wrote it.
    fn byte(&self, index: usize) -> u8;
}

/// The update task's end of a DMA ring.
#[derive(Debug)]
pub struct RingReader<W> {
    writer: W,
    consumed: u32,
    lost: u32,
}

impl<W: RingWriter> RingReader<W> {
    /// Reads `writer` from its start (the DMA not started yet, or just started).
    pub const fn new(writer: W) -> Self {
        Self {
            writer,
            consumed: 0,
            lost: 0,
        }
    }

    /// Bytes the DMA has written so far (wrapping). A reading taken in the few cycles between the
    /// DMA crossing a half and its interrupt counting it is a half ring short: harmless, the
    /// reader then sees nothing new until the next call.
    fn written(&self) -> u32 {
        let half = (self.writer.ring_len() / 2).max(1);
        loop {
            let a = self.writer.halves();
            let position = self.writer.position();
            if a == self.writer.halves() {
                return a
                    .wrapping_mul(half as u32)
                    .wrapping_add((position % half) as u32);
            }
        }
    }
}

impl<W: RingWriter> RxSource for RingReader<W> {
    fn pop(&mut self) -> Option<u8> {
        let len = self.writer.ring_len();
        let written = self.written();
        let behind = written.wrapping_sub(self.consumed);
        if behind == 0 || behind > u32::MAX / 2 {
            // Nothing new, or a reading from just before a half was counted.
            return None;
        }
        if behind > len as u32 {
            // Overwritten before they were read: skip to the oldest byte still in the ring.
            let skip = behind - len as u32;
            self.lost = self.lost.wrapping_add(skip);
            self.consumed = self.consumed.wrapping_add(skip);
        }
        let b = self.writer.byte(self.consumed as usize % len);
        self.consumed = self.consumed.wrapping_add(1);
        Some(b)
    }

    fn lost(&self) -> u32 {
        self.lost
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    extern crate std;
    use super::*;
    use core::cell::{Cell, RefCell};
    use std::vec::Vec;

    /// A circular DMA into 16 bytes: its interrupt counts each half completed.
    struct Dma {
        ring: RefCell<[u8; 16]>,
        pos: Cell<usize>,
        halves: Cell<u32>,
        /// The interrupt has not run yet after the last half crossed.
        irq_late: Cell<bool>,
    }

    impl Dma {
        fn new() -> Self {
            Self {
                ring: RefCell::new([0; 16]),
                pos: Cell::new(0),
                halves: Cell::new(0),
                irq_late: Cell::new(false),
            }
        }

        fn receive(&self, bytes: &[u8]) {
            for &b in bytes {
                let p = self.pos.get();
                self.ring.borrow_mut()[p] = b;
                self.pos.set((p + 1) % 16);
                if (p + 1).is_multiple_of(8) {
                    self.halves.set(self.halves.get() + 1);
                }
            }
        }
    }

    impl RingWriter for &Dma {
        fn ring_len(&self) -> usize {
            16
        }
        fn halves(&self) -> u32 {
            self.halves.get() - u32::from(self.irq_late.get())
        }
        fn position(&self) -> usize {
            self.pos.get()
        }
        fn byte(&self, index: usize) -> u8 {
            self.ring.borrow()[index]
        }
    }

    fn drain(r: &mut RingReader<&Dma>) -> Vec<u8> {
        core::iter::from_fn(|| r.pop()).collect()
    }

    #[test]
    fn every_byte_in_order_across_many_laps() {
        let dma = Dma::new();
        let mut r = RingReader::new(&dma);
        let mut got = Vec::new();
        let mut sent = Vec::new();
        for k in 0..200u32 {
            let chunk: Vec<u8> = (0..(k % 15 + 1)).map(|i| (k * 7 + i) as u8).collect();
            dma.receive(&chunk);
            sent.extend(&chunk);
            got.extend(drain(&mut r));
        }
        assert_eq!(got, sent);
        assert_eq!(r.lost(), 0);
    }

    #[test]
    fn a_late_interrupt_delays_bytes_and_loses_none() {
        let dma = Dma::new();
        let mut r = RingReader::new(&dma);
        dma.receive(&[1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(drain(&mut r), [1, 2, 3, 4, 5, 6, 7]);
        dma.receive(&[8, 9]);
        dma.irq_late.set(true);
        assert_eq!(drain(&mut r), Vec::<u8>::new());
        dma.irq_late.set(false);
        assert_eq!(drain(&mut r), [8, 9]);
    }

    #[test]
    fn a_reader_a_ring_behind_skips_the_overwritten_bytes_and_counts_them() {
        let dma = Dma::new();
        let mut r = RingReader::new(&dma);
        let bytes: Vec<u8> = (0..40).collect();
        dma.receive(&bytes);
        assert_eq!(drain(&mut r), (24..40).collect::<Vec<u8>>());
        assert_eq!(r.lost(), 24);
    }
}
