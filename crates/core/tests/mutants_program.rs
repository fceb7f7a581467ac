//! `Program::validate` is what stands between a decoded blob and the firmware's sample loop: every
//! rule is checked here on hand-built programs, on both sides of its boundary, together with the
//! small accessors and the builder's name rules.
//! Written to kill what `cargo mutants` found untested in `program.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use heapless::Vec as HVec;
use tcomp_core::program::Signal;
use tcomp_core::{MAX_STATEFUL, ParseErrorKind as K, Program, ProgramBuilder, ProgramError};

type P = Program<'static, 16, 4>;
/// The blob's operations (f32).
type Op = tcomp_core::Op;

/// A program over inputs `a`, `b` with `nodes` and the last node as its one feature.
fn program(nodes: &[Op]) -> P {
    let mut p = P::new();
    p.inputs.push("a").unwrap();
    p.inputs.push("b").unwrap();
    for op in nodes {
        p.nodes.push(*op).unwrap();
    }
    p.features
        .push(nodes.len().saturating_sub(1) as u8)
        .unwrap();
    p.feature_exprs.push("f").unwrap();
    p
}

fn check(nodes: &[Op]) -> Result<(), ProgramError> {
    program(nodes).validate()
}

#[test]
fn operands_must_come_earlier() {
    let x = Op::Input(0);
    assert_eq!(check(&[x, Op::Add(0, 0)]), Ok(()));
    assert_eq!(check(&[x, x, Op::Sub(1, 0)]), Ok(()));
    assert_eq!(
        check(&[x, Op::Mul(1, 0)]),
        Err(ProgramError::ForwardReference { node: 1 })
    );
    assert_eq!(
        check(&[x, Op::Div(0, 1)]),
        Err(ProgramError::ForwardReference { node: 1 })
    );
    assert_eq!(
        check(&[x, x, Op::Neg(3)]),
        Err(ProgramError::ForwardReference { node: 2 })
    );
}

#[test]
fn operands_of_every_op() {
    assert_eq!(Op::Input(1).operands(), (None, None));
    assert_eq!(Op::Const(2.0).operands(), (None, None));
    for op in [Op::Add(3, 5), Op::Sub(3, 5), Op::Mul(3, 5), Op::Div(3, 5)] {
        assert_eq!(op.operands(), (Some(3), Some(5)), "{op:?}");
    }
    for op in [
        Op::Neg(4),
        Op::Sq(4),
        Op::Abs(4),
        Op::Clamp {
            x: 4,
            lo: 0.0,
            hi: 1.0,
        },
        Op::Rate {
            x: 4,
            slot: 2,
            window_s: 1.0,
        },
        Op::Lag {
            x: 4,
            slot: 2,
            tau_s: 1.0,
        },
        Op::Hyst {
            x: 4,
            slot: 2,
            threshold: 1.0,
        },
    ] {
        assert_eq!(op.operands(), (Some(4), None), "{op:?}");
        let stateful = matches!(op, Op::Rate { .. } | Op::Lag { .. } | Op::Hyst { .. });
        assert_eq!(op.slot(), stateful.then_some(2), "{op:?}");
    }
    assert_eq!(Op::Add(0, 0).slot(), None);
}

#[test]
fn inputs_must_be_listed() {
    assert_eq!(check(&[Op::Input(1)]), Ok(()));
    assert_eq!(
        check(&[Op::Input(0), Op::Input(2)]),
        Err(ProgramError::UnknownInput { node: 1 })
    );
}

#[test]
fn parameters_must_be_finite_and_in_their_domain() {
    let x = Op::Input(0);
    let bad = |op: Op| check(&[x, op]) == Err(ProgramError::BadParameter { node: 1 });
    let good = |op: Op| check(&[x, op]) == Ok(());
    assert!(good(Op::Const(-3.0)));
    assert!(bad(Op::Const(f32::NAN)) && bad(Op::Const(f32::INFINITY)));
    let clamp = |lo, hi| Op::Clamp { x: 0, lo, hi };
    assert!(good(clamp(-1.0, 1.0)) && good(clamp(2.0, 2.0)));
    assert!(bad(clamp(1.0, -1.0)));
    assert!(bad(clamp(f32::NAN, 1.0)) && bad(clamp(0.0, f32::INFINITY)));
    assert!(bad(clamp(f32::NEG_INFINITY, 0.0)));
    let rate: fn(f32) -> Op = |window_s| Op::Rate {
        x: 0,
        slot: 0,
        window_s,
    };
    let lag: fn(f32) -> Op = |tau_s| Op::Lag {
        x: 0,
        slot: 0,
        tau_s,
    };
    for make in [rate, lag] {
        assert!(good(make(1e-3)) && good(make(60.0)));
        assert!(bad(make(0.0)) && bad(make(-1.0)));
        assert!(bad(make(f32::NAN)) && bad(make(f32::INFINITY)));
    }
    let hyst = |threshold| Op::Hyst {
        x: 0,
        slot: 0,
        threshold,
    };
    assert!(good(hyst(0.0)) && good(hyst(0.05)));
    assert!(bad(hyst(-0.05)) && bad(hyst(f32::NAN)) && bad(hyst(f32::INFINITY)));
}

#[test]
fn each_slot_serves_one_stateful_node() {
    let x = Op::Input(0);
    let lag = |slot| Op::Lag {
        x: 0,
        slot,
        tau_s: 1.0,
    };
    let last = (MAX_STATEFUL - 1) as u8;
    assert_eq!(check(&[x, lag(0), lag(last)]), Ok(()));
    assert_eq!(
        check(&[x, lag(1), lag(1)]),
        Err(ProgramError::BadSlot { node: 2 })
    );
    assert_eq!(
        check(&[x, lag(last + 1)]),
        Err(ProgramError::BadSlot { node: 1 })
    );
}

#[test]
fn features_and_signals_must_name_existing_nodes() {
    let mut p = program(&[Op::Input(0), Op::Input(1)]);
    assert_eq!(p.validate(), Ok(()));
    p.features.clear();
    p.feature_exprs.clear();
    assert_eq!(p.validate(), Err(ProgramError::NoFeatures));
    let mut p = program(&[Op::Input(0), Op::Input(1)]);
    p.feature_exprs.push("g").unwrap();
    assert_eq!(p.validate(), Err(ProgramError::BadFeature { feature: 0 }));
    let mut p = program(&[Op::Input(0), Op::Input(1)]);
    p.features.push(2).unwrap();
    p.feature_exprs.push("g").unwrap();
    assert_eq!(p.validate(), Err(ProgramError::BadFeature { feature: 1 }));
    let mut p = program(&[Op::Input(0), Op::Input(1)]);
    let signal = |node| Signal {
        name: "S",
        expr: "a",
        node,
    };
    p.signals.push(signal(1)).unwrap();
    assert_eq!(p.validate(), Ok(()));
    p.signals.push(signal(2)).unwrap();
    assert_eq!(p.validate(), Err(ProgramError::BadFeature { feature: 1 }));
}

#[test]
fn accessors() {
    let mut b = ProgramBuilder::<'static, 16, 4>::new();
    b.line("T = mean(ta, tb)").unwrap();
    b.feature("T").unwrap();
    b.feature("rate(T)").unwrap();
    b.feature("tc").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(p.n_features(), 3);
    assert_eq!(p.input_index("ta"), Some(0));
    assert_eq!(p.input_index("tb"), Some(1));
    assert_eq!(p.input_index("tc"), Some(2));
    assert_eq!(p.input_index("T"), None, "a signal is not an input");
    assert_eq!(P::new().n_features(), 0);
    let _: HVec<u8, 4> = p.features.clone();
}

#[test]
fn signal_names_are_identifiers_that_are_not_functions() {
    let mut b = ProgramBuilder::<'static, 16, 4>::new();
    assert_eq!(b.signal("lag", "a").unwrap_err().kind, K::BadName);
    assert_eq!(b.signal("1T", "a").unwrap_err().kind, K::BadName);
    assert_eq!(b.signal("T two", "a").unwrap_err().kind, K::BadName);
    b.signal("T", "a").unwrap();
    b.signal("U", "b").unwrap();
    assert_eq!(b.signal("T", "b").unwrap_err().kind, K::DuplicateSignal);
    b.feature("T - U").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(p.signals.len(), 2);
    assert_eq!(p.inputs.as_slice(), &["a", "b"]);
}

#[test]
fn line_errors_point_into_the_line() {
    let mut b = ProgramBuilder::<'static, 16, 4>::new();
    b.line("T = a").unwrap();
    // The name's error points at the name, the expression's into the expression.
    let e = b.line("  T = b").unwrap_err();
    assert_eq!((e.kind, e.start, e.end), (K::DuplicateSignal, 2, 3));
    let e = b.line("U =  a +").unwrap_err();
    assert_eq!((e.kind, e.start), (K::UnexpectedEnd, 8));
    let e = b.line("   V = ").unwrap_err();
    assert_eq!((e.kind, e.start, e.end), (K::Empty, 6, 7));
}

#[test]
fn every_program_error_names_its_place() {
    for (e, words) in [
        (ProgramError::ForwardReference { node: 7 }, "node 7"),
        (ProgramError::UnknownInput { node: 8 }, "node 8"),
        (ProgramError::BadParameter { node: 9 }, "node 9"),
        (ProgramError::BadSlot { node: 10 }, "node 10"),
        (ProgramError::BadFeature { feature: 11 }, "feature 11"),
        (ProgramError::NoFeatures, "no features"),
    ] {
        assert!(e.to_string().contains(words), "{e:?}: {e}");
    }
}
