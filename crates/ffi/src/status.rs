//! The status word of a compensated sample, for C: the bits as `#define`s (the values of the
//! core's one table, [`tcomp_core::frame::status`], checked at compile time) and their names
//! through the same table.
//!
//! The word is 16 bits wide, as in the output frame: the core sets the low bits below; a C
//! firmware may add its own loop and board bits (sensor error, stuck, overrun, …) in the places
//! the frame defines, and [`tcomp_status_describe`] names those too.
#![allow(unsafe_code)] // the C entry point reads a caller's buffer

use crate::guard;
use crate::out::CBuf;
use core::ffi::c_char;
use core::fmt::Write;
use tcomp_core::frame::status;

/// Model present, inputs good and inside the trained range.
pub const TCOMP_STATUS_OK: u16 = 0;
/// No valid model: the output is the raw value.
pub const TCOMP_STATUS_NO_MODEL: u16 = 1;
/// A feature was outside its trained range and was clamped.
pub const TCOMP_STATUS_OUT_OF_RANGE: u16 = 2;
/// An input or the raw value was NaN/infinite, or the time step was bad: the last good features
/// are held (the raw value passes through while there are none).
pub const TCOMP_STATUS_INPUT_FAULT: u16 = 4;
/// The model's correction was not finite for a finite raw value: the raw value passes through.
pub const TCOMP_STATUS_MODEL_FAULT: u16 = 32;

const _: () = assert!(
    TCOMP_STATUS_OK == status::OK
        && TCOMP_STATUS_NO_MODEL == status::NO_MODEL
        && TCOMP_STATUS_OUT_OF_RANGE == status::OUT_OF_RANGE
        && TCOMP_STATUS_INPUT_FAULT == status::INPUT_FAULT
        && TCOMP_STATUS_MODEL_FAULT == status::MODEL_FAULT,
    "the header's status bits must be the core's"
);

/// Writes the names of the set bits of `status`, lowest bit first, joined by `+`
/// (`"no-model+input-fault"`; `"ok"` for 0; a bit without a name as `bit<n>`), from the core's
/// table of status names, which also names the firmware's loop and board bits.
///
/// * `status` — a status word (the `status` of a `tcomp_output_t`, possibly with the firmware's own
///   bits added).
/// * `buf` — where the text goes, owned by the caller; may be NULL when `buf_len` is 0. At most
///   `buf_len` bytes are written, always NUL-terminated when `buf_len` > 0 (truncated if need be).
/// * `buf_len` — bytes available at `buf`.
///
/// Returns the length of the whole text without its NUL (`snprintf`-style: a result ≥ `buf_len`
/// means it was truncated), or `TCOMP_ERR_NULL` when `buf` is NULL and `buf_len` > 0.
/// Thread safety: reentrant; touches only `buf`. 160 bytes hold any word.
///
/// # Safety
/// `buf` must be NULL or point to `buf_len` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_status_describe(
    status: u16,
    buf: *mut c_char,
    buf_len: usize,
) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract: `buf` is NULL or `buf_len` writable bytes.
        let Some(buf) = (unsafe { guard::bytes_mut(buf.cast(), buf_len) }) else {
            return crate::TCOMP_ERR_NULL;
        };
        let mut w = CBuf::new(buf);
        describe(&mut w, status);
        i32::try_from(w.finish()).unwrap_or(i32::MAX)
    })
}

/// The names of `word`'s bits through the core's table.
fn describe(w: &mut CBuf<'_>, word: u16) {
    if word == 0 {
        let _ = w.write_str("ok");
        return;
    }
    let mut first = true;
    status::for_each_name(word, |name| {
        if !first {
            let _ = w.write_str("+");
        }
        first = false;
        let _ = match name {
            Ok(n) => w.write_str(n),
            Err(bit) => write!(w, "bit{bit}"),
        };
    });
}
