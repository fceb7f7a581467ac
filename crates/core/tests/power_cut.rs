//! The power-loss proof: a full update over the protocol and the boots that follow it — the trial
//! boot that programs the new slot's trial word, the confirm, and the next boot's erase of the old
//! slot (or, when the trial never confirms, the rollback and the erase of the failed slot) — on a
//! NOR flash model with the STM32F407's geometry for the two slots (sectors 10 and 11, 128 KiB
//! each, 4-byte program words), cut after every single write step and torn in the middle of every
//! one. After each cut the next boot must run exactly the old image or exactly the new one, never
//! a mix and never nothing (when there was an old one); which one is fixed by where the cut fell;
//! and the old image's bytes must still be in flash until the new one is confirmed. `cargo xtask
//! ci` runs this test and reads its `POWER-CUT` line.
//!
//! The same proof runs for a unit that checks Ed25519 signatures (issue 26): at boot, before a
//! slot is chosen (so before its trial or confirm words count), and at COMMIT, before the commit
//! word; its `POWER-CUT-SIGNED` line adds an update signed by another key, which no cut can make
//! the unit run.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_core::image::sign::{self, BLOCK_LEN, KeyStore};
use tcomp_core::image::{Image, write_image};
use tcomp_core::slots::sim::{Cut, SimNor};
use tcomp_core::slots::{Layout, PAYLOAD_AT, SlotId, boot, confirm, select};
use tcomp_core::update::wire::{Decoder, MAX_FRAME};
use tcomp_core::update::{Failure, Reason, Receiver, Sender, Status};

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

/// What the unit accepts: a readable image, and with `keys` one signed by a key among them.
#[derive(Clone, Debug, Default)]
struct Unit {
    keys: Option<Vec<u8>>,
}

impl Unit {
    /// The unit's check of `[offset, offset + len)`: at boot (a slot that fails it is passed over)
    /// and at COMMIT (a payload that fails it is never committed).
    fn check(&self, flash: &Flash, offset: u32, len: u32) -> Result<(), Reason> {
        let (at, len) = (offset as usize, len as usize);
        let bytes = flash.bytes().get(at..at + len).ok_or(Reason::Invalid)?;
        Image::parse(bytes).map_err(|_| Reason::Invalid)?;
        match &self.keys {
            None => Ok(()),
            Some(keys) => sign::verify(bytes, KeyStore(keys))
                .map(|_| ())
                .map_err(|_| Reason::BadSignature),
        }
    }
}

/// A boot as the firmware runs it (its trial and erase work included): the payload it runs.
fn boot_run(flash: &mut Flash, unit: &Unit) -> Option<(SlotId, Vec<u8>)> {
    let b = boot(flash, &LAYOUT, None, |f, o, l| unit.check(f, o, l).is_ok()).ok()?;
    let active = b.active?;
    let at = active.payload(&LAYOUT) as usize;
    let len = active.header.length as usize;
    Some((active.slot, flash.bytes()[at..at + len].to_vec()))
}

/// Whether `image` lies whole in one of the slots' payloads.
fn holds(flash: &Flash, image: &[u8]) -> bool {
    [SlotId::A, SlotId::B].iter().any(|&s| {
        let at = (LAYOUT.base(s) + PAYLOAD_AT) as usize;
        flash.bytes().get(at..at + image.len()) == Some(image)
    })
}

/// One update as the unit runs it: boot selection, then every request of the host's sender
/// encoded, decoded by the unit's decoder and handled, until the update ends or the power fails.
fn update(flash: &mut Flash, image: &[u8], unit: &Unit) -> Status {
    let active = select(flash, &LAYOUT, |f, o, l| unit.check(f, o, l).is_ok()).unwrap();
    let mut rx = Receiver::new(LAYOUT, active);
    let mut tx = Sender::new(image, 1);
    let (mut unit_in, mut host_in) = (Decoder::new(), Decoder::new());
    let mut frame = [0u8; MAX_FRAME];
    while let Some(n) = tx.request(&mut frame) {
        let mut reply_bytes = Vec::new();
        for &b in &frame[..n] {
            if let Some(p) = unit_in.push(b) {
                let reply = rx.handle(flash, &p, b"SN-TEST", |f, o, l| unit.check(f, o, l));
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

/// An update's whole life: the transfer, the trial boot, the confirm (`confirmed`) or not, and the
/// boot after (which erases the old slot, or rolls back and erases the failed one). Stops where
/// the power fails. Returns the step count when the transfer ended (its commit word).
fn lifecycle(flash: &mut Flash, new: &[u8], confirmed: bool, unit: &Unit) -> u32 {
    let done = matches!(update(flash, new, unit), Status::Done { .. });
    let commit = flash.steps();
    if !done || flash.is_dead() {
        return commit;
    }
    let Some((slot, _)) = boot_run(flash, unit) else {
        return commit;
    };
    if flash.is_dead() {
        return commit;
    }
    if confirmed && confirm(flash, &LAYOUT, slot).is_err() {
        return commit;
    }
    let _ = boot_run(flash, unit);
    commit
}

#[derive(Default, Debug)]
struct Tally {
    cut_points: u32,
    old: u32,
    new: u32,
    empty: u32,
    mixed: u32,
}

/// Cuts an update of `before` to `new` (and its boots) after and in every step; returns the
/// number of steps. `confirmed`: whether the trial boot confirms the new image.
fn cut_everywhere(
    before: &Flash,
    old: Option<&[u8]>,
    new: &[u8],
    confirmed: bool,
    tally: &mut Tally,
    unit: &Unit,
) -> u32 {
    let mut probe = before.clone();
    probe.plan(Cut::After(u32::MAX));
    // The update's own steps end with the commit word; the lifecycle then programs the trial
    // word, the confirm word (if confirmed), and erases a sector at the boot after (unless it is
    // blank already).
    let commit = lifecycle(&mut probe, new, confirmed, unit);
    let steps = probe.steps();
    let trial = commit + 1;
    for k in 1..=steps {
        for cut in [Cut::After(k), Cut::Torn(k)] {
            let mut flash = before.clone();
            flash.plan(cut);
            lifecycle(&mut flash, new, confirmed, unit);
            flash.power_on();
            tally.cut_points += 1;
            // The old image is in flash, whole, until the confirm word is complete.
            let confirm_done = confirmed && (k > trial + 1 || cut == Cut::After(trial + 1));
            if let Some(old) = old
                && !confirm_done
            {
                assert!(
                    holds(&flash, old),
                    "{cut:?} of {steps}: the old image is gone"
                );
            }
            let booted = boot_run(&mut flash, unit).map(|(_, b)| b);
            match booted.as_deref() {
                Some(b) if Some(b) == old => tally.old += 1,
                Some(b) if b == new => tally.new += 1,
                None if old.is_none() => tally.empty += 1,
                _ => tally.mixed += 1,
            }
            // Where the cut fell fixes which image runs next: before the commit word is complete
            // the old one; with it complete and the trial word not yet begun, the new one (this
            // boot is its trial); with the trial begun and not confirmed, the old one again (the
            // rollback); once confirmed, the new one.
            let expect_new = if k < commit {
                false
            } else if k == commit {
                cut == Cut::After(commit)
            } else if !confirmed {
                false
            } else {
                confirm_done
            };
            let want = if expect_new { Some(new) } else { old };
            assert_eq!(
                booted.as_deref(),
                want,
                "{cut:?} of {steps} (commit {commit}, confirmed {confirmed})"
            );
            // Now and then, the unit retries after the cut and must end on the new image.
            if k % 97 == 0 {
                let mut retry = flash.clone();
                let _ = lifecycle(&mut retry, new, true, unit);
                assert_eq!(
                    boot_run(&mut retry, unit).map(|(_, b)| b).as_deref(),
                    Some(new)
                );
            }
        }
    }
    steps
}

#[test]
fn every_power_cut_boots_the_old_or_the_new_image() {
    let (one, two, three) = (image(1), image(2), image(3));
    let mut tally = Tally::default();
    let unit = Unit::default();

    // A first update onto erased flash: a cut leaves no models or the new ones.
    let erased = Box::new(Flash::new());
    let first_steps = cut_everywhere(&erased, None, &one, true, &mut tally, &unit);

    // A second update after the first, confirmed (slot A active, B written) …
    let mut with_one = erased.clone();
    let _ = lifecycle(&mut with_one, &one, true, &unit);
    assert_eq!(
        boot_run(&mut with_one, &unit),
        Some((SlotId::A, one.clone()))
    );
    let second_steps = cut_everywhere(&with_one, Some(&one), &two, true, &mut tally, &unit);

    // … its trial never confirmed: every cut, and the end, leaves the first image running …
    let failed_steps = cut_everywhere(&with_one, Some(&one), &two, false, &mut tally, &unit);
    let mut rolled = with_one.clone();
    let _ = lifecycle(&mut rolled, &two, false, &unit);
    assert_eq!(boot_run(&mut rolled, &unit), Some((SlotId::A, one.clone())));

    // … and a third (B active, A — holding the first image — erased at boot and rewritten).
    let mut with_two = with_one.clone();
    let _ = lifecycle(&mut with_two, &two, true, &unit);
    assert_eq!(
        boot_run(&mut with_two, &unit),
        Some((SlotId::B, two.clone()))
    );
    let third_steps = cut_everywhere(&with_two, Some(&two), &three, true, &mut tally, &unit);

    println!(
        "POWER-CUT cut_points={} steps_per_update={},{},{},{} old={} new={} empty={} mixed={}",
        tally.cut_points,
        first_steps,
        second_steps,
        failed_steps,
        third_steps,
        tally.old,
        tally.new,
        tally.empty,
        tally.mixed
    );
    // Every step of each update, cut after it and torn within it.
    assert_eq!(
        tally.cut_points,
        2 * (first_steps + second_steps + failed_steps + third_steps)
    );
    // One sector erase, five header words, the payload's words, the commit word; then the trial
    // word, the confirm word and the boot's erase of the old slot.
    assert_eq!(second_steps as usize, 1 + 5 + two.len().div_ceil(4) + 1 + 3);
    assert_eq!(tally.mixed, 0);
    assert!(tally.old > 0 && tally.new > 0 && tally.empty > 0);
}

/// A secret key made now from the operating system's generator (no key lives in the repository).
fn fresh_key() -> [u8; 32] {
    use std::io::Read;
    let mut k = [0u8; 32];
    std::fs::File::open("/dev/urandom")
        .unwrap()
        .read_exact(&mut k)
        .unwrap();
    k
}

/// `image` with its Ed25519 signature block by `secret`.
fn signed(image: &[u8], secret: &[u8; 32]) -> Vec<u8> {
    let mut buf = image.to_vec();
    buf.resize(image.len() + BLOCK_LEN, 0);
    sign::sign(&mut buf, secret).unwrap();
    buf
}

/// With signature checks at boot (before a slot, its trial or its confirm is considered) and at
/// COMMIT (before the commit word): every cut of a signed update's whole life — transfer, trial
/// boot, confirm or not, the boot after — boots exactly the old or the new image, as the unsigned
/// proof says; an update signed by another key is refused at COMMIT and, cut anywhere (the
/// boot's erase of its uncommitted slot included), never runs: the old image does.
#[test]
fn every_power_cut_of_a_signed_update_boots_the_old_or_the_new_image() {
    let (station, rogue) = (fresh_key(), fresh_key());
    let unit = Unit {
        keys: Some(sign::public_key(&station).to_vec()),
    };
    let (one, two, bad) = (
        signed(&image(4), &station),
        signed(&image(5), &station),
        signed(&image(6), &rogue),
    );
    let mut tally = Tally::default();
    let mut with_one = Box::new(Flash::new());
    let _ = lifecycle(&mut with_one, &one, true, &unit);
    assert_eq!(
        boot_run(&mut with_one, &unit),
        Some((SlotId::A, one.clone()))
    );
    let confirmed_steps = cut_everywhere(&with_one, Some(&one), &two, true, &mut tally, &unit);
    let failed_steps = cut_everywhere(&with_one, Some(&one), &two, false, &mut tally, &unit);

    // The rogue image: refused at COMMIT with its reason; then every cut of that session and of
    // the boot after it (which erases the uncommitted slot) runs the old image.
    let mut probe = with_one.clone();
    assert_eq!(
        update(&mut probe, &bad, &unit),
        Status::Failed(Failure::Unit(Reason::BadSignature))
    );
    assert_eq!(boot_run(&mut probe, &unit), Some((SlotId::A, one.clone())));
    let rogue_steps = probe.steps();
    let mut rogue_old = 0u32;
    for k in 1..=rogue_steps {
        for cut in [Cut::After(k), Cut::Torn(k)] {
            let mut flash = with_one.clone();
            flash.plan(cut);
            let _ = update(&mut flash, &bad, &unit);
            let _ = boot_run(&mut flash, &unit);
            flash.power_on();
            assert_eq!(
                boot_run(&mut flash, &unit),
                Some((SlotId::A, one.clone())),
                "{cut:?} of the rogue update's {rogue_steps} steps"
            );
            rogue_old += 1;
        }
    }
    println!(
        "POWER-CUT-SIGNED cut_points={} steps_per_update={},{} old={} new={} mixed={} rogue_cut_points={} rogue_booted=0",
        tally.cut_points,
        confirmed_steps,
        failed_steps,
        tally.old,
        tally.new,
        tally.mixed,
        rogue_old
    );
    assert_eq!(tally.cut_points, 2 * (confirmed_steps + failed_steps));
    assert_eq!(tally.mixed, 0);
    assert!(tally.old > 0 && tally.new > 0);
}
