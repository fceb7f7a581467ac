//! The STM32F407 board binary in CI: a release build and its sizes against budgets derived from
//! the part (no hardware here: this checks that it builds and fits; `cargo xtask ci` lints it with
//! the other target crates).

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

use crate::{TARGET, cargo};

pub const PACKAGE: &str = "tcomp-board-stm32f4";
const BIN: &str = "tcomp-stm32f4";
/// The part's budgets, the same the QEMU build is held to (see `budget.rs`): the stack has the
/// 64 KiB CCM RAM to itself and is measured on the running unit (its boot reports).
use crate::budget::{FLASH_BUDGET, STATIC_RAM_BUDGET};

/// Builds the board binary, checks that it links the root `memory.x`, prints `BOARD-SUMMARY …` and
/// fails over budget.
pub fn board() -> Result<()> {
    let (flash, static_ram) = sizes()?;
    links_root_memory_x(&elf())?;
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
    let (flash, static_ram) = crate::elf::flash_and_static_ram(&elf())?;
    Ok((flash, static_ram))
}

/// The board binary's release ELF.
fn elf() -> PathBuf {
    crate::qemu::target_dir()
        .join(TARGET)
        .join("release")
        .join(BIN)
}

/// `(name, origin, length)` of each region of a linker script's `MEMORY` block (`NAME : ORIGIN =
/// 0x…, LENGTH = N` or `NK`).
fn regions(script: &str) -> Vec<(String, u64, u64)> {
    let number = |s: &str| {
        let s = s.trim().trim_end_matches(',');
        let (digits, scale) = match s.strip_suffix('K') {
            Some(k) => (k, 1024),
            None => (s, 1),
        };
        let v = match digits.strip_prefix("0x") {
            Some(hex) => u64::from_str_radix(&hex.replace('_', ""), 16).ok()?,
            None => digits.parse().ok()?,
        };
        Some(v * scale)
    };
    script
        .lines()
        .filter_map(|l| {
            let (name, rest) = l.split_once(':')?;
            let origin = rest.split("ORIGIN =").nth(1)?.split(',').next()?;
            let length = rest.split("LENGTH =").nth(1)?;
            Some((name.trim().to_owned(), number(origin)?, number(length)?))
        })
        .collect()
}

/// The binary's sections lie where the repository root's `memory.x` puts them: the vector table
/// at the start of its FLASH, code and constants inside FLASH, statics inside RAM. The QEMU
/// board's map (flash at 0) would fail the first.
fn links_root_memory_x(elf: &Path) -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let script = std::fs::read_to_string(root.join("memory.x"))?;
    let regions = regions(&script);
    let region = |name: &str| {
        regions
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|&(_, o, l)| (o, l))
            .with_context(|| format!("memory.x has no {name} region"))
    };
    let (flash, ram) = (region("FLASH")?, region("RAM")?);
    let sections = crate::elf::placed(elf)?;
    let inside = |(o, l): (u64, u64), at: u64, size: u64| at >= o && at + size <= o + l;
    for (name, at, size) in &sections {
        let home = match name.as_str() {
            ".vector_table" | ".text" | ".rodata" => flash,
            ".data" | ".bss" | ".uninit" => ram,
            _ => continue,
        };
        if !inside(home, *at, *size) || (name == ".vector_table" && *at != flash.0) {
            bail!(
                "{}: {name} at {at:#x} ({size} B) is not where the root memory.x puts it \
                 (FLASH {:#x}+{:#x}, RAM {:#x}+{:#x})",
                elf.display(),
                flash.0,
                flash.1,
                ram.0,
                ram.1
            );
        }
    }
    if !sections.iter().any(|(n, _, _)| n == ".vector_table") {
        bail!("{}: no .vector_table section", elf.display());
    }
    println!(
        "board: the binary links the root memory.x (FLASH {:#x}, RAM {:#x})",
        flash.0, ram.0
    );
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn regions_read_the_root_memory_x() {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
        let script = std::fs::read_to_string(root.join("memory.x")).unwrap();
        let r = regions(&script);
        assert_eq!(r[0], ("FLASH".to_owned(), 0x0800_0000, 768 * 1024));
        assert!(
            r.iter()
                .any(|x| *x == ("RAM".to_owned(), 0x2000_0000, 128 * 1024))
        );
        assert_eq!(r.len(), 4);
    }
}
