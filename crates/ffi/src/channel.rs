//! The channel storage a C caller provides, and what lives in it: the decoded model (numbers in
//! the storage, strings borrowed from the caller's blob), the core's streaming [`Channel`], why
//! the last load failed, and the image row's wiring.
//!
//! Why caller storage of a fixed size: a firmware keeps its channels in statics and must know
//! their size at compile time, with no allocator. [`TCOMP_CHANNEL_SIZE`] is a literal per pointer
//! width (cbindgen copies literals into the header, not expressions, and turns the `cfg` into an
//! `#if` on the C side's pointer width); the assertions below fail the build when the core's
//! types outgrow it — a change to the model's layout must raise it, and the header changes
//! with it.
//!
//! Why a magic word first: C storage starts as whatever the caller's memory held. Every entry
//! point but the initialisers checks the magic before it reads anything else, so a channel that
//! was never initialised is refused ([`crate::TCOMP_ERR_UNINITIALISED`]) rather than read.
#![allow(unsafe_code)] // the storage is cast to the state it holds

use crate::error::{TCOMP_ERR_ALIGNMENT, TCOMP_ERR_NULL, TCOMP_ERR_PANIC, TCOMP_ERR_UNINITIALISED};
use crate::guard;
use core::fmt;
use core::ptr::addr_of_mut;
use tcomp_core::image::ImageError;
use tcomp_core::{BlobError, Channel, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES, Model};

/// Bytes of one channel's storage (`tcomp_channel_t`) on a 32-bit target (a Cortex-M): the state
/// is about 1,940 bytes there, rounded up to a multiple of 128.
#[cfg(target_pointer_width = "32")]
pub const TCOMP_CHANNEL_SIZE: usize = 2048;
/// Bytes of one channel's storage (`tcomp_channel_t`) on a 64-bit host, where the model's borrowed
/// names are twice as wide: 2,312 bytes, rounded up to a multiple of 128.
#[cfg(target_pointer_width = "64")]
pub const TCOMP_CHANNEL_SIZE: usize = 2432;
/// Alignment, in bytes, the channel storage needs.
pub const TCOMP_CHANNEL_ALIGN: usize = 8;

/// Storage for one compensated channel: its model, its streaming state and its wiring.
///
/// Owned by the caller (a `static`, a stack variable or a member of the caller's struct), never
/// allocated by tcomp; opaque: only tcomp's functions read or write it. Initialise it with
/// `tcomp_channel_init`, `tcomp_load_blob` or `tcomp_load_image` before any other use. It may be
/// moved (copied with `memcpy`) while no call is using it; the blob or image it was loaded from
/// is borrowed, not copied, and must stay in place and unchanged while the channel is used.
///
/// Thread safety: a channel is not synchronised. Use each from one thread or interrupt at a time;
/// different channels are independent and may be used concurrently.
#[repr(C, align(8))]
pub struct TcompChannel {
    opaque: [u8; TCOMP_CHANNEL_SIZE],
}

/// A model at the reference firmware's capacities, its strings borrowed from the caller's blob.
pub(crate) type FfiModel = Model<'static, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>;
/// The core's streaming state of one channel.
pub(crate) type FfiChannel = Channel<FLIGHT_NODES, FLIGHT_FEATURES>;

/// Marks initialised storage.
const MAGIC: u32 = u32::from_le_bytes(*b"TCch");

/// Why a channel has no model.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Failure {
    /// Loaded, or initialised without a model on purpose.
    None,
    /// The blob was refused.
    Blob(BlobError),
    /// The image, or the channel's entry in it, was refused.
    Image(ImageError),
    /// The image is not for the board description the caller expects.
    OtherBoard,
    /// The image's table has no row for the channel id.
    NotInTable,
    /// The blob does not belong on its channel's row (sensor, axis, unit, inputs).
    WrongChannel,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::None => f.write_str("ok"),
            Self::Blob(e) => write!(f, "blob refused: {e}"),
            Self::Image(e) => write!(f, "image refused: {e}"),
            Self::OtherBoard => f.write_str("image refused: made for another board description"),
            Self::NotInTable => f.write_str("image refused: no row for this channel id"),
            Self::WrongChannel => f.write_str(
                "image refused: the blob's sensor, axis, unit or inputs are not its row's",
            ),
        }
    }
}

/// The channel row's wiring, copied at load from a version-2 image.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Row {
    pub(crate) id: u16,
    pub(crate) source: (u8, u8),
    pub(crate) scale: f32,
    /// For each model input, its thermometer on the board.
    pub(crate) thermometer: [u8; tcomp_core::MAX_INPUTS],
}

/// What a [`TcompChannel`] holds.
#[repr(C)]
pub(crate) struct State {
    /// [`MAGIC`] once initialised; first, so it is read before anything else.
    magic: u32,
    pub(crate) failure: Failure,
    pub(crate) model: Option<FfiModel>,
    pub(crate) channel: FfiChannel,
    pub(crate) row: Option<Row>,
}

const _: () = assert!(
    size_of::<State>() <= TCOMP_CHANNEL_SIZE,
    "a channel's state outgrew TCOMP_CHANNEL_SIZE: raise it (the header changes with it)"
);
const _: () = assert!(
    align_of::<State>() <= TCOMP_CHANNEL_ALIGN && align_of::<TcompChannel>() == TCOMP_CHANNEL_ALIGN,
    "a channel's state needs a larger alignment than TCOMP_CHANNEL_ALIGN"
);

/// The bytes of the state actually used on this target (for the README and the tests).
pub const STATE_SIZE: usize = size_of::<State>();

/// Initialises the storage at `ch` as a channel sampled every `period_s` seconds without a model,
/// field by field in place (no state is built on the stack and moved: a model is 1.5 KB), and
/// returns it. `Err` with a code for a NULL or misaligned pointer.
///
/// # Safety
/// A non-NULL `ch` must point to a `TcompChannel` the caller owns and no one else uses now.
pub(crate) unsafe fn init<'a>(ch: *mut TcompChannel, period_s: f32) -> Result<&'a mut State, i32> {
    let p = checked(ch)?;
    // SAFETY: `p` is non-NULL, aligned for `State` (asserted above) and points to
    // TCOMP_CHANNEL_SIZE ≥ size_of::<State>() bytes the caller owns; every field is written
    // before the reference is made.
    unsafe {
        addr_of_mut!((*p).failure).write(Failure::None);
        addr_of_mut!((*p).model).write(None);
        addr_of_mut!((*p).channel).write(FfiChannel::new(period_s));
        addr_of_mut!((*p).row).write(None);
        addr_of_mut!((*p).magic).write(MAGIC);
        Ok(&mut *p)
    }
}

/// Runs `body` on the initialised channel at `ch` under the panic guard; a panic poisons the
/// storage (it may be half-updated), so later calls are refused until it is initialised again.
///
/// # Safety
/// A non-NULL `ch` must point to a `TcompChannel` the caller owns and no one else uses now.
pub(crate) unsafe fn with<R>(
    ch: *mut TcompChannel,
    on_error: impl FnOnce(i32) -> R,
    body: impl FnOnce(&mut State) -> R,
) -> R {
    let p = match checked(ch) {
        Ok(p) => p,
        Err(code) => return on_error(code),
    };
    // SAFETY: non-NULL and aligned; the storage is at least 4 bytes, so its first word can be
    // read whatever it holds.
    if unsafe { p.cast::<u32>().read() } != MAGIC {
        return on_error(TCOMP_ERR_UNINITIALISED);
    }
    let mut finished = false;
    let result = guard::value(None, || {
        // SAFETY: the magic says an initialiser wrote every field; the caller guarantees
        // exclusive use for the duration of the call.
        let r = body(unsafe { &mut *p });
        finished = true;
        Some(r)
    });
    match result {
        Some(r) if finished => r,
        _ => {
            // SAFETY: as above; only the magic word is written.
            unsafe { p.cast::<u32>().write(0) };
            on_error(TCOMP_ERR_PANIC)
        }
    }
}

/// `ch` as a state pointer, or the code for NULL or a misaligned pointer.
fn checked(ch: *mut TcompChannel) -> Result<*mut State, i32> {
    if ch.is_null() {
        return Err(TCOMP_ERR_NULL);
    }
    if !(ch as usize).is_multiple_of(TCOMP_CHANNEL_ALIGN) {
        return Err(TCOMP_ERR_ALIGNMENT);
    }
    Ok(ch.cast::<State>())
}
