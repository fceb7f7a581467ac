//! The output frame: encode→decode identity, resynchronisation after garbage and corruption, loss
//! counting by sequence gaps, and a decoder that never panics on any bytes.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

use proptest::prelude::*;
use tcomp_core::frame::{
    CANONICAL_NAN_BITS, ChannelOutput, Decoder, Frame, FrameError, MAX_CHANNELS, MAX_FRAME_LEN,
    SYNC, frame_len, status,
};

fn encode(f: &Frame) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = f.encode(&mut buf).unwrap();
    buf[..n].to_vec()
}

fn decode_all(bytes: &[u8]) -> (Vec<Frame>, Decoder) {
    let mut d = Decoder::new();
    let mut frames = Vec::new();
    d.feed(bytes, |f| frames.push(f));
    (frames, d)
}

fn frame(seq: u32, k: usize) -> Frame {
    let channels: Vec<ChannelOutput> = (0..k)
        .map(|i| ChannelOutput {
            value: 360_000.0 + f64::from(seq) * 1e-3 + i as f64,
            status: (i as u16) & 0x1F,
        })
        .collect();
    Frame::new(seq, u64::from(seq) * 5_000, 1_000_000, &channels)
}

/// Values as the wire carries them: any NaN becomes the canonical one.
fn canonical(f: &Frame) -> Vec<(u64, u16)> {
    f.channels()
        .iter()
        .map(|c| {
            let bits = if c.value.is_nan() {
                CANONICAL_NAN_BITS
            } else {
                c.value.to_bits()
            };
            (bits, c.status)
        })
        .collect()
}

fn arb_frame() -> impl Strategy<Value = Frame> {
    let channel = (any::<u64>(), any::<u16>()).prop_map(|(bits, status)| ChannelOutput {
        value: f64::from_bits(bits),
        status,
    });
    (
        any::<u32>(),
        any::<u64>(),
        any::<u32>(),
        prop::collection::vec(channel, 1..=MAX_CHANNELS),
    )
        .prop_map(|(seq, ts, hz, ch)| Frame::new(seq, ts, hz, &ch))
}

#[test]
fn layout_of_a_six_channel_frame() {
    let f = frame(7, 6);
    let bytes = encode(&f);
    assert_eq!(bytes.len(), 84);
    assert_eq!(bytes.len(), frame_len(6));
    assert_eq!(bytes[..2], SYNC);
    assert_eq!(bytes[2], 1);
    assert_eq!(bytes[3], 6);
    assert_eq!(bytes[4..8], 7u32.to_le_bytes());
    assert_eq!(bytes[8..16], 35_000u64.to_le_bytes());
    assert_eq!(bytes[16..20], 1_000_000u32.to_le_bytes());
    assert_eq!(bytes[20..28], f.channels()[0].value.to_le_bytes());
    let crc = tcomp_core::blob::crc32(&bytes[2..80]);
    assert_eq!(bytes[80..84], crc.to_le_bytes());
    assert_eq!(f.time_s(), 0.035);
}

#[test]
fn nan_is_sent_canonical() {
    // A NaN with a payload and the sign bit set, as an ARM or x86 operation may produce.
    let odd_nan = f64::from_bits(0xFFF8_0000_DEAD_BEEF);
    let f = Frame::new(
        0,
        0,
        1,
        &[ChannelOutput {
            value: odd_nan,
            status: status::SENSOR_ERROR,
        }],
    );
    let bytes = encode(&f);
    assert_eq!(bytes[20..28], CANONICAL_NAN_BITS.to_le_bytes());
    // The f64 widening of the f32 canonical NaN 0x7FC0_0000.
    assert_eq!(
        f64::from(f32::from_bits(0x7FC0_0000)).to_bits(),
        CANONICAL_NAN_BITS
    );
}

#[test]
fn encode_errors() {
    let f = frame(0, 6);
    let mut short = [0u8; 83];
    assert_eq!(f.encode(&mut short), Err(FrameError::BufferTooSmall));
    let empty = Frame::new(0, 0, 1, &[]);
    assert_eq!(empty.encode(&mut [0u8; 64]), Err(FrameError::ChannelCount));
}

#[test]
fn status_names() {
    let mut names = Vec::new();
    status::for_each_name(
        status::NO_MODEL | status::SENSOR_ERROR | 0x200 | status::OVERRUN,
        |n| names.push(n),
    );
    assert_eq!(
        names,
        [Ok("no-model"), Ok("sensor-error"), Err(9), Ok("overrun")]
    );
    // Every named bit is a single bit, and no two share one.
    let all = status::NAMES.iter().fold(0u16, |acc, (m, _)| {
        assert_eq!(m.count_ones(), 1);
        assert_eq!(acc & m, 0);
        acc | m
    });
    assert_eq!(all.count_ones() as usize, status::NAMES.len());
}

#[test]
fn lost_and_corrupt_frames_are_counted() {
    let mut stream = Vec::new();
    stream.extend(b"line noise \xEB\x90\x01");
    stream.extend(encode(&frame(10, 6)));
    stream.extend(encode(&frame(11, 6)));
    // Frame 12 is corrupted by one flipped bit in a value.
    let mut bad = encode(&frame(12, 6));
    bad[30] ^= 0x10;
    stream.extend(&bad);
    // Frames 13 and 14 never arrive; frame 15 is cut short by 5 bytes, then 16 follows.
    let cut = encode(&frame(15, 6));
    stream.extend(&cut[..cut.len() - 5]);
    stream.extend(encode(&frame(16, 6)));
    stream.extend(encode(&frame(17, 3)));

    let (frames, d) = decode_all(&stream);
    let seqs: Vec<u32> = frames.iter().map(|f| f.sequence).collect();
    assert_eq!(seqs, [10, 11, 16, 17]);
    assert_eq!(frames[2], frame(16, 6));
    assert_eq!(frames[3], frame(17, 3));
    let s = d.stats();
    assert_eq!(s.frames, 4);
    // 12 (corrupt), 13, 14, 15 (cut) are missing between 11 and 16.
    assert_eq!(s.lost, 4);
    // The bit-flipped frame fails its CRC, and so does the cut one, whose candidate runs into frame
    // 16; the decoder then resynchronises on 16's sync word.
    assert_eq!(s.corrupt, 2);
    assert_eq!(s.restarts, 0);
}

#[test]
fn a_sender_restart_is_not_a_loss() {
    let mut stream = encode(&frame(1_000, 2));
    stream.extend(encode(&frame(0, 2)));
    stream.extend(encode(&frame(1, 2)));
    let (frames, d) = decode_all(&stream);
    assert_eq!(frames.len(), 3);
    assert_eq!(d.stats().lost, 0);
    assert_eq!(d.stats().restarts, 1);
}

proptest! {
    #[test]
    fn encode_decode_identity(frames in prop::collection::vec(arb_frame(), 1..6)) {
        let stream: Vec<u8> = frames.iter().flat_map(encode).collect();
        let (decoded, d) = decode_all(&stream);
        prop_assert_eq!(decoded.len(), frames.len());
        for (a, b) in frames.iter().zip(&decoded) {
            prop_assert_eq!((a.sequence, a.timestamp, a.tick_hz), (b.sequence, b.timestamp, b.tick_hz));
            prop_assert_eq!(canonical(a), canonical(b));
        }
        prop_assert_eq!(d.stats().corrupt, 0);
        prop_assert_eq!(d.stats().skipped, 0);
    }

    #[test]
    fn any_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2_000)) {
        let (frames, d) = decode_all(&bytes);
        prop_assert_eq!(d.stats().frames, frames.len() as u64);
    }

    #[test]
    fn garbage_between_frames_is_skipped(
        garbage in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..200), 4),
        chunk in 1usize..97,
    ) {
        // Frames 0..4 with garbage before each; fed in chunks of any size.
        let mut stream = Vec::new();
        for (i, g) in garbage.iter().enumerate() {
            stream.extend(g);
            stream.extend(encode(&frame(i as u32, 1 + i)));
        }
        let mut d = Decoder::new();
        let mut got = Vec::new();
        for c in stream.chunks(chunk) {
            d.feed(c, |f| got.push(f));
        }
        // Garbage may by chance contain a valid frame (vanishingly unlikely with a CRC-32), never
        // hide one: every sent frame is decoded, in order.
        let sent: Vec<Frame> = (0..4).map(|i| frame(i, 1 + i as usize)).collect();
        let mut it = got.iter();
        for s in &sent {
            prop_assert!(it.any(|g| g == s), "frame {} missing", s.sequence);
        }
    }
}
