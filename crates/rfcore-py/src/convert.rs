//! The one conversion layer between Python and the core: core errors to `ValueError`, the GIL
//! helper every heavy call uses, and array views. Every bindings file uses these; none defines
//! its own.

use nalgebra::DMatrix;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

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
