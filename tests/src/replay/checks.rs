//! Checking a QEMU replay against the host's run of the same loop: the UART capture frame by frame,
//! the boot reports, the firmware's summary line, and the status words of every injected fault.

use super::field;
use super::scenario::SAMPLES;
use super::vector::{Built, expect_flag};
use anyhow::{Context, Result, bail};
use tcomp_core::frame::{BootReport, Decoder, Item, boot_len, image_state};
use tcomp_firmware::app::{IMU6, PERIOD_S, status};
use tcomp_firmware::boot::REPORT_PERIODS;
use tcomp_firmware::replay::UNIT_SERIAL;

/// Decodes every frame of the UART capture with the core's decoder and compares each with the
/// host's frame of the same sequence number, byte for byte (values as f64 bits, status words with
/// the board's bits, timestamps). Returns the frames decoded.
pub fn compare_frames(capture: &[u8], expected: &[Vec<u8>]) -> Result<(usize, Vec<BootReport>)> {
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
pub fn check_reports(
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

/// The unit's status in its boot reports (the report repeats every [`REPORT_PERIODS`], so it is
/// also the status frame): every report sent from the loop carries a measured stack peak and a
/// non-zero worst sample task, at most one report per boot (the one sent before the first
/// period) has none yet, and the last report's figures are at most the run's summary (which
/// folds in the last boot's counters). Returns the last report's (stack peak, worst task).
pub fn check_status(reports: &[BootReport], boots: usize, summary: &Summary) -> Result<(u32, u32)> {
    let unmeasured = reports.iter().filter(|r| r.worst_task == 0).count();
    if unmeasured > boots {
        bail!("{unmeasured} boot reports carry no worst sample task, for {boots} boots");
    }
    if let Some(r) = reports
        .iter()
        .find(|r| r.worst_task != 0 && r.stack_peak == 0)
    {
        bail!("a report sent from the loop carries no stack peak: {r:?}");
    }
    let last = reports.last().context("no boot report")?;
    if last.worst_task == 0
        || u64::from(last.stack_peak) > summary.stack
        || u64::from(last.worst_task) > summary.task_max
    {
        bail!(
            "the last report's status (stack {} B, worst task {}) does not agree with the summary \
             (stack {} B, worst task {})",
            last.stack_peak,
            last.worst_task,
            summary.stack,
            summary.task_max
        );
    }
    Ok((last.stack_peak, last.worst_task))
}

/// The firmware's summary numbers of one run.
pub struct Summary {
    /// Samples compared.
    pub samples: u64,
    /// Outputs with a status bit set.
    pub flagged: u64,
    /// Instructions per sample, mean and worst.
    pub mean: u64,
    /// Worst instructions per ordinary sample (not after missed periods).
    pub max: u64,
    /// The worst over the samples after missed timer periods (the gap step).
    pub max_after_gap: u64,
    /// Samples taken late.
    pub late: u64,
    /// Timer periods missed.
    pub missed: u64,
    /// Watchdog resets.
    pub resets: u64,
    /// Stack peak, bytes.
    pub stack: u64,
    /// The worst whole sample task (entry to the watchdog feed), instructions.
    pub task_max: u64,
    /// Sample periods that began while the drain, or the update task, ran.
    pub drain_preempted: u64,
    /// See `drain_preempted`.
    pub update_preempted: u64,
    /// Frames the queue dropped whole, and received bytes the ring lost.
    pub dropped: u64,
    /// See `dropped`.
    pub rx_lost: u64,
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
        max_after_gap: get("instructions_max_after_gap=")?,
        late: get("late=")?,
        missed: get("missed=")?,
        resets: get("watchdog_resets=")?,
        stack: get("stack_bytes=")?,
        task_max: get("task_max=")?,
        drain_preempted: get("drain_preempted=")?,
        update_preempted: get("update_preempted=")?,
        dropped: get("dropped_frames=")?,
        rx_lost: get("rx_lost=")?,
    })
}

/// Every injected fault shows in the status word of the right channel and samples.
pub fn check_fault_flags(a: &Built<6>, b: &Built<6>, c: &Built<1>) -> Result<()> {
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
    Ok(())
}

/// The counter wrap, the recoveries after faults, the missed period and the latched intervals.
pub fn check_continuity(a: &Built<6>, wrap_at: usize) -> Result<()> {
    let sa = &a.statuses;
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

    Ok(())
}
