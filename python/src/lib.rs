//! `tcomp._tcomp`: the Python extension module under the `tcomp` package (`python/tcomp/`).
//!
//! Why it is thin: every function here converts Python values into the Rust crates' own types,
//! calls the one function the CLI calls (`tcomp_train::fit`, `tcomp_train::evaluate`,
//! `tcomp_discover::diagnose`, the CLI's own `calibrate` and `simulate` commands), and converts
//! the result back — as bytes (blobs, float64 columns) or as the JSON the CLI's `--json` prints.
//! Options arrive as the fit spec's keys and are read by the trainer's own reader
//! (`tcomp_train::Spec::parse`), so a Python keyword is checked exactly as the flag or spec key of
//! the same name, with the same message. The pure-Python layer (`tcomp/__init__.py`) only turns
//! DataFrames into columns and JSON into DataFrames.
//!
//! Errors are `tcomp.TcompError` (a `ValueError`) with the CLI's message and, where the error
//! has one, its place: `file`, `line`, `column`, `option` (`errors.rs`). Long work (fits,
//! evaluations, diagnoses, calibrations) runs with the GIL released.

mod args;
mod errors;

use args::{Columns, Kwargs};
use errors::{TcompError, py_err};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::{Path, PathBuf};
use tcomp_train::{Dataset, FitOptions, Spec};

/// Where a blob handed over as bytes is named in messages.
const BLOB_LABEL: &str = "<model bytes>";

/// Fits a model on columns of data with the fit spec's keys (`fit(...)` in Python).
/// Returns the blob and the fit summary (the JSON `tcomp fit --json` prints under its body).
#[pyfunction]
fn fit(py: Python<'_>, data: Columns, options: Kwargs) -> PyResult<(Py<PyBytes>, String)> {
    let spec = options.spec("tcomp.fit")?;
    let (bytes, summary) = py
        .detach(move || -> anyhow::Result<(Vec<u8>, String)> {
            let opts = FitOptions::from_spec(&spec)?;
            let data = data.dataset();
            let fitted = tcomp_train::fit(&data, &opts)?;
            let bytes = fitted.model.to_bytes()?;
            Ok((bytes, serde_json::to_string(&fitted.summary)?))
        })
        .map_err(py_err)?;
    Ok((PyBytes::new(py, &bytes).unbind(), summary))
}

/// Decodes and validates a blob; returns what `tcomp inspect --json` would say of it.
#[pyfunction]
fn inspect(py: Python<'_>, blob: Vec<u8>) -> PyResult<String> {
    py.detach(move || -> anyhow::Result<String> {
        let model = tcomp_train::blob_io::decode(Path::new(BLOB_LABEL), &blob)?;
        let args = tcomp::cmd::inspect::Args {
            model: PathBuf::from(BLOB_LABEL),
            json: true,
            // A blob carries no signature (images do: `tcomp inspect IMAGE --key`).
            keys: Vec::new(),
        };
        Ok(tcomp::cmd::inspect::blob_json(&args, &blob, &model).to_string())
    })
    .map_err(py_err)
}

/// Evaluates a blob on columns of data: the residual (float64 bytes, compensated − reference,
/// one per row) and the figures (the JSON of `tcomp eval --json`'s body).
#[pyfunction]
fn evaluate(
    py: Python<'_>,
    blob: Vec<u8>,
    data: Columns,
    options: Kwargs,
) -> PyResult<(Py<PyBytes>, String)> {
    let eval = options.eval_options("Model.evaluate")?;
    let (residual, report) = py
        .detach(move || -> anyhow::Result<(Vec<u8>, String)> {
            let model = tcomp_train::blob_io::decode(Path::new(BLOB_LABEL), &blob)?;
            let roles = eval.run.roles(&model);
            let data = eval.window(data.dataset(), &roles.time)?;
            let t = eval.temperature.as_deref();
            let gap = eval.run.run.gap;
            let report = tcomp_train::evaluate(&model, &data, &roles, eval.bin_s, t, gap)?;
            let run = tcomp_train::metrics::run_model(&model, &data, &roles, t, gap)?;
            let figures = tcomp::output::json::RunFigures::from(&report);
            let bytes = run.residual.iter().flat_map(|v| v.to_le_bytes()).collect();
            Ok((bytes, serde_json::to_string(&figures)?))
        })
        .map_err(py_err)?;
    Ok((PyBytes::new(py, &residual).unbind(), report))
}

/// Diagnoses a blob on columns of data (and a held-out run): the JSON of `tcomp diagnose
/// --json`'s body (the verdict, the candidate table, the segments).
#[pyfunction]
#[pyo3(signature = (blob, data, verify, options))]
fn diagnose(
    py: Python<'_>,
    blob: Vec<u8>,
    data: Columns,
    verify: Option<Columns>,
    options: Kwargs,
) -> PyResult<String> {
    let (eval, opts) = options.diagnose_options("tcomp.diagnose")?;
    py.detach(move || -> anyhow::Result<String> {
        let model = tcomp_train::blob_io::decode(Path::new(BLOB_LABEL), &blob)?;
        let roles = eval.run.roles(&model);
        let mut opts = opts;
        if eval.run.overrides_reference() {
            opts.roles = Some(roles.clone());
        }
        let data = eval.window(data.dataset(), &roles.time)?;
        let verify = verify.map(|v| v.dataset());
        let a = tcomp_discover::diagnose(&model, &data, verify.as_ref(), &opts)?;
        Ok(tcomp::cmd::diagnose::body(&a.diagnosis)?.to_string())
    })
    .map_err(py_err)
}

/// Runs `tcomp calibrate SPEC --out OUT` (one unit, or a folder of units with `units`) and returns
/// its `summary.json` (or `fleet.json`).
#[pyfunction]
#[pyo3(signature = (spec, out, units=None, accept=false, diagnosis=true, gate=true))]
fn calibrate(
    py: Python<'_>,
    spec: PathBuf,
    out: PathBuf,
    units: Option<PathBuf>,
    accept: bool,
    diagnosis: bool,
    gate: bool,
) -> PyResult<String> {
    py.detach(move || -> anyhow::Result<String> {
        let summary = out.join(if units.is_some() {
            "fleet.json"
        } else {
            "summary.json"
        });
        let args = tcomp::cmd::calibrate::Args {
            spec,
            out,
            units,
            unit: None,
            collect: None,
            accept,
            no_diagnosis: !diagnosis,
            no_gate: !gate,
            json: false,
            quiet: true,
        };
        tcomp::cmd::calibrate::run(&args)?;
        Ok(std::fs::read_to_string(&summary)?)
    })
    .map_err(py_err)
}

/// Runs `tcomp simulate --preset NAME` (or `--scenario FILE`) into `out`: train.csv,
/// verify.csv and truth.json, as the CLI writes them (the command without its printed summary).
#[pyfunction]
#[pyo3(signature = (out, preset=None, scenario=None, seed=None, rate_hz=None, step_s=None))]
fn simulate(
    py: Python<'_>,
    out: PathBuf,
    preset: Option<String>,
    scenario: Option<PathBuf>,
    seed: Option<u64>,
    rate_hz: Option<f64>,
    step_s: Option<f64>,
) -> PyResult<()> {
    py.detach(move || -> anyhow::Result<()> {
        let args = tcomp::cmd::simulate::Args {
            list: false,
            preset,
            scenario,
            out: Some(out),
            seed,
            rate_hz,
            step_s,
            units: None,
            outliers: 0,
            gzip: false,
            json: false,
            quiet: true,
        };
        tcomp::cmd::simulate::write(&args).map(|_| ())
    })
    .map_err(py_err)
}

/// The simulator's presets: `(name, description)`, as `tcomp simulate --list` prints them.
#[pyfunction]
fn presets() -> Vec<(String, String)> {
    tcomp_sim::presets::list()
        .iter()
        .map(|p| (p.name.to_string(), p.description.to_string()))
        .collect()
}

/// Reads a measurement CSV (or .csv.gz) as `tcomp` reads it: `(names, columns as float64
/// bytes)`, with the CLI's errors (file, line, column).
#[pyfunction]
fn read_csv(py: Python<'_>, path: PathBuf) -> PyResult<(Vec<String>, Vec<Py<PyBytes>>)> {
    let data = py
        .detach(move || Dataset::load(&path))
        .map_err(|e| py_err(e.into()))?;
    let names = data.names().to_vec();
    let mut cols = Vec::new();
    for n in &names {
        let c = data.column(n).map_err(|e| py_err(e.into()))?;
        let bytes: Vec<u8> = c.iter().flat_map(|v| v.to_le_bytes()).collect();
        cols.push(PyBytes::new(py, &bytes).unbind());
    }
    Ok((names, cols))
}

/// The fit spec's keys (what `fit` accepts as keyword arguments).
#[pyfunction]
fn fit_keys() -> Vec<String> {
    let mut keys = Vec::new();
    <Spec as tcomp_train::layer::Layer>::keys(&mut keys);
    keys
}

#[pymodule]
fn _tcomp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("TcompError", m.py().get_type::<TcompError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(inspect, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    m.add_function(wrap_pyfunction!(read_csv, m)?)?;
    m.add_function(wrap_pyfunction!(fit_keys, m)?)?;
    Ok(())
}
