//! The QEMU update run: the replay firmware with its UART on a pty, updated over it by
//! `tcomp flash` (the same binary and protocol code a user runs) while the loop keeps sending
//! frames, then reset into the new image.
//!
//! QEMU's loader puts the initial image (the one with QMA z's corrupt blob) at `0x003F_0000`, the
//! start of slot A, bare as `probe-rs download` would: the firmware runs it as generation 0. The
//! update writes slot B (`0x003F_8000`) and commits it; when the vector ends the firmware resets
//! (SYSRESETREQ). QEMU then loads the ELF, the vector and slot A's bare image again, but slot B
//! survives in RAM, so the next boot must choose slot B, generation 1, and load all six models.
//!
//! Before it, the same image signed by a key the unit was not provisioned with is sent: the unit
//! must refuse it at COMMIT (RESULT `UnknownKey`), keep running its models (the boot's records
//! stay bit-exact) and say so in the boot report it sends at once (last update refused, and why).
//! The refused session leaves slot B written, and nothing erases while the loop runs: the good
//! image's first BEGIN is refused (`flash error`), the unit resets once that reply has left, its
//! boot erases slot B before the watchdog starts, and the same `tcomp flash` waits for the unit's
//! first sample after that boot and sends the image again (it must say so:
//! `sent_again_after_reset`); that boot replays the vector from its start, compared bit for bit
//! as before.

use crate::field;
use crate::proc::{self, Bounded};
use anyhow::{Context, Result, bail};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{ChildStdout, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// How long `tcomp flash` waits for each reply before it repeats the request. Generous against the
/// guest's clock: QEMU runs the guest several times faster than real time (`-icount` without
/// sleeping), and the firmware keeps its loop running until the update has committed, so a longer
/// wait only costs wall time when a request is really lost.
const REPLY_TIMEOUT_MS: &str = "3000";
/// The whole `tcomp flash`: about 1 s of wall time for a 6-channel image.
const FLASH_LIMIT: Duration = proc::minutes(4);
/// QEMU naming its pty: at once.
const PTY_LIMIT: Duration = Duration::from_secs(30);

/// Runs the update; `vector` is an IMU6 vector without injected board faults built for
/// `initial` (its expected outputs and `hash`), `samples` the records it serves; `update` is the
/// image sent, after `rogue` (signed by another key) is refused.
#[allow(clippy::too_many_arguments)]
pub fn run(
    work: &Path,
    elf: &Path,
    initial: &Path,
    vector: &Path,
    rogue: &Path,
    update: &Path,
    hash: u32,
    samples: usize,
) -> Result<()> {
    let (mut qemu, stdout, pty) = start_qemu(elf, initial, vector)?;
    let log = proc::collect(stdout);
    refused(work, &pty, rogue)?;
    let flash = flash(work, &pty, update, "`tcomp flash` over QEMU's pty")?;
    let report = String::from_utf8_lossy(&flash.stdout).into_owned();
    print!("{report}");
    // The firmware holds its loop until the update commits, then ends its run; if `tcomp flash`
    // failed, QEMU is killed when `qemu` is dropped.
    if !flash.status.success() || !report.contains("\"result\": \"ok\"") {
        bail!("tcomp flash over QEMU's pty failed ({})", flash.status);
    }
    // The refused session left slot B written: the unit refused the first BEGIN, reset, its boot
    // erased slot B (before the watchdog starts), and `tcomp flash` sent the image again.
    if !report.contains("\"sent_again_after_reset\": true") {
        bail!("tcomp flash did not go through the unit's reset and boot erase of slot B");
    }
    println!(
        "update after the refused one: the unit reset to erase slot B at boot, `tcomp flash` \
         waited for its first sample and sent the image again"
    );
    let qemu_status = qemu.wait()?;
    let bytes = log.join().unwrap_or_default();
    let text = crate::defmt::decode(elf, &bytes)?;
    print!("{text}");
    if !qemu_status.success() {
        bail!("the QEMU update run failed ({qemu_status})");
    }
    let summary = tcomp_tests::replay::checks::check(&text, hash, samples)
        .context("the boot that received the update")?;
    let get =
        |k: &str| field(&report, k).with_context(|| format!("no {k} in tcomp flash's report"));
    let (n, lost, first, last) = (
        get("\"output_frames\": ")?,
        get("\"output_lost\": ")?,
        get("\"output_first_sequence\": ")?,
        get("\"output_last_sequence\": ")?,
    );
    // QEMU runs the guest several times faster than real time, so the frames come out of the pty
    // faster than `tcomp flash` reads them while it sends: when the pty's buffer is full, UART 0
    // stops taking bytes, the frame queue fills and the application drops whole frames (its
    // overflow policy). Every frame the host finds missing must be one the unit counted as dropped
    // whole; a frame cut, corrupted or lost otherwise would show as more gaps than drops.
    if n == 0 || last + 1 - first != n + lost || lost > summary.dropped {
        bail!(
            "output frames during the update: {n} from {first} to {last}, {lost} lost, {} dropped \
             whole by the unit",
            summary.dropped
        );
    }
    if !text.contains("UPDATE-COMMITTED Slot(B, 1)") {
        bail!("the firmware did not report the commit of slot B");
    }
    let boot = text
        .lines()
        .find(|l| l.contains("UPDATE-BOOT"))
        .context("no boot after the update's reset")?;
    if !boot.contains("source=Slot(B, 1)") || field(boot, "models_loaded=") != Some(6) {
        bail!("after the reset the firmware does not run the new image: {boot}");
    }
    // The new image's first boot is its trial: the application confirms it after 10 s of the
    // loop with every task alive, and the old one is kept until then.
    let trial = text
        .lines()
        .find(|l| l.contains("UPDATE-TRIAL"))
        .context("the boot after the update did not end its trial")?;
    if !trial.contains("source=Slot(B, 1) confirmed=true slot_state=Some(Confirmed)") {
        bail!("the new image's trial boot did not confirm it: {trial}");
    }
    println!(
        "update over the UART: committed to slot B, {n} output frames during it (sequences \
         {first}..={last}; {lost} missing, each dropped whole by the unit's queue: {} drops in \
         all); after the reset: slot B, generation 1, 6 of 6 models, on trial, confirmed",
        summary.dropped
    );
    Ok(())
}

/// `tcomp flash` of an image signed by a key the unit does not hold: refused before the commit,
/// with the reason in the RESULT and in the unit's boot report, which still names its image.
fn refused(work: &Path, pty: &str, rogue: &Path) -> Result<()> {
    let out = flash(
        work,
        pty,
        rogue,
        "`tcomp flash` of an image signed by another key",
    )?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    print!("{text}");
    let held = "image signed by a key this unit does not hold";
    let says = |k: &str, v: &str| text.contains(&format!("\"{k}\": \"{v}"));
    if out.status.success()
        || !says("result", "failed")
        || !says("reason", &format!("the unit refused: {held}"))
        || !says("last_update", "refused")
        || !says("last_update_reason", held)
        || !says("image_state", "ok")
    {
        bail!("the image signed by another key was not refused as it should be: {text}");
    }
    println!(
        "update with an image signed by another key: refused before the commit ({held}); the unit's boot report says so, and its image is still the one it ran"
    );
    Ok(())
}

/// `tcomp flash --json` of `image` over `pty`, at the description's baud, bounded.
fn flash(work: &Path, pty: &str, image: &Path, what: &str) -> Result<std::process::Output> {
    proc::output(
        Command::new(work.join("../debug/tcomp"))
            .args([
                "flash",
                "--port",
                pty,
                "--json",
                "--timeout-ms",
                REPLY_TIMEOUT_MS,
                "--board",
            ])
            .arg(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../firmware/descriptions/imu6-rlg-qma.toml"
            ))
            .arg(image),
        what,
        FLASH_LIMIT,
    )
}

/// Starts the replay firmware under QEMU (bounded) with its UART on a pty; returns QEMU, its
/// standard output (read past the line that names the pty) and the pty's path.
fn start_qemu(
    elf: &Path,
    initial: &Path,
    vector: &Path,
) -> Result<(Bounded, BufReader<ChildStdout>, String)> {
    let mut cmd = crate::qemu::qemu_command(elf, initial, vector, "pty");
    cmd.stdout(Stdio::piped());
    let mut qemu = Bounded::spawn(&mut cmd, "the QEMU update run", crate::qemu::QEMU_LIMIT)?;
    // QEMU names the pty on its standard output, before the guest's semihosting (defmt) bytes,
    // which the caller decodes. Read on a thread, so a QEMU that never names it fails in time.
    let stdout = BufReader::new(qemu.take_stdout().context("qemu stdout")?);
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut stdout = stdout;
        let mut line = String::new();
        let found = loop {
            line.clear();
            match stdout.read_line(&mut line) {
                Ok(0) | Err(_) => break None,
                Ok(_) => {}
            }
            if let Some(rest) = line.split("char device redirected to ").nth(1) {
                eprint!("{line}");
                break rest.split_whitespace().next().map(str::to_string);
            }
        };
        let _ = tx.send(found.map(|pty| (pty, stdout)));
    });
    match rx.recv_timeout(PTY_LIMIT) {
        Ok(Some((pty, stdout))) => Ok((qemu, stdout, pty)),
        Ok(None) => bail!("QEMU named no pty for its serial port"),
        Err(_) => bail!("QEMU named no pty within {} s: killed", PTY_LIMIT.as_secs()),
    }
}
