//! Errors as Python exceptions: `tcomp.TcompError` (a `ValueError`) carrying the CLI's message
//! and the place the error names — `file`, `line`, `column` (1-based) and `option` (the Python
//! keyword) — as attributes, `None` where the error has no such place.
//!
//! Why from the error values and not from their text: the trainer's errors are typed (a cell's
//! `CellRef`, a spec error's TOML span, an option's name), so the place is read from the same
//! value the CLI's message is printed from, and cannot drift from it.

use crate::args::python_name;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use tcomp_train::{DataError, TrainError};

pyo3::create_exception!(
    tcomp,
    TcompError,
    PyValueError,
    "An error of tcomp, with the command line's message; `file`, `line`, `column` and `option` \
     say where, when the error names a place (else None)."
);

/// Where an error points.
#[derive(Default)]
struct Place {
    file: Option<String>,
    line: Option<u64>,
    column: Option<usize>,
    option: Option<String>,
}

impl TcompError {
    /// A spec error of keyword arguments: the keyword is the `line`-th of `names` (one line
    /// each in the spec text the keywords were written to).
    pub fn from_spec(e: TrainError, names: &[String]) -> PyErr {
        let message = e.to_string();
        let mut place = Place::default();
        match &e {
            TrainError::Spec { file, .. } => {
                place.file = Some(file.clone());
                // toml's message says "line N, column M" of the spec text: line N is keyword N.
                let line = message
                    .split("line ")
                    .nth(1)
                    .and_then(|r| r.split(|c: char| !c.is_ascii_digit()).next())
                    .and_then(|d| d.parse::<usize>().ok());
                place.option = line.and_then(|l| names.get(l.checked_sub(1)?)).cloned();
            }
            TrainError::UnknownSpecKey { file, key, .. } => {
                place.file = Some(file.clone());
                place.option = Some(python_name(key));
            }
            _ => place = place_of(&e),
        }
        raise(message, place)
    }
}

/// `anyhow`'s error (any of the crates' errors) as a `TcompError`, with the message the CLI
/// prints (`error: …` without the prefix) and the place of the first typed error in its chain.
pub fn py_err(e: anyhow::Error) -> PyErr {
    let place = e
        .chain()
        .find_map(|c| {
            c.downcast_ref::<TrainError>()
                .map(place_of)
                .or_else(|| c.downcast_ref::<DataError>().map(data_place))
        })
        .unwrap_or_default();
    raise(message(&e), place)
}

/// The error and its causes on one line, without a cause whose text the message already holds
/// (as `tcomp`'s `main` prints it).
fn message(err: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in err.chain() {
        let c = cause.to_string();
        if text.is_empty() {
            text = c;
        } else if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}

fn place_of(e: &TrainError) -> Place {
    match e {
        TrainError::Data(d) => data_place(d),
        TrainError::OutOfRange { option, .. } => Place {
            // "--average -1 (spec key `average`)": the key is the keyword.
            option: option
                .split("spec key `")
                .nth(1)
                .and_then(|r| r.split('`').next())
                .map(python_name),
            ..Place::default()
        },
        TrainError::Spec { file, .. } | TrainError::Io { file, .. } => Place {
            file: Some(file.clone()),
            ..Place::default()
        },
        TrainError::UnknownSpecKey {
            file, line, key, ..
        } => Place {
            file: Some(file.clone()),
            line: Some(*line as u64),
            option: Some(python_name(key)),
            ..Place::default()
        },
        _ => Place::default(),
    }
}

fn data_place(d: &DataError) -> Place {
    let file = |f: &str| Some(f.to_string());
    match d {
        DataError::NonNumeric { at, .. }
        | DataError::NonFinite { at, .. }
        | DataError::TimeNotIncreasing { at, .. } => Place {
            file: file(&at.file),
            line: Some(at.line),
            column: Some(at.column),
            option: None,
        },
        DataError::Csv { file: f, line, .. } => Place {
            file: file(f),
            line: Some(*line),
            ..Place::default()
        },
        DataError::UnknownColumn { file: f, .. } | DataError::DuplicateColumn { file: f, .. } => {
            Place {
                file: file(f),
                line: Some(1),
                ..Place::default()
            }
        }
        DataError::Io { file: f, .. } | DataError::Empty { file: f, .. } => Place {
            file: file(f),
            ..Place::default()
        },
        _ => Place::default(),
    }
}

fn raise(message: String, place: Place) -> PyErr {
    Python::attach(|py| {
        let err = TcompError::new_err(message);
        let value = err.value(py);
        let set = |name: &str, v: Bound<'_, PyAny>| value.setattr(name, v);
        let ok = set(
            "file",
            place
                .file
                .into_pyobject(py)
                .map_or_else(|_| py.None().into_bound(py), Bound::into_any),
        )
        .and_then(|()| {
            set(
                "line",
                place
                    .line
                    .into_pyobject(py)
                    .map_or_else(|_| py.None().into_bound(py), Bound::into_any),
            )
        })
        .and_then(|()| {
            set(
                "column",
                place
                    .column
                    .into_pyobject(py)
                    .map_or_else(|_| py.None().into_bound(py), Bound::into_any),
            )
        })
        .and_then(|()| {
            set(
                "option",
                place
                    .option
                    .into_pyobject(py)
                    .map_or_else(|_| py.None().into_bound(py), Bound::into_any),
            )
        });
        match ok {
            Ok(()) => err,
            Err(e) => e,
        }
    })
}

/// A keyword whose value is of a type no option takes.
pub fn type_error(name: &str, v: &Bound<'_, PyAny>) -> PyErr {
    let ty = v
        .get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string());
    PyTypeError::new_err(format!(
        "{name}: a str, int, float, bool or a list of them, not {ty}"
    ))
}
