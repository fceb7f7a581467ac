//! `tcomp image --model ID=FILE.tcm … --out models.bin`: the model-blob image the firmware reads
//! from its `MODELS` flash region (0x003F_0000, 64 KiB), flashed on its own without rebuilding the
//! firmware, e.g. `probe-rs download --binary-format bin --base-address 0x3F0000 models.bin`.
//!
//! Layout (little-endian; the firmware's reader and its documentation are `firmware/src/image.rs`):
//! magic `TCMI`, version u16 = 1, count u16, CRC-32 (ISO-HDLC) of the table u32, then `count`
//! entries of (channel id u16, 0u16, offset u32, length u32), then the blobs, each 4-byte aligned.
//! Every blob is decoded into the firmware's own model types before it is written: a blob that would
//! not load on the board (corrupt, or too many features, centers or program nodes) is refused here.
use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use std::path::PathBuf;

/// Size of the firmware's `MODELS` region.
const REGION_BYTES: usize = 64 * 1024;
const MAGIC: &[u8; 4] = b"TCMI";
const VERSION: u16 = 1;
const HEADER_LEN: usize = 12;
const ENTRY_LEN: usize = 12;
const MAX_ENTRIES: usize = 32;

/// Arguments of `tcomp image`.
#[derive(ClapArgs)]
pub struct Args {
    /// A channel's blob as `ID=FILE.tcm` (repeatable). Firmware channel ids: 0–2 RLG x/y/z,
    /// 3–5 QMA x/y/z, 6 IFOG.
    #[arg(long = "model", value_name = "ID=FILE", required = true)]
    pub models: Vec<String>,
    /// Where to write the image.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.models.len() > MAX_ENTRIES {
        bail!("at most {MAX_ENTRIES} models fit the image table");
    }
    let mut blobs = Vec::new();
    for spec in &args.models {
        let (id, file) = spec
            .split_once('=')
            .with_context(|| format!("`--model {spec}`: expected ID=FILE"))?;
        let id: u16 = id
            .trim()
            .parse()
            .with_context(|| format!("`--model {spec}`: channel id is not a number"))?;
        if blobs.iter().any(|(i, _)| *i == id) {
            bail!("channel {id} is given twice");
        }
        let path = PathBuf::from(file.trim());
        let bytes = tcomp_train::blob_io::read(&path)?;
        tcomp_train::blob_io::check_flight(&path, &bytes)?;
        blobs.push((id, bytes));
    }
    let table_end = HEADER_LEN + ENTRY_LEN * blobs.len();
    let mut table = Vec::new();
    let mut body = Vec::new();
    let mut offset = table_end.next_multiple_of(4);
    for (id, bytes) in &blobs {
        table.extend_from_slice(&id.to_le_bytes());
        table.extend_from_slice(&0u16.to_le_bytes());
        table.extend_from_slice(&(offset as u32).to_le_bytes());
        table.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        body.extend_from_slice(bytes);
        body.resize(body.len().next_multiple_of(4), 0);
        offset = table_end.next_multiple_of(4) + body.len();
    }
    let mut image = Vec::with_capacity(offset);
    image.extend_from_slice(MAGIC);
    image.extend_from_slice(&VERSION.to_le_bytes());
    image.extend_from_slice(&(blobs.len() as u16).to_le_bytes());
    image.extend_from_slice(&tcomp_core::blob::crc32(&table).to_le_bytes());
    image.extend_from_slice(&table);
    image.resize(table_end.next_multiple_of(4), 0);
    image.extend_from_slice(&body);
    if image.len() > REGION_BYTES {
        bail!(
            "the image is {} bytes, more than the {REGION_BYTES}-byte MODELS region",
            image.len()
        );
    }
    let inputs: Vec<PathBuf> = args
        .models
        .iter()
        .filter_map(|spec| spec.split_once('='))
        .map(|(_, file)| PathBuf::from(file.trim()))
        .collect();
    let inputs: Vec<(&str, &std::path::Path)> =
        inputs.iter().map(|p| ("--model", p.as_path())).collect();
    super::output::refuse_overwriting_inputs("--out", std::slice::from_ref(&args.out), &inputs)?;
    super::output::check_file_output("--out", &args.out)?;
    tcomp_train::blob_io::write_atomic(&args.out, &image)?;
    outln!(
        "wrote {} ({} bytes, {} models): flash it at 0x003F0000",
        args.out.display(),
        image.len(),
        blobs.len()
    );
    Ok(())
}
