//! Python arguments into the Rust crates' own types: columns into a [`Dataset`], keyword
//! arguments into the fit spec (read by `Spec::parse`, the reader of `tcomp fit --spec`).
//!
//! Why keywords go through the spec's reader: the spec's keys are the CLI's flags (one struct set
//! for both, `tcomp_train::spec`), and its reader checks every key and type with the CLI's
//! messages. A Python keyword becomes one `key = value` line of a TOML text (`reference_value` →
//! `reference-value`, `from_` → `from`), so an error in it is reported for that key.

use crate::errors::{TcompError, type_error};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyFloat, PyInt, PyList, PyString, PyTuple};
use tcomp::args::run::RunArgs;
use tcomp_discover::DiagnoseOptions;
use tcomp_train::layer::Layer;
use tcomp_train::{Dataset, RunOptions, Spec};

/// Columns of data: `(label, names, columns)`, each column the bytes of a little-endian float64
/// array, all of one length; `label` names the data in errors where a CSV's file name would.
pub struct Columns {
    label: String,
    names: Vec<String>,
    cols: Vec<Vec<f64>>,
}

impl<'py> FromPyObject<'_, 'py> for Columns {
    type Error = PyErr;

    fn extract(ob: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        let (label, names, raw): (String, Vec<String>, Vec<Bound<'py, PyBytes>>) = ob.extract()?;
        if names.len() != raw.len() {
            return Err(PyTypeError::new_err("one name per column"));
        }
        let mut cols = Vec::with_capacity(raw.len());
        for (name, b) in names.iter().zip(&raw) {
            let bytes = b.as_bytes();
            if bytes.len() % 8 != 0 {
                return Err(PyTypeError::new_err(format!(
                    "column `{name}`: not float64 data"
                )));
            }
            cols.push(
                bytes
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                    .collect::<Vec<f64>>(),
            );
        }
        if cols.windows(2).any(|w| w[0].len() != w[1].len()) {
            return Err(PyTypeError::new_err("columns of different lengths"));
        }
        Ok(Self { label, names, cols })
    }
}

impl Columns {
    /// The columns as the trainer's dataset: a non-finite cell is reported, when a used column
    /// holds it, at its line (row + 2, as in the CSV the data would be written to) and column.
    pub fn dataset(self) -> Dataset {
        Dataset::from_columns(&self.label, self.names, self.cols)
    }
}

/// Keyword arguments: `(python name, value)` pairs in the order given.
pub struct Kwargs(Vec<(String, toml::Value)>);

impl<'py> FromPyObject<'_, 'py> for Kwargs {
    type Error = PyErr;

    fn extract(ob: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        let pairs: Vec<(String, Bound<'py, PyAny>)> = ob.extract()?;
        let mut out = Vec::new();
        for (name, v) in pairs {
            if v.is_none() {
                continue;
            }
            let value = value(&v).ok_or_else(|| type_error(&name, &v))?;
            out.push((name, value));
        }
        Ok(Self(out))
    }
}

/// A Python value as a TOML value: bool, int, float, str, or a list of them.
fn value(v: &Bound<'_, PyAny>) -> Option<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return v.extract::<bool>().ok().map(toml::Value::Boolean);
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().ok().map(toml::Value::Integer);
    }
    if v.is_instance_of::<PyFloat>() {
        return v.extract::<f64>().ok().map(toml::Value::Float);
    }
    if v.is_instance_of::<PyString>() {
        return v.extract::<String>().ok().map(toml::Value::String);
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = v.extract().ok()?;
        return items
            .iter()
            .map(value)
            .collect::<Option<Vec<_>>>()
            .map(toml::Value::Array);
    }
    None
}

/// The spec key of a Python keyword: `reference_value` → `reference-value`, `from_` → `from`.
pub fn spec_key(python: &str) -> String {
    python.trim_end_matches('_').replace('_', "-")
}

/// The Python keyword of a spec key (the inverse of [`spec_key`]).
pub fn python_name(key: &str) -> String {
    let name = key.replace('-', "_");
    if name == "from" { "from_".into() } else { name }
}

/// What an evaluation reads besides the model and the data: the run's options as the CLI's
/// `RunArgs` (roles, window, gaps), the bin and the segment temperature.
pub struct EvalOptions {
    pub run: RunArgs,
    pub bin_s: f64,
    pub temperature: Option<String>,
}

impl EvalOptions {
    /// The rows of `--from/--until` (all when neither is given).
    pub fn window(&self, data: Dataset, time: &str) -> anyhow::Result<Dataset> {
        self.run.check_window()?;
        let r = &self.run.run;
        if r.from.is_none() && r.until.is_none() {
            return Ok(data);
        }
        let lo = r.from.unwrap_or(f64::NEG_INFINITY);
        Ok(data.select_time(time, lo, r.until.unwrap_or(f64::INFINITY))?)
    }
}

impl Kwargs {
    /// The keywords as the text of a fit spec, one `key = value` line each, and their names.
    fn text(&self, only: Option<&[String]>, context: &str) -> PyResult<(String, Vec<String>)> {
        let mut text = String::new();
        let mut names = Vec::new();
        for (name, v) in &self.0 {
            let key = spec_key(name);
            if only.is_some_and(|keys| !keys.contains(&key)) {
                return Err(PyTypeError::new_err(format!(
                    "{context}() got an unexpected keyword argument '{name}'"
                )));
            }
            text.push_str(&format!("{key} = {v}\n"));
            names.push(name.clone());
        }
        Ok((text, names))
    }

    /// The keywords read as a fit spec (every key of `tcomp fit --spec`).
    pub fn spec(&self, context: &str) -> PyResult<Spec> {
        let (text, names) = self.text(None, context)?;
        let label = format!("{context}() keyword arguments");
        Spec::parse(&label, &text).map_err(|e| TcompError::from_spec(e, &names))
    }

    /// Takes the number keyword `name` out (a float or an int), or `default`.
    fn take_number(&mut self, name: &str, default: f64) -> PyResult<f64> {
        match self.take(name) {
            None => Ok(default),
            Some(toml::Value::Float(f)) => Ok(f),
            Some(toml::Value::Integer(i)) => Ok(i as f64),
            Some(other) => Err(PyTypeError::new_err(format!(
                "{name}: a number, not {other}"
            ))),
        }
    }

    fn take(&mut self, name: &str) -> Option<toml::Value> {
        let at = self.0.iter().position(|(n, _)| n == name)?;
        Some(self.0.remove(at).1)
    }

    fn take_string(&mut self, name: &str) -> PyResult<Option<String>> {
        match self.take(name) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s)),
            Some(other) => Err(PyTypeError::new_err(format!(
                "{name}: a string, not {other}"
            ))),
        }
    }

    /// The run's keywords (`reference`, `reference_value`, `from_`, `until`, `gap`, `power_on`)
    /// read as the spec reads them, after taking out `bin` and `temperature`.
    pub fn eval_options(mut self, context: &str) -> PyResult<EvalOptions> {
        let bin_s = self.take_number("bin", 100.0)?;
        self.eval_rest(bin_s, context)
    }

    fn eval_rest(mut self, bin_s: f64, context: &str) -> PyResult<EvalOptions> {
        let temperature = self.take_string("temperature")?;
        let mut keys = Vec::new();
        RunOptions::keys(&mut keys);
        let (text, names) = self.text(Some(&keys), context)?;
        let label = format!("{context}() keyword arguments");
        let spec = Spec::parse(&label, &text).map_err(|e| TcompError::from_spec(e, &names))?;
        Ok(EvalOptions {
            run: RunArgs {
                data: label.into(),
                run: spec.run,
            },
            bin_s,
            temperature,
        })
    }

    /// [`Kwargs::eval_options`] and the diagnosis thresholds (`bin` 60 s, `min_evidence` 5,
    /// `min_improvement` 5 %: `tcomp diagnose`'s defaults).
    pub fn diagnose_options(mut self, context: &str) -> PyResult<(EvalOptions, DiagnoseOptions)> {
        let bin_s = self.take_number("bin", 60.0)?;
        let mut opts = DiagnoseOptions::default();
        opts.criterion.min_delta_log_evidence = self.take_number("min_evidence", 5.0)?;
        opts.criterion.min_improvement_pct = self.take_number("min_improvement", 5.0)?;
        let eval = self.eval_rest(bin_s, context)?;
        opts.score.bin_s = eval.bin_s;
        opts.score.gap_s = eval.run.run.gap;
        opts.temperature.clone_from(&eval.temperature);
        Ok((eval, opts))
    }
}
