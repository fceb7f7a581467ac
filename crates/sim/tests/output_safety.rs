//! A failed simulation leaves an existing output directory as it was: options and scenario are
//! checked before any file is created, and files are renamed into place only when all are complete.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_sim::progress::Progress;
use tcomp_sim::{Preset, Profile, Segment, presets, write_preset, write_preset_with_progress};

const SENTINEL: &str = "time_s,x\n0,precious\n";

fn seeded_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in ["train.csv", "verify.csv", "truth.json"] {
        std::fs::write(dir.path().join(f), SENTINEL).unwrap();
    }
    dir
}

fn untouched(dir: &tempfile::TempDir) {
    for f in ["train.csv", "verify.csv", "truth.json"] {
        let text = std::fs::read_to_string(dir.path().join(f)).unwrap();
        assert_eq!(text, SENTINEL, "{f} was changed");
    }
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "temporaries left behind: {names:?}");
}

fn short(p: Preset) -> Preset {
    p.map(|mut s| {
        s.profile = Profile::new(20.0, vec![Segment::hold_h(0.2)]);
        s
    })
}

#[test]
fn bad_rates_and_steps_leave_an_existing_run_untouched() {
    let dir = seeded_dir();
    let base = short(presets::preset("qma").unwrap());
    for (rate, step) in [
        (0.0, 1.0),
        (-1.0, 1.0),
        (f64::NAN, 1.0),
        (f64::INFINITY, 1.0),
        (1e9, 1.0),
        (1.0, 0.0),
        (1.0, -1.0),
        (1.0, 1e6),
        (1.0, f64::NAN),
    ] {
        let p = base.clone().with_rate(rate, step);
        let e = write_preset(&p, dir.path(), false).unwrap_err().to_string();
        assert!(e.contains("rate_hz") || e.contains("step_s"), "{e}");
        untouched(&dir);
    }
}

#[test]
fn a_bad_scenario_and_a_bad_verification_run_leave_it_untouched() {
    let dir = seeded_dir();
    // Only the verification run is bad: the training run must not be written either.
    let mut p = short(presets::preset("ifog").unwrap());
    p.verify.profile = Profile::new(20.0, vec![Segment::hold_h(-1.0)]);
    assert!(write_preset(&p, dir.path(), false).is_err());
    untouched(&dir);
    // Too many internal samples for a run (a mistyped duration): refused before any work.
    let mut p = short(presets::preset("ifog").unwrap()).with_rate(1000.0, 1.0);
    p.train.profile = Profile::new(20.0, vec![Segment::hold_h(1e4)]);
    let e = write_preset(&p, dir.path(), false).unwrap_err().to_string();
    assert!(e.contains("internal samples"), "{e}");
    untouched(&dir);
}

#[test]
fn an_output_path_that_is_a_file_is_refused_unharmed() {
    // The output "directory" is a file: refused after validation, the file intact.
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("out");
    std::fs::write(&blocker, "not a directory").unwrap();
    let p = short(presets::preset("qma").unwrap());
    assert!(write_preset(&p, &blocker, false).is_err());
    assert_eq!(
        std::fs::read_to_string(&blocker).unwrap(),
        "not a directory"
    );
}

#[derive(Default)]
struct Recorder {
    tasks: Vec<(String, u64)>,
    last: u64,
    finished: bool,
}

impl Progress for Recorder {
    fn start(&mut self, what: &str, total: u64) {
        self.tasks.push((what.to_string(), total));
    }
    fn set(&mut self, done: u64) {
        self.last = done;
    }
    fn finish(&mut self) {
        self.finished = true;
    }
}

#[test]
fn a_good_run_replaces_the_files_and_reports_its_rows() {
    let dir = seeded_dir();
    let p = short(presets::preset("qma").unwrap());
    let mut rec = Recorder::default();
    let t = write_preset_with_progress(&p, dir.path(), false, &mut rec).unwrap();
    assert_eq!(rec.tasks.len(), 2);
    assert_eq!(rec.tasks[0].1, t.train.rows);
    assert_eq!(rec.last, t.verify.rows);
    assert!(rec.finished);
    let text = std::fs::read_to_string(dir.path().join("train.csv")).unwrap();
    assert_eq!(text.lines().count() as u64, t.train.rows + 1);
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
}

#[test]
fn gzip_output_is_gzip_after_staging() {
    let dir = tempfile::tempdir().unwrap();
    let p = short(presets::preset("qma").unwrap());
    write_preset(&p, dir.path(), true).unwrap();
    for f in ["train.csv.gz", "verify.csv.gz"] {
        let bytes = std::fs::read(dir.path().join(f)).unwrap();
        assert_eq!(bytes.get(..2), Some(&[0x1f, 0x8b][..]), "{f} is not gzip");
    }
}
