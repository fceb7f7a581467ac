//! The error codes of the C API and their names: one table, from which [`tcomp_error_name`] answers
//! and the header's `#define`s are checked (`tests/header.rs`).
//!
//! Why integers: a C caller switches on them, logs them and passes them through its own error
//! paths; a negative `int32_t` fits every C convention. Each code of the blob and image groups
//! stands for one variant of the core's [`BlobError`] or [`ImageError`], so a caller can tell a
//! corrupt blob from one too big for this build without parsing text; the core's full message
//! (with the field it names) is [`crate::tcomp_channel_describe`]'s.

#![allow(unsafe_code)] // `#[unsafe(no_mangle)]` on the naming function

use core::ffi::{CStr, c_char};
use tcomp_core::BlobError;
use tcomp_core::image::ImageError;

/// Success.
pub const TCOMP_OK: i32 = 0;
/// A required pointer argument was NULL.
pub const TCOMP_ERR_NULL: i32 = -1;
/// The channel storage is not aligned to `TCOMP_CHANNEL_ALIGN` bytes.
pub const TCOMP_ERR_ALIGNMENT: i32 = -2;
/// The channel storage was never initialised by `tcomp_channel_init`, `tcomp_load_blob` or
/// `tcomp_load_image` (or a caught panic left it unusable).
pub const TCOMP_ERR_UNINITIALISED: i32 = -3;
/// A numeric argument is out of its domain (a period or time step that is not a positive finite
/// number of seconds, a time that is not finite).
pub const TCOMP_ERR_ARGUMENT: i32 = -4;
/// The number of inputs passed to a step is not the number the channel's model reads.
pub const TCOMP_ERR_INPUT_COUNT: i32 = -5;
/// An index past the end (an input name past the model's inputs).
pub const TCOMP_ERR_INDEX: i32 = -6;
/// The library caught a panic (a bug in tcomp, never a property of the data): the call did not
/// complete. Host builds only; a bare-metal build stops in `tcomp_panic_hook` instead.
pub const TCOMP_ERR_PANIC: i32 = -7;
/// Blob: shorter than the smallest blob, or its structure ends early.
pub const TCOMP_ERR_BLOB_TRUNCATED: i32 = -20;
/// Blob: the first four bytes are not `TCMB`.
pub const TCOMP_ERR_BLOB_MAGIC: i32 = -21;
/// Blob: a format version this build does not read.
pub const TCOMP_ERR_BLOB_VERSION: i32 = -22;
/// Blob: the CRC-32 does not match (the blob is corrupt).
pub const TCOMP_ERR_BLOB_CHECKSUM: i32 = -23;
/// Blob: more centers, features, program nodes or inputs than this build's capacities
/// (`TCOMP_MAX_CENTERS`, …).
pub const TCOMP_ERR_BLOB_CAPACITY: i32 = -24;
/// Blob: the bytes do not form a model (bad UTF-8, a bad option tag, bytes left over).
pub const TCOMP_ERR_BLOB_MALFORMED: i32 = -25;
/// Blob: an enum tag past the known variants.
pub const TCOMP_ERR_BLOB_UNKNOWN_TAG: i32 = -26;
/// Blob: a number is NaN or infinite.
pub const TCOMP_ERR_BLOB_NON_FINITE: i32 = -27;
/// Blob: sizes or values disagree.
pub const TCOMP_ERR_BLOB_INCONSISTENT: i32 = -28;
/// Blob: the feature program is invalid.
pub const TCOMP_ERR_BLOB_PROGRAM: i32 = -29;
/// Blob: every number is valid, but the model's correction could be non-finite or implausibly
/// large somewhere in its trained range.
pub const TCOMP_ERR_BLOB_IMPLAUSIBLE: i32 = -30;
/// Blob: rejected for a reason newer than this list (the detail names it).
pub const TCOMP_ERR_BLOB_OTHER: i32 = -31;
/// Image: no image magic (erased or empty flash, or something else).
pub const TCOMP_ERR_IMAGE_NONE: i32 = -40;
/// Image: a format version this build does not read.
pub const TCOMP_ERR_IMAGE_VERSION: i32 = -41;
/// Image: the table is too long or runs past the end of the bytes.
pub const TCOMP_ERR_IMAGE_TABLE: i32 = -42;
/// Image: the CRC-32 does not match (a partial upload or a flipped bit).
pub const TCOMP_ERR_IMAGE_CHECKSUM: i32 = -43;
/// Image: no blob for the requested channel id.
pub const TCOMP_ERR_IMAGE_MISSING: i32 = -44;
/// Image: an entry's blob lies outside the image.
pub const TCOMP_ERR_IMAGE_BOUNDS: i32 = -45;
/// Image: a malformed row in its channel table.
pub const TCOMP_ERR_IMAGE_ROW: i32 = -46;
/// Image: an entry names a channel its table does not have.
pub const TCOMP_ERR_IMAGE_UNKNOWN_CHANNEL: i32 = -47;
/// Image: its board hash is not the hash of the rows it carries.
pub const TCOMP_ERR_IMAGE_BOARD_HASH: i32 = -48;
/// Image: made for another unit (its serial is not the one given).
pub const TCOMP_ERR_IMAGE_OTHER_UNIT: i32 = -49;
/// Image: rejected for a reason newer than this list (the detail names it).
pub const TCOMP_ERR_IMAGE_OTHER: i32 = -50;
/// Image: the blob's sensor kind, axis, unit or input columns are not those of its channel's row
/// (an entry pointing at another channel's valid blob).
pub const TCOMP_ERR_IMAGE_WRONG_CHANNEL: i32 = -51;
/// Image: the channel id has a blob but no row in the image's channel table.
pub const TCOMP_ERR_IMAGE_NOT_IN_TABLE: i32 = -52;

/// Every error code with its name, the name being the header's `#define`.
pub(crate) const NAMES: [(i32, &CStr); 33] = [
    (TCOMP_OK, c"TCOMP_OK"),
    (TCOMP_ERR_NULL, c"TCOMP_ERR_NULL"),
    (TCOMP_ERR_ALIGNMENT, c"TCOMP_ERR_ALIGNMENT"),
    (TCOMP_ERR_UNINITIALISED, c"TCOMP_ERR_UNINITIALISED"),
    (TCOMP_ERR_ARGUMENT, c"TCOMP_ERR_ARGUMENT"),
    (TCOMP_ERR_INPUT_COUNT, c"TCOMP_ERR_INPUT_COUNT"),
    (TCOMP_ERR_INDEX, c"TCOMP_ERR_INDEX"),
    (TCOMP_ERR_PANIC, c"TCOMP_ERR_PANIC"),
    (TCOMP_ERR_BLOB_TRUNCATED, c"TCOMP_ERR_BLOB_TRUNCATED"),
    (TCOMP_ERR_BLOB_MAGIC, c"TCOMP_ERR_BLOB_MAGIC"),
    (TCOMP_ERR_BLOB_VERSION, c"TCOMP_ERR_BLOB_VERSION"),
    (TCOMP_ERR_BLOB_CHECKSUM, c"TCOMP_ERR_BLOB_CHECKSUM"),
    (TCOMP_ERR_BLOB_CAPACITY, c"TCOMP_ERR_BLOB_CAPACITY"),
    (TCOMP_ERR_BLOB_MALFORMED, c"TCOMP_ERR_BLOB_MALFORMED"),
    (TCOMP_ERR_BLOB_UNKNOWN_TAG, c"TCOMP_ERR_BLOB_UNKNOWN_TAG"),
    (TCOMP_ERR_BLOB_NON_FINITE, c"TCOMP_ERR_BLOB_NON_FINITE"),
    (TCOMP_ERR_BLOB_INCONSISTENT, c"TCOMP_ERR_BLOB_INCONSISTENT"),
    (TCOMP_ERR_BLOB_PROGRAM, c"TCOMP_ERR_BLOB_PROGRAM"),
    (TCOMP_ERR_BLOB_IMPLAUSIBLE, c"TCOMP_ERR_BLOB_IMPLAUSIBLE"),
    (TCOMP_ERR_BLOB_OTHER, c"TCOMP_ERR_BLOB_OTHER"),
    (TCOMP_ERR_IMAGE_NONE, c"TCOMP_ERR_IMAGE_NONE"),
    (TCOMP_ERR_IMAGE_VERSION, c"TCOMP_ERR_IMAGE_VERSION"),
    (TCOMP_ERR_IMAGE_TABLE, c"TCOMP_ERR_IMAGE_TABLE"),
    (TCOMP_ERR_IMAGE_CHECKSUM, c"TCOMP_ERR_IMAGE_CHECKSUM"),
    (TCOMP_ERR_IMAGE_MISSING, c"TCOMP_ERR_IMAGE_MISSING"),
    (TCOMP_ERR_IMAGE_BOUNDS, c"TCOMP_ERR_IMAGE_BOUNDS"),
    (TCOMP_ERR_IMAGE_ROW, c"TCOMP_ERR_IMAGE_ROW"),
    (
        TCOMP_ERR_IMAGE_UNKNOWN_CHANNEL,
        c"TCOMP_ERR_IMAGE_UNKNOWN_CHANNEL",
    ),
    (TCOMP_ERR_IMAGE_BOARD_HASH, c"TCOMP_ERR_IMAGE_BOARD_HASH"),
    (TCOMP_ERR_IMAGE_OTHER_UNIT, c"TCOMP_ERR_IMAGE_OTHER_UNIT"),
    (TCOMP_ERR_IMAGE_OTHER, c"TCOMP_ERR_IMAGE_OTHER"),
    (
        TCOMP_ERR_IMAGE_WRONG_CHANNEL,
        c"TCOMP_ERR_IMAGE_WRONG_CHANNEL",
    ),
    (
        TCOMP_ERR_IMAGE_NOT_IN_TABLE,
        c"TCOMP_ERR_IMAGE_NOT_IN_TABLE",
    ),
];

/// The name of error code `code` (`"TCOMP_ERR_BLOB_CHECKSUM"`), or `"TCOMP_ERR_UNKNOWN"` for a
/// code this library does not define.
///
/// Returns a NUL-terminated string in static storage: never NULL, never to be freed.
/// Thread safety: reads constant data only; callable from any thread or interrupt.
#[unsafe(no_mangle)]
pub extern "C" fn tcomp_error_name(code: i32) -> *const c_char {
    name_of(code).as_ptr()
}

/// The name of `code` as a `CStr` (the table's, or `TCOMP_ERR_UNKNOWN`).
pub(crate) fn name_of(code: i32) -> &'static CStr {
    NAMES
        .iter()
        .find(|(c, _)| *c == code)
        .map_or(c"TCOMP_ERR_UNKNOWN", |(_, n)| *n)
}

/// The code of a blob the core refused.
pub(crate) fn blob_code(e: &BlobError) -> i32 {
    match e {
        BlobError::Truncated => TCOMP_ERR_BLOB_TRUNCATED,
        BlobError::BadMagic => TCOMP_ERR_BLOB_MAGIC,
        BlobError::UnsupportedVersion(_) => TCOMP_ERR_BLOB_VERSION,
        BlobError::Checksum => TCOMP_ERR_BLOB_CHECKSUM,
        BlobError::CapacityExceeded => TCOMP_ERR_BLOB_CAPACITY,
        BlobError::Malformed => TCOMP_ERR_BLOB_MALFORMED,
        BlobError::UnknownTag(_) => TCOMP_ERR_BLOB_UNKNOWN_TAG,
        BlobError::NonFinite(_) => TCOMP_ERR_BLOB_NON_FINITE,
        BlobError::Inconsistent(_) => TCOMP_ERR_BLOB_INCONSISTENT,
        BlobError::Program(_) => TCOMP_ERR_BLOB_PROGRAM,
        BlobError::Implausible(_) => TCOMP_ERR_BLOB_IMPLAUSIBLE,
        _ => TCOMP_ERR_BLOB_OTHER,
    }
}

/// The code of an image (or an image entry) the core refused.
pub(crate) fn image_code(e: &ImageError) -> i32 {
    match e {
        ImageError::NoImage => TCOMP_ERR_IMAGE_NONE,
        ImageError::UnsupportedVersion(_) => TCOMP_ERR_IMAGE_VERSION,
        ImageError::BadTable => TCOMP_ERR_IMAGE_TABLE,
        ImageError::Checksum => TCOMP_ERR_IMAGE_CHECKSUM,
        ImageError::Missing => TCOMP_ERR_IMAGE_MISSING,
        ImageError::OutOfBounds => TCOMP_ERR_IMAGE_BOUNDS,
        ImageError::BadRow => TCOMP_ERR_IMAGE_ROW,
        ImageError::UnknownChannel(_) => TCOMP_ERR_IMAGE_UNKNOWN_CHANNEL,
        ImageError::BoardHash => TCOMP_ERR_IMAGE_BOARD_HASH,
        ImageError::OtherUnit => TCOMP_ERR_IMAGE_OTHER_UNIT,
        _ => TCOMP_ERR_IMAGE_OTHER,
    }
}
