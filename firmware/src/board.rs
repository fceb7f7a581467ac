//! The QEMU mps2-an386 board layer: the few CMSDK peripherals the replay binary drives, by their
//! registers (there is no PAC for this board), plus the SysTick instruction counter and the
//! semihosting exit. Everything else — the loop, the frames, the time-base check, the fault record —
//! is the library's and shared with the STM32F407 board.
//!
//! Addresses and interrupt lines are QEMU 7.2's `hw/arm/mps2.c` for the AN385/AN386 images: CMSDK
//! APB timer 0 at `0x4000_0000` on IRQ 8, timer 1 at `0x4000_1000` on IRQ 9 (both clocked from the
//! 25 MHz system clock), UART0 at `0x4000_4000` (QEMU's first `-serial`), and the CMSDK APB watchdog
//! at `0x4000_8000` whose interrupt is the NMI and whose second expiry resets the system (QEMU
//! restarts the guest unless `-no-reboot` is given; RAM outside the loaded images survives).

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;

/// Instructions per SysTick tick on mps2-an386 under `-icount shift=0` (1 GHz virtual / 25 MHz).
pub const INSTRUCTIONS_PER_TICK: u32 = 40;
/// The board's peripheral clock.
pub const SYSCLK_HZ: u32 = 25_000_000;
/// IRQ number of CMSDK timer 0 (the sample timer).
pub const TIMER0_IRQ: i16 = 8;

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

/// CMSDK APB UART 0, transmit only, polled: QEMU sends each byte to its `-serial` backend at once.
pub struct Uart {
    base: usize,
}

impl Uart {
    const DATA: usize = 0x00;
    const STATE: usize = 0x04;
    const CTRL: usize = 0x08;
    const BAUDDIV: usize = 0x10;
    const STATE_TX_FULL: u32 = 1;
    const CTRL_TX_ENABLE: u32 = 1;

    /// UART 0 with its transmitter enabled.
    pub fn uart0() -> Self {
        let u = Self { base: 0x4000_4000 };
        // 25 MHz / 217 ≈ 115,200 Bd on the real board; QEMU needs a divider of at least 16.
        write(u.base + Self::BAUDDIV, 217);
        write(u.base + Self::CTRL, Self::CTRL_TX_ENABLE);
        u
    }

    /// Sends `bytes`, waiting for room before each.
    pub fn write_all(&self, bytes: &[u8]) {
        for &b in bytes {
            while read(self.base + Self::STATE) & Self::STATE_TX_FULL != 0 {}
            write(self.base + Self::DATA, u32::from(b));
        }
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

    /// Stops it (at the end of the run).
    pub fn stop(&self) {
        write(self.base + Self::LOCK, Self::UNLOCK);
        write(self.base + Self::CONTROL, 0);
        write(self.base + Self::LOCK, 0);
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
