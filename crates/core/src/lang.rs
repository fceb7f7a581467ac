//! The feature language, defined once: every function and operator with its arity, the domain of
//! its parameters, the operation it compiles to, the blob format version it exists since, and its
//! exact discrete-time definition.
//!
//! Why one table: the parser (names, arity, messages), the program validator (parameter domains,
//! the version a blob needs), the streaming evaluator's state slots and this documentation all read
//! it, so they cannot disagree.
//!
//! Adding a function: a row of [`FUNCTIONS`] (name, operands, parameters with domains and
//! defaults, its [`Code`], state, `since`, definition) and its `Code` variant; the
//! [`crate::Op`] variant, appended so older tags keep their numbers, with its arms in `Op`'s
//! exhaustive matches (the compiler lists them); its evaluation — a function in [`crate::eval`]
//! called from the evaluator's exhaustive match; the documentation table below (a test compares it
//! with [`write_table`]); and a test. A new operation gets `since` = the next blob format version,
//! and `blob::FORMAT_VERSION` must follow (a compile-time assertion insists): a blob that uses it
//! is stamped with that version ([`crate::Program::format_version`]), so an older reader refuses
//! it as a version it does not read rather than as malformed bytes.
//!
//! # Operators and their exact discrete-time definitions
//! Sample `n` arrives with inputs `x[n]` and the time step `Δt[n]` (seconds) since sample `n−1`.
//! Stateful operators start from their input's first value; see [`crate::eval`] for the code. The
//! table below is checked against [`write_table`] by a test.
//!
//! | expression | definition | since |
//! |---|---|---|
//! | `name` | the input column `name` at sample n, or a signal defined earlier (`NAME = expr`) | 1 |
//! | `1.5`, `-2e-3` | constants (finite) | 1 |
//! | `a + b`, `a - b`, `a * b`, `a / b`, `-a` | IEEE-754 arithmetic in the program's number type (f32 on the board, f64 in the simulator); a division by a constant zero is refused | 1 |
//! | `sq(x)` | `x·x` | 1 |
//! | `abs(x)` | `|x|` | 1 |
//! | `mean(a, ...)` | `(a + b + …) · (1/k)`, summed left to right | 1 |
//! | `rate(x[, window_s])` | d/dt in units **per minute**, window `w` seconds (default 60): two cascaded lags with `τ = w/2`, `L1` of `x` and `L2` of `L1`, and `rate = 60·(L1 − L2)·(e^(Δt/τ) − 1)/Δt`. The factor makes it exact on a ramp once the start-up transient (`∝ e^(−t/τ)`) has decayed: a ramp of slope `s`/s gives exactly `60·s`. Delay ≈ `w` seconds; white input noise is low-pass filtered twice. `rate[0] = 0`. | 1 |
//! | `lag(x, tau_s)` | first-order lag: `L[n] = L[n−1] + c·(x[n] − L[n−1])`, `c = 1 − e^(−Δt/τ)`, `L[0] = x[0]` (computed in the equivalent difference form, see [`crate::eval`]). These are the exact samples of a continuous lag driven by a zero-order hold, so a unit step gives `1 − e^(−kΔt/τ)` after `k` samples. | 1 |
//! | `hyst(x, threshold)` | heating/cooling state: `+1` if `x[n] > h`, `−1` if `x[n] < −h`, else the previous value; `0` before either. Typically `hyst(rate(T), 0.05)`. | 1 |
//! | `clamp(x, lo, hi)` | `x` limited to `[lo, hi]` | 1 |
//! | `warmup(tau_s)` | warm-up after power-on: `e^(−t_on/τ)`, `t_on` the seconds since power-on — the board counts from the channel's start at boot, the host from the run's first row or the `--power-on` time given; `t_on[n] = t_on[n−1] + Δt[n]` (compensated summation), across gaps too, which never reset it. | 2 |
//!
//! Parameters (the arguments after a function's operand; all of `warmup`'s) are constant
//! expressions (folded at compile time): windows and time constants finite and > 0, thresholds
//! finite and ≥ 0, `lo ≤ hi`.
//!
//! **Gaps.** A step the caller marks as a gap (a logger dropout on the host, a run of missed
//! periods on the board; see [`crate::ProgramState::step_gap`]) advances `lag` and `rate` exactly
//! as their nominal steps would over an input moving linearly across the gap (closed forms in
//! [`crate::eval`]), `hyst` keeps its state and `warmup`'s clock counts the gap. A gap longer than
//! [`crate::stream::RESET_AFTER_TIME_CONSTANTS`] times the program's longest time constant restarts
//! `lag`, `rate` and `hyst` as on a first sample (the caller is told, to warn), never `warmup`.

use core::fmt::{self, Write};

/// The operation a [`crate::Op`] performs, without its operands: one per `Op` variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Code {
    /// An input column.
    Input,
    /// A constant.
    Const,
    /// `a + b`.
    Add,
    /// `a - b`.
    Sub,
    /// `a * b`.
    Mul,
    /// `a / b`.
    Div,
    /// `-a`.
    Neg,
    /// `sq`.
    Sq,
    /// `abs`.
    Abs,
    /// `clamp`.
    Clamp,
    /// `rate`.
    Rate,
    /// `lag`.
    Lag,
    /// `hyst`.
    Hyst,
    /// `warmup`.
    Warmup,
}

/// Where a parameter's value must lie.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// Any finite number.
    Finite,
    /// Finite and > 0 (windows, time constants).
    Positive,
    /// Finite and ≥ 0 (thresholds).
    NonNegative,
    /// Finite and ≥ the previous parameter (`clamp`'s `hi`); an error concerns the whole call.
    NotBelowPrevious,
}

impl Domain {
    /// Whether `v` lies in the domain, `prev` being the previous parameter's value.
    pub fn admits<S: crate::Real>(self, v: S, prev: S) -> bool {
        v.is_finite()
            && match self {
                Domain::Finite => true,
                Domain::Positive => v > S::ZERO,
                Domain::NonNegative => v >= S::ZERO,
                Domain::NotBelowPrevious => prev <= v,
            }
    }
}

/// A constant parameter of a function (the arguments after the first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Param {
    /// Its name in the syntax (`window_s`).
    pub name: &'static str,
    /// Its domain.
    pub domain: Domain,
    /// The value when the argument is left out (only trailing parameters may have one).
    pub default: Option<f32>,
}

/// The operands of a function: its arguments that are expressions evaluated every sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Operands {
    /// One operand, `x`, followed by the parameters.
    One,
    /// One or more operands (`mean(a, ...)`), no parameters.
    OneOrMore,
    /// No operand: every argument is a parameter (`warmup(tau_s)`, a function of time alone).
    None,
}

/// One function of the language.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Function {
    /// Its name.
    pub name: &'static str,
    /// Its operands.
    pub operands: Operands,
    /// Its constant parameters, in order.
    pub params: &'static [Param],
    /// The operation it compiles to; `None` for syntax that compiles to other operations (`mean`:
    /// additions and a product).
    pub op: Option<Code>,
    /// Whether the operation keeps state between samples (it then takes one state slot).
    pub stateful: bool,
    /// The blob format version the operation exists since.
    pub since: u16,
    /// Its exact definition (documentation).
    pub definition: &'static str,
}

impl Function {
    /// Whether `n` arguments are a valid call.
    pub fn admits_arg_count(&self, n: usize) -> bool {
        match self.operands {
            Operands::OneOrMore => n >= 1,
            Operands::One | Operands::None => {
                let operands = usize::from(self.operands == Operands::One);
                let required = self.params.iter().filter(|p| p.default.is_none()).count();
                (operands + required..=operands + self.params.len()).contains(&n)
            }
        }
    }

    /// Writes the call syntax, `rate(x[, window_s])`.
    pub fn write_syntax<W: Write>(&self, w: &mut W) -> fmt::Result {
        let mut first = match self.operands {
            Operands::OneOrMore => return write!(w, "{}(a, ...)", self.name),
            Operands::One => {
                write!(w, "{}(x", self.name)?;
                false
            }
            Operands::None => {
                write!(w, "{}(", self.name)?;
                true
            }
        };
        for p in self.params {
            let sep = if first { "" } else { ", " };
            match p.default {
                Some(_) => write!(w, "[{sep}{}]", p.name)?,
                None => write!(w, "{sep}{}", p.name)?,
            }
            first = false;
        }
        w.write_char(')')
    }

    /// The index of the first parameter among the call's arguments (after the operand, if any).
    pub fn first_param(&self) -> usize {
        usize::from(self.operands == Operands::One)
    }
}

/// Default window of `rate(x)` in seconds.
pub const DEFAULT_RATE_WINDOW_S: f32 = 60.0;

const WINDOW: Param = Param {
    name: "window_s",
    domain: Domain::Positive,
    default: Some(DEFAULT_RATE_WINDOW_S),
};

/// The functions, in the order the error messages list them.
pub const FUNCTIONS: [Function; 8] = [
    Function {
        name: "sq",
        operands: Operands::One,
        params: &[],
        op: Some(Code::Sq),
        stateful: false,
        since: 1,
        definition: "`x·x`",
    },
    Function {
        name: "abs",
        operands: Operands::One,
        params: &[],
        op: Some(Code::Abs),
        stateful: false,
        since: 1,
        definition: "`|x|`",
    },
    Function {
        name: "mean",
        operands: Operands::OneOrMore,
        params: &[],
        op: None,
        stateful: false,
        since: 1,
        definition: "`(a + b + …) · (1/k)`, summed left to right",
    },
    Function {
        name: "rate",
        operands: Operands::One,
        params: &[WINDOW],
        op: Some(Code::Rate),
        stateful: true,
        since: 1,
        definition: "d/dt in units **per minute**, window `w` seconds (default 60): two cascaded lags with `τ = w/2`, `L1` of `x` and `L2` of `L1`, and `rate = 60·(L1 − L2)·(e^(Δt/τ) − 1)/Δt`. The factor makes it exact on a ramp once the start-up transient (`∝ e^(−t/τ)`) has decayed: a ramp of slope `s`/s gives exactly `60·s`. Delay ≈ `w` seconds; white input noise is low-pass filtered twice. `rate[0] = 0`.",
    },
    Function {
        name: "lag",
        operands: Operands::One,
        params: &[Param {
            name: "tau_s",
            domain: Domain::Positive,
            default: None,
        }],
        op: Some(Code::Lag),
        stateful: true,
        since: 1,
        definition: "first-order lag: `L[n] = L[n−1] + c·(x[n] − L[n−1])`, `c = 1 − e^(−Δt/τ)`, `L[0] = x[0]` (computed in the equivalent difference form, see [`crate::eval`]). These are the exact samples of a continuous lag driven by a zero-order hold, so a unit step gives `1 − e^(−kΔt/τ)` after `k` samples.",
    },
    Function {
        name: "hyst",
        operands: Operands::One,
        params: &[Param {
            name: "threshold",
            domain: Domain::NonNegative,
            default: None,
        }],
        op: Some(Code::Hyst),
        stateful: true,
        since: 1,
        definition: "heating/cooling state: `+1` if `x[n] > h`, `−1` if `x[n] < −h`, else the previous value; `0` before either. Typically `hyst(rate(T), 0.05)`.",
    },
    Function {
        name: "clamp",
        operands: Operands::One,
        params: &[
            Param {
                name: "lo",
                domain: Domain::Finite,
                default: None,
            },
            Param {
                name: "hi",
                domain: Domain::NotBelowPrevious,
                default: None,
            },
        ],
        op: Some(Code::Clamp),
        stateful: false,
        since: 1,
        definition: "`x` limited to `[lo, hi]`",
    },
    Function {
        name: "warmup",
        operands: Operands::None,
        params: &[Param {
            name: "tau_s",
            domain: Domain::Positive,
            default: None,
        }],
        op: Some(Code::Warmup),
        stateful: true,
        since: 2,
        definition: "warm-up after power-on: `e^(−t_on/τ)`, `t_on` the seconds since power-on — the board counts from the channel's start at boot, the host from the run's first row or the `--power-on` time given; `t_on[n] = t_on[n−1] + Δt[n]` (compensated summation), across gaps too, which never reset it.",
    },
];

/// Most constant parameters a function has (the size of [`crate::Op::params`]).
pub const MAX_PARAMS: usize = 2;

const _: () = {
    let mut i = 0;
    while i < FUNCTIONS.len() {
        assert!(
            FUNCTIONS[i].params.len() <= MAX_PARAMS,
            "a function has too many parameters"
        );
        assert!(FUNCTIONS[i].since >= 1, "format versions start at 1");
        i += 1;
    }
};

/// Syntax that is not a function call: names, constants, arithmetic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Syntax {
    /// How it is written (documentation).
    pub syntax: &'static str,
    /// The operations it compiles to.
    pub ops: &'static [Code],
    /// The blob format version these operations exist since.
    pub since: u16,
    /// Its definition (documentation).
    pub definition: &'static str,
}

/// Names, constants and arithmetic.
pub const SYNTAX: [Syntax; 3] = [
    Syntax {
        syntax: "`name`",
        ops: &[Code::Input],
        since: 1,
        definition: "the input column `name` at sample n, or a signal defined earlier (`NAME = expr`)",
    },
    Syntax {
        syntax: "`1.5`, `-2e-3`",
        ops: &[Code::Const],
        since: 1,
        definition: "constants (finite)",
    },
    Syntax {
        syntax: "`a + b`, `a - b`, `a * b`, `a / b`, `-a`",
        ops: &[Code::Add, Code::Sub, Code::Mul, Code::Div, Code::Neg],
        since: 1,
        definition: "IEEE-754 arithmetic in the program's number type (f32 on the board, f64 in the simulator); a division by a constant zero is refused",
    },
];

/// The function called `name`.
pub fn function(name: &str) -> Option<&'static Function> {
    FUNCTIONS.iter().find(|f| f.name == name)
}

/// The function that compiles to `code`, if `code` is a function's operation.
pub fn function_of(code: Code) -> Option<&'static Function> {
    FUNCTIONS.iter().find(|f| f.op == Some(code))
}

/// The newest `since` in the tables: the blob format version a build must read at least.
pub const NEWEST_SINCE: u16 = {
    let mut newest = 1;
    let mut i = 0;
    while i < FUNCTIONS.len() {
        if FUNCTIONS[i].since > newest {
            newest = FUNCTIONS[i].since;
        }
        i += 1;
    }
    let mut i = 0;
    while i < SYNTAX.len() {
        if SYNTAX[i].since > newest {
            newest = SYNTAX[i].since;
        }
        i += 1;
    }
    newest
};

/// What validation needs of an operation, distilled from the tables at compile time: a decoded
/// blob is checked against this small array, so the tables' names and documentation never reach
/// the firmware's flash.
#[derive(Clone, Copy)]
struct Rules {
    since: u16,
    /// Whether the operation is a function's (its parameters then have `domains`; the others'
    /// only parameter, a constant's value, must be finite).
    function: bool,
    domains: [Domain; MAX_PARAMS],
    params: u8,
}

const CODES: usize = Code::Warmup as usize + 1;

static RULES: [Rules; CODES] = {
    let mut rules = [Rules {
        since: 0,
        function: false,
        domains: [Domain::Finite; MAX_PARAMS],
        params: 0,
    }; CODES];
    let mut i = 0;
    while i < FUNCTIONS.len() {
        if let Some(code) = FUNCTIONS[i].op {
            let r = &mut rules[code as usize];
            r.since = FUNCTIONS[i].since;
            r.function = true;
            let params = FUNCTIONS[i].params;
            let mut k = 0;
            while k < params.len() {
                r.domains[k] = params[k].domain;
                k += 1;
            }
            r.params = params.len() as u8;
        }
        i += 1;
    }
    let mut i = 0;
    while i < SYNTAX.len() {
        let mut k = 0;
        while k < SYNTAX[i].ops.len() {
            rules[SYNTAX[i].ops[k] as usize].since = SYNTAX[i].since;
            k += 1;
        }
        i += 1;
    }
    // Every operation is in one of the tables.
    let mut c = 0;
    while c < CODES {
        assert!(
            rules[c].since >= 1,
            "an operation is missing from the language's tables"
        );
        c += 1;
    }
    rules
};

/// The blob format version `code` exists since.
pub fn since(code: Code) -> u16 {
    RULES.get(code as usize).map_or(u16::MAX, |r| r.since)
}

/// The domains of `code`'s parameters when it is a function's operation; `None` for the others
/// (whose only parameter, a constant's value, must be finite).
pub fn domains_of(code: Code) -> Option<&'static [Domain]> {
    let r = RULES.get(code as usize).filter(|r| r.function)?;
    r.domains.get(..r.params as usize)
}

/// Writes the names of the functions, `sq, abs, …` (for messages).
pub fn write_names<W: Write>(w: &mut W) -> fmt::Result {
    for (i, f) in FUNCTIONS.iter().enumerate() {
        if i > 0 {
            w.write_str(", ")?;
        }
        w.write_str(f.name)?;
    }
    Ok(())
}

/// Writes the names of the stateful functions, `rate/lag/hyst/warmup` (for messages).
pub fn write_stateful_names<W: Write>(w: &mut W) -> fmt::Result {
    for (i, f) in FUNCTIONS.iter().filter(|f| f.stateful).enumerate() {
        if i > 0 {
            w.write_char('/')?;
        }
        w.write_str(f.name)?;
    }
    Ok(())
}

/// Writes the call syntax of every function, `sq(x), abs(x), …` (for messages).
pub fn write_signatures<W: Write>(w: &mut W) -> fmt::Result {
    for (i, f) in FUNCTIONS.iter().enumerate() {
        if i > 0 {
            w.write_str(", ")?;
        }
        f.write_syntax(w)?;
    }
    Ok(())
}

/// Writes the language's documentation table (markdown, one row a line, as in this module's docs).
pub fn write_table<W: Write>(w: &mut W) -> fmt::Result {
    w.write_str("| expression | definition | since |\n|---|---|---|\n")?;
    for s in &SYNTAX {
        writeln!(w, "| {} | {} | {} |", s.syntax, s.definition, s.since)?;
    }
    for f in &FUNCTIONS {
        w.write_str("| `")?;
        f.write_syntax(w)?;
        writeln!(w, "` | {} | {} |", f.definition, f.since)?;
    }
    Ok(())
}
