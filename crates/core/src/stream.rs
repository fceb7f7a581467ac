//! Running a feature program sample by sample: the streaming state apart from the program.
//!
//! [`ProgramState`] holds one value per node and the state slots of `rate`, `lag` and `hyst`; the
//! [`Program`] itself stays immutable, so one program serves many channels and `reset` is trivial.
//! Filter coefficients depend on the time step; they are recomputed only when `Δt` changes, so a
//! fixed-rate loop pays for the exponentials once. The exact discrete-time definitions are in the
//! table of [`crate::program`].

use crate::MAX_STATEFUL;
use crate::program::{Op, Program};

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

/// State of one stateful operator. Lags are kept as the *difference* between their input and their
/// output (`e = x − L`), which stays small, rather than as `L` itself: at 200 Hz a lag's per-sample
/// increment is ~10⁻⁴ of a temperature of tens of degrees, below f32 resolution, and a lag stored as
/// `L` drifts by rounding bias (a 0.1 % rate error, measured). In difference form
/// `e[n] = (e[n−1] + Δx)·d` with `d = e^(−Δt/τ)`, which is the same recurrence exactly in real
/// arithmetic.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Slot {
    /// The operand's previous value.
    prev: f32,
    /// `x − L1` (`lag`, `rate`); the ±1/0 state of `hyst`.
    e1: f32,
    /// `L1 − L2` (`rate`).
    e2: f32,
    /// `e^(−Δt/τ)`.
    decay: f32,
    /// `rate` output gain `60·(e^(Δt/τ) − 1)/Δt`.
    gain: f32,
}

/// Streaming state of one channel's feature program with up to `N` nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramState<const N: usize> {
    values: [f32; N],
    slots: [Slot; MAX_STATEFUL],
    /// The Δt the slot coefficients were computed for; NaN when none.
    coef_dt: f32,
    started: bool,
}

impl<const N: usize> Default for ProgramState<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ProgramState<N> {
    /// A state before the first sample.
    pub const fn new() -> Self {
        Self {
            values: [0.0; N],
            slots: [Slot {
                prev: 0.0,
                e1: 0.0,
                e2: 0.0,
                decay: 0.0,
                gain: 0.0,
            }; MAX_STATEFUL],
            coef_dt: f32::NAN,
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
    pub fn value(&self, i: usize) -> f32 {
        self.values.get(i).copied().unwrap_or(f32::NAN)
    }

    /// Advances the program by one sample: `inputs` in the order of [`Program::inputs`], `dt` the
    /// seconds since the previous sample (ignored on the first). On error nothing changes.
    pub fn step<const F: usize>(
        &mut self,
        program: &Program<'_, N, F>,
        inputs: &[f32],
        dt: f32,
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
            if !(dt.is_finite() && dt > 0.0) {
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
    pub fn prepare<const F: usize>(&mut self, program: &Program<'_, N, F>, dt: f32) {
        if dt.is_finite() && dt > 0.0 && dt != self.coef_dt {
            self.update_coefficients(program, dt);
        }
    }

    /// Copies the feature values into `out` (first `program.n_features()` entries).
    pub fn features<const F: usize>(
        &self,
        program: &Program<'_, N, F>,
        out: &mut [f32],
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

    fn update_coefficients<const F: usize>(&mut self, program: &Program<'_, N, F>, dt: f32) {
        for op in program.nodes.iter() {
            let (slot, tau, is_rate) = match *op {
                Op::Rate { slot, window_s, .. } => (slot, 0.5 * window_s, true),
                Op::Lag { slot, tau_s, .. } => (slot, tau_s, false),
                _ => continue,
            };
            if let Some(s) = self.slots.get_mut(slot as usize) {
                let h = dt / tau;
                s.decay = libm::expf(-h);
                s.gain = if is_rate {
                    60.0 * libm::expm1f(h) / dt
                } else {
                    0.0
                };
            }
        }
        self.coef_dt = dt;
    }

    #[inline]
    fn val(&self, node: u8) -> f32 {
        self.values.get(node as usize).copied().unwrap_or(f32::NAN)
    }

    fn eval_op(&mut self, op: &Op, inputs: &[f32], first: bool) -> f32 {
        match *op {
            Op::Input(k) => inputs.get(k as usize).copied().unwrap_or(f32::NAN),
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
            Op::Abs(a) => libm::fabsf(self.val(a)),
            Op::Clamp { x, lo, hi } => {
                let v = self.val(x);
                if v < lo {
                    lo
                } else if v > hi {
                    hi
                } else {
                    v
                }
            }
            Op::Rate { x, slot, .. } => {
                let v = self.val(x);
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return f32::NAN;
                };
                // (Re)start from the input; also heals a state that a non-finite first value left.
                if first || !s.prev.is_finite() {
                    *s = Slot {
                        prev: v,
                        e1: 0.0,
                        e2: 0.0,
                        ..*s
                    };
                    return 0.0;
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
            Op::Lag { x, slot, .. } => {
                let v = self.val(x);
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return f32::NAN;
                };
                if first || !s.prev.is_finite() {
                    *s = Slot {
                        prev: v,
                        e1: 0.0,
                        ..*s
                    };
                } else if v.is_finite() {
                    s.e1 = (s.e1 + (v - s.prev)) * s.decay;
                    s.prev = v;
                }
                s.prev - s.e1
            }
            Op::Hyst { x, slot, threshold } => {
                let v = self.val(x);
                let Some(s) = self.slots.get_mut(slot as usize) else {
                    return f32::NAN;
                };
                if first {
                    s.e1 = 0.0;
                }
                if v > threshold {
                    s.e1 = 1.0;
                } else if v < -threshold {
                    s.e1 = -1.0;
                }
                s.e1
            }
        }
    }
}
