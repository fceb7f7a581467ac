//! CRC-32/ISO-HDLC (zip, PNG: reflected polynomial 0xEDB88320), the one checksum of the project:
//! the blob's trailer, the calibration image's header and table, the model slots' headers, the
//! output and boot-report frames, and the serial update's chunks and image.
//!
//! Why one module: the whole-buffer form and the incremental form (a slot's payload read from flash
//! in chunks, an update image checked as its chunks arrive) must agree bit for bit, so both are the
//! same loop. Bit by bit, without a 1 KiB table: every check runs once per load, frame or chunk, so
//! the firmware's flash matters more than the microseconds.

/// CRC-32 fed in pieces, equal to [`crc32`] over their concatenation.
#[derive(Clone, Copy, Debug)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// Nothing fed yet.
    pub const fn new() -> Self {
        Self(!0)
    }

    /// Feeds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u32::from(b);
            for _ in 0..8 {
                self.0 = (self.0 >> 1) ^ (0xEDB8_8320 & (self.0 & 1).wrapping_neg());
            }
        }
    }

    /// The CRC of everything fed.
    pub const fn finish(&self) -> u32 {
        !self.0
    }
}

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.finish()
}
