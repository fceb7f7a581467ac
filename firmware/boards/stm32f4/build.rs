//! Links the board binary with the repository root's `memory.x` (the STM32F407's map: the product
//! board's, where the project's layout puts it; the QEMU board, a workspace of its own, keeps its
//! own beside its code), cortex-m-rt's `link.x` and defmt's `defmt.x`, and selects the board
//! description the binary runs: `TCOMP_BOARD` names a file of `firmware/descriptions/` (default
//! `imu6-rlg-qma`), whose channel table `tcomp_firmware::wiring` generated.
//!
//! The linker would find the root's `memory.x` unaided (cargo runs it from the workspace root,
//! and it resolves `INCLUDE memory.x` there first); it is also put on the search path from here so
//! that the build reruns when it changes, and the link finds it wherever the linker runs.

use std::{env, error::Error, fs, path::PathBuf};

fn main() -> Result<(), Box<dyn Error>> {
    let out = PathBuf::from(env::var_os("OUT_DIR").ok_or("cargo sets OUT_DIR")?);
    let root =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").ok_or("cargo sets CARGO_MANIFEST_DIR")?);
    let memory_x = root.join("../../../memory.x");
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
    let rtds = rtd_table(&description)?;
    // The UART's rate is the description's `[link] baud`, generated once as `wiring::NAME_BAUD`.
    if tcomp_board_description::Board::load(&description)?
        .baud
        .is_none()
    {
        return Err(format!(
            "{}: no `[link] baud`: this board's UART takes its rate from the description",
            description.display()
        )
        .into());
    }
    fs::write(
        out.join("board_config.rs"),
        format!(
            "/// The channel table this binary runs: `firmware/descriptions/{board}.toml` (`TCOMP_BOARD`).\n\
             pub const CONFIG: &[tcomp_firmware::app::ChannelConfig] = &tcomp_firmware::wiring::{name};\n\
             /// Its board hash: an image made for another description loads no model.\n\
             pub const CONFIG_HASH: u64 = tcomp_firmware::wiring::{name}_HASH;\n\
             /// Its link's baud rate (`[link] baud`): USART1 runs at it.\n\
             pub const LINK_BAUD: u32 = tcomp_firmware::wiring::{name}_BAUD;\n\
             /// The RTD of each thermometer of `{board}.toml`, in its order (converter k, AIN0/AIN1).\n\
             pub const RTDS: &[tcomp_hal::rtd::Rtd] = &[{rtds}];\n"
        ),
    )?;
    if env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
    Ok(())
}

/// Converters on this board: one ADS1220 per thermometer, with a PT100 front end (IDAC 1 mA,
/// gain 4, the reference resistor `setup::R_REF_OHM`).
const CONVERTERS: usize = 12;

/// The description's thermometers as this board reads them, or why it cannot: thermometer `k` must
/// be a PT100-class RTD (r0 = 100 Ω; its own a, b) on converter `k`, input 0 — the board wires one
/// ADS1220 per thermometer and its front end is sized for 100 Ω.
fn rtd_table(description: &std::path::Path) -> Result<String, Box<dyn Error>> {
    let board = tcomp_board_description::Board::load(description)?;
    let mut rtds = Vec::new();
    for (k, t) in board.thermometer_rows().iter().enumerate() {
        let place = format!("{}: thermometer `{}`", description.display(), t.name);
        if k >= CONVERTERS || usize::from(t.adc) != k || t.input != 0 {
            return Err(format!(
                "{place}: this board reads thermometer k on converter k, input 0, for k < {CONVERTERS} \
                 (it is number {k}, on converter {} input {})",
                t.adc, t.input
            )
            .into());
        }
        match t.kind {
            tcomp_core::image::ThermKind::Rtd { r0, a, b } if (r0 - 100.0).abs() < 1e-3 => rtds.push(
                format!("tcomp_hal::rtd::Rtd::with_coefficients({r0:?}, {a:?}, {b:?}, tcomp_hal::rtd::Rtd::IEC_C)"),
            ),
            _ => {
                return Err(format!(
                    "{place}: this board's front end reads PT100-class RTDs only (r0 = 100 Ω)"
                )
                .into());
            }
        }
    }
    Ok(rtds.join(", "))
}
