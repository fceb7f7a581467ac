//! The bad-input catalogue: every way of calling `tcomp` wrongly that a reviewer tried, one row each.
//!
//! Each row runs the debug binary in a fresh directory holding a good run (`run.csv`), a good blob
//! (`m.tcm`), earlier outputs (`out.tcm`, `out.bin`, `out.html`, `demo/`) and the row's own files, with
//! `RUST_BACKTRACE=1` set. It asserts the exit code (1 for a failed run, 2 for bad usage), that stderr
//! names the place (`file:line:col`, the option, or the field) and holds no backtrace, and that the
//! directory is exactly as it was: every file's bytes unchanged and nothing added (no output, no
//! temporary file). [`hardened`] holds the rows fixed in the core and the trainer (CSV reader, option
//! ranges, the parser, model plausibility); they run with the rest.
//!
//! Below the catalogue: one test per command that an existing output survives every failing run,
//! and that `inspect` never prints a blob's control characters.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// One row of the catalogue.
struct Case {
    name: &'static str,
    args: Vec<String>,
    files: Vec<(&'static str, Vec<u8>)>,
    codes: &'static [i32],
    says: Vec<&'static str>,
    lacks: Vec<&'static str>,
    max_stderr: usize,
}

/// A row: the command line `line` (see [`command_line`]) run in the case directory, expected to
/// fail with exit code 1.
fn case(name: &'static str, line: &str) -> Case {
    Case {
        name,
        args: command_line(line),
        files: Vec::new(),
        codes: &[1],
        says: Vec::new(),
        lacks: Vec::new(),
        max_stderr: usize::MAX,
    }
}

impl Case {
    /// A file the row needs besides the standard ones.
    fn file(mut self, name: &'static str, bytes: impl Into<Vec<u8>>) -> Self {
        self.files.push((name, bytes.into()));
        self
    }
    /// Bad usage: clap's exit code 2.
    fn usage(mut self) -> Self {
        self.codes = &[2];
        self
    }
    /// Either exit code (for a check that may land in clap or in the library).
    fn usage_or_failure(mut self) -> Self {
        self.codes = &[1, 2];
        self
    }
    /// Substrings stderr must contain.
    fn says(mut self, s: &[&'static str]) -> Self {
        self.says.extend_from_slice(s);
        self
    }
    /// Substrings stderr must not contain.
    fn lacks(mut self, s: &[&'static str]) -> Self {
        self.lacks.extend_from_slice(s);
        self
    }
    /// Longest acceptable stderr in bytes.
    fn at_most(mut self, n: usize) -> Self {
        self.max_stderr = n;
        self
    }
}

fn tcomp_in(dir: &Path, args: &[String]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("run tcomp")
}

/// A 600-row chamber run: coil temperature on a sine, a gyro bias quadratic in it, a constant
/// reference.
fn run_csv() -> String {
    let mut s = String::from("time_s,t_coil_c,gyro_dph,ref_dph\n");
    for i in 0..600 {
        let t = i as f64;
        let temp = 20.0 + 15.0 * (t / 100.0).sin();
        let noise = 0.01 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5);
        s.push_str(&format!(
            "{t},{temp},{},10\n",
            10.0 + 0.02 * temp + 1e-3 * temp * temp + noise
        ));
    }
    s
}

/// A good blob fitted on [`run_csv`] by the binary itself, made once per test process.
fn model_blob() -> &'static [u8] {
    static BLOB: OnceLock<Vec<u8>> = OnceLock::new();
    BLOB.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("run.csv"), run_csv()).unwrap();
        let out = tcomp_in(dir.path(), &strings(&fit_args("run.csv", "m.tcm")));
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(dir.path().join("m.tcm")).unwrap()
    })
}

/// The good blob with its coefficients changed by `f`, re-encoded with a valid checksum (by hand:
/// `Model::encode` itself refuses an implausible model).
fn doctored(
    f: impl Fn(&mut tcomp_core::Rbf<{ tcomp_core::HOST_CENTERS }, { tcomp_core::HOST_FEATURES }>),
) -> Vec<u8> {
    let bytes = model_blob();
    let mut m = tcomp_train::blob_io::decode(Path::new("m.tcm"), bytes).unwrap();
    f(&mut m.rbf);
    let mut buf = vec![0u8; 64 * 1024];
    let n = postcard::to_slice(&m, &mut buf).unwrap().len();
    buf.truncate(n);
    let crc = tcomp_core::blob::crc32(&buf);
    buf.extend_from_slice(&crc.to_le_bytes());
    buf
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

fn fit_args<'a>(data: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "fit",
        "--data",
        data,
        "--target",
        "gyro_dph",
        "--reference",
        "ref_dph",
        "--feature",
        "t_coil_c",
        "--sensor",
        "ifog",
        "--axis",
        "x",
        "--unit",
        "deg/h",
        "--out",
        out,
        "--quiet",
    ]
}

/// Everything under `dir`: relative path → bytes (`None` for a directory).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    fn walk(root: &Path, dir: &Path, into: &mut BTreeMap<PathBuf, Option<Vec<u8>>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().to_path_buf();
            if p.is_dir() {
                into.insert(rel, None);
                walk(root, &p, into);
            } else {
                into.insert(rel, Some(std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut m = BTreeMap::new();
    walk(dir, dir, &mut m);
    m
}

/// A board description with two IFOG channels on one coil thermometer, for `tcomp image`.
const BOARD: &str = r#"
name = "two-ifogs"
[[thermometer]]
name = "coil"
adc = 0
input = 0
type = "pt100"
[[channel]]
id = 0
name = "ifog-a"
sensor = "ifog"
axis = "x"
unit = "deg/h"
counter = 0
scale = 1e-5
inputs = { t_coil_c = "coil" }
[[channel]]
id = 1
name = "ifog-b"
sensor = "ifog"
axis = "x"
unit = "deg/h"
counter = 1
scale = 1e-5
inputs = { t_coil_c = "coil" }
"#;

/// A directory with the standard files: a good run and blob, and earlier outputs of every command.
fn standard_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("run.csv"), run_csv()).unwrap();
    std::fs::write(p.join("m.tcm"), model_blob()).unwrap();
    std::fs::write(p.join("b.toml"), BOARD).unwrap();
    std::fs::write(p.join("out.tcm"), b"an earlier blob").unwrap();
    std::fs::write(p.join("out.bin"), b"an earlier image").unwrap();
    std::fs::write(p.join("out.html"), b"<p>an earlier report</p>").unwrap();
    std::fs::create_dir(p.join("demo")).unwrap();
    std::fs::write(p.join("demo/train.csv"), b"an earlier demo run").unwrap();
    std::fs::write(p.join("demo/report.html"), b"an earlier demo report").unwrap();
    dir
}

/// Runs `args` in `dir` expecting a failure with one of `codes` and the directory untouched;
/// returns stderr. Every check names `name`.
fn fails_leaving_dir_as_it_was(name: &str, dir: &Path, args: &[String], codes: &[i32]) -> String {
    let before = snapshot(dir);
    let out = tcomp_in(dir, args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let code = out.status.code();
    assert!(
        code.is_some_and(|c| codes.contains(&c)),
        "[{name}] exit code {code:?}, expected one of {codes:?}\nstderr: {err}"
    );
    assert!(
        !err.to_lowercase().contains("stack backtrace") && !err.contains("panicked"),
        "[{name}] a user error printed a backtrace or panicked:\n{err}"
    );
    assert!(
        err.starts_with("error: "),
        "[{name}] stderr does not start with `error: `:\n{err}"
    );
    let after = snapshot(dir);
    let changed: Vec<_> = before
        .keys()
        .chain(after.keys())
        .filter(|k| before.get(*k) != after.get(*k))
        .collect();
    assert!(
        changed.is_empty(),
        "[{name}] a failing run changed, added or removed {changed:?}"
    );
    err
}

fn run_case(c: &Case) {
    let dir = standard_dir();
    for (name, bytes) in &c.files {
        let p = dir.path().join(name);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).unwrap();
        }
        std::fs::write(p, bytes).unwrap();
    }
    let err = fails_leaving_dir_as_it_was(c.name, dir.path(), &c.args, c.codes);
    for s in &c.says {
        assert!(err.contains(s), "[{}] stderr lacks `{s}`:\n{err}", c.name);
    }
    for s in &c.lacks {
        assert!(!err.contains(s), "[{}] stderr holds `{s}`:\n{err}", c.name);
    }
    assert!(
        err.len() <= c.max_stderr,
        "[{}] stderr is {} bytes, more than {}",
        c.name,
        err.len(),
        c.max_stderr
    );
}

const RAGGED: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n1,20.1\n2,20.2,1,0\n";
const BAD_CELL: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n1,abc,1,0\n2,20.2,1,0\n";
const NAN_CELL: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n1,nan,1,0\n2,20.2,1,0\n";
const BACKWARDS: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n2,20.1,1,0\n1,20.2,1,0\n";
const REPEATED: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n1,20.1,1,0\n1,20.2,1,0\n";
const HEADER_ONLY: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n";
const ONE_ROW: &str = "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n";
const SEMICOLONS: &str = "time_s;t_coil_c;gyro_dph;ref_dph\n0;20;1;0\n1;20.1;1;0\n2;20.2;1;0\n";
const DUPLICATE: &str = "time_s,t_coil_c,t_coil_c,gyro_dph,ref_dph\n0,20,21,1,0\n1,20.1,21,1,0\n";
const BAD_TOML: &str = "target = \"gyro_dph\"\nfeature = [\"t_coil_c\"\n";
const TYPO_TOML: &str = "target = \"gyro_dph\"\nfeatuer = [\"t_coil_c\"]\n";

fn long_cell() -> String {
    format!(
        "time_s,t_coil_c,gyro_dph,ref_dph\n0,20,1,0\n1,{},1,0\n2,20.2,1,0\n",
        "x".repeat(5000)
    )
}

fn truncated_gzip() -> Vec<u8> {
    use std::io::Write;
    let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(run_csv().as_bytes()).unwrap();
    let mut bytes = z.finish().unwrap();
    bytes.truncate(bytes.len() / 2);
    bytes
}

fn half_blob() -> Vec<u8> {
    let b = model_blob();
    b[..b.len() / 2].to_vec()
}

fn flipped_blob() -> Vec<u8> {
    let mut b = model_blob().to_vec();
    let mid = b.len() / 2;
    b[mid] ^= 0x40;
    b
}

/// Splits a command line on spaces; `'…'` quotes an argument holding spaces. `FIT`, `EVAL` and
/// `DIAG` at the start stand for the usual beginnings of those commands.
fn command_line(line: &str) -> Vec<String> {
    let line = line
        .replacen(
            "FIT ",
            "fit --target gyro_dph --reference ref_dph --feature t_coil_c --quiet ",
            1,
        )
        .replacen("EVAL ", "eval --model m.tcm --data run.csv ", 1)
        .replacen("DIAG ", "diagnose --model m.tcm --data run.csv ", 1);
    let mut args = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '\'' => quoted = !quoted,
            ' ' if !quoted => {
                if !cur.is_empty() {
                    args.push(std::mem::take(&mut cur));
                }
            }
            c => cur.push(c),
        }
    }
    if !cur.is_empty() {
        args.push(cur);
    }
    args
}

/// The rows that pass today.
#[rustfmt::skip]
fn catalogue() -> Vec<Case> {
    vec![
        // --out naming an input, or not a writable file name
        case("fit --out is --data", "FIT --data run.csv --out run.csv").says(&["--out run.csv", "--data run.csv", "destroy"]),
        case("fit --out is --data by another name", "FIT --data run.csv --out sub/../run.csv").file("sub/keep", "").says(&["--data run.csv"]),
        case("fit --out is --spec", "FIT --data run.csv --spec s.toml --out s.toml").file("s.toml", "average = 10\n").says(&["--spec s.toml"]),
        case("image --out is a --model", "image --board b.toml --serial 1 --model 0=m.tcm --out m.tcm").says(&["--out m.tcm", "--model m.tcm"]),
        case("report --out is a --model", "report --model m.tcm --data run.csv --out m.tcm").says(&["--model m.tcm"]),
        case("report --out is --data", "report --model m.tcm --data run.csv --out run.csv").says(&["--data run.csv"]),
        case("report --out is --verify", "report --model m.tcm --data run.csv --verify v.csv --out v.csv").file("v.csv", run_csv()).says(&["--verify v.csv"]),
        case("fit --out in a missing directory", "FIT --data run.csv --out nodir/x.tcm").says(&["--out nodir/x.tcm", "does not exist"]),
        case("fit --out is a directory", "FIT --data run.csv --out demo").says(&["--out demo", "is a directory"]),
        case("report --out is a directory", "report --model m.tcm --data run.csv --out demo").says(&["--out demo", "is a directory"]),
        case("demo --out is a file", "demo --out run.csv").says(&["--out run.csv", "not a directory"]),
        // numeric flags, range-checked at parse time
        case("diagnose --min-evidence nan", "DIAG --min-evidence nan").usage().says(&["--min-evidence", "finite"]),
        case("diagnose --min-evidence -1", "DIAG --min-evidence -1").usage().says(&["--min-evidence", "between 0 and"]),
        case("diagnose --min-improvement 150", "DIAG --min-improvement 150").usage().says(&["--min-improvement", "between 0 and 100"]),
        case("diagnose --top -3", "DIAG --top -3").usage().says(&["--top", "from 1 to"]),
        case("diagnose --bin inf", "DIAG --bin inf").usage().says(&["--bin", "finite"]),
        case("diagnose --reference-value nan", "DIAG --reference-value nan").usage().says(&["--reference-value"]),
        case("eval --bin 1e-300", "EVAL --bin 1e-300").usage().says(&["--bin", "between 0.001 and 1e7 seconds"]),
        case("eval --bin 0", "EVAL --bin 0").usage().says(&["--bin"]),
        case("eval --bin 1e30", "EVAL --bin 1e30").usage().says(&["--bin"]),
        case("eval --reference-value inf", "EVAL --reference-value inf").usage().says(&["--reference-value", "finite"]),
        case("eval --reference-value 1e300", "EVAL --reference-value 1e300").usage().says(&["--reference-value", "1e9"]),
        case("eval --gap -1", "EVAL --gap -1").usage().says(&["--gap"]),
        case("eval --from nan", "EVAL --from nan").usage().says(&["--from"]),
        case("eval --until=-1 selects no row", "EVAL --until=-1").says(&["--from/--until select 0 row"]),
        case("eval --from after --until", "EVAL --from 10 --until 5").says(&["--from 10", "--until 5"]),
        case("diagnose --from after --until", "DIAG --from 10 --until 5").says(&["--from 10", "--until 5"]),
        case("diagnose --until=-1 selects no row", "DIAG --until=-1").says(&["--from/--until select 0 row"]),
        case("report --until=-1 selects no row", "report --model m.tcm --data run.csv --until=-1 --out out.html").says(&["--from/--until select 0 row"]),
        case("compare --from nan", "compare m.tcm m.tcm --data run.csv --from nan").usage().says(&["--from", "finite"]),
        case("spec TOML with a string for a number", "FIT --data run.csv --out out.tcm --spec s.toml").file("s.toml", "average = \"long\"\n").says(&["s.toml", "line 1, column 11"]),
        case("eval of a one-row file", "eval --model m.tcm --data one.csv").file("one.csv", ONE_ROW).says(&["one.csv", "at least 2"]),
        case("fit --average 1e-300", "FIT --data run.csv --out out.tcm --average 1e-300").usage().says(&["--average", "0 (off)"]),
        case("fit --average -5 (space, not =)", "FIT --data run.csv --out out.tcm --average -5").usage().says(&["--average", "0 (off)"]).lacks(&["unexpected argument"]),
        case("fit --average nan", "FIT --data run.csv --out out.tcm --average nan").usage().says(&["--average"]),
        case("fit --reference-value nan", "fit --data run.csv --target gyro_dph --feature t_coil_c --out out.tcm --reference-value nan").usage().says(&["--reference-value"]),
        case("fit --centers -1", "FIT --data run.csv --out out.tcm --centers -1").usage().says(&["--centers", "from 0 to 64"]),
        case("fit --centers 100000", "FIT --data run.csv --out out.tcm --centers 100000").usage().says(&["--centers", "from 0 to 64"]),
        case("fit --iterations 0", "FIT --data run.csv --out out.tcm --iterations 0").usage().says(&["--iterations"]),
        case("fit --seed -1", "FIT --data run.csv --out out.tcm --seed -1").usage().says(&["--seed"]),
        case("fit --gap 0", "FIT --data run.csv --out out.tcm --gap 0").usage().says(&["--gap"]),
        case("fit --until 1e300", "FIT --data run.csv --out out.tcm --until 1e300").usage().says(&["--until"]),
        case("compare --bin 0", "compare m.tcm m.tcm --data run.csv --bin 0").usage().says(&["--bin"]),
        case("demo --step 0", "demo --out demo --step 0").usage().says(&["--step", "between 0.1 and 10"]),
        case("demo --step 1e-300", "demo --out demo --step 1e-300").usage().says(&["--step"]),
        case("demo --seed -1", "demo --out demo --seed -1").usage().says(&["--seed"]),
        // malformed files
        case("ragged row", "FIT --data bad.csv --out out.tcm").file("bad.csv", RAGGED).says(&["bad.csv:3:", "2 fields, but the header has 4"]),
        case("non-numeric cell", "FIT --data bad.csv --out out.tcm").file("bad.csv", BAD_CELL).says(&["bad.csv:3:2: column `t_coil_c`", "not a number: `abc`"]),
        case("NaN cell, --missing refuse", "FIT --data bad.csv --out out.tcm --missing refuse").file("bad.csv", NAN_CELL).says(&["bad.csv:3:2: column `t_coil_c`", "missing value (`nan`)"]),
        case("time goes backwards, --repeated-time refuse", "FIT --data bad.csv --out out.tcm --repeated-time refuse").file("bad.csv", BACKWARDS).says(&["bad.csv:4:1: column `time_s`", "strictly increase"]),
        case("time repeats, --repeated-time refuse", "FIT --data bad.csv --out out.tcm --repeated-time refuse").file("bad.csv", REPEATED).says(&["bad.csv:4:1", "equal to"]),
        case("header only", "FIT --data bad.csv --out out.tcm").file("bad.csv", HEADER_ONLY).says(&["bad.csv", "no data rows"]),
        case("empty file", "FIT --data bad.csv --out out.tcm").file("bad.csv", "").says(&["bad.csv", "no header row"]),
        case("missing data file", "FIT --data missing.csv --out out.tcm").says(&["missing.csv", "No such file"]).lacks(&["(os error 2): No such file"]),
        case("eval on a non-numeric cell", "eval --model m.tcm --data bad.csv").file("bad.csv", BAD_CELL).says(&["bad.csv:3:2: column `t_coil_c`"]),
        case("diagnose on a ragged row", "diagnose --model m.tcm --data bad.csv").file("bad.csv", RAGGED).says(&["bad.csv:3:"]),
        // columns, expressions, names
        case("misspelled target", "fit --data run.csv --target gyro_dps --feature t_coil_c --out out.tcm").says(&["run.csv:1: no column `gyro_dps`", "did you mean `gyro_dph`"]),
        case("misspelled feature column", "fit --data run.csv --target gyro_dph --feature t_coil --out out.tcm").says(&["no column `t_coil`", "did you mean `t_coil_c`"]),
        case("unknown reference column", "fit --data run.csv --target gyro_dph --reference nope --feature t_coil_c --out out.tcm").says(&["run.csv:1: no column `nope`; columns are: time_s, t_coil_c"]),
        case("eval --temperature unknown", "EVAL --temperature nope").says(&["no column `nope`"]),
        case("unbalanced parenthesis", "FIT --data run.csv --out out.tcm --feature 'rate(t_coil_c'").says(&["in `rate(t_coil_c`", "column 14", "expected ')'"]),
        case("unknown function", "FIT --data run.csv --out out.tcm --feature 'foo(t_coil_c)'").says(&["in `foo(t_coil_c)`", "unknown function"]),
        case("signal without =", "FIT --data run.csv --out out.tcm --signal 'T t_coil_c'").says(&["in `T t_coil_c`", "NAME=EXPR"]),
        case("unknown method", "FIT --data run.csv --out out.tcm --method magic").says(&["unknown method `magic`", "bayes"]),
        case("unknown sensor", "FIT --data run.csv --out out.tcm --sensor laser").says(&["unknown sensor `laser`", "ifog"]),
        case("unknown center selection", "FIT --data run.csv --out out.tcm --method mse --select foo").says(&["unknown center selection `foo`"]),
        case("no target", "fit --data run.csv --feature t_coil_c --out out.tcm").says(&["--target"]),
        case("no feature", "fit --data run.csv --target gyro_dph --reference ref_dph --out out.tcm").says(&["--feature"]),
        case("constant feature", "FIT --data run.csv --out out.tcm --feature ref_dph").says(&["feature `ref_dph` is constant"]),
        case("collinear features", "FIT --data run.csv --out out.tcm --feature 2*t_coil_c").says(&["`t_coil_c` and `2*t_coil_c` are collinear"]),
        // spec files
        case("spec TOML does not parse", "FIT --data run.csv --out out.tcm --spec s.toml").file("s.toml", BAD_TOML).says(&["s.toml", "line 2, column 22"]),
        case("spec TOML unknown key", "FIT --data run.csv --out out.tcm --spec s.toml").file("s.toml", TYPO_TOML).says(&["s.toml", "unknown field `featuer`"]),
        case("spec file missing", "FIT --data run.csv --out out.tcm --spec nospec.toml").says(&["nospec.toml"]),
        // blobs
        case("blob with a bad magic", "eval --model junk.tcm --data run.csv").file("junk.tcm", "not a blob at all").says(&["junk.tcm: corrupt model blob", "bad magic"]),
        case("truncated blob", "inspect cut.tcm").file("cut.tcm", half_blob()).says(&["cut.tcm: corrupt model blob"]),
        case("blob with a flipped bit", "image --board b.toml --serial 1 --model 0=bad.tcm --out out.bin").file("bad.tcm", flipped_blob()).says(&["bad.tcm: corrupt model blob", "checksum"]),
        case("a CSV given as a blob", "inspect run.csv").says(&["run.csv: corrupt model blob"]),
        case("missing blob", "inspect missing.tcm").says(&["missing.tcm", "No such file"]),
        case("compare with a bad second blob", "compare m.tcm junk.tcm --data run.csv").file("junk.tcm", "junk").says(&["junk.tcm"]),
        case("report with a bad blob", "report --model junk.tcm --data run.csv --out out.html").file("junk.tcm", "junk").says(&["junk.tcm"]),
        case("diagnose --verify missing", "DIAG --verify nope.csv").says(&["nope.csv"]),
        // image arguments
        case("image channel id not a number", "image --board b.toml --serial 1 --model x=m.tcm --out out.bin").says(&["--model x=m.tcm", "channel id"]),
        case("image --model without ID=", "image --board b.toml --serial 1 --model m.tcm --out out.bin").says(&["expected ID=FILE"]),
        case("image channel not in the board", "image --board b.toml --serial 1 --model 99=m.tcm --out out.bin").says(&["--model 99=m.tcm", "channel 99", "b.toml"]),
        case("image board missing", "image --board nope.toml --serial 1 --model 0=m.tcm --out out.bin").says(&["nope.toml"]),
        case("image board not TOML", "image --board run.csv --serial 1 --model 0=m.tcm --out out.bin").says(&["run.csv", "line"]),
        case("image board input on no thermometer", "image --board bad.toml --serial 1 --model 0=m.tcm --out out.bin").file("bad.toml", BOARD.replace("t_coil_c = \"coil\" }\n[[channel]]", "t_coil_c = \"cool\" }\n[[channel]]")).says(&["bad.toml", "channel 0 (ifog-a)", "t_coil_c", "cool"]),
        case("image serial not a number", "image --board b.toml --serial x1 --model 0=m.tcm --out out.bin").usage().says(&["--serial", "x1"]),
        case("image channel twice", "image --board b.toml --serial 1 --model 0=m.tcm --model 0=m.tcm --out out.bin").says(&["channel 0 is given twice"]),
        // signatures (issue 26): keys that are missing, of the wrong kind or cut short; keygen never overwrites
        case("image --sign a missing key", "image --board b.toml --serial 1 --model 0=m.tcm --sign nokey.key --out out.bin").says(&["--sign nokey.key", "cannot read"]),
        case("image --sign a public key", "image --board b.toml --serial 1 --model 0=m.tcm --sign k.pub --out out.bin").file("k.pub", format!("tcomp-ed25519-public {}\n", "ab".repeat(32))).says(&["--sign k.pub", "public key, not a secret key"]),
        case("image --sign a key cut short", "image --board b.toml --serial 1 --model 0=m.tcm --sign short.key --out out.bin").file("short.key", "tcomp-ed25519-secret 00ff\n").says(&["--sign short.key", "64 hex digits"]),
        case("image --sign a key with a non-hex digit", "image --board b.toml --serial 1 --model 0=m.tcm --sign g.key --out out.bin").file("g.key", format!("tcomp-ed25519-secret {}g\n", "0".repeat(63))).says(&["--sign g.key", "not hex"]),
        case("image --sign raw bytes", "image --board b.toml --serial 1 --model 0=m.tcm --sign raw.key --out out.bin").file("raw.key", vec![7u8; 32]).says(&["--sign raw.key"]),
        case("inspect --key a secret key", "inspect m.tcm --key s.key").file("s.key", format!("tcomp-ed25519-secret {}\n", "01".repeat(32))).says(&["--key s.key", "secret key, not a public key"]),
        case("inspect --key not a key file", "inspect m.tcm --key junk.pub").file("junk.pub", "hello\n").says(&["--key junk.pub", "tcomp keygen"]),
        case("inspect --key missing", "inspect m.tcm --key none.pub").says(&["--key none.pub"]),
        case("keygen over an existing key", "keygen --out k").file("k.key", format!("tcomp-ed25519-secret {}\n", "01".repeat(32))).says(&["k.key exists", "never overwritten"]),
        case("keygen in a missing directory", "keygen --out nodir/k").says(&["nodir", "does not exist"]),
        case("flash without a rate", "flash --port /nonexistent/tty out.bin").usage().says(&["--board"]),
        // usage
        case("unknown flag", "FIT --data run.csv --out out.tcm --bogus").usage().says(&["--bogus"]),
        case("missing required --out", "fit --data run.csv --target gyro_dph").usage().says(&["--out"]),
        case("unknown command", "fitt").usage().says(&["fitt"]),
        case("unknown preset", "simulate --preset nope --out out.tcm").says(&["unknown preset", "nope"]),
        // autopilot logs and units (issue 23)
        case("truncated ULog", "fit --data cut.ulg --target sensor_baro.pressure --feature sensor_baro.temperature --out out.tcm").file("cut.ulg", truncated_ulog()).says(&["cut.ulg", "byte", "truncated"]),
        case("truncated ULog: autopilot-params", "autopilot-params --data cut.ulg --out out.params").file("cut.ulg", truncated_ulog()).says(&["cut.ulg", "byte", "truncated"]),
        case("DataFlash with a missing FMT", "fit --data nofmt.bin --target IMU.GyrX --feature IMU.T --out out.tcm").file("nofmt.bin", dataflash_missing_fmt()).says(&["nofmt.bin: byte 89", "type 129", "no FMT"]),
        case("not a ULog though named .ulg", "fit --data fake.ulg --target a.b --feature a.c --out out.tcm").file("fake.ulg", "time_s,x\n0,1\n").says(&["fake.ulg: byte 0", "not a ULog"]),
        case("a unit that does not parse", "FIT --data run.csv --out out.tcm --unit furlong/fortnight").says(&["--unit", "`furlong/fortnight`", "character 1", "`furlong` is not a unit"]),
        case("a unit with a dangling exponent", "FIT --data run.csv --out out.tcm --unit m/s^").says(&["--unit", "character 5", "no exponent"]),
        case("autopilot-params from a CSV", "autopilot-params --data run.csv --out out.params").says(&["run.csv", "not an autopilot log"]),
    ]
}

/// The real PX4 ULog of `data/autopilot/`, cut in the middle of its data section.
fn truncated_ulog() -> Vec<u8> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/autopilot/px4_sample_small.ulg");
    let mut b = std::fs::read(p).unwrap();
    b.truncate(b.len() / 2 + 7);
    b
}

/// A DataFlash log whose IMU records (type 129) come with no FMT record defining them.
fn dataflash_missing_fmt() -> Vec<u8> {
    let mut fmt = vec![0xA3, 0x95, 0x80, 0x80, 89];
    fmt.extend_from_slice(b"FMT\0");
    let mut f = [0u8; 16];
    f[..5].copy_from_slice(b"BBnNZ");
    fmt.extend_from_slice(&f);
    let mut l = [0u8; 64];
    l[..30].copy_from_slice(b"Type,Length,Name,Format,Labels");
    fmt.extend_from_slice(&l);
    let mut imu = vec![0xA3, 0x95, 129];
    imu.extend_from_slice(&1_000_000u64.to_le_bytes());
    imu.extend_from_slice(&0.5f32.to_le_bytes());
    imu.extend_from_slice(&35.0f32.to_le_bytes());
    [fmt, imu].concat()
}

/// Rows fixed in the core and the trainer: the CSV reader, option ranges, the parser, model plausibility.
#[rustfmt::skip]
fn hardened() -> Vec<Case> {
    let huge = doctored(|r| {
        let nf = usize::from(r.n_features);
        for c in r.centers.iter_mut() {
            c.q.0.iter_mut().take(nf).for_each(|q| *q = 3.2e38);
            c.g = 1e-7;
        }
    });
    let heavy = doctored(|r| r.centers.iter_mut().for_each(|c| c.w = 3e38));
    vec![
        case("duplicate header names", "FIT --data dup.csv --out out.tcm").file("dup.csv", DUPLICATE).says(&["dup.csv:1", "`t_coil_c`", "duplicate"]),
        case("semicolon separator hint", "FIT --data semi.csv --out out.tcm").file("semi.csv", SEMICOLONS).says(&["semi.csv:1", "`;`"]),
        case("a very long bad cell is truncated", "FIT --data long.csv --out out.tcm").file("long.csv", long_cell()).says(&["long.csv:3:2"]).at_most(1000),
        case("truncated gzip", "FIT --data cut.csv.gz --out out.tcm").file("cut.csv.gz", truncated_gzip()).says(&["cut.csv.gz"]).lacks(&[":0:"]),
        case("one-row file", "FIT --data one.csv --out out.tcm").file("one.csv", ONE_ROW).says(&["one.csv"]).lacks(&["constant"]),
        case("fit --from selecting nothing", "FIT --data run.csv --out out.tcm --from 1000").says(&["--from"]),
        case("T/0 refused at parse time", "FIT --data run.csv --out out.tcm --feature t_coil_c/0").says(&["`t_coil_c/0`"]).lacks(&["run.csv:2"]),
        case("--centers 0 --method mse", "FIT --data run.csv --out out.tcm --method mse --centers 0").usage_or_failure().says(&["--centers"]),
        case("simulate --rate-hz 0", "simulate --preset ifog-shupe --rate-hz 0 --out sim").usage_or_failure().says(&["--rate-hz"]),
        case("blob with q = 3.2e38, g = 1e-7: eval", "eval --model huge.tcm --data run.csv").file("huge.tcm", huge.clone()).says(&["huge.tcm"]),
        case("blob with q = 3.2e38, g = 1e-7: image", "image --board b.toml --serial 1 --model 0=huge.tcm --out out.bin").file("huge.tcm", huge.clone()).says(&["huge.tcm"]),
        case("blob with q = 3.2e38, g = 1e-7: inspect", "inspect huge.tcm").file("huge.tcm", huge).says(&["huge.tcm"]),
        case("blob with every weight 3e38: eval", "eval --model heavy.tcm --data run.csv").file("heavy.tcm", heavy.clone()).says(&["heavy.tcm"]),
        case("blob with every weight 3e38: image", "image --board b.toml --serial 1 --model 0=heavy.tcm --out out.bin").file("heavy.tcm", heavy.clone()).says(&["heavy.tcm"]),
        case("blob with every weight 3e38: inspect", "inspect heavy.tcm").file("heavy.tcm", heavy).says(&["heavy.tcm"]),
    ]
}

#[test]
fn every_catalogued_bad_input_fails_cleanly_and_names_the_place() {
    let mut rows = catalogue();
    rows.extend(hardened());
    assert!(rows.len() >= 60, "{} rows", rows.len());
    for c in &rows {
        run_case(c);
    }
}

/// Runs every failing run of `runs` in one standard directory holding `extra` files too: after each,
/// the directory is as it was (the earlier outputs byte for byte, no temporary file). Returns it.
fn outputs_survive(extra: &[(&str, Vec<u8>)], runs: &[(&str, &[&str])]) -> tempfile::TempDir {
    let dir = standard_dir();
    for (name, bytes) in extra {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    for (name, args) in runs {
        fails_leaving_dir_as_it_was(name, dir.path(), &strings(args), &[1, 2]);
    }
    dir
}

/// A successful run in `dir` replaces `outputs` (their bytes change) and changes nothing else: no
/// temporary or staging file is left behind.
fn succeeds_replacing_only(dir: &Path, args: &[&str], outputs: &[&str]) {
    let before = snapshot(dir);
    let out = tcomp_in(dir, &strings(args));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let after = snapshot(dir);
    let changed: Vec<PathBuf> = before
        .keys()
        .chain(after.keys())
        .filter(|k| before.get(*k) != after.get(*k))
        .cloned()
        .collect();
    for o in outputs {
        assert!(changed.contains(&PathBuf::from(o)), "{o} not replaced");
    }
    let others: Vec<_> = changed
        .iter()
        .filter(|c| !outputs.iter().any(|o| Path::new(o) == c.as_path()))
        .collect();
    assert!(others.is_empty(), "also changed: {others:?}");
}

#[test]
fn fit_output_survives_every_failing_run() {
    let dir = outputs_survive(
        &[("bad.csv", BAD_CELL.into()), ("s.toml", BAD_TOML.into())],
        &[
            (
                "bad flag",
                &[
                    "fit",
                    "--data",
                    "run.csv",
                    "--target",
                    "gyro_dph",
                    "--feature",
                    "t_coil_c",
                    "--out",
                    "out.tcm",
                    "--average",
                    "-5",
                ],
            ),
            (
                "missing data",
                &[
                    "fit",
                    "--data",
                    "nope.csv",
                    "--target",
                    "gyro_dph",
                    "--feature",
                    "t_coil_c",
                    "--out",
                    "out.tcm",
                ],
            ),
            (
                "bad cell",
                &[
                    "fit",
                    "--data",
                    "bad.csv",
                    "--target",
                    "gyro_dph",
                    "--feature",
                    "t_coil_c",
                    "--out",
                    "out.tcm",
                ],
            ),
            (
                "bad spec",
                &[
                    "fit", "--data", "run.csv", "--spec", "s.toml", "--out", "out.tcm",
                ],
            ),
            (
                "unknown column",
                &[
                    "fit",
                    "--data",
                    "run.csv",
                    "--target",
                    "gyro",
                    "--feature",
                    "t_coil_c",
                    "--out",
                    "out.tcm",
                ],
            ),
            (
                "fails after loading",
                &[
                    "fit",
                    "--data",
                    "run.csv",
                    "--target",
                    "gyro_dph",
                    "--feature",
                    "t_coil_c",
                    "--feature",
                    "2*t_coil_c",
                    "--out",
                    "out.tcm",
                ],
            ),
            (
                "--out is --data",
                &[
                    "fit",
                    "--data",
                    "run.csv",
                    "--target",
                    "gyro_dph",
                    "--feature",
                    "t_coil_c",
                    "--out",
                    "run.csv",
                ],
            ),
        ],
    );
    let args = fit_args("run.csv", "out.tcm");
    succeeds_replacing_only(dir.path(), &args, &["out.tcm"]);
    assert_eq!(
        std::fs::read(dir.path().join("out.tcm")).unwrap(),
        model_blob()
    );
}

#[test]
fn image_output_survives_every_failing_run() {
    let dir = outputs_survive(
        &[("bad.tcm", flipped_blob())],
        &[
            (
                "corrupt blob",
                &[
                    "image",
                    "--board",
                    "b.toml",
                    "--serial",
                    "1",
                    "--model",
                    "0=m.tcm",
                    "--model",
                    "1=bad.tcm",
                    "--out",
                    "out.bin",
                ],
            ),
            (
                "missing blob",
                &[
                    "image",
                    "--board",
                    "b.toml",
                    "--serial",
                    "1",
                    "--model",
                    "0=nope.tcm",
                    "--out",
                    "out.bin",
                ],
            ),
            (
                "channel twice",
                &[
                    "image", "--board", "b.toml", "--serial", "1", "--model", "0=m.tcm", "--model",
                    "0=m.tcm", "--out", "out.bin",
                ],
            ),
            (
                "bad channel id",
                &[
                    "image", "--board", "b.toml", "--serial", "1", "--model", "-1=m.tcm", "--out",
                    "out.bin",
                ],
            ),
            (
                "--out is a --model",
                &[
                    "image", "--board", "b.toml", "--serial", "1", "--model", "0=m.tcm", "--out",
                    "m.tcm",
                ],
            ),
        ],
    );
    succeeds_replacing_only(
        dir.path(),
        &[
            "image", "--board", "b.toml", "--serial", "1", "--model", "0=m.tcm", "--out", "out.bin",
        ],
        &["out.bin"],
    );
}

#[test]
fn report_output_survives_every_failing_run() {
    let dir = outputs_survive(
        &[("junk.tcm", b"junk".to_vec())],
        &[
            (
                "bad blob",
                &[
                    "report", "--model", "junk.tcm", "--data", "run.csv", "--out", "out.html",
                ],
            ),
            (
                "second blob bad",
                &[
                    "report", "--model", "m.tcm", "--model", "junk.tcm", "--data", "run.csv",
                    "--out", "out.html",
                ],
            ),
            (
                "missing data",
                &[
                    "report", "--model", "m.tcm", "--data", "nope.csv", "--out", "out.html",
                ],
            ),
            (
                "missing verify",
                &[
                    "report", "--model", "m.tcm", "--data", "run.csv", "--verify", "nope.csv",
                    "--out", "out.html",
                ],
            ),
            (
                "--out is --data",
                &[
                    "report", "--model", "m.tcm", "--data", "run.csv", "--out", "run.csv",
                ],
            ),
        ],
    );
    succeeds_replacing_only(
        dir.path(),
        &[
            "report",
            "--model",
            "m.tcm",
            "--data",
            "run.csv",
            "--out",
            "out.html",
            "--no-diagnosis",
        ],
        &["out.html"],
    );
}

#[test]
fn demo_output_survives_every_failing_run() {
    let dir = outputs_survive(
        &[],
        &[
            ("bad step", &["demo", "--out", "demo", "--step", "0"]),
            ("bad seed", &["demo", "--out", "demo", "--seed", "-3"]),
            ("--out is a file", &["demo", "--out", "run.csv"]),
        ],
    );
    let out = tcomp_in(
        dir.path(),
        &strings(&["demo", "--out", "demo", "--step", "10"]),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Written to demo:"), "{text}");
    let mut names: Vec<String> = std::fs::read_dir(dir.path().join("demo"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "after.tcm",
            "before.tcm",
            "report.html",
            "train.csv",
            "verify.csv"
        ],
        "no staging directory left"
    );
    let train = std::fs::read_to_string(dir.path().join("demo/train.csv")).unwrap();
    assert!(train.starts_with("time_s,"), "train.csv replaced");
}

/// The analysing commands write nothing: a failing run leaves every file as it was.
#[test]
fn eval_inspect_diagnose_compare_leave_files_alone_when_failing() {
    outputs_survive(
        &[("junk.tcm", b"junk".to_vec()), ("bad.csv", BAD_CELL.into())],
        &[
            (
                "eval bad blob",
                &["eval", "--model", "junk.tcm", "--data", "run.csv"],
            ),
            (
                "eval bad cell",
                &["eval", "--model", "m.tcm", "--data", "bad.csv"],
            ),
            (
                "eval empty selection",
                &[
                    "eval", "--model", "m.tcm", "--data", "run.csv", "--from", "5000",
                ],
            ),
            ("inspect bad blob", &["inspect", "junk.tcm"]),
            ("inspect csv", &["inspect", "run.csv"]),
            (
                "diagnose bad flag",
                &[
                    "diagnose",
                    "--model",
                    "m.tcm",
                    "--data",
                    "run.csv",
                    "--min-evidence",
                    "nan",
                ],
            ),
            (
                "diagnose bad cell",
                &["diagnose", "--model", "m.tcm", "--data", "bad.csv"],
            ),
            (
                "compare bad blob",
                &["compare", "m.tcm", "junk.tcm", "--data", "run.csv"],
            ),
            (
                "compare bad flag",
                &[
                    "compare", "m.tcm", "m.tcm", "--data", "run.csv", "--bin", "nan",
                ],
            ),
        ],
    );
}

/// Characters that must never reach a terminal raw.
fn raw_control(s: &str) -> Option<char> {
    s.chars().find(|&c| {
        (c.is_control() && c != '\n')
            || matches!(c, '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    })
}

/// A blob whose strings hold escape sequences (in the axis, the unit and a column name from the
/// CSV header): `inspect` prints them escaped, and `--json` too while keeping the same strings;
/// `eval` and `diagnose`, which print some of them, escape them as well. `fit --unit` now refuses
/// a unit that does not parse, so the unit's escapes are put into the blob afterwards, as a blob
/// from another tool or an older tcomp would carry them.
#[test]
fn inspect_escapes_the_strings_of_a_blob() {
    let dir = tempfile::tempdir().unwrap();
    let evil_col = "gyro\u{1b}[2J";
    let csv = run_csv().replacen("gyro_dph", evil_col, 1);
    std::fs::write(dir.path().join("run.csv"), csv).unwrap();
    let axis = "x\u{1b}]0;owned\u{7}";
    let unit = "°/h\u{202e}\u{9b}31m";
    let args = strings(&[
        "fit",
        "--data",
        "run.csv",
        "--target",
        evil_col,
        "--reference",
        "ref_dph",
        "--feature",
        "t_coil_c",
        "--axis",
        axis,
        "--unit",
        "°/h",
        "--out",
        "m.tcm",
        "--quiet",
    ]);
    let out = tcomp_in(dir.path(), &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let path = dir.path().join("m.tcm");
    let bytes = std::fs::read(&path).unwrap();
    let mut m = tcomp_train::blob_io::decode(Path::new("m.tcm"), &bytes).unwrap();
    m.meta.unit = unit;
    let mut buf = vec![0u8; 64 * 1024];
    let n = postcard::to_slice(&m, &mut buf).unwrap().len();
    buf.truncate(n);
    let crc = tcomp_core::blob::crc32(&buf);
    buf.extend_from_slice(&crc.to_le_bytes());
    drop(m);
    std::fs::write(&path, buf).unwrap();

    let out = tcomp_in(dir.path(), &strings(&["inspect", "m.tcm"]));
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(raw_control(&text), None, "{text:?}");
    for shown in [
        "gyro\\u{1b}[2J",
        "x\\u{1b}]0;owned\\u{7}",
        "°/h\\u{202e}\\u{9b}31m",
    ] {
        assert!(text.contains(shown), "{shown} not in {text}");
    }

    let out = tcomp_in(dir.path(), &strings(&["inspect", "m.tcm", "--json"]));
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(raw_control(&text.replace('\n', "")), None, "{text:?}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["axis"], axis);
    assert_eq!(v["unit"], unit);
    assert_eq!(v["columns"]["target"], evil_col);

    // eval prints the unit, diagnose the target, unit and features: escaped too
    for args in [
        &["eval", "--model", "m.tcm", "--data", "run.csv"][..],
        &["diagnose", "--model", "m.tcm", "--data", "run.csv"],
        &[
            "diagnose", "--model", "m.tcm", "--data", "run.csv", "--json",
        ],
    ] {
        let out = tcomp_in(dir.path(), &strings(args));
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        assert_eq!(
            raw_control(&text.replace('\n', "")),
            None,
            "{args:?}: {text:?}"
        );
        assert!(
            text.contains("\\u{202e}") || text.contains("\\u202e"),
            "{args:?}: {text}"
        );
    }
}

/// A reader that stops reading (`tcomp diagnose … | head`) is not a crash: no panic, no backtrace,
/// exit 0. The pipe's read end is closed before the command has loaded its data, so its first
/// write meets a closed pipe.
#[test]
fn a_closed_pipe_on_stdout_is_not_a_crash() {
    let dir = standard_dir();
    let mut child = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["diagnose", "--model", "m.tcm", "--data", "run.csv"])
        .current_dir(dir.path())
        .env("RUST_BACKTRACE", "1")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("panicked") && !err.to_lowercase().contains("backtrace"),
        "{err}"
    );
    assert_eq!(out.status.code(), Some(0), "{err}");
}
