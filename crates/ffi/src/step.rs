//! Stepping a channel: one sample at the channel's period or after a given time step, periods
//! missed, a reset, the time since power-on. Each is one call of the core's `Channel`, with the
//! arguments checked and the output written even when the call is refused, so a caller that
//! ignores the return code still never sends an unflagged value.
#![allow(unsafe_code)] // C entry points: raw pointers in, `#[unsafe(no_mangle)]` out

use crate::channel::{self, TcompChannel};
use crate::error::{
    TCOMP_ERR_ALIGNMENT, TCOMP_ERR_ARGUMENT, TCOMP_ERR_INPUT_COUNT, TCOMP_ERR_NULL,
    TCOMP_ERR_PANIC, TCOMP_OK,
};
use crate::guard;
use crate::status::{TCOMP_STATUS_INPUT_FAULT, TCOMP_STATUS_NO_MODEL};

/// One compensated sample.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TcompOutput {
    /// `raw − correction`, in the unit of the raw value (the model's unit, e.g. deg/h or ug); the
    /// raw value itself when the status says there is no usable correction.
    pub compensated: f32,
    /// The model's estimate of the temperature-induced error, same unit (0 without a model).
    pub correction: f32,
    /// `TCOMP_STATUS_*` bits; 0 when all is well.
    pub status: u16,
}

/// One sample at the channel's period (the `period_s` it was loaded with): what a fixed-rate
/// firmware loop calls once per channel per period. Periods the loop missed are announced
/// beforehand with `tcomp_skip`.
///
/// * `ch` — an initialised channel.
/// * `inputs`, `n_inputs` — the model's input columns for this sample, in the model's order
///   (`tcomp_channel_input_name`; for an image, `tcomp_channel_wiring` says which thermometer
///   feeds each), in the columns' units (°C for the `t_*_c` thermometers `tcomp fit` was trained
///   on). Borrowed for the call. `n_inputs` must be the model's input count
///   (`tcomp_channel_input_count`); a channel without a model ignores them (NULL allowed). A
///   NaN or infinite input is a fault the step handles (flagged `TCOMP_STATUS_INPUT_FAULT`, last
///   good features held), not an error.
/// * `raw` — the sensor's raw value for this sample in the model's unit (deg/h, ug, …).
/// * `out` — where the sample goes (caller-owned).
///
/// Returns `TCOMP_OK`; `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT` or `TCOMP_ERR_UNINITIALISED`;
/// `TCOMP_ERR_INPUT_COUNT` (the channel does not advance). Whenever `out` is not NULL it is
/// written: on an error with the raw value passed through, flagged `TCOMP_STATUS_INPUT_FAULT`
/// (and `TCOMP_STATUS_NO_MODEL` for a channel that cannot be read), so no NaN or unchecked value
/// ever leaves with status 0. Bounded time, no allocation. Thread safety: `ch` must not be in use
/// elsewhere.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns; `inputs` NULL or `n_inputs`
/// readable floats; `out` NULL or a writable `tcomp_output_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_step(
    ch: *mut TcompChannel,
    inputs: *const f32,
    n_inputs: usize,
    raw: f32,
    out: *mut TcompOutput,
) -> i32 {
    // SAFETY: the caller's contracts, passed on.
    unsafe { step(ch, inputs, n_inputs, None, false, raw, out) }
}

/// One sample `dt_s` seconds after the previous one: what a host replaying a log, or a firmware
/// with its own timestamps, calls.
///
/// * `ch`, `inputs`, `n_inputs`, `raw`, `out` — as for `tcomp_step`.
/// * `dt_s` — seconds since the previous sample (ignored on the first sample after a load or a
///   reset). A `dt_s` that is not a positive finite number is a data fault, handled as a NaN input
///   is (flagged, and the time carried to the next good step).
/// * `gap` — nonzero when this sample follows a gap in the record (a logger dropout, a pause):
///   `dt_s` then spans the whole gap, and the feature program's filters are carried across it as
///   for inputs that moved linearly (the core's `Channel::mark_gap`), or restarted when the gap is
///   far longer than their time constants; zero for an ordinary sample.
///
/// Returns and writes `out` as `tcomp_step` does. Thread safety: as `tcomp_step`.
///
/// # Safety
/// As `tcomp_step`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_step_dt(
    ch: *mut TcompChannel,
    inputs: *const f32,
    n_inputs: usize,
    dt_s: f32,
    gap: bool,
    raw: f32,
    out: *mut TcompOutput,
) -> i32 {
    // SAFETY: the caller's contracts, passed on.
    unsafe { step(ch, inputs, n_inputs, Some(dt_s), gap, raw, out) }
}

/// The two steps' body: checks, then one call of the core's `Channel::step` or `step_dt`.
///
/// # Safety
/// As [`tcomp_step`].
unsafe fn step(
    ch: *mut TcompChannel,
    inputs: *const f32,
    n_inputs: usize,
    dt_s: Option<f32>,
    gap: bool,
    raw: f32,
    out: *mut TcompOutput,
) -> i32 {
    if out.is_null() || !out.is_aligned() {
        return if out.is_null() {
            TCOMP_ERR_NULL
        } else {
            TCOMP_ERR_ALIGNMENT
        };
    }
    let refused = |status: u16| TcompOutput {
        compensated: raw,
        correction: 0.0,
        status,
    };
    let (code, sample) = guard::value(
        (
            TCOMP_ERR_PANIC,
            refused(TCOMP_STATUS_NO_MODEL | TCOMP_STATUS_INPUT_FAULT),
        ),
        || {
            // SAFETY: the caller's contract for `ch`.
            unsafe {
                channel::with(
                    ch,
                    |code| {
                        (
                            code,
                            refused(TCOMP_STATUS_NO_MODEL | TCOMP_STATUS_INPUT_FAULT),
                        )
                    },
                    |state| {
                        // SAFETY: the caller's contract for `inputs`.
                        let Some(inputs) = guard::floats(inputs, n_inputs) else {
                            return (TCOMP_ERR_NULL, refused(TCOMP_STATUS_INPUT_FAULT));
                        };
                        let model = state.model.as_ref();
                        if model.is_some_and(|m| m.program.inputs.len() != inputs.len()) {
                            return (TCOMP_ERR_INPUT_COUNT, refused(TCOMP_STATUS_INPUT_FAULT));
                        }
                        let o = match dt_s {
                            None => state.channel.step(model, inputs, raw),
                            Some(dt) => {
                                if gap {
                                    state.channel.mark_gap();
                                }
                                state.channel.step_dt(model, inputs, dt, raw)
                            }
                        };
                        let sample = TcompOutput {
                            compensated: o.compensated,
                            correction: o.correction,
                            status: u16::from(o.status.0),
                        };
                        (TCOMP_OK, sample)
                    },
                )
            }
        },
    );
    // SAFETY: `out` is non-NULL and aligned (checked above) and the caller's to write.
    unsafe { out.write(sample) };
    code
}

/// `seconds` passed without a sample (timer periods the loop missed): the next `tcomp_step`
/// covers them too, as a gap across which the feature program's filters are carried (the core's
/// `Channel::skip`). Costs the ordinary samples nothing.
///
/// * `ch` — an initialised channel.
/// * `seconds` — the time missed, in seconds: finite and ≥ 0 (0 does nothing).
///
/// Returns `TCOMP_OK`, `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_UNINITIALISED` or
/// `TCOMP_ERR_ARGUMENT`. Thread safety: `ch` must not be in use elsewhere.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_skip(ch: *mut TcompChannel, seconds: f32) -> i32 {
    guard::code(|| {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return TCOMP_ERR_ARGUMENT;
        }
        // SAFETY: the caller's contract for `ch`.
        unsafe {
            channel::with(
                ch,
                |c| c,
                |s| {
                    s.channel.skip(seconds);
                    TCOMP_OK
                },
            )
        }
    })
}

/// Forgets the channel's history (the feature program's filters, the held features): the next
/// sample is treated as the first. Keeps the model, the period and the time since power-on.
///
/// Returns `TCOMP_OK`, `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT` or `TCOMP_ERR_UNINITIALISED`.
/// Thread safety: `ch` must not be in use elsewhere.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_reset(ch: *mut TcompChannel) -> i32 {
    guard::code(|| {
        // SAFETY: the caller's contract for `ch`.
        unsafe {
            channel::with(
                ch,
                |c| c,
                |s| {
                    s.channel.reset();
                    if let Some(model) = &s.model {
                        s.channel.prepare(model);
                    }
                    TCOMP_OK
                },
            )
        }
    })
}

/// Sets the time since power-on, in seconds, of the channel's next first sample (after a load
/// or a reset): where a model's `warmup(...)` feature starts counting. A firmware leaves it at 0
/// (its channels start at boot); a host replaying a log sets the time between the instrument's
/// power-on and the log's first row.
///
/// * `seconds` — finite (may be negative for a log that starts before power-on).
///
/// Returns `TCOMP_OK`, `TCOMP_ERR_NULL`, `TCOMP_ERR_ALIGNMENT`, `TCOMP_ERR_UNINITIALISED` or
/// `TCOMP_ERR_ARGUMENT`. Thread safety: `ch` must not be in use elsewhere.
///
/// # Safety
/// `ch` must be NULL or point to a `tcomp_channel_t` the caller owns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn tcomp_set_time_on(ch: *mut TcompChannel, seconds: f32) -> i32 {
    guard::code(|| {
        if !seconds.is_finite() {
            return TCOMP_ERR_ARGUMENT;
        }
        // SAFETY: the caller's contract for `ch`.
        unsafe {
            channel::with(
                ch,
                |c| c,
                |s| {
                    s.channel.set_time_on(seconds);
                    TCOMP_OK
                },
            )
        }
    })
}
