//! Asking a channel what it runs: whether it has a model, the model's input columns (in the
//! order a step takes them), its metadata, the image row's wiring, and why a load failed — views
//! of the core's `Model` and `ChannelRow`, copied or borrowed, never computed here.
#![allow(unsafe_code)] // C entry points: raw pointers in, `#[unsafe(no_mangle)]` out

use crate::api::TCOMP_MAX_INPUTS;
use crate::channel::{self, Failure, TcompChannel};
use crate::error::{TCOMP_ERR_ALIGNMENT, TCOMP_ERR_INDEX, TCOMP_ERR_NULL, TCOMP_OK};
use crate::guard;
use crate::out;
use core::ffi::c_char;

/// How a channel loaded from a version-2 calibration image is wired on the board, from the
/// image's channel table (what the firmware's board description says).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TcompWiring {
    /// Channel id (the key of its blob in the image).
    pub channel_id: u16,
    /// Where the raw value comes from: 0 a pulse counter, 1 a sample source (a register).
    pub source_kind: u8,
    /// Index of that counter or sample source on the board.
    pub source_index: u8,
    /// Output unit per pulse (counter: arcsec for a gyro, ug·s for an accelerometer, so that
    /// raw = counts · scale / interval_s gives deg/h or ug) or per LSB (sample source).
    pub scale: f32,
    /// Entries of `thermometer` that are set: the model's input count.
    pub n_inputs: u8,
    /// For model input `i` (the order `tcomp_step` takes them in), the index of the board
    /// thermometer that feeds it.
    pub thermometer: [u8; TCOMP_MAX_INPUTS],
}

/// Whether the channel has a model: 1 yes, 0 no (never loaded, or the load failed), or a
/// negative error code (`TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_UNINITIALISED`).
/// Thread safety: `ch` must not be written concurrently.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_has_model(ch: *const TcompChannel) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract for `ch`; the body only reads.
        unsafe { channel::with(ch.cast_mut(), |c| c, |s| i32::from(s.model.is_some())) }
    })
}

/// The number of input columns the channel's model reads (what `n_inputs` of a step must be):
/// ≥ 0, 0 without a model, or a negative error code as for `tcomp_channel_has_model`.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_input_count(ch: *const TcompChannel) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract for `ch`; the body only reads.
        unsafe {
            channel::with(
                ch.cast_mut(),
                |c| c,
                |s| {
                    s.model
                        .as_ref()
                        .map_or(0, |m| m.program.inputs.len() as i32)
                },
            )
        }
    })
}

/// Writes the name of the model's input column `index` (e.g. `"t_anode_c"`, as in the training
/// CSV's header) into `buf`, NUL-terminated and truncated to fit.
///
/// * `index` — 0 ≤ `index` < `tcomp_channel_input_count(ch)`.
/// * `buf`, `buf_len` — the caller's buffer; `buf` may be NULL when `buf_len` is 0 (to ask for the
///   length).
///
/// Returns the name's length without the NUL (`snprintf`-style), `TCOMP_ERR_INDEX` past the
/// inputs (or without a model), or `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`,
/// `TCOMP_ERR_UNINITIALISED`. Thread safety: `ch` must not be written concurrently.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `buf` NULL or `buf_len`
/// writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_input_name(
    ch: *const TcompChannel,
    index: usize,
    buf: *mut c_char,
    buf_len: usize,
) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract for `buf`.
        let Some(buf) = (unsafe { guard::bytes_mut(buf.cast(), buf_len) }) else {
            return TCOMP_ERR_NULL;
        };
        // SAFETY: the caller's contract for `ch`; the body only reads it.
        unsafe {
            channel::with(
                ch.cast_mut(),
                |c| c,
                |s| match s.model.as_ref().and_then(|m| m.program.inputs.get(index)) {
                    Some(name) => len_code(out::display(buf, &&**name)),
                    None => TCOMP_ERR_INDEX,
                },
            )
        }
    })
}

/// Copies the wiring of a channel loaded from a version-2 image (`tcomp_load_image`) into
/// `wiring`: which counter or sample source gives its raw value, with which scale, and which
/// board thermometer feeds each model input.
///
/// Returns `TCOMP_OK`; `TCOMP_ERR_INDEX` when the channel has no image row (loaded from a bare
/// blob, from a version-1 image, or without a model; `wiring` is then zeroed); or
/// `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_UNINITIALISED`. Thread safety: `ch` must
/// not be written concurrently.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `wiring` NULL or a writable
/// `tcomp_wiring_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_wiring(
    ch: *const TcompChannel,
    wiring: *mut TcompWiring,
) -> i32 {
    guard::code(|| {
        if wiring.is_null() || !wiring.is_aligned() {
            return if wiring.is_null() {
                TCOMP_ERR_NULL
            } else {
                TCOMP_ERR_ALIGNMENT
            };
        }
        // SAFETY: the caller's contract for `ch`; the body only reads it.
        let (code, value) = unsafe {
            channel::with(
                ch.cast_mut(),
                |c| (c, TcompWiring::default()),
                |s| match (&s.row, &s.model) {
                    (Some(row), Some(model)) => (
                        TCOMP_OK,
                        TcompWiring {
                            channel_id: row.id,
                            source_kind: row.source.0,
                            source_index: row.source.1,
                            scale: row.scale,
                            n_inputs: model.program.inputs.len() as u8,
                            thermometer: row.thermometer,
                        },
                    ),
                    _ => (TCOMP_ERR_INDEX, TcompWiring::default()),
                },
            )
        };
        // SAFETY: non-NULL, aligned, the caller's to write.
        unsafe { wiring.write(value) };
        code
    })
}

/// Writes what the channel runs, or why its last load failed, into `buf` (the core's own
/// message, e.g. `"blob refused: inconsistent field ranges: one per feature"`;
/// `"ok"` after a successful load, `"no model"` after `tcomp_channel_init`), NUL-terminated and
/// truncated to fit.
///
/// * `buf`, `buf_len` — the caller's buffer; `buf` may be NULL when `buf_len` is 0.
///
/// Returns the text's length without the NUL (`snprintf`-style), or `TCOMP_ERR_NULL`,
/// `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_UNINITIALISED`. 160 bytes hold every message.
/// Thread safety: `ch` must not be written concurrently.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `buf` NULL or `buf_len`
/// writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_describe(
    ch: *const TcompChannel,
    buf: *mut c_char,
    buf_len: usize,
) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract for `buf`.
        let Some(buf) = (unsafe { guard::bytes_mut(buf.cast(), buf_len) }) else {
            return TCOMP_ERR_NULL;
        };
        // SAFETY: the caller's contract for `ch`; the body only reads it.
        unsafe {
            channel::with(
                ch.cast_mut(),
                |c| c,
                |s| match (&s.failure, &s.model) {
                    (Failure::None, None) => len_code(out::display(buf, &"no model")),
                    (f, _) => len_code(out::display(buf, f)),
                },
            )
        }
    })
}

/// A text length as a return value.
fn len_code(n: usize) -> i32 {
    i32::try_from(n).unwrap_or(i32::MAX)
}

/// A string borrowed from a channel's blob: `len` bytes of UTF-8 at `ptr`, **not NUL-terminated**
/// (print it with `printf("%.*s", (int)s.len, s.ptr)`). Valid while the blob stays in place and
/// the channel keeps this model; `ptr` is never NULL (an empty string has `len` 0).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct TcompStr {
    /// The first byte.
    pub ptr: *const c_char,
    /// Bytes.
    pub len: usize,
}

impl TcompStr {
    fn of(s: &str) -> Self {
        Self {
            ptr: s.as_ptr().cast(),
            len: s.len(),
        }
    }
}

/// What a channel's model is, from its blob's metadata (`tcomp inspect` prints the same).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct TcompMeta {
    /// The instrument: 0 RLG, 1 quartz accelerometer, 2 IFOG, 3 MEMS gyro, 4 MEMS
    /// accelerometer, 5 other (the calibration image's codes).
    pub sensor: u8,
    /// Features the model evaluates.
    pub n_features: u8,
    /// Input columns it reads (what a step's `n_inputs` must be).
    pub n_inputs: u8,
    /// Gaussian centers.
    pub n_centers: u16,
    /// The blob's format version.
    pub format_version: u16,
    /// Axis label (`x`, `y`, `z`).
    pub axis: TcompStr,
    /// Unit of the raw value, the correction and the output (`deg/h`, `ug`).
    pub unit: TcompStr,
    /// Training method (`bayes`, `poly3`, …).
    pub method: TcompStr,
    /// The training CSV's time column (seconds).
    pub time_column: TcompStr,
    /// The training CSV's sensor-output column.
    pub target_column: TcompStr,
    /// The training CSV's reference column; empty when a constant was used.
    pub reference_column: TcompStr,
    /// The constant reference, in the model's unit; NaN when a column was used.
    pub reference_value: f32,
    /// What data it was trained on (file and time window).
    pub trained_on: TcompStr,
    /// Training samples.
    pub train_samples: u32,
    /// Residual standard deviation seen on held-out data when the model was made (model unit).
    pub residual_std: f32,
}

/// Copies the channel's model metadata into `meta`; its strings are borrowed from the blob.
///
/// Returns `TCOMP_OK`; `TCOMP_ERR_INDEX` when the channel has no model (`meta` untouched); or
/// `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_UNINITIALISED`. Thread safety: `ch` must
/// not be written concurrently.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `meta` NULL or a writable
/// `tcomp_meta_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_channel_meta(ch: *const TcompChannel, meta: *mut TcompMeta) -> i32 {
    guard::code(|| {
        if meta.is_null() || !meta.is_aligned() {
            return if meta.is_null() {
                TCOMP_ERR_NULL
            } else {
                TCOMP_ERR_ALIGNMENT
            };
        }
        // SAFETY: the caller's contract for `ch`; the body only reads it.
        let value = unsafe {
            channel::with(ch.cast_mut(), Err, |s| {
                let m = s.model.as_ref().ok_or(TCOMP_ERR_INDEX)?;
                let c = &m.meta.columns;
                Ok(TcompMeta {
                    sensor: tcomp_core::image::table::sensor_code(m.meta.sensor),
                    n_features: m.rbf.n_features,
                    n_inputs: m.program.inputs.len() as u8,
                    n_centers: m.rbf.centers.len() as u16,
                    format_version: m.version,
                    axis: TcompStr::of(m.meta.axis),
                    unit: TcompStr::of(m.meta.unit),
                    method: TcompStr::of(m.meta.method),
                    time_column: TcompStr::of(c.time),
                    target_column: TcompStr::of(c.target),
                    reference_column: TcompStr::of(c.reference),
                    reference_value: c.reference_value.unwrap_or(f32::NAN),
                    trained_on: TcompStr::of(m.meta.trained_on),
                    train_samples: m.meta.train_samples,
                    residual_std: m.residual.std,
                })
            })
        };
        match value {
            Ok(v) => {
                // SAFETY: non-NULL, aligned, the caller's to write.
                unsafe { meta.write(v) };
                TCOMP_OK
            }
            Err(code) => code,
        }
    })
}
