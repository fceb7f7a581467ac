//! Fuzzing the expression parser: raw text of every kind, and expressions generated from the grammar
//! with a model of what the parser must make of them.
//!
//! The structured generator builds a syntax tree over the operator table of `program.rs` (inputs,
//! signals, constants, `+ - * /`, unary minus, parentheses, `sq abs mean rate lag hyst clamp` with
//! their arities and parameters), renders it as text with the parentheses precedence needs, and
//! predicts the parser's verdict from the tree: constant folding in f32 in the parser's order, the
//! nesting depth as the parser counts it, parameter domains, state slots and a bound on the nodes.
//! A spec the model calls valid must compile, validate and run; one it calls invalid must fail with
//! one of the predicted reasons.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use proptest::prelude::*;
use tcomp_core::{MAX_STATEFUL, ParseErrorKind as K, ProgramBuilder, ProgramState, StepError};

/// Cases per fuzz property in the normal `cargo test` run.
const FUZZ_CASES: u32 = 100_000;
/// The parser's nesting limit (`MAX_DEPTH` in `compile/parser.rs`).
const MAX_DEPTH: usize = 24;
/// Program capacity used by the structured cases: the largest a program may have.
const NODES: usize = 255;

const INPUTS: [&str; 6] = ["t_a", "t_b", "T", "x1", "coil_c", "supply_v"];

/// Compiles `lines` (a spec) into a program with capacity `N`, checking every error's position,
/// then runs a valid program over finite samples: features come out finite or as a typed error.
fn compile_and_run<const N: usize>(
    lines: &[&str],
    samples: &[[f32; 7]],
) -> Result<(), TestCaseError> {
    let mut b = ProgramBuilder::<N, 8>::new();
    for line in lines {
        if let Err(e) = b.line(line) {
            prop_assert!(e.start <= e.end, "{e:?} in {line:?}");
            prop_assert!(usize::from(e.end) <= line.len(), "{e:?} in {line:?}");
            prop_assert!(!e.to_string().is_empty());
            return Ok(());
        }
    }
    let Ok(program) = b.finish() else {
        return Ok(());
    };
    prop_assert!(program.validate().is_ok());
    run(&program, samples)
}

/// Steps `program` over `samples` (six input values and a time step each, all finite).
fn run<const N: usize>(
    program: &tcomp_core::Program<'_, N, 8>,
    samples: &[[f32; 7]],
) -> Result<(), TestCaseError> {
    let mut state = ProgramState::<N>::new();
    let mut out = [0f32; 8];
    for s in samples {
        let inputs: Vec<f32> = program
            .inputs
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let i = INPUTS.iter().position(|n| n == name).unwrap_or(k);
                s[i % 6]
            })
            .collect();
        prop_assert_eq!(state.step(program, &inputs, s[6]), Ok(()));
        match state.features(program, &mut out) {
            Ok(()) => {
                let n = program.n_features();
                prop_assert!(out[..n].iter().all(|v| v.is_finite()), "{:?}", &out[..n]);
            }
            Err(StepError::NonFiniteFeature { feature }) => {
                prop_assert!(usize::from(feature) < program.n_features());
            }
            Err(e) => prop_assert!(false, "unexpected step error {e}"),
        }
    }
    Ok(())
}

/// `m·10^e` for `m` and `e` drawn from the ranges. (Numbers are made from integers: proptest's own
/// float ranges trip a debug assertion of its sampler now and then.)
fn decimal(
    m: std::ops::RangeInclusive<i32>,
    e: std::ops::RangeInclusive<i32>,
) -> impl Strategy<Value = f32> {
    (m, e).prop_map(|(m, e)| (f64::from(m) * 10f64.powi(e)) as f32)
}

fn sample() -> impl Strategy<Value = [f32; 7]> {
    let value = prop_oneof![
        8 => decimal(-200_000..=200_000, -3..=-3),
        1 => decimal(-3000..=3000, -3..=35),
        1 => Just(0.0f32),
    ];
    let dt = prop_oneof![
        4 => Just(0.005f32),
        4 => decimal(1..=100_000, -4..=-3),
        1 => decimal(1..=1000, -33..=-6),
    ];
    (proptest::array::uniform6(value), dt)
        .prop_map(|(v, dt)| [v[0], v[1], v[2], v[3], v[4], v[5], dt])
}

// ---- Raw text ----------------------------------------------------------------------------------

fn raw_text() -> impl Strategy<Value = String> {
    let piece = "[a-zT_0-9+*/() ,.eE=-]{1,8}";
    let opener = prop_oneof![
        Just("("),
        Just("-"),
        Just("sq("),
        Just("rate("),
        Just("mean(x, "),
        Just("clamp(-"),
        Just("(-abs(")
    ];
    prop_oneof![
        // Anything, control characters and every plane of unicode included.
        3 => proptest::collection::vec(any::<char>(), 0..48).prop_map(|c| c.into_iter().collect()),
        2 => "\\PC{0,48}",
        // Near the grammar, where most of the parser's branches are.
        4 => "[a-zT_0-9+*/() ,.eE=\t-]{0,48}",
        1 => "(rate|lag|hyst|mean|clamp|sq|abs)\\([a-zT0-9 ,.()+*/-]{0,16}\\)?",
        // Very long, past the 65,535 bytes an error position can name.
        1 => (piece, 1usize..12_000).prop_map(|(p, n)| p.repeat(n)),
        // Deeply nested, closed or not.
        2 => (opener, 0usize..400, "[a-zT0-9.]{0,4}", 0usize..400)
            .prop_map(|(o, n, inner, m)| format!("{}{inner}{}", o.repeat(n), ")".repeat(m))),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(FUZZ_CASES))]

    /// Any text, one spec line per text line: never a panic or a hang, errors inside the line,
    /// and whatever compiles runs to finite features or a typed error.
    #[test]
    fn fuzz_raw_text(text in raw_text(), samples in proptest::collection::vec(sample(), 1..4)) {
        let lines: Vec<&str> = text.split('\n').collect();
        compile_and_run::<16>(&lines, &samples)?;
        compile_and_run::<255>(&lines, &samples)?;
    }
}

// ---- Structured expressions -------------------------------------------------------------------

#[derive(Clone, Debug)]
enum E {
    Input(u8),
    /// A signal defined on an earlier line (an input when there is none).
    Signal(u8),
    /// A non-negative literal, written in exponent form when the flag is set.
    Lit(f32, bool),
    Paren(u8, Box<E>),
    Neg(Box<E>),
    Bin(u8, Box<E>, Box<E>, bool),
    Sq(Box<E>),
    Abs(Box<E>),
    Mean(Vec<E>),
    Rate(Box<E>, Option<Box<E>>),
    Lag(Box<E>, Box<E>),
    Hyst(Box<E>, Box<E>),
    Clamp(Box<E>, Box<E>, Box<E>),
}

fn lit() -> impl Strategy<Value = E> {
    let value = prop_oneof![
        4 => (0u8..=10).prop_map(f32::from),
        4 => decimal(1..=1_000_000, -3..=-3),
        1 => Just(0.0f32),
        1 => decimal(1..=1000, -33..=-23),
        1 => decimal(1..=3000, 17..=35),
    ];
    (value, any::<bool>()).prop_map(|(v, e)| E::Lit(v, e))
}

fn binop() -> impl Strategy<Value = u8> {
    prop_oneof![Just(b'+'), Just(b'-'), Just(b'*'), Just(b'/')]
}

fn paren_count() -> impl Strategy<Value = u8> {
    prop_oneof![20 => 1u8..=2, 1 => 18u8..=26]
}

/// A constant expression: folded by the parser, of either sign.
fn constant() -> impl Strategy<Value = E> {
    lit().prop_recursive(2, 6, 2, |c| {
        prop_oneof![
            c.clone().prop_map(|e| E::Neg(Box::new(e))),
            (binop(), c.clone(), c.clone(), any::<bool>()).prop_map(|(op, a, b, s)| E::Bin(
                op,
                Box::new(a),
                Box::new(b),
                s
            )),
            (1u8..=2, c).prop_map(|(n, e)| E::Paren(n, Box::new(e))),
        ]
    })
}

/// A typical parameter (a positive number) or any constant expression. Built once: proptest
/// rebuilds a recursive strategy's levels for every case, so what they share is made outside.
fn constant_param() -> BoxedStrategy<E> {
    let typical = (decimal(1..=500_000, -2..=-2), any::<bool>()).prop_map(|(v, e)| E::Lit(v, e));
    prop_oneof![3 => typical, 1 => constant()].boxed()
}

/// Two ordered constants, the limits of a clamp.
fn ordered_limits() -> BoxedStrategy<(E, E)> {
    let signed = |v: f32| {
        let l = E::Lit(v.abs(), false);
        if v < 0.0 { E::Neg(Box::new(l)) } else { l }
    };
    (
        decimal(-500_000..=500_000, -3..=-3),
        decimal(0..=500_000, -3..=-3),
    )
        .prop_map(move |(lo, w)| (signed(lo), signed(lo + w)))
        .boxed()
}

fn expr() -> BoxedStrategy<E> {
    let leaf = prop_oneof![
        3 => (0u8..6).prop_map(E::Input),
        1 => (0u8..4).prop_map(E::Signal),
        2 => lit(),
    ];
    let constant = constant_param();
    let ordered = ordered_limits();
    leaf.prop_recursive(5, 48, 4, move |inner| {
        let b = |e: E| Box::new(e);
        // A parameter: mostly a constant, now and then something that is not.
        let param = prop_oneof![16 => constant.clone(), 1 => inner.clone()].boxed();
        // The limits of a clamp: mostly in order, sometimes any two parameters.
        let limits = prop_oneof![4 => ordered.clone(), 1 => (param.clone(), param.clone())];
        prop_oneof![
            2 => inner.clone().prop_map(move |e| E::Neg(b(e))),
            6 => (binop(), inner.clone(), inner.clone(), any::<bool>())
                .prop_map(move |(op, x, y, s)| E::Bin(op, b(x), b(y), s)),
            2 => (paren_count(), inner.clone()).prop_map(move |(n, e)| E::Paren(n, b(e))),
            1 => inner.clone().prop_map(move |e| E::Sq(b(e))),
            1 => inner.clone().prop_map(move |e| E::Abs(b(e))),
            1 => proptest::collection::vec(inner.clone(), 1..5).prop_map(E::Mean),
            1 => (inner.clone(), proptest::option::of(param.clone()))
                .prop_map(move |(x, p)| E::Rate(b(x), p.map(b))),
            1 => (inner.clone(), param.clone()).prop_map(move |(x, p)| E::Lag(b(x), b(p))),
            1 => (inner.clone(), param).prop_map(move |(x, p)| E::Hyst(b(x), b(p))),
            1 => (inner, limits)
                .prop_map(move |(x, (lo, hi))| E::Clamp(b(x), b(lo), b(hi))),
        ]
    })
    .boxed()
}

/// What the model knows of a rendered sub-expression.
#[derive(Clone, Copy, Debug)]
struct Info {
    /// Its value when the parser folds it into one constant node of this expression.
    folded: Option<f32>,
    /// Its value when its node is a constant at all (a folded one or a constant signal): what the
    /// division check sees.
    constant: Option<f32>,
    /// Deepest nesting below it, counted as the parser counts (each `(`, call argument and `-`).
    depth: usize,
    /// Most nodes it can occupy at once.
    nodes: usize,
}

/// The model: renders a tree as text and predicts the parser's verdict.
#[derive(Default)]
struct Model {
    /// Constant value (if any) of each signal defined so far.
    signals: Vec<Option<f32>>,
    stateful: usize,
    nodes: usize,
    /// Errors that occur if the parser gets that far.
    certain: Vec<K>,
    /// Errors that may occur (capacity, bounded only from above).
    possible: Vec<K>,
}

fn prec(e: &E) -> u8 {
    match e {
        E::Bin(b'+' | b'-', ..) => 1,
        E::Bin(..) => 2,
        _ => 3,
    }
}

fn fmt_lit(v: f32, exp: bool) -> String {
    if exp {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl Model {
    fn child(&mut self, e: &E, out: &mut String, paren: bool) -> Info {
        if paren {
            out.push('(');
        }
        let mut info = self.go(e, out);
        if paren {
            out.push(')');
            info.depth += 1;
        }
        info
    }

    /// A call's argument list; every argument is parsed at one more level of nesting.
    fn args(&mut self, name: &str, args: &[&E], out: &mut String) -> Vec<Info> {
        out.push_str(name);
        out.push('(');
        let mut infos = Vec::new();
        for (i, a) in args.iter().enumerate() {
            if i > 0 {
                out.push_str(", ");
            }
            let mut info = self.go(a, out);
            info.depth += 1;
            infos.push(info);
        }
        out.push(')');
        infos
    }

    fn call(&mut self, infos: &[Info], extra_nodes: usize) -> Info {
        Info {
            folded: None,
            constant: None,
            depth: infos.iter().map(|i| i.depth).max().unwrap_or(0),
            nodes: infos.iter().map(|i| i.nodes).sum::<usize>() + extra_nodes,
        }
    }

    fn stateful(&mut self, infos: &[Info], ok: impl Fn(f32) -> bool) -> Info {
        if let Some(p) = infos.get(1) {
            match p.folded {
                Some(v) if !ok(v) => self.certain.push(K::BadParameter),
                Some(_) => {}
                None => self.certain.push(K::ConstantRequired),
            }
        }
        self.stateful += 1;
        if self.stateful > MAX_STATEFUL {
            self.certain.push(K::TooManyStateful);
        }
        self.call(infos, 1)
    }

    fn go(&mut self, e: &E, out: &mut String) -> Info {
        let atom = |folded, constant, nodes| Info {
            folded,
            constant,
            depth: 0,
            nodes,
        };
        match e {
            E::Input(i) => {
                out.push_str(INPUTS[usize::from(*i) % INPUTS.len()]);
                atom(None, None, 1)
            }
            E::Signal(i) => {
                if self.signals.is_empty() {
                    return self.go(&E::Input(*i), out);
                }
                let k = usize::from(*i) % self.signals.len();
                out.push_str(&format!("S{k}"));
                atom(None, self.signals[k], 0)
            }
            E::Lit(v, exp) => {
                out.push_str(&fmt_lit(*v, *exp));
                atom(Some(*v), Some(*v), 1)
            }
            E::Paren(n, x) => {
                let n = usize::from(*n);
                out.push_str(&"(".repeat(n));
                let mut info = self.go(x, out);
                out.push_str(&")".repeat(n));
                info.depth += n;
                info
            }
            E::Neg(x) => {
                out.push('-');
                let a = self.child(x, out, matches!(**x, E::Bin(..)));
                let folded = a.folded.map(|v| -v);
                Info {
                    folded,
                    constant: folded,
                    depth: a.depth + 1,
                    nodes: a.nodes + 1,
                }
            }
            E::Bin(op, x, y, spaced) => {
                let p = prec(e);
                let a = self.child(x, out, prec(x) < p);
                if *spaced {
                    out.push(' ');
                }
                out.push(char::from(*op));
                if *spaced {
                    out.push(' ');
                }
                let b = self.child(y, out, prec(y) <= p);
                if *op == b'/' && b.constant == Some(0.0) {
                    self.certain.push(K::DivisionByZero);
                }
                let folded = match (a.folded, b.folded) {
                    (Some(x), Some(y)) => Some(match op {
                        b'+' => x + y,
                        b'-' => x - y,
                        b'*' => x * y,
                        _ => x / y,
                    })
                    .filter(|v| v.is_finite()),
                    _ => None,
                };
                Info {
                    folded,
                    constant: folded,
                    depth: a.depth.max(b.depth),
                    nodes: a.nodes + b.nodes + 1,
                }
            }
            E::Sq(x) => {
                let i = self.args("sq", &[x], out);
                self.call(&i, 1)
            }
            E::Abs(x) => {
                let i = self.args("abs", &[x], out);
                self.call(&i, 1)
            }
            E::Mean(xs) => {
                let refs: Vec<&E> = xs.iter().collect();
                let i = self.args("mean", &refs, out);
                let extra = if xs.len() > 1 { xs.len() + 1 } else { 0 };
                let mut info = self.call(&i, extra);
                if xs.len() == 1 {
                    // `mean(x)` is `x`'s node itself, so a constant stays one.
                    info.folded = i[0].folded;
                    info.constant = i[0].constant;
                }
                info
            }
            E::Rate(x, w) => {
                let args: Vec<&E> = std::iter::once(&**x).chain(w.as_deref()).collect();
                let i = self.args("rate", &args, out);
                self.stateful(&i, |w| w > 0.0)
            }
            E::Lag(x, t) => {
                let i = self.args("lag", &[x, t], out);
                self.stateful(&i, |t| t > 0.0)
            }
            E::Hyst(x, h) => {
                let i = self.args("hyst", &[x, h], out);
                self.stateful(&i, |h| h >= 0.0)
            }
            E::Clamp(x, lo, hi) => {
                let i = self.args("clamp", &[x, lo, hi], out);
                match (i[1].folded, i[2].folded) {
                    (Some(lo), Some(hi)) if lo > hi => self.certain.push(K::BadParameter),
                    (Some(_), Some(_)) => {}
                    _ => self.certain.push(K::ConstantRequired),
                }
                self.call(&i, 1)
            }
        }
    }

    /// Renders one line's expression and predicts its verdict (given that the lines before it
    /// compiled).
    fn line(&mut self, e: &E) -> Line {
        let mut text = String::new();
        let info = self.go(e, &mut text);
        if 1 + info.depth > MAX_DEPTH {
            self.certain.push(K::TooDeep);
        }
        self.nodes += info.nodes;
        if self.nodes > NODES {
            self.possible.push(K::TooManyNodes);
        }
        Line {
            text,
            constant: info.constant,
            certain: std::mem::take(&mut self.certain),
            possible: std::mem::take(&mut self.possible),
        }
    }
}

/// One rendered line and the model's verdict on it.
#[derive(Debug)]
struct Line {
    text: String,
    /// The constant value of its node, if it is a constant.
    constant: Option<f32>,
    /// Errors the parser must report one of (none: it must compile).
    certain: Vec<K>,
    /// Errors it may report besides.
    possible: Vec<K>,
}

#[derive(Clone, Debug)]
struct Spec {
    signals: Vec<E>,
    features: Vec<E>,
    /// Random blanks around the `=` of a signal.
    blanks: (bool, bool),
}

fn spec() -> impl Strategy<Value = Spec> {
    (
        proptest::collection::vec(expr(), 0..=2),
        proptest::collection::vec(expr(), 1..=4),
        any::<(bool, bool)>(),
    )
        .prop_map(|(signals, features, blanks)| Spec {
            signals,
            features,
            blanks,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(FUZZ_CASES))]

    /// Expressions generated from the grammar: the parser's verdict is the model's, a valid spec
    /// compiles into a program that validates, and the program runs on finite inputs to finite
    /// features or a typed error.
    #[test]
    fn fuzz_structured_expressions(spec in spec(), samples in proptest::collection::vec(sample(), 1..4)) {
        let mut model = Model::default();
        let mut lines = Vec::new();
        for (k, e) in spec.signals.iter().enumerate() {
            let mut line = model.line(e);
            let eq = match spec.blanks {
                (true, true) => " = ",
                (true, false) => " =",
                (false, true) => "= ",
                (false, false) => "=",
            };
            line.text = format!("S{k}{eq}{}", line.text);
            model.signals.push(line.constant);
            lines.push(line);
        }
        for e in &spec.features {
            lines.push(model.line(e));
        }

        let mut b = ProgramBuilder::<NODES, 8>::new();
        let mut failed = false;
        for line in &lines {
            match b.line(&line.text) {
                Ok(()) => prop_assert!(
                    line.certain.is_empty(),
                    "{:?} compiled, but the model expected {:?}", line.text, line.certain
                ),
                Err(e) => {
                    prop_assert!(
                        e.start <= e.end && usize::from(e.end) <= line.text.len(),
                        "{e:?} in {:?}", line.text
                    );
                    prop_assert!(
                        line.certain.contains(&e.kind) || line.possible.contains(&e.kind),
                        "{:?}: {e} ({:?}); the model expected {:?} / {:?}",
                        line.text, e.kind, line.certain, line.possible
                    );
                    failed = true;
                    break;
                }
            }
        }
        if !failed {
            let program = b.finish();
            prop_assert!(program.is_ok(), "{:?}: {lines:#?}", program.err());
            let program = program.unwrap();
            prop_assert_eq!(program.n_features(), spec.features.len());
            run(&program, &samples)?;
        }
    }
}
