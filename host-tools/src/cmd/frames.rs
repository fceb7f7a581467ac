//! `tcomp frames FILE [--json]`: decode a capture of the firmware's serial output into CSV (or JSON).
//!
//! The capture is the raw byte stream of the UART (e.g. `cat /dev/ttyUSB0 > capture.bin`): it may
//! start mid-frame and hold garbage or damaged frames; the core's streaming [`Decoder`] drops those
//! and counts them, and the counts go to stderr (CSV) or into the JSON. One implementation of the
//! format, `tcomp_core::frame`, is used by the firmware and by this command.
use anyhow::Context;
use clap::Args as ClapArgs;
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;
use tcomp_core::frame::{
    BootReport, DEVELOPMENT, Decoder, Frame, Item, Stats, WATCHDOG, image_state, status,
    update_state,
};
use tcomp_core::update::Reason;

/// Arguments of `tcomp frames`.
#[derive(ClapArgs)]
pub struct Args {
    /// The captured byte stream.
    pub file: PathBuf,
    /// Print JSON (frames and decoder counts) instead of CSV.
    #[arg(long)]
    pub json: bool,
}

/// The status word as names joined by `+` (`ok` when zero; unnamed bits as `bit<n>`).
pub fn status_names(word: u16) -> String {
    let mut out = String::new();
    status::for_each_name(word, |n| {
        if !out.is_empty() {
            out.push('+');
        }
        match n {
            Ok(name) => out.push_str(name),
            Err(bit) => {
                let _ = write!(out, "bit{bit}");
            }
        }
    });
    if out.is_empty() {
        out.push_str("ok");
    }
    out
}

fn stats_json(s: &Stats) -> serde_json::Value {
    json!({
        "frames": s.frames,
        "lost": s.lost,
        "corrupt": s.corrupt,
        "skipped_bytes": s.skipped,
        "restarts": s.restarts,
    })
}

/// A boot report: the unit, the image it runs and each channel's model state.
fn report_json(r: &BootReport) -> serde_json::Value {
    let image_state = image_state::name(r.image_state);
    // The firmware's `LoadError::code`.
    let model = |s: u8| match s {
        0 => "loaded",
        1 => "no blob in the image",
        2 => "image made for another unit",
        3 => "image unreadable",
        4 => "blob rejected",
        5 => "an input has no thermometer",
        6 => "channel table refused",
        7 => "channel not in the image's table",
        8 => "blob made for another channel",
        9 => "image made for another board description",
        _ => "unknown",
    };
    json!({
        "next_sequence": r.sequence,
        "unit_serial": r.unit_serial,
        "image_serial": r.image_serial,
        "image_version": r.image_version,
        "image_state": image_state,
        "board_hash": format!("{:016x}", r.board_hash),
        "image_crc": format!("{:08x}", r.image_crc),
        "watchdog_reset": r.flags & WATCHDOG != 0,
        "development_build": r.flags & DEVELOPMENT != 0,
        "signer": (r.signer != 0).then(|| format!("{:016x}", r.signer)),
        "last_update": update_state::name(r.update),
        "last_update_reason": (r.update != update_state::NONE && r.update != update_state::COMMITTED)
            .then(|| Reason::from_u8(r.update_reason).describe()),
        "stack_peak_bytes": (r.stack_peak != 0).then_some(r.stack_peak),
        "worst_sample_task_cost": r.worst_task,
        "channels": r.channels().iter().map(|c| json!({
            "id": c.id, "state": c.state, "model": model(c.state),
        })).collect::<Vec<_>>(),
    })
}

fn csv(frames: &[Frame]) -> String {
    let width = frames.iter().map(|f| f.channels().len()).max().unwrap_or(0);
    let mut out = String::from("time_s,sequence");
    for k in 0..width {
        let _ = write!(out, ",ch{k}_value,ch{k}_status");
    }
    out.push('\n');
    for f in frames {
        let _ = write!(out, "{},{}", f.time_s(), f.sequence);
        for k in 0..width {
            match f.channels().get(k) {
                Some(c) => {
                    let _ = write!(out, ",{},{}", c.value, status_names(c.status));
                }
                None => out.push_str(",,"),
            }
        }
        out.push('\n');
    }
    out
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let bytes =
        std::fs::read(&args.file).with_context(|| format!("reading {}", args.file.display()))?;
    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    let mut reports = Vec::new();
    decoder.feed_items(&bytes, |i| match i {
        Item::Data(f) => frames.push(f),
        Item::Boot(r) => reports.push(r),
    });
    let stats = decoder.stats();
    if args.json {
        let list: Vec<_> = frames
            .iter()
            .map(|f| {
                let channels: Vec<_> = f
                    .channels()
                    .iter()
                    .map(|c| {
                        json!({
                            "value": c.value.is_finite().then_some(c.value),
                            "status": c.status,
                            "status_names": status_names(c.status),
                        })
                    })
                    .collect();
                json!({
                    "sequence": f.sequence,
                    "timestamp": f.timestamp,
                    "tick_hz": f.tick_hz,
                    "time_s": f.time_s(),
                    "channels": channels,
                })
            })
            .collect();
        let value = json!({
            "file": args.file.display().to_string(),
            "stats": stats_json(&stats),
            "boot_reports": reports.iter().map(report_json).collect::<Vec<_>>(),
            "frames": list,
        });
        outln!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        out!("{}", csv(&frames));
        // Boot reports on stderr, beside the counts: the CSV on stdout stays one table.
        for r in &reports {
            eprintln!("boot report: {}", report_json(r));
        }
        eprintln!(
            "{} frames, {} lost (sequence gaps), {} corrupt (CRC), {} bytes skipped, {} restarts",
            stats.frames, stats.lost, stats.corrupt, stats.skipped, stats.restarts
        );
    }
    Ok(())
}
