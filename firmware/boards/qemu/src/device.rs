//! The mps2-an386 as a device crate for RTIC (there is no PAC for it): its interrupt lines, the
//! NVIC's priority bits, and the vector table of its device interrupts.
//!
//! Interrupt numbers are QEMU's `hw/arm/mps2.c` for the AN385/AN386 images: UART *n*'s receive
//! line is `{0, 2, 4, 18, 20}[n]` and its transmit line the next one; CMSDK APB timer 0 is on 8,
//! timer 1 on 9, the dual timer on 10; the UARTs' overflows share 12, the Ethernet controller 13.
//! The watchdog's interrupt is the NMI. Every line of the table points at `DefaultHandler` unless
//! a task binds it (`device.x`, `PROVIDE`), as a PAC's `device.x` does.

use cortex_m::interrupt::InterruptNumber;

/// Priority bits of the NVIC. The Cortex-M4 image of the MPS2 (AN386) implements 3 (CMSIS'
/// `__NVIC_PRIO_BITS` for CMSDK_CM4); QEMU's NVIC keeps 8, and RTIC's priorities, written in the
/// top 3 bits, mean the same in both.
pub const NVIC_PRIO_BITS: u8 = 3;

/// The device interrupts the firmware names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
#[allow(non_camel_case_types)]
pub enum Interrupt {
    /// UART 0 receive (the update link's bytes in).
    UART0RX = 0,
    /// UART 0 transmit (the frame queue's drain).
    UART0TX = 1,
    /// UART 1 receive: no device drives it here; the update task's pended interrupt.
    UART1RX = 2,
    /// UART 1 transmit: unused.
    UART1TX = 3,
    /// CMSDK APB timer 0: the sample timer.
    TIMER0 = 8,
    /// CMSDK APB timer 1: the free-running time base (its interrupt is not used).
    TIMER1 = 9,
}

// SAFETY: each variant is a device interrupt line of mps2-an386 below the NVIC's 32 lines.
unsafe impl InterruptNumber for Interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

/// RTIC's `#device::interrupt` path: the same enum.
pub use self::Interrupt as interrupt;

/// The device's peripherals, as RTIC hands them to `init` (the board's drivers reach the CMSDK
/// registers by address; nothing is owned here).
#[derive(Debug)]
pub struct Peripherals {}

impl Peripherals {
    /// The peripherals, once more.
    ///
    /// # Safety
    /// As any PAC's `steal`: the caller must not create aliasing owners of a peripheral (there is
    /// no state here to alias).
    pub unsafe fn steal() -> Self {
        Self {}
    }
}

/// One vector table entry.
#[repr(C)]
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: usize,
}

unsafe extern "C" {
    fn UART0RX();
    fn UART0TX();
    fn UART1RX();
    fn UART1TX();
    fn TIMER0();
    fn TIMER1();
    fn DefaultHandler();
}

/// The device's part of the vector table: 32 lines (cortex-m-rt's `device` feature links it after
/// the 16 system exceptions).
#[unsafe(link_section = ".vector_table.interrupts")]
#[unsafe(no_mangle)]
pub static __INTERRUPTS: [Vector; 32] = {
    let mut t = [const {
        Vector {
            handler: DefaultHandler,
        }
    }; 32];
    t[0] = Vector { handler: UART0RX };
    t[1] = Vector { handler: UART0TX };
    t[2] = Vector { handler: UART1RX };
    t[3] = Vector { handler: UART1TX };
    t[8] = Vector { handler: TIMER0 };
    t[9] = Vector { handler: TIMER1 };
    t
};
