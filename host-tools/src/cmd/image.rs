//! `tcomp image --model ID=FILE.tcm … --out models.bin`: the model-blob image the firmware reads
//! from its `MODELS` flash region (0x003F_0000, 64 KiB), flashed on its own without rebuilding the
//! firmware, e.g. `probe-rs download --binary-format bin --base-address 0x3F0000 models.bin`.
//!
//! The layout is `tcomp_core::image`'s (documented there), written by its `write_image`: the
//! firmware reads the image with the same module, so the two sides cannot disagree.
//! Every blob is decoded into the firmware's own model types before it is written: a blob that would
//! not load on the board (corrupt, or too many features, centers or program nodes) is refused here.
use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_core::image::{MAX_ENTRIES, image_len, write_image};

/// Size of the firmware's `MODELS` region.
const REGION_BYTES: usize = 64 * 1024;

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
    let entries: Vec<(u16, &[u8])> = blobs.iter().map(|(id, b)| (*id, b.as_slice())).collect();
    let len = image_len(&entries)?;
    if len > REGION_BYTES {
        bail!("the image is {len} bytes, more than the {REGION_BYTES}-byte MODELS region");
    }
    let mut image = vec![0u8; len];
    write_image(&entries, &mut image)?;
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
