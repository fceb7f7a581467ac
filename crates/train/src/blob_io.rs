//! An owned model description → the core's borrowed [`Model`] → bytes on disk, written atomically.
//!
//! Why: the core's `Model<'a>` borrows its strings (zero-copy on the firmware), so the host keeps an
//! owned [`OwnedModel`] and lends it out. Files are written to a temporary file in the same directory
//! and renamed over the target, so a crash or a full disk never leaves a half-written blob.

use crate::error::TrainError;
use crate::features::{F, FeatureSpec};
use crate::rbf64::C;
use crate::units::{self, Relation};
use std::io::Write;
use std::path::Path;
use tcomp_core::{ColumnRoles, FeatureRange, Meta, Model, Program, Rbf, ResidualLevel, SensorKind};

/// A decoded model at the host capacities (the core's one alias: centers, features and program
/// nodes are named once, in `tcomp_core::HOST_*`).
pub use tcomp_core::HostModel;

/// Largest blob the host writes.
pub const MAX_BLOB: usize = 64 * 1024;

/// What a model was trained on, as its blob's `trained_on` says it:
/// `"FILE [FROM s, UNTIL s) t=T0..T1 s"` — the file, the `--from/--until` window when one was
/// given, and the times of the first and last rows used. Written by the trainer and read by
/// `tcomp image` (provenance) and `tcomp diagnose` (the model's training window) from this one
/// definition.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainedOn {
    /// The data file as the trainer was given it.
    pub file: String,
    /// The `--from/--until` window (s), when one was given.
    pub window: Option<[f64; 2]>,
    /// Time of the first and last row used (s).
    pub span: Option<[f64; 2]>,
}

impl TrainedOn {
    /// The text for a run named `data_file` (a [`crate::Dataset::file`], which carries the
    /// window) whose rows span `t0..t1` seconds.
    pub fn text(data_file: &str, t0: f64, t1: f64) -> String {
        format!("{data_file} t={t0}..{t1} s")
    }

    /// Reads `trained_on`; parts it does not recognise are left in the file name.
    pub fn parse(trained_on: &str) -> Self {
        let (rest, span) = match trained_on.rsplit_once(" t=") {
            Some((f, w)) => (f, pair(w.trim_end_matches(" s"), "..")),
            None => (trained_on, None),
        };
        let (file, window) = match rest.rsplit_once(" [") {
            Some((f, w)) if w.ends_with(" s)") => match pair(w.trim_end_matches(" s)"), " s, ") {
                Some(p) => (f, Some(p)),
                None => (rest, None),
            },
            _ => (rest, None),
        };
        TrainedOn {
            file: file.to_string(),
            window,
            span: if file == rest || window.is_some() {
                span
            } else {
                None
            },
        }
    }
}

/// `"A<sep>B"` as two numbers.
fn pair(text: &str, sep: &str) -> Option<[f64; 2]> {
    let (a, b) = text.split_once(sep)?;
    Some([a.trim().parse().ok()?, b.trim().parse().ok()?])
}

/// Everything a model blob holds, owned.
#[derive(Clone, Debug)]
pub struct OwnedModel {
    /// Instrument kind.
    pub sensor: SensorKind,
    /// Axis label.
    pub axis: String,
    /// Target unit.
    pub unit: String,
    /// Method name.
    pub method: String,
    /// Time column.
    pub time: String,
    /// Target column.
    pub target: String,
    /// Reference column ("" when a constant).
    pub reference: String,
    /// Constant reference.
    pub reference_value: Option<f32>,
    /// What it was trained on.
    pub trained_on: String,
    /// Training samples (after averaging).
    pub train_samples: u32,
    /// The feature program's source.
    pub spec: FeatureSpec,
    /// Valid feature ranges.
    pub ranges: Vec<FeatureRange>,
    /// Coefficients.
    pub rbf: Rbf<C, F>,
    /// Residual level.
    pub residual: ResidualLevel,
}

impl OwnedModel {
    /// The core model, borrowing from `self`.
    pub fn model(&self) -> Result<HostModel<'_>, TrainError> {
        self.model_with(self.spec.program()?)
    }

    /// [`OwnedModel::model`] with `program`, [`OwnedModel::spec`] already compiled (a fit
    /// compiles it once for its two encodings).
    fn model_with<'a>(
        &'a self,
        program: Program<'a, { crate::features::N }, F>,
    ) -> Result<HostModel<'a>, TrainError> {
        let mut ranges = heapless::Vec::new();
        for r in &self.ranges {
            ranges.push(*r).map_err(|_| TrainError::OverCapacity {
                features: self.ranges.len(),
                max_features: F,
                centers: 0,
                max_centers: C,
            })?;
        }
        let meta = Meta {
            sensor: self.sensor,
            axis: &self.axis,
            unit: &self.unit,
            method: &self.method,
            columns: ColumnRoles {
                time: &self.time,
                target: &self.target,
                reference: &self.reference,
                reference_value: self.reference_value,
            },
            trained_on: &self.trained_on,
            train_samples: self.train_samples,
        };
        Ok(Model::new(
            meta,
            program,
            ranges,
            self.rbf.clone(),
            self.residual,
        ))
    }

    /// The encoded blob.
    pub fn to_bytes(&self) -> Result<Vec<u8>, TrainError> {
        self.encode(self.model()?)
    }

    /// [`OwnedModel::to_bytes`] with `program`, which must be [`OwnedModel::spec`] compiled
    /// (`spec.program()`): the trainer compiles the stored program once per fit.
    pub(crate) fn to_bytes_with(
        &self,
        program: &Program<'_, { crate::features::N }, F>,
    ) -> Result<Vec<u8>, TrainError> {
        self.encode(self.model_with(program.clone())?)
    }

    fn encode(&self, model: HostModel<'_>) -> Result<Vec<u8>, TrainError> {
        let mut buf = vec![0u8; MAX_BLOB];
        let len = model.encode(&mut buf).map_err(|e| TrainError::Blob {
            context: "cannot encode the model".into(),
            source: crate::error::Core(e),
        })?;
        buf.truncate(len);
        Ok(buf)
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), TrainError> {
    let io = |source| TrainError::Io {
        file: path.display().to_string(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Reads a blob file's bytes (decode them with [`Model::decode`]).
pub fn read(path: &Path) -> Result<Vec<u8>, TrainError> {
    std::fs::read(path).map_err(|source| TrainError::Io {
        file: path.display().to_string(),
        source,
    })
}

/// Decodes a blob, naming the file and the reason when it is rejected.
pub fn decode<'a>(path: &Path, bytes: &'a [u8]) -> Result<HostModel<'a>, TrainError> {
    Model::decode(bytes).map_err(|e| TrainError::Blob {
        context: format!("{}: corrupt model blob", path.display()),
        source: crate::error::Core(e),
    })
}

/// Checks that a blob loads into the reference firmware's model types
/// ([`tcomp_core::FLIGHT_CENTERS`] × [`tcomp_core::FLIGHT_FEATURES`], [`tcomp_core::FLIGHT_NODES`]
/// program nodes); the error names what is too large.
pub fn check_flight(path: &Path, bytes: &[u8]) -> Result<(), TrainError> {
    use tcomp_core::{FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES};
    let host = decode(path, bytes)?;
    let (f, c, n) = (
        usize::from(host.rbf.n_features),
        host.rbf.centers.len(),
        host.program.nodes.len(),
    );
    let mut over = Vec::new();
    if f > FLIGHT_FEATURES {
        over.push(format!(
            "{f} features (the firmware holds {FLIGHT_FEATURES})"
        ));
    }
    if c > FLIGHT_CENTERS {
        over.push(format!("{c} centers (the firmware holds {FLIGHT_CENTERS})"));
    }
    if n > FLIGHT_NODES {
        over.push(format!(
            "{n} feature-program nodes (the firmware holds {FLIGHT_NODES})"
        ));
    }
    if !over.is_empty() {
        return Err(TrainError::TooLargeForFlight {
            file: path.display().to_string(),
            over: over.join(", "),
        });
    }
    Model::<'_, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>::decode(bytes)
        .map(|_| ())
        .map_err(|e| TrainError::Blob {
            context: format!(
                "{}: the model does not load into the firmware's types",
                path.display()
            ),
            source: crate::error::Core(e),
        })
}

/// A blob whose unit is `unit` spelt another way ([`units::relate`]), re-encoded with `unit`'s
/// spelling; `Ok(None)` when the blob already says `unit`, or says another quantity or scale (the
/// caller's check then refuses it); an error naming the factor when the units are commensurable
/// but not equal, since a model in one cannot be flown as the other.
pub fn respell_blob(
    path: &std::path::Path,
    bytes: &[u8],
    unit: &str,
) -> Result<Option<Vec<u8>>, TrainError> {
    let m = decode(path, bytes)?;
    if m.meta.unit == unit || m.meta.unit.is_empty() || unit.is_empty() {
        return Ok(None);
    }
    let rel = match units::relate(m.meta.unit, unit) {
        Ok(r) => r,
        Err(_) => return Ok(None),
    };
    match rel {
        Relation::Same => {
            let mut re = m.clone();
            re.meta.unit = unit;
            let mut buf = vec![0u8; MAX_BLOB];
            let len = re.encode(&mut buf).map_err(|e| TrainError::Blob {
                context: format!("{}: re-encoding with unit {unit}", path.display()),
                source: crate::error::Core(e),
            })?;
            buf.truncate(len);
            Ok(Some(buf))
        }
        Relation::Scaled(k) => Err(TrainError::UnitScale {
            file: path.display().to_string(),
            model: m.meta.unit.to_string(),
            board: unit.to_string(),
            factor: crate::num::plain(k, 9),
        }),
        Relation::Different => Ok(None),
    }
}

#[cfg(test)]
mod trained_on_tests {
    use super::TrainedOn;

    #[test]
    fn the_trainer_s_text_reads_back() {
        let t = TrainedOn::parse(&TrainedOn::text("data/a b.csv [0 s, 3130 s)", 0.5, 3129.5));
        assert_eq!(t.file, "data/a b.csv");
        assert_eq!(t.window, Some([0.0, 3130.0]));
        assert_eq!(t.span, Some([0.5, 3129.5]));
        let t = TrainedOn::parse(&TrainedOn::text("x.csv [-inf s, 100 s)", 1.0, 99.0));
        assert_eq!(t.window, Some([f64::NEG_INFINITY, 100.0]));
        let t = TrainedOn::parse(&TrainedOn::text("x.csv", 1.0, 2.0));
        assert_eq!(
            (t.file.as_str(), t.window, t.span),
            ("x.csv", None, Some([1.0, 2.0]))
        );
        let t = TrainedOn::parse("tests/mutants.rs");
        assert_eq!(
            (t.file.as_str(), t.window, t.span),
            ("tests/mutants.rs", None, None)
        );
    }
}
