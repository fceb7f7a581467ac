//! The facts the porting guide (`README.md`) states are the library's: the channel sizes per
//! pointer width, and the loop bits it tells a firmware to use.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::path::PathBuf;

fn read(rel: &str) -> String {
    std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

/// The value of `#define TCOMP_CHANNEL_SIZE` inside the header's `#if defined(guard)` block.
fn header_size(header: &str, guard: &str) -> usize {
    let block = header
        .split(&format!("#if defined({guard})"))
        .nth(1)
        .and_then(|b| b.split("#endif").next())
        .unwrap();
    let line = block
        .lines()
        .find(|l| l.starts_with("#define TCOMP_CHANNEL_SIZE"))
        .unwrap();
    line.split_whitespace().nth(2).unwrap().parse().unwrap()
}

/// The number in the README's table row that starts with `| label |`.
fn readme_row(readme: &str, label: &str) -> usize {
    let row = readme
        .lines()
        .find(|l| l.starts_with(&format!("| {label} |")))
        .unwrap_or_else(|| panic!("README has no row `{label}`"));
    row.split('|').nth(2).unwrap().trim().parse().unwrap()
}

#[test]
fn channel_sizes_in_the_guide_are_the_headers() {
    let (readme, header) = (read("README.md"), read("include/tcomp.h"));
    let m4 = header_size(&header, "TCOMP_POINTER_32");
    let host = header_size(&header, "TCOMP_POINTER_64");
    assert_eq!(readme_row(&readme, "32-bit target (Cortex-M)"), m4);
    assert_eq!(readme_row(&readme, "64-bit host"), host);
    #[cfg(target_pointer_width = "64")]
    assert_eq!(host, tcomp_ffi::TCOMP_CHANNEL_SIZE);
}

#[test]
fn the_loop_bits_the_guide_names_are_the_frames() {
    use tcomp_core::frame::status::*;
    let readme = read("README.md");
    let stated = format!(
        "(sensor error {SENSOR_ERROR}, stuck {STUCK}, temperature jump {TEMP_JUMP}, time jump {TIME_JUMP}, watchdog reset 1<<{}, overrun 1<<{})",
        WATCHDOG_RESET.trailing_zeros(),
        OVERRUN.trailing_zeros()
    );
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(flat.contains(&stated), "README should say {stated}");
}
