//! The QEMU replay's host side, as a library `cargo xtask qemu` calls: the vectors (inputs, the host
//! loop's outputs and frames: [`vector`]), the runs' inputs with their injected faults
//! ([`scenario`]), and the checks of a run against the host ([`checks`]). The xtask only
//! orchestrates (build, simulate, fit, run QEMU, compare against budgets).

pub mod checks;
pub mod scenario;
pub mod vector;

/// The number after `key` in `text` (the firmware's `KEY=VALUE` summary lines).
pub fn field(text: &str, key: &str) -> Option<u64> {
    let rest = &text[text.find(key)? + key.len()..];
    rest.split(|c: char| !c.is_ascii_digit())
        .next()?
        .parse()
        .ok()
}
