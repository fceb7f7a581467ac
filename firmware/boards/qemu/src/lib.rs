//! The QEMU mps2-an386 board: its device module for RTIC ([`device`]: the interrupt lines and the
//! vector table, as a PAC would give them) and its drivers ([`drivers`]: CMSDK timers, UART and
//! watchdog, the model slots' RAM given NOR semantics, the SysTick instruction counter, the
//! semihosting exit). The binaries: `tcomp-qemu` binds the firmware's application to this board
//! and feeds it the replay vector (`src/main.rs`, `src/board.rs`); `smoke` times the RBF evaluator.
#![no_std]

pub mod device;
pub mod drivers;
