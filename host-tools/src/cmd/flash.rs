//! `tcomp flash --port PATH IMAGE`: replace a unit's model image over its serial link.
//!
//! The image is checked with the core's reader before the port is even opened (a bad image sends
//! nothing); then the core's update [`Sender`] drives the protocol (`tcomp_core::update`): HELLO
//! (the unit names its serial, active slot and generation), BEGIN, the chunks, COMMIT, and the
//! unit's RESULT. The unit writes its inactive slot and keeps compensating meanwhile, so its output
//! frames keep arriving on the same link: [`link::transfer`] decodes them beside the replies and
//! reports how many came and whether any were lost. The new image takes effect at the unit's next
//! reset (the running models are not swapped under the loop).
//!
//! The baud rate is the board description's (`--board FILE`, its `[link] baud`): the one number
//! the board binary's UART is built with, so the tool cannot open the port at another rate than
//! the unit's. `--baud` is for a description without `[link]` (a design no board binary runs yet)
//! or a link that is not the unit's own (a pty). The reply timeout follows from the baud rate;
//! each run draws a new session number, so its BEGIN takes over whatever a failed run left open.

pub mod link;

use anyhow::{Context, bail};
use clap::{ArgGroup, Args as ClapArgs};
use serde_json::json;
use std::path::PathBuf;
use std::time::Duration;
use tcomp_board_description::Board;
use tcomp_core::frame::{DEVELOPMENT, image_state, update_state};
use tcomp_core::image::Image;
use tcomp_core::update::wire::MAX_FRAME;
use tcomp_core::update::{Reason, Status};
use tcomp_train::progress::{Progress, Unit};

/// Arguments of `tcomp flash`.
#[derive(ClapArgs)]
#[command(group(ArgGroup::new("rate").required(true).args(["board", "baud"])))]
pub struct Args {
    /// The image written by `tcomp image`.
    pub image: PathBuf,
    /// The unit's serial port (e.g. /dev/ttyUSB0, or the pty QEMU names).
    #[arg(long)]
    pub port: PathBuf,
    /// The unit's board description (firmware/descriptions/*.toml): the port runs at its
    /// `[link] baud`, the rate the board binary is built with, and the image must be made for it.
    #[arg(long, value_name = "FILE")]
    pub board: Option<PathBuf>,
    /// The link's baud rate, instead of a description's (a description without `[link]`, or a
    /// link that is not the unit's own UART).
    #[arg(long, conflicts_with = "board")]
    pub baud: Option<u32>,
    /// Milliseconds to wait for a reply before sending a request again (default: 50 ms plus
    /// twice the time of a full transmit queue of the unit at the baud rate: 62 ms at 921,600).
    #[arg(long)]
    pub timeout_ms: Option<u64>,
    /// Milliseconds to wait for the answer to COMMIT (the unit reads the image back and checks
    /// it and its signature first).
    #[arg(long, default_value_t = 3000)]
    pub commit_timeout_ms: u64,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// Bytes the unit may have queued ahead of a reply: the STM32F407 board's 512-byte transmit
/// queue, plus a request and its reply on the wire.
const QUEUED_BYTES: u64 = 512 + 2 * MAX_FRAME as u64;

/// The reply timeout at `baud` (8N1: ten bits a byte): 50 ms for the host's side (a USB serial
/// adapter's latency timer is 16 ms, the scheduler's a few) and twice the time of
/// [`QUEUED_BYTES`].
pub fn reply_timeout(baud: u32) -> Duration {
    let queue_us = QUEUED_BYTES * 10 * 1_000_000 / u64::from(baud.max(1));
    Duration::from_millis(50) + Duration::from_micros(2 * queue_us)
}

/// A session number for this run: the clock's nanoseconds mixed with the process id, so two runs
/// (even two at once on two ports) do not share one.
fn session() -> u32 {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    (nanos as u32) ^ (nanos >> 32) as u32 ^ std::process::id().rotate_left(16)
}

/// The baud rate: the description's (and the image must be made for its board), or `--baud`.
fn baud(args: &Args, image: &Image<'_>) -> anyhow::Result<u32> {
    let Some(path) = &args.board else {
        return args
            .baud
            .context("give --board FILE (its [link] baud) or --baud");
    };
    let board = Board::load(path)?;
    if let Some(h) = image.header()
        && h.board_hash != board.hash()
    {
        bail!(
            "{}: made for board hash {:016x}, not for --board {} ({}, hash {:016x}); nothing sent",
            args.image.display(),
            h.board_hash,
            path.display(),
            crate::output::printable::text(&board.name),
            board.hash()
        );
    }
    board.baud.with_context(|| {
        format!(
            "--board {}: the description has no [link] baud (give --baud)",
            path.display()
        )
    })
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let image =
        std::fs::read(&args.image).with_context(|| format!("reading {}", args.image.display()))?;
    let parsed = Image::parse(&image)
        .with_context(|| format!("{}: not a model image, nothing sent", args.image.display()))?;
    let baud = baud(args, &parsed)?;
    let timing = link::Timing {
        reply: args
            .timeout_ms
            .map_or_else(|| reply_timeout(baud), Duration::from_millis),
        commit: Duration::from_millis(args.commit_timeout_ms),
        reset: link::RESET_ERASE,
    };
    let port_name = args.port.to_string_lossy().into_owned();
    let mut port = serialport::new(&port_name, baud)
        .timeout(Duration::from_millis(20))
        .open()
        .with_context(|| format!("--port {port_name}: cannot open"))?;
    // Whatever arrived before the port was raw is stale.
    port.clear(serialport::ClearBuffer::Input)
        .with_context(|| format!("--port {port_name}: cannot clear its input"))?;
    let bar = crate::output::progress::Bar::new(args.quiet || args.json);
    bar.start("sending", image.len() as u64, Unit::Bytes);
    let (outcome, through_reset) =
        link::transfer_through_reset(&mut port, &image, session(), timing, |sent, _| {
            bar.set(u64::from(sent))
        })
        .with_context(|| format!("--port {port_name}"))?;
    bar.clear();
    if through_reset && !args.json && !args.quiet {
        eprintln!(
            "--port {port_name}: the unit's slot held an earlier session's bytes; it reset, its \
             boot erased the slot, and the image was sent again"
        );
    }
    let info = outcome.info;
    let serial = info.map(|i| String::from_utf8_lossy(i.serial()).into_owned());
    let slot_name = |i: u8| if i == 0 { "A" } else { "B" };
    let unit_report = outcome.report.map(|r| {
        json!({
            "image_state": image_state::name(r.image_state),
            "signer": (r.signer != 0).then(|| format!("{:016x}", r.signer)),
            "development_build": r.flags & DEVELOPMENT != 0,
            "last_update": update_state::name(r.update),
            "last_update_reason": (r.update == update_state::REFUSED
                || r.update == update_state::FAILED)
                .then(|| Reason::from_u8(r.update_reason).describe()),
        })
    });
    let (slot, generation) = match outcome.status {
        Status::Done { slot, generation } => (slot, generation),
        Status::Failed(why) => {
            if args.json {
                let value = json!({
                    "port": port_name,
                    "baud": baud,
                    "image": args.image.display().to_string(),
                    "serial": serial,
                    "result": "failed",
                    "reason": why.to_string(),
                    "aborted": outcome.aborted,
                    "unit_report": unit_report,
                });
                outln!("{}", serde_json::to_string_pretty(&value)?);
            }
            if outcome.aborted {
                bail!(
                    "--port {port_name}: update failed: {why} (session aborted; the unit keeps its models)"
                );
            }
            bail!("--port {port_name}: update failed: {why} (the unit keeps its models)");
        }
        Status::Running { .. } => bail!("--port {port_name}: the update did not finish"),
    };
    if args.json {
        let value = json!({
            "port": port_name,
            "baud": baud,
            "image": args.image.display().to_string(),
            "bytes": image.len(),
            "serial": serial,
            "previous_slot": info.and_then(|i| i.active).map(|s| slot_name(s.index())),
            "previous_generation": info.map(|i| i.generation),
            "slot": slot_name(slot.index()),
            "generation": generation,
            "result": "ok",
            "repeats": outcome.repeats,
            "sent_again_after_reset": through_reset,
            "output_frames": outcome.output.frames,
            "output_lost": outcome.output.lost,
            "output_first_sequence": outcome.first_sequence,
            "output_last_sequence": outcome.last_sequence,
            "unit_report": unit_report,
        });
        outln!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        outln!(
            "unit {}: wrote {} bytes to slot {} (generation {}), verified and committed; it runs them from its next reset",
            serial.as_deref().unwrap_or("?"),
            image.len(),
            slot_name(slot.index()),
            generation
        );
        outln!(
            "{} requests repeated; {} output frames received during the update, {} lost",
            outcome.repeats,
            outcome.output.frames,
            outcome.output.lost
        );
    }
    Ok(())
}
