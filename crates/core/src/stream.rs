//! Running a feature program sample by sample: the streaming state apart from the program.
//!
//! [`ProgramState`] holds one value per node and the state slots of `rate`, `lag` and `hyst`; the
//! [`Program`] itself stays immutable, so one program serves many channels and `reset` is trivial.
//! Filter coefficients depend on the time step; they are recomputed only when `Δt` changes, so a
//! fixed-rate loop pays for the exponentials once. The exact discrete-time definitions are in the
//! table of [`crate::lang`]; each operation's evaluation is a function of [`crate::eval`].
//!
//! Generic over the number type ([`Real`]): the board runs `ProgramState<N>` (f32), the simulator
//! `ProgramState<N, f64>` over the same code.
//!
//! A gap in the samples (a logger dropout, periods the board missed) is a step the caller marks
//! ([`ProgramState::step_gap`], or [`ProgramState::mark_gap`] before an ordinary step): the
//! filters are carried across it exactly for an input that moved linearly (see [`crate::eval`]),
//! without touching the nominal step's coefficients, so the sample after the gap costs a few
//! operations per filter and the one after that none extra. The branch to the gap's code sits
//! inside the test for a changed time step that every step makes anyway, so a fixed-rate loop
//! pays nothing for it on ordinary samples. A gap longer than [`RESET_AFTER_TIME_CONSTANTS`] times
//! the program's longest time constant restarts the filters instead ([`gap_resets`]): after
//! 5 τ a first-order state has forgotten 99.3 % of its past, so carrying it on would assume the
//! input was linear over a stretch the filters no longer remember — a guess, not a measurement.
//! The clock of `warmup` (seconds since power-on) is never restarted by a gap.

use crate::eval::{self, Slot};
use crate::program::{Op, Program};
use crate::{MAX_STATEFUL, Real};

/// A gap longer than this many of the program's longest time constant restarts its filters
/// (see the module doc): `e^(−5) = 0.7 %` of the state before it would be left.
pub const RESET_AFTER_TIME_CONSTANTS: f32 = 5.0;

/// Whether a gap of `gap_s` seconds restarts `program`'s filters rather than carrying them: longer
/// than [`RESET_AFTER_TIME_CONSTANTS`] times its longest time constant
/// ([`Program::longest_time_constant`]). A program without `lag` or `rate` carries every gap.
pub fn gap_resets<const N: usize, const F: usize, S: Real>(
    program: &Program<'_, N, F, S>,
    gap_s: S,
) -> bool {
    let longest = program.longest_time_constant();
    longest > S::ZERO && gap_s > S::from_f32(RESET_AFTER_TIME_CONSTANTS) * longest
}

/// Why a sample could not advance the program. The state is left untouched in every case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StepError {
    /// Fewer inputs than the program reads.
    MissingInput {
        /// The first missing input index.
        index: u8,
    },
    /// An input is NaN or infinite.
    NonFiniteInput {
        /// The input's index in [`Program::inputs`].
        index: u8,
    },
    /// The time step is not a positive finite number of seconds.
    BadTimeStep,
    /// A feature came out NaN or infinite (e.g. a division by zero).
    NonFiniteFeature {
        /// The feature index.
        feature: u8,
    },
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::MissingInput { index } => write!(f, "input {index} is missing"),
            Self::NonFiniteInput { index } => write!(f, "input {index} is NaN or infinite"),
            Self::BadTimeStep => write!(f, "the time step is not a positive finite number"),
            Self::NonFiniteFeature { feature } => write!(f, "feature {feature} is NaN or infinite"),
        }
    }
}

/// Streaming state of one channel's feature program with up to `N` nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramState<const N: usize, S = f32> {
    values: [S; N],
    slots: [Slot<S>; MAX_STATEFUL],
    /// The Δt the slot coefficients were computed for; NaN when none.
    coef_dt: S,
    /// Seconds since power-on of the first sample (`warmup`'s clock starts there).
    time_on: S,
    started: bool,
    /// The next step follows a gap.
    gap_pending: bool,
}

impl<const N: usize, S: Real> Default for ProgramState<N, S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, S: Real> ProgramState<N, S> {
    /// A state before the first sample.
    pub const fn new() -> Self {
        Self {
            values: [S::ZERO; N],
            slots: [Slot::EMPTY; MAX_STATEFUL],
            coef_dt: S::NAN,
            time_on: S::ZERO,
            started: false,
            gap_pending: false,
        }
    }

    /// Forgets all history: the next sample is treated as the first. Keeps the time since
    /// power-on set by [`set_time_on`](Self::set_time_on). A gap in a record is not a reason:
    /// [`step_gap`](Self::step_gap) carries the state across it.
    pub fn reset(&mut self) {
        *self = Self {
            time_on: self.time_on,
            ..Self::new()
        };
    }

    /// Sets the time since power-on, in seconds, of the first sample (default 0): where
    /// `warmup`'s clock starts. The board starts its channels at boot (0); the host starts at the
    /// run's first row, which is power-on unless the user says otherwise (`--power-on`). Takes
    /// effect at the next first sample.
    pub fn set_time_on(&mut self, seconds: S) {
        self.time_on = seconds;
    }

    /// The time since power-on of the first sample (see [`set_time_on`](Self::set_time_on)).
    pub fn time_on(&self) -> S {
        self.time_on
    }

    /// Marks the next step as following a gap: it is carried across as [`step_gap`](Self::step_gap)
    /// does, provided its `dt` differs from the current nominal step (a gap always is longer).
    /// The board's way ([`crate::Channel::skip`]): it costs the ordinary samples nothing.
    pub fn mark_gap(&mut self) {
        self.gap_pending = true;
    }

    /// Advances the program by one sample that follows a gap of `dt` seconds since the previous one:
    /// `lag` and `rate` are carried across it exactly for an input that moved linearly, `hyst` keeps
    /// its state, `warmup`'s clock counts it — or, when [`gap_resets`] says the gap is too long, the
    /// filters restart as on a first sample (the clock still counts it). The nominal step's
    /// coefficients are kept. On error nothing changes. The first sample of a state is an ordinary
    /// first sample.
    pub fn step_gap<const F: usize>(
        &mut self,
        program: &Program<'_, N, F, S>,
        inputs: &[S],
        dt: S,
    ) -> Result<(), StepError> {
        check_inputs(program, inputs)?;
        if !self.started {
            return self.step(program, inputs, dt);
        }
        if !(dt.is_finite() && dt > S::ZERO) {
            return Err(StepError::BadTimeStep);
        }
        self.step_across_gap(program, inputs, dt);
        Ok(())
    }

    /// True once a sample has been taken.
    pub fn started(&self) -> bool {
        self.started
    }

    /// The current value of node `i` (NaN past the program).
    pub fn value(&self, i: usize) -> S {
        self.values.get(i).copied().unwrap_or(S::NAN)
    }

    /// Advances the program by one sample: `inputs` in the order of [`Program::inputs`], `dt` the
    /// seconds since the previous sample (ignored on the first). On error nothing changes.
    pub fn step<const F: usize>(
        &mut self,
        program: &Program<'_, N, F, S>,
        inputs: &[S],
        dt: S,
    ) -> Result<(), StepError> {
        check_inputs(program, inputs)?;
        let first = !self.started;
        if first {
            self.gap_pending = false;
        } else {
            if !(dt.is_finite() && dt > S::ZERO) {
                return Err(StepError::BadTimeStep);
            }
            if dt != self.coef_dt {
                if self.gap_pending {
                    self.step_across_gap(program, inputs, dt);
                    return Ok(());
                }
                self.update_coefficients(program, dt);
            }
        }
        for (i, op) in program.nodes.iter().enumerate() {
            let v = self.eval_op(op, inputs, first);
            if let Some(slot) = self.values.get_mut(i) {
                *slot = v;
            }
        }
        self.started = true;
        Ok(())
    }

    /// Computes the filters' coefficients for samples `dt` apart now, ahead of the first step, so
    /// that the second step (the first with a time step) costs no more than any other: on a
    /// Cortex-M4F the two `expf`s per filter are about 240 instructions, which would otherwise
    /// land on one sample after every start. The coefficients are the very ones
    /// [`step`](Self::step) would compute, so the outputs do not change.
    pub fn prepare<const F: usize>(&mut self, program: &Program<'_, N, F, S>, dt: S) {
        if dt.is_finite() && dt > S::ZERO && dt != self.coef_dt {
            self.update_coefficients(program, dt);
        }
    }

    /// Copies the feature values into `out` (first `program.n_features()` entries).
    pub fn features<const F: usize>(
        &self,
        program: &Program<'_, N, F, S>,
        out: &mut [S],
    ) -> Result<(), StepError> {
        for (i, (dst, &node)) in out.iter_mut().zip(program.features.iter()).enumerate() {
            let v = self.value(node as usize);
            if !v.is_finite() {
                return Err(StepError::NonFiniteFeature { feature: i as u8 });
            }
            *dst = v;
        }
        Ok(())
    }

    fn update_coefficients<const F: usize>(&mut self, program: &Program<'_, N, F, S>, dt: S) {
        for op in program.nodes.iter() {
            let (slot, tau, is_rate) = match *op {
                Op::Rate { slot, window_s, .. } => (slot, Slot::rate_tau(window_s), true),
                Op::Lag { slot, tau_s, .. } => (slot, tau_s, false),
                Op::Warmup { slot, .. } => {
                    if let Some(s) = self.slots.get_mut(slot as usize) {
                        s.set_clock_step(dt);
                    }
                    continue;
                }
                _ => continue,
            };
            if let Some(s) = self.slots.get_mut(slot as usize) {
                s.set_coefficients(tau, dt, is_rate);
            }
        }
        self.coef_dt = dt;
    }

    /// One step across a gap of `dt` seconds (inputs checked, state started): see
    /// [`step_gap`](Self::step_gap). Not inlined: it runs only on the sample after a gap.
    #[inline(never)]
    fn step_across_gap<const F: usize>(
        &mut self,
        program: &Program<'_, N, F, S>,
        inputs: &[S],
        dt: S,
    ) {
        self.gap_pending = false;
        // Before any step with a time step there is no nominal one: the gap is one ordinary step.
        if !self.coef_dt.is_finite() {
            self.update_coefficients(program, dt);
        }
        let steps = dt / self.coef_dt;
        let restart = gap_resets(program, dt);
        for (i, op) in program.nodes.iter().enumerate() {
            let v = self.gap_op(op, inputs, dt, steps, restart);
            if let Some(slot) = self.values.get_mut(i) {
                *slot = v;
            }
        }
        self.started = true;
    }

    /// One operation on the sample after a gap of `dt` seconds, `steps` nominal steps long.
    fn gap_op(&mut self, op: &Op<S>, inputs: &[S], dt: S, steps: S, restart: bool) -> S {
        let (x, slot, tau) = match *op {
            Op::Lag { x, slot, tau_s } => (x, slot, tau_s),
            Op::Rate { x, slot, window_s } => (x, slot, Slot::rate_tau(window_s)),
            Op::Hyst { x, slot, threshold } => {
                let v = self.val(x);
                return match self.slots.get_mut(slot as usize) {
                    Some(s) => eval::hyst(s, v, threshold, restart),
                    None => S::NAN,
                };
            }
            Op::Warmup { slot, tau_s } => {
                let start = self.time_on;
                return match self.slots.get_mut(slot as usize) {
                    Some(s) => eval::warmup(s, tau_s, dt, start, false),
                    None => S::NAN,
                };
            }
            _ => return self.eval_op(op, inputs, false),
        };
        let v = self.val(x);
        let is_rate = matches!(op, Op::Rate { .. });
        let Some(s) = self.slots.get_mut(slot as usize) else {
            return S::NAN;
        };
        if restart {
            return if is_rate {
                eval::rate(s, v, true)
            } else {
                eval::lag(s, v, true)
            };
        }
        let big_d = eval::gap_decay(s.decay(), tau, steps, dt);
        if is_rate {
            eval::rate_gap(s, v, big_d, steps)
        } else {
            eval::lag_gap(s, v, big_d, steps)
        }
    }

    #[inline]
    fn val(&self, node: u8) -> S {
        self.values.get(node as usize).copied().unwrap_or(S::NAN)
    }

    // Inlined into the per-sample loop: with the gap step as a second caller the compiler stopped
    // inlining it, which cost ~30 instructions per channel and sample on the board.
    #[inline(always)]
    fn eval_op(&mut self, op: &Op<S>, inputs: &[S], first: bool) -> S {
        match *op {
            Op::Input(k) => inputs.get(k as usize).copied().unwrap_or(S::NAN),
            Op::Const(v) => v,
            Op::Add(a, b) => self.val(a) + self.val(b),
            Op::Sub(a, b) => self.val(a) - self.val(b),
            Op::Mul(a, b) => self.val(a) * self.val(b),
            Op::Div(a, b) => self.val(a) / self.val(b),
            Op::Neg(a) => -self.val(a),
            Op::Sq(a) => {
                let v = self.val(a);
                v * v
            }
            Op::Abs(a) => self.val(a).abs(),
            Op::Clamp { x, lo, hi } => eval::clamp(self.val(x), lo, hi),
            Op::Rate { x, slot, .. } => {
                let v = self.val(x);
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return S::NAN;
                };
                eval::rate(s, v, first)
            }
            Op::Lag { x, slot, .. } => {
                let v = self.val(x);
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return S::NAN;
                };
                eval::lag(s, v, first)
            }
            Op::Hyst { x, slot, threshold } => {
                let v = self.val(x);
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return S::NAN;
                };
                eval::hyst(s, v, threshold, first)
            }
            Op::Warmup { slot, tau_s } => {
                let start = self.time_on;
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return S::NAN;
                };
                let step = s.clock_step();
                eval::warmup(s, tau_s, step, start, first)
            }
        }
    }
}

/// Checks that every input the program reads is there and finite.
#[inline(always)]
fn check_inputs<const N: usize, const F: usize, S: Real>(
    program: &Program<'_, N, F, S>,
    inputs: &[S],
) -> Result<(), StepError> {
    for index in 0..program.inputs.len() {
        match inputs.get(index) {
            None => return Err(StepError::MissingInput { index: index as u8 }),
            Some(v) if !v.is_finite() => {
                return Err(StepError::NonFiniteInput { index: index as u8 });
            }
            Some(_) => {}
        }
    }
    Ok(())
}
