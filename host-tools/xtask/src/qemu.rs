//! `cargo xtask qemu`: models and vectors from the simulator, the firmware's loop on the host, the
//! same loop under QEMU fed through QEMU's loader (no rebuild for a new image or vector), bit-exact
//! comparison, fault checks and budgets, ending with one `QEMU-SUMMARY` line.

use crate::proc;
use crate::{TARGET, cargo};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;
use tcomp_firmware::app::{IFOG1, IMU6};
use tcomp_firmware::image::Image;
use tcomp_firmware::replay::{CONFIG_IFOG1, CONFIG_IMU6, UNIT_SERIAL};
use tcomp_tests::replay::checks::{
    check, check_continuity, check_fault_flags, check_reports, check_status, compare_frames,
};
use tcomp_tests::replay::scenario::{ifog_inputs, imu6_inputs};
use tcomp_tests::replay::vector::{Built, Inputs, build};

/// The budgets, the part's (see `budget.rs`).
use crate::budget::{
    CORE_HZ, CYCLES_PER_INSTRUCTION, FLASH_BUDGET, SAMPLE_HZ,
    SAMPLE_TASK_INSTRUCTIONS as WORST_INSTRUCTIONS_BUDGET, STACK_BUDGET, STATIC_RAM_BUDGET,
};
/// The sample after missed timer periods carries every channel's filters across the gap too
/// (`tcomp_core::stream`'s gap step): the same budget (it was its own before, when the ordinary
/// sample's was within 1 % of it).
const GAP_SAMPLE_BUDGET: u64 = WORST_INSTRUCTIONS_BUDGET;
/// One `tcomp` command of the run (a simulation, a fit of 32 centers, an image): a second or two.
const TCOMP_LIMIT: Duration = proc::minutes(3);
/// One QEMU replay: 10,000 samples (50 s of guest time) take about 6 s on the 2-core machine.
pub const QEMU_LIMIT: Duration = proc::minutes(5);

/// The QEMU board's crate (a workspace of its own: see [`board_args`]) and the binary that binds
/// the application to it.
pub const QEMU_BOARD: &str = "firmware/boards/qemu";
/// See [`QEMU_BOARD`].
pub const QEMU_BIN: &str = "tcomp-qemu";

/// The arguments that make a cargo command act on the QEMU board: its manifest, and the
/// workspace's target directory. The board is a workspace of its own (its `Cargo.toml` says why:
/// the root's `memory.x` is the STM32F407's, and the linker reads `memory.x` from the directory
/// cargo runs it in, the workspace root, first), so `-p` from the root does not reach it.
pub fn board_args() -> Vec<String> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    vec![
        "--manifest-path".into(),
        root.join(QEMU_BOARD)
            .join("Cargo.toml")
            .display()
            .to_string(),
        "--target-dir".into(),
        target_dir().display().to_string(),
    ]
}

/// The workspace's target directory (`CARGO_TARGET_DIR` or `target/`).
pub fn target_dir() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    std::env::var_os("CARGO_TARGET_DIR").map_or(root.join("target"), PathBuf::from)
}

fn tcomp(dir: &Path, args: &[&str]) -> Result<()> {
    let exe = dir.join("../debug/tcomp");
    proc::run(
        Command::new(&exe)
            .args(args)
            .current_dir(dir)
            .stdout(Stdio::null()),
        &format!("`tcomp {}`", args.join(" ")),
        TCOMP_LIMIT,
    )
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
            // The QMA's z channel is an additive model (blob format 4, per-center feature masks and
            // kinds): T acts through terms of its own (its square and cube, Gaussians or steps)
            // that the evidence places.
            let additive = preset == "qma" && *axis == "z";
            let centers: &[&str] = if additive { &[] } else { &["--centers", "32"] };
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
            ];
            args.extend_from_slice(centers);
            args.extend_from_slice(&[
                "--sensor", sensor, "--axis", axis, "--unit", unit, "--out", &out, "--quiet",
            ]);
            let pinned: Vec<String> = features
                .iter()
                .enumerate()
                .map(|(k, f)| {
                    if additive && k == 0 {
                        format!("additive:{f}")
                    } else {
                        (*f).to_string()
                    }
                })
                .collect();
            for f in &pinned {
                args.extend_from_slice(&["--feature", f]);
            }
            tcomp(work, &args)?;
            if additive {
                require_masks(&work.join(&out))?;
            }
        }
    }
    Ok(())
}

/// Refuses to go on unless the blob at `path` is an additive model with terms of another kind
/// than a Gaussian (format 4, with masks and kinds): the run is meant to carry one through the
/// firmware.
fn require_masks(path: &Path) -> Result<()> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let m = tcomp_core::HostModel::decode(&bytes)
        .map_err(|e| anyhow::anyhow!("{}: {e:?}", path.display()))?;
    anyhow::ensure!(
        !m.rbf.masks.is_empty() && !m.rbf.kinds.is_empty(),
        "{}: the fit chose no additive structure with steps or powers; the QEMU run needs one",
        path.display()
    );
    let count = |k: u8| m.rbf.kinds.iter().filter(|x| **x == k).count();
    use tcomp_core::rbf::{KIND_CUBE, KIND_GAUSSIAN, KIND_RAMP, KIND_SQUARE, KIND_STEP};
    eprintln!(
        "{}: additive model, {} Gaussians, {} steps, {} ramps, {} powers, format {}",
        path.display(),
        count(KIND_GAUSSIAN),
        count(KIND_STEP),
        count(KIND_RAMP),
        count(KIND_SQUARE) + count(KIND_CUBE),
        m.version
    );
    Ok(())
}

/// QEMU's emulation of the board every QEMU run here uses (the smoke run, the replay and update
/// runs, the C API's replay): the mps2-an386 (a Cortex-M4 with the FPU), no display or monitor,
/// semihosting for the guest's output and exit code, `elf` loaded as the kernel, and
/// `-icount icount` (instruction counting: `shift=N` is 2^N ns of virtual time per instruction,
/// so a run's timing is the same on any host).
pub fn machine(elf: &Path, icount: &str) -> Command {
    let mut qemu = Command::new("qemu-system-arm");
    qemu.args([
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
        icount,
    ])
    .arg("-kernel")
    .arg(elf);
    qemu
}

/// The unit's key store, written by `tcomp keygen` beside the images in the work directory and
/// loaded into the QEMU board's `KEYS` region (`firmware/boards/qemu/memory.x`) as a factory
/// programs OTP.
pub const KEY_STORE: &str = "station.otp";

/// QEMU's mps2-an386 running the replay ELF `elf` with `image` loaded at the start of the models
/// region (slot A), the key store at `KEYS` and `vector` in the replay region, UART 0 on `serial`
/// (`file:PATH`, `pty`), one instruction per 8 ns of virtual time.
pub fn qemu_command(elf: &Path, image: &Path, vector: &Path, serial: &str) -> Command {
    let mut qemu = machine(elf, "shift=3,sleep=off");
    qemu.args(["-serial", serial])
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
        .arg("-device")
        .arg(format!(
            "loader,file={},addr=0x3EF000,force-raw=on",
            image.with_file_name(KEY_STORE).display()
        ));
    qemu
}

/// Runs the replay binary under QEMU (bounded by [`QEMU_LIMIT`]) with `image` and `vector` loaded
/// and UART 0 captured into `uart`, decodes its defmt output (boot messages and the summary, over
/// semihosting) and returns the decoded text; fails on QEMU's exit code. QEMU restarts the guest on
/// a watchdog reset (no `-no-reboot`): the loaders and the ELF are loaded again, the rest of RAM
/// and the UART capture go on.
fn run_qemu(elf: &Path, image: &Path, vector: &Path, uart: &Path) -> Result<String> {
    let mut cmd = qemu_command(elf, image, vector, &format!("file:{}", uart.display()));
    let out = proc::output(&mut cmd, "the QEMU replay", QEMU_LIMIT)?;
    let text = crate::defmt::decode(elf, &out.stdout)?;
    print!("{text}");
    if !out.status.success() {
        bail!("the QEMU replay failed ({})", out.status);
    }
    Ok(text)
}

pub fn qemu() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let target_dir = target_dir();
    let work = target_dir.join("qemu-replay");
    std::fs::create_dir_all(&work)?;
    let board = board_args();
    let board: Vec<&str> = board.iter().map(String::as_str).collect();
    cargo(
        &[
            &["build"][..],
            &board,
            &["--target", TARGET, "--release", "--bin", QEMU_BIN],
        ]
        .concat(),
    )?;
    let elf = target_dir.join(TARGET).join("release").join(QEMU_BIN);
    // The host CLI makes the models and vectors; build it so `cargo xtask qemu` stands alone
    // (in CI the test step built it already: see `host_build`).
    crate::host_build()?;
    fit_models(&work)?;
    simulate_slices(&root, &work)?;
    // The images, made as a user makes them: the shipped board descriptions, the unit serial the
    // replay board reports, a pinned creation time so the bytes are reproducible.
    let images = make_images(&root, &work)?;
    let (mut imu, wrap_at) = imu6_inputs(&work)?;
    let a = build(CONFIG_IMU6, &IMU6, &imu, &images.imu6)?;
    let b = build(CONFIG_IMU6, &IMU6, &imu, &images.corrupt)?;
    let c = build(CONFIG_IFOG1, &IFOG1, &ifog_inputs(&work)?, &images.ifog)?;
    check_fault_flags(&a, &b, &c)?;
    check_continuity(&a, wrap_at)?;
    println!("the loop goes on after every fault (checked above and frame by frame below)");
    let totals = replay_runs(&work, &elf, &a, &b, &c)?;
    update_run(&work, &elf, &mut imu, &images.corrupt)?;
    report(&elf, &totals)
}

/// The 200 Hz slices of `firmware/replay/*.toml`, simulated into `work/vector-*/`.
fn simulate_slices(root: &Path, work: &Path) -> Result<()> {
    for k in ["rlg", "qma", "ifog"] {
        let toml = root.join(format!("firmware/replay/{k}.toml"));
        let toml = toml.to_str().context("path")?;
        tcomp(
            work,
            &[
                "simulate",
                "--scenario",
                toml,
                "--out",
                &format!("vector-{k}"),
            ],
        )?;
    }
    Ok(())
}

/// The three images of the runs (IMU6, IMU6 with a corrupt blob, the single IFOG).
struct Images {
    imu6: Vec<u8>,
    ifog: Vec<u8>,
    corrupt: Vec<u8>,
}

/// The images, made as a user makes them: the shipped board descriptions, the unit serial the
/// replay board reports, a pinned creation time so the bytes are reproducible.
fn make_images(root: &Path, work: &Path) -> Result<Images> {
    let serial = tcomp_firmware::replay::UNIT_SERIAL.to_string();
    let descriptions = root.join("firmware/descriptions");
    let imu6_board = descriptions.join("imu6-rlg-qma.toml");
    let ifog_board = descriptions.join("ifog1.toml");
    // The station's key, made now (no key lives in the repository), and a second one that the
    // unit was not provisioned with.
    for prefix in ["station", "rogue"] {
        for ext in ["key", "pub", "otp"] {
            let _ = std::fs::remove_file(work.join(format!("{prefix}.{ext}")));
        }
        tcomp(work, &["keygen", "--out", prefix])?;
    }
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
    let mut rogue_args = model_args.clone();
    model_args.extend(["--sign".into(), "station.key".into()]);
    model_args.extend(["--out".into(), "models.bin".into()]);
    tcomp(
        work,
        &model_args.iter().map(String::as_str).collect::<Vec<_>>(),
    )?;
    // The same image signed by the key the unit does not hold: the update must refuse it.
    rogue_args.extend(["--sign".into(), "rogue.key".into()]);
    rogue_args.extend(["--out".into(), "models-rogue.bin".into()]);
    tcomp(
        work,
        &rogue_args.iter().map(String::as_str).collect::<Vec<_>>(),
    )?;
    let ifog_board = ifog_board.to_str().context("path")?;
    tcomp(
        work,
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
            "--sign",
            "station.key",
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
    // Signed again by the station (as a station would sign an image holding a bad blob): the
    // signature passes and the blob's own CRC is what refuses the channel.
    tcomp_core::image::sign::sign(&mut corrupt, &station_secret(work)?)
        .map_err(|e| anyhow::anyhow!("signing: {e}"))?;
    std::fs::write(work.join("models-corrupt.bin"), &corrupt)?;

    Ok(Images {
        imu6: image,
        ifog: ifog_image,
        corrupt,
    })
}

/// The station's secret key, as `tcomp keygen` wrote it (`tcomp-ed25519-secret` and 64 hex digits).
fn station_secret(work: &Path) -> Result<[u8; 32]> {
    let text = std::fs::read_to_string(work.join("station.key"))?;
    let hex = text.split_whitespace().nth(1).context("station.key")?;
    let mut key = [0u8; 32];
    for (i, k) in key.iter_mut().enumerate() {
        *k = u8::from_str_radix(hex.get(2 * i..2 * i + 2).context("station.key")?, 16)?;
    }
    Ok(key)
}

/// What the three replay runs add up to.
struct Totals {
    samples: u64,
    flagged: u64,
    stack: u64,
    mean: u64,
    worst: u64,
    worst_after_gap: u64,
    /// The worst whole sample task.
    task_max: u64,
    /// Periods that preempted the drain, the update task.
    drain_preempted: u64,
    update_preempted: u64,
}

/// Runs the three replays under QEMU and checks each against the host's run.
fn replay_runs(
    work: &Path,
    elf: &Path,
    a: &Built<6>,
    b: &Built<6>,
    c: &Built<1>,
) -> Result<Totals> {
    let mut samples = 0;
    let mut flagged = 0;
    let mut frames = 0;
    let mut timing = None;
    let mut stack = 0;
    let (mut task_max, mut drain_preempted, mut update_preempted) = (0, 0, 0);
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
        let text = run_qemu(elf, &work.join(image), &path, &uart)?;
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
        let (peak, worst) = check_status(&reports, boots, &s)?;
        println!(
            "{name}: {} boot reports (unit {UNIT_SERIAL:#x}, image v2, every channel as loaded); \
             the last carries stack peak {peak} B, worst sample task {worst} instructions",
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
        if s.dropped != 0 || s.rx_lost != 0 {
            bail!(
                "{name}: {} frames dropped by the queue, {} received bytes lost",
                s.dropped,
                s.rx_lost
            );
        }
        task_max = task_max.max(s.task_max);
        drain_preempted += s.drain_preempted;
        update_preempted += s.update_preempted;
        samples += s.samples;
        flagged += s.flagged;
        frames += n;
        stack = stack.max(s.stack);
        if name == "imu6" {
            timing = Some((s.mean, s.max, s.max_after_gap));
        }
    }
    let (mean, worst, worst_after_gap) = timing.context("no imu6 run")?;
    println!("{frames} UART frames in all, decoded and identical to the host's");
    Ok(Totals {
        samples,
        flagged,
        stack,
        mean,
        worst,
        worst_after_gap,
        task_max,
        drain_preempted,
        update_preempted,
    })
}

/// The update run: the same IMU6 inputs without the board's injected faults (a watchdog reset
/// would boot the new image in the middle of the vector), the corrupt image as the initial one.
fn update_run(work: &Path, elf: &Path, imu: &mut Inputs, corrupt: &[u8]) -> Result<()> {
    imu.board_faults.iter_mut().for_each(|f| *f = 0);
    imu.flags = tcomp_firmware::replay::HOLD_FOR_UPDATE;
    let d = build(CONFIG_IMU6, &IMU6, imu, corrupt)?;
    let vector_d = work.join("vector-imu6-update.bin");
    std::fs::write(&vector_d, &d.bytes)?;
    println!("--- QEMU update over the UART ---");
    crate::update::run(
        work,
        elf,
        &work.join("models-corrupt.bin"),
        &vector_d,
        &work.join("models-rogue.bin"),
        &work.join("models.bin"),
        d.hash,
        d.served.iter().filter(|&&s| s).count(),
    )?;
    Ok(())
}

/// Prints the figures and the `QEMU-SUMMARY` line, and checks the budgets.
fn report(elf: &Path, totals: &Totals) -> Result<()> {
    let Totals {
        samples,
        flagged,
        stack,
        mean,
        worst,
        worst_after_gap,
        task_max,
        drain_preempted,
        update_preempted,
    } = *totals;
    let (flash, static_ram) = crate::elf::flash_and_static_ram(elf)?;
    let (board_flash, board_ram) = crate::board::sizes()?;
    let load = |i: u64| (i * CYCLES_PER_INSTRUCTION * SAMPLE_HZ) as f64 / CORE_HZ as f64 * 100.0;
    println!(
        "instructions per 6-channel sample (every model every sample): mean {mean}, worst {worst} \
         (budget {WORST_INSTRUCTIONS_BUDGET}); the sample after missed periods {worst_after_gap} \
         (budget {GAP_SAMPLE_BUDGET}); at 168 MHz and 200 Hz, 2 cycles an instruction: {:.2} % CPU \
         mean, {:.2} % worst",
        load(mean),
        load(worst)
    );
    println!(
        "the loop's state (`App`: 6 decoded models + channel state) is {} B on the host, in a static",
        std::mem::size_of::<tcomp_firmware::app::App<'static>>()
    );
    println!(
        "flash {flash} B (budget {FLASH_BUDGET}), static RAM {static_ram} B (budget \
         {STATIC_RAM_BUDGET}), stack peak {stack} B (budget {STACK_BUDGET}); the STM32F407 \
         binary: flash {board_flash} B, static RAM {board_ram} B"
    );
    println!(
        "QEMU-SUMMARY samples={samples} mismatches=0 faults_flagged={flagged} transport=uart timer=hw \
         worst_instructions_per_sample={worst} instructions_per_sample={mean} \
         worst_instructions_after_gap={worst_after_gap} task_max_instructions={task_max} \
         drain_preempted={drain_preempted} update_preempted={update_preempted} \
         static_ram_bytes={static_ram} stack_bytes={stack} board=stm32f4 \
         board_flash_bytes={board_flash} board_static_ram_bytes={board_ram}"
    );
    let mut over = Vec::new();
    if worst > WORST_INSTRUCTIONS_BUDGET {
        over.push(format!(
            "worst instructions {worst} > {WORST_INSTRUCTIONS_BUDGET}"
        ));
    }
    if worst_after_gap > GAP_SAMPLE_BUDGET {
        over.push(format!(
            "instructions after missed periods {worst_after_gap} > {GAP_SAMPLE_BUDGET}"
        ));
    }
    if flash > FLASH_BUDGET {
        over.push(format!("flash {flash} > {FLASH_BUDGET}"));
    }
    if static_ram > STATIC_RAM_BUDGET || board_ram > STATIC_RAM_BUDGET {
        over.push(format!(
            "static RAM {static_ram} B (QEMU), {board_ram} B (STM32F407) > {STATIC_RAM_BUDGET}"
        ));
    }
    if stack > STACK_BUDGET {
        over.push(format!("stack {stack} > {STACK_BUDGET}"));
    }
    if !over.is_empty() {
        bail!("over budget: {}", over.join(", "));
    }
    Ok(())
}
