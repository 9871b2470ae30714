//! `knotsweep._native`: the solver for Python. The case parameters arrive as
//! keywords, are refused in the API's words (`solver::case::from_partial`)
//! and run by `solver::protocol::run_valid`, the function `knotsweep run`
//! calls, with the GIL released; the pure-Python package (`knotsweep/`)
//! wraps the answer.
use numpy::PyArray1;
use pyo3::create_exception;
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Value};
use solver::case::{FieldError, Group, PARAMETERS, Range, ValidCase};
use solver::measurements::{COLUMNS, Column, Sample};
use solver::protocol::{self, Progress, Status};
use std::time::{Duration, Instant};

create_exception!(
    _native,
    ParameterError,
    PyValueError,
    "A case parameter that is unknown, of the wrong type or out of its range. `fields` lists \
     (field, reason) pairs; the message is `field: reason` joined by `; `, the API's words."
);

/// How often a running case looks for Ctrl-C (the observer runs after every
/// sample; the GIL is taken at most this often for the check).
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// A parameter's value given by Python, as JSON (floats exactly, as the CLI parses them).
fn to_json(value: &Bound<'_, PyAny>) -> Result<Value, String> {
    if value.is_none() {
        return Ok(Value::Null);
    }
    if value.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(value.extract::<bool>().map_err(reason)?));
    }
    if value.is_instance_of::<PyInt>() {
        if let Ok(i) = value.extract::<i64>() {
            return Ok(Value::from(i));
        }
        return value
            .extract::<u64>()
            .map(Value::from)
            .map_err(|_| format!("integer {value} out of range"));
    }
    if value.is_instance_of::<PyFloat>() {
        let x: f64 = value.extract().map_err(reason)?;
        return finite(x);
    }
    if value.is_instance_of::<PyString>() {
        return Ok(Value::String(value.extract::<String>().map_err(reason)?));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        // A loading program's stage: {"pull": {"to_l_k_bar": 120.0}}.
        let mut object = Map::new();
        for (key, item) in dict.iter() {
            let key = key
                .extract::<String>()
                .map_err(|_| format!("invalid key {key}: keys must be strings"))?;
            object.insert(key, to_json(&item)?);
        }
        return Ok(Value::Object(object));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = value.extract().map_err(reason)?;
        return items
            .iter()
            .map(to_json)
            .collect::<Result<Vec<_>, _>>()
            .map(Value::Array);
    }
    // numpy arrays and scalars: their plain Python values.
    if value.hasattr("tolist").unwrap_or(false)
        && let Ok(plain) = value.call_method0("tolist")
        && !plain.hasattr("tolist").unwrap_or(false)
    {
        return to_json(&plain);
    }
    if let Ok(i) = value.call_method0("__index__") {
        return to_json(&i);
    }
    if let Ok(x) = value.call_method0("__float__").and_then(|x| x.extract::<f64>()) {
        return finite(x);
    }
    let kind = value.get_type().name().map(|n| n.to_string()).unwrap_or_default();
    Err(format!("invalid type: Python {kind}"))
}

/// An extraction's error as a reason.
fn reason(e: impl Into<PyErr>) -> String {
    e.into().to_string()
}

fn finite(x: f64) -> Result<Value, String> {
    serde_json::Number::from_f64(x)
        .map(Value::Number)
        .ok_or_else(|| format!("must be a finite number, got {x}"))
}

/// The keywords as a partial `CaseParams` object, or the problems with them.
fn partial(params: &Bound<'_, PyDict>) -> Result<Map<String, Value>, Vec<FieldError>> {
    let mut object = Map::new();
    let mut errors = Vec::new();
    for (key, value) in params.iter() {
        let field = key.extract::<String>().unwrap_or_else(|_| key.to_string());
        match to_json(&value) {
            Ok(v) => {
                object.insert(field, v);
            }
            Err(reason) => errors.push(FieldError { field, reason }),
        }
    }
    if errors.is_empty() {
        Ok(object)
    } else {
        Err(errors)
    }
}

fn parameter_error(py: Python<'_>, errors: &[FieldError]) -> PyErr {
    let message = errors
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ");
    let err = ParameterError::new_err(message);
    let fields: Vec<(String, String)> = errors
        .iter()
        .map(|e| (e.field.clone(), e.reason.clone()))
        .collect();
    if let Err(e) = err.value(py).setattr("fields", fields) {
        return e;
    }
    err
}

/// The case of these keywords, validated as the API validates a base.
fn valid_case(py: Python<'_>, params: &Bound<'_, PyDict>) -> PyResult<ValidCase> {
    let object = partial(params).map_err(|e| parameter_error(py, &e))?;
    solver::case::from_partial(&object).map_err(|e| parameter_error(py, &e))
}

/// Validates the case parameters (keywords of `run`) and returns every
/// parameter's value, defaults filled in, as JSON text; raises
/// ParameterError (a ValueError) naming each bad field.
#[pyfunction]
fn validate(py: Python<'_>, params: &Bound<'_, PyDict>) -> PyResult<String> {
    let case = valid_case(py, params)?;
    serde_json::to_string(case.params()).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Runs one case (the parameters as a dict) with the GIL released. Returns
/// the report as JSON text without its series, and the series as numpy
/// arrays by the columns of `knotsweep run --csv`. `progress`, if given, is
/// called after every sample with (fraction, l_k_bar, H_bar, steps); False
/// cancels the case (status "cancelled"). Ctrl-C stops the case and raises
/// KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (params, progress=None))]
fn run<'py>(
    py: Python<'py>,
    params: &Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, Bound<'py, PyDict>)> {
    let case = valid_case(py, params)?;
    let mut pending: Option<PyErr> = None;
    let mut report = py.detach(|| {
        let mut last_check = Instant::now();
        protocol::run_valid(&case, &mut |p: &Progress| {
            if pending.is_some() {
                return false;
            }
            let check = last_check.elapsed() >= SIGNAL_CHECK;
            if !check && progress.is_none() {
                return true;
            }
            Python::attach(|py| {
                if check {
                    last_check = Instant::now();
                    if let Err(e) = py.check_signals() {
                        pending = Some(e);
                        return false;
                    }
                }
                match &progress {
                    Some(callback) => match callback.call1(py, (p.fraction, p.l_k_bar, p.h_bar, p.steps)) {
                        Ok(answer) => !answer.bind(py).is(PyBool::new(py, false)),
                        Err(e) => {
                            pending = Some(e);
                            false
                        }
                    },
                    None => true,
                }
            })
        })
    });
    if let Some(e) = pending {
        return Err(e);
    }
    if report.status == Status::Cancelled && progress.is_none() {
        return Err(PyKeyboardInterrupt::new_err("case cancelled"));
    }
    let series = series_arrays(py, &report.series)?;
    report.series = Vec::new();
    let json = serde_json::to_string(&report).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((json, series))
}

/// The series as numpy arrays, one per column of the series CSV, in its order.
fn series_arrays<'py>(py: Python<'py>, series: &[Sample]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for (name, column) in COLUMNS {
        let array = match column {
            Column::Real(value) => PyArray1::from_vec(py, series.iter().map(value).collect()).into_any(),
            Column::Count(value) => {
                PyArray1::from_vec(py, series.iter().map(|s| value(s) as i64).collect()).into_any()
            }
        };
        out.set_item(name, array)?;
    }
    Ok(out)
}

/// A group's word, as the API's `x-group` writes it.
fn group_word(group: Group) -> String {
    match serde_json::to_value(group) {
        Ok(Value::String(word)) => word,
        _ => format!("{group:?}").to_lowercase(),
    }
}

/// The parameter table (`solver::case::PARAMETERS`): one dict per parameter
/// with name, group (its word and title, in form order), unit, default (JSON text), range, null, paper, doc,
/// description, kind (int, float, vector, flag, words, points, program, text) and words.
#[pyfunction]
fn parameters(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for p in PARAMETERS {
        let entry = PyDict::new(py);
        let (kind, words): (&str, &[&str]) = match p.range {
            Range::Integers(..) => ("int", &[]),
            Range::Interval(..) | Range::LengthOver(..) => ("float", &[]),
            Range::Components(..) => ("vector", &[]),
            Range::Flag => ("flag", &[]),
            Range::Words(words) => ("words", words),
            Range::Points => ("points", &[]),
            Range::Program => ("program", &[]),
            Range::BraidWord => ("text", &[]),
        };
        entry.set_item("name", p.name)?;
        entry.set_item("group", group_word(p.group))?;
        entry.set_item("group_title", p.group.title())?;
        entry.set_item("unit", p.unit)?;
        entry.set_item("default", p.default)?;
        entry.set_item("range", p.range_text())?;
        entry.set_item("null", p.null)?;
        entry.set_item("paper", p.paper)?;
        entry.set_item("doc", p.doc)?;
        entry.set_item("description", p.description())?;
        entry.set_item("kind", kind)?;
        entry.set_item("words", words.to_vec())?;
        list.append(entry)?;
    }
    Ok(list)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(parameters, m)?)?;
    m.add("ParameterError", m.py().get_type::<ParameterError>())?;
    m.add("PHYSICS_REVISION", solver::case::PHYSICS_REVISION)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
