//! The expression parser: text → program nodes, with errors that say where and why.
//!
//! Grammar (whitespace ignored):
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary)*
//! unary   := '-' unary | primary
//! primary := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//! A `name` is a signal defined earlier or else an input column. Functions: `sq`, `abs`, `mean`,
//! `rate`, `lag`, `hyst`, `clamp`; their parameters after the first argument must be constant
//! expressions. Constant sub-expressions are folded, so `-2 * 3` costs no node. A division by a
//! constant zero (`T / 0`, `T / (2 - 2)`, or by a signal defined as `0`) is refused here, pointing at
//! the divisor, rather than giving a feature that is NaN or infinite on every sample. Nesting
//! (parentheses, calls, unary minus) is limited to a fixed depth, so the recursion of the parser is
//! bounded whatever the text.
//! It runs without allocation, so the firmware could compile expressions too.

use crate::program::{DEFAULT_RATE_WINDOW_S, Op, ProgramBuilder};
use crate::{MAX_STATEFUL, program::Signal};

/// What went wrong in an expression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ParseErrorKind {
    /// The expression is empty.
    Empty,
    /// A character that starts no token.
    UnexpectedChar,
    /// The expression ended where an operand was expected.
    UnexpectedEnd,
    /// An operator or `)` where an operand was expected.
    ExpectedOperand,
    /// A missing `)`.
    ExpectedCloseParen,
    /// Text left over after a complete expression.
    TrailingInput,
    /// A number that does not parse.
    BadNumber,
    /// A function name that is not known.
    UnknownFunction,
    /// A function called with the wrong number of arguments.
    WrongArgCount,
    /// A parameter (window, time constant, threshold, limit) must be a constant expression.
    ConstantRequired,
    /// A parameter is out of its domain (time constants and windows > 0, thresholds ≥ 0, lo ≤ hi).
    BadParameter,
    /// Nesting deeper than the parser allows.
    TooDeep,
    /// A division by a constant zero.
    DivisionByZero,
    /// The program is out of nodes.
    TooManyNodes,
    /// The program reads too many input columns.
    TooManyInputs,
    /// Too many features.
    TooManyFeatures,
    /// Too many named signals.
    TooManySignals,
    /// Too many stateful operators (`rate`, `lag`, `hyst`).
    TooManyStateful,
    /// A signal with this name already exists.
    DuplicateSignal,
    /// A signal name must be an identifier and not a function name.
    BadName,
}

impl ParseErrorKind {
    fn message(self) -> &'static str {
        match self {
            Self::Empty => "the expression is empty",
            Self::UnexpectedChar => "unexpected character",
            Self::UnexpectedEnd => "the expression ends where an operand is expected",
            Self::ExpectedOperand => "expected a number, a name, a function call or '('",
            Self::ExpectedCloseParen => "expected ')'",
            Self::TrailingInput => "unexpected text after the end of the expression",
            Self::BadNumber => "not a valid number",
            Self::UnknownFunction => {
                "unknown function (known: sq, abs, mean, rate, lag, hyst, clamp)"
            }
            Self::WrongArgCount => {
                "wrong number of arguments (sq(x), abs(x), mean(a, ...), rate(x[, window_s]), lag(x, tau_s), hyst(x, threshold), clamp(x, lo, hi))"
            }
            Self::ConstantRequired => "this parameter must be a constant",
            Self::BadParameter => {
                "parameter out of range (windows and time constants > 0, thresholds >= 0, lo <= hi)"
            }
            Self::TooDeep => "expression nested too deeply",
            Self::DivisionByZero => "division by a constant zero",
            Self::TooManyNodes => "the program is out of operation slots",
            Self::TooManyInputs => "too many input columns",
            Self::TooManyFeatures => "too many features",
            Self::TooManySignals => "too many named signals",
            Self::TooManyStateful => "too many rate/lag/hyst operators",
            Self::DuplicateSignal => "a signal with this name is already defined",
            Self::BadName => "a signal name must be an identifier that is not a function name",
        }
    }
}

/// A parse error: the byte range `start..end` of the expression it concerns, and why. The range lies
/// within the text given (`start == end == len` for something missing at its end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParseError {
    /// Byte offset where the offending text starts.
    pub start: u16,
    /// Byte offset just past it.
    pub end: u16,
    /// Why.
    pub kind: ParseErrorKind,
}

impl ParseError {
    /// The same error with its position moved right by `by` bytes (for an expression inside a line).
    pub fn shifted(self, by: u16) -> Self {
        Self {
            start: self.start.saturating_add(by),
            end: self.end.saturating_add(by),
            kind: self.kind,
        }
    }

    /// 1-based column of the error start (in bytes; expressions are ASCII in practice).
    pub fn column(&self) -> usize {
        self.start as usize + 1
    }
}

impl core::fmt::Display for ParseError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "column {}: {}", self.column(), self.kind.message())
    }
}

const FUNCTIONS: [&str; 7] = ["sq", "abs", "mean", "rate", "lag", "hyst", "clamp"];
const MAX_DEPTH: u8 = 24;

/// True for `[A-Za-z_][A-Za-z0-9_]*`.
pub fn is_identifier(s: &str) -> bool {
    let mut bytes = s.bytes();
    matches!(bytes.next(), Some(b) if b.is_ascii_alphabetic() || b == b'_')
        && bytes.all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

/// True for a built-in function name.
pub fn is_function(s: &str) -> bool {
    FUNCTIONS.contains(&s)
}

/// Splits `NAME = expr` into (name, its offset, expr, its offset); `None` when the line has no
/// single `=` after an identifier.
pub fn split_definition(line: &str) -> Option<(&str, usize, &str, usize)> {
    let eq = line.find('=')?;
    let (lhs, rhs) = (line.get(..eq)?, line.get(eq + 1..)?);
    let name = lhs.trim();
    if !is_identifier(name) {
        return None;
    }
    let name_at = lhs.len() - lhs.trim_start().len();
    Some((name, name_at, rhs, eq + 1))
}

/// Compiles one expression into `builder`'s program, returning the node of its value.
pub(crate) fn compile_expr<'a, const N: usize, const F: usize>(
    builder: &mut ProgramBuilder<'a, N, F>,
    src: &'a str,
) -> Result<u8, ParseError> {
    const { assert!(N > 0 && N <= 255, "program capacity must be 1..=255 nodes") };
    let floor = builder.program.nodes.len();
    let mut p = Parser {
        src,
        pos: 0,
        b: builder,
        depth: 0,
        floor,
    };
    p.skip_ws();
    if p.pos >= src.len() {
        return Err(p.err_at(0, src.len(), ParseErrorKind::Empty));
    }
    let node = p.expr()?;
    p.skip_ws();
    if let Some(c) = p.peek() {
        let starts_token =
            c.is_ascii_alphanumeric() || matches!(c, b'_' | b'.' | b'(' | b')' | b',' | b'=');
        let kind = if starts_token {
            ParseErrorKind::TrailingInput
        } else {
            ParseErrorKind::UnexpectedChar
        };
        return Err(p.err_at(p.pos, src.len(), kind));
    }
    Ok(node)
}

struct Parser<'a, 'b, const N: usize, const F: usize> {
    src: &'a str,
    pos: usize,
    b: &'b mut ProgramBuilder<'a, N, F>,
    depth: u8,
    /// Nodes below this index belong to earlier expressions (signals) and are never folded away.
    floor: usize,
}

impl<'a, const N: usize, const F: usize> Parser<'a, '_, N, F> {
    fn err_at(&self, start: usize, end: usize, kind: ParseErrorKind) -> ParseError {
        let start = start.min(self.src.len());
        let end = end.clamp(start, self.src.len());
        ParseError {
            start: start.min(u16::MAX as usize) as u16,
            end: end.min(u16::MAX as usize) as u16,
            kind,
        }
    }

    fn peek(&self) -> Option<u8> {
        self.src.as_bytes().get(self.pos).copied()
    }

    fn skip_ws(&mut self) {
        while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
            self.pos += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_ws();
        if self.peek() == Some(c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn push(&mut self, op: Op, start: usize) -> Result<u8, ParseError> {
        let nodes = &mut self.b.program.nodes;
        let index = nodes.len();
        nodes
            .push(op)
            .map_err(|_| self.err_at(start, self.pos, ParseErrorKind::TooManyNodes))?;
        Ok(index as u8)
    }

    fn constant_of(&self, node: u8) -> Option<f32> {
        match self.b.program.nodes.get(node as usize) {
            Some(Op::Const(v)) => Some(*v),
            _ => None,
        }
    }

    /// Removes `node` if it is the last node and a constant, returning its value.
    fn pop_constant(&mut self, node: u8) -> Option<f32> {
        let v = self.constant_of(node)?;
        if node as usize >= self.floor && node as usize + 1 == self.b.program.nodes.len() {
            self.b.program.nodes.pop();
            Some(v)
        } else {
            None
        }
    }

    /// `a op b`, folded when both are constants; `divisor` is the text span of `b`, for the error
    /// of a division by a constant zero.
    fn binary(
        &mut self,
        op: u8,
        a: u8,
        b: u8,
        start: usize,
        divisor: (usize, usize),
    ) -> Result<u8, ParseError> {
        if op == b'/' && self.constant_of(b) == Some(0.0) {
            // The divisor's text without the blanks the parser skipped after it.
            let text = self.src.get(divisor.0..divisor.1).unwrap_or("");
            let end = divisor.0 + text.trim_end().len();
            return Err(self.err_at(divisor.0, end, ParseErrorKind::DivisionByZero));
        }
        if let (Some(x), Some(y)) = (self.constant_of(a), self.constant_of(b)) {
            let len = self.b.program.nodes.len();
            if a as usize >= self.floor && a as usize + 2 == len && b as usize + 1 == len {
                let v = match op {
                    b'+' => x + y,
                    b'-' => x - y,
                    b'*' => x * y,
                    _ => x / y,
                };
                if v.is_finite() {
                    self.b.program.nodes.pop();
                    self.b.program.nodes.pop();
                    return self.push(Op::Const(v), start);
                }
            }
        }
        let op = match op {
            b'+' => Op::Add(a, b),
            b'-' => Op::Sub(a, b),
            b'*' => Op::Mul(a, b),
            _ => Op::Div(a, b),
        };
        self.push(op, start)
    }

    fn expr(&mut self) -> Result<u8, ParseError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.err_at(self.pos, self.pos + 1, ParseErrorKind::TooDeep));
        }
        self.skip_ws();
        let start = self.pos;
        let mut acc = self.term()?;
        loop {
            self.skip_ws();
            match self.peek() {
                Some(op @ (b'+' | b'-')) => {
                    self.pos += 1;
                    self.skip_ws();
                    let rhs_start = self.pos;
                    let rhs = self.term()?;
                    acc = self.binary(op, acc, rhs, start, (rhs_start, self.pos))?;
                }
                _ => break,
            }
        }
        self.depth -= 1;
        Ok(acc)
    }

    fn term(&mut self) -> Result<u8, ParseError> {
        self.skip_ws();
        let start = self.pos;
        let mut acc = self.unary()?;
        loop {
            self.skip_ws();
            match self.peek() {
                Some(op @ (b'*' | b'/')) => {
                    self.pos += 1;
                    self.skip_ws();
                    let rhs_start = self.pos;
                    let rhs = self.unary()?;
                    acc = self.binary(op, acc, rhs, start, (rhs_start, self.pos))?;
                }
                _ => break,
            }
        }
        Ok(acc)
    }

    fn unary(&mut self) -> Result<u8, ParseError> {
        self.skip_ws();
        let start = self.pos;
        if self.peek() == Some(b'-') {
            self.pos += 1;
            self.depth += 1;
            if self.depth > MAX_DEPTH {
                return Err(self.err_at(start, self.pos, ParseErrorKind::TooDeep));
            }
            let a = self.unary()?;
            self.depth -= 1;
            if let Some(v) = self.pop_constant(a) {
                return self.push(Op::Const(-v), start);
            }
            return self.push(Op::Neg(a), start);
        }
        self.primary()
    }

    fn primary(&mut self) -> Result<u8, ParseError> {
        self.skip_ws();
        let start = self.pos;
        let Some(c) = self.peek() else {
            return Err(self.err_at(start, start, ParseErrorKind::UnexpectedEnd));
        };
        if c.is_ascii_digit() || c == b'.' {
            return self.number();
        }
        if c.is_ascii_alphabetic() || c == b'_' {
            while self
                .peek()
                .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
            {
                self.pos += 1;
            }
            let name = self.src.get(start..self.pos).unwrap_or("");
            let end = self.pos;
            if self.eat(b'(') {
                return self.call(name, start, end);
            }
            return self.name(name, start);
        }
        if c == b'(' {
            self.pos += 1;
            let node = self.expr()?;
            if !self.eat(b')') {
                return Err(self.err_at(
                    self.pos,
                    self.pos + 1,
                    ParseErrorKind::ExpectedCloseParen,
                ));
            }
            return Ok(node);
        }
        let kind = if matches!(c, b'+' | b'*' | b'/' | b')' | b',') {
            ParseErrorKind::ExpectedOperand
        } else {
            ParseErrorKind::UnexpectedChar
        };
        Err(self.err_at(start, start + 1, kind))
    }

    fn number(&mut self) -> Result<u8, ParseError> {
        let start = self.pos;
        while self.peek().is_some_and(|c| c.is_ascii_digit() || c == b'.') {
            self.pos += 1;
        }
        if matches!(self.peek(), Some(b'e' | b'E')) {
            self.pos += 1;
            if matches!(self.peek(), Some(b'+' | b'-')) {
                self.pos += 1;
            }
            while self.peek().is_some_and(|c| c.is_ascii_digit()) {
                self.pos += 1;
            }
        }
        let text = self.src.get(start..self.pos).unwrap_or("");
        match text.parse::<f32>() {
            Ok(v) if v.is_finite() => self.push(Op::Const(v), start),
            _ => Err(self.err_at(start, self.pos, ParseErrorKind::BadNumber)),
        }
    }

    fn name(&mut self, name: &'a str, start: usize) -> Result<u8, ParseError> {
        if let Some(s) = self
            .b
            .program
            .signals
            .iter()
            .find(|s: &&Signal<'_>| s.name == name)
        {
            return Ok(s.node);
        }
        let inputs = &mut self.b.program.inputs;
        let k = match inputs.iter().position(|n| *n == name) {
            Some(k) => k,
            None => {
                let k = inputs.len();
                inputs
                    .push(name)
                    .map_err(|_| self.err_at(start, self.pos, ParseErrorKind::TooManyInputs))?;
                k
            }
        };
        self.push(Op::Input(k as u8), start)
    }

    fn call(&mut self, name: &str, start: usize, name_end: usize) -> Result<u8, ParseError> {
        if !is_function(name) {
            return Err(self.err_at(start, name_end, ParseErrorKind::UnknownFunction));
        }
        // Arguments: the first is any expression; later ones are kept as (node, span).
        let mut args: [(u8, usize, usize); 16] = [(0, 0, 0); 16];
        let mut count = 0usize;
        loop {
            self.skip_ws();
            let arg_start = self.pos;
            let node = self.expr()?;
            let slot = args.get_mut(count).ok_or(self.err_at(
                start,
                self.pos,
                ParseErrorKind::WrongArgCount,
            ))?;
            *slot = (node, arg_start, self.pos);
            count += 1;
            if self.eat(b',') {
                continue;
            }
            if self.eat(b')') {
                break;
            }
            self.skip_ws();
            let kind = if self.pos >= self.src.len() {
                ParseErrorKind::ExpectedCloseParen
            } else {
                ParseErrorKind::UnexpectedChar
            };
            return Err(self.err_at(self.pos, self.pos + 1, kind));
        }
        let args = args.get(..count).unwrap_or(&[]);
        let arity_ok = match name {
            "sq" | "abs" => count == 1,
            "mean" => count >= 1,
            "rate" => count == 1 || count == 2,
            "lag" | "hyst" => count == 2,
            _ => count == 3, // clamp
        };
        if !arity_ok {
            return Err(self.err_at(start, self.pos, ParseErrorKind::WrongArgCount));
        }
        let x = args.first().map_or(0, |a| a.0);
        match name {
            "sq" => self.push(Op::Sq(x), start),
            "abs" => self.push(Op::Abs(x), start),
            "mean" => {
                let mut acc = x;
                for &(node, _, _) in args.iter().skip(1) {
                    acc = self.push(Op::Add(acc, node), start)?;
                }
                if count > 1 {
                    let k = self.push(Op::Const(1.0 / count as f32), start)?;
                    acc = self.push(Op::Mul(acc, k), start)?;
                }
                Ok(acc)
            }
            "clamp" => {
                // Pop in reverse order: the last constant is the last node.
                let hi = self.param(args, 2)?;
                let lo = self.param(args, 1)?;
                if lo > hi {
                    return Err(self.err_at(start, self.pos, ParseErrorKind::BadParameter));
                }
                self.push(Op::Clamp { x, lo, hi }, start)
            }
            _ => {
                let p = if count == 2 {
                    self.param(args, 1)?
                } else {
                    DEFAULT_RATE_WINDOW_S
                };
                let positive_required = name != "hyst";
                if (positive_required && p <= 0.0) || p < 0.0 {
                    let (s, e) = args.get(1).map_or((start, self.pos), |a| (a.1, a.2));
                    return Err(self.err_at(s, e, ParseErrorKind::BadParameter));
                }
                let slot = self.b.next_slot;
                if slot as usize >= MAX_STATEFUL {
                    return Err(self.err_at(start, self.pos, ParseErrorKind::TooManyStateful));
                }
                self.b.next_slot += 1;
                let op = match name {
                    "rate" => Op::Rate {
                        x,
                        slot,
                        window_s: p,
                    },
                    "lag" => Op::Lag { x, slot, tau_s: p },
                    _ => Op::Hyst {
                        x,
                        slot,
                        threshold: p,
                    },
                };
                self.push(op, start)
            }
        }
    }

    /// The constant value of argument `i`, removing its node.
    fn param(&mut self, args: &[(u8, usize, usize)], i: usize) -> Result<f32, ParseError> {
        let (node, s, e) = args.get(i).copied().unwrap_or((0, self.pos, self.pos));
        self.pop_constant(node)
            .ok_or(self.err_at(s, e, ParseErrorKind::ConstantRequired))
    }
}
