//! Commands on top, helpers below: no module outside `src/cmd/` names a command module.
//!
//! Why a test: `cmd/` holds one module per subcommand, and the rest of the crate (`calibrate/`,
//! `render/`, `demo/`, `output/`, `args/`, `image.rs`) is what the commands are built from. Once a
//! helper imports from a command, the command's clap arguments and printing leak into the library
//! (the Python binding calls it) and the two can no longer change apart; this happened before, when
//! the shared helpers lived in `cmd/`. Only the dispatchers, `main.rs` and `lib.rs`, may name
//! `cmd`. The check is textual, so a doc link to a command counts too: the helpers' docs should not
//! send a reader up either.

use std::path::{Path, PathBuf};

/// How a path into the command modules starts.
const COMMAND_PATHS: [&str; 3] = ["crate::cmd", "tcomp::cmd", "super::cmd"];

/// Every `.rs` file under `dir`, recursively, sorted.
fn rust_files(dir: &Path, into: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<Vec<PathBuf>>>()?;
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, into)?;
        } else if path.extension().is_some_and(|x| x == "rs") {
            into.push(path);
        }
    }
    Ok(())
}

/// Whether `line` names a command module: a path through `cmd` (`crate::cmd::…`), or `cmd` in a
/// grouped import from the crate root (`use crate::{cmd, …}`).
fn names_cmd(line: &str) -> bool {
    if COMMAND_PATHS.iter().any(|p| line.contains(p)) {
        return true;
    }
    ["crate::{", "tcomp::{"].iter().any(|g| {
        line.split(g).skip(1).any(|group| {
            group
                .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .any(|word| word == "cmd")
        })
    })
}

#[test]
fn no_module_outside_cmd_imports_a_command() -> std::io::Result<()> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let dispatchers = [src.join("main.rs"), src.join("lib.rs")];
    let mut files = Vec::new();
    rust_files(&src, &mut files)?;
    let mut found = Vec::new();
    for path in files
        .iter()
        .filter(|p| !p.starts_with(src.join("cmd")) && !dispatchers.contains(p))
    {
        let text = std::fs::read_to_string(path)?;
        for (i, line) in text.lines().enumerate() {
            if names_cmd(line) {
                let shown = path.strip_prefix(&src).unwrap_or(path);
                found.push(format!(
                    "src/{}:{}: {}",
                    shown.display(),
                    i + 1,
                    line.trim()
                ));
            }
        }
    }
    assert!(
        found.is_empty(),
        "a helper below the commands names a command module (`cmd/` is imported only by main.rs \
         and lib.rs; move what is shared out of `cmd/`):\n{}",
        found.join("\n")
    );
    Ok(())
}

#[test]
fn the_check_sees_each_way_of_naming_a_command() {
    for line in [
        "use crate::cmd::calibrate::Args;",
        "let bar = crate::cmd::progress::counter(q, \"x\", 1, \"u\");",
        "use tcomp::cmd::run::RunArgs;",
        "use super::cmd::json;",
        "use crate::{calibrate, cmd::image};",
        "/// See [`crate::cmd::image`].",
    ] {
        assert!(names_cmd(line), "missed: {line}");
    }
    for line in [
        "use crate::output::json;",
        "use crate::{calibrate, render};",
        "let cmd = Command::new(\"qemu\");",
        "use crate::image::{self, ChannelBlob};",
    ] {
        assert!(!names_cmd(line), "wrongly flagged: {line}");
    }
}
