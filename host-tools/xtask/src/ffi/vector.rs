//! The replay vectors of the C examples (layout in `crates/ffi/c/replay.c`), with the outputs the
//! Rust core's own `Channel` gives for them: what the C library must reproduce on both sides.

use anyhow::{Context, Result, ensure};
use std::path::Path;
use tcomp_core::testing::{example_model, example_sample};
use tcomp_core::{Channel, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES, Model, Output};

type FlightModel<'a> = Model<'a, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>;
type FlightChannel = Channel<FLIGHT_NODES, FLIGHT_FEATURES>;

/// One sample of a vector.
struct Record {
    inputs: Vec<f32>,
    raw: f32,
    dt: f32,
    /// Mode 0: `dt` seconds of missed periods before this sample; mode 1: a gap.
    flag: bool,
}

/// Stepping of a vector: 0 at the period (`tcomp_step`, `tcomp_skip`), 1 with a time step
/// (`tcomp_step_dt`).
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Period,
    Dt,
}

/// The smoke run's model (the core's example RLG model, 32 centers × 4 features) on 2,000
/// samples of its example ramp at 200 Hz, stepped at the period as a firmware loop does, with a
/// NaN thermometer, a NaN raw value, 100 samples far above the trained range and 4 missed
/// periods.
pub fn example() -> Result<Vec<u8>> {
    const PERIOD: f32 = 0.005;
    let model = example_model::<FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>(32, 11);
    let mut blob = vec![0u8; 8192];
    let len = model
        .encode(&mut blob)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    blob.truncate(len);
    let records = (0..2000u32)
        .map(|n| {
            let (mut t, mut raw) = example_sample(n, PERIOD);
            match n {
                300 => t[0] = f32::NAN,
                1200 => raw = f32::NAN,
                1500..1600 => t[0] += 80.0,
                _ => {}
            }
            Record {
                inputs: t.to_vec(),
                raw,
                dt: if n == 800 { 4.0 * PERIOD } else { PERIOD },
                flag: n == 800,
            }
        })
        .collect::<Vec<_>>();
    write(&blob, Mode::Period, PERIOD, &records)
}

/// The fitted model on rows 8,000–11,999 of its dropout run (`fitted_model` in `mod.rs`): the
/// CSV's cells as `tcomp eval` reads them (doubles rounded to float, the time step in double then
/// rounded), stepped with a time step, the dropout flagged as a gap (a step over 10 × the median,
/// `tcomp eval`'s rule).
pub fn fitted(blob: &[u8], run: &Path) -> Result<Vec<u8>> {
    let model = FlightModel::decode(blob).map_err(|e| anyhow::anyhow!("{e}"))?;
    let text = std::fs::read_to_string(run)?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().context("empty run")?.split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h.trim() == name)
            .with_context(|| format!("no column {name}"))
    };
    let time = col(model.meta.columns.time)?;
    let target = col(model.meta.columns.target)?;
    let inputs = model
        .program
        .inputs
        .iter()
        .map(|n| col(n))
        .collect::<Result<Vec<_>>>()?;
    let rows: Vec<Vec<f64>> = lines
        .skip(8_000)
        .take(4_000)
        .map(|l| l.split(',').map(|c| c.trim().parse::<f64>()).collect())
        .collect::<Result<_, _>>()?;
    let t: Vec<f64> = rows.iter().map(|r| r[time]).collect();
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps.get(steps.len() / 2).copied().unwrap_or(1.0);
    let records: Vec<Record> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let d = if i == 0 { 1.0 } else { t[i] - t[i - 1] };
            Record {
                inputs: inputs.iter().map(|&c| r[c] as f32).collect(),
                raw: r[target] as f32,
                dt: d as f32,
                flag: d > 10.0 * median,
            }
        })
        .collect();
    ensure!(
        records.iter().filter(|r| r.flag).count() == 1,
        "the dropout is one gap"
    );
    write(blob, Mode::Dt, median as f32, &records)
}

/// The vector's bytes, the expected outputs from the core's `Channel` at the C API's
/// capacities, readied as `tcomp_load_blob` readies it.
fn write(blob: &[u8], mode: Mode, period: f32, records: &[Record]) -> Result<Vec<u8>> {
    let model = FlightModel::decode(blob).map_err(|e| anyhow::anyhow!("{e}"))?;
    let k = model.program.inputs.len();
    ensure!(
        records.iter().all(|r| r.inputs.len() == k),
        "inputs per record"
    );
    let mut ch = FlightChannel::new(period);
    ch.prepare(&model);
    let expected: Vec<Output> = records
        .iter()
        .map(|r| match mode {
            Mode::Period => {
                if r.flag {
                    ch.skip(r.dt);
                }
                ch.step(Some(&model), &r.inputs, r.raw)
            }
            Mode::Dt => {
                if r.flag {
                    ch.mark_gap();
                }
                ch.step_dt(Some(&model), &r.inputs, r.dt, r.raw)
            }
        })
        .collect();
    let mut v = Vec::new();
    let word = |v: &mut Vec<u8>, w: u32| v.extend_from_slice(&w.to_le_bytes());
    v.extend_from_slice(b"TCRV");
    word(&mut v, 1);
    word(&mut v, u32::try_from(records.len())?);
    word(&mut v, u32::try_from(k)?);
    word(&mut v, u32::from(mode == Mode::Dt));
    word(&mut v, period.to_bits());
    word(&mut v, u32::try_from(blob.len())?);
    v.extend_from_slice(blob);
    v.resize(v.len().next_multiple_of(4), 0);
    for r in records {
        for x in &r.inputs {
            word(&mut v, x.to_bits());
        }
        word(&mut v, r.raw.to_bits());
        word(&mut v, r.dt.to_bits());
        word(&mut v, u32::from(r.flag));
    }
    for o in &expected {
        word(&mut v, o.compensated.to_bits());
        word(&mut v, o.correction.to_bits());
        word(&mut v, u32::from(o.status.0));
    }
    Ok(v)
}
