//! Feature programs: the compiled form of feature expressions, carried in the model blob.
//!
//! A program is a list of operations in evaluation order (each operand refers to an earlier node), the
//! input column names it reads, and which nodes are the model's features. Named signals are ordinary
//! nodes that several features share, so `T = mean(a, b, c)` is computed once per sample.
//!
//! The language itself — functions, arity, parameter domains, the version each operation exists
//! since, and the exact definitions — is the table of [`crate::lang`]; validation reads it. The
//! compiler from text is [`crate::compile`], the evaluator [`crate::stream`].
//!
//! A program is generic over its number type `S` ([`Real`]): `f32` (the default) in blobs and on the
//! board, `f64` where the host needs the same features without f32 rounding (the simulator).

use crate::lang::{self, Code};
use crate::{MAX_INPUTS, MAX_SIGNALS, MAX_STATEFUL, Real};
use heapless::Vec;
use serde::{Deserialize, Serialize};

pub use crate::lang::DEFAULT_RATE_WINDOW_S;

/// One operation of a feature program; operands are indices of earlier nodes.
///
/// The variant order is the blob's wire format: a new operation is appended (its row in
/// [`crate::lang`] says since which format version it exists). Every `match` on `Op` is
/// exhaustive, so the compiler lists the places a new variant must be handled.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(remote = "Self")] // serde traits in `crate::tag`: an unknown tag is told apart
pub enum Op<S = f32> {
    /// Input column by index into [`Program::inputs`].
    Input(u8),
    /// A constant.
    Const(S),
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
        lo: S,
        /// Upper limit.
        hi: S,
    },
    /// Rate of change per minute over a window (see the module table).
    Rate {
        /// Operand node.
        x: u8,
        /// State slot.
        slot: u8,
        /// Window in seconds.
        window_s: S,
    },
    /// First-order lag.
    Lag {
        /// Operand node.
        x: u8,
        /// State slot.
        slot: u8,
        /// Time constant in seconds.
        tau_s: S,
    },
    /// Heating/cooling hysteresis state.
    Hyst {
        /// Operand node.
        x: u8,
        /// State slot.
        slot: u8,
        /// Threshold (positive).
        threshold: S,
    },
    /// Warm-up after power-on, `e^(−t_on/τ)` (since blob format version 2).
    Warmup {
        /// State slot (the clock).
        slot: u8,
        /// Time constant in seconds.
        tau_s: S,
    },
}

impl<S: Real> Op<S> {
    /// The operand nodes of this operation (up to two).
    pub fn operands(&self) -> (Option<u8>, Option<u8>) {
        match *self {
            Op::Input(_) | Op::Const(_) | Op::Warmup { .. } => (None, None),
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) => (Some(a), Some(b)),
            Op::Neg(a) | Op::Sq(a) | Op::Abs(a) => (Some(a), None),
            Op::Clamp { x, .. } | Op::Rate { x, .. } | Op::Lag { x, .. } | Op::Hyst { x, .. } => {
                (Some(x), None)
            }
        }
    }

    /// The operation without its operands: its row in the language's table ([`crate::lang`]).
    pub fn code(&self) -> Code {
        match self {
            Op::Input(_) => Code::Input,
            Op::Const(_) => Code::Const,
            Op::Add(..) => Code::Add,
            Op::Sub(..) => Code::Sub,
            Op::Mul(..) => Code::Mul,
            Op::Div(..) => Code::Div,
            Op::Neg(_) => Code::Neg,
            Op::Sq(_) => Code::Sq,
            Op::Abs(_) => Code::Abs,
            Op::Clamp { .. } => Code::Clamp,
            Op::Rate { .. } => Code::Rate,
            Op::Lag { .. } => Code::Lag,
            Op::Hyst { .. } => Code::Hyst,
            Op::Warmup { .. } => Code::Warmup,
        }
    }

    /// The constant parameters, in the order of the function's parameters in [`crate::lang`]
    /// (a constant's value counts as its one parameter).
    pub fn params(&self) -> ([S; 2], usize) {
        match *self {
            Op::Const(v) => ([v, v], 1),
            Op::Clamp { lo, hi, .. } => ([lo, hi], 2),
            Op::Rate { window_s: p, .. }
            | Op::Lag { tau_s: p, .. }
            | Op::Hyst { threshold: p, .. }
            | Op::Warmup { tau_s: p, .. } => ([p, p], 1),
            Op::Input(_)
            | Op::Add(..)
            | Op::Sub(..)
            | Op::Mul(..)
            | Op::Div(..)
            | Op::Neg(_)
            | Op::Sq(_)
            | Op::Abs(_) => ([S::ZERO; 2], 0),
        }
    }

    /// The operation `code` applied to `x` with parameters `p` and state slot `slot` — how a
    /// function of [`crate::lang::FUNCTIONS`] compiles; `None` for codes that are not a function's
    /// operation. Missing parameters read as 0 (the compiler passes them all); `x` is ignored by
    /// a function without operand (`warmup`).
    pub fn function(code: Code, x: u8, slot: u8, p: &[S]) -> Option<Self> {
        let p0 = p.first().copied().unwrap_or(S::ZERO);
        let p1 = p.get(1).copied().unwrap_or(p0);
        Some(match code {
            Code::Sq => Op::Sq(x),
            Code::Abs => Op::Abs(x),
            Code::Clamp => Op::Clamp { x, lo: p0, hi: p1 },
            Code::Rate => Op::Rate {
                x,
                slot,
                window_s: p0,
            },
            Code::Lag => Op::Lag { x, slot, tau_s: p0 },
            Code::Hyst => Op::Hyst {
                x,
                slot,
                threshold: p0,
            },
            Code::Warmup => Op::Warmup { slot, tau_s: p0 },
            Code::Input
            | Code::Const
            | Code::Add
            | Code::Sub
            | Code::Mul
            | Code::Div
            | Code::Neg => return None,
        })
    }

    /// The state slot of a stateful operation.
    pub fn slot(&self) -> Option<u8> {
        match *self {
            Op::Rate { slot, .. }
            | Op::Lag { slot, .. }
            | Op::Hyst { slot, .. }
            | Op::Warmup { slot, .. } => Some(slot),
            Op::Input(_)
            | Op::Const(_)
            | Op::Add(..)
            | Op::Sub(..)
            | Op::Mul(..)
            | Op::Div(..)
            | Op::Neg(_)
            | Op::Sq(_)
            | Op::Abs(_)
            | Op::Clamp { .. } => None,
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
pub struct Program<'a, const N: usize, const F: usize, S = f32> {
    /// Input column names, in the order the `inputs` slice of a step must follow.
    #[serde(borrow)]
    pub inputs: Vec<&'a str, MAX_INPUTS>,
    /// Named signals.
    #[serde(borrow)]
    pub signals: Vec<Signal<'a>, MAX_SIGNALS>,
    /// Operations in evaluation order.
    pub nodes: Vec<Op<S>, N>,
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

impl<'a, const N: usize, const F: usize, S: Real> Program<'a, N, F, S> {
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
            if let Op::Input(k) = *op
                && k as usize >= self.inputs.len()
            {
                return Err(ProgramError::UnknownInput { node });
            }
            let params_ok = params_in_domain(op);
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

    /// The program's longest memory, seconds: the largest `lag` time constant or `rate` window (a
    /// window is two time constants of its cascaded lags, whose repeated pole forgets more slowly
    /// than one lag); 0 when it has neither. A gap longer than a few of these is one the filters
    /// cannot carry meaningfully (see [`crate::stream::RESET_AFTER_TIME_CONSTANTS`]).
    pub fn longest_time_constant(&self) -> S {
        let mut longest = S::ZERO;
        for op in self.nodes.iter() {
            let t = match *op {
                Op::Lag { tau_s, .. } => tau_s,
                Op::Rate { window_s, .. } => window_s,
                _ => continue,
            };
            if t > longest {
                longest = t;
            }
        }
        longest
    }

    /// The blob format version this program needs: the newest `since` ([`crate::lang`]) of its
    /// operations, at least 1. A blob is stamped with it, so a reader that predates one of the
    /// operations refuses the blob by its version instead of meeting an unknown operation.
    pub fn format_version(&self) -> u16 {
        self.nodes
            .iter()
            .map(|op| lang::since(op.code()))
            .fold(1, u16::max)
    }
}

impl<const N: usize, const F: usize, S: Real> Default for Program<'_, N, F, S> {
    fn default() -> Self {
        Self::new()
    }
}

/// Whether an operation's parameters lie in the domains [`crate::lang`] gives them (a constant must
/// be finite).
fn params_in_domain<S: Real>(op: &Op<S>) -> bool {
    let (values, n) = op.params();
    let Some(domains) = lang::domains_of(op.code()) else {
        return values.iter().take(n).all(|v| v.is_finite());
    };
    let mut prev = S::ZERO;
    for (v, domain) in values.iter().zip(domains).take(n) {
        if !domain.admits(*v, prev) {
            return false;
        }
        prev = *v;
    }
    true
}
