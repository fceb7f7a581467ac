//! What survives a reset: the cause read from RCC_CSR, and the location of the last panic or
//! HardFault, kept in RAM that the start-up code does not initialise.
//!
//! A board in the field has no debugger attached: a semihosting call would itself fault, and a
//! `panic-probe`-style handler that breakpoints would lock the core. So a panic or a HardFault writes
//! a small record into `.uninit` (cortex-m-rt leaves that section alone at reset) and resets the
//! chip; the next boot reads the record, reports it over defmt and the reset-cause line, and clears
//! it. The record has a magic word and its complement so that power-on garbage is not taken for a
//! fault.
//!
//! A stack overflow runs off the bottom of the core-coupled RAM into reserved address space: the
//! exception entry itself faults, the core locks up, and the independent watchdog resets it — the
//! next boot reports an IWDG reset with no fault record.

use core::mem::MaybeUninit;
use core::panic::PanicInfo;
use core::ptr::{addr_of, addr_of_mut};
use cortex_m_rt::{ExceptionFrame, exception};

/// Marks a valid record.
const MAGIC: u32 = 0x7C0F_A017;
/// Bytes of the source file name kept (the end of the path).
const FILE_BYTES: usize = 48;

/// What ended the previous run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
#[repr(u32)]
pub enum FaultKind {
    /// `panic!` (or an arithmetic overflow check, an out-of-bounds index, …).
    Panic = 1,
    /// A HardFault (bad address, undefined instruction, escalated bus or usage fault).
    HardFault = 2,
}

/// The no-init record.
#[repr(C)]
#[derive(Clone, Copy)]
struct Record {
    magic: u32,
    kind: u32,
    /// Panic: source line; HardFault: the faulting PC.
    line_or_pc: u32,
    /// HardFault: LR at the fault; panic: 0.
    lr: u32,
    file_len: u32,
    file: [u8; FILE_BYTES],
    /// `!magic`, written last.
    check: u32,
}

#[unsafe(link_section = ".uninit.tcomp_fault")]
static mut RECORD: MaybeUninit<Record> = MaybeUninit::uninit();

/// A fault recorded by the previous run.
#[derive(Clone, Copy, Debug)]
pub struct Fault {
    /// Panic or HardFault.
    pub kind: FaultKind,
    /// Panic: source line; HardFault: PC.
    pub line_or_pc: u32,
    /// HardFault: LR.
    pub lr: u32,
    file: [u8; FILE_BYTES],
    file_len: usize,
}

impl Fault {
    /// The end of the panicking source file's path (empty for a HardFault).
    pub fn file(&self) -> &str {
        let bytes = self.file.get(..self.file_len).unwrap_or(&[]);
        core::str::from_utf8(bytes).unwrap_or("?")
    }
}

fn write(record: Record) {
    // SAFETY: `RECORD` is only touched here and in `take`, each time with interrupts masked or from a
    // handler that never returns, so no other access overlaps; a volatile write of a plain-data value
    // into `MaybeUninit` storage is always valid.
    unsafe { core::ptr::write_volatile(addr_of_mut!(RECORD).cast::<Record>(), record) };
}

/// Reads and clears the previous run's record (call once, at boot).
pub fn take() -> Option<Fault> {
    // SAFETY: see `write`; every bit pattern is a valid `Record` (plain integers and bytes), so reading
    // uninitialised-at-power-on RAM yields some value, which the magic check then rejects.
    let r = unsafe { core::ptr::read_volatile(addr_of!(RECORD).cast::<Record>()) };
    write(Record {
        magic: 0,
        check: 0,
        ..r
    });
    if r.magic != MAGIC || r.check != !MAGIC {
        return None;
    }
    let kind = match r.kind {
        1 => FaultKind::Panic,
        2 => FaultKind::HardFault,
        _ => return None,
    };
    Some(Fault {
        kind,
        line_or_pc: r.line_or_pc,
        lr: r.lr,
        file: r.file,
        file_len: (r.file_len as usize).min(FILE_BYTES),
    })
}

/// Records `kind` and resets the chip.
fn record_and_reset(kind: FaultKind, line_or_pc: u32, lr: u32, file: &str) -> ! {
    cortex_m::interrupt::disable();
    let tail = file
        .len()
        .checked_sub(FILE_BYTES)
        .and_then(|start| file.get(start..))
        .unwrap_or(file);
    let mut name = [0u8; FILE_BYTES];
    for (d, s) in name.iter_mut().zip(tail.bytes()) {
        *d = s;
    }
    write(Record {
        magic: MAGIC,
        kind: kind as u32,
        line_or_pc,
        lr,
        file_len: tail.len().min(FILE_BYTES) as u32,
        file: name,
        check: !MAGIC,
    });
    cortex_m::asm::dsb();
    cortex_m::peripheral::SCB::sys_reset()
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    let (file, line) = info.location().map_or(("", 0), |l| (l.file(), l.line()));
    record_and_reset(FaultKind::Panic, line, 0, file)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    record_and_reset(FaultKind::HardFault, frame.pc(), frame.lr(), "")
}

/// Why the chip last reset, from RCC_CSR (several flags can be set at once; the most telling wins).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ResetCause {
    /// Low-power management reset.
    LowPower,
    /// Window watchdog.
    WindowWatchdog,
    /// Independent watchdog: the loop stopped feeding it (a hang, a lock-up, a stack overflow).
    IndependentWatchdog,
    /// Software reset: after a recorded panic or HardFault, or a deliberate reset.
    Software,
    /// Power-on or power-down reset.
    PowerOn,
    /// Brown-out.
    BrownOut,
    /// The NRST pin (a reset button or a debugger).
    Pin,
    /// No flag set.
    Unknown,
}

/// Reads the reset flags and clears them, so the next boot sees only its own cause.
pub fn reset_cause(rcc: &stm32f4xx_hal::pac::RCC) -> ResetCause {
    let csr = rcc.csr().read();
    let cause = if csr.lpwrrstf().bit_is_set() {
        ResetCause::LowPower
    } else if csr.wwdgrstf().bit_is_set() {
        ResetCause::WindowWatchdog
    } else if csr.wdgrstf().bit_is_set() {
        ResetCause::IndependentWatchdog
    } else if csr.sftrstf().bit_is_set() {
        ResetCause::Software
    } else if csr.porrstf().bit_is_set() {
        ResetCause::PowerOn
    } else if csr.borrstf().bit_is_set() {
        ResetCause::BrownOut
    } else if csr.padrstf().bit_is_set() {
        ResetCause::Pin
    } else {
        ResetCause::Unknown
    };
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    cause
}
