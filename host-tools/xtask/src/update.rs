//! The QEMU update run: the replay firmware with its UART on a pty, updated over it by
//! `tcomp flash` (the same binary and protocol code a user runs) while the loop keeps sending
//! frames, then reset into the new image.
//!
//! QEMU's loader puts the initial image (the one with QMA z's corrupt blob) at `0x003F_0000`, the
//! start of slot A, bare as `probe-rs download` would: the firmware runs it as generation 0. The
//! update writes slot B (`0x003F_8000`) and commits it; when the vector ends the firmware resets
//! (SYSRESETREQ). QEMU then loads the ELF, the vector and slot A's bare image again, but slot B
//! survives in RAM, so the next boot must choose slot B, generation 1, and load all six models.

use crate::field;
use anyhow::{Context, Result, bail};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

/// Runs the update; `vector` is an IMU6 vector without injected board faults built for
/// `initial` (its expected outputs and `hash`), `samples` the records it serves; `update` is the
/// image sent.
pub fn run(
    work: &Path,
    elf: &Path,
    initial: &Path,
    vector: &Path,
    update: &Path,
    hash: u32,
    samples: usize,
) -> Result<()> {
    let (mut qemu, mut stdout, pty) = start_qemu(elf, initial, vector)?;
    let mut decoder = Command::new("defmt-print")
        .arg("-e")
        .arg(elf)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .context("starting defmt-print")?;
    let mut to_decoder = decoder.stdin.take().context("defmt-print stdin")?;
    let pump = std::thread::spawn(move || std::io::copy(&mut stdout, &mut to_decoder));
    let flash = Command::new(work.join("../debug/tcomp"))
        .args([
            "flash",
            "--port",
            &pty,
            "--json",
            "--timeout-ms",
            "1000",
            "--board",
        ])
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../firmware/descriptions/imu6-rlg-qma.toml"
        ))
        .arg(update)
        .output()
        .context("running tcomp flash")?;
    let report = String::from_utf8_lossy(&flash.stdout).into_owned();
    print!("{report}");
    eprint!("{}", String::from_utf8_lossy(&flash.stderr));
    let qemu_status = qemu.wait()?;
    pump.join().ok();
    let text = String::from_utf8_lossy(&decoder.wait_with_output()?.stdout).into_owned();
    print!("{text}");
    if !flash.status.success() || !report.contains("\"result\": \"ok\"") {
        bail!("tcomp flash over QEMU's pty failed");
    }
    if !qemu_status.success() {
        bail!("the QEMU update run failed ({qemu_status})");
    }
    tcomp_tests::replay::checks::check(&text, hash, samples)
        .context("the boot that received the update")?;
    let get =
        |k: &str| field(&report, k).with_context(|| format!("no {k} in tcomp flash's report"));
    let (n, lost, first, last) = (
        get("\"output_frames\": ")?,
        get("\"output_lost\": ")?,
        get("\"output_first_sequence\": ")?,
        get("\"output_last_sequence\": ")?,
    );
    if n == 0 || lost != 0 || last + 1 - first != n {
        bail!("output frames during the update: {n} from {first} to {last}, {lost} lost");
    }
    if !text.contains("UPDATE-COMMITTED slot=B generation=1") {
        bail!("the firmware did not report the commit of slot B");
    }
    let boot = text
        .lines()
        .find(|l| l.contains("UPDATE-BOOT"))
        .context("no boot after the update's reset")?;
    if !boot.contains("source=Slot(B, 1)") || field(boot, "models_loaded=") != Some(6) {
        bail!("after the reset the firmware does not run the new image: {boot}");
    }
    println!(
        "update over the UART: committed to slot B, {n} output frames during it (sequences {first}..={last}, none lost); after the reset: slot B, generation 1, 6 of 6 models"
    );
    Ok(())
}

/// Starts the replay firmware under QEMU with its UART on a pty; returns QEMU, its standard output
/// (read past the line that names the pty) and the pty's path.
fn start_qemu(
    elf: &Path,
    initial: &Path,
    vector: &Path,
) -> Result<(
    std::process::Child,
    BufReader<std::process::ChildStdout>,
    String,
)> {
    let mut qemu = crate::qemu::qemu_command(elf, initial, vector, "pty")
        .stdout(Stdio::piped())
        .spawn()
        .context("starting qemu-system-arm")?;
    // QEMU names the pty on its standard output, before the guest's semihosting (defmt) bytes,
    // which then go on to defmt-print.
    let mut stdout = BufReader::new(qemu.stdout.take().context("qemu stdout")?);
    let mut line = String::new();
    let pty = loop {
        line.clear();
        if stdout.read_line(&mut line)? == 0 {
            bail!("QEMU named no pty for its serial port");
        }
        if let Some(rest) = line.split("char device redirected to ").nth(1) {
            eprint!("{line}");
            break rest
                .split_whitespace()
                .next()
                .context("pty path")?
                .to_string();
        }
    };
    Ok((qemu, stdout, pty))
}
