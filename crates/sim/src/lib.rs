//! Simulated temperature-chamber runs of inertial sensors with known physics and named effects.
//!
//! Why: fitting, diagnosis and the demo need data whose truth is known. A [`Scenario`] describes a
//! sensor (RLG, QMA, IFOG), a chamber profile of holds and ramps, bias effects with coefficients,
//! noise, rates and a seed; the simulator streams a measurement CSV (the DESIGN.md convention) and
//! returns a [`Truth`]: the effects as exact expressions in the core's feature language, and the
//! noise floor actually drawn.
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
//! bias effects), [`noise`] (white, Gauss–Markov, pulses, statistics), [`scenario`] (TOML and
//! validation), [`writer`] (streaming CSV), [`truth`] (JSON truth), [`presets`], [`expr`] (a
//! reference evaluator for checking expressions), [`ops`] (the core's operators mirrored).

pub mod effects;
mod engine;
pub mod error;
pub mod expr;
pub mod noise;
pub mod ops;
pub mod presets;
pub mod profile;
pub mod scenario;
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

/// Streams `scenario` to a CSV file, gzip-compressed when `path` ends with `.gz`.
pub fn simulate_to_path(scenario: &Scenario, path: &Path) -> Result<Truth> {
    let mut sink = writer::FileSink::create(path)?;
    let truth = engine::run(scenario, &mut sink)?;
    sink.close(path)?;
    Ok(truth)
}

/// Writes a preset's `train.csv`, `verify.csv` (`.csv.gz` with `gzip`) and `truth.json` into `dir`
/// (created if missing); returns the truth file's contents.
pub fn write_preset(preset: &Preset, dir: &Path, gzip: bool) -> Result<TruthFile> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let ext = if gzip { "csv.gz" } else { "csv" };
    let (train_name, verify_name) = (format!("train.{ext}"), format!("verify.{ext}"));
    let train = simulate_to_path(&preset.train, &dir.join(&train_name))?;
    let verify = simulate_to_path(&preset.verify, &dir.join(&verify_name))?;
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
    let path = dir.join("truth.json");
    let json = serde_json::to_string_pretty(&file).map_err(|e| Error::io(&path, e.into()))?;
    std::fs::write(&path, json + "\n").map_err(|e| Error::io(&path, e))?;
    Ok(file)
}
