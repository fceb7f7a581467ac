//! The STM32F407 board binary in CI: a release build and its sizes against budgets derived from
//! the part (no hardware here: this checks that it builds and fits; `cargo xtask ci` lints it with
//! the other target crates).

use anyhow::{Result, bail};
use std::path::PathBuf;

use crate::{TARGET, cargo};

pub const PACKAGE: &str = "tcomp-board-stm32f4";
const BIN: &str = "tcomp-stm32f4";
/// The part's budgets, the same the QEMU build is held to (see `budget.rs`): the stack has the
/// 64 KiB CCM RAM to itself and is measured on the running unit (its boot reports).
use crate::budget::{FLASH_BUDGET, STATIC_RAM_BUDGET};

/// Builds the board binary, prints `BOARD-SUMMARY …` and fails over budget.
pub fn board() -> Result<()> {
    let (flash, static_ram) = sizes()?;
    println!(
        "BOARD-SUMMARY {BIN}: flash {flash} B (budget {FLASH_BUDGET}), static RAM {static_ram} B \
         (budget {STATIC_RAM_BUDGET})"
    );
    if flash > FLASH_BUDGET || static_ram > STATIC_RAM_BUDGET {
        bail!("board binary over budget");
    }
    Ok(())
}

/// Builds the board binary and returns its flash (`.vector_table + .text + .rodata + .data`) and
/// static RAM (`.data + .bss + .uninit`) in bytes.
pub fn sizes() -> Result<(u64, u64)> {
    let common = ["-p", PACKAGE, "--target", TARGET];
    cargo(&[&["build"][..], &common, &["--release"]].concat())?;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let target_dir =
        std::env::var_os("CARGO_TARGET_DIR").map_or(root.join("target"), PathBuf::from);
    let elf = target_dir.join(TARGET).join("release").join(BIN);
    let (flash, static_ram) = crate::elf::flash_and_static_ram(&elf)?;
    Ok((flash, static_ram))
}
