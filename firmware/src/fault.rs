//! The fault record that survives a reset: its format and checks, apart from where a board keeps it.
//!
//! A board without a debugger cannot report a panic or a HardFault when it happens (semihosting would
//! itself fault), so its handler writes a [`FaultRecord`] into RAM that the start-up code leaves
//! alone (`.uninit`) and resets; the next boot reads it back with [`FaultRecord::valid`], reports it
//! and clears it. Power-on RAM holds garbage, so a record counts only with its magic word and that
//! word's complement in place. Plain data and no `unsafe` here, so the format is tested on the host;
//! the board owns the static and the handlers.

/// Marks a valid record.
pub const MAGIC: u32 = 0x7C0F_A017;
/// Bytes of the source file name kept: the end of the path, where the file name is.
pub const FILE_BYTES: usize = 48;

/// What ended the previous run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum FaultKind {
    /// `panic!` (or an overflow check, an out-of-bounds index, …).
    Panic,
    /// A HardFault (bad address, undefined instruction, escalated bus or usage fault).
    HardFault,
    /// The watchdog expired: its early-warning interrupt wrote the record before the reset.
    Watchdog,
}

/// The record, as it lies in no-init RAM (`repr(C)`, every bit pattern a valid value).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaultRecord {
    magic: u32,
    kind: u32,
    line_or_pc: u32,
    lr: u32,
    file_len: u32,
    file: [u8; FILE_BYTES],
    check: u32,
}

impl FaultRecord {
    /// A record that [`valid`](Self::valid) rejects: what a board writes after reading one.
    pub const CLEAR: Self = Self {
        magic: 0,
        kind: 0,
        line_or_pc: 0,
        lr: 0,
        file_len: 0,
        file: [0; FILE_BYTES],
        check: 0,
    };

    /// A panic at `file:line`; a long path keeps its last [`FILE_BYTES`] bytes (cut at a character
    /// boundary).
    pub fn panic(file: &str, line: u32) -> Self {
        let mut start = file.len().saturating_sub(FILE_BYTES);
        while !file.is_char_boundary(start) {
            start += 1;
        }
        let tail = file.get(start..).unwrap_or("");
        let mut name = [0u8; FILE_BYTES];
        for (d, s) in name.iter_mut().zip(tail.bytes()) {
            *d = s;
        }
        Self {
            magic: MAGIC,
            kind: 1,
            line_or_pc: line,
            lr: 0,
            file_len: tail.len() as u32,
            file: name,
            check: !MAGIC,
        }
    }

    /// A HardFault at `pc`, with the link register `lr`.
    pub fn hard_fault(pc: u32, lr: u32) -> Self {
        Self {
            magic: MAGIC,
            kind: 2,
            line_or_pc: pc,
            lr,
            check: !MAGIC,
            ..Self::CLEAR
        }
    }

    /// The watchdog's early warning (its first expiry) interrupted the loop at `pc`; `lr` as stacked.
    pub fn watchdog(pc: u32, lr: u32) -> Self {
        Self {
            kind: 4,
            ..Self::hard_fault(pc, lr)
        }
    }

    /// The fault, if this is a record and not garbage.
    pub fn valid(&self) -> Option<FaultKind> {
        if self.magic != MAGIC || self.check != !MAGIC {
            return None;
        }
        match self.kind {
            1 => Some(FaultKind::Panic),
            2 => Some(FaultKind::HardFault),
            4 => Some(FaultKind::Watchdog),
            _ => None,
        }
    }

    /// Panic: the source line; HardFault: the faulting PC.
    pub fn line_or_pc(&self) -> u32 {
        self.line_or_pc
    }

    /// HardFault: the LR at the fault; panic: 0.
    pub fn lr(&self) -> u32 {
        self.lr
    }

    /// The end of the panicking source file's path (empty for a HardFault, `?` if garbled).
    pub fn file(&self) -> &str {
        let len = (self.file_len as usize).min(FILE_BYTES);
        core::str::from_utf8(self.file.get(..len).unwrap_or(&[])).unwrap_or("?")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panic_and_hard_fault_records_read_back() {
        let p = FaultRecord::panic("firmware/src/app.rs", 321);
        assert_eq!(p.valid(), Some(FaultKind::Panic));
        assert_eq!(
            (p.file(), p.line_or_pc(), p.lr()),
            ("firmware/src/app.rs", 321, 0)
        );
        let h = FaultRecord::hard_fault(0x0800_1234, 0xFFFF_FFF9);
        assert_eq!(h.valid(), Some(FaultKind::HardFault));
        assert_eq!(
            (h.file(), h.line_or_pc(), h.lr()),
            ("", 0x0800_1234, 0xFFFF_FFF9)
        );
    }

    #[test]
    fn a_watchdog_record_reads_back_as_one() {
        let w = FaultRecord::watchdog(0x1234, 0xFFFF_FFF9);
        assert_eq!(w.valid(), Some(FaultKind::Watchdog));
        assert_eq!((w.line_or_pc(), w.lr()), (0x1234, 0xFFFF_FFF9));
        assert_ne!(w.valid(), FaultRecord::hard_fault(0x1234, 0).valid());
    }

    #[test]
    fn a_long_path_keeps_its_end_on_a_character_boundary() {
        let path = "/home/someone/.cargo/registry/src/index/crate-1.0.0/src/módulo/deep/file.rs";
        let r = FaultRecord::panic(path, 7);
        assert!(r.file().len() <= FILE_BYTES);
        assert!(path.ends_with(r.file()));
        assert!(r.file().ends_with("deep/file.rs"));
    }

    #[test]
    fn garbage_and_cleared_records_are_rejected() {
        assert_eq!(FaultRecord::CLEAR.valid(), None);
        let mut r = FaultRecord::panic("a.rs", 1);
        r.check ^= 1;
        assert_eq!(r.valid(), None);
        let mut r = FaultRecord::hard_fault(0, 0);
        r.kind = 3;
        assert_eq!(r.valid(), None);
        // Power-on RAM: all ones, or a repeating pattern.
        let ones = FaultRecord {
            magic: u32::MAX,
            kind: u32::MAX,
            line_or_pc: u32::MAX,
            lr: u32::MAX,
            file_len: u32::MAX,
            file: [0xFF; FILE_BYTES],
            check: u32::MAX,
        };
        assert_eq!(ones.valid(), None);
        assert_eq!(ones.file(), "?");
    }
}
