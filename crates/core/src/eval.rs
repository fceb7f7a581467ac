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
//!
//! # Across a gap
//! A gap — a logger dropout, a run of periods the board missed — is a step of `Δ = k·δ` seconds
//! where the filter has been running at a nominal step `δ`. Stepping once with the coefficients
//! of `Δ` would assume the input jumped to its new value at the start of the gap and stayed there
//! (a zero-order hold), which for a gap of one time constant gets a lag's state wrong by a third
//! of the input's change. What is right for a first-order system is to advance it exactly under
//! the assumption the data allow: the input moved linearly between the samples on both sides
//! (a first-order hold). [`lag_gap`] and [`rate_gap`] do that *for the filter the program runs*,
//! i.e. they give in closed form what `k` nominal steps would give over the linearly interpolated
//! input, so a gap costs the same few operations whatever its length, and where the input really
//! was linear the state after the gap is the gap-free run's (tested). With `p = (x[n] − x[n−1])/k`
//! the input's change per nominal step, `d = e^(−δ/τ)`, `D = d^k` and `a = p·d/(1 − d)` the
//! steady error of the lag on that ramp:
//!
//! * `lag`: `e ← D·e + a·(1 − D)`. For `δ → 0` this is the continuous lag's exact response to a
//!   linear input, `e ← e^(−Δ/τ)·e + s·τ·(1 − e^(−Δ/τ))` with `s` the slope.
//! * `rate`: its two cascaded lags share `τ`, so the second one sees the first one's transient
//!   through the repeated pole: `e1 ← D·e1 + a·(1 − D)` and
//!   `e2 ← D·e2 + a·(1 − D) + (e1 − a)·k·(1 − d)·D` (continuous limit: `(Δ/τ)·e^(−Δ/τ)`). The
//!   output gain stays the nominal step's: it turns the lag difference into a slope per minute, a
//!   property of the filter, not of the gap (on a ramp the rate is `60·s` after the gap as before).
//! * `hyst` has no time in it: it keeps its state.
//! * `warmup` counts the gap's seconds like any others.
//!
//! Each filter assumes its *own operand* moved linearly: exact for a filter of the inputs (or of
//! sums and products of constants with them); a filter of a filter (`rate(lag(x, τ))`) sees an
//! operand that curved across the gap, and carries it to first order only.
//!
//! `D` is `d^k` by repeated squaring when `k` is a whole number (the board: `k` missed periods
//! plus one), exactly the gap-free run's decay; otherwise `e^(−Δ/τ)`. A gap with `k = 1` is an
//! ordinary step: the formulas reduce to the recurrences above.

use crate::Real;

/// State of one stateful operation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Slot<S> {
    /// The operand's previous value.
    prev: S,
    /// `x − L1` (`lag`, `rate`); the ±1/0 state of `hyst`; the clock's rounding compensation
    /// (`warmup`, which keeps its clock, seconds since power-on, in `prev`).
    e1: S,
    /// `L1 − L2` (`rate`).
    e2: S,
    /// `e^(−Δt/τ)`.
    decay: S,
    /// `rate` output gain `60·(e^(Δt/τ) − 1)/Δt`; `warmup`'s step `Δt`.
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

    /// `e^(−Δt/τ)` at the nominal step.
    #[inline]
    pub fn decay(&self) -> S {
        self.decay
    }

    /// The step a `warmup` clock advances by.
    #[inline]
    pub fn clock_step(&self) -> S {
        self.gain
    }

    /// The step `dt` of a `warmup` clock.
    #[inline]
    pub fn set_clock_step(&mut self, dt: S) {
        self.gain = dt;
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

/// `d^k` for a gap of `k = Δ/δ` nominal steps of a filter with time constant `tau` and nominal decay
/// `d` (see the module doc): by repeated squaring when `k` is whole, else `e^(−Δ/τ)`.
#[inline]
pub fn gap_decay<S: Real>(d: S, tau: S, steps: S, dt: S) -> S {
    match steps.whole() {
        Some(m) => {
            let (mut base, mut m, mut acc) = (d, m, S::ONE);
            while m > 0 {
                if m & 1 == 1 {
                    acc = acc * base;
                }
                base = base * base;
                m >>= 1;
            }
            acc
        }
        None => (-(dt / tau)).exp(),
    }
}

/// The lag's steady error `a = p·d/(1 − d)` on a ramp rising `dx` over `steps` nominal steps;
/// `None` when `d` rounds to 1 (a time constant so long against the step that nothing decays).
#[inline]
fn ramp_error<S: Real>(d: S, dx: S, steps: S) -> Option<S> {
    let one_minus_d = S::ONE - d;
    (one_minus_d > S::ZERO).then(|| dx / steps * d / one_minus_d)
}

/// `lag(v)` for the sample after a gap of `steps` nominal steps, `big_d` = [`gap_decay`] (see the
/// module doc); the slot's coefficients are the nominal step's.
pub fn lag_gap<S: Real>(s: &mut Slot<S>, v: S, big_d: S, steps: S) -> S {
    if !s.prev.is_finite() {
        return lag(s, v, true);
    }
    if v.is_finite() {
        let dx = v - s.prev;
        s.e1 = match ramp_error(s.decay, dx, steps) {
            Some(a) => big_d * s.e1 + a * (S::ONE - big_d),
            None => s.e1 + dx,
        };
        s.prev = v;
    }
    s.prev - s.e1
}

/// `rate(v)` for the sample after a gap of `steps` nominal steps, `big_d` = [`gap_decay`] of its
/// lags (see the module doc); the slot's coefficients are the nominal step's.
pub fn rate_gap<S: Real>(s: &mut Slot<S>, v: S, big_d: S, steps: S) -> S {
    if !s.prev.is_finite() {
        return rate(s, v, true);
    }
    if v.is_finite() {
        let dx = v - s.prev;
        match ramp_error(s.decay, dx, steps) {
            Some(a) => {
                let forced = a * (S::ONE - big_d);
                let e1 = big_d * s.e1 + forced;
                let repeated = (s.e1 - a) * steps * (S::ONE - s.decay) * big_d;
                s.e2 = big_d * s.e2 + forced + repeated;
                s.e1 = e1;
            }
            // Nothing decays: the first lag's error takes the whole change, the second is still.
            None => s.e1 = s.e1 + dx,
        }
        s.prev = v;
    }
    s.e2 * s.gain
}

/// `warmup(tau_s)` for one sample: `e^(−t_on/τ)`, `t_on` the clock (seconds since power-on). The
/// first sample sets the clock to `start`; later ones advance it by `advance` seconds (the step, or
/// a gap's length), with compensated summation so that hours of 5 ms steps add up in f32 to
/// within a microsecond-scale rounding rather than drifting by the steps' rounding.
#[inline]
pub fn warmup<S: Real>(s: &mut Slot<S>, tau: S, advance: S, start: S, first: bool) -> S {
    if first {
        s.prev = start;
        s.e1 = S::ZERO;
    } else {
        // Kahan: `e1` holds the low-order part the last addition lost (negated).
        let y = advance - s.e1;
        let t = s.prev + y;
        s.e1 = (t - s.prev) - y;
        s.prev = t;
    }
    (-(s.prev / tau)).exp()
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
