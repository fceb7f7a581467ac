//! The expression printer writes text the compiler reads back to the tree's program: printing and
//! compiling gives the same program as printing with every parenthesis, for random trees.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use proptest::prelude::*;
use tcomp_core::expr::{self, BinOp, Expr, Notation};
use tcomp_core::{Op, ParseErrorKind, Program, ProgramBuilder};

/// The tree printed with every operator and number in parentheses: trivially what the tree says.
fn parenthesised(e: &Expr) -> String {
    match e {
        Expr::Name(n) => n.clone(),
        Expr::Text(t) => format!("({t})"),
        Expr::Num(..) => format!("({e})"),
        Expr::Neg(a) => format!("(-{})", parenthesised(a)),
        Expr::Binary(op, a, b) => {
            let s = match op {
                BinOp::Add => "+",
                BinOp::Sub => "-",
                BinOp::Mul => "*",
                BinOp::Div => "/",
            };
            format!("({} {s} {})", parenthesised(a), parenthesised(b))
        }
        Expr::Call(name, args) => {
            let args: Vec<String> = args.iter().map(parenthesised).collect();
            format!("{name}({})", args.join(", "))
        }
    }
}

/// The compiled program's inputs and operations (its source text aside), or the error's kind.
type Compiled = Result<(Vec<&'static str>, Vec<Op<f64>>), ParseErrorKind>;

fn compile(text: String) -> Compiled {
    let text: &'static str = Box::leak(text.into_boxed_str());
    let mut b = ProgramBuilder::<200, 1, f64>::new();
    b.feature(text).map_err(|e| e.kind)?;
    let p: Program<'static, 200, 1, f64> = b.finish().unwrap();
    Ok((p.inputs.to_vec(), p.nodes.to_vec()))
}

fn number() -> impl Strategy<Value = Expr> {
    (
        prop_oneof![
            Just(0.0),
            Just(-0.0),
            Just(2.0),
            -1e6..1e6f64,
            -1e-3..1e-3f64,
            any::<f64>().prop_filter("finite", |v| v.is_finite()),
        ],
        any::<bool>(),
    )
        .prop_map(|(v, sci)| {
            Expr::Num(
                v,
                if sci {
                    Notation::Scientific
                } else {
                    Notation::Plain
                },
            )
        })
}

fn tree() -> impl Strategy<Value = Expr> {
    let leaf = prop_oneof![
        3 => prop_oneof![Just("a"), Just("b"), Just("c")].prop_map(Expr::name),
        2 => number(),
        1 => Just(Expr::text("a + b * c")),
    ];
    leaf.prop_recursive(6, 40, 3, |inner| {
        let positive = prop_oneof![Just(1.0), 0.5..5000.0f64];
        prop_oneof![
            inner.clone().prop_map(|a| -a),
            (inner.clone(), inner.clone(), 0..4u8).prop_map(|(a, b, op)| match op {
                0 => a + b,
                1 => a - b,
                2 => a * b,
                _ => a / b,
            }),
            inner.clone().prop_map(expr::sq),
            inner.clone().prop_map(expr::abs),
            proptest::collection::vec(inner.clone(), 1..4).prop_map(expr::mean),
            (inner.clone(), positive.clone()).prop_map(|(a, w)| expr::rate_window(a, w)),
            (inner.clone(), positive.clone()).prop_map(|(a, t)| expr::lag(a, t)),
            (inner.clone(), 0.0..1.0f64).prop_map(|(a, h)| expr::hyst(a, h)),
            (inner, -10.0..0.0f64, 0.0..10.0f64).prop_map(|(a, lo, hi)| expr::clamp(
                a,
                Expr::num(lo),
                Expr::sci(hi)
            )),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn printing_keeps_the_program(e in tree()) {
        let printed = e.to_string();
        let reference = compile(parenthesised(&e));
        let got = compile(printed.clone());
        prop_assert_eq!(got, reference, "{}", printed);
    }

    #[test]
    fn numbers_print_back_to_themselves(v in any::<f64>().prop_filter("finite", |v| v.is_finite())) {
        for e in [Expr::num(v), Expr::sci(v)] {
            let text = e.to_string();
            prop_assert_eq!(text.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{}", text);
        }
    }
}

#[test]
fn the_printer_writes_the_fewest_parentheses() {
    let (a, b, c) = (expr::name("a"), expr::name("b"), expr::name("c"));
    let cases = [
        (a.clone() - b.clone() - c.clone(), "a - b - c"),
        (a.clone() - (b.clone() - c.clone()), "a - (b - c)"),
        (a.clone() * (b.clone() + c.clone()), "a * (b + c)"),
        (a.clone() * b.clone() + c.clone(), "a * b + c"),
        (-(a.clone() * b.clone()), "-(a * b)"),
        (-a.clone() * b.clone(), "-a * b"),
        (a.clone() - Expr::num(-2.0), "a - -2"),
        (a.clone() / (b.clone() * c.clone()), "a / (b * c)"),
        (Expr::text("x + y") * a.clone(), "(x + y) * a"),
        (expr::name("T") * expr::rate(expr::name("T")), "T * rate(T)"),
        (expr::rate_window(a.clone(), 60.0), "rate(a)"),
        (expr::rate_window(a.clone(), 240.0), "rate(a, 240)"),
        (expr::lag(a.clone(), 2400.0), "lag(a, 2400)"),
        (
            expr::hyst(expr::rate(a.clone()), 0.05),
            "hyst(rate(a), 0.05)",
        ),
        (
            expr::clamp(Expr::text("mean(a, b)"), Expr::sci(-10.0), Expr::sci(21.5)),
            "clamp(mean(a, b), -1e1, 2.15e1)",
        ),
        (
            Expr::call("rate", [a.clone(), 240.0.into()]),
            "rate(a, 240)",
        ),
        (expr::mean([a, b, c]), "mean(a, b, c)"),
        (Expr::num(f64::NAN), "1e999"),
    ];
    for (e, text) in cases {
        assert_eq!(e.to_string(), text);
    }
    assert_eq!(
        expr::define("T", &expr::mean([expr::name("x"), expr::name("y")])),
        "T = mean(x, y)"
    );
}

#[test]
fn a_non_finite_number_is_refused_by_the_compiler() {
    let e = expr::lag(expr::name("a"), f64::INFINITY);
    assert_eq!(
        compile(e.to_string()).unwrap_err(),
        ParseErrorKind::BadNumber
    );
}
