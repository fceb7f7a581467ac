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
