//! `cargo xtask`: the one entry point a person and CI both run.
//!
//! * `cargo xtask ci`   — fmt, clippy (host and thumbv7em, both boards, `-D warnings`), host tests,
//!   the no_std build of the core, the STM32F407 board binary with its size budgets (`board.rs`),
//!   the QEMU smoke run with its instruction budget, and the QEMU product run (`qemu.rs`).
//! * `cargo xtask lint` — only fmt and clippy (the first steps of `ci`).
//! * `cargo xtask prepare` — `lint`, the host crates' clippy done inside the host test build
//!   (what `.ci/run` runs while it installs Debian's packages).
//! * `cargo xtask board` — only the board binary's build and sizes.
//! * `cargo xtask targets` — the no_std build of the core and the HAL, then `board` (the target
//!   builds of `ci`, which runs them beside the host tests).
//! * `cargo xtask smoke` — only the QEMU smoke run.
//! * `cargo xtask power-cut` — the model slots' power-loss test (a power cut after and inside every
//!   write step of three updates); prints its `POWER-CUT` line, and `POWER-CUT-SIGNED` (the
//!   same with signature checks, and an update signed by another key).
//! * `cargo xtask ffi`   — the C API's examples: a host C program against `tcomp eval`, a
//!   bare-metal C program under QEMU against the host, bit for bit (see `ffi/mod.rs`).
//! * `cargo xtask python` — the Python wheel built, installed into a fresh virtual environment,
//!   and its pytest suite run (see `python.rs`).
//! * `cargo xtask qemu`  — the QEMU replay of the 200 Hz loop with bit-exact host parity, fault
//!   checks and budgets (see `qemu.rs`), and a model update over the emulated UART with
//!   `tcomp flash` (`update.rs`).

mod board;
mod budget;
mod defmt;
mod elf;
mod ffi;
mod proc;
mod python;
mod qemu;
mod update;

use anyhow::{Context, Result, bail};
use std::process::Command;
use std::time::{Duration, Instant};
use tcomp_tests::replay::field;

const TARGET: &str = "thumbv7em-none-eabihf";
/// Budget for one RBF evaluation (32 centers × 4 features) under QEMU, in instructions.
const RBF_EVAL_BUDGET: u64 = budget::RBF_EVAL_INSTRUCTIONS;

fn main() -> Result<()> {
    let task = std::env::args().nth(1).unwrap_or_default();
    match task.as_str() {
        "ci" => ci(),
        "lint" => lint(),
        "prepare" => prepare(),
        "smoke" => smoke(),
        "qemu" => qemu::qemu(),
        "board" => board::board(),
        "targets" => targets(),
        "power-cut" => power_cut(),
        "ffi" => ffi::ffi(),
        "python" => python::python(),
        _ => bail!(
            "usage: cargo xtask <ci|lint|prepare|smoke|qemu|board|targets|power-cut|ffi|python>"
        ),
    }
}

/// The longest a cargo command of the xtask may take: the workspace's test build from nothing
/// takes about 10 min on the 2-core machine while other builds run; CI's own limit is 90 min.
const CARGO_LIMIT: Duration = proc::minutes(40);
/// The host test set: the workspace less the STM32 board crate (a target-only binary; the QEMU
/// board is a workspace of its own).
pub const HOST_TESTS: [&str; 3] = ["--workspace", "--exclude", board::PACKAGE];
/// The QEMU smoke run: about 1 s.
const SMOKE_LIMIT: Duration = proc::minutes(2);

fn cargo(args: &[&str]) -> Result<()> {
    eprintln!("$ cargo {}", args.join(" "));
    proc::run(
        Command::new(env!("CARGO")).args(args),
        &format!("`cargo {}`", args.join(" ")),
        CARGO_LIMIT,
    )
}

/// A cargo command over the host workspace whose crates are compiled by `clippy-driver` with
/// `-D warnings`: the host lint happens inside the test build, as `cargo clippy` runs it (the same
/// driver and arguments, set the way `cargo clippy` sets them), but with code generated.
///
/// Why: `cargo clippy` is a check build, which shares no artifact with the test build, so the
/// dependencies were compiled twice, once as metadata for the lint and once as code for the tests
/// (clippy 343 s before a 393 s test build on the slower 2-core machine). Here they are compiled
/// once, and only the workspace's own crates pay for the lints. The driver is the toolchain's own
/// (beside its `cargo`), so its crates link with the dependencies rustc built. Cargo hashes the
/// wrapper into the workspace crates' metadata, so a plain `cargo test` keeps its own artifacts
/// and neither build invalidates the other. The driver turns MIR optimisations off (its lints read
/// the unoptimised MIR); LLVM's optimisation and the floating-point results are unchanged, and the
/// binaries a user flashes or installs are never built this way: the target builds and release
/// builds use plain rustc.
fn host_cargo(args: &[&str]) -> Result<Command> {
    let driver = std::path::Path::new(env!("CARGO")).with_file_name("clippy-driver");
    if !driver.is_file() {
        bail!(
            "no clippy-driver beside cargo ({}): `rustup component add clippy`",
            driver.display()
        );
    }
    eprintln!(
        "$ cargo {} (the workspace compiled by clippy-driver, -D warnings)",
        args.join(" ")
    );
    let mut cmd = Command::new(env!("CARGO"));
    cmd.args(args)
        .env("RUSTC_WORKSPACE_WRAPPER", driver)
        .env("CLIPPY_ARGS", CLIPPY_ARGS);
    Ok(cmd)
}

/// `-D warnings` as `cargo clippy -- -D warnings` hands it to `clippy-driver`: each argument
/// followed by the separator the driver splits on.
const CLIPPY_ARGS: &str = "-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__";

/// Runs [`host_cargo`]'s command, bounded by [`CARGO_LIMIT`].
fn host_cargo_run(args: &[&str]) -> Result<()> {
    proc::run(
        &mut host_cargo(args)?,
        &format!("`cargo {}`", args.join(" ")),
        CARGO_LIMIT,
    )
}

/// The wall time of each step of `cargo xtask ci`, printed as it goes and summed up at the end
/// (`CI-TIMING`), so a slow CI run says where its time went.
struct Steps(Vec<(&'static str, Duration)>);

impl Steps {
    fn run(&mut self, name: &'static str, step: impl FnOnce() -> Result<()>) -> Result<()> {
        let t = Instant::now();
        let r = step();
        let took = t.elapsed();
        eprintln!("CI-STEP {name}: {:.0} s", took.as_secs_f64());
        self.0.push((name, took));
        r.with_context(|| format!("step `{name}`"))
    }
}

impl Drop for Steps {
    fn drop(&mut self) {
        let total: f64 = self.0.iter().map(|(_, d)| d.as_secs_f64()).sum();
        let steps: Vec<String> = self
            .0
            .iter()
            .map(|(n, d)| format!("{n}={:.0}", d.as_secs_f64()))
            .collect();
        println!("CI-TIMING total={total:.0} {}", steps.join(" "));
    }
}

/// `cargo xtask lint`: the first steps of `ci` on their own (`.ci/run` runs them while it
/// installs Debian's packages).
fn lint() -> Result<()> {
    lint_steps(&mut Steps(Vec::new()), HostLint::Check)
}

/// `cargo xtask prepare`: the first steps of `ci` that need no Debian package — the lint and the
/// host test build — on their own. `.ci/run` runs them while it installs the packages, and `ci`
/// then finds them done (its fmt, clippy and test build re-check in seconds): on a fresh clone
/// the setup took 574 s with the build in it, against 324 s + a 296 s test build after it.
fn prepare() -> Result<()> {
    lint_steps(&mut Steps(Vec::new()), HostLint::InTestBuild)
}

/// How [`lint_steps`] lints the host crates.
enum HostLint {
    /// `cargo clippy --all-targets`, a check build (`cargo xtask lint`: no code generated).
    Check,
    /// Inside the host test build ([`host_build`], through [`host_cargo`]): `prepare` and `ci`,
    /// which need that build anyway.
    InTestBuild,
}

/// Formatting and clippy, host and target. The target's clippy (the firmware crates and the STM32
/// board's binary for thumbv7em, the STM32F4 PAC among them; then the QEMU board's, a workspace
/// of its own) shares no artifact with the host's
/// but a few proc-macros, so it runs beside it, in its own target directory (cargo's lock on one
/// directory would serialise the two): the host build leaves a core idle much of the time.
fn lint_steps(steps: &mut Steps, host: HostLint) -> Result<()> {
    let qemu_board = qemu::board_args();
    let qemu_board: Vec<&str> = qemu_board.iter().map(String::as_str).collect();
    steps.run("fmt", || {
        cargo(&["fmt", "--all", "--", "--check"])?;
        // The QEMU board is a workspace of its own: `--all` is the root's members.
        cargo(&[&["fmt"][..], &qemu_board[..2], &["--", "--check"]].concat())
    })?;
    let mut clippy_target = Command::new(env!("CARGO"));
    clippy_target
        .args([
            "clippy",
            "-p",
            "tcomp-core",
            "-p",
            "tcomp-hal",
            "-p",
            "tcomp-firmware",
            "-p",
            board::PACKAGE,
            "--target",
            TARGET,
            "--",
            "-D",
            "warnings",
        ])
        .env("CARGO_TARGET_DIR", qemu::target_dir().join("clippy-target"));
    // Everything that runs on the target, both boards' binaries with it.
    let target = Lane::start("clippy_target", clippy_target)?;
    // The host crates, the firmware's application library with them (its tests run on the host).
    match host {
        HostLint::Check => steps.run("clippy_host", || {
            cargo(
                &[
                    &["clippy"][..],
                    &HOST_TESTS,
                    &["--all-targets", "--", "-D", "warnings"],
                ]
                .concat(),
            )
        })?,
        HostLint::InTestBuild => steps.run("test_build_and_clippy_host", host_build)?,
    }
    steps.run("clippy_target", || target.finish())?;
    // The QEMU board, a workspace of its own, after the lane (its dependencies' checks are the
    // lane's, in the same target directory).
    steps.run("clippy_qemu_board", || {
        let dir = qemu::target_dir().join("clippy-target");
        let dir = dir.display().to_string();
        cargo(
            &[
                &["clippy"][..],
                &qemu_board[..2],
                &[
                    "--target-dir",
                    &dir,
                    "--target",
                    TARGET,
                    "--",
                    "-D",
                    "warnings",
                ],
            ]
            .concat(),
        )
    })
}

fn ci() -> Result<()> {
    let mut steps = Steps(Vec::new());
    // The lint with the test build in it, then the tests beside the target builds: the tests
    // keep about 1.6 of the two cores busy, and the release builds for thumbv7em (their own
    // profile and target, so cargo's lock does not serialise them with the tests) take most of
    // the rest.
    lint_steps(&mut steps, HostLint::InTestBuild)?;
    let mut targets = Command::new(std::env::current_exe()?);
    targets.arg("targets");
    let targets = Lane::start("targets", targets)?;
    steps.run("test", || {
        host_cargo_run(&[&["test"][..], &HOST_TESTS].concat())
    })?;
    steps.run("targets", || targets.finish())?;
    // The Python step (a wheel built by maturin with its own feature set, packages from PyPI,
    // pytest) shares nothing with the steps below but the test build's `tcomp` binary, and the
    // steps below spend most of their time in QEMU on one core: it runs beside them, in a child
    // xtask whose output is printed whole when it ends (so the log stays readable).
    let mut python = Command::new(std::env::current_exe()?);
    python.arg("python");
    let python = Lane::start("python", python)?;
    steps.run("power_cut", power_cut)?;
    steps.run("smoke", smoke)?;
    steps.run("qemu", qemu::qemu)?;
    steps.run("ffi", ffi::ffi)?;
    steps.run("python", || python.finish())
}

/// `cargo xtask targets`: the no_std build of the core and the HAL for the Cortex-M4F, then the
/// STM32F407 board binary with its size budgets; each step's time printed as in `ci`.
fn targets() -> Result<()> {
    let mut steps = Steps(Vec::new());
    steps.run("no_std_core_hal", || {
        cargo(&[
            "build",
            "-p",
            "tcomp-core",
            "-p",
            "tcomp-hal",
            "--target",
            TARGET,
            "--release",
        ])
    })?;
    steps.run("board", board::board)
}

/// A step run beside the others: a child process (bounded by [`CARGO_LIMIT`], killed when
/// dropped unfinished), its output kept in a file under the target directory and echoed whole
/// when it ends, so the log stays readable.
struct Lane {
    child: proc::Bounded,
    log: std::path::PathBuf,
    started: Instant,
}

impl Lane {
    fn start(step: &str, mut cmd: Command) -> Result<Self> {
        let log = qemu::target_dir().join(format!("ci-{step}.log"));
        if let Some(dir) = log.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let file = std::fs::File::create(&log).with_context(|| format!("{}", log.display()))?;
        cmd.stdout(file.try_clone()?)
            .stderr(file)
            .stdin(std::process::Stdio::null());
        eprintln!(
            "CI-LANE {step}: started beside the next steps (its output: {})",
            log.display()
        );
        Ok(Self {
            child: proc::Bounded::spawn(&mut cmd, &format!("the {step} step"), CARGO_LIMIT)?,
            log,
            started: Instant::now(),
        })
    }

    /// Waits for the lane, echoes its output, and fails when it failed.
    fn finish(mut self) -> Result<()> {
        let status = self.child.wait();
        let text = std::fs::read_to_string(&self.log).unwrap_or_default();
        eprintln!(
            "--- {} (ran beside the steps above, {:.0} s) ---\n{text}--- end of it ---",
            self.log.display(),
            self.started.elapsed().as_secs_f64()
        );
        let status = status?;
        if !status.success() {
            bail!("failed ({status})");
        }
        Ok(())
    }
}

/// The host build the test step made (`cargo test --no-run` over [`HOST_TESTS`]): the `tcomp`
/// binary and `libtcomp_ffi.a` that the C and Python steps use. Built with the test step's own
/// package set, so its features are the same and nothing is compiled a second time (a `cargo
/// build -p …` of a subset unifies features differently and rebuilds the dependency tree).
///
/// It is also the host lint ([`host_cargo`]): `--all-targets` builds the benches too, so every
/// target `cargo clippy --all-targets` would check is compiled through the driver.
pub fn host_build() -> Result<()> {
    host_cargo_run(&[&["test", "--no-run", "--all-targets"][..], &HOST_TESTS].concat())
}

/// The host build's artifacts ([`host_build`]'s command, which builds nothing when the test step
/// ran), as cargo's JSON messages. What that build makes stays under `target/debug/deps` with its
/// hash (only a `cargo build` of a package copies its outputs up to `target/debug`), so the
/// steps that use one take its path from here.
fn host_artifacts() -> Result<Vec<serde_json::Value>> {
    let args = [
        &[
            "test",
            "--no-run",
            "--message-format=json-render-diagnostics",
        ][..],
        &HOST_TESTS,
    ]
    .concat();
    let out = proc::output(&mut host_cargo(&args)?, "the host test build", CARGO_LIMIT)?;
    if !out.status.success() {
        bail!("the host test build failed ({})", out.status);
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|m| m["reason"] == "compiler-artifact")
        .collect())
}

/// The executable of the integration test `name` in the host build.
fn host_test_binary(name: &str) -> Result<std::path::PathBuf> {
    host_artifacts()?
        .iter()
        .find(|m| m["target"]["name"] == name && has_kind(m, "test"))
        .and_then(|m| m["executable"].as_str().map(std::path::PathBuf::from))
        .with_context(|| format!("the host test build has no test binary `{name}`"))
}

/// The file of kind `kind` (`staticlib`, …) of the library `name` in the host build, by its
/// extension `ext`.
pub fn host_library(name: &str, kind: &str, ext: &str) -> Result<std::path::PathBuf> {
    host_artifacts()?
        .iter()
        .filter(|m| m["target"]["name"] == name && has_kind(m, kind))
        .flat_map(|m| m["filenames"].as_array().cloned().unwrap_or_default())
        .filter_map(|f| f.as_str().map(std::path::PathBuf::from))
        .find(|f| f.extension().is_some_and(|e| e == ext))
        .with_context(|| format!("the host test build has no {kind} of `{name}`"))
}

fn has_kind(message: &serde_json::Value, kind: &str) -> bool {
    message["target"]["kind"]
        .as_array()
        .is_some_and(|k| k.iter().any(|k| k == kind))
}

/// Runs the smoke binary under QEMU (with the runner's arguments of `.cargo/config.toml`, bounded
/// by [`SMOKE_LIMIT`]), echoes its output, and checks its verdict, QEMU's exit code and the
/// instruction budget.
fn smoke() -> Result<()> {
    let board = qemu::board_args();
    let board: Vec<&str> = board.iter().map(String::as_str).collect();
    cargo(
        &[
            &["build"][..],
            &board,
            &["--target", TARGET, "--release", "--bin", "smoke"],
        ]
        .concat(),
    )?;
    let elf = qemu::target_dir().join(TARGET).join("release/smoke");
    // One instruction per ns of virtual time (the runner of `.cargo/config.toml` uses the same).
    let mut qemu = qemu::machine(&elf, "shift=0");
    let out = proc::output(&mut qemu, "the QEMU smoke run", SMOKE_LIMIT)?;
    let text = String::from_utf8_lossy(&out.stdout);
    print!("{text}");
    if !out.status.success() || !text.contains("SMOKE OK") {
        bail!("QEMU smoke run failed ({})", out.status);
    }
    let per_eval =
        field(&text, "instructions_per_rbf_eval=").context("no instruction count in output")?;
    let per_masked = field(&text, "instructions_per_additive_rbf_eval=")
        .context("no additive instruction count in output")?;
    let per_kinds = field(&text, "instructions_per_kinds_rbf_eval=")
        .context("no instruction count for the model with steps and powers in output")?;
    for (what, n) in [
        ("joint", per_eval),
        ("additive", per_masked),
        ("steps and powers", per_kinds),
    ] {
        if n > RBF_EVAL_BUDGET {
            bail!(
                "{what} RBF evaluation takes {n} instructions, over the budget of {RBF_EVAL_BUDGET}"
            );
        }
    }
    println!(
        "smoke: ok, {per_eval} instructions per 32x4 RBF evaluation, {per_masked} additive, \
         {per_kinds} with steps and powers (budget {RBF_EVAL_BUDGET})"
    );
    Ok(())
}

/// Runs the power-loss test of the model slots and reports how many cut points it tried.
fn power_cut() -> Result<()> {
    // The test step's binary, run with its output shown (`cargo test --test power_cut` selects
    // one target, resolves the dependencies' features for it alone and rebuilt the core's
    // dependency tree: a minute on the 2-core machine).
    let exe = host_test_binary("power_cut")?;
    eprintln!("$ {} --nocapture", exe.display());
    let out = proc::output(
        Command::new(&exe).arg("--nocapture"),
        "the power-loss test",
        CARGO_LIMIT,
    )?;
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
    // The same proof with signature checks at boot and at COMMIT, and a rogue-signed update.
    let signed = text
        .lines()
        .find(|l| l.starts_with("POWER-CUT-SIGNED "))
        .context("the power-loss test printed no POWER-CUT-SIGNED line")?;
    println!("{signed}");
    if field(signed, "mixed=") != Some(0) || field(signed, "rogue_booted=") != Some(0) {
        bail!("signed power-loss test failed: {signed}");
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The host build's cargo runs the toolchain's own clippy-driver on the workspace with the
    /// arguments `cargo clippy -- -D warnings` would give it, and nothing else of cargo's
    /// environment changes (the target builds and the release binaries stay plain rustc builds).
    #[test]
    fn the_host_build_lints_with_the_toolchains_clippy_driver() {
        let cmd = host_cargo(&["test", "--no-run"]).unwrap();
        let envs: std::collections::BTreeMap<String, String> = cmd
            .get_envs()
            .map(|(k, v)| {
                let v = v.map(|v| v.to_string_lossy().into_owned());
                (k.to_string_lossy().into_owned(), v.unwrap_or_default())
            })
            .collect();
        let keys: Vec<&str> = envs.keys().map(String::as_str).collect();
        assert_eq!(keys, ["CLIPPY_ARGS", "RUSTC_WORKSPACE_WRAPPER"]);
        let driver = std::path::Path::new(&envs["RUSTC_WORKSPACE_WRAPPER"]);
        assert!(driver.is_file(), "{}", driver.display());
        assert_eq!(
            driver.parent(),
            std::path::Path::new(env!("CARGO")).parent()
        );
        let args: Vec<&str> = envs["CLIPPY_ARGS"]
            .split("__CLIPPY_HACKERY__")
            .filter(|a| !a.is_empty())
            .collect();
        assert_eq!(args, ["-D", "warnings"]);
    }
}
