//! Text into a caller's buffer, `snprintf`-style: as much as fits, always NUL-terminated when the
//! buffer has a byte at all, and the full length returned so the caller can retry with a bigger
//! buffer. The text itself always comes from the core's `Display` implementations or tables.

use core::fmt::{self, Write};

/// A `fmt::Write` over a byte buffer that truncates and counts.
pub(crate) struct CBuf<'a> {
    buf: &'a mut [u8],
    /// Bytes the whole text needs (without the NUL).
    needed: usize,
}

impl<'a> CBuf<'a> {
    /// Over `buf` (may be empty: then only the length is counted).
    pub(crate) fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, needed: 0 }
    }

    /// Writes the terminating NUL (after the last byte that fitted) and returns the full length.
    pub(crate) fn finish(self) -> usize {
        let cap = self.buf.len();
        if cap > 0 {
            let at = self.needed.min(cap - 1);
            if let Some(b) = self.buf.get_mut(at) {
                *b = 0;
            }
        }
        self.needed
    }
}

impl Write for CBuf<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        // Keep the last byte for the NUL.
        let room = self.buf.len().saturating_sub(1);
        for (i, &b) in s.as_bytes().iter().enumerate() {
            let at = self.needed + i;
            if at < room
                && let Some(slot) = self.buf.get_mut(at)
            {
                *slot = b;
            }
        }
        self.needed += s.len();
        Ok(())
    }
}

/// Writes `value`'s `Display` into `buf`; the full length.
pub(crate) fn display(buf: &mut [u8], value: &dyn fmt::Display) -> usize {
    let mut w = CBuf::new(buf);
    // `CBuf` never fails; a `Display` that does would leave a shorter text, which is all we can do.
    let _ = write!(w, "{value}");
    w.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncates_terminates_and_counts() {
        let mut b = [0xAAu8; 5];
        assert_eq!(display(&mut b, &"abcdefg"), 7);
        assert_eq!(&b, b"abcd\0");
        let mut b = [0xAAu8; 8];
        assert_eq!(display(&mut b, &"abc"), 3);
        assert_eq!(&b[..4], b"abc\0");
        assert_eq!(display(&mut [], &"abc"), 3);
        let mut one = [0xAAu8; 1];
        assert_eq!(display(&mut one, &"abc"), 3);
        assert_eq!(one, [0]);
    }
}
