//! `tcomp flash` end to end over a pseudo-terminal: the test plays the unit with the core's
//! receiver on the flash model, interleaves output frames with the replies and loses one reply;
//! `tcomp flash` must retry, commit, report the unit's output frames without a gap, and leave the
//! new image as the one the unit boots. A bad image is refused before the port is opened.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use serialport::{SerialPort, TTYPort};
use std::io::{Read, Write};
use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use tcomp_core::frame::{BootReport, ChannelOutput, Frame, update_state};
use tcomp_core::image::{Image, write_image};
use tcomp_core::slots::sim::SimNor;
use tcomp_core::slots::{Layout, SlotId, select};
use tcomp_core::update::Receiver;
use tcomp_core::update::wire::{Decoder, Kind, MAX_FRAME};

const SECTOR: usize = 4096;
type Flash = SimNor<{ 2 * SECTOR }, SECTOR>;
const LAYOUT: Layout = Layout {
    a: 0,
    b: SECTOR as u32,
    size: SECTOR as u32,
};

fn validate(flash: &mut Flash, offset: u32, len: u32) -> bool {
    let (at, len) = (offset as usize, len as usize);
    flash
        .bytes()
        .get(at..at + len)
        .is_some_and(|b| Image::parse(b).is_ok())
}

fn image() -> Vec<u8> {
    let blobs: Vec<Vec<u8>> = (0..3u8)
        .map(|i| {
            (0..900)
                .map(|j: u32| (j as u8).wrapping_mul(3) ^ i)
                .collect()
        })
        .collect();
    let entries: Vec<(u16, &[u8])> = blobs
        .iter()
        .enumerate()
        .map(|(i, b)| (i as u16, b.as_slice()))
        .collect();
    let mut buf = vec![0u8; SECTOR];
    let n = write_image(&entries, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

/// The unit: answers every request, sends an output frame after each reply and each idle read,
/// and loses the reply to the second DATA request once.
fn unit(mut port: TTYPort, stop: Arc<AtomicBool>) -> Flash {
    let mut flash = Flash::new();
    let mut rx = Receiver::new(LAYOUT, None);
    let mut decoder = Decoder::new();
    let (mut sequence, mut data_seen) = (0u32, 0);
    let mut buf = [0u8; 256];
    while !stop.load(Ordering::Acquire) {
        let n = match port.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => 0,
            Err(_) => break,
        };
        let mut out = Vec::new();
        for &b in &buf[..n] {
            if let Some(p) = decoder.push(b) {
                let reply = rx.handle(&mut flash, &p, b"SN-PTY-7", |f, o, l| {
                    validate(f, o, l)
                        .then_some(())
                        .ok_or(tcomp_core::update::Reason::Invalid)
                });
                data_seen += usize::from(p.kind == Kind::Data);
                if p.kind == Kind::Data && data_seen == 2 {
                    continue; // this reply is lost
                }
                let mut f = [0u8; MAX_FRAME];
                let m = reply.packet().encode(&mut f).unwrap();
                out.extend_from_slice(&f[..m]);
                // As the firmware does: its boot report as soon as an update ends.
                if reply.kind() == Kind::Result {
                    let mut r = BootReport::default();
                    r.unit_serial = 7;
                    r.update = update_state::COMMITTED;
                    let mut b = [0u8; 128];
                    let k = r.encode(&mut b).unwrap();
                    out.extend_from_slice(&b[..k]);
                }
            }
        }
        let frame = Frame::new(
            sequence,
            u64::from(sequence),
            200,
            &[ChannelOutput {
                value: 1.5,
                status: 0,
            }],
        );
        sequence += 1;
        let mut f = [0u8; 64];
        let k = frame.encode(&mut f).unwrap();
        out.extend_from_slice(&f[..k]);
        if port.write_all(&out).is_err() {
            break;
        }
    }
    flash
}

#[test]
fn an_update_over_a_pty_commits_and_keeps_the_output_frames() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("models.bin");
    let img = image();
    std::fs::write(&path, &img).unwrap();
    let (mut master, slave) = TTYPort::pair().unwrap();
    master.set_timeout(Duration::from_millis(20)).unwrap();
    let name = slave.name().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let unit_stop = Arc::clone(&stop);
    let unit = std::thread::spawn(move || unit(master, unit_stop));
    let out = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["flash", "--port", &name, "--baud", "921600", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    stop.store(true, Ordering::Release);
    let mut flash = unit.join().unwrap();
    drop(slave);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["result"], "ok");
    assert_eq!(v["serial"], "SN-PTY-7");
    assert_eq!(
        (v["slot"].as_str(), v["generation"].as_u64()),
        (Some("A"), Some(1))
    );
    assert!(
        v["repeats"].as_u64().unwrap() >= 1,
        "the lost reply was retried"
    );
    assert!(v["output_frames"].as_u64().unwrap() > 5);
    assert_eq!(v["unit_report"]["last_update"], "committed", "{v}");
    assert_eq!(v["output_lost"], 0);
    let active = select(&mut flash, &LAYOUT, validate).unwrap().unwrap();
    assert_eq!(active.slot, SlotId::A);
    let at = active.payload(&LAYOUT) as usize;
    assert_eq!(&flash.bytes()[at..at + img.len()], &img[..]);
}

#[test]
fn a_bad_image_is_refused_before_the_port_is_opened() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("junk.bin");
    std::fs::write(&path, b"not an image at all").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["flash", "--port", "/nonexistent/tty", "--baud", "921600"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("junk.bin") && err.contains("not a model image"),
        "{err}"
    );
    assert!(
        !err.contains("/nonexistent/tty"),
        "the port must not be touched: {err}"
    );
    assert!(out.stdout.is_empty());
}

/// The help names the product board's model address (not only QEMU's), and `tcomp flash` takes its
/// rate from the description or refuses to guess one.
#[test]
fn the_help_names_the_boards_address_and_flash_needs_a_rate() {
    let help = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["image", "--help"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(
        text.contains("0x080C0000 on the STM32F407 board") && text.contains("0x003F0000"),
        "{text}"
    );
    let help = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["flash", "--help"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(
        text.contains("--board <FILE>") && text.contains("[link] baud"),
        "{text}"
    );
    assert!(!text.contains("115200"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("models.bin");
    std::fs::write(&path, image()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["flash", "--port", "/nonexistent/tty"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "clap's usage error");
    assert!(String::from_utf8_lossy(&out.stderr).contains("--board"));
}
