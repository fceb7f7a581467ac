//! `cargo xtask qemu`: models and vectors from the simulator, the firmware's loop on the host, the
//! same loop under QEMU fed through QEMU's loader (no rebuild for a new image or vector), bit-exact
//! comparison, fault checks and budgets, ending with one `QEMU-SUMMARY` line.

use crate::vector::{Csv, Inputs, QMA_PER_PULSE, RLG_PER_PULSE, build, expect_flag};
use crate::{TARGET, cargo, field};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use tcomp_core::frame::{BootReport, Decoder, Item, boot_len, image_state};
use tcomp_firmware::app::{IFOG1, IMU6, PERIOD_S, status};
use tcomp_firmware::boot::REPORT_PERIODS;
use tcomp_firmware::image::Image;
use tcomp_firmware::replay::{
    CONFIG_IFOG1, CONFIG_IMU6, HANG, MISS, STALL, TIME_GLITCH, UNIT_SERIAL,
};

/// Budgets, from the issue and the part. Instructions: the worst 6-channel sample with every model
/// evaluated every sample (no stagger): 11,360 measured. Flash: an STM32F405/407 has 1 MiB, less
/// the two 128 KiB sectors 10–11 that hold the model slots (the board crate's budget, `board.rs`).
/// Memory: static RAM + stack ≤ 16 KiB for the 6-channel run; measured 11,732 B static (the `App`
/// with six models) + 4,052 B stack (6,544 B while the blob was decoded by value: serde moved the
/// model through four stack copies; `Model::decode_into` decodes in place).
const WORST_INSTRUCTIONS_BUDGET: u64 = 12_000;
const RAM_BUDGET: u64 = 16 * 1024;
const FLASH_BUDGET: u64 = crate::board::FLASH_BUDGET;
const SAMPLES: usize = 10_000;
/// The core's clock on the STM32F407 board, for the CPU load the instruction counts mean (an M4F
/// retires about one of these instructions per cycle; flash wait states are hidden by the ART
/// accelerator for straight-line code).
const CORE_HZ: f64 = 168e6;
const SAMPLE_HZ: f64 = 200.0;

fn tcomp(dir: &Path, args: &[&str]) -> Result<()> {
    let exe = dir.join("../debug/tcomp");
    let status = Command::new(&exe)
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .status()
        .with_context(|| format!("running {}", exe.display()))?;
    if !status.success() {
        bail!("`tcomp {}` failed", args.join(" "));
    }
    Ok(())
}

/// Models: the seed presets at 1 Hz, 32 centers × 4 features each.
fn fit_models(work: &Path) -> Result<()> {
    let fits: [(&str, &str, &str, &str, [&str; 4]); 3] = [
        (
            "rlg",
            "gyro_dph",
            "ref_dph",
            "T=mean(t_anode_c,t_cathode_c,t_shell_c)",
            [
                "T",
                "rate(T)",
                "t_anode_c - t_shell_c",
                "t_cathode_c - t_shell_c",
            ],
        ),
        (
            "qma",
            "accel_ug",
            "ref_ug",
            "T=t_qma_c",
            ["T", "rate(T)", "lag(T, 1200)", "T * rate(T)"],
        ),
        (
            "ifog-shupe",
            "gyro_dph",
            "ref_dph",
            "T=t_coil_c",
            ["T", "rate(T)", "T * rate(T)", "lag(T, 2400)"],
        ),
    ];
    for (preset, target, reference, signal, features) in fits {
        tcomp(work, &["simulate", "--preset", preset, "--out", preset])?;
        // One blob per channel: the numbers are the preset's, the metadata (sensor kind, axis,
        // unit) the channel's row in the board description, which `tcomp image --board` and the
        // firmware check each blob against.
        let (sensor, unit, axes): (&str, &str, &[&str]) = match preset {
            "rlg" => ("rlg", "deg/h", &["x", "y", "z"]),
            "qma" => ("qma", "ug", &["x", "y", "z"]),
            _ => ("ifog", "deg/h", &["x"]),
        };
        for axis in axes {
            let data = format!("{preset}/train.csv");
            let out = format!("{preset}-{axis}.tcm");
            let mut args = vec![
                "fit",
                "--data",
                &data,
                "--target",
                target,
                "--reference",
                reference,
                "--signal",
                signal,
                "--centers",
                "32",
                "--sensor",
                sensor,
                "--axis",
                axis,
                "--unit",
                unit,
                "--out",
                &out,
                "--quiet",
            ];
            for f in &features {
                args.extend_from_slice(&["--feature", f]);
            }
            tcomp(work, &args)?;
        }
    }
    Ok(())
}

/// Runs the replay binary under QEMU with `image` and `vector` loaded and UART 0 captured into
/// `uart`, decodes its defmt output (boot messages and the summary, over semihosting) with
/// `defmt-print`, and returns the decoded text; fails on QEMU's exit code. QEMU restarts the guest
/// on a watchdog reset (no `-no-reboot`): the loaders and the ELF are loaded again, the rest of RAM
/// and the UART capture go on.
fn run_qemu(elf: &Path, image: &Path, vector: &Path, uart: &Path) -> Result<String> {
    let mut qemu = Command::new("qemu-system-arm")
        .args([
            "-cpu",
            "cortex-m4",
            "-machine",
            "mps2-an386",
            "-nographic",
            "-monitor",
            "none",
            "-semihosting-config",
            "enable=on,target=native",
            "-icount",
            "shift=3,sleep=off",
            "-serial",
        ])
        .arg(format!("file:{}", uart.display()))
        .arg("-kernel")
        .arg(elf)
        .arg("-device")
        .arg(format!(
            "loader,file={},addr=0x3F0000,force-raw=on",
            image.display()
        ))
        .arg("-device")
        .arg(format!(
            "loader,file={},addr=0x21000000,force-raw=on",
            vector.display()
        ))
        .stdout(Stdio::piped())
        .spawn()
        .context("starting qemu-system-arm")?;
    let frames = qemu.stdout.take().context("qemu stdout")?;
    let decoder = Command::new("defmt-print")
        .arg("-e")
        .arg(elf)
        .stdin(frames)
        .stdout(Stdio::piped())
        .spawn()
        .context("starting defmt-print (cargo install defmt-print --locked)")?;
    let qemu_status = qemu.wait()?;
    let decoded = decoder.wait_with_output()?;
    let text = String::from_utf8_lossy(&decoded.stdout).into_owned();
    print!("{text}");
    if !qemu_status.success() {
        bail!("the QEMU replay failed ({qemu_status})");
    }
    Ok(text)
}

/// Decodes every frame of the UART capture with the core's decoder and compares each with the
/// host's frame of the same sequence number, byte for byte (values as f64 bits, status words with
/// the board's bits, timestamps). Returns the frames decoded.
fn compare_frames(capture: &[u8], expected: &[Vec<u8>]) -> Result<(usize, Vec<BootReport>)> {
    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    let mut reports = Vec::new();
    decoder.feed_items(capture, |i| match i {
        Item::Data(f) => frames.push(f),
        Item::Boot(r) => reports.push(r),
    });
    let stats = decoder.stats();
    let mut mismatches = 0;
    let mut first = None;
    for f in &frames {
        let mut buf = vec![0u8; f.len()];
        let len = f.encode(&mut buf).map_err(|e| anyhow::anyhow!("{e}"))?;
        let same = expected
            .get(f.sequence as usize)
            .is_some_and(|e| !e.is_empty() && e[..] == buf[..len]);
        if !same {
            mismatches += 1;
            first.get_or_insert(f.sequence);
        }
    }
    // Samples the board never served (a missed period) have no frame.
    let want = expected.iter().filter(|e| !e.is_empty()).count();
    if frames.len() != want || mismatches != 0 {
        bail!(
            "UART frames differ from the host's: {} decoded of {want} ({stats:?}), {mismatches} \
             mismatches (first at sequence {first:?})",
            frames.len(),
        );
    }
    let reported: usize = reports.iter().map(|r| boot_len(r.channels().len())).sum();
    let sent: usize = expected.iter().map(Vec::len).sum::<usize>() + reported;
    if capture.len() != sent {
        bail!(
            "UART capture is {} B, the host's frames and the boot reports {sent} B",
            capture.len()
        );
    }
    Ok((frames.len(), reports))
}

/// The boot reports of a run: one per boot (`boots`) plus one every `REPORT_PERIODS` served
/// samples, each naming this unit, the image made for it, and per channel the load state the
/// host's loop had (`states`); the report after a watchdog reset says so.
fn check_reports(
    reports: &[BootReport],
    boots: usize,
    served: &[bool],
    states: &[u8],
) -> Result<()> {
    let periodic = served
        .iter()
        .enumerate()
        .filter(|&(n, &s)| s && (n as u32 + 1).is_multiple_of(REPORT_PERIODS))
        .count();
    if reports.len() != boots + periodic {
        bail!(
            "{} boot reports, expected {boots} boots + {periodic} periodic",
            reports.len()
        );
    }
    for r in reports {
        let got: Vec<u8> = r.channels().iter().map(|c| c.state).collect();
        if r.unit_serial != UNIT_SERIAL
            || r.image_serial != UNIT_SERIAL
            || r.image_version != 2
            || r.image_state != image_state::OK
            || got != states
        {
            bail!("boot report {r:?}: expected unit {UNIT_SERIAL:#x}, image v2, states {states:?}");
        }
    }
    if boots > 1 && !reports.iter().any(|r| r.flags & 1 != 0) {
        bail!("no boot report says the watchdog reset the unit");
    }
    Ok(())
}

/// The firmware's summary numbers of one run.
pub struct Summary {
    samples: u64,
    flagged: u64,
    mean: u64,
    max: u64,
    late: u64,
    missed: u64,
    resets: u64,
    stack: u64,
}

/// The firmware's summary numbers of one run, checked against the host's hash.
pub fn check(text: &str, host_hash: u32, samples: usize) -> Result<Summary> {
    let line = text
        .lines()
        .find(|l| l.contains("REPLAY-SUMMARY"))
        .context("no REPLAY-SUMMARY")?;
    let get = |k: &str| field(line, k).with_context(|| format!("no {k} in {line}"));
    let (n, mismatches, flagged, hash) = (
        get("samples=")?,
        get("mismatches=")?,
        get("flagged=")?,
        get("hash=")?,
    );
    if n != samples as u64 {
        bail!("the firmware ran {n} samples of {samples}");
    }
    if mismatches != 0 || hash != u64::from(host_hash) {
        bail!(
            "firmware outputs differ from the host's: {mismatches} mismatches, hash {hash} vs {host_hash}"
        );
    }
    Ok(Summary {
        samples: n,
        flagged,
        mean: get("instructions_mean=")?,
        max: get("instructions_max=")?,
        late: get("late=")?,
        missed: get("missed=")?,
        resets: get("watchdog_resets=")?,
        stack: get("stack_bytes=")?,
    })
}

pub fn qemu() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let target_dir =
        std::env::var_os("CARGO_TARGET_DIR").map_or(root.join("target"), PathBuf::from);
    let work = target_dir.join("qemu-replay");
    std::fs::create_dir_all(&work)?;
    cargo(&[
        "build",
        "-p",
        "tcomp-firmware",
        "--target",
        TARGET,
        "--release",
        "--bin",
        "replay",
    ])?;
    let elf = target_dir.join(TARGET).join("release/replay");
    // The host CLI makes the models and vectors; build it so `cargo xtask qemu` stands alone.
    cargo(&["build", "-p", "tcomp"])?;
    fit_models(&work)?;
    for k in ["rlg", "qma", "ifog"] {
        let toml = root.join(format!("firmware/replay/{k}.toml"));
        let toml = toml.to_str().context("path")?;
        tcomp(
            &work,
            &[
                "simulate",
                "--scenario",
                toml,
                "--out",
                &format!("vector-{k}"),
            ],
        )?;
    }
    // The images, made as a user makes them: the shipped board descriptions, the unit serial the
    // replay board reports, a pinned creation time so the bytes are reproducible.
    let serial = tcomp_firmware::replay::UNIT_SERIAL.to_string();
    let descriptions = root.join("firmware/descriptions");
    let imu6_board = descriptions.join("imu6-rlg-qma.toml");
    let ifog_board = descriptions.join("ifog1.toml");
    let mut model_args: Vec<String> = vec!["image".into(), "--board".into()];
    model_args.push(imu6_board.to_str().context("path")?.into());
    for (id, m) in ["rlg-x", "rlg-y", "rlg-z", "qma-x", "qma-y", "qma-z"]
        .iter()
        .enumerate()
    {
        model_args.extend(["--model".into(), format!("{id}={m}.tcm")]);
    }
    model_args.extend([
        "--serial".into(),
        serial.clone(),
        "--created".into(),
        "0".into(),
    ]);
    model_args.extend(["--out".into(), "models.bin".into()]);
    tcomp(
        &work,
        &model_args.iter().map(String::as_str).collect::<Vec<_>>(),
    )?;
    let ifog_board = ifog_board.to_str().context("path")?;
    tcomp(
        &work,
        &[
            "image",
            "--board",
            ifog_board,
            "--model",
            "0=ifog-shupe-x.tcm",
            "--serial",
            &serial,
            "--created",
            "0",
            "--out",
            "models-ifog.bin",
        ],
    )?;
    let image = std::fs::read(work.join("models.bin"))?;
    let ifog_image = std::fs::read(work.join("models-ifog.bin"))?;

    // A second image with QMA z's blob corrupted: one flipped byte in its middle, the image
    // re-sealed (its whole-image CRC recomputed), so that the blob's own CRC is what refuses it
    // and only that channel runs without a model.
    let mut corrupt = image.clone();
    let table = Image::parse(&image).map_err(|e| anyhow::anyhow!("image: {e:?}"))?;
    let (_, blob) = table
        .entry(5)
        .map_err(|e| anyhow::anyhow!("image: {e:?}"))?;
    let at = blob.as_ptr() as usize - image.as_ptr() as usize + blob.len() / 2;
    corrupt[at] ^= 0x10;
    tcomp_core::image::seal(&mut corrupt).map_err(|e| anyhow::anyhow!("image: {e:?}"))?;
    std::fs::write(work.join("models-corrupt.bin"), &corrupt)?;

    // IMU6 vector: three RLG axes from one 200 Hz slice (offset rows), three QMA axes likewise.
    let rlg = Csv::read(&work.join("vector-rlg/train.csv"))?;
    let qma = Csv::read(&work.join("vector-qma/train.csv"))?;
    let ifog = Csv::read(&work.join("vector-ifog/train.csv"))?;
    let mut imu = Inputs::new(SAMPLES);
    for axis in 0..3 {
        for col in ["t_anode_c", "t_cathode_c", "t_shell_c"] {
            imu.thermometer(&rlg.column(col, axis * 300, SAMPLES)?);
        }
    }
    for axis in 0..3 {
        imu.thermometer(&qma.column("t_qma_c", axis * 300, SAMPLES)?);
    }
    for axis in 0..3 {
        // RLG x wraps through zero at about sample 1000 (5,000 pulses per sample).
        let wrap = if axis == 0 { 5_000_000 } else { 1 << 31 };
        imu.counter(
            &rlg.column("gyro_dph", axis * 300, SAMPLES)?,
            RLG_PER_PULSE,
            wrap,
        );
    }
    for axis in 0..3 {
        // 500,000 pulses per sample: QMA x wraps at about sample 1500, the others later.
        let wrap = if axis == 0 {
            750_000_000
        } else {
            3_000_000_000
        };
        imu.counter(
            &qma.column("accel_ug", axis * 300, SAMPLES)?,
            QMA_PER_PULSE,
            wrap,
        );
    }
    // Faults: ADC bus error, NaN, stuck, out of trained range, counter bus error, and the new ones.
    for n in 2000..2010 {
        imu.therm_faults[0][n] = true; // RLG x anode: bus error
    }
    for n in 3000..3005 {
        imu.temps[10][n] = f32::NAN; // QMA y: NaN reading
    }
    let stuck = imu.temps[8][4000];
    for n in 4000..5000 {
        imu.temps[8][n] = stuck; // RLG z shell: stuck
    }
    // QMA x: 70 °C above the trained range by 9000, reached at 4 °C/s (a step would be refused as
    // an implausible jump before the range check sees it), held to the end.
    for n in 5500..SAMPLES {
        let ramp = ((n - 5500) as f32 / 3500.0).min(1.0);
        imu.temps[9][n] += 70.0 * ramp;
    }
    for n in 7000..7004 {
        imu.counter_faults[4][n] = true; // QMA y counter: bus error
    }
    for n in 6500..6503 {
        imu.counter_flagged[1][n] = true; // RLG y counter: flagged intervals (pulses lost)
    }
    for n in 8000..8010 {
        imu.temps[4][n] += 3.0; // RLG y cathode: jumps 3 °C within range for 50 ms
    }
    imu.board_faults[1500] |= STALL; // sample 1500 overruns: 1501 is late
    imu.board_faults[2500] |= TIME_GLITCH; // 2500's timestamp is half a period off
    imu.board_faults[6000] |= HANG; // the loop hangs in 6000: the watchdog resets
    imu.board_faults[3500] |= MISS; // 3500 overruns past 3501's edge: 3502 covers two periods
    let wrap_at = (1..SAMPLES)
        .find(|&n| imu.counters[0][n] < imu.counters[0][n - 1])
        .context("no wrap")?;

    let a = build(CONFIG_IMU6, &IMU6, &imu, &image)?;
    let b = build(CONFIG_IMU6, &IMU6, &imu, &corrupt)?;
    let mut ifog_in = Inputs::new(SAMPLES);
    ifog_in.thermometer(&ifog.column("t_coil_c", 0, SAMPLES)?);
    ifog_in.counter(
        &ifog.column("gyro_dph", 0, SAMPLES)?,
        RLG_PER_PULSE,
        1 << 31,
    );
    for n in 5000..5003 {
        ifog_in.therm_faults[0][n] = true;
    }
    let c = build(CONFIG_IFOG1, &IFOG1, &ifog_in, &ifog_image)?;

    let fault = status::SENSOR_ERROR | status::INPUT_FAULT;
    let sa = &a.statuses;
    expect_flag(sa, "ADC bus error (RLG x anode)", 0, 2000..2010, fault)?;
    expect_flag(
        sa,
        "NaN reading (QMA y)",
        4,
        3000..3005,
        status::INPUT_FAULT,
    )?;
    expect_flag(
        sa,
        "stuck thermometer (RLG z shell)",
        2,
        4400..5000,
        status::STUCK,
    )?;
    expect_flag(
        sa,
        "temperature outside the trained range (QMA x)",
        3,
        9000..9100,
        status::OUT_OF_RANGE,
    )?;
    expect_flag(sa, "counter bus error (QMA y)", 4, 7000..7004, fault)?;
    expect_flag(
        sa,
        "counter interval flagged (RLG y)",
        1,
        6500..6503,
        status::SENSOR_ERROR,
    )?;
    expect_flag(
        sa,
        "thermometer jump within range (RLG y cathode)",
        1,
        8000..8010,
        status::TEMP_JUMP | status::INPUT_FAULT,
    )?;
    for k in 0..IMU6.len() {
        expect_flag(
            sa,
            "overrun (sample 1500 too long)",
            k,
            1501..1502,
            status::OVERRUN,
        )?;
        expect_flag(sa, "timestamp jump", k, 2500..2502, status::TIME_JUMP)?;
        expect_flag(
            sa,
            "watchdog reset (loop hung in sample 6000)",
            k,
            6001..6002,
            status::WATCHDOG_RESET,
        )?;
    }
    expect_flag(
        &b.statuses,
        "corrupt blob (QMA z)",
        5,
        0..SAMPLES,
        status::NO_MODEL,
    )?;
    expect_flag(
        &c.statuses,
        "ADC bus error (IFOG coil)",
        0,
        5000..5003,
        fault,
    )?;
    // A mishandled wrap is a jump of 2^32 pulses (8.6e6 deg/h); the gyro's own noise is a few deg/h.
    let out_a = &a.outputs;
    let (before, after) = (out_a[wrap_at - 1][0], out_a[wrap_at][0]);
    if after.status != 0 || (after.compensated - before.compensated).abs() > 100.0 {
        bail!("counter wrap at sample {wrap_at} disturbed RLG x: {before:?} -> {after:?}");
    }
    println!("counter wrap-around (RLG x, sample {wrap_at}): output continuous, status ok");
    let after_gap = out_a[7004][4];
    if after_gap.status & status::SENSOR_ERROR != 0 || !after_gap.compensated.is_finite() {
        bail!("QMA y did not recover after its counter bus error: {after_gap:?}");
    }
    // After the flagged intervals RLG y's next interval is one period again: exact, not flagged.
    let after_flag = out_a[6503][1];
    if after_flag.status & status::SENSOR_ERROR != 0 || after_flag.periods != 1 {
        bail!("RLG y after its flagged intervals: {after_flag:?}");
    }
    // The missed period: record 3501 never served, 3502 covers both periods over their latched
    // interval, flagged OVERRUN, no TIME_JUMP (the board counted the missed edge).
    if a.served[3501] || !a.served[3502] {
        bail!("the missed period did not skip exactly record 3501");
    }
    for k in 0..IMU6.len() {
        let r = out_a[3502][k];
        let s = sa[3502].map_or(0, |o| o[k]);
        if r.periods != 2 || s & status::OVERRUN == 0 || s & status::TIME_JUMP != 0 {
            bail!("channel {k} after the missed period: {r:?}, status {s:#x}");
        }
    }
    println!(
        "missed timer period (sample 3500 overruns past the next edge): 3502 covers two periods, flagged OVERRUN"
    );
    // The rates divide by the latched (jittered) intervals, not the nominal period: most records
    // of a valid count must carry an interval other than the nominal one.
    let latched = out_a
        .iter()
        .flatten()
        .filter(|r| r.periods > 0 && r.interval_s != PERIOD_S * f32::from(r.periods))
        .count();
    if latched < SAMPLES * IMU6.len() / 2 {
        bail!("only {latched} IMU6 records were divided by a latched interval");
    }
    println!("rates from the latched interval: {latched} IMU6 records off the nominal period");
    println!("the loop goes on after every fault (checked above and frame by frame below)");

    let mut samples = 0;
    let mut flagged = 0;
    let mut frames = 0;
    let mut timing = None;
    let mut stack = 0;
    /// Name, vector, image file, the host's hash, the host's frames.
    type Run<'a> = (&'a str, &'a [u8], &'a str, u32, &'a [Vec<u8>], &'a [bool]);
    let runs: [Run<'_>; 3] = [
        ("imu6", &a.bytes, "models.bin", a.hash, &a.frames, &a.served),
        (
            "imu6-corrupt-blob",
            &b.bytes,
            "models-corrupt.bin",
            b.hash,
            &b.frames,
            &b.served,
        ),
        (
            "ifog1",
            &c.bytes,
            "models-ifog.bin",
            c.hash,
            &c.frames,
            &c.served,
        ),
    ];
    for (name, bin, image, hash, expected, served) in runs {
        let path = work.join(format!("vector-{name}.bin"));
        let uart = work.join(format!("uart-{name}.bin"));
        std::fs::write(&path, bin)?;
        println!("--- QEMU replay: {name} ---");
        let text = run_qemu(&elf, &work.join(image), &path, &uart)?;
        let s = check(&text, hash, served.iter().filter(|&&s| s).count())?;
        let capture = std::fs::read(&uart).with_context(|| format!("{}", uart.display()))?;
        let (n, reports) = compare_frames(&capture, expected)?;
        println!("{name}: {n} UART frames decoded, each identical to the host's");
        let boots = if name.starts_with("imu6") { 2 } else { 1 };
        // QMA z's corrupt blob: refused by its own CRC (LoadError::Blob, code 4).
        let states: &[u8] = match name {
            "imu6" => &[0; 6],
            "imu6-corrupt-blob" => &[0, 0, 0, 0, 0, 4],
            _ => &[0],
        };
        check_reports(&reports, boots, served, states)?;
        println!(
            "{name}: {} boot reports (unit {UNIT_SERIAL:#x}, image v2, every channel as loaded)",
            reports.len()
        );
        // Both IMU6 runs replay the same inputs: one stalled sample, one missed period (its
        // sample late too) and one hang each.
        let (want_late, want_missed, want_resets) = if name.starts_with("imu6") {
            (2, 1, 1)
        } else {
            (0, 0, 0)
        };
        if s.late != want_late || s.missed != want_missed || s.resets != want_resets {
            bail!(
                "{name}: {} late samples, {} missed periods, {} watchdog resets; expected \
                 {want_late}, {want_missed}, {want_resets}",
                s.late,
                s.missed,
                s.resets
            );
        }
        samples += s.samples;
        flagged += s.flagged;
        frames += n;
        stack = stack.max(s.stack);
        if name == "imu6" {
            timing = Some((s.mean, s.max));
        }
    }
    // The update run: the same IMU6 inputs without the board's injected faults (a watchdog reset
    // would boot the new image in the middle of the vector), the corrupt image as the initial one.
    imu.board_faults.iter_mut().for_each(|f| *f = 0);
    let d = build(CONFIG_IMU6, &IMU6, &imu, &corrupt)?;
    let vector_d = work.join("vector-imu6-update.bin");
    std::fs::write(&vector_d, &d.bytes)?;
    println!("--- QEMU update over the UART ---");
    crate::update::run(
        &work,
        &elf,
        &work.join("models-corrupt.bin"),
        &vector_d,
        &work.join("models.bin"),
        d.hash,
        d.served.iter().filter(|&&s| s).count(),
    )?;
    let (mean, worst) = timing.context("no imu6 run")?;
    println!("{frames} UART frames in all, decoded and identical to the host's");
    let (flash, static_ram) = crate::elf::flash_and_static_ram(&elf)?;
    let (board_flash, board_ram) = crate::board::sizes()?;
    let load = |i: u64| i as f64 * SAMPLE_HZ / CORE_HZ * 100.0;
    println!(
        "instructions per 6-channel sample (every model every sample): mean {mean}, worst {worst} \
         (budget {WORST_INSTRUCTIONS_BUDGET}); at 168 MHz and 200 Hz: {:.2} % CPU mean, {:.2} % worst",
        load(mean),
        load(worst)
    );
    println!(
        "the loop's state (`App`: 6 decoded models + channel state) is {} B on the host, in a static",
        std::mem::size_of::<tcomp_firmware::app::App<'static>>()
    );
    println!(
        "flash {flash} B (budget {FLASH_BUDGET}), static RAM {static_ram} B + stack peak {stack} B = {} B (budget {RAM_BUDGET})",
        static_ram + stack
    );
    println!(
        "QEMU-SUMMARY samples={samples} mismatches=0 faults_flagged={flagged} transport=uart timer=hw \
         worst_instructions_per_sample={worst} instructions_per_sample={mean} \
         static_ram_bytes={static_ram} stack_bytes={stack} board=stm32f4 \
         board_flash_bytes={board_flash} board_static_ram_bytes={board_ram}"
    );
    let mut over = Vec::new();
    if worst > WORST_INSTRUCTIONS_BUDGET {
        over.push(format!(
            "worst instructions {worst} > {WORST_INSTRUCTIONS_BUDGET}"
        ));
    }
    if flash > FLASH_BUDGET {
        over.push(format!("flash {flash} > {FLASH_BUDGET}"));
    }
    if static_ram + stack > RAM_BUDGET {
        over.push(format!(
            "static RAM + stack {} > {RAM_BUDGET}",
            static_ram + stack
        ));
    }
    if !over.is_empty() {
        bail!("over budget: {}", over.join(", "));
    }
    Ok(())
}
