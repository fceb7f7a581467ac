//! Section sizes and addresses of a 32-bit little-endian ELF file (what `size -A` prints), without
//! a tool.

use anyhow::{Context, Result};
use std::path::Path;

fn u16_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from(u16::from_le_bytes(
        b.get(at..at + 2)?.try_into().ok()?,
    )))
}

fn u32_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from(u32::from_le_bytes(
        b.get(at..at + 4)?.try_into().ok()?,
    )))
}

/// `(flash, static RAM)` of a firmware ELF: flash is .vector_table + .text + .rodata + .data (the
/// initial values of .data live in flash), static RAM is .data + .bss + .uninit.
pub fn flash_and_static_ram(path: &Path) -> Result<(u64, u64)> {
    let sizes = sections(path)?;
    let size = |n: &str| {
        sizes
            .iter()
            .filter(|(s, _)| s == n)
            .map(|(_, v)| *v)
            .sum::<u64>()
    };
    let flash = size(".vector_table") + size(".text") + size(".rodata") + size(".data");
    let static_ram = size(".data") + size(".bss") + size(".uninit");
    Ok((flash, static_ram))
}

/// `(name, size)` of every section.
pub fn sections(path: &Path) -> Result<Vec<(String, u64)>> {
    Ok(placed(path)?
        .into_iter()
        .map(|(name, _, size)| (name, size))
        .collect())
}

/// `(name, address, size)` of every section.
pub fn placed(path: &Path) -> Result<Vec<(String, u64, u64)>> {
    let b = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    let bad = || anyhow::anyhow!("{} is not a 32-bit ELF file", path.display());
    if b.get(..5) != Some(&b"\x7fELF\x01"[..]) {
        return Err(bad());
    }
    let shoff = u32_at(&b, 0x20).ok_or_else(bad)? as usize;
    let shentsize = u16_at(&b, 0x2E).ok_or_else(bad)? as usize;
    let shnum = u16_at(&b, 0x30).ok_or_else(bad)? as usize;
    let shstrndx = u16_at(&b, 0x32).ok_or_else(bad)? as usize;
    let header = |i: usize| shoff + i * shentsize;
    let strtab = u32_at(&b, header(shstrndx) + 0x10).ok_or_else(bad)? as usize;
    (0..shnum)
        .map(|i| {
            let name_at = strtab + u32_at(&b, header(i)).ok_or_else(bad)? as usize;
            let name = b.get(name_at..).ok_or_else(bad)?;
            let end = name.iter().position(|&c| c == 0).unwrap_or(0);
            let addr = u32_at(&b, header(i) + 0x0C).ok_or_else(bad)?;
            let size = u32_at(&b, header(i) + 0x14).ok_or_else(bad)?;
            Ok((
                String::from_utf8_lossy(&name[..end]).into_owned(),
                addr,
                size,
            ))
        })
        .collect()
}
