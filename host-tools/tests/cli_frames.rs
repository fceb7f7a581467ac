//! `tcomp frames`: a capture with garbage, a corrupt frame and a lost one decodes to CSV and JSON.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::process::Command;
use tcomp_core::frame::{ChannelOutput, Frame, MAX_FRAME_LEN, status};

fn tcomp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .unwrap()
}

fn encode(f: &Frame) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = f.encode(&mut buf).unwrap();
    buf[..n].to_vec()
}

fn frame(seq: u32) -> Frame {
    let channels = [
        ChannelOutput {
            value: 360_000.002 + f64::from(seq),
            status: status::OK,
        },
        ChannelOutput {
            value: if seq == 3 { f64::NAN } else { -12.5 },
            status: if seq == 3 {
                status::NO_MODEL | status::SENSOR_ERROR
            } else {
                status::NO_MODEL
            },
        },
    ];
    // 200 Hz periods of a 1 MHz sample timer.
    Frame::new(seq, u64::from(seq) * 5_000, 1_000_000, &channels)
}

fn capture() -> Vec<u8> {
    // Starts mid-frame, frame 2 corrupt, frame 4 lost.
    let mut bytes = encode(&frame(0))[30..].to_vec();
    bytes.extend(encode(&frame(1)));
    let mut bad = encode(&frame(2));
    bad[22] ^= 1;
    bytes.extend(bad);
    bytes.extend(encode(&frame(3)));
    bytes.extend(encode(&frame(5)));
    bytes
}

#[test]
fn frames_to_csv_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("capture.bin");
    std::fs::write(&path, capture()).unwrap();
    let path = path.to_str().unwrap();

    let out = tcomp(&["frames", path]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines,
        [
            "time_s,sequence,ch0_value,ch0_status,ch1_value,ch1_status",
            "0.005,1,360001.002,ok,-12.5,no-model",
            "0.015,3,360003.002,ok,NaN,no-model+sensor-error",
            "0.025,5,360005.002,ok,-12.5,no-model",
        ]
    );
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("3 frames, 2 lost"), "{err}");
    assert!(err.contains("1 corrupt"), "{err}");

    let out = tcomp(&["frames", path, "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["stats"]["frames"], 3);
    assert_eq!(v["stats"]["lost"], 2);
    assert_eq!(v["stats"]["corrupt"], 1);
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    assert_eq!(frames[1]["sequence"], 3);
    assert!(frames[1]["channels"][1]["value"].is_null());
    assert_eq!(
        frames[1]["channels"][1]["status_names"],
        "no-model+sensor-error"
    );
    assert_eq!(frames[2]["channels"][0]["value"], 360_005.002);
}

#[test]
fn missing_file_is_an_error() {
    let out = tcomp(&["frames", "/nonexistent/capture.bin"]);
    assert!(!out.status.success());
}

#[test]
fn a_boot_report_between_frames_is_printed_and_the_frames_kept() {
    use tcomp_core::frame::{BootReport, ChannelState, image_state};
    let mut r = BootReport::default();
    r.sequence = 3;
    r.unit_serial = 0x5EED;
    r.image_serial = 0x5EED;
    r.image_version = 2;
    r.image_state = image_state::OK;
    r.set_channels(&[
        ChannelState { id: 0, state: 0 },
        ChannelState { id: 1, state: 8 },
    ]);
    let mut buf = [0u8; 128];
    let n = r.encode(&mut buf).unwrap();
    let mut bytes = encode(&frame(2));
    bytes.extend_from_slice(&buf[..n]);
    bytes.extend(encode(&frame(3)));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("boot.bin");
    std::fs::write(&path, &bytes).unwrap();
    let out = tcomp(&["frames", path.to_str().unwrap(), "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["frames"].as_array().unwrap().len(), 2);
    assert_eq!(v["stats"]["skipped_bytes"], 0);
    let b = &v["boot_reports"][0];
    assert_eq!(b["unit_serial"], 0x5EED);
    assert_eq!(b["image_state"], "ok");
    assert_eq!(b["channels"][1]["model"], "blob made for another channel");
    let out = tcomp(&["frames", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("boot report"), "{err}");
}
