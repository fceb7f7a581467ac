//! The firmware's budgets, from the part both boards stand for: the STM32F407 (168 MHz Cortex-M4F,
//! 128 KiB SRAM + 64 KiB CCM, 1 MiB flash in one bank) at the loop's 200 Hz. One place, so the
//! QEMU run (`qemu.rs`) and the board binary's check (`board.rs`) hold the two builds of the one
//! application to the same numbers, each with its margin stated here.

/// The core's clock, Hz.
pub const CORE_HZ: u64 = 168_000_000;
/// The loop's rate, Hz.
pub const SAMPLE_HZ: u64 = 200;

/// CPU: the sample task may take at most a quarter of its 5 ms period, 210,000 core cycles: the
/// rest of the period belongs to the tasks below it (the drain: about 10 % of the CPU while the
/// line is full; the update task's chunk programs) and the margin for the sensors' SPI reads on
/// the board, which QEMU does not time.
pub const SAMPLE_TASK_CYCLES: u64 = CORE_HZ / SAMPLE_HZ / 4;
/// QEMU counts instructions; an M4F at 168 MHz with 5 flash wait states retires straight-line
/// code from the ART accelerator at about one per cycle, loads and branches cost 2–3, the FPU's
/// divide and square root 14: counted at 2 cycles per instruction.
pub const CYCLES_PER_INSTRUCTION: u64 = 2;
/// The sample task's budget in QEMU's instructions: 105,000. The receive path's worst latency
/// follows from it: the update task, pended every period, reads the ring within one period plus
/// the sample task's worst (5 ms + 1.25 ms), 576 bytes of a 921,600-baud line, well inside the
/// 2 KiB ring.
pub const SAMPLE_TASK_INSTRUCTIONS: u64 = SAMPLE_TASK_CYCLES / CYCLES_PER_INSTRUCTION;

/// Channels of the largest board description shipped (the IMU6: three gyros, three
/// accelerometers).
pub const MAX_CHANNELS: u64 = 6;
/// One RBF evaluation at the firmware's capacity (32 centers × 4 features, joint or additive): half
/// the sample task's budget shared by the largest board's channels, 8,750 instructions; the other
/// half is the feature programs, the drivers' reads and the output frames (measured 10–11 k of the
/// task's 105 k for six channels in the QEMU replay).
pub const RBF_EVAL_INSTRUCTIONS: u64 = SAMPLE_TASK_INSTRUCTIONS / 2 / MAX_CHANNELS;

/// The SRAM (SRAM1 + SRAM2, contiguous: statics) and the CCM (the stack alone), bytes.
pub const SRAM: u64 = 128 * 1024;
/// See [`SRAM`].
pub const CCM: u64 = 64 * 1024;
/// Static RAM (`.data + .bss + .uninit`) and the stack may each use three quarters of their
/// region; a quarter is kept for what comes next (more channels or larger models, the ring or
/// queue grown) and the stack painting's granularity. Both boards' builds are held to it.
pub const STATIC_RAM_BUDGET: u64 = SRAM * 3 / 4;
/// See [`STATIC_RAM_BUDGET`].
pub const STACK_BUDGET: u64 = CCM * 3 / 4;
/// Flash for the firmware: 1 MiB less sectors 10 and 11 (2 × 128 KiB), the two model slots.
pub const FLASH_BUDGET: u64 = (1024 - 256) * 1024;

#[cfg(test)]
mod tests {
    use super::*;

    /// The figures the docs state (BENCHMARKS.md, firmware/README.md) are these constants'.
    #[test]
    fn the_stated_figures_are_the_constants() {
        assert_eq!(SAMPLE_TASK_CYCLES, 210_000);
        assert_eq!(SAMPLE_TASK_INSTRUCTIONS, 105_000);
        assert_eq!(STATIC_RAM_BUDGET, 98_304);
        assert_eq!(STACK_BUDGET, 49_152);
        assert_eq!(FLASH_BUDGET, 786_432);
        assert_eq!(RBF_EVAL_INSTRUCTIONS, 8_750);
    }
}
