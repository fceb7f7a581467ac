//! `tcomp image --board FILE --serial N --model ID=FILE.tcm … --out models.bin`: the calibration
//! image a unit runs from one of its two model slots, sent with `tcomp flash` or written bare at
//! the start of the board's `MODELS` region by a probe, without rebuilding the firmware, e.g.
//! `probe-rs download --binary-format bin --base-address 0x080C0000 models.bin` on the STM32F407
//! board. The addresses in the help come from one table (`tcomp_board_description::targets`),
//! checked against the firmware's memory maps.
//!
//! The checks and the layout are [`crate::image`]'s, shared with `tcomp calibrate`: this module
//! reads the `--model ID=FILE` arguments, builds the image there, signs it if asked, and writes it
//! (refused, with nothing written, when any model fails a check).
use crate::image::{ChannelBlob, build, created_now, sign_image};
use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use std::path::{Path, PathBuf};
use tcomp_board_description::{Board, targets};
use tcomp_core::image::MAX_ENTRIES;

/// `tcomp image`'s one-line help: what the image is and where it goes, with each board's address.
pub fn about() -> String {
    format!(
        "Pack model blobs, checked against a board description, into a unit's calibration image: \
         sent with `tcomp flash`, or written bare by a probe at the MODELS region ({})",
        targets::probe_addresses()
    )
}

/// Arguments of `tcomp image`.
#[derive(ClapArgs)]
pub struct Args {
    /// The board description (TOML) the image is made for: its channel table goes into the image.
    #[arg(long, value_name = "FILE")]
    pub board: PathBuf,
    /// A channel's blob as `ID=FILE.tcm` (repeatable); ID is a channel id of the board description.
    #[arg(long = "model", value_name = "ID=FILE", required = true)]
    pub models: Vec<String>,
    /// The unit's serial number (decimal or 0x hex): the firmware refuses an image made for
    /// another unit.
    #[arg(long, value_parser = parse_serial)]
    pub serial: u64,
    /// Creation time, seconds since 1970 UTC (default: `SOURCE_DATE_EPOCH`, else now), so an
    /// image can be rebuilt bit for bit.
    #[arg(long, value_name = "SECONDS")]
    pub created: Option<u64>,
    /// Sign the image with this secret key (`tcomp keygen`'s PREFIX.key): units run only images
    /// signed by a key they were provisioned with.
    #[arg(long, value_name = "KEY")]
    pub sign: Option<PathBuf>,
    /// Where to write the image.
    #[arg(long)]
    pub out: PathBuf,
    /// Print what was written as JSON (the shared vocabulary: `command`, `subject`, then the
    /// image's fields).
    #[arg(long)]
    pub json: bool,
    /// Print nothing on success (errors still go to stderr).
    #[arg(long)]
    pub quiet: bool,
}

/// `tcomp image --json`'s own fields.
#[derive(serde::Serialize)]
struct ImageJson {
    out: String,
    bytes: usize,
    board: String,
    board_hash: String,
    serial: u64,
    /// The signing key's id, or null for an unsigned image.
    signer: Option<String>,
    channels: Vec<ChannelJson>,
}

/// One channel of the image in `--json`.
#[derive(serde::Serialize)]
struct ChannelJson {
    id: u16,
    model: String,
}

fn parse_serial(s: &str) -> Result<u64, String> {
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => s.parse(),
    };
    r.map_err(|e| format!("`{s}`: {e}"))
}

fn created(args: &Args) -> anyhow::Result<u64> {
    match args.created {
        Some(t) => Ok(t),
        None => created_now(),
    }
}

/// Parses `ID=FILE` and reads the file.
fn read_model_arg(spec: &str) -> anyhow::Result<ChannelBlob> {
    let (id, file) = spec
        .split_once('=')
        .with_context(|| format!("`--model {spec}`: expected ID=FILE"))?;
    let id: u16 = id
        .trim()
        .parse()
        .with_context(|| format!("`--model {spec}`: channel id is not a number"))?;
    let path = PathBuf::from(file.trim());
    Ok(ChannelBlob {
        id,
        bytes: tcomp_train::blob_io::read(&path)?,
        path,
        label: format!("`--model {spec}`"),
    })
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.models.len() > MAX_ENTRIES {
        bail!("at most {MAX_ENTRIES} models fit the image table");
    }
    let board = Board::load(&args.board)?;
    // Read and check one `--model` at a time, so the first bad argument is the one named.
    let mut blobs = Vec::new();
    for spec in &args.models {
        blobs.push(read_model_arg(spec)?);
        build(&board, args.serial, 0, &blobs)?;
    }
    let secret = args
        .sign
        .as_deref()
        .map(super::keygen::read_secret)
        .transpose()?;
    let mut image = build(&board, args.serial, created(args)?, &blobs)?;
    let signer = match &secret {
        Some(secret) => Some(sign_image(&mut image, secret)?),
        None => None,
    };
    let mut inputs: Vec<(&str, &Path)> = blobs
        .iter()
        .map(|l| ("--model", l.path.as_path()))
        .collect();
    inputs.push(("--board", args.board.as_path()));
    if let Some(key) = &args.sign {
        inputs.push(("--sign", key.as_path()));
    }
    crate::output::files::refuse_overwriting_inputs(
        "--out",
        std::slice::from_ref(&args.out),
        &inputs,
    )?;
    crate::output::files::check_file_output("--out", &args.out)?;
    tcomp_train::blob_io::write_atomic(&args.out, &image)?;
    if args.json {
        let subject = crate::output::json::Subject {
            models: blobs.iter().map(|b| b.path.display().to_string()).collect(),
            ..Default::default()
        };
        let body = ImageJson {
            out: args.out.display().to_string(),
            bytes: image.len(),
            board: board.name.clone(),
            board_hash: format!("{:016x}", board.hash()),
            serial: args.serial,
            signer: signer.map(|k| k.to_string()),
            channels: blobs
                .iter()
                .map(|b| ChannelJson {
                    id: b.id,
                    model: b.path.display().to_string(),
                })
                .collect(),
        };
        return crate::output::json::print("image", &subject, &body);
    }
    if args.quiet {
        return Ok(());
    }
    outln!(
        "wrote {} ({} bytes, {} models for board {} (hash {:016x}), unit {}, {}): send it with `tcomp flash`, or write it bare at {}",
        args.out.display(),
        image.len(),
        blobs.len(),
        crate::output::printable::text(&board.name),
        board.hash(),
        args.serial,
        signer.map_or("unsigned".to_string(), |k| format!("signed by key {k}")),
        targets::probe_addresses()
    );
    Ok(())
}
