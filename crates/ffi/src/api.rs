//! The entry points that make a channel: version and capacities, validating a blob, loading a
//! blob or an image's channel into a channel's storage (stepping it is `step.rs`, asking it what
//! it runs `query.rs`).
//!
//! Each is a thin translation: C pointers become slices (`guard.rs`), the work is one call into
//! the core (`Model::decode_into`, `Image::parse`, `ChannelRow::accepts`, …), and its `Result`
//! becomes an integer code.
#![allow(unsafe_code)] // C entry points: raw pointers in, `#[unsafe(no_mangle)]` out

use crate::channel::{self, Failure, FfiModel, Row, State, TcompChannel};
use crate::error::*;
use crate::guard;
use crate::out;
use core::ffi::c_char;
use tcomp_core::blob::{FORMAT_VERSION, OLDEST_FORMAT_VERSION};
use tcomp_core::image::{ChannelRow, Image, VERSION_2};
use tcomp_core::{FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES, MAX_INPUTS};

/// Version of this C API: raised when a declaration of `tcomp.h` changes incompatibly.
pub const TCOMP_API_VERSION: u32 = 1;
/// Most Gaussian centers a loadable model may have (the reference firmware's capacity).
pub const TCOMP_MAX_CENTERS: usize = 32;
/// Most features a loadable model may have.
pub const TCOMP_MAX_FEATURES: usize = 4;
/// Most feature-program operations a loadable model may have.
pub const TCOMP_MAX_NODES: usize = 16;
/// Most named inputs (thermometer columns) a model reads: the length `tcomp_step` may be given.
pub const TCOMP_MAX_INPUTS: usize = 8;

const _: () = assert!(
    TCOMP_MAX_CENTERS == FLIGHT_CENTERS
        && TCOMP_MAX_FEATURES == FLIGHT_FEATURES
        && TCOMP_MAX_NODES == FLIGHT_NODES
        && TCOMP_MAX_INPUTS == MAX_INPUTS,
    "the header's capacities must be the core's flight capacities"
);

/// The library's version and capacities, for a caller to check at run time that the library it
/// linked is the one its header describes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TcompCapacities {
    /// `TCOMP_API_VERSION` of the library.
    pub api_version: u32,
    /// `TCOMP_CHANNEL_SIZE` of the library, bytes.
    pub channel_size: u32,
    /// `TCOMP_CHANNEL_ALIGN` of the library, bytes.
    pub channel_align: u32,
    /// Bytes of the storage the library actually uses on this target (≤ `channel_size`).
    pub channel_used: u32,
    /// Most Gaussian centers per model.
    pub max_centers: u16,
    /// Most features per model.
    pub max_features: u16,
    /// Most feature-program operations per model.
    pub max_nodes: u16,
    /// Most input columns per model.
    pub max_inputs: u16,
    /// The newest blob format version this library reads.
    pub blob_format_newest: u16,
    /// The oldest blob format version this library reads.
    pub blob_format_oldest: u16,
    /// The newest calibration-image format version this library reads.
    pub image_format: u16,
}

/// The library's version as text (`"0.1.0"`).
///
/// Returns a NUL-terminated string in static storage: never NULL, never to be freed.
/// Thread safety: constant data; callable from anywhere.
#[unsafe(no_mangle)]
pub extern "C" fn tcomp_version() -> *const c_char {
    const VERSION: &core::ffi::CStr = match core::ffi::CStr::from_bytes_with_nul(
        concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes(),
    ) {
        Ok(v) => v,
        Err(_) => c"",
    };
    VERSION.as_ptr()
}

/// The library's API version, storage size and capacities (see `tcomp_capacities_t`).
///
/// Returns the capacities by value. Thread safety: constant data; callable from anywhere.
#[unsafe(no_mangle)]
pub extern "C" fn tcomp_capacities() -> TcompCapacities {
    TcompCapacities {
        api_version: TCOMP_API_VERSION,
        channel_size: channel::TCOMP_CHANNEL_SIZE as u32,
        channel_align: channel::TCOMP_CHANNEL_ALIGN as u32,
        channel_used: channel::STATE_SIZE as u32,
        max_centers: TCOMP_MAX_CENTERS as u16,
        max_features: TCOMP_MAX_FEATURES as u16,
        max_nodes: TCOMP_MAX_NODES as u16,
        max_inputs: TCOMP_MAX_INPUTS as u16,
        blob_format_newest: FORMAT_VERSION,
        blob_format_oldest: OLDEST_FORMAT_VERSION,
        image_format: VERSION_2,
    }
}

/// Checks a model blob completely (length, magic, CRC-32, version, structure, capacities, values,
/// plausibility) without keeping it: what a firmware runs before it writes a received blob to
/// flash.
///
/// * `blob`, `blob_len` — the blob's bytes (a `.tcm` file as `tcomp fit` wrote it), borrowed for
///   the call only. `blob` may be NULL when `blob_len` is 0.
/// * `why`, `why_len` — optional: a caller's buffer for the core's reason (`why` may be NULL);
///   NUL-terminated, truncated to fit, `"ok"` when the blob is valid.
///
/// Returns `TCOMP_OK`, or the `TCOMP_ERR_BLOB_*` code of the first check that failed
/// (`TCOMP_ERR_NULL` for a NULL `blob` with `blob_len` > 0).
/// Decodes on the stack: the model (1.9 KB on a Cortex-M4) and the decoder's frames, about
/// 5.5 KB of stack in all (measured by `cargo xtask ffi`; `tcomp_load_blob` decodes in place and
/// needs about 1.3 KB less). Thread safety: reentrant.
///
/// # Safety
/// `blob` must be NULL or point to `blob_len` readable bytes; `why` NULL or `why_len` writable
/// bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_validate_blob(
    blob: *const u8,
    blob_len: usize,
    why: *mut c_char,
    why_len: usize,
) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract for `blob`.
        let Some(bytes) = (unsafe { guard::bytes(blob, blob_len) }) else {
            return TCOMP_ERR_NULL;
        };
        let mut place: Option<FfiModel> = None;
        let result = FfiModel::decode_into(bytes, &mut place);
        // SAFETY: the caller's contract for `why`; a NULL `why` means no text is wanted.
        if let Some(buf) = unsafe { guard::bytes_mut(why.cast(), why_len) } {
            match &result {
                Ok(()) => out::display(buf, &"ok"),
                Err(e) => out::display(buf, e),
            };
        }
        result.map_or_else(|e| blob_code(&e), |()| TCOMP_OK)
    })
}

/// Initialises `ch` as a channel without a model: every step passes the raw value through with
/// `TCOMP_STATUS_NO_MODEL` (what a firmware runs before, or instead of, a valid model).
///
/// * `ch` — the caller's storage (`TCOMP_CHANNEL_SIZE` bytes aligned to `TCOMP_CHANNEL_ALIGN`).
/// * `period_s` — the sampling period in seconds, used by `tcomp_step` (e.g. 0.005 at 200 Hz);
///   a positive finite number.
///
/// Returns `TCOMP_OK`, `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT` or `TCOMP_ERR_ARGUMENT` (bad
/// period; `ch` is then left as it was). Thread safety: `ch` must not be in use elsewhere.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_init(ch: *mut TcompChannel, period_s: f32) -> i32 {
    guard::code(|| {
        if !positive(period_s) {
            return TCOMP_ERR_ARGUMENT;
        }
        // SAFETY: the caller's contract for `ch`.
        match unsafe { channel::init(ch, period_s) } {
            Ok(_) => TCOMP_OK,
            Err(code) => code,
        }
    })
}

/// Decodes a model blob into `ch`, in place, and readies the channel for it (history cleared,
/// filter coefficients computed for `period_s`). On any error `ch` is still initialised, as by
/// `tcomp_channel_init`, without a model: stepping it passes raw values through, flagged.
///
/// * `ch` — the caller's storage (`TCOMP_CHANNEL_SIZE` bytes aligned to `TCOMP_CHANNEL_ALIGN`);
///   whatever it held is replaced.
/// * `blob`, `blob_len` — the blob's bytes, **borrowed, not copied**: the model's names point
///   into them, so they must stay in place and unchanged (flash, or a static buffer) for as long
///   as `ch` is used with this model.
/// * `period_s` — the sampling period in seconds, used by `tcomp_step`; positive and finite.
///
/// Returns `TCOMP_OK`, `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_ARGUMENT` (bad period:
/// `ch` is left as it was) or a `TCOMP_ERR_BLOB_*` code (the reason in full:
/// `tcomp_channel_describe`). The model is decoded straight into `ch`; the decoder's frames
/// still take about 4 KB of stack on a Cortex-M4 (measured by `cargo xtask ffi`: plan the boot
/// stack for it; stepping needs far less). Thread safety: `ch` must not be in use elsewhere.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `blob` NULL or `blob_len`
/// readable bytes that outlive every later use of `ch` with this model.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_load_blob(
    ch: *mut TcompChannel,
    blob: *const u8,
    blob_len: usize,
    period_s: f32,
) -> i32 {
    guard::code(|| {
        if !positive(period_s) {
            return TCOMP_ERR_ARGUMENT;
        }
        // SAFETY: the caller's contract: the blob outlives the channel's use of it.
        let Some(bytes) = (unsafe { guard::bytes::<'static>(blob, blob_len) }) else {
            return TCOMP_ERR_NULL;
        };
        // SAFETY: the caller's contract for `ch`.
        let state = match unsafe { channel::init(ch, period_s) } {
            Ok(s) => s,
            Err(code) => return code,
        };
        let loaded = load_blob(state, bytes);
        finish_load(state, loaded)
    })
}

/// Loads channel `channel_id`'s model from a calibration image (as `tcomp image` writes it and
/// the board's model slot holds it) into `ch`: the whole image is checked (CRC, rows, board hash),
/// then optionally its unit and board, then the channel's blob is decoded in place and, for a
/// version-2 image, checked against the channel's row (sensor kind, axis, unit, every input
/// column wired to a thermometer); the row's wiring is kept (`tcomp_channel_wiring`). On any
/// error `ch` is initialised without a model, as by `tcomp_channel_init`.
///
/// * `ch` — the caller's storage; whatever it held is replaced.
/// * `image`, `image_len` — the image's bytes (a whole flash slot may be given: bytes past the
///   image are ignored), **borrowed, not copied**: they must stay in place and unchanged while
///   `ch` is used with this model.
/// * `channel_id` — the channel's id in the image (the board description's `id`).
/// * `unit_serial` — optional: NULL, or the unit's serial number; an image made for another unit
///   is refused (`TCOMP_ERR_IMAGE_OTHER_UNIT`).
/// * `board_hash` — optional: NULL, or the FNV-1a 64 hash of the board description the firmware
///   was written for (`tcomp inspect` prints an image's); an image for another description is
///   refused (`TCOMP_ERR_IMAGE_BOARD_HASH`).
/// * `period_s` — the sampling period in seconds; positive and finite.
///
/// Returns `TCOMP_OK`, `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_ARGUMENT` (bad period:
/// `ch` is left as it was), a `TCOMP_ERR_IMAGE_*` or a `TCOMP_ERR_BLOB_*` code (in full:
/// `tcomp_channel_describe`). Thread safety: `ch` must not be in use elsewhere; the image may be
/// shared by several channels (read only).
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `image` NULL or `image_len`
/// readable bytes that outlive every later use of `ch` with this model; `unit_serial` and
/// `board_hash` NULL or pointing to a readable `uint64_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_load_image(
    ch: *mut TcompChannel,
    image: *const u8,
    image_len: usize,
    channel_id: u16,
    unit_serial: *const u64,
    board_hash: *const u64,
    period_s: f32,
) -> i32 {
    guard::code(|| {
        if !positive(period_s) {
            return TCOMP_ERR_ARGUMENT;
        }
        // SAFETY: the caller's contract: the image outlives the channel's use of it.
        let Some(bytes) = (unsafe { guard::bytes::<'static>(image, image_len) }) else {
            return TCOMP_ERR_NULL;
        };
        // SAFETY: the caller's contract: NULL or a readable u64.
        let (serial, hash) = unsafe { (optional(unit_serial), optional(board_hash)) };
        // SAFETY: the caller's contract for `ch`.
        let state = match unsafe { channel::init(ch, period_s) } {
            Ok(s) => s,
            Err(code) => return code,
        };
        let loaded = load_image(state, bytes, channel_id, serial, hash);
        finish_load(state, loaded)
    })
}

/// Decodes `bytes` into the state's model slot.
fn load_blob(state: &mut State, bytes: &'static [u8]) -> Result<(), Failure> {
    FfiModel::decode_into(bytes, &mut state.model).map_err(Failure::Blob)
}

/// The image checks, the blob, and the row (see [`tcomp_load_image`]).
fn load_image(
    state: &mut State,
    bytes: &'static [u8],
    id: u16,
    serial: Option<u64>,
    hash: Option<u64>,
) -> Result<(), Failure> {
    let image = Image::parse(bytes).map_err(Failure::Image)?;
    if let Some(serial) = serial {
        image.check_unit(serial).map_err(Failure::Image)?;
    }
    if let (Some(h), Some(expected)) = (image.header(), hash)
        && h.board_hash != expected
    {
        return Err(Failure::OtherBoard);
    }
    let blob = image.blob(id).map_err(Failure::Image)?;
    load_blob(state, blob)?;
    if image.version() < VERSION_2 {
        return Ok(());
    }
    let row = image.channel_by_id(id).ok_or(Failure::NotInTable)?;
    let model = state.model.as_ref().ok_or(Failure::NotInTable)?;
    row.accepts(&model.meta, model.program.inputs.iter().map(|s| &**s))
        .map_err(|_| Failure::WrongChannel)?;
    state.row = Some(wiring(&row, model));
    Ok(())
}

/// The row's source, scale and, per model input, the thermometer `ChannelRow::thermometer_for`
/// names (every input has one: `accepts` checked it).
fn wiring(row: &ChannelRow<'_>, model: &FfiModel) -> Row {
    let mut thermometer = [0u8; MAX_INPUTS];
    for (t, name) in thermometer.iter_mut().zip(model.program.inputs.iter()) {
        *t = row.thermometer_for(name).unwrap_or(u8::MAX);
    }
    Row {
        id: row.id,
        source: row.source.code(),
        scale: row.scale,
        thermometer,
    }
}

/// Records a load's outcome: on success readies the channel for the model; on failure clears the
/// model and keeps the reason.
fn finish_load(state: &mut State, loaded: Result<(), Failure>) -> i32 {
    match (loaded, &state.model) {
        (Ok(()), Some(model)) => {
            state.channel.prepare(model);
            TCOMP_OK
        }
        (Ok(()), None) => TCOMP_ERR_BLOB_OTHER,
        (Err(failure), _) => {
            state.model = None;
            state.row = None;
            state.failure = failure;
            failure_code(&failure)
        }
    }
}

fn failure_code(f: &Failure) -> i32 {
    match f {
        Failure::None => TCOMP_OK,
        Failure::Blob(e) => blob_code(e),
        Failure::Image(e) => image_code(e),
        Failure::OtherBoard => TCOMP_ERR_IMAGE_BOARD_HASH,
        Failure::NotInTable => TCOMP_ERR_IMAGE_NOT_IN_TABLE,
        Failure::WrongChannel => TCOMP_ERR_IMAGE_WRONG_CHANNEL,
    }
}

/// A positive finite number of seconds.
fn positive(s: f32) -> bool {
    s.is_finite() && s > 0.0
}

/// `None` for NULL, else the `u64` at `p` (read unaligned: a C caller may pack it anywhere).
///
/// # Safety
/// `p` must be NULL or point to 8 readable bytes.
unsafe fn optional(p: *const u64) -> Option<u64> {
    if p.is_null() {
        return None;
    }
    // SAFETY: non-NULL and readable by the caller's contract; no alignment is assumed.
    Some(unsafe { p.read_unaligned() })
}
