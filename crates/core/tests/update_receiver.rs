//! The update receiver and sender over every misbehaviour of a link: lost, duplicated, corrupt and
//! reordered frames, an oversize image, a second BEGIN, an early COMMIT, an image that fails
//! validation; and the frame decoder over garbage and the unit's output frames.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use proptest::prelude::*;
use tcomp_core::frame::{ChannelOutput, Frame};
use tcomp_core::image::{Image, write_image};
use tcomp_core::slots::sim::SimNor;
use tcomp_core::slots::{Crc32, Header, Layout, SlotId, select};
use tcomp_core::update::wire::{Decoder, Kind, MAX_CHUNK, MAX_FRAME, Packet};
use tcomp_core::update::{Failure, Reason, Receiver, Reply, Sender, Status};

const SECTOR: usize = 4096;
type Flash = SimNor<{ 2 * SECTOR }, SECTOR>;
const LAYOUT: Layout = Layout {
    a: 0,
    b: SECTOR as u32,
    size: SECTOR as u32,
};

fn image(seed: u8, blob_len: usize) -> Vec<u8> {
    let blobs: Vec<Vec<u8>> = (0..3u8)
        .map(|i| (0..blob_len).map(|j| (j as u8) ^ seed ^ i).collect())
        .collect();
    let entries: Vec<(u16, &[u8])> = blobs
        .iter()
        .enumerate()
        .map(|(i, b)| (i as u16, b.as_slice()))
        .collect();
    let mut buf = vec![0u8; 8 * SECTOR];
    let n = write_image(&entries, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn validate(flash: &mut Flash, offset: u32, len: u32) -> bool {
    let (at, len) = (offset as usize, len as usize);
    flash
        .bytes()
        .get(at..at + len)
        .is_some_and(|b| Image::parse(b).is_ok())
}

/// [`validate`] as the receiver's check before the commit.
fn check(flash: &mut Flash, offset: u32, len: u32) -> Result<(), Reason> {
    validate(flash, offset, len)
        .then_some(())
        .ok_or(Reason::Invalid)
}

fn booted(flash: &mut Flash) -> Option<(SlotId, u32, Vec<u8>)> {
    let a = select(flash, &LAYOUT, validate).unwrap()?;
    let at = a.payload(&LAYOUT) as usize;
    let bytes = flash.bytes()[at..at + a.header.length as usize].to_vec();
    Some((a.slot, a.header.generation, bytes))
}

/// A unit: flash, receiver and its decoder; requests go in as bytes, replies come out decoded.
struct Unit {
    flash: Flash,
    rx: Receiver,
    decoder: Decoder,
}

impl Unit {
    fn boot(mut flash: Flash) -> Self {
        let active = select(&mut flash, &LAYOUT, validate).unwrap();
        Self {
            flash,
            rx: Receiver::new(LAYOUT, active),
            decoder: Decoder::new(),
        }
    }

    fn feed(&mut self, bytes: &[u8]) -> Vec<Reply> {
        let mut replies = Vec::new();
        for &b in bytes {
            if let Some(p) = self.decoder.push(b) {
                replies.push(self.rx.handle(&mut self.flash, &p, b"SN-0042", check));
            }
        }
        replies
    }

    fn send(&mut self, kind: Kind, seq: u16, payload: &[u8]) -> Reply {
        let mut out = [0u8; MAX_FRAME];
        let n = Packet { kind, seq, payload }.encode(&mut out).unwrap();
        let replies = self.feed(&out[..n]);
        assert_eq!(replies.len(), 1);
        replies[0]
    }

    fn begin(&mut self, image: &[u8]) -> Reply {
        self.begin_session(image, 1)
    }

    fn begin_session(&mut self, image: &[u8], session: u32) -> Reply {
        let mut p = (image.len() as u32).to_le_bytes().to_vec();
        p.extend_from_slice(&tcomp_core::blob::crc32(image).to_le_bytes());
        p.extend_from_slice(&session.to_le_bytes());
        self.send(Kind::Begin, 1, &p)
    }

    fn data(&mut self, image: &[u8], offset: usize) -> Reply {
        let end = (offset + MAX_CHUNK).min(image.len());
        let mut p = (offset as u32).to_le_bytes().to_vec();
        p.extend_from_slice(&image[offset..end]);
        self.send(Kind::Data, 2, &p)
    }

    fn send_all(&mut self, image: &[u8]) {
        for offset in (0..image.len()).step_by(MAX_CHUNK) {
            assert_eq!(self.data(image, offset).kind(), Kind::Ack);
        }
    }
}

fn nak(reply: Reply, reason: Reason) {
    assert_eq!(reply.kind(), Kind::Nak, "{reply:?}");
    assert_eq!(reply.reason(), reason);
}

fn expected_offset(reply: Reply) -> u32 {
    reply.packet().u32_at(1).unwrap()
}

/// A unit running `image` from slot A, generation 1.
fn unit_with(image: &[u8]) -> Unit {
    let mut unit = Unit::boot(Flash::new());
    assert_eq!(unit.begin(image).kind(), Kind::Ack);
    unit.send_all(image);
    let result = unit.send(Kind::Commit, 3, &[]);
    assert_eq!((result.kind(), result.reason()), (Kind::Result, Reason::Ok));
    let unit = Unit::boot(unit.flash);
    assert_eq!(unit.rx.target(), SlotId::B);
    unit
}

#[test]
fn a_full_update_boots_the_new_image_in_the_other_slot() {
    let (old, new) = (image(1, 500), image(2, 700));
    let mut unit = unit_with(&old);
    let info = unit.send(Kind::Hello, 9, &[]);
    assert_eq!(info.kind(), Kind::Info);
    let p = info.packet();
    assert_eq!((p.payload[0], p.u32_at(1)), (0, Some(1)));
    assert_eq!(&p.payload[9..], b"SN-0042");
    assert_eq!(unit.begin(&new).kind(), Kind::Ack);
    unit.send_all(&new);
    let result = unit.send(Kind::Commit, 3, &[]);
    assert_eq!((result.kind(), result.reason()), (Kind::Result, Reason::Ok));
    assert_eq!(result.packet().payload[1], 1);
    assert_eq!(booted(&mut unit.flash), Some((SlotId::B, 2, new)));
    // A lost RESULT: the repeated COMMIT gets the same answer; a new BEGIN waits for the reset.
    assert_eq!(unit.send(Kind::Commit, 3, &[]), result);
    nak(unit.begin(&old), Reason::RebootPending);
}

#[test]
fn a_lost_chunk_is_named_by_the_nak_and_sent_again() {
    let new = image(3, 900);
    let mut unit = Unit::boot(Flash::new());
    unit.begin(&new);
    assert_eq!(unit.data(&new, 0).kind(), Kind::Ack);
    // The chunk at 256 is lost; the one at 512 arrives.
    let reply = unit.data(&new, 2 * MAX_CHUNK);
    nak(reply, Reason::OutOfOrder);
    assert_eq!(expected_offset(reply), MAX_CHUNK as u32);
    unit.send_all(&new);
    assert_eq!(unit.send(Kind::Commit, 3, &[]).reason(), Reason::Ok);
    assert_eq!(booted(&mut unit.flash).unwrap().2, new);
}

#[test]
fn a_duplicated_chunk_or_begin_is_acknowledged_without_writing() {
    let new = image(4, 600);
    let mut unit = Unit::boot(Flash::new());
    unit.flash.power_on();
    assert_eq!(unit.begin(&new).kind(), Kind::Ack);
    let after_begin = unit.flash.steps();
    assert_eq!(unit.begin(&new).kind(), Kind::Ack, "a repeated BEGIN");
    assert_eq!(unit.flash.steps(), after_begin, "no second erase");
    assert_eq!(unit.data(&new, 0).kind(), Kind::Ack);
    let after_chunk = unit.flash.steps();
    assert_eq!(unit.data(&new, 0).kind(), Kind::Ack, "a repeated chunk");
    assert_eq!(unit.flash.steps(), after_chunk);
    unit.send_all(&new);
    assert_eq!(unit.send(Kind::Commit, 3, &[]).reason(), Reason::Ok);
    assert_eq!(booted(&mut unit.flash).unwrap().2, new);
}

#[test]
fn a_corrupt_frame_gets_no_reply_and_the_next_good_one_is_decoded() {
    let new = image(5, 300);
    let mut unit = Unit::boot(Flash::new());
    unit.begin(&new);
    let mut out = [0u8; MAX_FRAME];
    let mut payload = 0u32.to_le_bytes().to_vec();
    payload.extend_from_slice(&new[..MAX_CHUNK]);
    let n = Packet {
        kind: Kind::Data,
        seq: 7,
        payload: &payload,
    }
    .encode(&mut out)
    .unwrap();
    let mut corrupt = out[..n].to_vec();
    corrupt[40] ^= 0x10;
    assert!(unit.feed(&corrupt).is_empty());
    let replies = unit.feed(&out[..n]);
    assert_eq!(replies.len(), 1);
    assert_eq!(replies[0].kind(), Kind::Ack);
}

#[test]
fn an_out_of_order_chunk_writes_nothing() {
    let new = image(6, 900);
    let mut unit = Unit::boot(Flash::new());
    unit.begin(&new);
    let before = unit.flash.bytes().to_vec();
    let reply = unit.data(&new, MAX_CHUNK);
    nak(reply, Reason::OutOfOrder);
    assert_eq!(expected_offset(reply), 0);
    assert_eq!(unit.flash.bytes(), &before[..]);
    // A misaligned chunk that is not the last is refused too.
    let mut p = 0u32.to_le_bytes().to_vec();
    p.extend_from_slice(&new[..10]);
    nak(unit.send(Kind::Data, 4, &p), Reason::BadChunk);
}

#[test]
fn an_oversize_image_is_refused_before_anything_is_erased() {
    let old = image(7, 400);
    let mut unit = unit_with(&old);
    let before = unit.flash.bytes().to_vec();
    let mut p = (LAYOUT.capacity() + 1).to_le_bytes().to_vec();
    p.extend_from_slice(&0u32.to_le_bytes());
    p.extend_from_slice(&1u32.to_le_bytes());
    nak(unit.send(Kind::Begin, 1, &p), Reason::TooLarge);
    assert_eq!(unit.flash.bytes(), &before[..]);
    // The sender refuses it itself once it has the unit's capacity.
    let big = vec![0u8; LAYOUT.capacity() as usize + 1];
    let mut tx = Sender::new(&big, 1);
    let mut out = [0u8; MAX_FRAME];
    let n = tx.request(&mut out).unwrap();
    for r in unit.feed(&out[..n]) {
        tx.on_reply(&r.packet());
    }
    assert_eq!(
        tx.status(),
        Status::Failed(Failure::TooLarge {
            capacity: LAYOUT.capacity()
        })
    );
}

#[test]
fn a_begin_of_another_session_takes_over_a_failed_one() {
    let (a, b) = (image(8, 400), image(9, 500));
    let mut unit = Unit::boot(Flash::new());
    unit.begin_session(&a, 1);
    unit.data(&a, 0);
    unit.data(&a, MAX_CHUNK);
    // The first session's host died mid-transfer; a new run sends another image.
    assert_eq!(unit.begin_session(&b, 2).kind(), Kind::Ack);
    // Its chunks start at 0 again: nothing of the first session's image is kept.
    nak(unit.data(&b, MAX_CHUNK), Reason::OutOfOrder);
    unit.send_all(&b);
    assert_eq!(unit.send(Kind::Commit, 3, &[]).reason(), Reason::Ok);
    assert_eq!(booted(&mut unit.flash).unwrap().2, b);
}

#[test]
fn a_new_session_with_the_same_image_starts_over_and_a_repeat_does_not() {
    let a = image(8, 400);
    let mut unit = Unit::boot(Flash::new());
    unit.begin_session(&a, 7);
    unit.data(&a, 0);
    // A repeat of session 7's BEGIN (its ACK was lost) keeps the chunk written.
    assert_eq!(unit.begin_session(&a, 7).kind(), Kind::Ack);
    assert_eq!(unit.data(&a, MAX_CHUNK).kind(), Kind::Ack);
    // Session 8 with the same image begins the slot again.
    assert_eq!(unit.begin_session(&a, 8).kind(), Kind::Ack);
    let reply = unit.data(&a, 2 * MAX_CHUNK);
    nak(reply, Reason::OutOfOrder);
    assert_eq!(expected_offset(reply), 0);
}

#[test]
fn abort_ends_a_session_and_keeps_the_active_slot() {
    let (old, new) = (image(3, 400), image(4, 500));
    let mut unit = unit_with(&old);
    unit.begin(&new);
    unit.data(&new, 0);
    assert_eq!(unit.send(Kind::Abort, 5, &[]).kind(), Kind::Ack);
    nak(unit.data(&new, MAX_CHUNK), Reason::NotStarted);
    nak(unit.send(Kind::Commit, 3, &[]), Reason::NotStarted);
    assert_eq!(booted(&mut unit.flash), Some((SlotId::A, 1, old)));
    // The sender's ABORT: sent after BEGIN, it ends the update as aborted.
    let mut tx = Sender::new(&new, 9);
    let mut out = [0u8; MAX_FRAME];
    for _ in 0..2 {
        let n = tx.request(&mut out).unwrap();
        for r in unit.feed(&out[..n]) {
            tx.on_reply(&r.packet());
        }
    }
    assert!(tx.holds_session());
    tx.abort();
    let n = tx.request(&mut out).unwrap();
    assert_eq!(out[2], Kind::Abort as u8);
    for r in unit.feed(&out[..n]) {
        tx.on_reply(&r.packet());
    }
    assert_eq!(tx.status(), Status::Failed(Failure::Aborted));
    assert!(tx.request(&mut out).is_none());
    assert!(!unit.rx.is_receiving());
}

#[test]
fn a_refusal_before_the_commit_carries_the_validators_reason() {
    let new = image(5, 300);
    let mut unit = Unit::boot(Flash::new());
    unit.begin(&new);
    unit.send_all(&new);
    let mut out = [0u8; MAX_FRAME];
    let n = Packet {
        kind: Kind::Commit,
        seq: 3,
        payload: &[],
    }
    .encode(&mut out)
    .unwrap();
    let mut replies = Vec::new();
    for &b in &out[..n] {
        if let Some(p) = unit.decoder.push(b) {
            replies.push(unit.rx.handle(&mut unit.flash, &p, b"SN", |_, _, _| {
                Err(Reason::BadSignature)
            }));
        }
    }
    assert_eq!(
        (replies[0].kind(), replies[0].reason()),
        (Kind::Result, Reason::BadSignature)
    );
    assert!(booted(&mut unit.flash).is_none());
}

#[test]
fn a_commit_before_all_data_names_the_missing_offset() {
    let new = image(10, 800);
    let mut unit = Unit::boot(Flash::new());
    unit.begin(&new);
    unit.data(&new, 0);
    let reply = unit.send(Kind::Commit, 3, &[]);
    nak(reply, Reason::Incomplete);
    assert_eq!(expected_offset(reply), MAX_CHUNK as u32);
    assert!(booted(&mut unit.flash).is_none());
    nak(unit.send(Kind::Data, 6, &[0; 3]), Reason::Malformed);
}

#[test]
fn data_or_commit_without_begin_is_refused() {
    let mut unit = Unit::boot(Flash::new());
    nak(unit.data(&image(1, 100), 0), Reason::NotStarted);
    nak(unit.send(Kind::Commit, 3, &[]), Reason::NotStarted);
}

#[test]
fn an_image_that_fails_validation_or_its_crc_leaves_the_active_slot_untouched() {
    let old = image(11, 400);
    let mut unit = unit_with(&old);
    let slot_a = unit.flash.bytes()[..SECTOR].to_vec();
    // Well transported (its CRC is right) but not an image.
    let junk = vec![0x5Au8; 1000];
    unit.begin(&junk);
    unit.send_all(&junk);
    let result = unit.send(Kind::Commit, 3, &[]);
    assert_eq!(
        (result.kind(), result.reason()),
        (Kind::Result, Reason::Invalid)
    );
    assert_eq!(&unit.flash.bytes()[..SECTOR], &slot_a[..]);
    assert_eq!(booted(&mut unit.flash), Some((SlotId::A, 1, old.clone())));
    // An image whose bytes do not have the announced CRC.
    let new = image(12, 400);
    let mut p = (new.len() as u32).to_le_bytes().to_vec();
    p.extend_from_slice(&(tcomp_core::blob::crc32(&new) ^ 1).to_le_bytes());
    p.extend_from_slice(&1u32.to_le_bytes());
    assert_eq!(unit.send(Kind::Begin, 1, &p).kind(), Kind::Ack);
    unit.send_all(&new);
    assert_eq!(unit.send(Kind::Commit, 3, &[]).reason(), Reason::Crc);
    assert_eq!(booted(&mut unit.flash), Some((SlotId::A, 1, old)));
}

/// The sender over a link that drops, duplicates and corrupts frames (a fixed pattern), with the
/// unit's output frames interleaved: it ends committed, and the unit boots the new image.
#[test]
fn the_sender_recovers_from_a_lossy_link_carrying_output_frames() {
    let (old, new) = (image(13, 500), image(14, 1200));
    let mut unit = unit_with(&old);
    let mut tx = Sender::new(&new, 1);
    let mut host = Decoder::new();
    let mut out = [0u8; MAX_FRAME];
    let mut sequence = 0u32;
    let mut outputs = tcomp_core::frame::Decoder::new();
    for round in 0..400u32 {
        let Some(n) = tx.request(&mut out) else { break };
        let mut wire = out[..n].to_vec();
        match round % 7 {
            2 => wire.clear(),                 // lost request
            4 => wire[n / 2] ^= 0x01,          // corrupt request
            5 => wire.extend_from_within(..n), // duplicated request
            _ => {}
        }
        let mut back = Vec::new();
        for r in unit.feed(&wire) {
            let mut buf = [0u8; MAX_FRAME];
            let m = r.packet().encode(&mut buf).unwrap();
            // The unit's output frame goes out between replies.
            let frame = Frame::new(
                sequence,
                0,
                200,
                &[ChannelOutput {
                    value: 1.0,
                    status: 0,
                }],
            );
            sequence += 1;
            let mut f = [0u8; 64];
            let k = frame.encode(&mut f).unwrap();
            back.extend_from_slice(&f[..k]);
            if round % 11 != 3 {
                back.extend_from_slice(&buf[..m]); // else: the reply is lost
            }
        }
        let mut got = false;
        for &b in &back {
            outputs.feed(&[b], |_| {});
            if let Some(p) = host.push(b) {
                tx.on_reply(&p);
                got = true;
            }
        }
        if !got {
            tx.on_timeout();
        }
    }
    assert!(
        matches!(
            tx.status(),
            Status::Done {
                slot: SlotId::B,
                generation: 2
            }
        ),
        "{:?}",
        tx.status()
    );
    assert!(tx.repeats() > 0);
    assert_eq!(outputs.stats().frames, u64::from(sequence));
    assert_eq!(outputs.stats().lost, 0);
    assert_eq!(booted(&mut unit.flash), Some((SlotId::B, 2, new)));
}

#[test]
fn a_silent_unit_times_the_sender_out() {
    let img = image(1, 100);
    let mut tx = Sender::new(&img, 1);
    for _ in 0..=tcomp_core::update::sender::MAX_RETRIES {
        assert!(matches!(tx.status(), Status::Running { .. }));
        tx.on_timeout();
    }
    assert_eq!(tx.status(), Status::Failed(Failure::Timeout));
}

#[test]
fn the_streaming_crc_and_the_header_agree_with_the_core() {
    let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7) as u8).collect();
    let mut crc = Crc32::new();
    for part in bytes.chunks(37) {
        crc.update(part);
    }
    assert_eq!(crc.finish(), tcomp_core::blob::crc32(&bytes));
    let h = Header {
        generation: 7,
        length: 1234,
        payload_crc: 0xDEAD_BEEF,
    };
    let mut raw = [0xFFu8; 24];
    raw[..20].copy_from_slice(&h.encode());
    assert_eq!(Header::decode(&raw), Some((h, 0xFFFF_FFFF)));
    raw[5] ^= 1;
    assert_eq!(Header::decode(&raw), None);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Any bytes: no panic, and every packet decoded re-encodes to bytes that were fed.
    #[test]
    fn the_decoder_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..800)) {
        let mut d = Decoder::new();
        for b in bytes {
            if let Some(p) = d.push(b) {
                let mut out = [0u8; MAX_FRAME];
                prop_assert!(p.encode(&mut out).is_some());
            }
        }
    }

    /// A frame after any garbage is found, with its fields intact.
    #[test]
    fn a_frame_after_garbage_decodes(
        garbage in proptest::collection::vec(any::<u8>(), 0..300),
        payload in proptest::collection::vec(any::<u8>(), 0..=tcomp_core::update::wire::MAX_PAYLOAD),
        seq in any::<u16>(),
    ) {
        let mut out = [0u8; MAX_FRAME];
        let n = Packet { kind: Kind::Data, seq, payload: &payload }.encode(&mut out).unwrap();
        let mut d = Decoder::new();
        let mut found = Vec::new();
        for &b in garbage.iter().chain(&out[..n]) {
            if let Some(p) = d.push(b) {
                found.push((p.kind, p.seq, p.payload.to_vec()));
            }
            while let Some(p) = d.poll() {
                found.push((p.kind, p.seq, p.payload.to_vec()));
            }
        }
        prop_assert_eq!(found.last(), Some(&(Kind::Data, seq, payload)));
    }
}

/// The longest frame (a whole DATA chunk) decodes; a header promising a longer payload is no
/// frame start and a request with a corrupt CRC costs that request only: the good one after
/// both is found, and every byte before it is counted as skipped.
#[test]
fn the_longest_frame_decodes_after_a_longer_header_and_a_corrupt_frame() {
    use tcomp_core::update::wire::{MAX_PAYLOAD, SYNC};
    let payload = [0x5Au8; MAX_PAYLOAD];
    let mut good = [0u8; MAX_FRAME];
    let packet = Packet {
        kind: Kind::Data,
        seq: 9,
        payload: &payload,
    };
    assert_eq!(packet.encode(&mut good), Some(MAX_FRAME));
    let mut bad = good;
    bad[20] ^= 0x04;
    let mut stream = vec![SYNC[0], SYNC[1], Kind::Data as u8, 0, 0];
    stream.extend(((MAX_PAYLOAD + 1) as u16).to_le_bytes());
    stream.extend(bad);
    stream.extend(good);
    let mut d = Decoder::new();
    let mut found = Vec::new();
    for b in stream {
        if let Some(p) = d.push(b) {
            found.push((p.kind, p.seq, p.payload.to_vec()));
        }
        while let Some(p) = d.poll() {
            found.push((p.kind, p.seq, p.payload.to_vec()));
        }
    }
    assert_eq!(found, [(Kind::Data, 9, payload.to_vec())]);
    assert_eq!(d.skipped() as usize, 7 + MAX_FRAME);
}

/// A flash that fails mid-update (here: the power model's cut, seen by the receiver as an error)
/// is reported as a NAK, and the next BEGIN starts over on the same inactive slot.
#[test]
fn a_flash_error_is_reported_and_the_update_can_start_again() {
    let (old, new) = (image(15, 400), image(16, 600));
    let mut unit = unit_with(&old);
    unit.flash.plan(tcomp_core::slots::sim::Cut::After(20));
    assert_eq!(unit.begin(&new).kind(), Kind::Ack);
    nak(unit.data(&new, 0), Reason::Flash);
    nak(unit.data(&new, MAX_CHUNK), Reason::NotStarted);
    unit.flash.power_on();
    assert_eq!(unit.begin(&new).kind(), Kind::Ack);
    unit.send_all(&new);
    assert_eq!(unit.send(Kind::Commit, 3, &[]).reason(), Reason::Ok);
    assert_eq!(booted(&mut unit.flash), Some((SlotId::B, 2, new)));
}
