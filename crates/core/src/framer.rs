//! The one byte-at-a-time decoder of sync-word frames: the output link's frames ([`crate::frame`],
//! sync 0xEB 0x90) and the serial update protocol's ([`crate::update::wire`], sync 0xEB 0x91) are
//! both read with it, each a thin [`Framing`] over it.
//!
//! Why one: resynchronisation is the subtle part of a serial decoder, and the two links had a
//! copy each of the same search; it is now written and tested once: a fixed buffer of one longest
//! frame, filled a byte at a time (postcard's accumulator, with a sync word and a CRC
//! instead of COBS), that yields a frame once its sync word, the length its header implies and its
//! CRC-32 all check; after garbage or a failed CRC it drops the first byte of the false start and
//! searches again from the byte after it, so a frame that began inside a corrupt one (or inside a
//! frame of the other protocol sharing the link) is still found, and one corrupt frame costs at
//! most that frame.
//!
//! # What every framed format shares
//!
//! ```text
//! offset       size        field
//! 0            SYNC.len()  the sync word
//! SYNC.len()   …           the header (its first HEADER_LEN bytes, sync included, give the length)
//! …            …           the body
//! len − 4      4           CRC-32 (the core's [`crc`](crate::crc)), little-endian, of bytes
//!                          SYNC.len() .. len − 4
//! ```
//!
//! No allocation, no panic on any bytes; the capacity `N` (the longest frame) is in the type.

use crate::crc::Crc32;
use core::marker::PhantomData;

/// Bytes of the CRC-32 at the end of every frame.
pub const CRC_LEN: usize = 4;

/// What a framed format tells the framer: its sync word and how long a frame is.
pub trait Framing {
    /// The bytes every frame starts with (not empty).
    const SYNC: &'static [u8];
    /// Bytes from the start of a frame (sync word included) that [`frame_len`](Self::frame_len)
    /// reads: at least the sync word.
    const HEADER_LEN: usize;
    /// The whole frame's length, sync word and CRC included, read from its first
    /// [`HEADER_LEN`](Self::HEADER_LEN) bytes; `None` when they are not a frame header.
    fn frame_len(header: &[u8]) -> Option<usize>;
}

/// What the start of the buffer holds.
enum Candidate {
    /// Not enough bytes to tell.
    Incomplete,
    /// Not a frame start: no sync word, a header that is no frame's, or a length past the buffer.
    NoFrame,
    /// A frame start whose CRC failed.
    Corrupt,
    /// A good frame of this many bytes.
    Good(usize),
}

/// Byte-at-a-time decoder of the frames of `F`, with a buffer of `N` bytes (the longest frame).
#[derive(Clone, Debug)]
pub struct Framer<F, const N: usize> {
    buf: [u8; N],
    len: usize,
    /// Bytes of the frame handed out, still at the start of the buffer (dropped at the next call).
    ready: usize,
    skipped: u64,
    corrupt: u64,
    framing: PhantomData<F>,
}

impl<F: Framing, const N: usize> Default for Framer<F, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<F: Framing, const N: usize> Framer<F, N> {
    /// A framer that has seen nothing.
    pub const fn new() -> Self {
        const {
            assert!(!F::SYNC.is_empty(), "a sync word has at least one byte");
            assert!(
                F::SYNC.len() <= F::HEADER_LEN,
                "the header starts with the sync word"
            );
            assert!(
                F::HEADER_LEN + CRC_LEN <= N,
                "the buffer holds a header and a CRC"
            );
        }
        Self {
            buf: [0; N],
            len: 0,
            ready: 0,
            skipped: 0,
            corrupt: 0,
            framing: PhantomData,
        }
    }

    /// Bytes dropped while searching for a frame: garbage, the first byte of every false start
    /// and of every corrupt frame (wrapping).
    pub const fn skipped(&self) -> u64 {
        self.skipped
    }

    /// Frame starts (sync word and a valid header) whose CRC failed (wrapping).
    pub const fn corrupt(&self) -> u64 {
        self.corrupt
    }

    /// Feeds one byte; returns a frame (sync word to CRC, all checked) if one is complete. The
    /// frame stays in the buffer until the next call. If it returns a frame, call
    /// [`poll`](Self::poll) until `None` before the next byte: a resynchronisation can leave a
    /// second complete frame in the buffer.
    pub fn push(&mut self, byte: u8) -> Option<&[u8]> {
        self.release();
        if self.len >= N {
            // Cannot happen: a candidate never outgrows the longest frame. Drop the oldest byte.
            self.drop_front(1);
            self.skipped = self.skipped.wrapping_add(1);
        }
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = byte;
            self.len += 1;
        }
        self.poll()
    }

    /// Looks for a complete frame in the bytes already fed.
    pub fn poll(&mut self) -> Option<&[u8]> {
        self.release();
        loop {
            match self.candidate() {
                Candidate::Incomplete => return None,
                Candidate::NoFrame => {
                    self.drop_front(1);
                    self.skipped = self.skipped.wrapping_add(1);
                }
                Candidate::Corrupt => {
                    // Resynchronise from the byte after this false or damaged start.
                    self.drop_front(1);
                    self.skipped = self.skipped.wrapping_add(1);
                    self.corrupt = self.corrupt.wrapping_add(1);
                }
                Candidate::Good(len) => {
                    self.ready = len;
                    return self.buf.get(..len);
                }
            }
        }
    }

    fn release(&mut self) {
        if self.ready > 0 {
            self.drop_front(self.ready);
            self.ready = 0;
        }
    }

    fn candidate(&self) -> Candidate {
        let bytes = self.buf.get(..self.len).unwrap_or(&[]);
        for (i, s) in F::SYNC.iter().enumerate() {
            match bytes.get(i) {
                None => return Candidate::Incomplete,
                Some(b) if b != s => return Candidate::NoFrame,
                Some(_) => {}
            }
        }
        let Some(header) = bytes.get(..F::HEADER_LEN) else {
            return Candidate::Incomplete;
        };
        let Some(len) = F::frame_len(header).filter(|&n| n >= F::HEADER_LEN + CRC_LEN && n <= N)
        else {
            return Candidate::NoFrame;
        };
        let Some((body, sent)) = bytes
            .get(..len)
            .and_then(|f| f.split_at_checked(len - CRC_LEN))
        else {
            return Candidate::Incomplete;
        };
        let mut crc = Crc32::new();
        crc.update(body.get(F::SYNC.len()..).unwrap_or(&[]));
        if sent == crc.finish().to_le_bytes() {
            Candidate::Good(len)
        } else {
            Candidate::Corrupt
        }
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }
}
