//! The QEMU mps2-an386 board's drivers: the few CMSDK peripherals the application drives, by their
//! registers (there is no PAC for this board), plus the SysTick instruction counter and the
//! semihosting exit. Everything else — the tasks, the loop, the frames, the time-base check, the
//! fault record — is the firmware library's and shared with the STM32F407 board.
//!
//! The `MODELS` region's RAM gets NOR flash semantics ([`RamFlash`]) for the model slots' update.
//!
//! Addresses and interrupt lines are QEMU 7.2's `hw/arm/mps2.c` for the AN385/AN386 images: CMSDK
//! APB timer 0 at `0x4000_0000` on IRQ 8, timer 1 at `0x4000_1000` on IRQ 9 (both clocked from the
//! 25 MHz system clock), UART0 at `0x4000_4000` (QEMU's first `-serial`; receive IRQ 0), and the CMSDK APB watchdog
//! at `0x4000_8000` whose interrupt is the NMI and whose second expiry resets the system (QEMU
//! restarts the guest unless `-no-reboot` is given; RAM outside the loaded images survives).

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use tcomp_firmware::application::SerialTx;
use tcomp_firmware::slots::MappedFlash;

/// Instructions per SysTick tick on mps2-an386 under `-icount shift=0` (1 GHz virtual / 25 MHz).
pub const INSTRUCTIONS_PER_TICK: u32 = 40;
/// The board's peripheral clock.
pub const SYSCLK_HZ: u32 = 25_000_000;

/// Received bytes the receive ring had no room for.
static RX_LOST: AtomicU32 = AtomicU32::new(0);

/// Counts a received byte the ring had no room for.
pub fn count_rx_lost() {
    RX_LOST.fetch_add(1, Ordering::Relaxed);
}

/// Received bytes the ring had no room for, so far.
pub fn rx_lost() -> u32 {
    RX_LOST.load(Ordering::Relaxed)
}

fn write(addr: usize, value: u32) {
    // SAFETY: `addr` is a register of a CMSDK peripheral of this board (the constants below), which
    // is always mapped; a register write has no effect on Rust-visible memory.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

fn read(addr: usize) -> u32 {
    // SAFETY: as in `write`; reading these registers has no side effect the code relies on.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

/// A CMSDK APB timer: a 32-bit down-counter reloading from `RELOAD`, interrupting at zero.
pub struct Timer {
    base: usize,
}

impl Timer {
    const CTRL: usize = 0x00;
    const VALUE: usize = 0x04;
    const RELOAD: usize = 0x08;
    const INTCLEAR: usize = 0x0C;
    const CTRL_ENABLE: u32 = 1;
    const CTRL_IRQ_ENABLE: u32 = 1 << 3;

    /// Timer 0, the sample timer (IRQ [`TIMER0_IRQ`]).
    pub const fn timer0() -> Self {
        Self { base: 0x4000_0000 }
    }

    /// Timer 1, free-running as the time base.
    pub const fn timer1() -> Self {
        Self { base: 0x4000_1000 }
    }

    /// Starts counting `ticks` per period; with `irq`, interrupting at the end of each.
    pub fn start(&self, ticks: u32, irq: bool) {
        write(self.base + Self::CTRL, 0);
        write(self.base + Self::RELOAD, ticks - 1);
        write(self.base + Self::VALUE, ticks - 1);
        write(self.base + Self::INTCLEAR, 1);
        let ctrl = Self::CTRL_ENABLE | if irq { Self::CTRL_IRQ_ENABLE } else { 0 };
        write(self.base + Self::CTRL, ctrl);
    }

    /// Stops the timer.
    pub fn stop(&self) {
        write(self.base + Self::CTRL, 0);
    }

    /// Acknowledges the interrupt.
    pub fn clear(&self) {
        write(self.base + Self::INTCLEAR, 1);
    }

    /// The counter (counts down).
    pub fn value(&self) -> u32 {
        read(self.base + Self::VALUE)
    }
}

/// Timer 1 free-running from `0xFFFF_FFFF` down, read as elapsed ticks (wraps after 171 s; one
/// wrap between two reads is handled by wrapping subtraction).
pub struct TimeBase {
    timer: Timer,
}

impl TimeBase {
    /// Starts timer 1 free-running.
    pub fn start() -> Self {
        let timer = Timer::timer1();
        write(timer.base + Timer::CTRL, 0);
        write(timer.base + Timer::RELOAD, u32::MAX);
        write(timer.base + Timer::VALUE, u32::MAX);
        write(timer.base + Timer::CTRL, Timer::CTRL_ENABLE);
        Self { timer }
    }

    /// Ticks since start (modulo 2³²).
    pub fn now(&self) -> u32 {
        u32::MAX - self.timer.value()
    }
}

/// CMSDK APB UART 0, polled: QEMU sends each byte to its `-serial` backend at once, and holds
/// received bytes back until the one-byte receive buffer has been read (nothing is lost).
pub struct Uart {
    base: usize,
}

impl Uart {
    const DATA: usize = 0x00;
    const STATE: usize = 0x04;
    const CTRL: usize = 0x08;
    const BAUDDIV: usize = 0x10;
    const STATE_TX_FULL: u32 = 1;
    const STATE_RX_FULL: u32 = 1 << 1;
    const INTCLEAR: usize = 0x0C;
    const CTRL_TX_ENABLE: u32 = 1;
    const CTRL_RX_ENABLE: u32 = 1 << 1;
    const CTRL_RX_IRQ_ENABLE: u32 = 1 << 3;
    const INT_RX: u32 = 1 << 1;

    /// UART 0 with its transmitter and receiver enabled (no interrupts yet).
    pub fn uart0() -> Self {
        let u = Self::handle0();
        // 25 MHz / 217 ≈ 115,200 Bd on the real board; QEMU needs a divider of at least 16.
        write(u.base + Self::BAUDDIV, 217);
        write(
            u.base + Self::CTRL,
            Self::CTRL_TX_ENABLE | Self::CTRL_RX_ENABLE,
        );
        u
    }

    /// UART 0 as configured by [`Uart::uart0`], without touching its registers: the receive
    /// interrupt's handle.
    pub const fn handle0() -> Self {
        Self { base: 0x4000_4000 }
    }

    /// Raises UART 0's receive interrupt for every received byte (until cleared).
    pub fn enable_rx_interrupt(&self) {
        let ctrl = read(self.base + Self::CTRL);
        write(self.base + Self::CTRL, ctrl | Self::CTRL_RX_IRQ_ENABLE);
    }

    /// Acknowledges the receive interrupt (a byte received afterwards raises it again).
    pub fn clear_rx_interrupt(&self) {
        write(self.base + Self::INTCLEAR, Self::INT_RX);
    }

    /// The received byte, if one is waiting.
    pub fn read(&self) -> Option<u8> {
        if read(self.base + Self::STATE) & Self::STATE_RX_FULL == 0 {
            return None;
        }
        Some(read(self.base + Self::DATA) as u8)
    }
}

/// UART 0's transmitter, as the application's drain writes it: a byte whenever its one-byte buffer
/// is free, the transmit interrupt (IRQ 1) on while bytes wait.
pub struct UartTx {
    base: usize,
}

impl UartTx {
    const CTRL_TX_IRQ_ENABLE: u32 = 1 << 2;
    const INT_TX: u32 = 1;

    /// UART 0's transmitter (configured by [`Uart::uart0`]).
    pub const fn uart0() -> Self {
        Self { base: 0x4000_4000 }
    }
}

impl SerialTx for UartTx {
    fn ready(&mut self) -> bool {
        read(self.base + Uart::STATE) & Uart::STATE_TX_FULL == 0
    }

    fn write(&mut self, byte: u8) {
        write(self.base + Uart::DATA, u32::from(byte));
    }

    fn listen(&mut self, on: bool) {
        // Acknowledge the "byte sent" interrupt first: with the interrupt on, the next byte sent
        // raises it again.
        write(self.base + Uart::INTCLEAR, Self::INT_TX);
        let ctrl = read(self.base + Uart::CTRL);
        let ctrl = if on {
            ctrl | Self::CTRL_TX_IRQ_ENABLE
        } else {
            ctrl & !Self::CTRL_TX_IRQ_ENABLE
        };
        write(self.base + Uart::CTRL, ctrl);
    }
}

/// The QEMU board's model "flash": the `MODELS` region of mps2-an386's SSRAM (RAM in QEMU), given
/// NOR semantics so the update code runs as on a part: an erase sets a whole slot-sized sector to
/// 0xFF, a program writes 4-byte words and can only clear bits.
pub struct RamFlash {
    base: usize,
    len: usize,
}

/// The erase unit: one slot (`tcomp_firmware::slots::QEMU_LAYOUT`).
const RAM_FLASH_SECTOR: usize = 32 * 1024;

impl RamFlash {
    /// The flash over `[base, base + len)`.
    ///
    /// # Safety
    /// The range must be the `MODELS` region (mapped, word aligned, RAM-backed under QEMU), and no
    /// Rust reference may be alive over the part of it this flash erases or programs while it does
    /// (the loop's models borrow only the active slot, which the update never writes).
    pub unsafe fn new(base: *const u8, len: usize) -> Self {
        Self {
            base: base as usize,
            len,
        }
    }

    /// The bytes `[offset, offset + len)` for the rest of the run: the loop's models borrow the
    /// active slot's payload this way. Empty outside the region.
    ///
    /// # Safety
    /// Nothing may erase or program the range for the rest of the run (the active slot's payload:
    /// an update writes only the other slot).
    pub unsafe fn map_static(&self, offset: u32, len: u32) -> &'static [u8] {
        match (offset as usize).checked_add(len as usize) {
            // SAFETY: inside the region, which `new`'s contract keeps mapped; the caller's
            // contract keeps it unwritten.
            Some(end) if end <= self.len => unsafe {
                core::slice::from_raw_parts(
                    (self.base + offset as usize) as *const u8,
                    len as usize,
                )
            },
            _ => &[],
        }
    }

    fn check(&self, offset: u32, len: usize, align: usize) -> Result<usize, NorFlashErrorKind> {
        let at = offset as usize;
        if !at.is_multiple_of(align) || !len.is_multiple_of(align) {
            return Err(NorFlashErrorKind::NotAligned);
        }
        match at.checked_add(len) {
            Some(end) if end <= self.len => Ok(self.base + at),
            _ => Err(NorFlashErrorKind::OutOfBounds),
        }
    }
}

impl MappedFlash for RamFlash {
    fn mapped(&self, offset: u32, len: u32) -> Option<&[u8]> {
        let end = (offset as usize).checked_add(len as usize)?;
        if end > self.len {
            return None;
        }
        // SAFETY: inside the region (checked), which `new`'s contract keeps mapped; the slice
        // borrows `self`, so no erase or program (`&mut self`) happens while it lives.
        Some(unsafe {
            core::slice::from_raw_parts((self.base + offset as usize) as *const u8, len as usize)
        })
    }
}

impl ErrorType for RamFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        let at = self.check(offset, bytes.len(), 1)?;
        for (i, b) in bytes.iter_mut().enumerate() {
            // SAFETY: inside the region (checked above).
            *b = unsafe { core::ptr::read_volatile((at + i) as *const u8) };
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.len
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = RAM_FLASH_SECTOR;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), NorFlashErrorKind> {
        let len = (to as usize)
            .checked_sub(from as usize)
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        let at = self.check(from, len, RAM_FLASH_SECTOR)?;
        for p in (at..at + len).step_by(4) {
            // SAFETY: a word inside the region (checked, sector aligned); no reference over it is
            // alive (`new`'s contract).
            unsafe { core::ptr::write_volatile(p as *mut u32, u32::MAX) };
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        let at = self.check(offset, bytes.len(), 4)?;
        for (i, w) in bytes.chunks_exact(4).enumerate() {
            let word: [u8; 4] = w.try_into().map_err(|_| NorFlashErrorKind::NotAligned)?;
            let p = (at + 4 * i) as *mut u32;
            // SAFETY: a word inside the region (checked, word aligned); no reference over it is
            // alive (`new`'s contract). NOR: a program only clears bits.
            unsafe {
                let old = core::ptr::read_volatile(p);
                core::ptr::write_volatile(p, old & u32::from_le_bytes(word));
            }
        }
        Ok(())
    }
}

/// The CMSDK APB watchdog: interrupt (NMI) at the first expiry, reset at the second.
pub struct Watchdog {
    base: usize,
}

impl Watchdog {
    const LOAD: usize = 0x00;
    const CONTROL: usize = 0x08;
    const INTCLR: usize = 0x0C;
    const LOCK: usize = 0xC00;
    const UNLOCK: u32 = 0x1ACC_E551;
    const CONTROL_INTEN: u32 = 1;
    const CONTROL_RESEN: u32 = 1 << 1;

    /// Starts the watchdog with `ticks` of the 25 MHz clock to each expiry, and locks it.
    pub fn start(ticks: u32) -> Self {
        let w = Self { base: 0x4000_8000 };
        write(w.base + Self::LOCK, Self::UNLOCK);
        write(w.base + Self::LOAD, ticks);
        write(
            w.base + Self::CONTROL,
            Self::CONTROL_INTEN | Self::CONTROL_RESEN,
        );
        write(w.base + Self::LOCK, 0);
        w
    }

    /// Reloads the counter (and clears a pending early warning).
    pub fn feed(&self) {
        write(self.base + Self::LOCK, Self::UNLOCK);
        write(self.base + Self::INTCLR, 1);
        write(self.base + Self::LOCK, 0);
    }

    /// Stops it (at the end of the run), whoever holds its handle.
    pub fn stop_any() {
        let base = 0x4000_8000;
        write(base + Self::LOCK, Self::UNLOCK);
        write(base + Self::CONTROL, 0);
        write(base + Self::LOCK, 0);
    }
}

/// Free-running SysTick used as an instruction counter.
pub struct InstructionCounter {
    syst: SYST,
}

impl InstructionCounter {
    /// Starts SysTick counting down from its 24-bit maximum.
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        Self { syst }
    }

    /// The current tick count (counts down, wraps every 2^24 ticks).
    pub fn now(&self) -> u32 {
        SYST::get_current()
    }

    /// SysTick ticks from `start` to `end` (one wrap at most).
    pub fn ticks_between(&self, start: u32, end: u32) -> u32 {
        start.wrapping_sub(end) & 0x00FF_FFFF
    }

    /// Instructions elapsed from `start` to `end` (one wrap at most) under `-icount shift=0`.
    pub fn instructions_between(&self, start: u32, end: u32) -> u32 {
        let ticks = start.wrapping_sub(end) & 0x00FF_FFFF;
        ticks.saturating_mul(INSTRUCTIONS_PER_TICK)
    }

    /// Gives SysTick back.
    pub fn free(self) -> SYST {
        self.syst
    }
}

/// Ends the QEMU run: exit code 0 when `ok`, 1 otherwise.
pub fn exit(ok: bool) -> ! {
    use cortex_m_semihosting::debug;
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}
