//! No import circle among a crate's top-level modules, in the two crates that had them
//! (`tcomp-train`, `tcomp-discover`): a helper never imports what builds on it (e.g. the
//! fit-method trait imports no method; the registry imports the methods).
//!
//! The sources are scanned for `crate::x` paths (in `use` lines, grouped `crate::{x, y}` imports
//! and inline paths; comments left out, so a doc link is no edge), each attributed to the top-level
//! module whose file or folder holds it, and the graph must have no cycle.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The code of a Rust file without its comments (`//` to the end of the line, `/* … */`).
fn code(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find("/*") {
        out.push_str(&rest[..i]);
        rest = rest[i..].find("*/").map_or("", |j| &rest[i + j + 2..]);
    }
    out.push_str(rest);
    out.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The leading identifier of `s`.
fn ident(s: &str) -> &str {
    let s = s.trim_start();
    let end = s
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// The top-level modules named after `crate::` in `code`.
fn referenced(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in code.match_indices("crate::") {
        let after = &code[i + "crate::".len()..];
        if let Some(group) = after.strip_prefix('{') {
            // `crate::{a, b::c, d::{e, f}}`: the first identifier of each top-level item.
            let mut depth = 0;
            let mut start = 0;
            for (k, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        out.insert(ident(&group[start..k]).to_string());
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        out.insert(ident(&group[start..k]).to_string());
                        start = k + 1;
                    }
                    _ => {}
                }
            }
        } else {
            out.insert(ident(after).to_string());
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Module → the other top-level modules it uses.
fn graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut modules = BTreeMap::new();
    for e in std::fs::read_dir(src).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if p.extension().is_some_and(|x| x == "rs") && name != "lib" {
            modules.insert(name, BTreeSet::new());
        }
    }
    let names: BTreeSet<String> = modules.keys().cloned().collect();
    for (name, uses) in &mut modules {
        let mut files = vec![src.join(format!("{name}.rs"))];
        if src.join(name.as_str()).is_dir() {
            rust_files(&src.join(name.as_str()), &mut files);
        }
        for f in files {
            let text = std::fs::read_to_string(&f).unwrap();
            uses.extend(
                referenced(&code(&text))
                    .into_iter()
                    .filter(|m| names.contains(m) && m != name),
            );
        }
    }
    modules
}

/// A cycle of the graph, if any (depth-first search; the path from a module back to itself).
fn cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    // 0 unvisited, 1 on the current path, 2 done.
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_string(), 1);
        path.push(m.to_string());
        for n in g.get(m).into_iter().flatten() {
            match state.get(n).copied().unwrap_or(0) {
                1 => {
                    let from = path.iter().position(|p| p == n).unwrap_or(0);
                    let mut c = path[from..].to_vec();
                    c.push(n.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(n, g, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in g.keys() {
        if state.get(m).copied().unwrap_or(0) == 0
            && let Some(c) = visit(m, g, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn the_scan_finds_a_planted_cycle() {
    let mut g = BTreeMap::new();
    g.insert("a".to_string(), BTreeSet::from(["b".to_string()]));
    g.insert("b".to_string(), BTreeSet::from(["a".to_string()]));
    assert!(cycle(&g).is_some());
    let uses = referenced(&code(
        "use crate::{a::X, b::{C, D}, c};\n// crate::d\nlet x = crate::e::f();",
    ));
    assert_eq!(uses, BTreeSet::from(["a", "b", "c", "e"].map(String::from)));
}

/// The `src` folder of workspace crate `dir` (`crates/train`).
fn src_of(dir: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(dir)
        .join("src")
}

#[test]
fn no_import_circle_among_the_discovery_crates_modules() {
    let g = graph(&src_of("crates/discover"));
    assert!(
        g.contains_key("confirm") && g.contains_key("compose"),
        "{g:?}"
    );
    assert_eq!(
        cycle(&g),
        None,
        "an import circle among tcomp-discover's modules"
    );
}

#[test]
fn no_import_circle_among_the_top_level_modules() {
    let g = graph(&src_of("crates/train"));
    assert!(
        g.contains_key("method") && g.contains_key("registry"),
        "{g:?}"
    );
    assert!(
        g["registry"].contains("bayes") && !g["method"].contains("bayes"),
        "the registry imports the methods, the trait none: {g:?}"
    );
    assert_eq!(
        cycle(&g),
        None,
        "an import circle among tcomp-train's modules"
    );
}
