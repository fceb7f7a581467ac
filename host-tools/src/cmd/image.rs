//! `tcomp image --board FILE --serial N --model ID=FILE.tcm … --out models.bin`: the calibration
//! image the firmware reads from its `MODELS` flash region (0x003F_0000, 64 KiB), flashed on its own
//! without rebuilding the firmware, e.g.
//! `probe-rs download --binary-format bin --base-address 0x3F0000 models.bin`.
//!
//! The layout is `tcomp_core::image`'s (documented there), written by its `ImageSpec::write`: the
//! firmware reads the image with the same module, so the two sides cannot disagree. Before
//! anything is written every model is checked against the board description's row for its channel
//! (an unknown or repeated channel, a model for another sensor kind, unit or axis, an input the
//! channel's thermometers cannot supply) and decoded into the firmware's own model types (a blob
//! that would not load on the board is refused here); any refusal writes nothing.
use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use std::path::{Path, PathBuf};
use tcomp_core::image::{Entry, Fnv64, ImageSpec, MAX_ENTRIES, Mismatch, Provenance};

use tcomp_board_description::Board;

/// Size of the firmware's `MODELS` region.
const REGION_BYTES: usize = 64 * 1024;

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
    /// Where to write the image.
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_serial(s: &str) -> Result<u64, String> {
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => s.parse(),
    };
    r.map_err(|e| format!("`{s}`: {e}"))
}

/// The tool version the header carries: the package version and, when the build saw one, the
/// git revision (`TCOMP_GIT_REV` at compile time; no build script, so a fresh clone builds).
fn tool_version() -> String {
    let v = env!("CARGO_PKG_VERSION");
    let s = match option_env!("TCOMP_GIT_REV") {
        Some(rev) if !rev.is_empty() => format!("{v}+{rev}"),
        _ => v.to_string(),
    };
    s.chars().take(16).collect()
}

fn created(args: &Args) -> anyhow::Result<u64> {
    if let Some(t) = args.created {
        return Ok(t);
    }
    if let Ok(s) = std::env::var("SOURCE_DATE_EPOCH") {
        return s
            .trim()
            .parse()
            .with_context(|| format!("SOURCE_DATE_EPOCH `{s}` is not a number of seconds"));
    }
    Ok(std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()))
}

/// One `--model` after its checks.
struct Loaded {
    id: u16,
    path: PathBuf,
    bytes: Vec<u8>,
    data: String,
    data_hash: u64,
    window: [f32; 2],
    method: String,
}

/// `"FILE [FROM s, UNTIL s) t=T0..T1 s"` (the trainer's `trained_on`) as the file, its hash when
/// it is there to read, and the window of the rows it trained on.
fn provenance_of(trained_on: &str) -> (String, u64, [f32; 2]) {
    let t = tcomp_train::blob_io::TrainedOn::parse(trained_on);
    let window = t.span.map_or([f32::NAN; 2], |[a, b]| [a as f32, b as f32]);
    let hash = std::fs::read(&t.file).map_or(0, |bytes| {
        let mut h = Fnv64::new();
        h.write(&bytes);
        h.finish()
    });
    (t.file, hash, window)
}

fn load_model(spec: &str, board: &Board, done: &[Loaded]) -> anyhow::Result<Loaded> {
    let (id, file) = spec
        .split_once('=')
        .with_context(|| format!("`--model {spec}`: expected ID=FILE"))?;
    let id: u16 = id
        .trim()
        .parse()
        .with_context(|| format!("`--model {spec}`: channel id is not a number"))?;
    if done.iter().any(|l| l.id == id) {
        bail!("`--model {spec}`: channel {id} is given twice");
    }
    let rows = board.channel_rows();
    let Some(row) = rows.iter().find(|r| r.id == id) else {
        let ids: Vec<String> = rows.iter().map(|r| r.id.to_string()).collect();
        bail!(
            "`--model {spec}`: channel {id} is not in the board description {} (its channels: {})",
            board.path.display(),
            ids.join(", ")
        );
    };
    let path = PathBuf::from(file.trim());
    let bytes = tcomp_train::blob_io::read(&path)?;
    tcomp_train::blob_io::check_flight(&path, &bytes)?;
    let m = tcomp_train::blob_io::decode(&path, &bytes)?;
    let on = format!("`--model {spec}`: channel {id} ({})", row.name);
    match row.accepts(&m.meta, m.program.inputs.iter().map(|s| &**s)) {
        Ok(()) => {}
        Err(Mismatch::Sensor(s)) => bail!(
            "{on} is a {:?} channel; the model is for a {s:?}",
            row.sensor
        ),
        Err(Mismatch::Unit) => bail!(
            "{on} outputs \"{}\"; the model's unit is \"{}\"",
            row.unit,
            m.meta.unit.escape_debug()
        ),
        Err(Mismatch::Axis) => bail!(
            "{on} is axis \"{}\"; the model's axis is \"{}\" (fit it with --axis {})",
            row.axis,
            m.meta.axis.escape_debug(),
            row.axis
        ),
        Err(Mismatch::Input(input)) => {
            let have: Vec<&str> = row.inputs().iter().map(|i| i.name).collect();
            bail!(
                "{on} has no thermometer for the model's input `{}` (its inputs: {})",
                input.escape_debug(),
                have.join(", ")
            )
        }
    }
    let (data, data_hash, window) = provenance_of(m.meta.trained_on);
    let method = m.meta.method.to_string();
    drop(m);
    Ok(Loaded {
        id,
        method,
        path,
        data,
        data_hash,
        window,
        bytes,
    })
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.models.len() > MAX_ENTRIES {
        bail!("at most {MAX_ENTRIES} models fit the image table");
    }
    let board = Board::load(&args.board)?;
    let mut loaded: Vec<Loaded> = Vec::new();
    for spec in &args.models {
        let l = load_model(spec, &board, &loaded)?;
        loaded.push(l);
    }
    let thermometers = board.thermometer_rows();
    let channels = board.channel_rows();
    let entries: Vec<Entry<'_>> = loaded
        .iter()
        .map(|l| Entry {
            channel: l.id,
            blob: &l.bytes,
            provenance: Provenance {
                data: &l.data,
                data_hash: l.data_hash,
                window: l.window,
                method: &l.method,
            },
        })
        .collect();
    let tool = tool_version();
    let spec = ImageSpec {
        serial: args.serial,
        created: created(args)?,
        tool: &tool,
        thermometers: &thermometers,
        channels: &channels,
        entries: &entries,
    };
    let len = spec.image_len()?;
    if len > REGION_BYTES {
        bail!("the image is {len} bytes, more than the {REGION_BYTES}-byte MODELS region");
    }
    let mut image = vec![0u8; len];
    spec.write(&mut image)?;
    let mut inputs: Vec<(&str, &Path)> = loaded
        .iter()
        .map(|l| ("--model", l.path.as_path()))
        .collect();
    inputs.push(("--board", args.board.as_path()));
    super::output::refuse_overwriting_inputs("--out", std::slice::from_ref(&args.out), &inputs)?;
    super::output::check_file_output("--out", &args.out)?;
    tcomp_train::blob_io::write_atomic(&args.out, &image)?;
    outln!(
        "wrote {} ({} bytes, {} models for board {} (hash {:016x}), unit {}): flash it at 0x003F0000",
        args.out.display(),
        image.len(),
        loaded.len(),
        super::printable::text(&board.name),
        board.hash(),
        args.serial
    );
    Ok(())
}
