//! The loop's counter handling against the real counter-block driver on a mock SPI bus: a flagged
//! interval is consumed (NaN + SENSOR_ERROR, the next interval is one period), a bus error is not
//! (the next good read covers both periods).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

extern crate std;

use super::*;
use embedded_hal::spi::{
    ErrorKind as SpiErrorKind, ErrorType as SpiErrorType, Operation, SpiDevice,
};
use embedded_hal_mock::eh1::spi::{Mock, Transaction as Tx};
use std::{vec, vec::Vec};
use tcomp_hal::pulse_counter::{CounterBlock, ID_VALUE, status as block_status};

/// INFO: 8 channels, 32-bit counters, 10 MHz timestamp clock.
const INFO: u32 = 0x2710_2008;
/// Timestamp ticks per loop period at 10 MHz.
const TICKS: u32 = 50_000;

fn frame(ops: Vec<Tx<u8>>) -> Vec<Tx<u8>> {
    let mut v = vec![Tx::transaction_start()];
    v.extend(ops);
    v.push(Tx::transaction_end());
    v
}

fn id_frame() -> Vec<Tx<u8>> {
    let mut data = ID_VALUE.to_be_bytes().to_vec();
    data.extend(INFO.to_be_bytes());
    frame(vec![Tx::write_vec(vec![0x80]), Tx::read_vec(data)])
}

/// `[LATCH, READ | STATUS]` then STATUS, TIMESTAMP, COUNT[..].
fn snapshot(status: u32, timestamp: u32, counts: &[u32]) -> Vec<Tx<u8>> {
    let mut data = status.to_be_bytes().to_vec();
    data.extend(timestamp.to_be_bytes());
    for c in counts {
        data.extend(c.to_be_bytes());
    }
    frame(vec![Tx::write_vec(vec![0x01, 0x82]), Tx::read_vec(data)])
}

/// Fails the `fail_on`-th transaction before it reaches the mock (a bus fault before chip select).
struct FailAt<S> {
    inner: S,
    fail_on: usize,
    count: usize,
}

impl<S> SpiErrorType for FailAt<S> {
    type Error = SpiErrorKind;
}

impl<S: SpiDevice<Error = SpiErrorKind>> SpiDevice for FailAt<S> {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SpiErrorKind> {
        let n = self.count;
        self.count += 1;
        if n == self.fail_on {
            return Err(SpiErrorKind::Other);
        }
        self.inner.transaction(operations)
    }
}

/// A thermometer that always reads 25 °C.
struct Fixed;

impl tcomp_hal::ErrorType for Fixed {
    type Error = ErrorKind;
}

impl Thermometer for Fixed {
    fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
        Ok(25.0)
    }
}

fn thermometers() -> [Fixed; MAX_THERMOMETERS] {
    core::array::from_fn(|_| Fixed)
}

/// The raw value the loop must report for `counts` pulses over one period on channel `k` of IMU6
/// (no model: the raw value is passed through).
fn one_period(k: usize, counts: i32) -> f32 {
    IMU6[k].scale.rate(counts, PERIOD_S).unwrap()
}

#[test]
fn flagged_interval_is_consumed_through_a_pulse_counter_handle() {
    // One RLG counter (channel 0 of a one-channel block): 1000 pulses per period, i.e. 2 °/h at
    // 1e-5 arcsec per pulse; the second interval is flagged LOST.
    let mut e = id_frame();
    e.extend(snapshot(0, 0, &[0]));
    e.extend(snapshot(0, TICKS, &[1_000]));
    e.extend(snapshot(1 << block_status::LOST_SHIFT, 2 * TICKS, &[1_900]));
    e.extend(snapshot(0, 3 * TICKS, &[2_900]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 1> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];
    let mut counters = [&mut block];

    app.sample(&mut therms, &mut counters, &mut out);
    assert_eq!(out[0].compensated, one_period(0, 1_000));
    assert!(
        (out[0].compensated - 2.0).abs() < 1e-5,
        "{}",
        out[0].compensated
    );
    assert_eq!(out[0].status, status::NO_MODEL);

    app.sample(&mut therms, &mut counters, &mut out);
    assert!(out[0].compensated.is_nan());
    assert_eq!(out[0].status & status::SENSOR_ERROR, status::SENSOR_ERROR);

    // The flagged interval was consumed: the next one is one period of 1000 pulses, not two.
    app.sample(&mut therms, &mut counters, &mut out);
    assert_eq!(out[0].compensated, one_period(0, 1_000));
    assert_eq!(out[0].status, status::NO_MODEL);
    spi.done();
}

#[test]
fn bus_error_carries_the_interval_to_the_next_read() {
    let mut e = id_frame();
    e.extend(snapshot(0, 0, &[0]));
    e.extend(snapshot(0, TICKS, &[1_000]));
    // Transaction 3 (the second sample) fails on the bus before reaching the mock.
    e.extend(snapshot(0, 3 * TICKS, &[3_000]));
    let mut spi = Mock::new(&e);
    let bus = FailAt {
        inner: spi.clone(),
        fail_on: 3,
        count: 0,
    };
    let mut block: CounterBlock<_, 1> = CounterBlock::new(bus);
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];
    let mut counters = [&mut block];

    app.sample(&mut therms, &mut counters, &mut out);
    assert_eq!(out[0].compensated, one_period(0, 1_000));
    app.sample(&mut therms, &mut counters, &mut out);
    assert!(out[0].compensated.is_nan());
    assert_eq!(out[0].status & status::SENSOR_ERROR, status::SENSOR_ERROR);
    // 2000 pulses over the two periods since the last good read: the same 2 °/h.
    app.sample(&mut therms, &mut counters, &mut out);
    assert_eq!(
        out[0].compensated,
        IMU6[0].scale.rate(2_000, 2.0 * PERIOD_S).unwrap()
    );
    assert!(
        (out[0].compensated - 2.0).abs() < 1e-5,
        "{}",
        out[0].compensated
    );
    assert_eq!(out[0].status, status::NO_MODEL);
    spi.done();
}

/// Pulses a period of each channel of [`six_channel_block`].
const PER_PERIOD: [u32; 6] = [1_000, 2_000, 3_000, 400, 500, 600];

/// The SPI traffic of a six-channel block: its identification, then one snapshot per entry of
/// `statuses`, snapshot `n` at `n` periods with `n` periods' pulses of every channel (1,000, 2,000,
/// 3,000, 400, 500, 600 a period) and block status `statuses[n]`.
fn six_channel_block(statuses: &[u32]) -> Vec<Tx<u8>> {
    let mut e = id_frame();
    for (n, &status) in (0u32..).zip(statuses) {
        let counts: Vec<u32> = PER_PERIOD.iter().map(|p| p * n).collect();
        e.extend(snapshot(status, n * TICKS, &counts));
    }
    e
}

#[test]
fn one_snapshot_per_sample_and_a_flagged_channel_alone() {
    // Six channels latched by one frame per sample; channel 4 (QMA y) is flagged FAULT in the
    // second interval, and channel 1 (RLG y) LOST in the third.
    let e = six_channel_block(&[
        0,
        0,
        1 << (block_status::FAULT_SHIFT + 4),
        1 << (block_status::LOST_SHIFT + 1),
        0,
    ]);
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 6> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];

    let flagged_at = [None, None, Some(4), Some(1), None];
    for flagged in flagged_at.iter().skip(1) {
        app.sample_snapshot(&mut therms, &mut block, &mut out);
        for (k, rec) in out.iter().enumerate() {
            if Some(k) == *flagged {
                assert!(rec.compensated.is_nan(), "channel {k}");
                assert_eq!(rec.status, status::NO_MODEL | status::SENSOR_ERROR);
            } else {
                let expected = one_period(k, PER_PERIOD[k] as i32);
                assert_eq!(rec.compensated, expected, "channel {k}");
                assert_eq!(rec.status, status::NO_MODEL, "channel {k}");
            }
        }
    }
    spi.done();
}

#[test]
fn precise_value_keeps_the_pulse_resolution_at_high_rates() {
    // 360,000 °/h on an RLG at 1e-5 arcsec per pulse is
    // 1.8e8 pulses per 5 ms period. One pulse more must show in the frame's value, not in the f32.
    let counts = 180_000_000i32;
    let mut e = id_frame();
    e.extend(snapshot(0, 0, &[0]));
    e.extend(snapshot(0, TICKS, &[counts as u32]));
    e.extend(snapshot(0, 2 * TICKS, &[2 * counts as u32 + 1]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 1> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];
    let mut counters = [&mut block];

    app.sample(&mut therms, &mut counters, &mut out);
    let a = app.precise_value(0, &out[0]);
    let f32_a = out[0].compensated;
    app.sample(&mut therms, &mut counters, &mut out);
    let b = app.precise_value(0, &out[0]);
    let f32_b = out[0].compensated;
    // The exact rate of one pulse per period, °/h (arcsec/s).
    let pulse = f64::from(RLG_ARCSEC_PER_PULSE) / f64::from(PERIOD_S);
    assert!((a - 360_000.0).abs() < 0.1, "{a}");
    assert!(
        ((b - a) - pulse).abs() < 1e-6 * pulse,
        "{} vs {pulse}",
        b - a
    );
    // The f32 output cannot tell them apart.
    assert_eq!(f32_a, f32_b);
    // No valid count: NaN.
    let flagged = Record {
        compensated: f32::NAN,
        periods: 0,
        ..out[0]
    };
    assert!(app.precise_value(0, &flagged).is_nan());
    spi.done();
}

#[test]
fn frames_of_the_loop_decode_to_its_outputs() {
    // What the board does every period, on the host: latch, step, frame, encode; then the host's
    // decoder. Channel 2 is flagged in the second interval.
    let e = six_channel_block(&[0, 0, 1 << (block_status::LOST_SHIFT + 2)]);
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 6> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];
    let mut wire = Vec::new();
    let mut sent = Vec::new();
    for seq in 0..2u32 {
        app.sample_snapshot(&mut therms, &mut block, &mut out);
        let frame = app.frame(seq, u64::from(seq + 1) * 5_000, 1_000_000, &out);
        let mut buf = [0u8; tcomp_core::frame::MAX_FRAME_LEN];
        let n = frame.encode(&mut buf).unwrap();
        wire.extend_from_slice(&buf[..n]);
        sent.push(out);
    }
    let mut decoder = tcomp_core::frame::Decoder::new();
    let mut got = Vec::new();
    decoder.feed(&wire, |f| got.push(f));
    assert_eq!(got.len(), 2);
    for (f, recs) in got.iter().zip(&sent) {
        assert_eq!(f.channels().len(), IMU6.len());
        for (k, (c, rec)) in f.channels().iter().zip(recs).enumerate() {
            assert_eq!(c.status, rec.status, "channel {k}");
            let expected = app.precise_value(k, rec);
            if expected.is_nan() {
                assert_eq!(c.value.to_bits(), tcomp_core::frame::CANONICAL_NAN_BITS);
            } else {
                assert_eq!(c.value, expected, "channel {k}");
                // The f64 value is the exact count over one period (no model: no correction).
                let exact = f64::from(PER_PERIOD[k]) * f64::from(IMU6[k].scale.per_pulse())
                    / f64::from(PERIOD_S);
                assert!(
                    (c.value - exact).abs() <= 1e-12 * exact.abs(),
                    "channel {k}"
                );
            }
        }
    }
    assert!(got[1].channels()[2].value.is_nan());
    assert_eq!(
        got[1].channels()[2].status,
        status::NO_MODEL | status::SENSOR_ERROR
    );
    assert_eq!(got[1].time_s(), 0.01);
    spi.done();
}

/// A thermometer replaying a list of readings, then repeating the last.
struct Seq(Vec<f32>, usize);

impl tcomp_hal::ErrorType for Seq {
    type Error = ErrorKind;
}

impl Thermometer for Seq {
    fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
        let v = self.0.get(self.1).or(self.0.last()).copied().unwrap();
        self.1 += 1;
        Ok(v)
    }
}

/// A counter counting 1000 pulses per period.
struct Steady;

impl tcomp_hal::ErrorType for Steady {
    type Error = ErrorKind;
}

impl PulseCounter for Steady {
    fn read_delta(&mut self) -> Result<i32, ErrorKind> {
        Ok(1000)
    }
}

/// IFOG1's coil thermometer reads `temps`: the status words of the samples.
fn coil_statuses(temps: Vec<f32>) -> Vec<u16> {
    let n = temps.len();
    let mut app = App::new(&IFOG1);
    let mut t = [Seq(temps, 0)];
    let mut out = [Record::default()];
    (0..n)
        .map(|_| {
            app.sample(&mut t, &mut [Steady], &mut out);
            out[0].status
        })
        .collect()
}

#[test]
fn a_thermometer_jump_within_range_is_refused_and_flagged_while_it_lasts() {
    // 25 °C, a 3 °C spike for 10 samples (50 ms), back to 25 °C.
    let mut temps = vec![25.0; 20];
    for t in &mut temps[5..15] {
        *t = 28.0;
    }
    let s = coil_statuses(temps);
    for (n, w) in s.iter().enumerate() {
        let jumped = w & status::TEMP_JUMP != 0;
        // (No model here: the refused reading's INPUT_FAULT shows only with one, as in the QEMU run.)
        assert_eq!(jumped, (5..15).contains(&n), "sample {n}: {w:#x}");
    }
}

#[test]
fn a_drift_at_the_physical_rate_passes_and_a_real_step_is_accepted_after_its_time() {
    // 4 °C/s (below the 5 °C/s bound): never flagged.
    let ramp: Vec<f32> = (0..400).map(|n| 20.0 + 4.0 * PERIOD_S * n as f32).collect();
    assert!(
        coil_statuses(ramp)
            .iter()
            .all(|w| w & status::TEMP_JUMP == 0)
    );
    // A lasting 3 °C step is refused until the allowance (0.5 °C + 5 °C/s) covers it: 0.5 s.
    let mut step = vec![25.0; 10];
    step.extend(vec![28.0; 200]);
    let s = coil_statuses(step);
    let flagged = s.iter().filter(|w| *w & status::TEMP_JUMP != 0).count();
    let expected =
        ((3.0 - TEMP_STEP_MARGIN_C) / (MAX_TEMP_RATE_C_PER_S * PERIOD_S)).ceil() as usize;
    assert!(flagged.abs_diff(expected) <= 1, "{flagged} vs {expected}");
    assert_eq!(s.last().unwrap() & status::TEMP_JUMP, 0);
}

#[test]
fn reset_in_place_equals_a_new_loop() {
    let temps: Vec<f32> = (0..50).map(|n| 25.0 + 0.01 * n as f32).collect();
    let mut used = App::new(&IMU6);
    let mut t: [Seq; MAX_THERMOMETERS] = core::array::from_fn(|_| Seq(temps.clone(), 0));
    let mut out = [Record::default(); 6];
    for _ in 0..50 {
        used.sample(
            &mut t,
            &mut [Steady, Steady, Steady, Steady, Steady, Steady],
            &mut out,
        );
    }
    used.reset(&IFOG1);
    let mut fresh = App::new(&IFOG1);
    let run = |app: &mut App<'_>| {
        let mut t = [Seq(vec![30.0, 30.5, 31.0], 0)];
        let mut out = [Record::default()];
        (0..3)
            .map(|_| {
                app.sample(&mut t, &mut [Steady], &mut out);
                (out[0].compensated.to_bits(), out[0].status)
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(used.config().len(), 1);
    assert_eq!(run(&mut used), run(&mut fresh));
}

/// A one-channel block (RLG x) whose snapshots latch `(timestamp, count)`, after a baseline at 0.
fn rlg_block(snaps: &[(u32, u32)]) -> Vec<Tx<u8>> {
    let mut e = id_frame();
    e.extend(snapshot(0, 0, &[0]));
    for &(t, c) in snaps {
        e.extend(snapshot(0, t, &[c]));
    }
    e
}

#[test]
fn the_rate_divides_by_the_latched_interval() {
    // 1000 pulses over 5.1 ms (51,000 ticks of 10 MHz), then 1000 over exactly 5 ms.
    let e = rlg_block(&[(51_000, 1_000), (101_000, 2_000)]);
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 1> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];

    app.sample_snapshot(&mut therms, &mut block, &mut out);
    let expected = IMU6[0].scale.rate(1_000, 0.0051).unwrap();
    assert_eq!(out[0].compensated, expected);
    assert_ne!(out[0].compensated, one_period(0, 1_000));
    assert_eq!(out[0].interval_s, 0.0051);
    assert_eq!(out[0].status, status::NO_MODEL);
    // The frame's value uses the same interval.
    let exact = 1_000.0 * f64::from(IMU6[0].scale.per_pulse()) / f64::from(0.0051f32);
    assert!((app.precise_value(0, &out[0]) - exact).abs() < 1e-9 * exact);

    app.sample_snapshot(&mut therms, &mut block, &mut out);
    assert_eq!(out[0].compensated, one_period(0, 1_000));
    assert_eq!(out[0].status, status::NO_MODEL);
    spi.done();
}

#[test]
fn an_implausible_latched_interval_is_flagged_and_the_nominal_period_used() {
    // 6 ms (+20 %) and 3.9 ms (−22 %) are both outside the tolerance; 5.4 ms (+8 %) is inside.
    let e = rlg_block(&[(60_000, 1_000), (99_000, 2_000), (153_000, 3_000)]);
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 1> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let mut app = App::new(&IMU6);
    let mut therms = thermometers();
    let mut out = [Record::default(); MAX_CHANNELS];

    for _ in 0..2 {
        app.sample_snapshot(&mut therms, &mut block, &mut out);
        assert_eq!(out[0].compensated, one_period(0, 1_000));
        assert_eq!(out[0].interval_s, PERIOD_S);
        assert_eq!(out[0].status, status::NO_MODEL | status::TIME_JUMP);
    }
    app.sample_snapshot(&mut therms, &mut block, &mut out);
    assert_eq!(
        out[0].compensated,
        IMU6[0].scale.rate(1_000, 0.0054).unwrap()
    );
    assert_eq!(out[0].status, status::NO_MODEL);
    spi.done();
}

#[test]
fn a_skipped_timer_period_is_covered_by_the_next_latched_interval() {
    // The interrupt of the second period never ran: the next snapshot latches 2000 pulses over
    // 10.01 ms. Announced, that is two periods at the latched interval; unannounced, it is a
    // time jump (a whole period off).
    for announce in [true, false] {
        let e = rlg_block(&[(TICKS, 1_000), (3 * TICKS + 100, 3_000)]);
        let mut spi = Mock::new(&e);
        let mut block: CounterBlock<_, 1> = CounterBlock::new(spi.clone());
        block.init().unwrap();
        let mut app = App::new(&IMU6);
        let mut therms = thermometers();
        let mut out = [Record::default(); MAX_CHANNELS];

        app.sample_snapshot(&mut therms, &mut block, &mut out);
        assert_eq!(out[0].compensated, one_period(0, 1_000));
        if announce {
            app.skip_periods(1);
        }
        app.sample_snapshot(&mut therms, &mut block, &mut out);
        assert_eq!(out[0].counts, 2_000);
        if announce {
            assert_eq!(out[0].periods, 2);
            assert_eq!(
                out[0].compensated,
                IMU6[0].scale.rate(2_000, 0.01001).unwrap()
            );
            assert_eq!(out[0].status, status::NO_MODEL);
        } else {
            assert_eq!(out[0].periods, 1);
            assert_eq!(out[0].compensated, one_period(0, 2_000));
            assert_eq!(out[0].status, status::NO_MODEL | status::TIME_JUMP);
        }
        spi.done();
    }
}
