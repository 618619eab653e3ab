//! A board's reply lines read by the console protocol crate (`finger-protocol`, the one parser
//! of docs/console.md's grammar): `softfinger/board.py` takes its final lines, error codes and
//! fields from here, and writes no parser of its own.
use finger_protocol::reply::{Fields, Item, Reply};
use finger_protocol::Value;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// A field's value for Python: a float, a tuple of floats (comma-separated numbers), else its
/// text (`-`, a word, a list with a word in it).
fn value<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    match Value::of_syntax(text) {
        Value::Number(x) => Ok(x.into_pyobject(py)?.into_any()),
        Value::List(l) => match l.items().map(|i| i.number()).collect::<Option<Vec<f64>>>() {
            Some(v) => Ok(PyTuple::new(py, v)?.into_any()),
            None => Ok(text.into_pyobject(py)?.into_any()),
        },
        Value::Missing | Value::Word(_) => Ok(text.into_pyobject(py)?.into_any()),
    }
}

/// A final reply line: `("ok",)`, `("err", code, message)`, or `None` for a line before
/// a final one.
#[pyfunction]
pub fn _reply_final<'py>(py: Python<'py>, line: &str) -> PyResult<Option<Bound<'py, PyTuple>>> {
    use finger_protocol::reply::Error;
    Ok(match Reply::parse(line) {
        Ok(Reply::Ok(_)) | Err(Error::BadValue | Error::NotAField) => Some(PyTuple::new(py, ["ok"])?),
        Ok(Reply::Err { code, message }) => Some(PyTuple::new(py, ["err", code.as_str(), message])?),
        Err(Error::NoCode) => Some(PyTuple::new(py, ["err", line.strip_prefix("err ").unwrap_or(line).trim(), ""])?),
        Err(Error::NotFinal) => None,
    })
}

/// The `key=value` fields of a line, each value as [`value`] reads it (the words before any
/// field, `ok`'s, skipped).
#[pyfunction]
pub fn _reply_fields<'py>(py: Python<'py>, line: &str) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in Fields::new(line).pairs() {
        d.set_item(k, value(py, v)?)?;
    }
    Ok(d)
}

/// `key`'s comma-separated numbers, a component not measured yet (`-`) as NaN; `None` without
/// `key`, or when a component is a word.
#[pyfunction]
pub fn _reply_measured(line: &str, key: &str) -> Option<Vec<f64>> {
    let text = Fields::new(line).text(key)?;
    let items: Vec<Item> = match Value::of_syntax(text) {
        Value::List(l) => l.items().collect(),
        Value::Number(x) => vec![Item::Number(x)],
        Value::Missing => vec![Item::Missing],
        Value::Word(_) => return None,
    };
    items.into_iter().map(|i| if i == Item::Missing { Some(f64::NAN) } else { i.number() }).collect()
}
