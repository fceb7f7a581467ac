//! Parse errors and the lexical rules of feature expressions: what a name is, where a definition
//! splits. The grammar itself and the compilation into program nodes are in [`crate::compile`];
//! the functions, their arity and their parameters in [`crate::lang`], which the messages here list.
//!
//! Grammar (whitespace ignored):
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary)*
//! unary   := '-' unary | primary
//! primary := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//! A `name` is a signal defined earlier or else an input column.

use crate::lang;
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
    fn write_message(self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let text = match self {
            Self::Empty => "the expression is empty",
            Self::UnexpectedChar => "unexpected character",
            Self::UnexpectedEnd => "the expression ends where an operand is expected",
            Self::ExpectedOperand => "expected a number, a name, a function call or '('",
            Self::ExpectedCloseParen => "expected ')'",
            Self::TrailingInput => "unexpected text after the end of the expression",
            Self::BadNumber => "not a valid number",
            Self::UnknownFunction => {
                f.write_str("unknown function (known: ")?;
                lang::write_names(f)?;
                return f.write_str(")");
            }
            Self::WrongArgCount => {
                f.write_str("wrong number of arguments (")?;
                lang::write_signatures(f)?;
                return f.write_str(")");
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
            Self::TooManyStateful => {
                f.write_str("too many ")?;
                lang::write_stateful_names(f)?;
                return f.write_str(" operators");
            }
            Self::DuplicateSignal => "a signal with this name is already defined",
            Self::BadName => "a signal name must be an identifier that is not a function name",
        };
        f.write_str(text)
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
        write!(f, "column {}: ", self.column())?;
        self.kind.write_message(f)
    }
}

/// True for `[A-Za-z_][A-Za-z0-9_]*`.
pub fn is_identifier(s: &str) -> bool {
    let mut bytes = s.bytes();
    matches!(bytes.next(), Some(b) if b.is_ascii_alphabetic() || b == b'_')
        && bytes.all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

/// True for a column name the expressions can spell: an identifier, optionally followed by
/// `.field` and `[instance]` parts, as the columns of autopilot logs are named (`sensor_gyro.x`,
/// `IMU[1].GyrX`, `sensor_accel[2].temperature`). Signal names stay plain identifiers.
pub fn is_column_name(s: &str) -> bool {
    let Some(first) = s.split(['.', '[']).next() else {
        return false;
    };
    if !is_identifier(first) {
        return false;
    }
    let mut rest = s.get(first.len()..).unwrap_or("");
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('.') {
            let part = r.split(['.', '[']).next().unwrap_or("");
            if !is_identifier(part) {
                return false;
            }
            rest = r.get(part.len()..).unwrap_or("");
        } else if let Some(r) = rest.strip_prefix('[') {
            let digits = r.bytes().take_while(u8::is_ascii_digit).count();
            if digits == 0 || r.as_bytes().get(digits) != Some(&b']') {
                return false;
            }
            rest = r.get(digits + 1..).unwrap_or("");
        } else {
            return false;
        }
    }
    true
}

/// True for a built-in function name.
pub fn is_function(s: &str) -> bool {
    lang::function(s).is_some()
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
