//! The prior over structures: a candidate's description length in the feature language.
//!
//! Why: the refit's log evidence prices a candidate's column — its weight at its prior precision —
//! but not the choice of the expression that made the column. Two candidates whose columns
//! explain the run equally, `hyst(x − c, h)` and `hyst(lag(x, τ) − c, h)`, or `lag(g, τ)` and
//! `lag(g * supply_v, τ)` on a run whose supply barely moves, were then a tie, and the verdict
//! said "cannot tell" where one explains as much with a function or a factor fewer. The
//! comparison between structures needs a prior over them, as in any Bayesian comparison of
//! models.
//!
//! The prior: each symbol of an expression — a function, a binary operator between two signals,
//! an input — is drawn uniformly from the language's alphabet: its functions
//! ([`tcomp_core::lang::FUNCTIONS`]), its four binary operators and the run's inputs — the
//! sensor's temperatures, the differences of its thermometer pairs (a gradient is one input, as it
//! is one atom of the composition search, [`crate::compose`]) and its non-thermal columns
//! ([`crate::candidates::Sources`]). An expression of `s` symbols then has prior probability
//! `K^-s`, and its description length is `s ln K` nats — the
//! simplest form of the expression prior of Guimerà et al., "A Bayesian machine scientist to aid
//! in the solution of challenging scientific problems" (Science Advances, 2020), and the Bayesian
//! reading of minimum description length. Numbers are no symbols: a shift `x − c`, a scale `2 x`,
//! a time constant or a threshold is a parameter the search estimates (the placebo leg prices the
//! search, [`crate::placebo`]). A candidate that replaces features is priced by what it adds:
//! its symbols less those of the features it replaces.
//!
//! Where it acts: the verdict ranks the candidates that pass by their refit's log evidence less
//! their description length, and two of them are a tie only when those differ by less than
//! [`crate::score::INDISTINCT_NATS`] ([`crate::verdict`]). On the simulated runs of the tests a
//! symbol costs 2.6–3 nats: a structure one symbol richer must explain the run by that much more
//! ("positive" evidence on Kass and Raftery's scale) to be preferred.

use crate::candidates::Sources;
use tcomp_core::lang::FUNCTIONS;

/// The binary operators of the language: `+`, `-`, `*`, `/`.
const BINARY_OPERATORS: usize = 4;

/// Nats per symbol: `ln K`, `K` the language's functions, its binary operators and the run's
/// inputs (each name once, and each pair of thermometers).
pub fn nats_per_symbol(src: &Sources) -> f64 {
    let mut names: Vec<&str> = src
        .temperatures
        .iter()
        .chain(&src.thermometers)
        .chain(&src.inputs)
        .map(String::as_str)
        .collect();
    names.sort_unstable();
    names.dedup();
    let n = src.thermometers.len();
    let gradients = n * n.saturating_sub(1) / 2;
    ((FUNCTIONS.len() + BINARY_OPERATORS + names.len() + gradients) as f64).ln()
}

/// A token of an expression's text.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Token {
    /// A name: a function (followed by `(`) or an input.
    Name,
    /// A number literal.
    Number,
    /// `+`, `-`, `*` or `/`.
    Operator(u8),
    /// `(`.
    Open,
    /// `)`.
    Close,
    /// `,`.
    Comma,
}

/// The tokens of `e`, in order (white space dropped; a number's exponent is part of it).
fn tokens(e: &str) -> Vec<Token> {
    let b = e.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(&ch) = b.get(i) {
        i += 1;
        match ch {
            b'(' => out.push(Token::Open),
            b')' => out.push(Token::Close),
            b',' => out.push(Token::Comma),
            b'+' | b'-' | b'*' | b'/' => out.push(Token::Operator(ch)),
            c if c.is_ascii_alphabetic() || c == b'_' => {
                while b
                    .get(i)
                    .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
                {
                    i += 1;
                }
                out.push(Token::Name);
            }
            c if c.is_ascii_digit() || c == b'.' => {
                while let Some(&c) = b.get(i) {
                    let exponent_sign = (c == b'+' || c == b'-')
                        && matches!(b.get(i.wrapping_sub(1)), Some(b'e' | b'E'));
                    if c.is_ascii_digit() || c == b'.' || c == b'e' || c == b'E' || exponent_sign {
                        i += 1;
                    } else {
                        break;
                    }
                }
                out.push(Token::Number);
            }
            _ => {}
        }
    }
    out
}

/// The symbols of one expression: its names (functions and inputs), and its binary operators
/// between two operands that are not numbers; the difference of two inputs (a gradient) is one.
/// A sign, a shift by a number or a scale by one is a parameter, not a symbol. Parsed by the language's grammar ([`tcomp_core::syntax`]), so that
/// precedence decides what an operator's operands are (`x * 1e-3 + y` adds two signals); text
/// that does not parse counts its names.
pub fn symbols(e: &str) -> usize {
    let t = tokens(e);
    let mut p = Parser { t: &t, at: 0 };
    match p.expr() {
        Some(part) if p.at == t.len() => part.symbols,
        _ => t.iter().filter(|k| **k == Token::Name).count(),
    }
}

/// A parsed part of an expression: its symbols, whether it reads no signal (a number), and
/// whether it is a bare name (an input, no call).
#[derive(Clone, Copy)]
struct Part {
    symbols: usize,
    constant: bool,
    name: bool,
}

impl Part {
    /// `a op b`: an operator between two signals is a symbol; the difference of two inputs is
    /// one — a gradient, an atom of the search as an input is ([`crate::compose`]).
    fn binary(a: Part, op: u8, b: Part) -> Part {
        let symbols = if op == b'-' && a.name && b.name {
            1
        } else {
            a.symbols + b.symbols + usize::from(!a.constant && !b.constant)
        };
        Part {
            symbols,
            constant: a.constant && b.constant,
            name: false,
        }
    }
}

/// A recursive-descent reading of the grammar in [`tcomp_core::syntax`], counting symbols.
struct Parser<'a> {
    t: &'a [Token],
    at: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<Token> {
        self.t.get(self.at).copied()
    }

    fn eat(&mut self, k: Token) -> bool {
        let hit = self.peek() == Some(k);
        self.at += usize::from(hit);
        hit
    }

    /// The operator at the cursor, consumed.
    fn operator(&mut self) -> Option<u8> {
        let Some(Token::Operator(op)) = self.peek() else {
            return None;
        };
        self.at += 1;
        Some(op)
    }

    /// `expr := term (('+' | '-') term)*` and `term := unary (('*' | '/') unary)*`, read left
    /// to right as one: the count does not depend on which operator binds first, since a number
    /// joined to a signal is a signal (`a * 2 + b` and `a * (2 + b)` both hold three symbols).
    fn expr(&mut self) -> Option<Part> {
        let mut acc = self.unary()?;
        while let Some(op) = self.operator() {
            let rhs = self.unary()?;
            acc = Part::binary(acc, op, rhs);
        }
        Some(acc)
    }

    /// `unary := '-' unary | primary`.
    fn unary(&mut self) -> Option<Part> {
        if self.operator().is_some() {
            let part = self.unary()?;
            return Some(Part {
                name: false,
                ..part
            });
        }
        self.primary()
    }

    /// `primary := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'`.
    fn primary(&mut self) -> Option<Part> {
        match self.peek()? {
            Token::Number => {
                self.at += 1;
                Some(Part {
                    symbols: 0,
                    constant: true,
                    name: false,
                })
            }
            Token::Name => {
                self.at += 1;
                let mut part = Part {
                    symbols: 1,
                    constant: false,
                    name: true,
                };
                if self.eat(Token::Open) {
                    part.name = false;
                    loop {
                        part.symbols += self.expr()?.symbols;
                        if !self.eat(Token::Comma) {
                            break;
                        }
                    }
                    if !self.eat(Token::Close) {
                        return None;
                    }
                }
                Some(part)
            }
            Token::Open => {
                self.at += 1;
                let part = self.expr()?;
                self.eat(Token::Close).then_some(Part {
                    name: false,
                    ..part
                })
            }
            _ => None,
        }
    }
}

/// A candidate's description length in nats: the symbols of its expressions less those of the
/// features it replaces, at `per_symbol` nats each.
pub fn nats(expressions: &[String], replaces: &[String], per_symbol: f64) -> f64 {
    let count = |es: &[String]| es.iter().map(|e| symbols(e)).sum::<usize>() as f64;
    (count(expressions) - count(replaces)) * per_symbol
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_operators_between_signals_are_symbols_numbers_are_not() {
        assert_eq!(symbols("supply_v"), 1);
        assert_eq!(symbols("lag(t_qma_c, 1400)"), 2);
        // A gradient is one input.
        assert_eq!(symbols("t_anode_c - t_cathode_c"), 1);
        assert_eq!(symbols("lag(t_anode_c - t_cathode_c, 1400)"), 2);
        assert_eq!(
            symbols("rate(t_anode_c - t_shell_c)"),
            symbols("rate(t_shell_c, 64)")
        );
        assert_eq!(
            symbols("lag((t_anode_c - t_cathode_c) * supply_v, 1300)"),
            4
        );
        assert_eq!(symbols("hyst(t_qma_c - t_case_c - 0.402, 0.014)"), 2);
        assert_eq!(symbols("t_qma_c - lag(t_qma_c, 60)"), 4);
        // A shift, a sign, a scale and an exponent are parameters.
        assert_eq!(symbols("hyst(t_qma_c - 5.65, 29)"), 2);
        assert_eq!(symbols("hyst(lag(t_qma_c, 950) - 8.62, 16)"), 3);
        assert_eq!(symbols("hyst(t_qma_c + -5.65, 29)"), 2);
        assert_eq!(symbols("2 * t_qma_c"), 1);
        assert_eq!(symbols("-t_qma_c"), 1);
        assert_eq!(symbols("clamp(rate(t_qma_c, 810), -2.27e-2, 9.45e-3)"), 3);
        assert_eq!(symbols("t_qma_c * 1e-3 + supply_v"), 3);
        assert_eq!(symbols("1 + 2 * t_qma_c"), 1);
        // The same expression however it is spaced.
        assert_eq!(symbols("(t_anode_c-t_shell_c)*rate(T,53)"), 4);
    }

    #[test]
    fn a_replacement_is_priced_by_what_it_adds() {
        let e = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert_eq!(nats(&e(&["lag(T, 900)"]), &e(&["T"]), 2.0), 2.0);
        assert_eq!(
            nats(&e(&["lag(t_qma_c, 120)", "lag(t_qma_c, 1300)"]), &[], 1.5),
            6.0
        );
    }

    #[test]
    fn each_symbol_costs_the_log_of_the_alphabet() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let src = Sources {
            temperatures: s(&["T", "t_qma_c"]),
            thermometers: s(&["t_qma_c", "t_case_c"]),
            inputs: s(&["supply_v"]),
            environment: s(&["t_chamber_c"]),
            outputs: s(&["acc_x"]),
        };
        // Four inputs and one gradient (the chamber and the outputs are none), the functions,
        // four operators.
        let k = FUNCTIONS.len() + 4 + 4 + 1;
        assert!((nats_per_symbol(&src) - (k as f64).ln()).abs() < 1e-12);
    }
}
