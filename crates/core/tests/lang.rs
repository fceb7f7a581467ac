//! The operator table is the language: the parser's names, arity and messages, the validator's
//! domains, the documentation and the blob format version of each operation all come from it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_core::blob::{FORMAT_VERSION, OLDEST_FORMAT_VERSION};
use tcomp_core::lang::{self, Code, FUNCTIONS, SYNTAX};
use tcomp_core::testing::example_model;
use tcomp_core::{BlobError, Model, Op, ParseErrorKind, ProgramBuilder};

const ALL_CODES: [Code; 14] = [
    Code::Input,
    Code::Const,
    Code::Add,
    Code::Sub,
    Code::Mul,
    Code::Div,
    Code::Neg,
    Code::Sq,
    Code::Abs,
    Code::Clamp,
    Code::Rate,
    Code::Lag,
    Code::Hyst,
    Code::Warmup,
];

/// The table in `lang.rs`'s module documentation, as markdown lines.
fn documented_table() -> String {
    include_str!("../src/lang.rs")
        .lines()
        .filter_map(|l| l.strip_prefix("//! |").map(|rest| format!("|{rest}\n")))
        .collect()
}

#[test]
fn the_documented_table_is_the_generated_one() {
    let mut generated = String::new();
    lang::write_table(&mut generated).unwrap();
    assert_eq!(
        documented_table(),
        generated,
        "regenerate the table in lang.rs's docs from lang::write_table"
    );
    // Every function appears in it by its call syntax.
    for f in &FUNCTIONS {
        let mut syntax = String::new();
        f.write_syntax(&mut syntax).unwrap();
        assert!(generated.contains(&format!("| `{syntax}` |")), "{syntax}");
    }
}

#[test]
fn every_operation_is_in_exactly_one_row_and_no_newer_than_this_build() {
    for code in ALL_CODES {
        let functions = FUNCTIONS.iter().filter(|f| f.op == Some(code)).count();
        let syntax = SYNTAX.iter().filter(|s| s.ops.contains(&code)).count();
        assert_eq!(functions + syntax, 1, "{code:?}");
        let since = lang::since(code);
        assert!((1..=FORMAT_VERSION).contains(&since), "{code:?}: {since}");
    }
    const { assert!(lang::NEWEST_SINCE <= FORMAT_VERSION && OLDEST_FORMAT_VERSION <= FORMAT_VERSION) };
}

#[test]
fn each_function_compiles_to_its_operation_and_the_program_needs_its_version() {
    for f in &FUNCTIONS {
        let args: Vec<&str> = match (f.name, f.params.len()) {
            ("clamp", _) => vec!["x", "-1", "2"],
            ("warmup", _) => vec!["600"],
            (_, 0) => vec!["x", "y"].into_iter().take(1).collect(),
            (_, n) => std::iter::once("x")
                .chain(std::iter::repeat_n("3", n))
                .collect(),
        };
        let text = format!("{}({})", f.name, args.join(", "));
        let mut b = ProgramBuilder::<16, 1>::new();
        b.feature(Box::leak(text.clone().into_boxed_str())).unwrap();
        let p = b.finish().unwrap();
        if let Some(code) = f.op {
            let last = p.nodes.last().unwrap();
            assert_eq!(last.code(), code, "{text}");
            assert_eq!(last.slot().is_some(), f.stateful, "{text}");
        }
        assert_eq!(p.format_version(), f.since, "{text}");
    }
}

#[test]
fn arity_and_names_come_from_the_table() {
    for f in &FUNCTIONS {
        for n in 0..5 {
            let args = vec!["1"; n].join(", ");
            let text: &'static str = Box::leak(
                format!("{}(x{}{args})", f.name, if n > 0 { ", " } else { "" }).into_boxed_str(),
            );
            let mut b = ProgramBuilder::<16, 1>::new();
            let r = b.feature(text);
            let wrong = r.as_ref().err().map(|e| e.kind) == Some(ParseErrorKind::WrongArgCount);
            assert_eq!(wrong, !f.admits_arg_count(n + 1), "{text}: {r:?}");
        }
        assert!(tcomp_core::syntax::is_function(f.name));
    }
    assert!(!tcomp_core::syntax::is_function("exp"));
}

#[test]
fn messages_list_the_table() {
    let err = |text: &'static str| {
        let mut b = ProgramBuilder::<16, 1>::new();
        b.feature(text).unwrap_err().to_string()
    };
    assert_eq!(
        err("foo(x)"),
        "column 1: unknown function (known: sq, abs, mean, rate, lag, hyst, clamp, warmup)"
    );
    assert_eq!(
        err("sq(x, 1)"),
        "column 1: wrong number of arguments (sq(x), abs(x), mean(a, ...), rate(x[, window_s]), \
         lag(x, tau_s), hyst(x, threshold), clamp(x, lo, hi), warmup(tau_s))"
    );
    let mut b = ProgramBuilder::<64, 1>::new();
    let too_many = (0..=tcomp_core::MAX_STATEFUL)
        .map(|_| "lag(x, 1)")
        .collect::<Vec<_>>()
        .join(" + ");
    let e = b.feature(Box::leak(too_many.into_boxed_str())).unwrap_err();
    assert!(
        e.to_string()
            .ends_with(": too many rate/lag/hyst/warmup operators"),
        "{e}"
    );
}

#[test]
fn the_validator_reads_the_domains() {
    let mut p = tcomp_core::testing::rlg_program::<16, 4>();
    let rate = p
        .nodes
        .iter()
        .position(|op| op.code() == Code::Rate)
        .unwrap();
    for (window, ok) in [(60.0, true), (1e-30, true), (0.0, false), (-1.0, false)] {
        if let Op::Rate { window_s, .. } = &mut p.nodes[rate] {
            *window_s = window;
        }
        assert_eq!(p.validate().is_ok(), ok, "window {window}");
    }
}

fn encode(m: &Model<'_, 64, 8, 48>) -> Vec<u8> {
    let mut buf = vec![0u8; 8192];
    let n = m.encode(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn reseal(blob: &mut [u8]) {
    let n = blob.len() - 4;
    let crc = tcomp_core::blob::crc32(&blob[..n]);
    blob[n..].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn a_blob_is_stamped_with_the_version_its_program_needs() {
    let m = example_model::<64, 8, 48>(8, 1);
    assert_eq!(
        m.version,
        m.program.format_version().max(OLDEST_FORMAT_VERSION)
    );
    assert_eq!(m.version, 1, "today's blobs stay at version 1");
    assert_eq!(encode(&m)[4], 1);
}

/// A blob from a newer build that uses an operation this build does not know is refused as a
/// version this build does not read — not as malformed — because the writer stamps the version the
/// operation needs; with its version left at 1 the same bytes are an unknown tag (malformed).
#[test]
fn a_blob_using_a_newer_operation_is_too_new_not_malformed() {
    let a = example_model::<64, 8, 48>(8, 1);
    let sub = a
        .program
        .nodes
        .iter()
        .position(|op| op.code() == Code::Sub)
        .unwrap();
    let mut b = a.clone();
    if let Op::Sub(x, y) = b.program.nodes[sub] {
        b.program.nodes[sub] = Op::Add(x, y);
    }
    let (ea, eb) = (encode(&a), encode(&b));
    let body = ea.len() - 4;
    let diff: Vec<usize> = (0..body).filter(|&i| ea[i] != eb[i]).collect();
    assert_eq!(diff.len(), 1, "one operation tag differs");
    let unknown_tag = ALL_CODES.len() as u8; // the next operation a newer build would add
    let mut newer = ea.clone();
    newer[diff[0]] = unknown_tag;
    newer[4] = (FORMAT_VERSION + 1) as u8;
    reseal(&mut newer);
    assert_eq!(
        Model::<64, 8, 48>::decode(&newer).unwrap_err(),
        BlobError::UnsupportedVersion(FORMAT_VERSION + 1)
    );
    let mut unstamped = ea.clone();
    unstamped[diff[0]] = unknown_tag;
    reseal(&mut unstamped);
    assert_eq!(
        Model::<64, 8, 48>::decode(&unstamped).unwrap_err(),
        BlobError::UnknownTag("program.nodes")
    );
    // A model claiming an older version than one of its operations is inconsistent.
    let mut claims = a.clone();
    claims.version = 0;
    assert_eq!(
        claims.validate().unwrap_err(),
        BlobError::UnsupportedVersion(0)
    );
}
