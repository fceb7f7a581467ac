//! The committed C header is what cbindgen makes of this crate now, and its error names are the
//! library's.
//!
//! Why a test and not a build script: the header is part of the source a C user reads and
//! reviews; regenerating it on every build would hide changes to the C API inside a build
//! directory. Here a change to the API fails the test until the header is regenerated
//! (`TCOMP_BLESS_HEADER=1 cargo test -p tcomp-ffi --test header`) and committed with it, so
//! the diff shows the C side of every change. cbindgen runs as a library (a dev-dependency):
//! CI needs no `cargo install`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(unsafe_code)] // reading the static C strings the library returns

use std::ffi::CStr;
use std::path::PathBuf;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The header as cbindgen generates it from `src/lib.rs` (and the modules it declares) with
/// `cbindgen.toml`.
fn generate() -> String {
    let dir = crate_dir();
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen parses the crate");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).unwrap()
}

fn committed_path() -> PathBuf {
    crate_dir().join("include/tcomp.h")
}

#[test]
fn committed_header_is_fresh() {
    let fresh = generate();
    let path = committed_path();
    if std::env::var_os("TCOMP_BLESS_HEADER").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != fresh {
        let line = committed
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or(committed.lines().count().min(fresh.lines().count()), |i| i)
            + 1;
        panic!(
            "{} is not what cbindgen generates now (first difference at line {line}); \
             regenerate it with `TCOMP_BLESS_HEADER=1 cargo test -p tcomp-ffi --test header` \
             and commit it",
            path.display()
        );
    }
}

/// `#define NAME VALUE` lines of the header whose name starts with `prefix`.
fn defines(header: &str, prefix: &str) -> Vec<(String, i64)> {
    header
        .lines()
        .filter_map(|l| l.strip_prefix("#define "))
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            let name = it.next()?;
            let value = it.next()?.trim_start_matches('(').trim_end_matches(')');
            if !name.starts_with(prefix) {
                return None;
            }
            Some((name.to_string(), value.parse().ok()?))
        })
        .collect()
}

#[test]
fn every_error_code_in_the_header_is_named_by_the_library() {
    let header = std::fs::read_to_string(committed_path()).unwrap();
    let codes = defines(&header, "TCOMP_ERR_");
    assert!(codes.len() >= 30, "found {} error codes", codes.len());
    let mut seen = std::collections::HashSet::new();
    for (name, value) in codes.iter().chain(&defines(&header, "TCOMP_OK")) {
        let code = i32::try_from(*value).unwrap();
        assert!(seen.insert(code), "{name}: code {code} is used twice");
        // SAFETY: the library returns a NUL-terminated static string, never NULL.
        let named = unsafe { CStr::from_ptr(tcomp_ffi::tcomp_error_name(code)) };
        assert_eq!(named.to_str().unwrap(), name, "tcomp_error_name({code})");
    }
    // SAFETY: as above.
    let unknown = unsafe { CStr::from_ptr(tcomp_ffi::tcomp_error_name(12345)) };
    assert_eq!(unknown.to_str().unwrap(), "TCOMP_ERR_UNKNOWN");
}

#[test]
fn the_header_documents_every_function() {
    let header = std::fs::read_to_string(committed_path()).unwrap();
    let lines: Vec<&str> = header.lines().collect();
    let mut functions = 0;
    for (i, line) in lines.iter().enumerate() {
        let is_decl = line.contains("tcomp_")
            && line.contains('(')
            && !line.starts_with("//")
            && !line.starts_with('#')
            && !line.starts_with(' ')
            && !line.starts_with("typedef");
        if is_decl {
            functions += 1;
            let above = i.checked_sub(1).map(|j| lines[j]).unwrap_or("");
            assert!(
                above.starts_with("//") || above.starts_with(" *") || above.starts_with("/*"),
                "line {}: `{line}` has no doc comment",
                i + 1
            );
        }
    }
    assert!(functions >= 15, "found {functions} function declarations");
}
