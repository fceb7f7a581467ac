//! `cargo xtask ffi` (a step of `cargo xtask ci`): the C API's two examples, built with real C
//! compilers against the real static library, run and compared bit for bit.
//!
//! * **Host**: `crates/ffi/c/host_eval.c`, built with the system `cc` against the host
//!   `libtcomp_ffi.a`, evaluates a blob fitted by `tcomp fit` on a simulated run with a logger
//!   dropout; every figure it prints must be the one `tcomp eval --json` reports, to the bit.
//! * **Target**: `crates/ffi/c/replay.c` with the bare-metal `mps2/startup.c`, built with Debian's
//!   `arm-none-eabi-gcc` against the `thumbv7em-none-eabihf` library, replays two vectors under
//!   QEMU's mps2-an386 (Cortex-M4F): the core's example RLG model at the firmware's period (the
//!   smoke run's model, so the instruction count compares with the Rust firmware's) and the
//!   fitted IFOG model over the dropout. Each output must equal the Rust core's (computed here,
//!   carried in the vector) and the same C source's on the host, hash for hash.
//!
//! Also the library's lints for the target, its flash cost in the C image (from the linker map)
//! and the instructions per step (SysTick under `-icount`), printed on one `FFI-SUMMARY` line.
//! Every child process runs under a timeout and is killed when it overruns.

mod vector;

use crate::{TARGET, cargo};
use anyhow::{Context, Result, bail, ensure};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// Instructions per SysTick tick under `-icount shift=3`: one instruction per 8 ns of virtual
/// time, SysTick at the board's 25 MHz (40 ns).
const INSTRUCTIONS_PER_TICK: u64 = 5;
/// A C compile or a host run: seconds.
const SHORT: Duration = Duration::from_secs(120);
/// A QEMU run of a vector (a few seconds of host time each).
const QEMU: Duration = Duration::from_secs(120);

/// The C flags both builds share: warnings are errors, and no floating-point contraction, so the
/// C side's double arithmetic is the Rust side's operation for operation.
const C_FLAGS: [&str; 6] = [
    "-std=c11",
    "-O2",
    "-Wall",
    "-Wextra",
    "-Werror",
    "-ffp-contract=off",
];

pub fn ffi() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let target_dir =
        std::env::var_os("CARGO_TARGET_DIR").map_or(root.join("target"), PathBuf::from);
    let work = target_dir.join("ffi-examples");
    std::fs::create_dir_all(&work)?;
    let c_dir = root.join("crates/ffi/c");
    let include = root.join("crates/ffi/include");

    crate::host_build()?;
    cargo(&[
        "clippy",
        "-p",
        "tcomp-ffi",
        "--target",
        TARGET,
        "--",
        "-D",
        "warnings",
    ])?;
    cargo(&["build", "-p", "tcomp-ffi", "--target", TARGET, "--release"])?;
    let host_lib = crate::host_library("tcomp_ffi", "staticlib", "a")?;
    let arm_lib = target_dir.join(TARGET).join("release/libtcomp_ffi.a");

    // The host example against `tcomp eval`.
    let tcomp = target_dir.join("debug/tcomp");
    let (blob, run) = fitted_model(&tcomp, &work)?;
    let host_eval = work.join("host_eval");
    let mut cc = Command::new("cc");
    cc.args(C_FLAGS)
        .arg("-D_POSIX_C_SOURCE=200809L")
        .arg("-I")
        .arg(&include)
        .arg(c_dir.join("host_eval.c"))
        .arg(&host_lib)
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&host_eval);
    run_checked(&mut cc, SHORT, "cc host_eval.c")?;
    let ours = run_checked(
        Command::new(&host_eval).arg(&blob).arg(&run),
        SHORT,
        "host_eval",
    )?;
    let theirs = run_checked(
        Command::new(&tcomp)
            .args(["eval", "--json", "--quiet", "--model"])
            .arg(&blob)
            .arg("--data")
            .arg(&run),
        SHORT,
        "tcomp eval",
    )?;
    let figures = compare_eval(&ours, &theirs)?;
    println!("ffi: host_eval.c reproduces `tcomp eval` bit for bit ({figures})");

    // The bare-metal replay against the host.
    let elf = work.join("replay.elf");
    let map = work.join("replay.map");
    let mut gcc = Command::new("arm-none-eabi-gcc");
    gcc.args([
        "-mcpu=cortex-m4",
        "-mthumb",
        "-mfloat-abi=hard",
        "-mfpu=fpv4-sp-d16",
    ])
    .args(C_FLAGS)
    .args([
        "-ffreestanding",
        "-ffunction-sections",
        "-fdata-sections",
        "-nostdlib",
    ])
    .arg("-I")
    .arg(&include)
    .arg("-T")
    .arg(c_dir.join("mps2/link.ld"))
    .arg(format!("-Wl,--gc-sections,-Map={}", map.display()))
    .arg(c_dir.join("replay.c"))
    .arg(c_dir.join("mps2/startup.c"))
    .arg(&arm_lib)
    .args(["-lgcc", "-o"])
    .arg(&elf);
    run_checked(&mut gcc, SHORT, "arm-none-eabi-gcc replay.c")?;
    let replay_host = work.join("replay_host");
    let mut cc = Command::new("cc");
    cc.args(C_FLAGS)
        .arg("-I")
        .arg(&include)
        .arg(c_dir.join("replay.c"))
        .arg(c_dir.join("replay_host.c"))
        .arg(&host_lib)
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&replay_host);
    run_checked(&mut cc, SHORT, "cc replay_host.c")?;

    let vectors = [
        ("example", vector::example()?),
        ("fitted", vector::fitted(&std::fs::read(&blob)?, &run)?),
    ];
    let mut per_step = Vec::new();
    for (name, bytes) in &vectors {
        let path = work.join(format!("vector-{name}.bin"));
        std::fs::write(&path, bytes)?;
        let host = run_checked(Command::new(&replay_host).arg(&path), SHORT, "replay_host")?;
        // Semihosting's console (SYS_WRITE0) is QEMU's standard error.
        let (_, target) = run_both(&mut qemu(&elf, &path), QEMU, "qemu-system-arm")?;
        print!("{name}, host:   {host}{name}, target: {target}");
        let (h, t) = (replay_line(&host)?, replay_line(&target)?);
        ensure!(
            host.contains("REPLAY OK") && target.contains("REPLAY OK"),
            "{name}: replay failed"
        );
        ensure!(
            h.get("hash") == t.get("hash") && h.get("samples") == t.get("samples"),
            "{name}: the target's outputs differ from the host's"
        );
        let samples: u64 = t.get("samples").context("samples")?.parse()?;
        let total: u64 = t.get("ticks_total").context("ticks")?.parse()?;
        let max: u64 = t.get("ticks_max").context("ticks")?.parse()?;
        let stack = t.get("stack_peak").context("no stack_peak")?;
        let validate = target
            .split_whitespace()
            .find_map(|f| f.strip_prefix("stack_peak_validate="))
            .context("no stack_peak_validate")?;
        per_step.push(format!(
            "{name} {} samples: {} instructions per step mean, {} worst, stack peak {stack} B \
             (load and steps; {validate} B with tcomp_validate_blob)",
            samples,
            total * INSTRUCTIONS_PER_TICK / samples.max(1),
            max * INSTRUCTIONS_PER_TICK
        ));
    }
    let (lib, total) = flash_cost(&map, &elf)?;
    println!(
        "FFI-SUMMARY host_eval=exact replay=bit-exact {}; flash {lib} B of libtcomp_ffi.a in a \
         {total} B image (.text + .rodata + .data)",
        per_step.join("; ")
    );
    Ok(())
}

/// A model fitted by `tcomp fit` on the simulated IFOG (Shupe term, a thermal lag; 32 centers ×
/// 4 features, the firmware's capacity) and its verification run with 300 rows cut out after
/// row 9,000: a logger dropout, which `tcomp eval` and `host_eval` must both see as one gap.
fn fitted_model(tcomp: &Path, work: &Path) -> Result<(PathBuf, PathBuf)> {
    let mut sim = Command::new(tcomp);
    sim.args(["simulate", "--preset", "ifog-shupe", "--out", "ifog"])
        .current_dir(work);
    run_checked(&mut sim, SHORT, "tcomp simulate")?;
    let blob = work.join("ifog-x.tcm");
    let mut fit = Command::new(tcomp);
    fit.args([
        "fit",
        "--data",
        "ifog/train.csv",
        "--target",
        "gyro_dph",
        "--reference",
    ])
    .args([
        "ref_dph",
        "--signal",
        "T=t_coil_c",
        "--feature",
        "T",
        "--feature",
        "rate(T)",
    ])
    .args([
        "--feature",
        "T * rate(T)",
        "--feature",
        "lag(T, 2400)",
        "--centers",
        "32",
    ])
    .args([
        "--sensor", "ifog", "--axis", "x", "--unit", "deg/h", "--quiet", "--out",
    ])
    .arg(&blob)
    .current_dir(work);
    run_checked(&mut fit, SHORT, "tcomp fit")?;
    let verify = std::fs::read_to_string(work.join("ifog/verify.csv"))?;
    let run = work.join("ifog-dropout.csv");
    let kept: Vec<&str> = verify
        .lines()
        .enumerate()
        .filter(|(i, _)| !(9_001..9_301).contains(i))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(&run, kept.join("\n") + "\n")?;
    Ok((blob, run))
}

/// Every figure `host_eval` prints against the same key of `tcomp eval --json` (top-level keys:
/// the first occurrence, before the nested bins and segments); floats compared by their bits.
fn compare_eval(ours: &str, json: &str) -> Result<String> {
    let mut compared = Vec::new();
    for line in ours.lines() {
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        let theirs = match key {
            "out_of_range" => continue, // a count here, a percentage there (same flags)
            k => json_number(json, k).with_context(|| format!("`tcomp eval --json` has no {k}"))?,
        };
        let ours: f64 = value.parse()?;
        ensure!(
            ours.to_bits() == theirs.to_bits(),
            "{key}: host_eval.c gives {ours:e}, tcomp eval {theirs:e}"
        );
        compared.push(format!("{key} {ours}"));
    }
    ensure!(compared.len() >= 8, "host_eval printed too little: {ours}");
    Ok(compared.join(", "))
}

/// The number after the first `"key":` of a JSON text.
fn json_number(json: &str, key: &str) -> Option<f64> {
    let at = json.find(&format!("\"{key}\":"))? + key.len() + 3;
    let rest = json.get(at..)?.trim_start();
    let end = rest.find([',', '\n', '}'])?;
    rest.get(..end)?.trim().parse().ok()
}

/// The `key=value` fields of the `REPLAY samples=…` line.
fn replay_line(text: &str) -> Result<std::collections::HashMap<String, String>> {
    let line = text
        .lines()
        .find(|l| l.starts_with("REPLAY samples="))
        .context("no REPLAY line")?;
    Ok(line
        .split_whitespace()
        .filter_map(|f| f.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect())
}

/// QEMU's mps2-an386 running `elf` with `vector` at 0x21000000.
fn qemu(elf: &Path, vector: &Path) -> Command {
    let mut q = crate::qemu::machine(elf, "shift=3,sleep=off");
    q.arg("-device").arg(format!(
        "loader,file={},addr=0x21000000,force-raw=on",
        vector.display()
    ));
    q
}

/// Bytes the linker placed in flash (`.text`, `.rodata`, `.data`'s initial values, `.ARM.exidx`)
/// from `libtcomp_ffi.a`, read from the map, and the whole image's flash.
fn flash_cost(map: &Path, elf: &Path) -> Result<(u64, u64)> {
    let text = std::fs::read_to_string(map)?;
    let body = text
        .split_once("Linker script and memory map")
        .map_or(text.as_str(), |(_, b)| b);
    let (mut lib, mut section) = (0u64, String::new());
    let mut pending: Option<String> = None;
    for line in body.lines() {
        if let Some(name) = line
            .strip_prefix('.')
            .and_then(|l| l.split_whitespace().next())
        {
            section = format!(".{name}");
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        // An input section: ` .name 0xADDR 0xSIZE file`, or its name alone on one line and the
        // rest on the next.
        let (name, rest) = match (fields.first(), &pending) {
            (Some(f), _) if f.starts_with('.') && line.starts_with(' ') => {
                if fields.len() == 1 {
                    pending = Some((*f).to_string());
                    continue;
                }
                (Some((*f).to_string()), &fields[1..])
            }
            (Some(f), Some(p)) if f.starts_with("0x") => (Some(p.clone()), &fields[..]),
            _ => (None, &fields[..]),
        };
        pending = None;
        if name.is_none() || rest.len() < 3 || !rest[2].contains("libtcomp_ffi.a") {
            continue;
        }
        if [".text", ".rodata", ".data", ".ARM.exidx"].contains(&section.as_str()) {
            lib += u64::from_str_radix(rest[1].trim_start_matches("0x"), 16)?;
        }
    }
    let sizes = crate::elf::sections(elf)?;
    let total = sizes
        .iter()
        .filter(|(n, _)| {
            [".isr_vector", ".text", ".rodata", ".data", ".ARM.exidx"].contains(&n.as_str())
        })
        .map(|(_, s)| s)
        .sum();
    ensure!(
        lib > 0 && lib <= total,
        "no library sections found in {}",
        map.display()
    );
    Ok((lib, total))
}

/// Runs `cmd` with its output in files, killed after `limit`; its standard output, or an error
/// with both outputs when it fails.
pub fn run_checked(cmd: &mut Command, limit: Duration, what: &str) -> Result<String> {
    run_both(cmd, limit, what).map(|(out, _)| out)
}

/// [`run_checked`], returning standard output and standard error (the child bounded by the
/// xtask's one runner, [`crate::proc::Bounded`]).
fn run_both(cmd: &mut Command, limit: Duration, what: &str) -> Result<(String, String)> {
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = crate::proc::Bounded::spawn(cmd, what, limit)?;
    let out = crate::proc::collect(child.take_stdout().context("stdout")?);
    let err = crate::proc::collect(child.take_stderr().context("stderr")?);
    let status = child.wait()?;
    let text = |h: std::thread::JoinHandle<Vec<u8>>| {
        String::from_utf8_lossy(&h.join().unwrap_or_default()).into_owned()
    };
    let (out, err) = (text(out), text(err));
    if !status.success() {
        bail!("{what} failed ({status}):\n{out}{err}");
    }
    Ok((out, err))
}
