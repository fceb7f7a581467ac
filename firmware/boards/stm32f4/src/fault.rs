//! What survives a reset: the cause read from RCC_CSR, and the last panic or HardFault, kept as a
//! [`FaultRecord`] (format and checks in `tcomp_firmware::fault`, host-tested) in RAM that the
//! start-up code does not initialise.
//!
//! A board in the field has no debugger attached: a semihosting call would itself fault, and a
//! handler that breakpoints would lock the core. So a panic or a HardFault writes the record into
//! `.uninit` (cortex-m-rt leaves that section alone at reset) and resets the chip; the next boot
//! reads it, reports it and clears it.
//!
//! A stack overflow runs off the bottom of the core-coupled RAM into reserved address space: the
//! exception entry itself faults, the core locks up, and the independent watchdog resets it — the
//! next boot reports an IWDG reset with no fault record.

use core::mem::MaybeUninit;
use core::panic::PanicInfo;
use core::ptr::{addr_of, addr_of_mut};
use cortex_m_rt::{ExceptionFrame, exception};
use tcomp_firmware::fault::FaultRecord;

#[unsafe(link_section = ".uninit.tcomp_fault")]
static mut RECORD: MaybeUninit<FaultRecord> = MaybeUninit::uninit();

fn write(record: FaultRecord) {
    // SAFETY: `RECORD` is only touched here and in `take`: at boot before interrupts are enabled, or
    // from a handler that masks interrupts and never returns, so no accesses overlap; a volatile
    // write of a plain-data value into `MaybeUninit` storage is always valid.
    unsafe { core::ptr::write_volatile(addr_of_mut!(RECORD).cast::<FaultRecord>(), record) };
}

/// Reads and clears the previous run's record (call once, at boot); `None` unless it is valid.
pub fn take() -> Option<FaultRecord> {
    // SAFETY: see `write`. `FaultRecord` is `repr(C)` integers and bytes, so every bit pattern —
    // including power-on garbage — is a valid value, which `valid()` then accepts or rejects.
    let r = unsafe { core::ptr::read_volatile(addr_of!(RECORD).cast::<FaultRecord>()) };
    write(FaultRecord::CLEAR);
    r.valid().map(|_| r)
}

fn record_and_reset(record: FaultRecord) -> ! {
    cortex_m::interrupt::disable();
    write(record);
    cortex_m::asm::dsb();
    cortex_m::peripheral::SCB::sys_reset()
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    let (file, line) = info.location().map_or(("", 0), |l| (l.file(), l.line()));
    record_and_reset(FaultRecord::panic(file, line))
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    record_and_reset(FaultRecord::hard_fault(frame.pc(), frame.lr()))
}

/// Why the chip last reset, from RCC_CSR (several flags can be set at once: a pin-reset flag
/// accompanies every reset, so the most telling flag wins).
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
