//! `tcomp flash --port PATH IMAGE`: replace a unit's model image over its serial link.
//!
//! The image is checked with the core's reader before the port is even opened (a bad image sends
//! nothing); then the core's update [`Sender`] drives the protocol (`tcomp_core::update`): HELLO
//! (the unit names its serial, active slot and generation), BEGIN, the chunks, COMMIT, and the
//! unit's RESULT. The unit writes its inactive slot and keeps compensating meanwhile, so its output
//! frames keep arriving on the same link: [`link::transfer`] decodes them beside the replies and
//! reports how many came and whether any were lost. The new image takes effect at the unit's next
//! reset (the running models are not swapped under the loop).

pub mod link;

use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use serde_json::json;
use std::path::PathBuf;
use std::time::Duration;
use tcomp_core::image::Image;
use tcomp_core::update::Status;
use tcomp_train::progress::{Progress, Unit};

/// Arguments of `tcomp flash`.
#[derive(ClapArgs)]
pub struct Args {
    /// The image written by `tcomp image`.
    pub image: PathBuf,
    /// The unit's serial port (e.g. /dev/ttyUSB0, or the pty QEMU names).
    #[arg(long)]
    pub port: PathBuf,
    /// The link's baud rate.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Milliseconds to wait for a reply before sending a request again.
    #[arg(long, default_value_t = 500)]
    pub timeout_ms: u64,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let image =
        std::fs::read(&args.image).with_context(|| format!("reading {}", args.image.display()))?;
    Image::parse(&image)
        .with_context(|| format!("{}: not a model image, nothing sent", args.image.display()))?;
    let port_name = args.port.to_string_lossy().into_owned();
    let mut port = serialport::new(&port_name, args.baud)
        .timeout(Duration::from_millis(20))
        .open()
        .with_context(|| format!("--port {port_name}: cannot open"))?;
    // Whatever arrived before the port was raw is stale.
    port.clear(serialport::ClearBuffer::Input)
        .with_context(|| format!("--port {port_name}: cannot clear its input"))?;
    let bar = super::progress::Bar::new(args.quiet || args.json);
    bar.start("sending", image.len() as u64, Unit::Bytes);
    let outcome = link::transfer(
        &mut port,
        &image,
        Duration::from_millis(args.timeout_ms),
        |sent, _| bar.set(u64::from(sent)),
    )
    .with_context(|| format!("--port {port_name}"))?;
    bar.clear();
    let info = outcome.info;
    let serial = info.map(|i| String::from_utf8_lossy(i.serial()).into_owned());
    let (slot, generation) = match outcome.status {
        Status::Done { slot, generation } => (slot, generation),
        Status::Failed(why) => bail!("--port {port_name}: update failed: {why}"),
        Status::Running { .. } => bail!("--port {port_name}: the update did not finish"),
    };
    let slot_name = |i: u8| if i == 0 { "A" } else { "B" };
    if args.json {
        let value = json!({
            "port": port_name,
            "image": args.image.display().to_string(),
            "bytes": image.len(),
            "serial": serial,
            "previous_slot": info.and_then(|i| i.active).map(|s| slot_name(s.index())),
            "previous_generation": info.map(|i| i.generation),
            "slot": slot_name(slot.index()),
            "generation": generation,
            "result": "ok",
            "repeats": outcome.repeats,
            "output_frames": outcome.output.frames,
            "output_lost": outcome.output.lost,
            "output_first_sequence": outcome.first_sequence,
            "output_last_sequence": outcome.last_sequence,
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
