//! The replay vectors: simulator CSVs at 200 Hz → sensor samples with injected faults, and the
//! host's outputs for them (the firmware's own loop, run here), in the layout of
//! `firmware/src/replay.rs`.

use anyhow::{Context, Result, bail};
use std::path::Path;
use tcomp_core::frame::MAX_FRAME_LEN;
use tcomp_firmware::app::{
    App, ChannelConfig, QMA_UG_PER_HZ, RLG_ARCSEC_PER_PULSE, Record, status,
};
use tcomp_firmware::replay::{
    COUNTER_FLAG_SHIFT, HANG, HEADER_LEN, MAGIC, MISS, STALL, TICK_HZ, TICKS_PER_PERIOD,
    UNIT_SERIAL, VERSION, Vector,
};

/// Largest jitter of the replayed latch instants, ticks of 25 MHz (±40 µs, ±0.8 % of a period):
/// a board that latches the counter block from its interrupt rather than the timer's trigger
/// output. Well inside the loop's tolerance for a latched interval (10 %), yet far above a
/// count's resolution, so a loop that divided by the nominal period would show it.
pub const LATCH_JITTER_TICKS: i64 = 1_000;

/// The latch instant of sample `n`, ticks: `n + 1` periods after the initial latch at 0, with a
/// deterministic pseudo-random jitter of up to ±[`LATCH_JITTER_TICKS`].
fn latch_ticks(n: usize) -> u32 {
    let h = ((n as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 33) as i64;
    let jitter = h % (2 * LATCH_JITTER_TICKS + 1) - LATCH_JITTER_TICKS;
    ((n as i64 + 1) * TICKS_PER_PERIOD as i64 + jitter) as u32
}
use tcomp_firmware::timing::TimeCheck;
use tcomp_firmware::{HASH_START, fold_hash};

/// A column-addressable CSV.
pub struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    /// Reads a CSV file whole (the simulator's 200 Hz slices are small).
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
        let mut lines = text.lines();
        let header = lines
            .next()
            .context("empty CSV")?
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .map(|l| {
                l.split(',')
                    .map(|v| v.trim().parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        Ok(Self { header, rows })
    }

    /// `n` values of column `name` from row `from`.
    pub fn column(&self, name: &str, from: usize, n: usize) -> Result<Vec<f64>> {
        let i = self
            .header
            .iter()
            .position(|h| h == name)
            .with_context(|| format!("no column {name}"))?;
        let rows = self
            .rows
            .get(from..from + n)
            .context("CSV too short for the vector")?;
        Ok(rows
            .iter()
            .map(|r| r.get(i).copied().unwrap_or(f64::NAN))
            .collect())
    }
}

/// One sensor stream of the vector and the faults injected into it.
pub struct Inputs {
    /// Per thermometer, its readings (°C, may be NaN).
    pub temps: Vec<Vec<f32>>,
    /// Per thermometer, the samples whose read is a bus error.
    pub therm_faults: Vec<Vec<bool>>,
    /// Per counter, its free-running register at each sample.
    pub counters: Vec<Vec<u32>>,
    /// Per counter, its register before the first sample.
    pub counter_start: Vec<u32>,
    /// Per counter, the samples whose read is a bus error.
    pub counter_faults: Vec<Vec<bool>>,
    /// Counter intervals the block flags (pulses lost: consumed, not counted).
    pub counter_flagged: Vec<Vec<bool>>,
    /// The board's injections per sample (`replay::STALL`, `TIME_GLITCH`, `HANG`, `MISS`).
    pub board_faults: Vec<u32>,
    /// The counter block's latch instants, ticks of 25 MHz (the one before the first sample is 0).
    pub timestamps: Vec<u32>,
    /// The vector's header flags (`replay::HOLD_FOR_UPDATE`).
    pub flags: u16,
}

impl Inputs {
    /// No streams yet, `samples` long, with the nominal latch instants.
    pub fn new(samples: usize) -> Self {
        Self {
            temps: vec![],
            therm_faults: vec![],
            counters: vec![],
            counter_start: vec![],
            counter_faults: vec![],
            counter_flagged: vec![],
            board_faults: vec![0; samples],
            timestamps: (0..samples).map(latch_ticks).collect(),
            flags: 0,
        }
    }

    /// Samples per stream.
    pub fn samples(&self) -> usize {
        self.temps.first().map_or(0, Vec::len)
    }

    /// Adds a thermometer stream; returns its index.
    pub fn thermometer(&mut self, celsius: &[f64]) -> usize {
        self.temps.push(celsius.iter().map(|&t| t as f32).collect());
        self.therm_faults.push(vec![false; celsius.len()]);
        self.temps.len() - 1
    }

    /// A free-running 32-bit counter integrating `rate` (°/h or µg) at `per_pulse` over the latched
    /// intervals, starting at `start` pulses before the register wraps through zero.
    pub fn counter(&mut self, rate: &[f64], per_pulse: f32, wrap_after: u64) -> usize {
        let start = (0u64.wrapping_sub(wrap_after) & 0xFFFF_FFFF) as u32;
        let mut pulses = 0.0f64;
        let mut last = 0u32;
        let regs = rate
            .iter()
            .zip(&self.timestamps)
            .map(|(r, &t)| {
                let dt = f64::from(t.wrapping_sub(last)) / f64::from(TICK_HZ);
                last = t;
                pulses += r * dt / f64::from(per_pulse);
                start.wrapping_add(pulses.floor() as i64 as u32)
            })
            .collect();
        self.counters.push(regs);
        self.counter_start.push(start);
        self.counter_faults.push(vec![false; rate.len()]);
        self.counter_flagged.push(vec![false; rate.len()]);
        self.counters.len() - 1
    }

    /// Serialises the inputs with zeroed expected outputs for `channels`.
    fn bytes(&self, config: u16, channels: usize) -> Vec<u8> {
        let n = self.samples();
        let mut b = Vec::new();
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&config.to_le_bytes());
        b.extend_from_slice(&(n as u32).to_le_bytes());
        b.extend_from_slice(&(self.temps.len() as u16).to_le_bytes());
        b.extend_from_slice(&(self.counters.len() as u16).to_le_bytes());
        b.extend_from_slice(&(channels as u16).to_le_bytes());
        b.extend_from_slice(&self.flags.to_le_bytes());
        debug_assert_eq!(b.len(), HEADER_LEN);
        b.extend_from_slice(&0u32.to_le_bytes());
        for s in &self.counter_start {
            b.extend_from_slice(&s.to_le_bytes());
        }
        for i in 0..n {
            let mut mask = 0u32;
            for (t, f) in self.therm_faults.iter().enumerate() {
                mask |= u32::from(f[i]) << t;
            }
            for (c, f) in self.counter_faults.iter().enumerate() {
                mask |= u32::from(f[i]) << (16 + c);
            }
            for (c, f) in self.counter_flagged.iter().enumerate() {
                mask |= u32::from(f[i]) << (COUNTER_FLAG_SHIFT as usize + c);
            }
            mask |= self.board_faults.get(i).copied().unwrap_or(0);
            b.extend_from_slice(&mask.to_le_bytes());
            b.extend_from_slice(&self.timestamps[i].to_le_bytes());
            for t in &self.temps {
                b.extend_from_slice(&t[i].to_bits().to_le_bytes());
            }
            for c in &self.counters {
                b.extend_from_slice(&c[i].to_le_bytes());
            }
        }
        b.resize(b.len() + n * channels * 8, 0);
        b
    }
}

/// A vector with the host's run of the firmware's loop over it.
pub struct Built<const K: usize> {
    /// The vector, expected outputs filled in.
    pub bytes: Vec<u8>,
    /// The loop's records per sample (before the board's bits; default where not served).
    pub outputs: Vec<[Record; K]>,
    /// Whether the board serves each sample (false for a record skipped after a missed period).
    pub served: Vec<bool>,
    /// Their hash, as the firmware folds it.
    pub hash: u32,
    /// The frames the board must send, encoded, one per sample (empty where not served).
    pub frames: Vec<Vec<u8>>,
    /// Each frame's status words (the records' with the board's bits).
    pub statuses: Vec<Option<[u16; K]>>,
}

/// Runs the firmware's loop on the host over `inputs` with `image` as the board runs it — after a
/// `HANG` sample a fresh boot (new loop, models loaded again, counters latched anew) resumes with
/// the next sample, after a `MISS` sample the next record is skipped and the one after covers two
/// periods — and returns the finished vector with the outputs and frames to expect.
pub fn build<const K: usize>(
    config_code: u16,
    config: &'static [ChannelConfig; K],
    inputs: &Inputs,
    image: &[u8],
) -> Result<Built<K>> {
    let mut bytes = inputs.bytes(config_code, K);
    let (outputs, frames, statuses, served) = {
        let v = Vector::parse(&bytes).map_err(|e| anyhow::anyhow!("vector: {e:?}"))?;
        let mut app = App::new(config);
        let loaded = app.load_for_unit(
            image,
            UNIT_SERIAL,
            tcomp_firmware::replay::board_hash(config_code),
            v.counters,
            v.thermometers,
        );
        for (c, r) in config.iter().zip(loaded) {
            if let Err(e) = r {
                eprintln!("host: channel {}: no model ({e:?})", c.name);
            }
        }
        let mut board = v.board();
        let mut check = TimeCheck::new(TICKS_PER_PERIOD);
        // The first frame of every boot is flagged (the board's bit).
        let mut boot_flags = status::FIRST_SAMPLE;
        let mut outputs = Vec::with_capacity(v.samples);
        let mut frames = Vec::with_capacity(v.samples);
        let mut statuses = Vec::with_capacity(v.samples);
        let mut served = Vec::with_capacity(v.samples);
        let mut late = false;
        let mut skip = false;
        let mut missed = 0;
        for n in 0..v.samples {
            if skip {
                // The board missed this record's timer edge altogether.
                skip = false;
                missed += 1;
                outputs.push([Record::default(); K]);
                frames.push(Vec::new());
                statuses.push(None);
                served.push(false);
                continue;
            }
            let injected = v.board_faults(n);
            v.load(n, &mut board);
            app.skip_periods(missed);
            let (t, c) = board.snapshot();
            let mut out = [Record::default(); K];
            app.sample_snapshot(t, c, &mut out);
            outputs.push(out);
            served.push(true);
            let mut flags = check.check(v.timestamp(n), u32::from(missed)) | boot_flags;
            missed = 0;
            if late {
                flags |= status::OVERRUN;
            }
            boot_flags = 0;
            let mut with_flags = out;
            for r in &mut with_flags {
                r.status |= flags;
            }
            statuses.push(Some(with_flags.map(|r| r.status)));
            let frame = app.frame(n as u32, v.timestamp(n), TICK_HZ, &with_flags);
            let mut buf = [0u8; MAX_FRAME_LEN];
            let len = frame
                .encode(&mut buf)
                .map_err(|e| anyhow::anyhow!("frame: {e}"))?;
            // A sample task that hangs never returns: its frame is queued but the drain, below
            // it, never sends it before the watchdog resets the board.
            frames.push(if injected & HANG != 0 {
                Vec::new()
            } else {
                buf[..len].to_vec()
            });
            late = injected & (STALL | MISS) != 0;
            skip = injected & MISS != 0;
            if injected & HANG != 0 {
                app.reset(config);
                let _ = app.load(image);
                board = v.board_at(n + 1);
                check = TimeCheck::new(TICKS_PER_PERIOD);
                boot_flags = status::WATCHDOG_RESET | status::FIRST_SAMPLE;
            }
        }
        (outputs, frames, statuses, served)
    };
    let mut hash = HASH_START;
    let tail = bytes.len() - outputs.len() * K * 8;
    for (i, rec) in outputs.iter().flatten().enumerate() {
        if served[i / K] {
            hash = fold_hash(hash, rec);
        }
        let at = tail + i * 8;
        bytes[at..at + 4].copy_from_slice(&rec.compensated.to_bits().to_le_bytes());
        bytes[at + 4..at + 8].copy_from_slice(&u32::from(rec.status).to_le_bytes());
    }
    Ok(Built {
        bytes,
        outputs,
        served,
        hash,
        frames,
        statuses,
    })
}

/// Scales of the replayed counters (the firmware's channel configuration).
pub const RLG_PER_PULSE: f32 = RLG_ARCSEC_PER_PULSE;
/// µg·s per QMA pulse.
pub const QMA_PER_PULSE: f32 = QMA_UG_PER_HZ;

/// Fails unless every sample in `range` of `channel` has all of `flags` (in the frames' status
/// words, which carry the board's bits too).
pub fn expect_flag<const K: usize>(
    outputs: &[Option<[u16; K]>],
    what: &str,
    channel: usize,
    range: std::ops::Range<usize>,
    flags: u16,
) -> Result<()> {
    for n in range {
        let Some(s) = outputs[n].map(|o| o[channel]) else {
            continue;
        };
        if s & flags != flags {
            bail!(
                "fault `{what}` not flagged: sample {n} channel {channel} status {s:#x}, expected {flags:#x}"
            );
        }
    }
    println!("fault {what}: flagged (status bits {flags:#x})");
    Ok(())
}
