//! Feature expressions as syntax values, with one printer (feature `alloc`).
//!
//! Why: host code builds expressions — the diagnosis' candidate features, the cubic baseline's
//! clamp, the simulator's truth — and assembling them with `format!` at each site leaves each site
//! to decide on its own where parentheses go and how a number is spelled; a missed pair of
//! parentheses silently changes the feature. Here an expression is a tree ([`Expr`]) built with
//! constructors and operators (`name("T") * rate(name("T"))`, `lag(x, 2400.0)`, `a - b`), and
//! [`Expr`]'s `Display` is the only printer: it writes the fewest parentheses that make the
//! compiler ([`crate::compile`]) build exactly the tree's program (tested: printing and compiling
//! gives the same program as printing with every parenthesis). It lives in the core, behind the
//! `alloc` feature, so the simulator, the trainer and the diagnosis share it without depending on
//! each other; the firmware never enables it.

use crate::lang::DEFAULT_RATE_WINDOW_S;
use alloc::borrow::ToOwned;
use alloc::boxed::Box;
use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

/// How a number literal is spelled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Notation {
    /// Positional, shortest round-trip digits: `2400`, `0.05`.
    Plain,
    /// Scientific, shortest round-trip digits: `2.15e1`.
    Scientific,
}

/// A binary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `*`.
    Mul,
    /// `/`.
    Div,
}

impl BinOp {
    fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
        }
    }

    fn precedence(self) -> u8 {
        match self {
            BinOp::Add | BinOp::Sub => SUM,
            BinOp::Mul | BinOp::Div => PRODUCT,
        }
    }
}

/// A feature expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// An input column or a signal.
    Name(String),
    /// A number literal (a non-finite one prints as `1e999`, which the compiler refuses).
    Num(f64, Notation),
    /// Source text taken as one operand, parenthesised where it is an operator's operand (a
    /// user's expression the tree embeds, printed as given).
    Text(String),
    /// `-a`.
    Neg(Box<Expr>),
    /// `a op b`.
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `name(args)`.
    Call(String, Vec<Expr>),
}

// Binding strength, loosest first.
const TEXT: u8 = 0;
const SUM: u8 = 1;
const PRODUCT: u8 = 2;
const UNARY: u8 = 3;
const ATOM: u8 = 4;

impl Expr {
    /// An input column or signal.
    pub fn name(name: &str) -> Self {
        Expr::Name(name.to_owned())
    }

    /// A number, spelled positionally.
    pub fn num(v: f64) -> Self {
        Expr::Num(v, Notation::Plain)
    }

    /// A number, spelled in scientific notation.
    pub fn sci(v: f64) -> Self {
        Expr::Num(v, Notation::Scientific)
    }

    /// Source text as one operand.
    pub fn text(text: &str) -> Self {
        Expr::Text(text.to_owned())
    }

    /// A call of the function `name` (see [`crate::lang::FUNCTIONS`]; an unknown name or a wrong
    /// number of arguments is the compiler's error, with its position).
    pub fn call(name: &str, args: impl IntoIterator<Item = Expr>) -> Self {
        Expr::Call(name.to_owned(), args.into_iter().collect())
    }

    fn precedence(&self) -> u8 {
        match self {
            Expr::Name(_) | Expr::Call(..) => ATOM,
            Expr::Num(v, _) if v.is_sign_negative() => UNARY,
            Expr::Num(..) => ATOM,
            Expr::Text(_) => TEXT,
            Expr::Neg(_) => UNARY,
            Expr::Binary(op, ..) => op.precedence(),
        }
    }

    /// Writes `self`, in parentheses when it binds looser than `min`.
    fn write_operand(&self, f: &mut fmt::Formatter<'_>, min: u8) -> fmt::Result {
        if self.precedence() < min {
            write!(f, "({self})")
        } else {
            write!(f, "{self}")
        }
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Expr::Name(n) | Expr::Text(n) => f.write_str(n),
            Expr::Num(v, _) if !v.is_finite() => {
                f.write_str(if *v < 0.0 { "-1e999" } else { "1e999" })
            }
            Expr::Num(v, Notation::Plain) => write!(f, "{v}"),
            Expr::Num(v, Notation::Scientific) => write!(f, "{v:e}"),
            Expr::Neg(a) => {
                f.write_str("-")?;
                a.write_operand(f, UNARY)
            }
            Expr::Binary(op, a, b) => {
                let p = op.precedence();
                a.write_operand(f, p)?;
                write!(f, " {} ", op.symbol())?;
                // The grammar is left-associative: an operand on the right at the same binding
                // strength keeps its parentheses.
                b.write_operand(f, p + 1)
            }
            Expr::Call(name, args) => {
                write!(f, "{name}(")?;
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{a}")?;
                }
                f.write_str(")")
            }
        }
    }
}

/// The line `name = expr` that defines a signal.
pub fn define(name: &str, expr: &Expr) -> String {
    alloc::format!("{name} = {expr}")
}

/// An input column or signal.
pub fn name(name: &str) -> Expr {
    Expr::name(name)
}

/// `sq(x)`.
pub fn sq(x: Expr) -> Expr {
    Expr::call("sq", [x])
}

/// `abs(x)`.
pub fn abs(x: Expr) -> Expr {
    Expr::call("abs", [x])
}

/// `mean(a, ...)`.
pub fn mean(args: impl IntoIterator<Item = Expr>) -> Expr {
    Expr::call("mean", args)
}

/// `rate(x)`, the default window.
pub fn rate(x: Expr) -> Expr {
    Expr::call("rate", [x])
}

/// `rate(x, window_s)`, written `rate(x)` when the window is the default.
pub fn rate_window(x: Expr, window_s: f64) -> Expr {
    if window_s == f64::from(DEFAULT_RATE_WINDOW_S) {
        rate(x)
    } else {
        Expr::call("rate", [x, Expr::num(window_s)])
    }
}

/// `lag(x, tau_s)`.
pub fn lag(x: Expr, tau_s: f64) -> Expr {
    Expr::call("lag", [x, Expr::num(tau_s)])
}

/// `hyst(x, threshold)`.
pub fn hyst(x: Expr, threshold: f64) -> Expr {
    Expr::call("hyst", [x, Expr::num(threshold)])
}

/// `warmup(tau_s)`: `e^(−t_on/τ)`, `t_on` the seconds since power-on.
pub fn warmup(tau_s: f64) -> Expr {
    Expr::call("warmup", [Expr::num(tau_s)])
}

/// `clamp(x, lo, hi)`.
pub fn clamp(x: Expr, lo: Expr, hi: Expr) -> Expr {
    Expr::call("clamp", [x, lo, hi])
}

impl From<f64> for Expr {
    fn from(v: f64) -> Self {
        Expr::num(v)
    }
}

impl From<&str> for Expr {
    fn from(name: &str) -> Self {
        Expr::name(name)
    }
}

macro_rules! binary {
    ($trait:ident, $method:ident, $op:expr) => {
        impl core::ops::$trait for Expr {
            type Output = Expr;
            fn $method(self, rhs: Expr) -> Expr {
                Expr::Binary($op, Box::new(self), Box::new(rhs))
            }
        }
    };
}

binary!(Add, add, BinOp::Add);
binary!(Sub, sub, BinOp::Sub);
binary!(Mul, mul, BinOp::Mul);
binary!(Div, div, BinOp::Div);

impl core::ops::Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        Expr::Neg(Box::new(self))
    }
}
