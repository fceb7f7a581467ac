//! One evaluation function per stateful or non-trivial operation, the state each needs, and the same
//! operations as stand-alone streaming filters.
//!
//! Why here and generic: [`crate::stream`] runs a program's nodes through these functions in `f32`
//! on the board, and the simulator computes its bias effects (a lagging element, a rate, a
//! hysteresis) through the very same functions in `f64` via [`Lag`], [`Rate`] and [`Hyst`], so the
//! truth it writes is the language's definition, not a copy of it (see the table in
//! [`crate::lang`]).
//!
//! Lags are kept as the *difference* between their input and their output (`e = x − L`), which
//! stays small, rather than as `L` itself: at 200 Hz a lag's per-sample increment is ~10⁻⁴ of a
//! temperature of tens of degrees, below f32 resolution, and a lag stored as `L` drifts by rounding
//! bias (a 0.1 % rate error, measured). In difference form `e[n] = (e[n−1] + Δx)·d` with
//! `d = e^(−Δt/τ)`, which is the same recurrence exactly in real arithmetic.

use crate::Real;

/// State of one stateful operation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Slot<S> {
    /// The operand's previous value.
    prev: S,
    /// `x − L1` (`lag`, `rate`); the ±1/0 state of `hyst`.
    e1: S,
    /// `L1 − L2` (`rate`).
    e2: S,
    /// `e^(−Δt/τ)`.
    decay: S,
    /// `rate` output gain `60·(e^(Δt/τ) − 1)/Δt`.
    gain: S,
}

impl<S: Real> Slot<S> {
    /// A slot before the first sample.
    pub const EMPTY: Self = Self {
        prev: S::ZERO,
        e1: S::ZERO,
        e2: S::ZERO,
        decay: S::ZERO,
        gain: S::ZERO,
    };

    /// The coefficients for samples `dt` apart of a lag with time constant `tau` — `lag(x, tau_s)`,
    /// or with `is_rate` each of `rate(x, window_s)`'s two lags (`tau = window_s / 2`) and its
    /// output gain.
    #[inline]
    pub fn set_coefficients(&mut self, tau: S, dt: S, is_rate: bool) {
        let h = dt / tau;
        self.decay = (-h).exp();
        self.gain = if is_rate {
            S::from_f32(60.0) * h.exp_m1() / dt
        } else {
            S::ZERO
        };
    }

    /// The time constant of `rate`'s lags for a window of `window_s` seconds.
    #[inline]
    pub fn rate_tau(window_s: S) -> S {
        S::from_f32(0.5) * window_s
    }
}

/// `clamp(v, lo, hi)`.
#[inline(always)]
pub fn clamp<S: Real>(v: S, lo: S, hi: S) -> S {
    if v < lo {
        lo
    } else if v > hi {
        hi
    } else {
        v
    }
}

/// `rate(v)` for one sample, the slot's coefficients set; `first` restarts it.
#[inline(always)]
pub fn rate<S: Real>(s: &mut Slot<S>, v: S, first: bool) -> S {
    // (Re)start from the input; also heals a state that a non-finite first value left.
    if first || !s.prev.is_finite() {
        *s = Slot {
            prev: v,
            e1: S::ZERO,
            e2: S::ZERO,
            ..*s
        };
        return S::ZERO;
    }
    // A non-finite operand (say 0/0 upstream) must not poison the filter: hold.
    if v.is_finite() {
        let dx = v - s.prev;
        let e1 = (s.e1 + dx) * s.decay;
        let dl1 = dx - (e1 - s.e1);
        s.e2 = (s.e2 + dl1) * s.decay;
        s.e1 = e1;
        s.prev = v;
    }
    s.e2 * s.gain
}

/// `lag(v)` for one sample, the slot's coefficients set; `first` restarts it.
#[inline(always)]
pub fn lag<S: Real>(s: &mut Slot<S>, v: S, first: bool) -> S {
    if first || !s.prev.is_finite() {
        *s = Slot {
            prev: v,
            e1: S::ZERO,
            ..*s
        };
    } else if v.is_finite() {
        s.e1 = (s.e1 + (v - s.prev)) * s.decay;
        s.prev = v;
    }
    s.prev - s.e1
}

/// `hyst(v, threshold)` for one sample; `first` restarts it.
#[inline(always)]
pub fn hyst<S: Real>(s: &mut Slot<S>, v: S, threshold: S, first: bool) -> S {
    if first {
        s.e1 = S::ZERO;
    }
    if v > threshold {
        s.e1 = S::ONE;
    } else if v < -threshold {
        s.e1 = -S::ONE;
    }
    s.e1
}

/// A stand-alone filter: one stateful operation with its parameter, stepped with its own `dt`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Filter<S> {
    param: S,
    slot: Slot<S>,
    /// The Δt the coefficients were computed for; NaN when none.
    coef_dt: S,
    started: bool,
}

impl<S: Real> Filter<S> {
    fn new(param: S) -> Self {
        Self {
            param,
            slot: Slot::EMPTY,
            coef_dt: S::NAN,
            started: false,
        }
    }

    /// Whether this is the first sample; sets the coefficients for `dt` (ignored on the first)
    /// when `dt` changed.
    fn advance(&mut self, dt: S, is_rate: bool) -> bool {
        let first = !self.started;
        if !first && dt != self.coef_dt {
            let tau = if is_rate {
                Slot::rate_tau(self.param)
            } else {
                self.param
            };
            self.slot.set_coefficients(tau, dt, is_rate);
            self.coef_dt = dt;
        }
        self.started = true;
        first
    }
}

/// `lag(x, tau_s)` as a stand-alone filter (the simulator's lagging elements).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lag<S = f64>(Filter<S>);

impl<S: Real> Lag<S> {
    /// A lag with time constant `tau_s` seconds.
    pub fn new(tau_s: S) -> Self {
        Self(Filter::new(tau_s))
    }

    /// Feeds `x` after `dt` seconds (ignored on the first sample); returns the lagged value.
    pub fn step(&mut self, x: S, dt: S) -> S {
        let first = self.0.advance(dt, false);
        lag(&mut self.0.slot, x, first)
    }
}

/// `rate(x, window_s)` as a stand-alone filter: units per minute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rate<S = f64>(Filter<S>);

impl<S: Real> Rate<S> {
    /// A rate with the given window in seconds.
    pub fn new(window_s: S) -> Self {
        Self(Filter::new(window_s))
    }

    /// Feeds `x` after `dt` seconds (ignored on the first sample); returns the rate per minute.
    pub fn step(&mut self, x: S, dt: S) -> S {
        let first = self.0.advance(dt, true);
        rate(&mut self.0.slot, x, first)
    }
}

/// `hyst(x, threshold)` as a stand-alone filter: +1, −1, or 0 before either.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hyst<S = f64> {
    threshold: S,
    slot: Slot<S>,
}

impl<S: Real> Hyst<S> {
    /// A hysteresis with the given threshold.
    pub fn new(threshold: S) -> Self {
        Self {
            threshold,
            slot: Slot::EMPTY,
        }
    }

    /// Feeds `x`; returns the state.
    pub fn step(&mut self, x: S) -> S {
        hyst(&mut self.slot, x, self.threshold, false)
    }
}
