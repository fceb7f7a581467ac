//! Board support of the QEMU mps2-an386 target: the SysTick instruction counter and semihosting exit.

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;

/// Instructions per SysTick tick on mps2-an386 under `-icount shift=0` (1 GHz virtual / 25 MHz).
pub const INSTRUCTIONS_PER_TICK: u32 = 40;

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

    /// Instructions elapsed from `start` to `end` (one wrap at most).
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
