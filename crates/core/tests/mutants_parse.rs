//! The parser's promises that the operator tests do not reach: constant folding (values, and that a
//! folded constant costs one node and never eats a signal's node), the nesting limit and its
//! position, identifiers, and a message for every kind of error.
//! Written to kill what `cargo mutants` found untested in `syntax.rs` (the parser itself is `compile/parser.rs`).
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::syntax::{is_function, is_identifier, split_definition};
use tcomp_core::{Op, ParseError, ParseErrorKind as K, ProgramBuilder, ProgramState};

type B<'a> = ProgramBuilder<'a, 48, 8>;

/// The feature values of a program of `lines` after one sample of `inputs`.
fn values(lines: &[&'static str], inputs: &[f32]) -> Vec<f32> {
    let mut b = B::new();
    for l in lines {
        b.line(l).unwrap();
    }
    let p = b.finish().unwrap();
    let mut st = ProgramState::<48>::new();
    st.step(&p, inputs, 1.0).unwrap();
    let mut out = [0.0f32; 8];
    st.features(&p, &mut out).unwrap();
    out[..p.n_features()].to_vec()
}

#[test]
fn constant_arithmetic_folds_to_one_node_with_the_right_value() {
    for (expr, v) in [
        ("1 + 2", 3.0f32),
        ("7 - 2.5", 4.5),
        ("2 * 3", 6.0),
        ("3 / 4", 0.75),
        ("1 - 2 - 3", -4.0),
        ("(1 + 2) * (10 - 4) / 8", 2.25),
        ("-(2 + 3)", -5.0),
    ] {
        let mut b = B::new();
        b.feature(expr).unwrap();
        let p = b.finish().unwrap();
        assert_eq!(p.nodes.as_slice(), &[Op::Const(v)], "{expr}");
    }
}

#[test]
fn a_constant_next_to_a_column_stays_an_operation() {
    let mut b = B::new();
    b.feature("x + 2").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(
        p.nodes.as_slice(),
        &[Op::Input(0), Op::Const(2.0), Op::Add(0, 1)]
    );
}

#[test]
fn folding_never_consumes_a_signal() {
    // A constant signal's node belongs to the signal: an expression over it computes a new node
    // and leaves the signal's value alone, whatever order the features come in.
    assert_eq!(values(&["K = 5", "K * 2", "K"], &[]), [10.0, 5.0]);
    assert_eq!(values(&["K = 5", "-K", "K"], &[]), [-5.0, 5.0]);
    assert_eq!(values(&["K = 5", "K - 1", "K"], &[]), [4.0, 5.0]);
}

#[test]
fn a_signal_is_not_a_constant_parameter() {
    let mut b = B::new();
    b.line("K = 5").unwrap();
    let e = b.feature("lag(K, K)").unwrap_err();
    assert_eq!((e.kind, e.start, e.end), (K::ConstantRequired, 7, 8));
}

#[test]
fn nesting_up_to_the_limit_parses_and_one_more_is_too_deep() {
    // The top-level expression is level 1 and each parenthesis one more: 23 pairs are level 24.
    let nested = |k: usize| -> &'static str {
        Box::leak(format!("{}x{}", "(".repeat(k), ")".repeat(k)).into_boxed_str())
    };
    let mut b = B::new();
    b.feature(nested(23)).unwrap();
    let mut b = B::new();
    let e = b.feature(nested(24)).unwrap_err();
    assert_eq!(e.kind, K::TooDeep);
    // The error points at one character: where the 25th level starts.
    assert_eq!((e.start, e.end), (24, 25));
    // Unary minus counts as a level too: 23 of them are level 24.
    let minus =
        |k: usize| -> &'static str { Box::leak(format!("{}x", "-".repeat(k)).into_boxed_str()) };
    B::new().feature(minus(23)).unwrap();
    let e = B::new().feature(minus(24)).unwrap_err();
    assert_eq!((e.kind, e.start, e.end), (K::TooDeep, 23, 24));
}

#[test]
fn depth_is_given_back_after_each_sub_expression() {
    // Forty parenthesised terms side by side never nest deeper than two levels.
    let flat: &'static str = Box::leak(vec!["(1)"; 40].join(" + ").into_boxed_str());
    assert_eq!(values(&[flat], &[]), [40.0]);
    // Thirty negations side by side (folded into one constant) never nest deeper than two levels.
    let negated: &'static str = Box::leak(vec!["-1"; 30].join(" + ").into_boxed_str());
    assert_eq!(values(&[negated], &[]), [-30.0]);
    // 15 terms: 44 of the 48 nodes (each name reads its column into a node of its own).
    let negated: &'static str = Box::leak(vec!["-x"; 15].join(" + ").into_boxed_str());
    assert_eq!(values(&[negated], &[2.0]), [-30.0]);
    let calls: &'static str = Box::leak(vec!["sq(x)"; 30].join(" + ").into_boxed_str());
    let mut b = ProgramBuilder::<'static, 200, 8>::new();
    b.feature(calls).unwrap();
}

#[test]
fn identifiers_are_letters_digits_and_underscores_not_starting_with_a_digit() {
    for ok in ["x", "_", "_t1", "t_anode_c", "T", "a9_Z"] {
        assert!(is_identifier(ok), "{ok}");
    }
    for bad in ["", "1x", "9", "t-anode", "a b", "x.y", "é", "x=", "(x)"] {
        assert!(!is_identifier(bad), "{bad:?}");
    }
    assert!(is_function("rate") && is_function("clamp") && !is_function("T"));
    assert_eq!(split_definition("T = a + b"), Some(("T", 0, " a + b", 3)));
    assert_eq!(split_definition("  G=a"), Some(("G", 2, "a", 4)));
    assert_eq!(split_definition("1x = a"), None);
    assert_eq!(split_definition("a + b"), None);
}

#[test]
fn every_error_kind_has_its_own_message() {
    let kinds = [
        K::Empty,
        K::UnexpectedChar,
        K::UnexpectedEnd,
        K::ExpectedOperand,
        K::ExpectedCloseParen,
        K::TrailingInput,
        K::BadNumber,
        K::UnknownFunction,
        K::WrongArgCount,
        K::ConstantRequired,
        K::BadParameter,
        K::TooDeep,
        K::TooManyNodes,
        K::TooManyInputs,
        K::TooManyFeatures,
        K::TooManySignals,
        K::TooManyStateful,
        K::DuplicateSignal,
        K::BadName,
        K::DivisionByZero,
    ];
    let texts: Vec<String> = kinds
        .iter()
        .map(|&kind| {
            ParseError {
                start: 4,
                end: 6,
                kind,
            }
            .to_string()
        })
        .collect();
    for (kind, t) in kinds.iter().zip(&texts) {
        let message = t.strip_prefix("column 5: ").unwrap();
        assert!(message.len() > 10, "{kind:?}: {t:?}");
    }
    for (i, a) in texts.iter().enumerate() {
        for b in &texts[i + 1..] {
            assert_ne!(a, b, "two kinds share a message");
        }
    }
    // The two messages that teach the language name every function.
    for f in ["sq", "abs", "mean", "rate", "lag", "hyst", "clamp"] {
        assert!(texts[7].contains(f) && texts[8].contains(f), "{f}");
    }
}

fn error(expr: &'static str) -> (K, u16, u16) {
    let e = B::new().line(expr).unwrap_err();
    (e.kind, e.start, e.end)
}

#[test]
fn error_spans_cover_the_offending_text() {
    // An error at the end of the text is an empty span at its end, never past it.
    assert_eq!(error("(a + b"), (K::ExpectedCloseParen, 6, 6));
    assert_eq!(error("a + * b"), (K::ExpectedOperand, 4, 5));
    assert_eq!(error("a + )"), (K::ExpectedOperand, 4, 5));
    assert_eq!(error("$"), (K::UnexpectedChar, 0, 1));
    assert_eq!(error("a $ b"), (K::UnexpectedChar, 2, 5));
    assert_eq!(error("a b"), (K::TrailingInput, 2, 3));
    assert_eq!(error("a + "), (K::UnexpectedEnd, 4, 4));
    assert_eq!(error("foo(x)"), (K::UnknownFunction, 0, 3));
    assert_eq!(error("1e999"), (K::BadNumber, 0, 5));
    assert_eq!(error("1.2.3"), (K::BadNumber, 0, 5));
    assert_eq!(error("lag(x)"), (K::WrongArgCount, 0, 6));
    assert_eq!(error("lag(x, -3)"), (K::BadParameter, 7, 9));
    assert_eq!(error("sq(x y)"), (K::UnexpectedChar, 5, 6));
    assert_eq!(error("sq(x"), (K::ExpectedCloseParen, 4, 4));
}

#[test]
fn numbers_in_every_notation() {
    for (text, v) in [
        ("2", 2.0f32),
        ("0.25", 0.25),
        (".5", 0.5),
        ("1.5e-3", 1.5e-3),
        ("2E+2", 200.0),
        ("3e2", 300.0),
        ("1e-40", 1e-40),
    ] {
        let mut b = B::new();
        b.feature(text).unwrap();
        assert_eq!(
            b.finish().unwrap().nodes.as_slice(),
            &[Op::Const(v)],
            "{text}"
        );
    }
}

#[test]
fn each_function_takes_its_number_of_arguments() {
    for (expr, ok) in [
        ("sq(x)", true),
        ("sq(x, y)", false),
        ("abs(x)", true),
        ("abs(x, y)", false),
        ("mean(x)", true),
        ("mean(x, y, z, w)", true),
        ("rate(x)", true),
        ("rate(x, 30)", true),
        ("rate(x, 30, 2)", false),
        ("lag(x, 5)", true),
        ("lag(x)", false),
        ("lag(x, 5, 6)", false),
        ("hyst(x, 0.1)", true),
        ("hyst(x)", false),
        ("clamp(x, 0, 1)", true),
        ("clamp(x, 0)", false),
        ("clamp(x, 0, 1, 2)", false),
    ] {
        match B::new().feature(expr) {
            Ok(()) => assert!(ok, "{expr} accepted"),
            Err(e) => assert!(!ok && e.kind == K::WrongArgCount, "{expr}: {:?}", e.kind),
        }
    }
    // More arguments than the parser keeps (16) is a count error too, not a panic.
    let many: &'static str =
        Box::leak(format!("mean({})", vec!["x"; 17].join(", ")).into_boxed_str());
    let mut b = ProgramBuilder::<'static, 200, 8>::new();
    let e = b.feature(many).unwrap_err();
    assert_eq!((e.kind, e.start), (K::WrongArgCount, 0));
    assert!(e.end > e.start);
}

#[test]
fn functions_compute_what_their_names_say() {
    assert_eq!(
        values(
            &[
                "sq(x)",
                "abs(x)",
                "mean(x, y, 4)",
                "mean(y)",
                "clamp(x, -1, 1)"
            ],
            &[-3.0, 5.0]
        ),
        [9.0, 3.0, 2.0, 5.0, -1.0]
    );
    // `mean` of one argument is that argument: no division node.
    let mut b = B::new();
    b.feature("mean(x)").unwrap();
    assert_eq!(b.finish().unwrap().nodes.as_slice(), &[Op::Input(0)]);
    let mut b = B::new();
    b.feature("mean(x, y)").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(
        p.nodes.as_slice(),
        &[
            Op::Input(0),
            Op::Input(1),
            Op::Add(0, 1),
            Op::Const(0.5),
            Op::Mul(2, 3)
        ]
    );
}

#[test]
fn stateful_functions_get_their_parameters_and_a_slot_each() {
    let mut b = B::new();
    b.feature("rate(x)").unwrap();
    b.feature("rate(x, 30)").unwrap();
    b.feature("lag(x, 5)").unwrap();
    b.feature("hyst(x, 0)").unwrap();
    b.feature("clamp(x, 2, 2)").unwrap();
    let p = b.finish().unwrap();
    let ops: Vec<Op> = p.features.iter().map(|&f| p.nodes[f as usize]).collect();
    assert_eq!(
        ops,
        [
            Op::Rate {
                x: 0,
                slot: 0,
                window_s: 60.0
            },
            Op::Rate {
                x: 2,
                slot: 1,
                window_s: 30.0
            },
            Op::Lag {
                x: 4,
                slot: 2,
                tau_s: 5.0
            },
            Op::Hyst {
                x: 6,
                slot: 3,
                threshold: 0.0
            },
            Op::Clamp {
                x: 8,
                lo: 2.0,
                hi: 2.0
            },
        ]
    );
    for bad in ["rate(x, 0)", "lag(x, 0)", "hyst(x, -0.1)", "rate(x, -5)"] {
        assert_eq!(error(bad).0, K::BadParameter, "{bad}");
    }
}

#[test]
fn eight_stateful_operators_fit_and_a_ninth_does_not() {
    let mut b = B::new();
    b.feature("lag(x, 1) + lag(x, 2) + lag(x, 3) + lag(x, 4)")
        .unwrap();
    b.feature("rate(x) + rate(x, 2) + hyst(x, 1) + lag(x, 5)")
        .unwrap();
    let e = b.feature("lag(x, 9)").unwrap_err();
    assert_eq!((e.kind, e.start, e.end), (K::TooManyStateful, 0, 9));
    assert_eq!(b.finish().unwrap().n_features(), 2);
}

#[test]
fn a_name_is_a_signal_first_then_an_input_read_once_per_use() {
    let mut b = B::new();
    b.line("a = 2 * c").unwrap();
    b.feature("a + b + c").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(p.inputs.as_slice(), &["c", "b"]);
    let mut st = ProgramState::<48>::new();
    st.step(&p, &[10.0, 1.0], 1.0).unwrap();
    let mut out = [0.0f32; 8];
    st.features(&p, &mut out).unwrap();
    assert_eq!(out[0], 20.0 + 1.0 + 10.0);
}

/// Autopilot log columns (`topic.field`, `MSG[instance].Field`) are names in expressions, one
/// input each; a half-written suffix is not a name.
#[test]
fn log_column_names_are_inputs() {
    for ok in [
        "sensor_gyro.x",
        "IMU.T",
        "IMU[1].GyrX",
        "sensor_accel[2].temperature",
        "sensor_combined.gyro_rad[0]",
    ] {
        assert!(tcomp_core::syntax::is_column_name(ok), "{ok}");
    }
    for bad in [
        "", "IMU.", "IMU[]", "IMU[1", "IMU[a].T", ".T", "IMU..T", "IMU.1x", "a b",
    ] {
        assert!(!tcomp_core::syntax::is_column_name(bad), "{bad:?}");
    }
    let mut b = ProgramBuilder::<'static, 16, 4>::new();
    b.feature("rate(IMU[1].T)").unwrap();
    b.feature("IMU[1].T - sensor_gyro.temperature").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(&p.inputs[..], ["IMU[1].T", "sensor_gyro.temperature"]);
    let mut b = ProgramBuilder::<'static, 16, 4>::new();
    assert!(b.feature("IMU[1.T").is_err());
    assert!(b.feature("IMU.").is_err());
}
