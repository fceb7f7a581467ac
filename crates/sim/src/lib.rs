//! Simulated temperature-chamber runs of inertial sensors with known physics and named effects.
//!
//! Why: fitting, diagnosis and the demo need data whose truth is known. A [`Scenario`] describes a
//! sensor (RLG, QMA, IFOG), a chamber profile of holds and ramps, bias effects with coefficients,
//! noise, rates and a seed; the simulator streams a measurement CSV (the design notes' convention)
//! and returns a [`Truth`]: the effects as exact expressions in the core's feature language, and
//! the noise floor actually drawn.
//!
//! ```no_run
//! # fn main() -> tcomp_sim::Result<()> {
//! let p = tcomp_sim::presets::preset("ifog-shupe")?.with_seed(7);
//! let truth = tcomp_sim::write_preset(&p, std::path::Path::new("out"), false)?;
//! println!("noise floor (100 s bins): {}", truth.verify.noise.std_100s);
//! # Ok(()) }
//! ```
//!
//! Modules: [`profile`] (chamber profiles), [`thermal`] (lags, self-heating), [`effects`] (named
//! bias effects, one module each), [`sensor`] (what the simulator adds to the core's sensor kinds),
//! [`noise`] (white, Gauss–Markov, pulses, statistics), [`scenario`] (the data and its validation),
//! [`scenario_file`] (TOML), [`dropout`] (rows a logger lost), [`writer`] (streaming CSV), [`progress`] (reporting long runs),
//! [`truth`] (JSON truth, and [`truth::evaluate`], which evaluates its expressions over a file with
//! the core's own compiler and evaluator in f64), [`presets`].

pub mod dropout;
pub mod effects;
mod engine;
pub mod error;
pub mod noise;
pub mod presets;
pub mod profile;
pub mod progress;
pub mod scenario;
pub mod scenario_file;
pub mod sensor;
pub mod thermal;
pub mod truth;
pub mod writer;

use std::collections::BTreeMap;
use std::path::Path;

pub use effects::{Effect, EffectKind, EffectTruth};
pub use error::{Error, Result};
pub use noise::NoiseSpec;
pub use presets::{Preset, PresetInfo};
pub use profile::{Profile, RandomProfile, Segment};
pub use scenario::{Scenario, SensorKind, SupplySpec};
pub use sensor::SensorExt;
pub use thermal::ThermometerSpec;
pub use truth::{Truth, TruthFile};
pub use writer::{CsvWriter, RowSink, Table};

/// Runs `scenario` into any [`RowSink`] (streaming; nothing is kept).
pub fn simulate_into<S: RowSink>(scenario: &Scenario, sink: &mut S) -> Result<Truth> {
    engine::run(scenario, sink)
}

/// Runs `scenario` in memory (for tests and small runs).
pub fn simulate(scenario: &Scenario) -> Result<(Table, Truth)> {
    let mut table = Table::default();
    let truth = engine::run(scenario, &mut table)?;
    Ok((table, truth))
}

/// Streams `scenario` as CSV into `writer`.
pub fn simulate_to_writer<W: std::io::Write>(scenario: &Scenario, writer: W) -> Result<Truth> {
    let mut w = CsvWriter::new(writer);
    let truth = engine::run(scenario, &mut w)?;
    w.into_inner()?;
    Ok(truth)
}

/// Streams `scenario` to a CSV file, gzip-compressed when `path` ends with `.gz`. The scenario is
/// validated before the file is created, so a bad scenario leaves an existing file untouched (the
/// file is written in place, though: use [`write_preset`] for all-or-nothing output).
pub fn simulate_to_path(scenario: &Scenario, path: &Path) -> Result<Truth> {
    scenario.validate()?;
    let mut sink = writer::FileSink::create(path)?;
    let truth = engine::run(scenario, &mut sink)?;
    sink.close(path)?;
    Ok(truth)
}

/// Writes a preset's `train.csv`, `verify.csv` (`.csv.gz` with `gzip`) and `truth.json` into `dir`
/// (created if missing); returns the truth file's contents.
pub fn write_preset(preset: &Preset, dir: &Path, gzip: bool) -> Result<TruthFile> {
    write_preset_with_progress(preset, dir, gzip, &mut progress::Silent)
}

/// [`write_preset`], reporting the rows written to `progress` (one task per run).
///
/// Nothing in `dir` is touched unless everything succeeds: both scenarios are validated before
/// any file is created, every file is written to a temporary in `dir` and the three are renamed
/// into place only once all are complete (a failure removes the temporaries). An existing run in
/// `dir` therefore survives a bad option, a bad scenario or a full disk.
pub fn write_preset_with_progress(
    preset: &Preset,
    dir: &Path,
    gzip: bool,
    progress: &mut dyn progress::Progress,
) -> Result<TruthFile> {
    preset.train.validate()?;
    preset.verify.validate()?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let ext = if gzip { "csv.gz" } else { "csv" };
    let (train_name, verify_name) = (format!("train.{ext}"), format!("verify.{ext}"));
    let mut staged = Staged::new(dir);
    let mut run = |sc: &Scenario, name: &str, label: &str| -> Result<Truth> {
        let tmp = staged.add(name);
        progress.start(label, sc.rows());
        let mut sink = progress::Counting::new(writer::FileSink::create(&tmp)?, &mut *progress);
        let truth = engine::run(sc, &mut sink)?;
        sink.into_inner().close(&tmp)?;
        Ok(truth)
    };
    let train = run(&preset.train, &train_name, "simulating the training run")?;
    let verify = run(
        &preset.verify,
        &verify_name,
        "simulating the verification run",
    )?;
    progress.finish();
    let file = TruthFile {
        name: preset.name.clone(),
        description: preset.description.clone(),
        sensor: train.sensor,
        columns: train.columns.clone(),
        effects: train.effects.clone(),
        true_features: train.true_features.clone(),
        profile: train.profile.clone(),
        noise: train.noise.clone(),
        files: BTreeMap::from([
            ("train".to_string(), train_name),
            ("verify".to_string(), verify_name),
            ("truth".to_string(), "truth.json".to_string()),
        ]),
        train,
        verify,
    };
    let tmp = staged.add("truth.json");
    let json = serde_json::to_string_pretty(&file).map_err(|e| Error::io(&tmp, e.into()))?;
    std::fs::write(&tmp, json + "\n").map_err(|e| Error::io(&tmp, e))?;
    staged.commit()?;
    Ok(file)
}

/// Files written to temporaries beside their final names, renamed into place together by
/// [`Staged::commit`]; dropped uncommitted, the temporaries are removed.
struct Staged {
    dir: std::path::PathBuf,
    files: Vec<(std::path::PathBuf, String)>,
    committed: bool,
}

impl Staged {
    fn new(dir: &Path) -> Self {
        Staged {
            dir: dir.to_path_buf(),
            files: Vec::new(),
            committed: false,
        }
    }

    /// The temporary path for the final file `name` (same directory, so the rename is atomic;
    /// the name ends as the final one does, so `.gz` still selects compression).
    fn add(&mut self, name: &str) -> std::path::PathBuf {
        let tmp = self
            .dir
            .join(format!(".partial-{}-{name}", std::process::id()));
        self.files.push((tmp.clone(), name.to_string()));
        tmp
    }

    fn commit(mut self) -> Result<()> {
        for (tmp, name) in &self.files {
            let dst = self.dir.join(name);
            std::fs::rename(tmp, &dst).map_err(|e| Error::io(&dst, e))?;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            for (tmp, _) in &self.files {
                // Best effort: a temporary that was never created is not an error.
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}
