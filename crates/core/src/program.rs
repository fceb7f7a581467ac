//! Feature programs: the compiled form of feature expressions, carried in the model blob.
//!
//! A program is a list of operations in evaluation order (each operand refers to an earlier node), the
//! input column names it reads, and which nodes are the model's features. Named signals are ordinary
//! nodes that several features share, so `T = mean(a, b, c)` is computed once per sample.
//!
//! # Operators and their exact discrete-time definitions
//! Sample `n` arrives with inputs `x[n]` and the time step `Δt[n]` (seconds) since sample `n−1`.
//! Stateful operators start from their input's first value; see [`crate::stream`] for the code.
//!
//! | expression | definition |
//! |---|---|
//! | `name` | the input column `name` at sample n |
//! | `1.5`, `-2e-3` | constants |
//! | `a + b`, `a - b`, `a * b`, `a / b`, `-a` | IEEE-754 f32 arithmetic |
//! | `sq(a)` | `a·a` |
//! | `abs(a)` | `|a|` |
//! | `mean(a, b, …)` | `(a + b + …) · (1/k)`, summed left to right |
//! | `clamp(a, lo, hi)` | `a` limited to `[lo, hi]` (constants) |
//! | `lag(a, τ)` | first-order lag: `L[n] = L[n−1] + c·(a[n] − L[n−1])`, `c = 1 − e^(−Δt/τ)`, `L[0] = a[0]` (computed in the equivalent difference form, see [`crate::stream`]). These are the exact samples of a continuous lag driven by a zero-order hold, so a unit step gives `1 − e^(−kΔt/τ)` after `k` samples. |
//! | `rate(a)`, `rate(a, w)` | d/dt in units **per minute**, window `w` seconds (default 60): two cascaded lags with `τ = w/2`, `L1` of `a` and `L2` of `L1`, and `rate = 60·(L1 − L2)·(e^(Δt/τ) − 1)/Δt`. The factor makes it exact on a ramp once the start-up transient (`∝ e^(−t/τ)`) has decayed: a ramp of slope `s`/s gives exactly `60·s`. Delay ≈ `w` seconds; white input noise is low-pass filtered twice. `rate[0] = 0`. |
//! | `hyst(a, h)` | heating/cooling state: `+1` if `a[n] > h`, `−1` if `a[n] < −h`, else the previous value; `0` before either. Typically `hyst(rate(T), 0.05)`. |

use crate::parse::{self, ParseError, ParseErrorKind};
use crate::{MAX_INPUTS, MAX_SIGNALS, MAX_STATEFUL};
use heapless::Vec;
use serde::{Deserialize, Serialize};

/// Default window of `rate(x)` in seconds.
pub const DEFAULT_RATE_WINDOW_S: f32 = 60.0;

/// One operation of a feature program; operands are indices of earlier nodes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(remote = "Self")] // serde traits in `crate::tag`: an unknown tag is told apart
pub enum Op {
    /// Input column by index into [`Program::inputs`].
    Input(u8),
    /// A constant.
    Const(f32),
    /// `a + b`.
    Add(u8, u8),
    /// `a - b`.
    Sub(u8, u8),
    /// `a * b`.
    Mul(u8, u8),
    /// `a / b`.
    Div(u8, u8),
    /// `-a`.
    Neg(u8),
    /// `a * a`.
    Sq(u8),
    /// `|a|`.
    Abs(u8),
    /// `a` limited to `[lo, hi]`.
    Clamp {
        /// Operand node.
        x: u8,
        /// Lower limit.
        lo: f32,
        /// Upper limit.
        hi: f32,
    },
    /// Rate of change per minute over a window (see the module table).
    Rate {
        /// Operand node.
        x: u8,
        /// State slot.
        slot: u8,
        /// Window in seconds.
        window_s: f32,
    },
    /// First-order lag.
    Lag {
        /// Operand node.
        x: u8,
        /// State slot.
        slot: u8,
        /// Time constant in seconds.
        tau_s: f32,
    },
    /// Heating/cooling hysteresis state.
    Hyst {
        /// Operand node.
        x: u8,
        /// State slot.
        slot: u8,
        /// Threshold (positive).
        threshold: f32,
    },
}

impl Op {
    /// The operand nodes of this operation (up to two).
    pub fn operands(&self) -> (Option<u8>, Option<u8>) {
        match *self {
            Op::Input(_) | Op::Const(_) => (None, None),
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) => (Some(a), Some(b)),
            Op::Neg(a) | Op::Sq(a) | Op::Abs(a) => (Some(a), None),
            Op::Clamp { x, .. } | Op::Rate { x, .. } | Op::Lag { x, .. } | Op::Hyst { x, .. } => {
                (Some(x), None)
            }
        }
    }

    /// The state slot of a stateful operation.
    pub fn slot(&self) -> Option<u8> {
        match *self {
            Op::Rate { slot, .. } | Op::Lag { slot, .. } | Op::Hyst { slot, .. } => Some(slot),
            _ => None,
        }
    }
}

/// A named signal kept for display and for rebuilding the source text.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Signal<'a> {
    /// Its name.
    pub name: &'a str,
    /// Its defining expression.
    pub expr: &'a str,
    /// The node holding its value.
    pub node: u8,
}

/// A compiled feature program with at most `N` nodes and `F` features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Program<'a, const N: usize, const F: usize> {
    /// Input column names, in the order the `inputs` slice of a step must follow.
    #[serde(borrow)]
    pub inputs: Vec<&'a str, MAX_INPUTS>,
    /// Named signals.
    #[serde(borrow)]
    pub signals: Vec<Signal<'a>, MAX_SIGNALS>,
    /// Operations in evaluation order.
    pub nodes: Vec<Op, N>,
    /// The node of each feature.
    pub features: Vec<u8, F>,
    /// The source expression of each feature.
    #[serde(borrow)]
    pub feature_exprs: Vec<&'a str, F>,
}

/// Why a compiled program is unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ProgramError {
    /// An operand refers to itself or a later node.
    ForwardReference {
        /// Node index.
        node: u8,
    },
    /// An input index is past the input list.
    UnknownInput {
        /// Node index.
        node: u8,
    },
    /// A constant or parameter is NaN or infinite, or a time constant/threshold is not positive.
    BadParameter {
        /// Node index.
        node: u8,
    },
    /// Two stateful nodes share a slot, or a slot is past capacity.
    BadSlot {
        /// Node index.
        node: u8,
    },
    /// A feature or signal refers to a missing node, or the feature lists differ in length.
    BadFeature {
        /// Feature index.
        feature: u8,
    },
    /// The program has no features.
    NoFeatures,
}

impl core::fmt::Display for ProgramError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ForwardReference { node } => write!(f, "node {node} uses a later node"),
            Self::UnknownInput { node } => {
                write!(f, "node {node} reads an input that is not listed")
            }
            Self::BadParameter { node } => {
                write!(f, "node {node} has a non-finite or non-positive parameter")
            }
            Self::BadSlot { node } => write!(f, "node {node} has an invalid or shared state slot"),
            Self::BadFeature { feature } => write!(f, "feature {feature} refers to a missing node"),
            Self::NoFeatures => write!(f, "the program has no features"),
        }
    }
}

impl<'a, const N: usize, const F: usize> Program<'a, N, F> {
    /// An empty program.
    pub const fn new() -> Self {
        Self {
            inputs: Vec::new(),
            signals: Vec::new(),
            nodes: Vec::new(),
            features: Vec::new(),
            feature_exprs: Vec::new(),
        }
    }

    /// Number of features.
    pub fn n_features(&self) -> usize {
        self.features.len()
    }

    /// Index of an input column by name.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|n| *n == name)
    }

    /// Checks the structure a decoded program must have before it may run.
    pub fn validate(&self) -> Result<(), ProgramError> {
        let mut used_slots = [false; MAX_STATEFUL];
        for (i, op) in self.nodes.iter().enumerate() {
            let node = i as u8;
            let (a, b) = op.operands();
            if a.is_some_and(|a| a as usize >= i) || b.is_some_and(|b| b as usize >= i) {
                return Err(ProgramError::ForwardReference { node });
            }
            let params_ok = match *op {
                Op::Input(k) => {
                    if k as usize >= self.inputs.len() {
                        return Err(ProgramError::UnknownInput { node });
                    }
                    true
                }
                Op::Const(v) => v.is_finite(),
                Op::Clamp { lo, hi, .. } => lo.is_finite() && hi.is_finite() && lo <= hi,
                Op::Rate { window_s: p, .. } | Op::Lag { tau_s: p, .. } => p.is_finite() && p > 0.0,
                Op::Hyst { threshold, .. } => threshold.is_finite() && threshold >= 0.0,
                _ => true,
            };
            if !params_ok {
                return Err(ProgramError::BadParameter { node });
            }
            if let Some(slot) = op.slot() {
                match used_slots.get_mut(slot as usize) {
                    Some(used) if !*used => *used = true,
                    _ => return Err(ProgramError::BadSlot { node }),
                }
            }
        }
        if self.features.is_empty() {
            return Err(ProgramError::NoFeatures);
        }
        if self.feature_exprs.len() != self.features.len() {
            return Err(ProgramError::BadFeature { feature: 0 });
        }
        for (i, &f) in self.features.iter().enumerate() {
            if f as usize >= self.nodes.len() {
                return Err(ProgramError::BadFeature { feature: i as u8 });
            }
        }
        for (i, s) in self.signals.iter().enumerate() {
            if s.node as usize >= self.nodes.len() {
                return Err(ProgramError::BadFeature { feature: i as u8 });
            }
        }
        Ok(())
    }
}

impl<const N: usize, const F: usize> Default for Program<'_, N, F> {
    fn default() -> Self {
        Self::new()
    }
}

/// Compiles signal definitions and feature expressions into a [`Program`].
///
/// ```
/// use tcomp_core::ProgramBuilder;
/// let mut b = ProgramBuilder::<32, 4>::new();
/// b.line("T = mean(t_anode_c, t_cathode_c, t_shell_c)").unwrap();
/// b.feature("T").unwrap();
/// b.feature("rate(T)").unwrap();
/// b.feature("t_anode_c - t_shell_c").unwrap();
/// let program = b.finish().unwrap();
/// assert_eq!(program.inputs.as_slice(), &["t_anode_c", "t_cathode_c", "t_shell_c"]);
/// ```
#[derive(Debug)]
pub struct ProgramBuilder<'a, const N: usize, const F: usize> {
    pub(crate) program: Program<'a, N, F>,
    pub(crate) next_slot: u8,
}

impl<'a, const N: usize, const F: usize> Default for ProgramBuilder<'a, N, F> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a, const N: usize, const F: usize> ProgramBuilder<'a, N, F> {
    /// A builder for an empty program.
    pub fn new() -> Self {
        Self {
            program: Program::new(),
            next_slot: 0,
        }
    }

    /// Defines a named signal `name = expr`, usable by later signals and features.
    pub fn signal(&mut self, name: &'a str, expr: &'a str) -> Result<(), ParseError> {
        let name_err = |kind| ParseError {
            start: 0,
            end: name.len() as u16,
            kind,
        };
        if !parse::is_identifier(name) || parse::is_function(name) {
            return Err(name_err(ParseErrorKind::BadName));
        }
        if self.program.signals.iter().any(|s| s.name == name) {
            return Err(name_err(ParseErrorKind::DuplicateSignal));
        }
        if self.program.signals.is_full() {
            return Err(name_err(ParseErrorKind::TooManySignals));
        }
        let node = parse::compile_expr(self, expr)?;
        let _ = self.program.signals.push(Signal { name, expr, node });
        Ok(())
    }

    /// Adds a feature computed by `expr`.
    pub fn feature(&mut self, expr: &'a str) -> Result<(), ParseError> {
        if self.program.features.is_full() {
            return Err(ParseError {
                start: 0,
                end: expr.len() as u16,
                kind: ParseErrorKind::TooManyFeatures,
            });
        }
        let node = parse::compile_expr(self, expr)?;
        let _ = self.program.features.push(node);
        let _ = self.program.feature_exprs.push(expr.trim());
        Ok(())
    }

    /// One line of a spec: `NAME = expr` defines a signal, anything else is a feature.
    /// Errors are positioned within `line`.
    pub fn line(&mut self, line: &'a str) -> Result<(), ParseError> {
        match parse::split_definition(line) {
            Some((name, name_at, expr, expr_at)) => self.signal(name, expr).map_err(|e| {
                let shift = if e.kind == ParseErrorKind::BadName
                    || e.kind == ParseErrorKind::DuplicateSignal
                {
                    name_at
                } else {
                    expr_at
                };
                e.shifted(shift as u16)
            }),
            None => self.feature(line),
        }
    }

    /// The finished program.
    pub fn finish(self) -> Result<Program<'a, N, F>, ProgramError> {
        self.program.validate()?;
        Ok(self.program)
    }
}
