//! The calibration image of one unit: model blobs checked against the board description and laid
//! out by the core's `ImageSpec::write`, optionally signed. `tcomp image` packs the blobs given on
//! its command line; `tcomp calibrate` packs the ones it has just fitted.
//!
//! Why a module of its own below `cmd/`: both commands must check and lay out an image the same
//! way, and `calibrate/` (the library under `tcomp calibrate`) builds images without being a
//! command; a helper never imports a command, so the building lives here and `cmd/image.rs` keeps
//! only the command (its arguments, reading `--model ID=FILE`, writing and printing).
//!
//! The layout is `tcomp_core::image`'s (documented there), written by its `ImageSpec::write`: the
//! firmware reads the image with the same module, so the two sides cannot disagree. Before
//! anything is written every model is checked against the board description's row for its channel
//! (an unknown or repeated channel, a model for another sensor kind, unit or axis, an input the
//! channel's thermometers cannot supply) and decoded into the firmware's own model types (a blob
//! that would not load on the board is refused here); any refusal builds nothing.
use anyhow::{Context, bail};
use std::path::PathBuf;
use tcomp_core::image::{Entry, Fnv64, ImageSpec, MAX_ENTRIES, Mismatch, Provenance, sign};

use tcomp_board_description::{Board, targets};

/// The largest image any board's slot holds (its capacity: the slot less its header).
fn largest_slot_capacity() -> usize {
    targets::TARGETS
        .iter()
        .map(|t| t.slot_bytes as usize - tcomp_core::slots::PAYLOAD_AT as usize)
        .max()
        .unwrap_or(0)
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

/// An image's creation time: `SOURCE_DATE_EPOCH` (so an image can be rebuilt bit for bit), else now.
pub fn created_now() -> anyhow::Result<u64> {
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

/// One channel's blob for [`build`]: the board's channel id, the file it was read from (named in
/// errors and in the provenance) and how errors name it (`--model 0=gx.tcm`, `channel gyro_x`).
#[derive(Clone, Debug)]
pub struct ChannelBlob {
    /// Channel id in the board description.
    pub id: u16,
    /// Where the blob was read from, or will be written.
    pub path: PathBuf,
    /// How an error names this blob.
    pub label: String,
    /// The blob.
    pub bytes: Vec<u8>,
}

/// Checks one blob against the board description's row for its channel.
fn check_blob(blob: &ChannelBlob, board: &Board, done: &[Loaded]) -> anyhow::Result<Loaded> {
    let (id, spec, path, bytes) = (blob.id, &blob.label, &blob.path, &blob.bytes);
    if done.iter().any(|l| l.id == id) {
        bail!("{spec}: channel {id} is given twice");
    }
    let rows = board.channel_rows();
    let Some(row) = rows.iter().find(|r| r.id == id) else {
        let ids: Vec<String> = rows.iter().map(|r| r.id.to_string()).collect();
        bail!(
            "{spec}: channel {id} is not in the board description {} (its channels: {})",
            board.path.display(),
            ids.join(", ")
        );
    };
    tcomp_train::blob_io::check_flight(path, bytes)?;
    let m = tcomp_train::blob_io::decode(path, bytes)?;
    let on = format!("{spec}: channel {id} ({})", row.name);
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
        data,
        data_hash,
        window,
    })
}

/// `blobs` with each unit compared with its channel's by [`tcomp_train::units`], not as text: a
/// model of the channel's sensor kind whose unit is the channel's spelt another way is re-encoded
/// in the channel's spelling; one in a commensurable unit (`deg/s` on `rad/s`) is refused with
/// the factor. Any other mismatch is left to [`check_blob`], which names it.
fn respell_units(board: &Board, blobs: &[ChannelBlob]) -> anyhow::Result<Vec<ChannelBlob>> {
    let rows = board.channel_rows();
    blobs
        .iter()
        .map(|b| {
            let mut b = b.clone();
            let Some(row) = rows.iter().find(|r| r.id == b.id) else {
                return Ok(b);
            };
            let Ok(m) = tcomp_train::blob_io::decode(&b.path, &b.bytes) else {
                return Ok(b);
            };
            let unit_only = matches!(
                row.accepts(&m.meta, m.program.inputs.iter().map(|s| &**s)),
                Err(Mismatch::Unit)
            );
            drop(m);
            if unit_only
                && let Some(bytes) = tcomp_train::blob_io::respell_blob(&b.path, &b.bytes, row.unit)
                    .with_context(|| format!("{}: channel {} ({})", b.label, b.id, row.name))?
            {
                b.bytes = bytes;
            }
            Ok(b)
        })
        .collect()
}

/// The image of one unit: `blobs` checked against `board` (an unknown or repeated channel, a model
/// for another sensor kind, unit or axis, an input the channel's thermometers cannot supply, a blob
/// the firmware would not load, an image larger than the `MODELS` region are all refused) and laid
/// out by the core's `ImageSpec::write`. Shared by `tcomp image` and `tcomp calibrate`, so the two
/// cannot check differently. A channel without a blob is simply absent from the table.
pub fn build(
    board: &Board,
    serial: u64,
    created: u64,
    blobs: &[ChannelBlob],
) -> anyhow::Result<Vec<u8>> {
    if blobs.len() > MAX_ENTRIES {
        bail!("at most {MAX_ENTRIES} models fit the image table");
    }
    // A model whose unit is the channel's spelt another way (`m/s2` for `m/s^2`) flies in the
    // channel's spelling; a scaled one (`deg/s` for `rad/s`) is refused with the factor.
    let respelled = respell_units(board, blobs)?;
    let blobs = respelled.as_slice();
    let mut loaded: Vec<Loaded> = Vec::new();
    for b in blobs {
        let l = check_blob(b, board, &loaded)?;
        loaded.push(l);
    }
    let thermometers = board.thermometer_rows();
    let channels = board.channel_rows();
    let entries: Vec<Entry<'_>> = loaded
        .iter()
        .zip(blobs)
        .map(|(l, b)| Entry {
            channel: l.id,
            blob: &b.bytes,
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
        serial,
        created,
        tool: &tool,
        thermometers: &thermometers,
        channels: &channels,
        entries: &entries,
    };
    let len = spec.image_len()?;
    let capacity = largest_slot_capacity();
    if len > capacity {
        bail!("the image is {len} bytes, more than a model slot holds ({capacity} bytes)");
    }
    let mut image = vec![0u8; len];
    spec.write(&mut image)?;
    Ok(image)
}

/// Appends the signature block (`tcomp_core::image::sign`) to `image`; returns the key id.
pub fn sign_image(image: &mut Vec<u8>, secret: &[u8; 32]) -> anyhow::Result<sign::KeyId> {
    let len = image.len();
    image.resize(len + sign::BLOCK_LEN, 0);
    sign::sign(image, secret)?;
    Ok(sign::KeyId::of(&sign::public_key(secret)))
}
