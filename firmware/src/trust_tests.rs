//! The unit's trust check on real version-2 images of the shipped IMU6 description, with keys
//! made at test time: accepted when signed by a provisioned key for this unit; every single-bit
//! flip, another key, another unit's signed image, an unsigned image refused; a development build
//! runs unsigned images and says so. Then the boot's choice and the update task with it: a slot
//! that fails the check is passed over (the boot report says why when nothing runs), and an
//! update signed by another key is refused at COMMIT while the old image stays the one that boots.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

extern crate std;
use crate::boot::report;
use crate::slots::{Choice, MappedFlash, QEMU_LAYOUT, Source, boot, choose, confirm};
use crate::test_flash::{Flash, Sim};
use crate::trust::{Signer, Trust};
use crate::update::{MAX_REPLY, UpdateTask};
use embedded_storage::nor_flash::NorFlash;
use std::io::Read;
use std::vec;
use std::vec::Vec;
use tcomp_board_description::Board;
use tcomp_core::frame::{DEVELOPMENT, image_state, update_state};
use tcomp_core::image::sign::{self, BLOCK_LEN, KeyId};
use tcomp_core::image::{Entry, ImageSpec};
use tcomp_core::slots::{SlotId, Trial, trial};
use tcomp_core::update::wire::{Decoder, MAX_FRAME};
use tcomp_core::update::{Failure, Reason, Sender, Status};

const UNIT: u64 = 0x7C0_0001;

fn fresh_key() -> [u8; 32] {
    let mut k = [0u8; 32];
    std::fs::File::open("/dev/urandom")
        .unwrap()
        .read_exact(&mut k)
        .unwrap();
    k
}

/// A version-2 image of `descriptions/imu6-rlg-qma.toml` for unit `serial` (blobs are not
/// decoded by the trust check: three small byte strings stand in).
fn image(serial: u64, seed: u8) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("descriptions")
        .join("imu6-rlg-qma.toml");
    let board = Board::load(&path).unwrap();
    let (therms, rows) = (board.thermometer_rows(), board.channel_rows());
    let blobs: Vec<Vec<u8>> = (0..3u8)
        .map(|i| (0..200u32).map(|j| (j as u8) ^ i ^ seed).collect())
        .collect();
    let entries: Vec<Entry<'_>> = blobs
        .iter()
        .enumerate()
        .map(|(k, b)| Entry {
            channel: k as u16,
            blob: b,
            provenance: Default::default(),
        })
        .collect();
    let spec = ImageSpec {
        serial,
        created: 0,
        tool: "test",
        thermometers: &therms,
        channels: &rows,
        entries: &entries,
    };
    let mut out = vec![0u8; spec.image_len().unwrap()];
    spec.write(&mut out).unwrap();
    out
}

fn signed(image: &[u8], secret: &[u8; 32]) -> Vec<u8> {
    let mut buf = image.to_vec();
    buf.resize(image.len() + BLOCK_LEN, 0xFF);
    sign::sign(&mut buf, secret).unwrap();
    buf
}

fn production(keys: &[u8]) -> Trust<'_> {
    Trust {
        development: false,
        ..Trust::new(UNIT, keys)
    }
}

#[test]
fn a_signed_image_for_this_unit_is_accepted_and_names_its_key() {
    let station = fresh_key();
    let public = sign::public_key(&station);
    let s = signed(&image(UNIT, 1), &station);
    let trust = production(&public);
    assert_eq!(trust.check(&s), Ok(Signer::Key(KeyId::of(&public))));
    assert_eq!(trust.check_payload(&s), Ok(Signer::Key(KeyId::of(&public))));
    // A payload with a byte past the signature block: not every byte is covered.
    let mut longer = s.clone();
    longer.push(0);
    assert_eq!(trust.check_payload(&longer), Err(Reason::Invalid));
}

#[test]
fn every_single_bit_flip_of_a_signed_image_is_refused() {
    let station = fresh_key();
    let public = sign::public_key(&station);
    let trust = production(&public);
    let s = signed(&image(UNIT, 2), &station);
    let mut flipped = s.clone();
    for byte in 0..s.len() {
        for bit in 0..8 {
            flipped[byte] ^= 1 << bit;
            assert!(
                trust.check_payload(&flipped).is_err(),
                "bit {bit} of byte {byte} flipped was accepted"
            );
            flipped[byte] ^= 1 << bit;
        }
    }
    assert!(trust.check_payload(&flipped).is_ok());
}

#[test]
fn another_key_another_unit_and_no_signature_are_refused() {
    let (station, rogue) = (fresh_key(), fresh_key());
    let public = sign::public_key(&station);
    let trust = production(&public);
    assert_eq!(
        trust.check(&signed(&image(UNIT, 3), &rogue)),
        Err(Reason::UnknownKey)
    );
    // Signed by the station, but for another unit (a calibration moved by editing the serial
    // would need a new signature; one made for the other unit is refused here).
    assert_eq!(
        trust.check(&signed(&image(UNIT + 1, 3), &station)),
        Err(Reason::OtherUnit)
    );
    assert_eq!(trust.check(&image(UNIT, 3)), Err(Reason::Unsigned));
    // A development build runs the unsigned image, but a signature that is there must verify.
    let dev = Trust {
        development: true,
        ..Trust::new(UNIT, &public)
    };
    assert_eq!(dev.check_payload(&image(UNIT, 3)), Ok(Signer::Unsigned));
    let mut bad = signed(&image(UNIT, 3), &station);
    let n = bad.len();
    bad[n - 1] ^= 1;
    assert_eq!(dev.check(&bad), Err(Reason::BadSignature));
    assert_eq!(
        dev.check(&signed(&image(UNIT, 3), &rogue)),
        Err(Reason::UnknownKey)
    );
}

/// An update of `image` through the update task, validated by `trust` at COMMIT.
fn update(flash: &mut Flash, task: &mut UpdateTask, image: &[u8], trust: &Trust<'_>) -> Status {
    let mut tx = Sender::new(image, 3);
    let mut host = Decoder::new();
    let mut frame = [0u8; MAX_FRAME];
    while let Some(n) = tx.request(&mut frame) {
        for &b in &frame[..n] {
            let mut reply = [0u8; MAX_REPLY];
            let validate = |f: &mut Flash, off: u32, len: u32| {
                f.mapped(off, len)
                    .map_or(Err(Reason::Flash), |b| trust.check_payload(b).map(|_| ()))
            };
            if let Some(m) = task.push(b, flash, b"SN", validate, &mut reply) {
                for &r in &reply[..m] {
                    if let Some(p) = host.push(r) {
                        tx.on_reply(&p);
                    }
                }
            }
        }
    }
    tx.status()
}

/// The bytes a choice runs.
fn running(flash: &Flash, c: &Choice) -> Vec<u8> {
    c.image
        .and_then(|(off, len)| flash.mapped(off, len))
        .unwrap_or(&[])
        .to_vec()
}

/// The boot report of a choice (no channel table: the image fields and the trust fields).
fn report_of(flash: &Flash, c: &Choice) -> tcomp_core::frame::BootReport {
    report(
        &running(flash, c),
        c.signer,
        c.refused,
        UNIT,
        &[],
        &[],
        false,
    )
}

#[test]
fn the_boot_and_the_update_run_only_trusted_images() {
    let (station, rogue) = (fresh_key(), fresh_key());
    let public = sign::public_key(&station);
    let trust = production(&public);
    let accept = |b: &[u8]| trust.check(b);
    let old = signed(&image(UNIT, 4), &station);
    let mut flash = Flash(Sim::new());
    let mut task = UpdateTask::new(QEMU_LAYOUT, choose(&mut flash, &QEMU_LAYOUT, accept).active);
    assert!(matches!(
        update(&mut flash, &mut task, &old, &trust),
        Status::Done { .. }
    ));
    assert_eq!(task.outcome(), (update_state::COMMITTED, 0));

    // Booted: the signed image runs on trial, and the report names its signer; confirmed.
    let c = boot(&mut flash, &QEMU_LAYOUT, accept).unwrap();
    assert_eq!((c.source, c.trial), (Source::Slot(SlotId::A, 1), true));
    assert_eq!(c.signer, Some(Signer::Key(KeyId::of(&public))));
    let r = report_of(&flash, &c);
    assert_eq!(r.signer, KeyId::of(&public).as_u64());
    assert_eq!(r.flags & DEVELOPMENT, 0);
    confirm(&mut flash, &QEMU_LAYOUT, SlotId::A).unwrap();
    let c = boot(&mut flash, &QEMU_LAYOUT, accept).unwrap();
    assert_eq!((c.source, c.trial), (Source::Slot(SlotId::A, 1), false));

    // An update signed by another key: refused at COMMIT, the reason kept for the report; the
    // old image boots, confirmed, and the boot erases the refused session's slot.
    let mut task = UpdateTask::new(QEMU_LAYOUT, c.active);
    let rogue_image = signed(&image(UNIT, 5), &rogue);
    assert_eq!(
        update(&mut flash, &mut task, &rogue_image, &trust),
        Status::Failed(Failure::Unit(Reason::UnknownKey))
    );
    assert_eq!(
        task.outcome(),
        (update_state::REFUSED, Reason::UnknownKey as u8)
    );
    let c = boot(&mut flash, &QEMU_LAYOUT, accept).unwrap();
    assert_eq!((c.source, c.trial), (Source::Slot(SlotId::A, 1), false));
    assert_eq!(running(&flash, &c), old);
    assert!(flash.0.bytes()[32 * 1024..].iter().all(|&b| b == 0xFF));

    // A unit provisioned with no key runs nothing, and its report says why.
    let none = production(&[0xFF; 128]);
    let c = choose(&mut flash, &QEMU_LAYOUT, |b| none.check(b));
    assert_eq!(c.source, Source::None);
    assert_eq!(report_of(&flash, &c).image_state, image_state::UNKNOWN_KEY);
}

/// The trust check comes before the trial scheme: a committed slot whose signature no longer
/// verifies (its key revoked) is passed over like a corrupt one, never put on trial or
/// confirmed, and the unit runs the confirmed image before it.
#[test]
fn a_slot_refused_at_boot_is_never_put_on_trial() {
    let (station, second) = (fresh_key(), fresh_key());
    let mut keys = sign::public_key(&station).to_vec();
    keys.extend_from_slice(&sign::public_key(&second));
    let both = production(&keys);
    let mut flash = Flash(Sim::new());
    let mut task = UpdateTask::new(QEMU_LAYOUT, None);
    let one = signed(&image(UNIT, 7), &station);
    assert!(matches!(
        update(&mut flash, &mut task, &one, &both),
        Status::Done { .. }
    ));
    let c = boot(&mut flash, &QEMU_LAYOUT, |b| both.check(b)).unwrap();
    confirm(&mut flash, &QEMU_LAYOUT, SlotId::A).unwrap();
    let c2 = boot(&mut flash, &QEMU_LAYOUT, |b| both.check(b)).unwrap();
    assert_eq!((c.trial, c2.trial), (true, false));
    let mut task = UpdateTask::new(QEMU_LAYOUT, c2.active);
    let two = signed(&image(UNIT, 8), &second);
    assert!(matches!(
        update(&mut flash, &mut task, &two, &both),
        Status::Done { .. }
    ));
    // The second key is revoked (its block zeroed) before slot B's first boot.
    keys[32..].fill(0);
    let revoked = production(&keys);
    let c = boot(&mut flash, &QEMU_LAYOUT, |b| revoked.check(b)).unwrap();
    assert_eq!((c.source, c.trial), (Source::Slot(SlotId::A, 1), false));
    assert_eq!(c.refused, Some(Reason::UnknownKey));
    assert_eq!(running(&flash, &c), one);
    assert_eq!(
        trial(&mut flash, &QEMU_LAYOUT, SlotId::B).unwrap(),
        Trial::Fresh,
        "a refused slot got a trial word"
    );
}

/// A bare image a probe wrote at slot A is checked like a slot's; refused, it does not run but is
/// kept (an update writes slot B).
#[test]
fn a_probes_unsigned_image_does_not_run_in_a_production_build() {
    let station = fresh_key();
    let public = sign::public_key(&station);
    let trust = production(&public);
    let mut flash = Flash(Sim::new());
    let mut bare = image(UNIT, 6);
    bare.resize(bare.len().next_multiple_of(4), 0);
    flash.write(0, &bare).unwrap();
    let c = boot(&mut flash, &QEMU_LAYOUT, |b| trust.check(b)).unwrap();
    assert_eq!(
        (c.source, c.refused),
        (Source::None, Some(Reason::Unsigned))
    );
    assert_eq!(c.active.map(|a| a.slot), Some(SlotId::A));
    assert_eq!(
        &flash.0.bytes()[..bare.len()],
        &bare[..],
        "the probe's image was erased"
    );
    assert_eq!(report_of(&flash, &c).image_state, image_state::UNSIGNED);
    let s = signed(&image(UNIT, 6), &station);
    let mut region = vec![0xFFu8; 64 * 1024];
    region[..s.len()].copy_from_slice(&s);
    let c = choose(&mut crate::slots::Mapped(&region), &QEMU_LAYOUT, |b| {
        trust.check(b)
    });
    assert_eq!(c.source, Source::Probe);
}
