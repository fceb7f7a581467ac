//! FPGA up/down counter block against embedded-hal-mock SPI transaction queues.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

mod common;

use common::FailAt;
use embedded_hal_mock::eh1::spi::{Mock, Transaction as Tx};
use proptest::prelude::*;
use tcomp_hal::pulse_counter::{self, ChannelFlags, CounterBlock, Error, ID_VALUE, Info, status};
use tcomp_hal::{CounterSnapshot, Error as _, ErrorKind, Interval, PulseCounter, wrapping_delta};

/// INFO: 8 channels, 32-bit counters, 10 MHz timestamp clock (10 000 kHz = 0x2710).
const INFO: u32 = 0x2710_2008;

fn frame(ops: Vec<Tx<u8>>) -> Vec<Tx<u8>> {
    let mut v = vec![Tx::transaction_start()];
    v.extend(ops);
    v.push(Tx::transaction_end());
    v
}

/// `[READ | ID]` then ID and INFO.
fn id_frame(id: u32, info: u32) -> Vec<Tx<u8>> {
    let mut data = id.to_be_bytes().to_vec();
    data.extend(info.to_be_bytes());
    frame(vec![Tx::write_vec(vec![0x80]), Tx::read_vec(data)])
}

/// `[LATCH, READ | STATUS]` then STATUS, TIMESTAMP, COUNT[0..N].
fn snapshot(status: u32, timestamp: u32, counts: &[u32]) -> Vec<Tx<u8>> {
    let mut data = status.to_be_bytes().to_vec();
    data.extend(timestamp.to_be_bytes());
    for c in counts {
        data.extend(c.to_be_bytes());
    }
    frame(vec![Tx::write_vec(vec![0x01, 0x82]), Tx::read_vec(data)])
}

fn init_frames(counts: &[u32], timestamp: u32) -> Vec<Tx<u8>> {
    let mut v = id_frame(ID_VALUE, INFO);
    // Baseline snapshot: its (stale) flags are discarded.
    v.extend(snapshot(0xFFFF_FFFF, timestamp, counts));
    v
}

#[test]
fn info_register_layout() {
    let info = Info::from_register(INFO);
    assert_eq!(
        info,
        Info {
            channels: 8,
            counter_bits: 32,
            timestamp_khz: 10_000
        }
    );
    assert_eq!(info.to_register(), INFO);
    assert_eq!(info.timestamp_hz(), 10_000_000);
}

#[test]
fn init_and_normal_deltas_with_sign() {
    let mut e = init_frames(&[100, 200, 300], 1_000);
    // 5 ms later at 10 MHz: +50 000 ticks. Channel 0 counted 50 up, channel 1 20 down (net), 2 idle.
    e.extend(snapshot(0, 51_000, &[150, 180, 300]));
    e.extend(snapshot(0, 101_000, &[149, 190, 300]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 3> = CounterBlock::new(spi.clone());
    let info = block.init().unwrap();
    assert_eq!(info.channels, 8);
    assert_eq!(block.timestamp_hz(), 10_000_000);

    let s = block.sample().unwrap();
    let deltas: Vec<i32> = s
        .channels
        .iter()
        .map(|c| c.valid_delta().unwrap())
        .collect();
    assert_eq!(deltas, [50, -20, 0]);
    assert!(s.channels.iter().all(|c| c.ticks == 50_000));
    assert_eq!(s.interval_s(0), Some(0.005));
    assert_eq!(s.interval_s(3), None);

    let s = block.sample().unwrap();
    let deltas: Vec<i32> = s.channels.iter().map(|c| c.delta).collect();
    assert_eq!(deltas, [-1, 10, 0]);
    spi.done();
}

#[test]
fn wrap_around_both_directions() {
    // Channel 0 counts up through 2³², channel 1 down through 0.
    let mut e = init_frames(&[0xFFFF_FFF0, 0x0000_0005], 0xFFFF_0000);
    // Timestamp wraps too: 0xFFFF_0000 → 0x0000_C350 is 0x1_0000 + 0xC350 = 115 536 ticks.
    e.extend(snapshot(0, 0x0000_C350, &[0x0000_0010, 0xFFFF_FFFB]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 2> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let s = block.sample().unwrap();
    // 0xFFFF_FFF0 → 0x1_0000_0010: +0x20 = +32.  5 → −5 (0xFFFF_FFFB): −10.
    assert_eq!(s.channels[0].valid_delta(), Ok(32));
    assert_eq!(s.channels[1].valid_delta(), Ok(-10));
    assert_eq!(s.channels[0].ticks, 115_536);
    spi.done();
}

#[test]
fn status_bits_flag_only_their_channel() {
    let mut e = init_frames(&[0, 0, 0], 0);
    let lost_ch0 = 1 << (status::LOST_SHIFT);
    let fault_ch2 = 1 << (status::FAULT_SHIFT + 2);
    e.extend(snapshot(lost_ch0 | fault_ch2, 100, &[7, 8, 9]));
    e.extend(snapshot(status::CLOCK_FAULT, 200, &[8, 9, 10]));
    e.extend(snapshot(0, 300, &[9, 10, 11]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 3> = CounterBlock::new(spi.clone());
    block.init().unwrap();

    let s = block.sample().unwrap();
    assert_eq!(s.channels[0].valid_delta(), Err(ErrorKind::Overflow));
    assert_eq!(s.channels[1].valid_delta(), Ok(8));
    assert_eq!(s.channels[2].valid_delta(), Err(ErrorKind::Fault));
    // The faulty interval is consumed: its counts are still reported, marked.
    assert_eq!(s.channels[2].delta, 9);

    // A clock fault taints every channel.
    let s = block.sample().unwrap();
    assert!(s.channels.iter().all(|c| c.flags.clock_fault));
    assert!(
        s.channels
            .iter()
            .all(|c| c.valid_delta() == Err(ErrorKind::Fault))
    );

    // The event flags are per interval: the next clean snapshot is clean.
    let s = block.sample().unwrap();
    assert!(s.channels.iter().all(|c| c.valid_delta() == Ok(1)));
    spi.done();
}

#[test]
fn per_channel_handles_keep_counts_and_faults_of_the_others() {
    let mut e = init_frames(&[1_000, 2_000], 0);
    // Read channel 0: channel 1 has a sensor fault in this interval and keeps counting.
    e.extend(snapshot(
        1 << (status::FAULT_SHIFT + 1),
        10,
        &[1_003, 2_050],
    ));
    // Read channel 1: its snapshot is clean, but the earlier fault is still pending for it, and its
    // delta covers both intervals (2 000 → 2 070).
    e.extend(snapshot(0, 20, &[1_004, 2_070]));
    // Read channel 1 again: now clean.
    e.extend(snapshot(0, 30, &[1_005, 2_071]));
    // Read channel 0: 1 003 → 1 005.
    e.extend(snapshot(0, 40, &[1_005, 2_072]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 2> = CounterBlock::new(spi.clone());
    block.init().unwrap();

    assert_eq!(block.channel(0).unwrap().read_delta(), Ok(3));
    let err = block.channel(1).unwrap().read_delta().unwrap_err();
    assert_eq!(err, Error::SensorFault);
    assert_eq!(err.kind(), ErrorKind::Fault);
    assert_eq!(block.channel(1).unwrap().read_delta(), Ok(1));
    assert_eq!(block.channel(0).unwrap().read_delta(), Ok(2));
    assert!(block.channel(2).is_none());
    assert_eq!(
        block.read_channel(5).unwrap_err().kind(),
        ErrorKind::InvalidConfig
    );
    spi.done();
}

#[test]
fn lost_pulses_and_clock_fault_through_the_trait() {
    let mut e = init_frames(&[0], 0);
    e.extend(snapshot(1 << status::LOST_SHIFT, 1, &[5]));
    e.extend(snapshot(status::CLOCK_FAULT, 2, &[6]));
    e.extend(snapshot(0, 3, &[4]));
    let mut spi = Mock::new(&e);
    // A one-channel block is itself a PulseCounter.
    let mut block: CounterBlock<_, 1> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    let err = block.read_delta().unwrap_err();
    assert_eq!((err, err.kind()), (Error::PulsesLost, ErrorKind::Overflow));
    let err = block.read_delta().unwrap_err();
    assert_eq!((err, err.kind()), (Error::ClockFault, ErrorKind::Fault));
    assert_eq!(block.read_delta(), Ok(-2));
    spi.done();
}

#[test]
fn id_mismatch_at_init() {
    // A floating MISO reads all ones.
    let mut spi = Mock::new(&id_frame(0xFFFF_FFFF, 0xFFFF_FFFF));
    let mut block: CounterBlock<_, 6> = CounterBlock::new(spi.clone());
    let err = block.init().unwrap_err();
    assert_eq!(err, Error::WrongId { id: 0xFFFF_FFFF });
    assert_eq!(err.kind(), ErrorKind::WrongDevice);
    // Not initialised: reads refuse rather than return counts since power-on.
    assert_eq!(block.sample().unwrap_err().kind(), ErrorKind::NotReady);
    spi.done();
}

#[test]
fn too_few_channels_or_wrong_width_at_init() {
    // INFO says 4 channels; the driver wants 6.
    let four = 0x2710_2004;
    // INFO says 8 channels of 16 bits.
    let narrow = 0x2710_1008;
    let mut e = id_frame(ID_VALUE, four);
    e.extend(id_frame(ID_VALUE, narrow));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 6> = CounterBlock::new(spi.clone());
    assert_eq!(block.init().unwrap_err(), Error::Unsupported { info: four });
    let err = block.init().unwrap_err();
    assert_eq!(err, Error::Unsupported { info: narrow });
    assert_eq!(err.kind(), ErrorKind::WrongDevice);
    spi.done();
}

#[test]
fn bus_error_loses_no_pulses() {
    let mut e = init_frames(&[10, 20], 0);
    // Transaction 2 (the first sample) fails on the bus and never reaches the device.
    e.extend(snapshot(0, 100, &[15, 18]));
    let mut mock = Mock::new(&e);
    let mut block: CounterBlock<_, 2> = CounterBlock::new(FailAt::new(mock.clone(), 2));
    block.init().unwrap();
    let err = block.sample().unwrap_err();
    assert_eq!(err, Error::Spi(embedded_hal::spi::ErrorKind::Other));
    assert_eq!(err.kind(), ErrorKind::Bus);
    // The next read covers everything since the last successful one.
    let s = block.sample().unwrap();
    assert_eq!(s.channels[0].valid_delta(), Ok(5));
    assert_eq!(s.channels[1].valid_delta(), Ok(-2));
    assert_eq!(s.channels[0].ticks, 100);
    mock.done();
}

#[test]
fn bus_error_at_init_and_through_the_trait() {
    let mut e = init_frames(&[0], 0);
    e.extend(snapshot(0, 1, &[3]));
    let mut mock = Mock::new(&e);
    // Fail the very first transaction (ID read) and the first read after init.
    let mut block: CounterBlock<_, 1> = CounterBlock::new(FailAt::new(mock.clone(), 0));
    assert_eq!(block.init().unwrap_err().kind(), ErrorKind::Bus);
    block.init().unwrap();
    assert_eq!(block.read_delta(), Ok(3));
    mock.done();
}

#[test]
fn wrapping_delta_examples() {
    assert_eq!(wrapping_delta(0, 0, 32), 0);
    assert_eq!(wrapping_delta(0, 0x7FFF_FFFF, 32), i32::MAX);
    assert_eq!(wrapping_delta(0, 0x8000_0000, 32), i32::MIN);
    assert_eq!(wrapping_delta(0xFFFF_FFFF, 0, 32), 1);
    assert_eq!(wrapping_delta(0, 0xFFFF_FFFF, 32), -1);
    // A 16-bit MCU timer in encoder mode: the high bits are ignored.
    assert_eq!(wrapping_delta(0xFFF0, 0x0010, 16), 32);
    assert_eq!(wrapping_delta(0x0005, 0xFFFB, 16), -10);
    assert_eq!(wrapping_delta(0xABCD_0005, 0x1234_FFFB, 16), -10);
    assert_eq!(wrapping_delta(0, 0x8000, 16), -32_768);
    // Out-of-range widths are clamped, never a panic.
    assert_eq!(wrapping_delta(0, 5, 0), -1);
    assert_eq!(wrapping_delta(0, 5, 40), 5);
}

#[test]
fn channel_flags_priority() {
    let all = ChannelFlags {
        pulses_lost: true,
        sensor_fault: true,
        clock_fault: true,
    };
    assert_eq!(all.check(), Err(ErrorKind::Fault));
    assert_eq!(ChannelFlags::default().check(), Ok(()));
    assert_eq!(pulse_counter::MAX_CHANNELS, 8);
}

proptest! {
    #[test]
    fn wrapping_delta_inverts_wrapping_add_32(prev in any::<u32>(), delta in any::<i32>()) {
        prop_assert_eq!(wrapping_delta(prev, prev.wrapping_add(delta as u32), 32), delta);
    }

    #[test]
    fn wrapping_delta_inverts_wrapping_add_16(prev in any::<u16>(), delta in any::<i16>()) {
        let now = prev.wrapping_add(delta as u16);
        prop_assert_eq!(wrapping_delta(u32::from(prev), u32::from(now), 16), i32::from(delta));
    }
}

#[test]
fn snapshot_trait_latches_once_and_tells_flagged_from_unread() {
    let mut e = init_frames(&[0, 0, 0], 0);
    e.extend(snapshot(1 << (status::FAULT_SHIFT + 1), 10, &[5, 6, 7]));
    // Transaction 3 fails on the bus (see below); the next snapshot covers both periods.
    e.extend(snapshot(0, 30, &[15, 16, 17]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 3> = CounterBlock::new(FailAt::new(spi.clone(), 3));
    block.init().unwrap();
    // A longer output than the block: the extra entries are left alone.
    let untouched = Interval::Counted(-1);
    let mut out = [untouched; 4];

    // 10 ticks of the 10 MHz timestamp clock since the baseline.
    assert_eq!(block.read_snapshot(&mut out), Some(10.0 / 10.0e6));
    assert_eq!(
        out,
        [
            Interval::Counted(5),
            Interval::Flagged(ErrorKind::Fault),
            Interval::Counted(7),
            untouched,
        ]
    );
    assert_eq!(block.read_snapshot(&mut out), None);
    assert_eq!(out[..3], [Interval::Unread(ErrorKind::Bus); 3]);
    assert_eq!(out[3], untouched);
    // Nothing was consumed by the failed read: counts and time both cover the two periods.
    assert_eq!(block.read_snapshot(&mut out), Some(20.0 / 10.0e6));
    assert_eq!(
        out[..3],
        [
            Interval::Counted(10),
            Interval::Counted(10),
            Interval::Counted(10)
        ]
    );
    spi.done();
}

#[test]
fn interval_from_result_follows_the_error_kind() {
    let mut e = init_frames(&[0], 0);
    e.extend(snapshot(1 << status::LOST_SHIFT, 1, &[5]));
    e.extend(snapshot(status::CLOCK_FAULT, 2, &[6]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 1> = CounterBlock::new(FailAt::new(spi.clone(), 4));
    block.init().unwrap();
    assert_eq!(
        Interval::from_result(block.read_delta()),
        Interval::Flagged(ErrorKind::Overflow)
    );
    assert_eq!(
        Interval::from_result(block.read_delta()),
        Interval::Flagged(ErrorKind::Fault)
    );
    assert_eq!(
        Interval::from_result(block.read_delta()),
        Interval::Unread(ErrorKind::Bus)
    );
    assert_eq!(
        Interval::from_result(Ok::<_, ErrorKind>(3)),
        Interval::Counted(3)
    );
    spi.done();
}

#[test]
fn snapshot_interval_only_when_every_channel_was_consumed_at_one_instant() {
    let mut e = init_frames(&[0, 0], 0);
    // Channel 0 alone consumed at 50,000 ticks; the snapshot at 100,000 then covers 5 ms for
    // channel 0 and 10 ms for channel 1: no single interval. The next one does have one again.
    e.extend(snapshot(0, 50_000, &[10, 20]));
    e.extend(snapshot(0, 100_000, &[30, 40]));
    e.extend(snapshot(0, 151_000, &[50, 60]));
    let mut spi = Mock::new(&e);
    let mut block: CounterBlock<_, 2> = CounterBlock::new(spi.clone());
    block.init().unwrap();
    assert_eq!(block.read_channel(0).unwrap().ticks, 50_000);
    let mut out = [Interval::Counted(0); 2];
    assert_eq!(block.read_snapshot(&mut out), None);
    assert_eq!(out, [Interval::Counted(20), Interval::Counted(40)]);
    assert_eq!(block.read_snapshot(&mut out), Some(51_000.0 / 10.0e6));
    assert_eq!(out, [Interval::Counted(20), Interval::Counted(20)]);
    spi.done();
}
