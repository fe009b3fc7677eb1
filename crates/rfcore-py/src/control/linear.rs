//! Bindings for the linear laws: open loop, state feedback, discrete LTI.

use numpy::{IntoPyArray, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use rfcore::control::linear::{LinearFeedback, Lti, OpenLoop};

use crate::convert::{matrix, read_only, slice1, to_py_err};

/// A copy of a constructor's array (what pickling gives back: the values the law was made from,
/// whatever happens to the caller's array afterwards).
/// Read-only, so a caller changing `__getnewargs__()`'s arrays cannot make a pickle that loads
/// other values than the live law flies.
fn copy1<'py>(py: Python<'py>, a: &PyReadonlyArray1<'py, f64>) -> Bound<'py, PyAny> {
    read_only(py, a.as_array().to_vec()).into_any()
}

fn copy2<'py>(py: Python<'py>, a: &PyReadonlyArray2<'py, f64>) -> Bound<'py, PyAny> {
    let array = a.as_array().to_owned().into_pyarray(py);
    array.readwrite().make_nonwriteable();
    array.into_any()
}

/// A piecewise-constant command schedule.
#[pyclass(name = "OpenLoop", module = "rotorfault._rfcore", frozen)]
pub struct PyOpenLoop {
    pub(crate) inner: OpenLoop,
    /// The constructor's arguments (copies), for pickling.
    args: Py<PyTuple>,
}

#[pymethods]
impl PyOpenLoop {
    #[new]
    fn new(
        times_s: PyReadonlyArray1<'_, f64>,
        commands: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Self> {
        let inner = OpenLoop::new(
            slice1("times", &times_s)?.to_vec(),
            matrix("commands", &commands)?,
        )
        .map_err(to_py_err)?;
        let py = times_s.py();
        let args = PyTuple::new(py, [copy1(py, &times_s), copy2(py, &commands)])?.unbind();
        Ok(PyOpenLoop { inner, args })
    }
    /// Pickled as the arrays it was made from.
    fn __getnewargs__(&self, py: Python<'_>) -> Py<PyTuple> {
        self.args.clone_ref(py)
    }
}

/// `u = u_trim - K (x - x_trim)`.
#[pyclass(name = "LinearFeedback", module = "rotorfault._rfcore", frozen)]
pub struct PyLinearFeedback {
    pub(crate) inner: LinearFeedback,
    /// The constructor's arguments (copies), for pickling.
    args: Py<PyTuple>,
}

#[pymethods]
impl PyLinearFeedback {
    #[new]
    fn new(
        x_trim: PyReadonlyArray1<'_, f64>,
        u_trim: PyReadonlyArray1<'_, f64>,
        gain: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Self> {
        let inner = LinearFeedback::new(
            slice1("x_trim", &x_trim)?,
            slice1("u_trim", &u_trim)?,
            matrix("gain", &gain)?,
        )
        .map_err(to_py_err)?;
        let py = gain.py();
        let args = PyTuple::new(py, [copy1(py, &x_trim), copy1(py, &u_trim), copy2(py, &gain)])?.unbind();
        Ok(PyLinearFeedback { inner, args })
    }
    /// Pickled as the arrays it was made from.
    fn __getnewargs__(&self, py: Python<'_>) -> Py<PyTuple> {
        self.args.clone_ref(py)
    }
}

/// A discrete LTI controller driven by the state error.
#[pyclass(name = "Lti", module = "rotorfault._rfcore", frozen)]
pub struct PyLti {
    pub(crate) inner: Lti,
    /// The constructor's arguments (copies), for pickling.
    args: Py<PyTuple>,
}

#[pymethods]
impl PyLti {
    #[new]
    fn new(
        a: PyReadonlyArray2<'_, f64>,
        b: PyReadonlyArray2<'_, f64>,
        c: PyReadonlyArray2<'_, f64>,
        d: PyReadonlyArray2<'_, f64>,
        x_trim: PyReadonlyArray1<'_, f64>,
        u_trim: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let inner = Lti::new(
            matrix("A_K", &a)?,
            matrix("B_K", &b)?,
            matrix("C_K", &c)?,
            matrix("D_K", &d)?,
            slice1("x_trim", &x_trim)?,
            slice1("u_trim", &u_trim)?,
        )
        .map_err(to_py_err)?;
        let py = a.py();
        let args = PyTuple::new(
            py,
            [copy2(py, &a), copy2(py, &b), copy2(py, &c), copy2(py, &d), copy1(py, &x_trim), copy1(py, &u_trim)],
        )?
        .unbind();
        Ok(PyLti { inner, args })
    }
    /// Pickled as the arrays it was made from.
    fn __getnewargs__(&self, py: Python<'_>) -> Py<PyTuple> {
        self.args.clone_ref(py)
    }
}

impl crate::control::class::ControllerClass for PyOpenLoop {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}

impl crate::control::class::ControllerClass for PyLinearFeedback {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}

impl crate::control::class::ControllerClass for PyLti {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
