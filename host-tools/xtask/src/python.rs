//! `cargo xtask python`: the Python package (`python/`, PyO3 + maturin) as a user gets it — the
//! abi3 wheel built with the workspace's dev profile (no LTO; it reuses what the test step built
//! in `target/`), installed into a fresh virtual environment with pinned packages from PyPI, and
//! its pytest suite run against the installed wheel and the CLI in `target/debug/tcomp`.
//!
//! A step of `cargo xtask ci`, so the README's one test command runs it too. Every child is bounded
//! ([`crate::proc`]); the limits are a few times what each takes on a loaded 2-core machine.

use crate::proc::{minutes, run};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The build tool and the test environment, pinned so a fresh machine gets what was tested.
const MATURIN: &str = "maturin==1.16.0";
const TEST_PACKAGES: [&str; 4] = [
    "pytest==9.2.0",
    "numpy==2.4.6",
    "pandas==3.1.1",
    "matplotlib==3.11.2",
];

fn venv(python: &str, dir: &Path) -> Result<PathBuf> {
    run(
        Command::new(python).args(["-m", "venv"]).arg(dir),
        "python3 -m venv",
        minutes(2),
    )?;
    Ok(dir.join("bin"))
}

pub fn python() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let target = crate::qemu::target_dir();
    let (build, test, wheels) = (
        target.join("py-build"),
        target.join("py-test"),
        target.join("wheels-ci"),
    );
    for dir in [&build, &test, &wheels] {
        if dir.exists() {
            std::fs::remove_dir_all(dir).with_context(|| format!("removing {}", dir.display()))?;
        }
    }
    // The CLI the tests compare the binding with.
    crate::host_build()?;
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".to_string());
    let bin = venv(&python, &build)?;
    run(
        Command::new(bin.join("pip")).args(["install", "-q", MATURIN]),
        "pip install maturin",
        minutes(10),
    )?;
    run(
        Command::new(bin.join("maturin"))
            .args(["build", "-m"])
            .arg(root.join("python/Cargo.toml"))
            .args(["--profile", "dev", "--strip", "--out"])
            .arg(&wheels),
        "maturin build",
        minutes(30),
    )?;
    let bin = venv(&python, &test)?;
    run(
        Command::new(bin.join("pip"))
            .args(["install", "-q"])
            .args(TEST_PACKAGES),
        "pip install the test packages",
        minutes(10),
    )?;
    let wheel = std::fs::read_dir(&wheels)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .context("maturin wrote no wheel")?;
    run(
        Command::new(bin.join("pip"))
            .args(["install", "-q"])
            .arg(&wheel),
        "pip install the wheel",
        minutes(5),
    )?;
    run(
        Command::new(bin.join("pytest"))
            .args(["-p", "no:cacheprovider"])
            .arg(root.join("python/tests"))
            .env("TCOMP_CLI", target.join("debug/tcomp")),
        "pytest python/tests",
        minutes(20),
    )
}
