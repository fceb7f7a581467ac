//! The boundary: every entry point's body runs through [`code`] (or [`value`]), and raw pointers
//! become slices only through the helpers here, each checked for NULL.
//!
//! On the host a panic inside the body (a bug: the core never panics on data, and
//! `tests/no_panic.rs` drives every entry point with arbitrary input to keep it so) is caught
//! here and returned as [`TCOMP_ERR_PANIC`](crate::TCOMP_ERR_PANIC): unwinding into C would be
//! undefined behaviour, and Rust would abort the caller's whole process at an `extern "C"`
//! boundary. A bare-metal build cannot unwind (`panic = "abort"` is the target's only strategy):
//! there the panic handler of `panic.rs` reports and stops.
#![allow(unsafe_code)] // turning C pointers into slices is this module's job

/// Runs `body`, turning a panic into `TCOMP_ERR_PANIC` (host) .
pub(crate) fn code(body: impl FnOnce() -> i32) -> i32 {
    value(crate::TCOMP_ERR_PANIC, body)
}

/// Runs `body`, returning `on_panic` if it panics (host); `body`'s result otherwise.
#[cfg(not(target_os = "none"))]
pub(crate) fn value<R>(on_panic: R, body: impl FnOnce() -> R) -> R {
    // The body's state is the caller's storage, which the entry points poison (see
    // `channel::with_channel`) when a panic left it half-updated, so asserting unwind safety
    // hands nothing broken back to the caller.
    std::panic::catch_unwind(core::panic::AssertUnwindSafe(body)).unwrap_or(on_panic)
}

/// Runs `body` (bare metal: a panic never returns, see `panic.rs`).
#[cfg(target_os = "none")]
pub(crate) fn value<R>(_on_panic: R, body: impl FnOnce() -> R) -> R {
    body()
}

/// `len` bytes at `ptr` as a slice; `None` for a NULL `ptr` with `len` > 0 (an empty slice for
/// `len` 0, whatever `ptr` is).
///
/// # Safety
/// A non-NULL `ptr` must point to `len` readable bytes that stay unchanged for `'a`.
pub(crate) unsafe fn bytes<'a>(ptr: *const u8, len: usize) -> Option<&'a [u8]> {
    if len == 0 {
        return Some(&[]);
    }
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-NULL, and the caller guarantees `len` readable bytes living for `'a`.
    Some(unsafe { core::slice::from_raw_parts(ptr, len) })
}

/// `len` writable bytes at `ptr`; `None` for a NULL `ptr` with `len` > 0.
///
/// # Safety
/// A non-NULL `ptr` must point to `len` writable bytes not otherwise borrowed for `'a`.
pub(crate) unsafe fn bytes_mut<'a>(ptr: *mut u8, len: usize) -> Option<&'a mut [u8]> {
    if len == 0 {
        return Some(&mut []);
    }
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-NULL, and the caller guarantees `len` writable, unaliased bytes for `'a`.
    Some(unsafe { core::slice::from_raw_parts_mut(ptr, len) })
}

/// `len` floats at `ptr`; `None` for a NULL or misaligned `ptr` with `len` > 0.
///
/// # Safety
/// A non-NULL `ptr` must point to `len` readable `float`s.
pub(crate) unsafe fn floats<'a>(ptr: *const f32, len: usize) -> Option<&'a [f32]> {
    if len == 0 {
        return Some(&[]);
    }
    if ptr.is_null() || !ptr.is_aligned() {
        return None;
    }
    // SAFETY: non-NULL and aligned; the caller guarantees `len` readable floats.
    Some(unsafe { core::slice::from_raw_parts(ptr, len) })
}

#[cfg(test)]
mod tests {
    #[test]
    #[allow(clippy::panic)]
    fn a_panic_in_a_body_comes_back_as_the_panic_code() {
        assert_eq!(super::code(|| panic!("a bug")), crate::TCOMP_ERR_PANIC);
        assert_eq!(super::code(|| 3), 3);
    }
}
