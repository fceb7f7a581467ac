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

use crate::eval::{self, Slot};
use crate::program::{Op, Program};
use crate::{MAX_STATEFUL, Real};

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
    started: bool,
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
            started: false,
        }
    }

    /// Forgets all history: the next sample is treated as the first (use it across gaps in a record).
    pub fn reset(&mut self) {
        *self = Self::new();
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
        for index in 0..program.inputs.len() {
            match inputs.get(index) {
                None => return Err(StepError::MissingInput { index: index as u8 }),
                Some(v) if !v.is_finite() => {
                    return Err(StepError::NonFiniteInput { index: index as u8 });
                }
                Some(_) => {}
            }
        }
        let first = !self.started;
        if !first {
            if !(dt.is_finite() && dt > S::ZERO) {
                return Err(StepError::BadTimeStep);
            }
            if dt != self.coef_dt {
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
                _ => continue,
            };
            if let Some(s) = self.slots.get_mut(slot as usize) {
                s.set_coefficients(tau, dt, is_rate);
            }
        }
        self.coef_dt = dt;
    }

    #[inline]
    fn val(&self, node: u8) -> S {
        self.values.get(node as usize).copied().unwrap_or(S::NAN)
    }

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
        }
    }
}
