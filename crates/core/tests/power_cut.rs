//! The power-loss proof: a full update over the protocol and the boots that follow it — the trial
//! boot that programs the new slot's trial word, the confirm, and the next boot's erase of the old
//! slot (or, when the trial never confirms, the rollback and the erase of the failed slot) — on a
//! NOR flash model with the STM32F407's geometry for the two slots (sectors 10 and 11, 128 KiB
//! each, 4-byte program words), cut after every single write step and torn in the middle of every
//! one. After each cut the next boot must run exactly the old image or exactly the new one, never
//! a mix and never nothing (when there was an old one); which one is fixed by where the cut fell;
//! and the old image's bytes must still be in flash until the new one is confirmed. `cargo xtask
//! ci` runs this test and reads its `POWER-CUT` line.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_core::image::{Image, write_image};
use tcomp_core::slots::sim::{Cut, SimNor};
use tcomp_core::slots::{Layout, PAYLOAD_AT, SlotId, boot, confirm, select};
use tcomp_core::update::wire::{Decoder, MAX_FRAME};
use tcomp_core::update::{Receiver, Sender, Status};

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

/// A boot as the firmware runs it (its trial and erase work included): the payload it runs.
fn boot_run(flash: &mut Flash) -> Option<(SlotId, Vec<u8>)> {
    let b = boot(flash, &LAYOUT, None, validate).ok()?;
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
fn update(flash: &mut Flash, image: &[u8]) -> Status {
    let active = select(flash, &LAYOUT, validate).unwrap();
    let mut rx = Receiver::new(LAYOUT, active);
    let mut tx = Sender::new(image);
    let (mut unit_in, mut host_in) = (Decoder::new(), Decoder::new());
    let mut frame = [0u8; MAX_FRAME];
    while let Some(n) = tx.request(&mut frame) {
        let mut reply_bytes = Vec::new();
        for &b in &frame[..n] {
            if let Some(p) = unit_in.push(b) {
                let reply = rx.handle(flash, &p, b"SN-TEST", validate);
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
fn lifecycle(flash: &mut Flash, new: &[u8], confirmed: bool) -> u32 {
    let done = matches!(update(flash, new), Status::Done { .. });
    let commit = flash.steps();
    if !done || flash.is_dead() {
        return commit;
    }
    let Some((slot, _)) = boot_run(flash) else {
        return commit;
    };
    if flash.is_dead() {
        return commit;
    }
    if confirmed && confirm(flash, &LAYOUT, slot).is_err() {
        return commit;
    }
    let _ = boot_run(flash);
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
) -> u32 {
    let mut probe = before.clone();
    probe.plan(Cut::After(u32::MAX));
    // The update's own steps end with the commit word; the lifecycle then programs the trial
    // word, the confirm word (if confirmed), and erases a sector at the boot after (unless it is
    // blank already).
    let commit = lifecycle(&mut probe, new, confirmed);
    let steps = probe.steps();
    let trial = commit + 1;
    for k in 1..=steps {
        for cut in [Cut::After(k), Cut::Torn(k)] {
            let mut flash = before.clone();
            flash.plan(cut);
            lifecycle(&mut flash, new, confirmed);
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
            let booted = boot_run(&mut flash).map(|(_, b)| b);
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
                let _ = lifecycle(&mut retry, new, true);
                assert_eq!(boot_run(&mut retry).map(|(_, b)| b).as_deref(), Some(new));
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
    let first_steps = cut_everywhere(&erased, None, &one, true, &mut tally);

    // A second update after the first, confirmed (slot A active, B written) …
    let mut with_one = erased.clone();
    let _ = lifecycle(&mut with_one, &one, true);
    assert_eq!(boot_run(&mut with_one), Some((SlotId::A, one.clone())));
    let second_steps = cut_everywhere(&with_one, Some(&one), &two, true, &mut tally);

    // … its trial never confirmed: every cut, and the end, leaves the first image running …
    let failed_steps = cut_everywhere(&with_one, Some(&one), &two, false, &mut tally);
    let mut rolled = with_one.clone();
    let _ = lifecycle(&mut rolled, &two, false);
    assert_eq!(boot_run(&mut rolled), Some((SlotId::A, one.clone())));

    // … and a third (B active, A — holding the first image — erased at boot and rewritten).
    let mut with_two = with_one.clone();
    let _ = lifecycle(&mut with_two, &two, true);
    assert_eq!(boot_run(&mut with_two), Some((SlotId::B, two.clone())));
    let third_steps = cut_everywhere(&with_two, Some(&two), &three, true, &mut tally);

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
