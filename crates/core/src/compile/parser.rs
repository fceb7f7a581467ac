//! The recursive-descent grammar of [`crate::syntax`], emitting nodes into a [`ProgramBuilder`] as
//! it goes. Constant sub-expressions are folded, so `-2 * 3` costs no node. A division by a constant
//! zero (`T / 0`, `T / (2 - 2)`, or by a signal defined as `0`) is refused here, pointing at the
//! divisor, rather than giving a feature that is NaN or infinite on every sample. Nesting
//! (parentheses, calls, unary minus) is limited to a fixed depth, so the recursion is bounded
//! whatever the text. Function calls are compiled from the language's table in `call`.

use super::ProgramBuilder;
use crate::Real;
use crate::program::{Op, Signal};
use crate::syntax::{ParseError, ParseErrorKind};

const MAX_DEPTH: u8 = 24;

/// Compiles one expression into `builder`'s program, returning the node of its value.
pub(super) fn compile_expr<'a, const N: usize, const F: usize, S: Real>(
    builder: &mut ProgramBuilder<'a, N, F, S>,
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

pub(super) struct Parser<'a, 'b, const N: usize, const F: usize, S> {
    pub(super) src: &'a str,
    pub(super) pos: usize,
    pub(super) b: &'b mut ProgramBuilder<'a, N, F, S>,
    depth: u8,
    /// Nodes below this index belong to earlier expressions (signals) and are never folded away.
    floor: usize,
}

impl<'a, const N: usize, const F: usize, S: Real> Parser<'a, '_, N, F, S> {
    pub(super) fn err_at(&self, start: usize, end: usize, kind: ParseErrorKind) -> ParseError {
        let start = start.min(self.src.len());
        let end = end.clamp(start, self.src.len());
        ParseError {
            start: start.min(u16::MAX as usize) as u16,
            end: end.min(u16::MAX as usize) as u16,
            kind,
        }
    }

    pub(super) fn peek(&self) -> Option<u8> {
        self.src.as_bytes().get(self.pos).copied()
    }

    pub(super) fn skip_ws(&mut self) {
        while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
            self.pos += 1;
        }
    }

    pub(super) fn eat(&mut self, c: u8) -> bool {
        self.skip_ws();
        if self.peek() == Some(c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    pub(super) fn push(&mut self, op: Op<S>, start: usize) -> Result<u8, ParseError> {
        let nodes = &mut self.b.program.nodes;
        let index = nodes.len();
        nodes
            .push(op)
            .map_err(|_| self.err_at(start, self.pos, ParseErrorKind::TooManyNodes))?;
        Ok(index as u8)
    }

    fn constant_of(&self, node: u8) -> Option<S> {
        match self.b.program.nodes.get(node as usize) {
            Some(Op::Const(v)) => Some(*v),
            _ => None,
        }
    }

    /// Removes `node` if it is the last node and a constant, returning its value.
    pub(super) fn pop_constant(&mut self, node: u8) -> Option<S> {
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
        if op == b'/' && self.constant_of(b) == Some(S::ZERO) {
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

    pub(super) fn expr(&mut self) -> Result<u8, ParseError> {
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
            self.column_suffix();
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

    /// The rest of a column name read from an autopilot log: `.field` and `[instance]` parts after
    /// the first identifier (`sensor_gyro.x`, `IMU[1].GyrX`; [`crate::syntax::is_column_name`]).
    /// Nothing else in the language uses `.` after a name or `[`, so the name stays one token.
    fn column_suffix(&mut self) {
        let bytes = self.src.as_bytes();
        loop {
            let at = self.pos;
            match bytes.get(at) {
                Some(b'.')
                    if bytes
                        .get(at + 1)
                        .is_some_and(|c| c.is_ascii_alphabetic() || *c == b'_') =>
                {
                    self.pos = at + 1;
                    while self
                        .peek()
                        .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
                    {
                        self.pos += 1;
                    }
                }
                Some(b'[') => {
                    let digits = bytes
                        .get(at + 1..)
                        .map_or(0, |r| r.iter().take_while(|c| c.is_ascii_digit()).count());
                    if digits == 0 || bytes.get(at + 1 + digits) != Some(&b']') {
                        return;
                    }
                    self.pos = at + digits + 2;
                }
                _ => return,
            }
        }
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
        match S::parse(text) {
            Some(v) if v.is_finite() => self.push(Op::Const(v), start),
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
}
