//! The compiler: signal definitions and feature expressions → a [`Program`].
//!
//! Why beside the parser rather than in [`crate::program`]: the program is what a blob carries and
//! the firmware validates and runs; compiling text is a host-side job (though it allocates nothing,
//! so a firmware could do it too). The grammar is in `parser`, function calls — read from the
//! language's table, [`crate::lang`] — in `call`; errors and lexical rules in [`crate::syntax`].
//! The builder is generic over the number type like the program: `f32` by default, `f64` for the
//! simulator's exact truths.

mod call;
mod parser;

use crate::Real;
use crate::program::{Program, ProgramError, Signal};
use crate::syntax::{self, ParseError, ParseErrorKind};

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
pub struct ProgramBuilder<'a, const N: usize, const F: usize, S = f32> {
    program: Program<'a, N, F, S>,
    next_slot: u8,
}

impl<'a, const N: usize, const F: usize, S: Real> Default for ProgramBuilder<'a, N, F, S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a, const N: usize, const F: usize, S: Real> ProgramBuilder<'a, N, F, S> {
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
        if !syntax::is_identifier(name) || syntax::is_function(name) {
            return Err(name_err(ParseErrorKind::BadName));
        }
        if self.program.signals.iter().any(|s| s.name == name) {
            return Err(name_err(ParseErrorKind::DuplicateSignal));
        }
        if self.program.signals.is_full() {
            return Err(name_err(ParseErrorKind::TooManySignals));
        }
        let node = parser::compile_expr(self, expr)?;
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
        let node = parser::compile_expr(self, expr)?;
        let _ = self.program.features.push(node);
        let _ = self.program.feature_exprs.push(expr.trim());
        Ok(())
    }

    /// One line of a spec: `NAME = expr` defines a signal, anything else is a feature.
    /// Errors are positioned within `line`.
    pub fn line(&mut self, line: &'a str) -> Result<(), ParseError> {
        match syntax::split_definition(line) {
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
    pub fn finish(self) -> Result<Program<'a, N, F, S>, ProgramError> {
        self.program.validate()?;
        Ok(self.program)
    }
}
