//! The replay runs' inputs: the simulated 200 Hz slices laid out as the IMU6 and IFOG1 boards read
//! them, with the faults the QEMU run must see flagged.

use super::vector::{Csv, Inputs, QMA_PER_PULSE, RLG_PER_PULSE};
use anyhow::{Context, Result};
use std::path::Path;
use tcomp_firmware::replay::{HANG, MISS, STALL, TIME_GLITCH};

/// Samples per replay run (50 s at 200 Hz).
pub const SAMPLES: usize = 10_000;

/// The IMU6 vector's inputs with the injected faults, and the sample where RLG x's counter wraps.
pub fn imu6_inputs(work: &Path) -> Result<(Inputs, usize)> {
    // IMU6 vector: three RLG axes from one 200 Hz slice (offset rows), three QMA axes likewise.
    let rlg = Csv::read(&work.join("vector-rlg/train.csv"))?;
    let qma = Csv::read(&work.join("vector-qma/train.csv"))?;
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
    Ok((imu, wrap_at))
}

/// The single IFOG's inputs: its coil thermometer with a short ADC bus error.
pub fn ifog_inputs(work: &Path) -> Result<Inputs> {
    let ifog = Csv::read(&work.join("vector-ifog/train.csv"))?;
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
    Ok(ifog_in)
}
