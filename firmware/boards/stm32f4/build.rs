//! Links the board binary with this crate's `memory.x` (the STM32F407's map, not the QEMU board's in
//! `firmware/`), cortex-m-rt's `link.x` and defmt's `defmt.x`, and selects the board description
//! the binary runs: `TCOMP_BOARD` names a file of `firmware/descriptions/` (default `imu6-rlg-qma`),
//! whose channel table `tcomp_firmware::wiring` generated.

use std::{env, error::Error, fs, path::PathBuf};

fn main() -> Result<(), Box<dyn Error>> {
    let out = PathBuf::from(env::var_os("OUT_DIR").ok_or("cargo sets OUT_DIR")?);
    let root =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").ok_or("cargo sets CARGO_MANIFEST_DIR")?);
    let memory_x = root.join("memory.x");
    fs::copy(&memory_x, out.join("memory.x"))?;
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=TCOMP_BOARD");
    let board = env::var("TCOMP_BOARD").unwrap_or_else(|_| "imu6-rlg-qma".into());
    let description = root
        .join("../../descriptions")
        .join(format!("{board}.toml"));
    if !description.is_file() {
        return Err(format!(
            "TCOMP_BOARD={board}: no {} (the descriptions are firmware/descriptions/*.toml)",
            description.display()
        )
        .into());
    }
    let name = board.to_uppercase().replace('-', "_");
    fs::write(
        out.join("board_config.rs"),
        format!(
            "/// The channel table this binary runs: `firmware/descriptions/{board}.toml` (`TCOMP_BOARD`).\n\
             pub const CONFIG: &[tcomp_firmware::app::ChannelConfig] = &tcomp_firmware::wiring::{name};\n"
        ),
    )?;
    if env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
    Ok(())
}
