//! Function calls, compiled from the language's table ([`crate::lang::FUNCTIONS`]): the name, the
//! number of arguments, the parameters' constancy, defaults and domains, the state slot and the
//! operation all come from the function's row, so nothing here names a function.

use super::parser::Parser;
use crate::lang::{self, Domain, Function, MAX_PARAMS};
use crate::program::Op;
use crate::syntax::{ParseError, ParseErrorKind};
use crate::{MAX_STATEFUL, Real};

/// Most arguments a call may have (`mean` of many columns).
const MAX_ARGS: usize = 16;

/// An argument: its node and the byte span of its text.
type Arg = (u8, usize, usize);

impl<const N: usize, const F: usize, S: Real> Parser<'_, '_, N, F, S> {
    /// `name(args)`, the opening parenthesis already read; `start..name_end` is the name.
    pub(super) fn call(
        &mut self,
        name: &str,
        start: usize,
        name_end: usize,
    ) -> Result<u8, ParseError> {
        let Some(function) = lang::function(name) else {
            return Err(self.err_at(start, name_end, ParseErrorKind::UnknownFunction));
        };
        // Arguments: the first is any expression; later ones are kept as (node, span).
        let mut args: [Arg; MAX_ARGS] = [(0, 0, 0); MAX_ARGS];
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
        if !function.admits_arg_count(count) {
            return Err(self.err_at(start, self.pos, ParseErrorKind::WrongArgCount));
        }
        match function.op {
            None => self.mean(args, start),
            Some(code) => {
                let x = args.first().map_or(0, |a| a.0);
                let params = self.params(function, args, start)?;
                let slot = if function.stateful {
                    self.take_slot(start)?
                } else {
                    0
                };
                let n = function.params.len().min(MAX_PARAMS);
                let op = Op::function(code, x, slot, params.get(..n).unwrap_or(&[]))
                    .ok_or(self.err_at(start, self.pos, ParseErrorKind::UnknownFunction))?;
                self.push(op, start)
            }
        }
    }

    /// `mean(a, b, …)`: `(a + b + …) · (1/k)`, summed left to right.
    fn mean(&mut self, args: &[Arg], start: usize) -> Result<u8, ParseError> {
        let mut acc = args.first().map_or(0, |a| a.0);
        for &(node, _, _) in args.iter().skip(1) {
            acc = self.push(Op::Add(acc, node), start)?;
        }
        if args.len() > 1 {
            let k = self.push(Op::Const(S::ONE / S::from_u8(args.len() as u8)), start)?;
            acc = self.push(Op::Mul(acc, k), start)?;
        }
        Ok(acc)
    }

    /// The function's parameters (the arguments after its operand, if it has one): constants, removed from the program
    /// last first (the last constant is the last node), defaults for those left out, each checked
    /// against its domain in order.
    fn params(
        &mut self,
        function: &Function,
        args: &[Arg],
        start: usize,
    ) -> Result<[S; MAX_PARAMS], ParseError> {
        let mut values = [S::ZERO; MAX_PARAMS];
        let first = function.first_param();
        for (i, p) in function.params.iter().enumerate().rev() {
            let value = match (args.get(i + first), p.default) {
                (Some(_), _) | (None, None) => self.param(args, i + first)?,
                (None, Some(default)) => S::from_f32(default),
            };
            if let Some(v) = values.get_mut(i) {
                *v = value;
            }
        }
        let mut prev = S::ZERO;
        for (i, (p, &v)) in function.params.iter().zip(&values).enumerate() {
            if !p.domain.admits(v, prev) {
                let whole = (start, self.pos);
                let (s, e) = match p.domain {
                    Domain::NotBelowPrevious => whole,
                    _ => args.get(i + first).map_or(whole, |a| (a.1, a.2)),
                };
                return Err(self.err_at(s, e, ParseErrorKind::BadParameter));
            }
            prev = v;
        }
        Ok(values)
    }

    /// The next free state slot.
    fn take_slot(&mut self, start: usize) -> Result<u8, ParseError> {
        let slot = self.b.next_slot;
        if slot as usize >= MAX_STATEFUL {
            return Err(self.err_at(start, self.pos, ParseErrorKind::TooManyStateful));
        }
        self.b.next_slot += 1;
        Ok(slot)
    }

    /// The constant value of argument `i`, removing its node.
    fn param(&mut self, args: &[Arg], i: usize) -> Result<S, ParseError> {
        let (node, s, e) = args.get(i).copied().unwrap_or((0, self.pos, self.pos));
        self.pop_constant(node)
            .ok_or(self.err_at(s, e, ParseErrorKind::ConstantRequired))
    }
}
