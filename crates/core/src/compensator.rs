//! The compensator: one channel's streaming state, driven by an immutable model.
//!
//! `compensated = raw − f(features)`, with a [`Status`] word that says how far the output can be
//! trusted. The model is passed to every step rather than owned, so one model can drive several
//! channels, a channel can run with no model at all (raw passed through, flagged), and swapping in a
//! newly flashed model is an assignment. Bad data never panics:
//!
//! * a NaN/infinite input or a bad time step: the program state is not advanced, the last good
//!   features are held, the sample is flagged [`Status::INPUT_FAULT`], and the skipped time is carried
//!   into the next good step so rates and lags stay on the clock;
//! * a feature outside the range seen in training: flagged [`Status::OUT_OF_RANGE`]; the Gaussians see
//!   it clamped to that range (they were fitted only inside it), while the linear term sees it clamped
//!   to the range widened by one span on each side, so a trend keeps extrapolating somewhat beyond
//!   the trained envelope (what the linear term is for) but never without bound;
//! * no model: the raw value passes through, flagged [`Status::NO_MODEL`];
//! * a correction that is not finite, or a `raw − correction` that overflows, for a finite raw value:
//!   the raw value passes through, flagged [`Status::MODEL_FAULT`]. A decoded model cannot do this
//!   inside its range box (see [`crate::bound`]); the check makes "never NaN with status OK" hold
//!   whatever the model.
//!
//! Time that passes without a sample (the board missed timer periods) is a gap:
//! [`Channel::skip`] adds it to the next step, which carries the feature program's filters
//! across it (see [`ProgramState::step_gap`]) instead of treating it as one ordinary period.
//!
//! A channel may refresh its correction less often than it samples
//! ([`Channel::with_model_interval`]): thermal features move on time scales of seconds to hours, so
//! a correction evaluated every k-th sample and held in between differs from the per-sample one by
//! far less than the sensor noise, while the feature program still runs every sample (rates and lags
//! stay exact). With several channels the refreshes are staggered by `phase`, so one loop iteration
//! evaluates one model instead of all of them. The default is every sample.

use crate::blob::Model;
use crate::stream::ProgramState;

/// Status word of one compensated sample: a set of flags, zero when all is well.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status(pub u8);

impl Status {
    /// Model present, inputs good and inside the trained range.
    pub const OK: Status = Status(0);
    /// No valid model: the output is the raw value.
    pub const NO_MODEL: Status = Status(1);
    /// A feature was outside its trained range and was clamped.
    pub const OUT_OF_RANGE: Status = Status(2);
    /// An input was NaN/infinite (or the raw value was): last good features held.
    pub const INPUT_FAULT: Status = Status(4);
    /// The model's correction (or `raw − correction`) was not finite for a finite raw value: the raw
    /// value is passed through. Bits 8 and 16 are the firmware's own flags, hence 32.
    pub const MODEL_FAULT: Status = Status(32);

    /// True when no flag is set.
    pub fn is_ok(self) -> bool {
        self.0 == 0
    }

    /// True when every flag of `other` is set in `self`.
    pub fn contains(self, other: Status) -> bool {
        self.0 & other.0 == other.0
    }

    /// `self` with the flags of `other` added.
    #[must_use]
    pub fn with(self, other: Status) -> Status {
        Status(self.0 | other.0)
    }
}

impl core::fmt::Display for Status {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.is_ok() {
            return write!(f, "ok");
        }
        let names = [
            (Status::NO_MODEL, "no-model"),
            (Status::OUT_OF_RANGE, "out-of-range"),
            (Status::INPUT_FAULT, "input-fault"),
            (Status::MODEL_FAULT, "model-fault"),
        ];
        let mut first = true;
        for (flag, name) in names {
            if self.contains(flag) {
                write!(f, "{}{name}", if first { "" } else { "+" })?;
                first = false;
            }
        }
        Ok(())
    }
}

/// One compensated sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// `raw − correction`.
    pub compensated: f32,
    /// The model's estimate of the temperature-induced error (0 without a model or features).
    pub correction: f32,
    /// How far to trust it.
    pub status: Status,
}

/// Streaming state of one channel: feature-program state, the last good features, the sample period.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel<const N: usize, const F: usize> {
    state: ProgramState<N>,
    features: [f32; F],
    have_features: bool,
    pending_dt: f32,
    period_s: f32,
    /// Refresh the correction every this many samples (≥ 1).
    model_interval: u16,
    /// On which sample of the interval.
    model_phase: u16,
    /// Samples since the interval started.
    tick: u16,
    /// The correction last evaluated, and whether there is one.
    held: Option<f32>,
}

impl<const N: usize, const F: usize> Channel<N, F> {
    /// A channel sampled every `period_s` seconds (used by [`Channel::step`]).
    pub const fn new(period_s: f32) -> Self {
        Self {
            state: ProgramState::new(),
            features: [0.0; F],
            have_features: false,
            pending_dt: 0.0,
            period_s,
            model_interval: 1,
            model_phase: 0,
            tick: 0,
            held: None,
        }
    }

    /// The same channel refreshing its correction every `interval` samples (at least 1), on sample
    /// `phase % interval` of each interval, holding it in between (see the module doc).
    #[must_use]
    pub const fn with_model_interval(mut self, interval: u16, phase: u16) -> Self {
        let interval = if interval == 0 { 1 } else { interval };
        self.model_interval = interval;
        self.model_phase = phase % interval;
        self
    }

    /// Forgets all history (when a new model is loaded); keeps the period, the model interval and
    /// the time since power-on of the start ([`Channel::set_time_on`]).
    pub fn reset(&mut self) {
        let time_on = self.state.time_on();
        *self = Self::new(self.period_s).with_model_interval(self.model_interval, self.model_phase);
        self.state.set_time_on(time_on);
    }

    /// Sets the time since power-on, seconds, of the channel's first sample (default 0, the
    /// board's boot): where `warmup`'s clock starts (see [`ProgramState::set_time_on`]).
    pub fn set_time_on(&mut self, seconds: f32) {
        self.state.set_time_on(seconds);
    }

    /// `seconds` passed without a sample (periods the board missed): the next step covers them
    /// too, as a gap across which the feature program's filters are carried
    /// ([`ProgramState::step_gap`]). Costs the ordinary samples nothing.
    pub fn skip(&mut self, seconds: f32) {
        if seconds > 0.0 {
            self.pending_dt += seconds;
            self.state.mark_gap();
        }
    }

    /// The next step follows a gap (its `dt` is the whole gap, longer than the channel's usual
    /// step): the host's way of replaying a record with dropouts as [`Channel::skip`] does on the
    /// board.
    pub fn mark_gap(&mut self) {
        self.state.mark_gap();
    }

    /// Readies the channel for `model` at its period: the feature program's filter coefficients
    /// are computed now instead of on the second sample (see [`ProgramState::prepare`]); the
    /// outputs are the same.
    pub fn prepare<const C: usize>(&mut self, model: &Model<'_, C, F, N>) {
        self.state.prepare(&model.program, self.period_s);
    }

    /// The last good (unclamped) features.
    pub fn features(&self) -> &[f32; F] {
        &self.features
    }

    /// One sample at the channel's fixed period.
    pub fn step<const C: usize>(
        &mut self,
        model: Option<&Model<'_, C, F, N>>,
        inputs: &[f32],
        raw: f32,
    ) -> Output {
        self.step_dt(model, inputs, self.period_s, raw)
    }

    /// One sample, `dt` seconds after the previous one.
    pub fn step_dt<const C: usize>(
        &mut self,
        model: Option<&Model<'_, C, F, N>>,
        inputs: &[f32],
        dt: f32,
        raw: f32,
    ) -> Output {
        let Some(model) = model else {
            return Output {
                compensated: raw,
                correction: 0.0,
                status: Status::NO_MODEL,
            };
        };
        let mut status = Status::OK;
        let dt_total = self.pending_dt + dt;
        let stepped = self.state.step(&model.program, inputs, dt_total);
        match stepped.and_then(|()| self.state.features(&model.program, &mut self.features)) {
            Ok(()) => {
                self.have_features = true;
                self.pending_dt = 0.0;
            }
            Err(_) => {
                status = status.with(Status::INPUT_FAULT);
                if stepped.is_err() && dt.is_finite() && dt > 0.0 {
                    self.pending_dt = dt_total;
                } else {
                    self.pending_dt = 0.0;
                }
            }
        }
        if !raw.is_finite() {
            status = status.with(Status::INPUT_FAULT);
        }
        if !self.have_features {
            return Output {
                compensated: raw,
                correction: 0.0,
                status: status.with(Status::INPUT_FAULT),
            };
        }
        let mut x_gauss = self.features;
        let mut x_linear = self.features;
        for ((g, l), r) in x_gauss
            .iter_mut()
            .zip(x_linear.iter_mut())
            .zip(&model.ranges)
        {
            let span = r.hi - r.lo;
            if *g < r.lo {
                *g = r.lo;
                *l = if *l < r.lo - span { r.lo - span } else { *l };
                status = status.with(Status::OUT_OF_RANGE);
            } else if *g > r.hi {
                *g = r.hi;
                *l = if *l > r.hi + span { r.hi + span } else { *l };
                status = status.with(Status::OUT_OF_RANGE);
            }
        }
        let due = self.tick == self.model_phase;
        self.tick = if self.tick + 1 >= self.model_interval {
            0
        } else {
            self.tick + 1
        };
        let correction = match self.held {
            Some(held) if !due => held,
            _ => {
                let c = model.rbf.eval_split(&x_gauss, &x_linear);
                self.held = Some(c);
                c
            }
        };
        let compensated = raw - correction;
        // One check per sample: a finite raw value never leaves as NaN or ±inf. Decoding refuses a
        // model whose correction could overflow in its range box, so this is the last line.
        if !compensated.is_finite() && raw.is_finite() {
            return Output {
                compensated: raw,
                correction: 0.0,
                status: status.with(Status::MODEL_FAULT),
            };
        }
        Output {
            compensated,
            correction,
            status,
        }
    }
}
