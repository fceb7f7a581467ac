//! The repository's documents hold facts the code also holds: each test here reads a document and
//! checks it against the code (or the tree), so a doc that goes stale fails `cargo test` instead
//! of misleading its next reader.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::path::{Path, PathBuf};

/// The repository's root (this crate is `tests/`).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The cells of a markdown table row (`| a | b |` → `["a", "b"]`, trimmed), or `None` for a line
/// that is not one. `\|` is a pipe inside a cell, as markdown reads it.
fn cells(line: &str) -> Option<Vec<String>> {
    let line = line.trim();
    if !line.starts_with('|') {
        return None;
    }
    let mut out = Vec::new();
    let mut cell = String::new();
    let mut chars = line[1..].chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                cell.push('|');
                chars.next();
            }
            '|' => out.push(std::mem::take(&mut cell).trim().to_string()),
            _ => cell.push(c),
        }
    }
    if !cell.trim().is_empty() {
        out.push(cell.trim().to_string());
    }
    Some(out)
}

/// The table rows (line number, cells) of a markdown document, code blocks skipped; the
/// delimiter rows (`|---|`) left out.
fn table_rows(doc: &str) -> Vec<(usize, Vec<String>)> {
    let mut fenced = false;
    let mut rows = Vec::new();
    for (i, line) in doc.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if let Some(c) = cells(line) {
            if c.iter().all(|c| c.chars().all(|ch| ch == '-' || ch == ':')) {
                continue;
            }
            rows.push((i + 1, c));
        }
    }
    rows
}

/// The rows of the first table after the heading `heading` (a line equal to it).
fn section_table(doc: &str, heading: &str) -> Vec<Vec<String>> {
    let start = doc
        .lines()
        .position(|l| l.trim() == heading)
        .unwrap_or_else(|| panic!("no heading `{heading}`"));
    let mut rows = Vec::new();
    for line in doc.lines().skip(start + 1) {
        match cells(line) {
            Some(c) => rows.push(c),
            None if rows.is_empty() => continue,
            None => break,
        }
    }
    assert!(!rows.is_empty(), "no table under `{heading}`");
    // The header row and the delimiter row.
    rows.drain(..2);
    rows
}

/// `BENCHMARKS.md` is a dashboard: one current figure per cell with its command; the history of a
/// figure lives in git, not in the table.
#[test]
fn benchmarks_cells_are_short() {
    const LIMIT: usize = 300;
    let doc = read("BENCHMARKS.md");
    let long: Vec<String> = table_rows(&doc)
        .into_iter()
        .flat_map(|(line, cells)| {
            cells
                .into_iter()
                .filter(|c| c.chars().count() > LIMIT)
                .map(move |c| format!("line {line}: {} characters: {c}", c.chars().count()))
        })
        .collect();
    assert!(
        long.is_empty(),
        "BENCHMARKS.md cells over {LIMIT} characters (keep the current figure, move the history \
         out):\n{}",
        long.join("\n")
    );
}

/// The status-word table of `firmware/README.md` is `tcomp_core::frame::status`: every named bit
/// has its row, with its constant's name and value, and there is no row for another bit.
#[test]
fn firmware_readme_status_bits_are_the_cores() {
    use tcomp_core::frame::status::{self, NAMES};
    // The constants by name; their values are the code's. A README row naming a constant not
    // listed here fails, so does a named bit (`NAMES`) without a row.
    let consts = [
        ("NO_MODEL", status::NO_MODEL),
        ("OUT_OF_RANGE", status::OUT_OF_RANGE),
        ("INPUT_FAULT", status::INPUT_FAULT),
        ("SENSOR_ERROR", status::SENSOR_ERROR),
        ("STUCK", status::STUCK),
        ("MODEL_FAULT", status::MODEL_FAULT),
        ("TEMP_JUMP", status::TEMP_JUMP),
        ("TIME_JUMP", status::TIME_JUMP),
        ("FIRST_SAMPLE", status::FIRST_SAMPLE),
        ("WATCHDOG_RESET", status::WATCHDOG_RESET),
        ("OVERRUN", status::OVERRUN),
    ];
    let readme = read("firmware/README.md");
    let rows = section_table(&readme, "## Status word (u16)");
    let mut documented = Vec::new();
    for row in &rows {
        // `| 5 (32) | `MODEL_FAULT` | meaning |`
        let (bit, value) = row[0].split_once(' ').unwrap();
        let bit: u32 = bit.parse().unwrap();
        let value: u16 = value
            .trim_matches(|c| c == '(' || c == ')')
            .parse()
            .unwrap();
        let name = row[1].trim_matches('`');
        assert_eq!(
            value,
            1 << bit,
            "row `{}`: {value} is not bit {bit}",
            row[0]
        );
        let (_, code) = consts
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("bit {bit}: `{name}` is not a status constant"));
        assert_eq!(
            *code, value,
            "`{name}` is {code} in the code, {value} in the README"
        );
        documented.push(value);
    }
    let mut named: Vec<u16> = NAMES.iter().map(|(m, _)| *m).collect();
    named.sort_unstable();
    documented.sort_unstable();
    assert_eq!(
        documented, named,
        "the README's status bits are not the named bits of tcomp_core::frame::status"
    );
    assert_eq!(
        consts.len(),
        NAMES.len(),
        "a status constant is missing here"
    );
}

/// Every path in the root README's layout table exists.
#[test]
fn readme_layout_paths_exist() {
    let readme = read("README.md");
    let rows = section_table(&readme, "## Layout");
    assert!(rows.len() > 10, "the layout table has {} rows", rows.len());
    for row in rows {
        let path = row[0].trim_matches('`');
        assert!(
            root().join(path).exists(),
            "README.md's layout names `{path}`, which is not in the tree"
        );
    }
}

/// The update task's doc states its receive buffer: one protocol frame.
#[test]
fn update_task_buffer_is_one_frame() {
    let doc = read("firmware/src/update.rs");
    let stated = format!(
        "receive buffer ({} B, [`tcomp_core::update::wire::MAX_FRAME`])",
        tcomp_core::update::wire::MAX_FRAME
    );
    let flat = doc
        .lines()
        .map(|l| l.trim_start().trim_start_matches("//!").trim())
        .collect::<Vec<_>>()
        .join(" ");
    assert!(
        flat.contains(&stated),
        "firmware/src/update.rs should say {stated}"
    );
}

/// A constant expression of a Rust source line: integers (decimal or hex, `_` allowed), `+ - * /`
/// and parentheses.
fn eval(expr: &str) -> u64 {
    fn sum(t: &[String], i: &mut usize) -> u64 {
        let mut v = product(t, i);
        while *i < t.len() && (t[*i] == "+" || t[*i] == "-") {
            let op = t[*i].clone();
            *i += 1;
            let r = product(t, i);
            v = if op == "+" { v + r } else { v - r };
        }
        v
    }
    fn product(t: &[String], i: &mut usize) -> u64 {
        let mut v = atom(t, i);
        while *i < t.len() && (t[*i] == "*" || t[*i] == "/") {
            let op = t[*i].clone();
            *i += 1;
            let r = atom(t, i);
            v = if op == "*" { v * r } else { v / r };
        }
        v
    }
    fn atom(t: &[String], i: &mut usize) -> u64 {
        let tok = t[*i].clone();
        *i += 1;
        if tok == "(" {
            let v = sum(t, i);
            assert_eq!(t[*i], ")");
            *i += 1;
            return v;
        }
        let digits = tok.replace('_', "");
        match digits.strip_prefix("0x") {
            Some(hex) => u64::from_str_radix(hex, 16).unwrap(),
            None => digits.parse().unwrap(),
        }
    }
    let mut tokens = Vec::new();
    let mut word = String::new();
    for c in expr.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
            continue;
        }
        if !word.is_empty() {
            tokens.push(std::mem::take(&mut word));
        }
        if !c.is_whitespace() {
            tokens.push(c.to_string());
        }
    }
    if !word.is_empty() {
        tokens.push(word);
    }
    let mut i = 0;
    let v = sum(&tokens, &mut i);
    assert_eq!(i, tokens.len(), "cannot evaluate `{expr}`");
    v
}

/// The value of `const NAME: type = expr;` in a Rust source file.
fn rust_const(source: &str, file: &str, name: &str) -> u64 {
    let line = source
        .lines()
        .map(str::trim)
        .find(|l| {
            l.trim_start_matches("pub ")
                .starts_with(&format!("const {name}:"))
        })
        .unwrap_or_else(|| panic!("{file} has no `const {name}`"));
    let expr = line.split_once('=').unwrap().1.trim().trim_end_matches(';');
    eval(expr)
}

/// The `MEMORY` regions of a linker script: (name, origin, length in bytes).
fn memory_regions(script: &str) -> Vec<(String, u64, u64)> {
    let block = script
        .split("MEMORY")
        .nth(1)
        .and_then(|b| b.split('{').nth(1))
        .and_then(|b| b.split('}').next())
        .unwrap();
    block
        .lines()
        .filter(|l| l.contains("ORIGIN"))
        .map(|l| {
            let (name, rest) = l.split_once(':').unwrap();
            let field = |key: &str| {
                let v = rest.split(key).nth(1).unwrap();
                let v = v.trim_start_matches([' ', '=']);
                v.split(',').next().unwrap().trim().to_string()
            };
            let length = field("LENGTH");
            let length = match length.strip_suffix('K') {
                Some(k) => k.parse::<u64>().unwrap() * 1024,
                None => eval(&length),
            };
            (name.trim().to_string(), eval(&field("ORIGIN")), length)
        })
        .collect()
}

/// `0x0800_0000` / `768 KiB (sectors 0–9)` of the board README's memory map.
fn readme_number(cell: &str) -> u64 {
    let first = cell.trim_matches('`').split_whitespace().next().unwrap();
    let v = eval(first);
    if cell.contains("KiB") { v * 1024 } else { v }
}

/// The STM32F407 board's `memory.x`, at the repository root, is what its Rust code and the firmware's slot layout assume
/// (the flash driver's `MODELS` region, `STM32F4_LAYOUT`, the part's figures the budgets of `cargo
/// xtask` are taken from), and
/// what its README's memory map says.
#[test]
fn stm32_memory_x_is_what_the_code_assumes() {
    const MEMORY_X: &str = "memory.x";
    let regions = memory_regions(&read(MEMORY_X));
    let region = |name: &str| {
        regions
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|&(_, origin, length)| (origin, length))
            .unwrap_or_else(|| panic!("{MEMORY_X} has no region {name}"))
    };

    // The board's flash driver: where it reads and writes the slots.
    let flash_rs = "firmware/boards/stm32f4/src/flash.rs";
    let driver = read(flash_rs);
    let models = (
        rust_const(&driver, flash_rs, "MODELS_ADDRESS"),
        rust_const(&driver, flash_rs, "MODELS_LEN"),
    );
    assert_eq!(region("MODELS"), models, "MODELS against {flash_rs}");
    // The application's slot layout: slot A then slot B, together the whole region.
    let layout = tcomp_firmware::slots::STM32F4_LAYOUT;
    assert_eq!(u64::from(layout.a), 0);
    assert_eq!(u64::from(layout.b), u64::from(layout.size));
    assert_eq!(u64::from(layout.b + layout.size), models.1);
    assert_eq!(
        u64::from(layout.size),
        rust_const(&driver, flash_rs, "SECTOR"),
        "one slot is one sector"
    );

    // The firmware's flash ends where the slots begin, and is what the size budget allows.
    // The budgets' part figures (`cargo xtask`'s one budget module, for both boards).
    let xtask_rs = "host-tools/xtask/src/budget.rs";
    let xtask = read(xtask_rs);
    let (flash_origin, flash_len) = region("FLASH");
    assert_eq!(flash_origin + flash_len, models.0, "FLASH runs into MODELS");
    assert_eq!(flash_len, rust_const(&xtask, xtask_rs, "FLASH_BUDGET"));
    assert_eq!(region("RAM").1, rust_const(&xtask, xtask_rs, "SRAM"));
    assert_eq!(region("CCMRAM").1, rust_const(&xtask, xtask_rs, "CCM"));

    // The board README's memory map.
    let readme = read("firmware/boards/stm32f4/README.md");
    let map = section_table(
        &readme,
        "## Memory map (`memory.x`, at the repository root)",
    );
    assert_eq!(map.len(), regions.len(), "one README row per region");
    for row in map {
        let (origin, length) = region(&row[0]);
        assert_eq!(
            readme_number(&row[1]),
            origin,
            "README address of {}",
            row[0]
        );
        assert_eq!(readme_number(&row[2]), length, "README size of {}", row[0]);
    }
}

/// The root `memory.x` is the product board's and the one its binary links (its `build.rs` names
/// it); the QEMU board, whose map differs, is a workspace of its own, because cargo runs the
/// linker from the workspace root and the linker resolves cortex-m-rt's `INCLUDE memory.x` there
/// first: a root workspace member would link the root's map whatever its own search path says.
/// `cargo xtask board` checks the linked ELF's sections against the root's regions.
#[test]
fn the_root_memory_x_is_the_product_boards() {
    let build = read("firmware/boards/stm32f4/build.rs");
    assert!(
        build.contains(r#"root.join("../../../memory.x")"#),
        "the STM32 board's build.rs links the root memory.x"
    );
    assert!(!root().join("firmware/boards/stm32f4/memory.x").exists());
    assert!(root().join("firmware/boards/qemu/memory.x").exists());
    let workspace = read("Cargo.toml");
    assert!(workspace.contains(r#"exclude = ["firmware/boards/qemu"]"#));
    let qemu = read("firmware/boards/qemu/Cargo.toml");
    assert!(
        qemu.contains("\n[workspace]\n"),
        "the QEMU board is its own workspace"
    );
    // Its release profile is the root's (a profile applies only in its own workspace).
    let profile = |toml: &str| {
        let at = toml.find("[profile.release]").expect("a release profile");
        toml[at..]
            .lines()
            .skip(1)
            .take_while(|l| !l.trim().is_empty() && !l.starts_with('['))
            .map(str::to_owned)
            .collect::<Vec<_>>()
    };
    assert_eq!(profile(&qemu), profile(&workspace));
    // Its registry dependencies at the root's versions, where the root names them.
    let version = |line: &str| {
        let at = line.find('"')? + 1;
        Some(line[at..at + line[at..].find('"')?].to_owned())
    };
    let section = |toml: &str, head: &str| {
        let at = toml.find(head).expect("the section");
        toml[at + head.len()..]
            .lines()
            .take_while(|l| !l.starts_with('['))
            .filter(|l| !l.starts_with('#') && !l.contains("path ="))
            .filter_map(|l| Some((l.split('=').next()?.trim().to_owned(), version(l)?)))
            .collect::<Vec<_>>()
    };
    let roots = section(&workspace, "[workspace.dependencies]");
    let mut compared = 0;
    for (name, v) in section(&qemu, "[dependencies]") {
        if let Some((_, rv)) = roots.iter().find(|(n, _)| *n == name) {
            assert_eq!(&v, rv, "{name}: the QEMU board's version is the root's");
            compared += 1;
        }
    }
    assert!(compared >= 6, "compared {compared} dependencies");
}
