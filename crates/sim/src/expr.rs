//! A small reference evaluator of the core's feature-expression language over a [`Table`].
//!
//! Why: the truth file's expressions are strings other tools will compile with the core; this
//! evaluator lets the simulator's own tests (and users' scripts) check that every expression parses,
//! names only existing columns, and reproduces the bias. It uses the same operator definitions as
//! [`crate::ops`]. It is a checking tool, not the implementation that trains or flies.
//!
//! Grammar: `expr := term (('+'|'-') term)*`, `term := unary (('*'|'/') unary)*`,
//! `unary := '-' unary | primary`, `primary := number | name | name '(' args ')' | '(' expr ')'`;
//! functions `sq(x)`, `abs(x)`, `mean(a, ...)`, `rate(x[, window_s])`, `lag(x, tau_s)`, `hyst(x, th)`,
//! `clamp(x, lo, hi)`; names are columns or signals.

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::ops::{Hyst, Lag, RATE_WINDOW_S, Rate};
use crate::writer::Table;

#[derive(Debug, Clone)]
enum Node {
    Num(f64),
    Col(usize),
    Neg(Box<Node>),
    Bin(char, Box<Node>, Box<Node>),
    Sq(Box<Node>),
    Abs(Box<Node>),
    Mean(Vec<Node>),
    Clamp(Box<Node>, Box<Node>, Box<Node>),
    Rate(Box<Node>, Rate),
    Lag(Box<Node>, Lag),
    Hyst(Box<Node>, Hyst),
}

impl Node {
    fn eval(&mut self, row: &[f64], dt: f64) -> f64 {
        match self {
            Node::Num(v) => *v,
            Node::Col(i) => row.get(*i).copied().unwrap_or(f64::NAN),
            Node::Neg(a) => -a.eval(row, dt),
            Node::Bin(op, a, b) => {
                let (x, y) = (a.eval(row, dt), b.eval(row, dt));
                match op {
                    '+' => x + y,
                    '-' => x - y,
                    '*' => x * y,
                    _ => x / y,
                }
            }
            Node::Sq(a) => {
                let x = a.eval(row, dt);
                x * x
            }
            Node::Abs(a) => a.eval(row, dt).abs(),
            Node::Mean(args) => {
                let n = args.len().max(1) as f64;
                args.iter_mut().map(|a| a.eval(row, dt)).sum::<f64>() / n
            }
            Node::Clamp(x, lo, hi) => {
                let (x, lo, hi) = (x.eval(row, dt), lo.eval(row, dt), hi.eval(row, dt));
                x.max(lo).min(hi)
            }
            Node::Rate(a, r) => {
                let x = a.eval(row, dt);
                r.step(x, dt)
            }
            Node::Lag(a, l) => {
                let x = a.eval(row, dt);
                l.step(x, dt)
            }
            Node::Hyst(a, h) => {
                let x = a.eval(row, dt);
                h.step(x)
            }
        }
    }
}

struct Parser<'a> {
    src: &'a str,
    pos: usize,
    names: &'a [String],
    signals: &'a BTreeMap<String, Node>,
}

impl Parser<'_> {
    fn err(&self, msg: impl Into<String>) -> Error {
        Error::Expr {
            expr: self.src.to_string(),
            message: format!("at column {}: {}", self.pos + 1, msg.into()),
        }
    }

    fn peek(&mut self) -> Option<char> {
        let rest = self.src.get(self.pos..).unwrap_or("");
        let trimmed = rest.trim_start();
        self.pos += rest.len() - trimmed.len();
        trimmed.chars().next()
    }

    fn eat(&mut self, c: char) -> bool {
        if self.peek() == Some(c) {
            self.pos += c.len_utf8();
            true
        } else {
            false
        }
    }

    fn expr(&mut self) -> Result<Node> {
        let mut left = self.term()?;
        while let Some(op @ ('+' | '-')) = self.peek() {
            self.pos += 1;
            let right = self.term()?;
            left = Node::Bin(op, Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn term(&mut self) -> Result<Node> {
        let mut left = self.unary()?;
        while let Some(op @ ('*' | '/')) = self.peek() {
            self.pos += 1;
            let right = self.unary()?;
            left = Node::Bin(op, Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn unary(&mut self) -> Result<Node> {
        if self.eat('-') {
            return Ok(Node::Neg(Box::new(self.unary()?)));
        }
        self.primary()
    }

    fn constant(&mut self) -> Result<f64> {
        match self.expr()? {
            Node::Num(v) => Ok(v),
            Node::Neg(b) => match *b {
                Node::Num(v) => Ok(-v),
                _ => Err(self.err("expected a numeric constant")),
            },
            _ => Err(self.err("expected a numeric constant")),
        }
    }

    fn primary(&mut self) -> Result<Node> {
        let Some(c) = self.peek() else {
            return Err(self.err("unexpected end"));
        };
        if c == '(' {
            self.pos += 1;
            let e = self.expr()?;
            if !self.eat(')') {
                return Err(self.err("expected ')'"));
            }
            return Ok(e);
        }
        let rest = self.src.get(self.pos..).unwrap_or("");
        if c.is_ascii_digit() || c == '.' {
            let len = rest
                .find(|ch: char| !(ch.is_ascii_digit() || ch == '.' || ch == 'e' || ch == 'E'))
                .unwrap_or(rest.len());
            let text = rest.get(..len).unwrap_or("");
            let v: f64 = text
                .parse()
                .map_err(|_| self.err(format!("bad number \"{text}\"")))?;
            self.pos += len;
            return Ok(Node::Num(v));
        }
        if c.is_ascii_alphabetic() || c == '_' {
            let len = rest
                .find(|ch: char| !(ch.is_ascii_alphanumeric() || ch == '_'))
                .unwrap_or(rest.len());
            let name = rest.get(..len).unwrap_or("").to_string();
            self.pos += len;
            if self.eat('(') {
                return self.call(&name);
            }
            if let Some(node) = self.signals.get(&name) {
                return Ok(node.clone());
            }
            return self
                .names
                .iter()
                .position(|n| *n == name)
                .map(Node::Col)
                .ok_or_else(|| {
                    self.err(format!(
                        "unknown column or signal \"{name}\" (columns: {})",
                        self.names.join(", ")
                    ))
                });
        }
        Err(self.err(format!("unexpected '{c}'")))
    }

    fn call(&mut self, name: &str) -> Result<Node> {
        let mut args = vec![self.expr()?];
        let mut consts = Vec::new();
        while self.eat(',') {
            if matches!(name, "rate" | "lag" | "hyst") {
                consts.push(self.constant()?);
            } else {
                args.push(self.expr()?);
            }
        }
        if !self.eat(')') {
            return Err(self.err("expected ')' or ','"));
        }
        let one = |args: Vec<Node>| args.into_iter().next().map(Box::new);
        let node = match (name, args.len(), consts.as_slice()) {
            ("sq", 1, []) => one(args).map(Node::Sq),
            ("abs", 1, []) => one(args).map(Node::Abs),
            ("mean", _, []) => Some(Node::Mean(args)),
            ("clamp", 3, []) => {
                let mut it = args.into_iter().map(Box::new);
                match (it.next(), it.next(), it.next()) {
                    (Some(x), Some(lo), Some(hi)) => Some(Node::Clamp(x, lo, hi)),
                    _ => None,
                }
            }
            ("rate", 1, []) => one(args).map(|a| Node::Rate(a, Rate::new(RATE_WINDOW_S))),
            ("rate", 1, [w]) if *w > 0.0 => one(args).map(|a| Node::Rate(a, Rate::new(*w))),
            ("lag", 1, [tau]) if *tau > 0.0 => one(args).map(|a| Node::Lag(a, Lag::new(*tau))),
            ("hyst", 1, [th]) => one(args).map(|a| Node::Hyst(a, Hyst::new(*th))),
            _ => None,
        };
        node.ok_or_else(|| self.err(format!("bad call of {name}(...)")))
    }
}

fn parse(src: &str, names: &[String], signals: &BTreeMap<String, Node>) -> Result<Node> {
    let mut p = Parser {
        src,
        pos: 0,
        names,
        signals,
    };
    let node = p.expr()?;
    if p.peek().is_some() {
        return Err(p.err("unexpected text after the expression"));
    }
    Ok(node)
}

/// Evaluates `expr` over every row of `table` with sample period `dt_s`; `signals` maps names to
/// their defining expressions (which may use earlier signals in name order).
pub fn evaluate(
    table: &Table,
    signals: &BTreeMap<String, String>,
    expr: &str,
    dt_s: f64,
) -> Result<Vec<f64>> {
    let mut defs = BTreeMap::new();
    for (name, text) in signals {
        let node = parse(text, &table.names, &defs)?;
        defs.insert(name.clone(), node);
    }
    let mut node = parse(expr, &table.names, &defs)?;
    let rows = table.rows();
    let mut row = vec![0.0; table.columns.len()];
    let mut out = Vec::with_capacity(rows);
    for r in 0..rows {
        for (slot, col) in row.iter_mut().zip(&table.columns) {
            *slot = col.get(r).copied().unwrap_or(f64::NAN);
        }
        out.push(node.eval(&row, dt_s));
    }
    Ok(out)
}
