//! The power-loss proof: a full update over the protocol, on a NOR flash model with the STM32F407's
//! geometry for the two slots (sectors 10 and 11, 128 KiB each, 4-byte program words), cut after
//! every single write step and torn in the middle of every one; after each cut the next boot must
//! run exactly the old image or exactly the new one, never a mix and never nothing (when there was
//! an old one). `cargo xtask ci` runs this test and reads its `POWER-CUT` line.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_core::image::{Image, write_image};
use tcomp_core::slots::sim::{Cut, SimNor};
use tcomp_core::slots::{Layout, SlotId, select};
use tcomp_core::update::wire::{Decoder, MAX_FRAME};
use tcomp_core::update::{Reason, Receiver, Sender, Status};

const SECTOR: usize = 128 * 1024;
type Flash = SimNor<{ 2 * SECTOR }, SECTOR>;
const LAYOUT: Layout = Layout {
    a: 0,
    b: SECTOR as u32,
    size: SECTOR as u32,
};

/// An image of six pseudo-random "blobs" (the image layer does not decode them) of odd lengths.
fn image(seed: u32) -> Vec<u8> {
    let mut x = seed | 1;
    let blobs: Vec<(u16, Vec<u8>)> = (0..6u16)
        .map(|id| {
            let len = 700 + 37 * usize::from(id) + seed as usize % 13;
            let bytes = (0..len)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    x as u8
                })
                .collect();
            (id, bytes)
        })
        .collect();
    let entries: Vec<(u16, &[u8])> = blobs.iter().map(|(i, b)| (*i, b.as_slice())).collect();
    let mut buf = vec![0u8; 16 * 1024];
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

/// What the next boot runs: the payload of the selected slot.
fn boot(flash: &mut Flash) -> Option<(SlotId, Vec<u8>)> {
    let active = select(flash, &LAYOUT, validate).unwrap()?;
    let at = active.payload(&LAYOUT) as usize;
    let len = active.header.length as usize;
    Some((active.slot, flash.bytes()[at..at + len].to_vec()))
}

/// One update as the unit runs it: boot selection, then every request of the host's sender
/// encoded, decoded by the unit's decoder and handled, until the update ends or the power fails.
fn update(flash: &mut Flash, image: &[u8]) -> Status {
    let active = select(flash, &LAYOUT, validate).unwrap();
    let mut rx = Receiver::new(LAYOUT, active);
    let mut tx = Sender::new(image, 1);
    let (mut unit_in, mut host_in) = (Decoder::new(), Decoder::new());
    let mut frame = [0u8; MAX_FRAME];
    while let Some(n) = tx.request(&mut frame) {
        let mut reply_bytes = Vec::new();
        for &b in &frame[..n] {
            if let Some(p) = unit_in.push(b) {
                let reply = rx.handle(flash, &p, b"SN-TEST", check);
                let mut out = [0u8; MAX_FRAME];
                let m = reply.packet().encode(&mut out).unwrap();
                reply_bytes.extend_from_slice(&out[..m]);
            }
        }
        if flash.is_dead() {
            break; // the unit is off: no reply, and nothing more happens
        }
        for &b in &reply_bytes {
            if let Some(p) = host_in.push(b) {
                tx.on_reply(&p);
            }
        }
    }
    tx.status()
}

#[derive(Default, Debug)]
struct Tally {
    cut_points: u32,
    old: u32,
    new: u32,
    empty: u32,
    mixed: u32,
}

/// Cuts `image`'s update of `before` after and in every step; returns the number of steps.
fn cut_everywhere(before: &Flash, old: Option<&[u8]>, new: &[u8], tally: &mut Tally) -> u32 {
    let mut probe = before.clone();
    probe.plan(Cut::After(u32::MAX));
    assert!(matches!(update(&mut probe, new), Status::Done { .. }));
    let steps = probe.steps();
    for k in 1..=steps {
        for cut in [Cut::After(k), Cut::Torn(k)] {
            let mut flash = before.clone();
            flash.plan(cut);
            let status = update(&mut flash, new);
            flash.power_on();
            tally.cut_points += 1;
            let booted = boot(&mut flash).map(|(_, b)| b);
            match booted.as_deref() {
                Some(b) if Some(b) == old => tally.old += 1,
                Some(b) if b == new => tally.new += 1,
                None if old.is_none() => tally.empty += 1,
                _ => tally.mixed += 1,
            }
            // The commit word is the last step: before it the old image boots, after it the new.
            if k < steps {
                assert_eq!(
                    booted.as_deref(),
                    old,
                    "{cut:?} of {steps}: not the old image"
                );
                assert!(!matches!(status, Status::Done { .. }));
            }
            if cut == Cut::After(steps) {
                assert_eq!(booted.as_deref(), Some(new), "a committed update must boot");
            }
            // Now and then, the unit retries after the cut and must end on the new image.
            if k % 97 == 0 {
                assert!(matches!(update(&mut flash, new), Status::Done { .. }));
                assert_eq!(boot(&mut flash).map(|(_, b)| b).as_deref(), Some(new));
            }
        }
    }
    steps
}

#[test]
fn every_power_cut_boots_the_old_or_the_new_image() {
    let (one, two, three) = (image(1), image(2), image(3));
    let mut tally = Tally::default();

    // A first update onto erased flash: a cut leaves no models or the new ones.
    let erased = Box::new(Flash::new());
    let first_steps = cut_everywhere(&erased, None, &one, &mut tally);

    // A second update after the first (slot A active, B written) …
    let mut with_one = erased.clone();
    assert!(matches!(
        update(&mut with_one, &one),
        Status::Done {
            slot: SlotId::A,
            generation: 1
        }
    ));
    let second_steps = cut_everywhere(&with_one, Some(&one), &two, &mut tally);

    // … and a third (B active, A — holding the first image — erased and rewritten).
    let mut with_two = with_one.clone();
    assert!(matches!(
        update(&mut with_two, &two),
        Status::Done {
            slot: SlotId::B,
            generation: 2
        }
    ));
    let third_steps = cut_everywhere(&with_two, Some(&two), &three, &mut tally);

    println!(
        "POWER-CUT cut_points={} steps_per_update={},{},{} old={} new={} empty={} mixed={}",
        tally.cut_points,
        first_steps,
        second_steps,
        third_steps,
        tally.old,
        tally.new,
        tally.empty,
        tally.mixed
    );
    // Every step of each update, cut after it and torn within it.
    assert_eq!(
        tally.cut_points,
        2 * (first_steps + second_steps + third_steps)
    );
    // One sector erase, five header words, the payload's words, the commit word.
    assert_eq!(second_steps as usize, 1 + 5 + two.len().div_ceil(4) + 1);
    assert_eq!(tally.mixed, 0);
    assert!(tally.old > 0 && tally.new > 0 && tally.empty > 0);
}

// --- The same proof with signature checks in the update path (issue 26) ---------------------
//
// Kept apart from the functions above (which the trial-boot work extends): a unit that verifies
// Ed25519 signatures at boot (before a slot is chosen) and at COMMIT (before the commit word).

mod signed {
    use super::*;
    use std::io::Read;
    use tcomp_core::image::sign::{self, BLOCK_LEN, KeyStore};

    /// A secret key made now from the operating system's generator.
    pub fn fresh_key() -> [u8; 32] {
        let mut k = [0u8; 32];
        std::fs::File::open("/dev/urandom")
            .unwrap()
            .read_exact(&mut k)
            .unwrap();
        k
    }

    pub fn signed(image: &[u8], secret: &[u8; 32]) -> Vec<u8> {
        let mut buf = image.to_vec();
        buf.resize(image.len() + BLOCK_LEN, 0);
        sign::sign(&mut buf, secret).unwrap();
        buf
    }

    /// The unit's check: the image reads and its signature verifies against `keys`.
    pub fn trusted(flash: &Flash, keys: &[u8], offset: u32, len: u32) -> Result<(), Reason> {
        let (at, len) = (offset as usize, len as usize);
        let bytes = flash.bytes().get(at..at + len).ok_or(Reason::Invalid)?;
        Image::parse(bytes).map_err(|_| Reason::Invalid)?;
        sign::verify(bytes, KeyStore(keys))
            .map(|_| ())
            .map_err(|_| Reason::BadSignature)
    }

    pub fn boot(flash: &mut Flash, keys: &[u8]) -> Option<Vec<u8>> {
        let snapshot = flash.clone();
        let active = select(flash, &LAYOUT, |_, o, l| trusted(&snapshot, keys, o, l).is_ok())
            .unwrap()?;
        let at = active.payload(&LAYOUT) as usize;
        Some(flash.bytes()[at..at + active.header.length as usize].to_vec())
    }

    pub fn update(flash: &mut Flash, image: &[u8], keys: &[u8]) -> Status {
        let snapshot = flash.clone();
        let active = select(flash, &LAYOUT, |_, o, l| trusted(&snapshot, keys, o, l).is_ok())
            .unwrap();
        let mut rx = Receiver::new(LAYOUT, active);
        let mut tx = Sender::new(image, 7);
        let (mut unit_in, mut host_in) = (Decoder::new(), Decoder::new());
        let mut frame = [0u8; MAX_FRAME];
        while let Some(n) = tx.request(&mut frame) {
            let mut reply_bytes = Vec::new();
            for &b in &frame[..n] {
                if let Some(p) = unit_in.push(b) {
                    let reply = rx.handle(flash, &p, b"SN-TEST", |f, o, l| {
                        trusted(f, keys, o, l)
                    });
                    let mut out = [0u8; MAX_FRAME];
                    let m = reply.packet().encode(&mut out).unwrap();
                    reply_bytes.extend_from_slice(&out[..m]);
                }
            }
            if flash.is_dead() {
                break;
            }
            for &b in &reply_bytes {
                if let Some(p) = host_in.push(b) {
                    tx.on_reply(&p);
                }
            }
        }
        tx.status()
    }
}

/// With signature checks at boot and at COMMIT: a signed update cut after and inside every write
/// step boots exactly the old or exactly the new image; an update signed by another key, cut
/// anywhere or completed, never boots (the old image does).
#[test]
fn every_power_cut_of_a_signed_update_boots_the_old_or_the_new_image() {
    let (station, rogue) = (signed::fresh_key(), signed::fresh_key());
    let keys = tcomp_core::image::sign::public_key(&station).to_vec();
    let old = signed::signed(&image(4), &station);
    let new = signed::signed(&image(5), &station);
    let bad = signed::signed(&image(6), &rogue);
    let mut before = Box::new(Flash::new());
    assert!(matches!(
        signed::update(&mut before, &old, &keys),
        Status::Done { .. }
    ));
    assert_eq!(signed::boot(&mut before, &keys).as_deref(), Some(&old[..]));

    // The rogue image: refused at COMMIT, so no cut point can make it boot.
    let mut probe = before.clone();
    assert_eq!(
        signed::update(&mut probe, &bad, &keys),
        Status::Failed(tcomp_core::update::Failure::Unit(Reason::BadSignature))
    );
    assert_eq!(signed::boot(&mut probe, &keys).as_deref(), Some(&old[..]));

    let mut probe = before.clone();
    probe.plan(Cut::After(u32::MAX));
    assert!(matches!(
        signed::update(&mut probe, &new, &keys),
        Status::Done { .. }
    ));
    let steps = probe.steps();
    let (mut olds, mut news) = (0u32, 0u32);
    for k in 1..=steps {
        for cut in [Cut::After(k), Cut::Torn(k)] {
            for (image, may_boot) in [(&new, true), (&bad, false)] {
                let mut flash = before.clone();
                flash.plan(cut);
                signed::update(&mut flash, image, &keys);
                flash.power_on();
                let booted = signed::boot(&mut flash, &keys);
                match booted.as_deref() {
                    Some(b) if b == &old[..] => olds += 1,
                    Some(b) if may_boot && b == &new[..] => news += 1,
                    other => panic!(
                        "{cut:?}: booted {:?} bytes, neither the old nor the new signed image",
                        other.map(<[u8]>::len)
                    ),
                }
            }
        }
    }
    println!(
        "POWER-CUT-SIGNED cut_points={} steps={steps} old={olds} new={news} mixed=0 rogue_booted=0",
        4 * steps
    );
    assert!(news >= 1 && olds > 0);
}
