//! The product's application on QEMU's mps2-an386, fed by the replay board: the same RTIC
//! application the STM32F407 binary binds (`tcomp_firmware::application!`), with this board's
//! setup and drivers (`board.rs`, `tcomp_board_qemu::drivers`).
//!
//! The sensors are the replay board's: the vector (loaded into `mps.ram` by QEMU's loader) says
//! what the front ends latched at each timer edge, and which faults to inject, including those of
//! the board itself — a sample that overruns its period, one that overruns past the next timer
//! edge (a whole missed period), a glitch of the latched timestamp, and a hang that the watchdog
//! must end. Frames leave over UART 0 through the application's frame queue and drain; a model
//! update arrives on UART 0's receive interrupt. Semihosting carries only the boot messages, the
//! summary line and the exit code (defmt).
#![no_std]
#![no_main]

mod board;

use defmt_semihosting as _;

tcomp_firmware::application! {
    device: tcomp_board_qemu::device,
    board: crate::board,
    sample: TIMER0,
    drain: UART0TX,
    receive: UART0RX,
    update: UART1RX,
}
