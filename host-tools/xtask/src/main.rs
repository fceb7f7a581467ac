//! `cargo xtask`: the one entry point a person and CI both run.
//!
//! * `cargo xtask ci`   — fmt, clippy (host and thumbv7em, `-D warnings`), host tests, the no_std
//!   build of the core, the STM32F407 board binary with its size budgets (`board.rs`), and the
//!   QEMU smoke run with its instruction budget.
//! * `cargo xtask board` — only the board binary's build, clippy and sizes.
//! * `cargo xtask smoke` — only the QEMU smoke run.
//! * `cargo xtask power-cut` — the model slots' power-loss test (a power cut after and inside every
//!   write step of three updates); prints its `POWER-CUT` line.
//! * `cargo xtask ffi`   — the C API's examples: a host C program against `tcomp eval`, a
//!   bare-metal C program under QEMU against the host, bit for bit (see `ffi/mod.rs`).
//! * `cargo xtask qemu`  — the QEMU replay of the 200 Hz loop with bit-exact host parity, fault
//!   checks and budgets (see `qemu.rs`), and a model update over the emulated UART with
//!   `tcomp flash` (`update.rs`).

mod board;
mod elf;
mod ffi;
mod qemu;
mod update;

use anyhow::{Context, Result, bail};
use std::process::{Command, Stdio};
use tcomp_tests::replay::field;

const TARGET: &str = "thumbv7em-none-eabihf";
/// Budget for one RBF evaluation (32 centers × 4 features) under QEMU, in instructions.
const RBF_EVAL_BUDGET: u64 = 1_000;

fn main() -> Result<()> {
    let task = std::env::args().nth(1).unwrap_or_default();
    match task.as_str() {
        "ci" => ci(),
        "smoke" => smoke(),
        "qemu" => qemu::qemu(),
        "board" => board::board(),
        "power-cut" => power_cut(),
        "ffi" => ffi::ffi(),
        _ => bail!("usage: cargo xtask <ci|smoke|qemu|board|power-cut|ffi>"),
    }
}

fn cargo(args: &[&str]) -> Result<()> {
    eprintln!("$ cargo {}", args.join(" "));
    let status = Command::new(env!("CARGO"))
        .args(args)
        .status()
        .context("running cargo")?;
    if !status.success() {
        bail!("`cargo {}` failed ({status})", args.join(" "));
    }
    Ok(())
}

fn ci() -> Result<()> {
    cargo(&["fmt", "--all", "--", "--check"])?;
    cargo(&[
        "clippy",
        "--workspace",
        "--exclude",
        "tcomp-firmware",
        "--exclude",
        "tcomp-board-stm32f4",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ])?;
    cargo(&[
        "clippy",
        "-p",
        "tcomp-core",
        "-p",
        "tcomp-hal",
        "-p",
        "tcomp-firmware",
        "--target",
        TARGET,
        "--",
        "-D",
        "warnings",
    ])?;
    // The firmware's library (the loop) has host tests; its binaries are target-only.
    let firmware_lib = ["-p", "tcomp-firmware", "--lib", "--tests"];
    cargo(&[&["clippy"][..], &firmware_lib, &["--", "-D", "warnings"]].concat())?;
    cargo(&[
        "test",
        "--workspace",
        "--exclude",
        "tcomp-firmware",
        "--exclude",
        "tcomp-board-stm32f4",
    ])?;
    cargo(&["test", "-p", "tcomp-firmware", "--lib"])?;
    power_cut()?;
    cargo(&["build", "-p", "tcomp-core", "--target", TARGET, "--release"])?;
    cargo(&["build", "-p", "tcomp-hal", "--target", TARGET, "--release"])?;
    board::board()?;
    smoke()?;
    qemu::qemu()?;
    ffi::ffi()
}

/// Runs the smoke binary under QEMU (the runner in `.cargo/config.toml`), echoes its output, and
/// checks its verdict, QEMU's exit code and the instruction budget.
fn smoke() -> Result<()> {
    let args = [
        "run",
        "-p",
        "tcomp-firmware",
        "--target",
        TARGET,
        "--release",
        "--bin",
        "smoke",
    ];
    eprintln!("$ cargo {}", args.join(" "));
    let out = Command::new(env!("CARGO"))
        .args(args)
        .stderr(Stdio::inherit())
        .output()
        .context("running QEMU (is qemu-system-arm installed?)")?;
    let text = String::from_utf8_lossy(&out.stdout);
    print!("{text}");
    if !out.status.success() || !text.contains("SMOKE OK") {
        bail!("QEMU smoke run failed ({})", out.status);
    }
    let per_eval =
        field(&text, "instructions_per_rbf_eval=").context("no instruction count in output")?;
    if per_eval > RBF_EVAL_BUDGET {
        bail!("RBF evaluation takes {per_eval} instructions, over the budget of {RBF_EVAL_BUDGET}");
    }
    println!(
        "smoke: ok, {per_eval} instructions per 32x4 RBF evaluation (budget {RBF_EVAL_BUDGET})"
    );
    Ok(())
}

/// Runs the power-loss test of the model slots and reports how many cut points it tried.
fn power_cut() -> Result<()> {
    let args = [
        "test",
        "-p",
        "tcomp-core",
        "--test",
        "power_cut",
        "--",
        "--nocapture",
    ];
    eprintln!("$ cargo {}", args.join(" "));
    let out = Command::new(env!("CARGO"))
        .args(args)
        .stderr(Stdio::inherit())
        .output()
        .context("running the power-loss test")?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("POWER-CUT "))
        .context("the power-loss test printed no POWER-CUT line")?;
    println!("{line}");
    let cut_points = field(line, "cut_points=").context("no cut_points in the POWER-CUT line")?;
    if !out.status.success() || field(line, "mixed=") != Some(0) || cut_points == 0 {
        bail!("power-loss test failed ({})", out.status);
    }
    Ok(())
}
