//! The candidate table is one function in two layouts (`render/candidates.rs`): the demo's
//! narrative and `tcomp diagnose` on the demo's "before" model list the same candidates in the same
//! order, with the same ones marked as passing the criterion.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::process::Command;

fn tcomp(args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .expect("run tcomp");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

/// (passes, effect) of each row of the demo's paragraph 4.
fn demo_rows(text: &str) -> Vec<(bool, String)> {
    text.lines()
        .filter_map(|l| {
            // A row's evidence is a signed number (the criterion's sentence says "≥ 5").
            let (head, tail) = l.split_once(" Δ log evidence ")?;
            tail.trim_start().starts_with(['+', '-']).then_some(())?;
            let row = head.strip_prefix("   ")?;
            let passes = row.starts_with('✔');
            Some((passes, row.trim_start_matches('✔').trim().to_string()))
        })
        .collect()
}

/// (passes, effect) of each row of the candidate table of `tcomp diagnose`: a row's first line
/// (`  ✔  ` or five spaces, then the effect's first words and the figures), the rest of its effect
/// wrapped on lines indented by seven, then its expressions after `= `.
fn diagnose_rows(text: &str) -> Vec<(bool, String)> {
    let mut rows: Vec<(bool, String)> = Vec::new();
    for l in text
        .lines()
        .skip_while(|l| !l.trim_end().ends_with("AR(1)/placebo"))
        .skip(1)
        .take_while(|l| l.starts_with("  ") && !l.starts_with("  skipped"))
    {
        if let Some(rest) = l.strip_prefix("       ") {
            if !rest.starts_with("= ")
                && let Some(row) = rows.last_mut()
            {
                row.1 = format!("{} {}", row.1, rest.trim());
            }
            continue;
        }
        let row = l.trim_start();
        let passes = row.starts_with('✔');
        let row = row.trim_start_matches('✔').trim_start();
        let effect = row.split("  ").next().unwrap_or("").trim().to_string();
        rows.push((passes, effect));
    }
    rows
}

/// The table of `tcomp diagnose` fits a 100-column page: every line of it, however long the
/// effect's name, with the figures under their header.
fn assert_fits(text: &str) {
    for l in text
        .lines()
        .skip_while(|l| !l.trim_end().ends_with("AR(1)/placebo"))
        .take_while(|l| l.starts_with("  ") && !l.starts_with("  skipped"))
        .filter(|l| !l.trim_start().starts_with("= "))
    {
        assert!(
            l.chars().count() <= 100,
            "wider than the page:\n{l}\n{text}"
        );
    }
}

#[test]
fn demo_and_diagnose_print_the_same_candidates() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = out.to_str().unwrap();
    let demo = tcomp(&["demo", "--seed", "3", "--step", "5", "--out", o]);
    let p = |f: &str| out.join(f).to_str().unwrap().to_string();
    let diagnose = tcomp(&[
        "diagnose",
        "--model",
        &p("before.tcm"),
        "--data",
        &p("train.csv"),
        "--verify",
        &p("verify.csv"),
    ]);
    let (a, b) = (demo_rows(&demo), diagnose_rows(&diagnose));
    assert!(a.len() >= 2, "too few candidates in the demo:\n{demo}");
    assert!(b.len() >= a.len(), "too few candidates:\n{diagnose}");
    assert_eq!(a, b[..a.len()], "demo:\n{demo}\ndiagnose:\n{diagnose}");
    assert!(a.iter().any(|r| r.0), "no candidate passes:\n{demo}");
    assert_fits(&diagnose);
}
