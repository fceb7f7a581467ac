//! Parse errors say where and why.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::{ParseErrorKind as K, ProgramBuilder};

fn err(expr: &'static str) -> (usize, K) {
    let mut b = ProgramBuilder::<48, 8>::new();
    let e = b.line(expr).unwrap_err();
    (e.column(), e.kind)
}

#[test]
fn errors_are_positioned() {
    assert_eq!(err("foo(x)"), (1, K::UnknownFunction));
    assert_eq!(err("a + "), (5, K::UnexpectedEnd));
    assert_eq!(err("a + * b"), (5, K::ExpectedOperand));
    assert_eq!(err("(a + b"), (7, K::ExpectedCloseParen));
    assert_eq!(err("a b"), (3, K::TrailingInput));
    assert_eq!(err("lag(x)"), (1, K::WrongArgCount));
    assert_eq!(err("lag(x, y)"), (8, K::ConstantRequired));
    assert_eq!(err("lag(x, -3)"), (8, K::BadParameter));
    assert_eq!(err("rate(x, 0)"), (9, K::BadParameter));
    assert_eq!(err("clamp(x, 2, 1)"), (1, K::BadParameter));
    assert_eq!(err("a $ b"), (3, K::UnexpectedChar));
    assert_eq!(err("1e999"), (1, K::BadNumber));
    assert_eq!(err("   "), (1, K::Empty));
    assert_eq!(err("T = a +"), (8, K::UnexpectedEnd));
    assert_eq!(err("lag = a"), (1, K::BadName));
}

#[test]
fn display_names_the_column() {
    let mut b = ProgramBuilder::<48, 8>::new();
    let e = b.feature("rate(T, )").unwrap_err();
    assert!(e.to_string().starts_with("column 9:"), "{e}");
}

#[test]
fn capacities_are_errors_not_panics() {
    let mut b = ProgramBuilder::<4, 8>::new();
    assert_eq!(b.feature("a + b + c").unwrap_err().kind, K::TooManyNodes);
    let mut b = ProgramBuilder::<48, 1>::new();
    b.feature("a").unwrap();
    assert_eq!(b.feature("b").unwrap_err().kind, K::TooManyFeatures);
    let mut b = ProgramBuilder::<48, 8>::new();
    assert_eq!(
        b.feature("a+b+c+d+e+f+g+h+i").unwrap_err().kind,
        K::TooManyInputs
    );
    let mut b = ProgramBuilder::<200, 8>::new();
    let deep: &'static str =
        Box::leak(format!("{}x{}", "(".repeat(40), ")".repeat(40)).into_boxed_str());
    assert_eq!(b.feature(deep).unwrap_err().kind, K::TooDeep);
    let mut b = ProgramBuilder::<48, 8>::new();
    b.line("T = a").unwrap();
    assert_eq!(b.line("T = b").unwrap_err().kind, K::DuplicateSignal);
}

proptest::proptest! {
    #[test]
    fn any_text_parses_or_errors_without_panicking(s in "\\PC{0,40}") {
        let s: &'static str = Box::leak(s.into_boxed_str());
        let mut b = ProgramBuilder::<16, 4>::new();
        let _ = b.line(s);
        let _ = b.finish();
    }

    #[test]
    fn expression_like_text_never_panics(s in "[a-c0-9+*/() ,.-]{0,30}|(rate|lag|hyst|mean|clamp|sq)\\([a-c0-9 ,.-]{0,12}\\)") {
        let s: &'static str = Box::leak(s.into_boxed_str());
        let mut b = ProgramBuilder::<16, 4>::new();
        let _ = b.line(s);
    }
}

/// The error of `line` as (start, end, kind).
fn span(line: &'static str) -> (u16, u16, K) {
    let mut b = ProgramBuilder::<48, 8>::new();
    let e = b.line(line).unwrap_err();
    (e.start, e.end, e.kind)
}

#[test]
fn constant_division_by_zero_is_refused_at_the_divisor() {
    assert_eq!(span("T/0"), (2, 3, K::DivisionByZero));
    assert_eq!(span("T / 0.0"), (4, 7, K::DivisionByZero));
    assert_eq!(span("T / -0"), (4, 6, K::DivisionByZero));
    // Constants are folded, so a divisor that folds to zero is caught too.
    assert_eq!(span("T/(2-2)"), (2, 7, K::DivisionByZero));
    assert_eq!(span("T / (0 * 5) + 1"), (4, 11, K::DivisionByZero));
    assert_eq!(span("1/0"), (2, 3, K::DivisionByZero));
    assert_eq!(span("rate(T / 0e3)"), (9, 12, K::DivisionByZero));
    // Inside a signal definition the position is within the line.
    assert_eq!(span("R = t_a / (1 - 1)"), (10, 17, K::DivisionByZero));
    // A signal that is the constant zero.
    let mut b = ProgramBuilder::<48, 8>::new();
    b.line("Z = 0").unwrap();
    let e = b.line("T / Z  ").unwrap_err();
    assert_eq!((e.start, e.end, e.kind), (4, 5, K::DivisionByZero));
    assert!(
        e.to_string()
            .starts_with("column 5: division by a constant zero"),
        "{e}"
    );
}

#[test]
fn nonzero_or_varying_divisors_still_compile() {
    for line in [
        "T/2",
        "T / (2 - 1)",
        "T/1e-30",
        "T / -0.5",
        "T / (T - T)",
        "T / rate(T)",
    ] {
        let mut b = ProgramBuilder::<48, 8>::new();
        b.line(line).unwrap();
        b.finish().unwrap();
    }
}

#[test]
fn error_positions_lie_within_the_text() {
    for line in ["(a + b", "rate(T, 1", "a +", "sq(", "T = (a"] {
        let (start, end, _) = span(line);
        assert!(
            start <= end && usize::from(end) <= line.len(),
            "{line}: {start}..{end}"
        );
    }
}

/// Nesting far beyond the limit, in each form that recurses, is a `TooDeep` error and never a stack
/// overflow.
#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let n = 100_000;
    let forms = [
        format!("{}x{}", "(".repeat(n), ")".repeat(n)),
        format!("{}x", "-".repeat(n)),
        format!("{}x{}", "sq(".repeat(n), ")".repeat(n)),
        format!("{}x{}", "(-sq(".repeat(n), "))".repeat(n)),
        format!("{}x", "(".repeat(n)),
        format!("x{}", "*(x".repeat(n)),
        format!("mean({}x", "x, mean(".repeat(n)),
    ];
    for text in &forms {
        let mut b = ProgramBuilder::<255, 8>::new();
        let e = b.feature(text).unwrap_err();
        assert!(
            matches!(e.kind, K::TooDeep),
            "{}…: {:?}",
            &text[..12],
            e.kind
        );
    }
    // Just under the limit compiles.
    let ok = format!("{}x{}", "(".repeat(22), ")".repeat(22));
    let mut b = ProgramBuilder::<255, 8>::new();
    b.feature(&ok).unwrap();
}
