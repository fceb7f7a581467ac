//! What the demo writes: the simulated runs as CSV, the blobs, the report; each failure names its
//! file.

use anyhow::Context as _;
use std::path::Path;
use tcomp_train::Dataset;

/// Creates the output directory.
pub(super) fn create_dir(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())
}

/// Writes `bytes` to `path`.
pub(super) fn write(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    std::fs::write(path, bytes).with_context(|| path.display().to_string())
}

/// Writes a dataset as CSV: its header, then one row per sample (a missing value as `NaN`).
pub(super) fn save_csv(path: &Path, d: &Dataset) -> anyhow::Result<()> {
    let mut s = d.names().join(",");
    s.push('\n');
    let cols: Vec<&[f64]> = d.names().iter().filter_map(|n| d.column(n).ok()).collect();
    for i in 0..d.len() {
        let row: Vec<String> = cols
            .iter()
            .map(|c| format!("{}", c.get(i).copied().unwrap_or(f64::NAN)))
            .collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    write(path, s.as_bytes())
}
