//! The one conversion layer between Python and the core: core errors to `ValueError`, the GIL
//! helper every heavy call uses, and array views. Every bindings file uses these; none defines
//! its own.

use nalgebra::DMatrix;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use rfcore::RfError;

pub(crate) fn to_py_err(error: RfError) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// Runs `work` with the GIL released and converts core errors: the one helper every heavy call uses.
pub(crate) fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> rfcore::Result<T> + Send,
{
    py.detach(work).map_err(to_py_err)
}

/// Borrows a contiguous 1-D array as a slice, naming the field if it is not contiguous.
pub(crate) fn slice1<'a>(field: &str, array: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a contiguous array")))
}

pub(crate) fn slice2<'a>(field: &str, array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a C-contiguous array")))
}

pub(crate) fn read_only<'py>(py: Python<'py>, values: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    let array = values.into_pyarray(py);
    array.readwrite().make_nonwriteable();
    array
}

pub(crate) fn matrix(field: &str, array: &PyReadonlyArray2<'_, f64>) -> PyResult<DMatrix<f64>> {
    let view = array.as_array();
    let (rows, cols) = view.dim();
    let flat: Vec<f64> = view.iter().copied().collect();
    if flat.len() != rows * cols {
        return Err(PyValueError::new_err(format!("{field}: malformed array")));
    }
    Ok(DMatrix::from_row_slice(rows, cols, &flat))
}

// -- settings classes: one protocol for the named settings Python uses directly ----------------

/// A real number for field `field`, by Python's rule (`numbers.Real`, not a bool): anything else
/// is a `TypeError` naming the field; the value rules are the core's `check`s.
pub(crate) fn real(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    use pyo3::types::PyBool;
    let real_type = value.py().import("numbers")?.getattr("Real")?;
    if value.is_instance_of::<PyBool>() || !value.is_instance(&real_type)? {
        return Err(PyTypeError::new_err(format!(
            "{field}: expected a real number, got {}",
            value.get_type().name()?
        )));
    }
    value.extract::<f64>().map_err(|_| {
        PyValueError::new_err(format!("{field}: must be finite, got a number too large for a float"))
    })
}

/// The field values of a settings object, by name.
fn field_values<'py>(obj: &Bound<'py, PyAny>, fields: &[&str]) -> PyResult<Vec<Bound<'py, PyAny>>> {
    fields.iter().map(|f| obj.getattr(*f)).collect()
}

/// `Name(field=value, ...)`, as a dataclass prints.
pub(crate) fn settings_repr(obj: &Bound<'_, PyAny>, fields: &[&str]) -> PyResult<String> {
    let parts: PyResult<Vec<String>> = fields
        .iter()
        .map(|f| Ok(format!("{f}={}", obj.getattr(*f)?.repr()?)))
        .collect();
    Ok(format!("{}({})", obj.get_type().name()?, parts?.join(", ")))
}

/// Equal type and equal fields (NaN fields compare unequal, as floats do).
pub(crate) fn settings_eq(a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>, fields: &[&str]) -> PyResult<bool> {
    if !b.get_type().is(&a.get_type()) {
        return Ok(false);
    }
    for f in fields {
        if !a.getattr(*f)?.eq(b.getattr(*f)?)? {
            return Ok(false);
        }
    }
    Ok(true)
}

/// The hash of the field values (equal settings hash equal; frozen, so usable as keys).
pub(crate) fn settings_hash(obj: &Bound<'_, PyAny>, fields: &[&str]) -> PyResult<isize> {
    PyTuple::new(obj.py(), field_values(obj, fields)?)?.hash()
}

/// Every field as a keyword argument (the constructor takes them back: copies and pickling).
pub(crate) fn settings_kwargs<'py>(obj: &Bound<'py, PyAny>, fields: &[&str]) -> PyResult<Bound<'py, PyDict>> {
    let kwargs = PyDict::new(obj.py());
    for f in fields {
        kwargs.set_item(*f, obj.getattr(*f)?)?;
    }
    Ok(kwargs)
}

/// A copy with some fields changed, validated as a new object is (an unknown field is a
/// `TypeError` naming it and the fields).
pub(crate) fn settings_replace<'py>(
    obj: &Bound<'py, PyAny>,
    fields: &[&str],
    changes: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let kwargs = settings_kwargs(obj, fields)?;
    if let Some(changes) = changes {
        for (key, value) in changes.iter() {
            let name: String = key.extract()?;
            if !fields.contains(&name.as_str()) {
                return Err(PyTypeError::new_err(format!(
                    "{name}: not a field of {} (fields: {})",
                    obj.get_type().name()?,
                    fields.join(", ")
                )));
            }
            kwargs.set_item(name, value)?;
        }
    }
    obj.get_type().call((), Some(&kwargs)).map(|o| o.into_any())
}
