//! The generic sync-word framer on a toy format: garbage skipped, a false start inside a frame,
//! a corrupt CRC followed by a good frame, the longest frame, two frames left by one
//! resynchronisation, and any bytes never panicking. The output frames (`frame.rs`,
//! `boot_report.rs`) and the update protocol's frames (`update_receiver.rs`) test its two users.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

use proptest::prelude::*;
use tcomp_core::crc::crc32;
use tcomp_core::framer::{CRC_LEN, Framer, Framing};

/// Sync 0xA5 0x5A, one length byte (the payload's), the payload, the CRC.
#[derive(Clone, Debug)]
struct Toy;

const SYNC: [u8; 2] = [0xA5, 0x5A];
const HEADER: usize = 3;

impl Framing for Toy {
    const SYNC: &'static [u8] = &SYNC;
    const HEADER_LEN: usize = HEADER;

    fn frame_len(header: &[u8]) -> Option<usize> {
        let len = usize::from(*header.get(2)?);
        // 0xFF: not a header of this format (a header the format refuses).
        (len != 0xFF).then_some(HEADER + len + CRC_LEN)
    }
}

/// The longest toy frame in [`Small`]: a payload of 9 bytes.
const N: usize = 16;
type Small = Framer<Toy, N>;

fn frame(payload: &[u8]) -> Vec<u8> {
    let mut f = SYNC.to_vec();
    f.push(payload.len() as u8);
    f.extend_from_slice(payload);
    let crc = crc32(&f[SYNC.len()..]);
    f.extend_from_slice(&crc.to_le_bytes());
    f
}

/// Every frame the framer yields for `bytes`, fed one at a time and polled empty after each.
fn frames<const M: usize>(framer: &mut Framer<Toy, M>, bytes: &[u8]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for &b in bytes {
        if let Some(f) = framer.push(b) {
            out.push(f.to_vec());
            while let Some(f) = framer.poll() {
                out.push(f.to_vec());
            }
        }
    }
    out
}

#[test]
fn garbage_before_a_frame_is_skipped() {
    let good = frame(b"abc");
    let mut stream = b"line noise \xA5\xA5\x5B".to_vec();
    stream.extend(&good);
    let mut f = Small::new();
    assert_eq!(frames(&mut f, &stream), [good]);
    assert_eq!(f.skipped(), 14);
    assert_eq!(f.corrupt(), 0);
}

#[test]
fn a_frame_starting_inside_a_corrupt_frame_is_found() {
    // A frame whose payload carries a whole frame, then one bit of the outer payload flipped: the
    // outer CRC fails, and the search from its second byte finds the inner frame.
    let inner = frame(b"in");
    let mut outer = frame(&[b"x".as_slice(), &inner].concat());
    outer[3] ^= 0x01;
    let after = frame(b"after");
    let mut f = Framer::<Toy, 32>::new();
    assert_eq!(
        frames(&mut f, &[outer.clone(), after.clone()].concat()),
        [inner.clone(), after]
    );
    assert_eq!(f.corrupt(), 1);
    // The outer frame's sync word, length byte and flipped byte before the inner frame, and its
    // CRC after it.
    assert_eq!(f.skipped(), (4 + CRC_LEN) as u64);
}

#[test]
fn a_false_start_whose_length_runs_into_a_frame() {
    // A sync word and a length byte in garbage promise a 10-byte frame; the good frame that begins
    // right after them is found once that promise fails its CRC.
    let good = frame(b"0123456");
    let mut stream = vec![0x00, SYNC[0], SYNC[1], 3];
    stream.extend(&good);
    let mut f = Small::new();
    assert_eq!(frames(&mut f, &stream), [good]);
    assert_eq!((f.skipped(), f.corrupt()), (4, 1));
}

#[test]
fn a_corrupt_crc_costs_that_frame_only() {
    let mut bad = frame(b"bad");
    let n = bad.len();
    bad[n - 1] ^= 0x80;
    let good = frame(b"good");
    let mut f = Small::new();
    assert_eq!(
        frames(&mut f, &[bad.clone(), good.clone()].concat()),
        [good]
    );
    assert_eq!(f.corrupt(), 1);
    assert_eq!(f.skipped(), n as u64);
}

#[test]
fn the_longest_frame_fills_the_buffer_and_a_longer_one_is_no_frame() {
    let longest = frame(&[7; N - HEADER - CRC_LEN]);
    assert_eq!(longest.len(), N);
    // A header promising one byte more than the buffer holds: not a frame start (not corrupt).
    let too_long = frame(&[7; N - HEADER - CRC_LEN + 1]);
    // And a header the format refuses.
    let refused = [SYNC[0], SYNC[1], 0xFF];
    let mut f = Small::new();
    let stream = [
        longest.clone(),
        too_long.clone(),
        refused.to_vec(),
        longest.clone(),
    ]
    .concat();
    assert_eq!(frames(&mut f, &stream), [longest.clone(), longest]);
    assert_eq!(f.corrupt(), 0);
    assert_eq!(f.skipped(), (too_long.len() + refused.len()) as u64);
}

#[test]
fn one_resynchronisation_can_leave_two_frames() {
    // A false start promising 17 bytes, then two 7-byte frames: when the false start fails its
    // CRC at byte 17 both frames are complete; push returns the first, poll the second.
    let (a, b) = (frame(&[]), frame(&[]));
    let mut stream = vec![SYNC[0], SYNC[1], 10];
    stream.extend(&a);
    stream.extend(&b);
    assert_eq!(stream.len(), 17);
    let mut f = Framer::<Toy, 32>::new();
    let (last, head) = stream.split_last().unwrap();
    for &x in head {
        assert_eq!(f.push(x), None);
    }
    assert_eq!(f.push(*last).map(<[u8]>::to_vec), Some(a));
    assert_eq!(f.poll().map(<[u8]>::to_vec), Some(b));
    assert_eq!(f.poll(), None);
    assert_eq!((f.skipped(), f.corrupt()), (3, 1));
}

proptest! {
    /// Any bytes: no panic, every frame yielded checks, and no byte is both skipped and yielded.
    #[test]
    fn any_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2_000)) {
        let mut f = Small::new();
        let got = frames(&mut f, &bytes);
        for g in &got {
            prop_assert_eq!(&g[..2], &SYNC[..]);
            prop_assert_eq!(g.len(), HEADER + usize::from(g[2]) + CRC_LEN);
            prop_assert_eq!(&g[g.len() - 4..], &crc32(&g[2..g.len() - 4]).to_le_bytes()[..]);
        }
        let yielded: usize = got.iter().map(Vec::len).sum();
        prop_assert!(f.skipped() as usize + yielded <= bytes.len());
    }

    /// Frames with any garbage before each are all found, in order, whatever the garbage.
    #[test]
    fn every_frame_after_garbage_is_found(
        garbage in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..40), 4),
        payloads in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..=9), 4),
    ) {
        let mut stream = Vec::new();
        for (g, p) in garbage.iter().zip(&payloads) {
            stream.extend(g);
            stream.extend(frame(p));
        }
        let got = frames(&mut Small::new(), &stream);
        let mut it = got.iter();
        for p in &payloads {
            let sent = frame(p);
            prop_assert!(it.any(|g| *g == sent), "frame {:?} missing", p);
        }
    }
}
