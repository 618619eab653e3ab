//! The model's typed errors as Python exceptions: each `finger_model::Error` becomes an
//! instance of its class in `softfinger/errors.py` (a `FingerError` subclass) carrying the
//! variant's fields by name, its `kind` (the variant) and `code` (the console's error code).
//! Not here: the exception classes themselves (Python, so that one can also be a ValueError).
use finger_model::Error;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The exception class of each variant (`softfinger.errors`).
fn class_of(e: &Error) -> &'static str {
    match e {
        Error::VoltageCeiling { .. } | Error::PullIn { .. } => "VoltageCeilingError",
        Error::ThicknessLimit { .. } => "ThicknessLimitError",
        Error::Unreachable { .. } => "UnreachableError",
        Error::NotConverged { .. } => "NotConvergedError",
        Error::Param { .. } | Error::NonFinite { .. } | Error::Input { .. } => "InputError",
        Error::Contact { .. } | Error::LimitPoint { .. } | Error::ForceLimit { .. } => "BranchEndError",
        Error::Singular { .. } | Error::PullingStop { .. } => "FingerError",
        // a variant this package does not know yet: the base class, its text in `detail`
        #[allow(unreachable_patterns)]
        _ => "FingerError",
    }
}

/// The variant's name and fields.
fn fields<'py>(py: Python<'py>, e: &Error) -> PyResult<(&'static str, Bound<'py, PyDict>)> {
    let d = PyDict::new(py);
    let kind = match *e {
        Error::Param { name, range } => {
            d.set_item("name", name)?;
            d.set_item("range", range)?;
            "Param"
        }
        Error::NonFinite { input } => {
            d.set_item("input", input)?;
            "NonFinite"
        }
        Error::Input { input, reason } => {
            d.set_item("input", input)?;
            d.set_item("reason", reason)?;
            "Input"
        }
        Error::VoltageCeiling { joint, volts, ceiling } => {
            d.set_item("joint", joint)?;
            d.set_item("volts", volts)?;
            d.set_item("ceiling", ceiling)?;
            "VoltageCeiling"
        }
        Error::PullIn { volts, pull_in } => {
            d.set_item("volts", volts)?;
            d.set_item("pull_in", pull_in)?;
            "PullIn"
        }
        Error::ThicknessLimit { joint, requested_mm, limit_mm } => {
            d.set_item("joint", joint)?;
            d.set_item("requested_mm", requested_mm)?;
            d.set_item("limit_mm", limit_mm)?;
            "ThicknessLimit"
        }
        Error::Contact { joint, tension } => {
            d.set_item("joint", joint)?;
            d.set_item("tension", tension)?;
            "Contact"
        }
        Error::LimitPoint { joint, tension } => {
            d.set_item("joint", joint)?;
            d.set_item("tension", tension)?;
            "LimitPoint"
        }
        Error::ForceLimit { tension, fmax } => {
            d.set_item("tension", tension)?;
            d.set_item("fmax", fmax)?;
            "ForceLimit"
        }
        Error::PullingStop { tension, force } => {
            d.set_item("tension", tension)?;
            d.set_item("force", force)?;
            "PullingStop"
        }
        Error::NotConverged { iterations, residual } => {
            d.set_item("iterations", iterations)?;
            d.set_item("residual", residual)?;
            "NotConverged"
        }
        Error::Singular { what } => {
            d.set_item("what", what)?;
            "Singular"
        }
        Error::Unreachable { joint, needed, min, max } => {
            d.set_item("joint", joint)?;
            d.set_item("needed", needed)?;
            d.set_item("min", min)?;
            d.set_item("max", max)?;
            "Unreachable"
        }
        #[allow(unreachable_patterns)]
        _ => {
            d.set_item("detail", format!("{e:?}"))?;
            "Other"
        }
    };
    Ok((kind, d))
}

fn build(py: Python<'_>, e: Error, index: Option<usize>) -> PyErr {
    let make = || -> PyResult<PyErr> {
        let cls = py.import("softfinger.errors")?.getattr(class_of(&e))?;
        let (kind, kw) = fields(py, &e)?;
        kw.set_item("kind", kind)?;
        kw.set_item("code", e.code().as_str())?;
        if let Some(i) = index {
            kw.set_item("index", i)?;
        }
        let msg = match index {
            Some(i) => format!("row {i}: {e}"),
            None => e.to_string(),
        };
        Ok(PyErr::from_value(cls.call((msg,), Some(&kw))?))
    };
    make().unwrap_or_else(|err| err)
}

/// The model error as its Python exception, with `msg` for its message.
pub fn model_err_msg(e: Error, msg: String) -> PyErr {
    Python::attach(|py| {
        let make = || -> PyResult<PyErr> {
            let cls = py.import("softfinger.errors")?.getattr(class_of(&e))?;
            let (kind, kw) = fields(py, &e)?;
            kw.set_item("kind", kind)?;
            kw.set_item("code", e.code().as_str())?;
            Ok(PyErr::from_value(cls.call((msg,), Some(&kw))?))
        };
        make().unwrap_or_else(|err| err)
    })
}

/// `pose` of a negative joint angle: `UnreachableError` (kind `Extension`, fields `joint`,
/// `angle_deg`) in the firmware's words (src/app/pose.rs).
pub fn extension_err(joint: usize, angle_deg: f64) -> PyErr {
    Python::attach(|py| {
        let make = || -> PyResult<PyErr> {
            let cls = py.import("softfinger.errors")?.getattr("UnreachableError")?;
            let kw = PyDict::new(py);
            kw.set_item("kind", "Extension")?;
            kw.set_item("code", "unreachable")?;
            kw.set_item("joint", joint)?;
            kw.set_item("angle_deg", angle_deg)?;
            let msg = format!("joint {joint}: {angle_deg:.3} deg is an extension; the cable only flexes the joints (angles >= 0)");
            Ok(PyErr::from_value(cls.call((msg,), Some(&kw))?))
        };
        make().unwrap_or_else(|err| err)
    })
}

/// The model error as its Python exception.
pub fn model_err(e: Error) -> PyErr {
    Python::attach(|py| build(py, e, None))
}

/// The model error of row `index` of a `solve_many` (the exception's `index`).
pub fn row_err(py: Python<'_>, e: Error, index: usize) -> PyErr {
    build(py, e, Some(index))
}

/// Nothing to register: the classes live in Python. Kept so the module's init names every part.
pub fn register(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
