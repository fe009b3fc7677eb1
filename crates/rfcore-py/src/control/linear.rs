//! Bindings for the linear laws: open loop, state feedback, discrete LTI.

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use rfcore::control::linear::{LinearFeedback, Lti, OpenLoop};

use crate::convert::{matrix, slice1, to_py_err};

/// A piecewise-constant command schedule.
#[pyclass(name = "OpenLoop", module = "rotorfault._rfcore", frozen)]
pub struct PyOpenLoop {
    pub(crate) inner: OpenLoop,
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
        Ok(PyOpenLoop { inner })
    }
}

/// `u = u_trim - K (x - x_trim)`.
#[pyclass(name = "LinearFeedback", module = "rotorfault._rfcore", frozen)]
pub struct PyLinearFeedback {
    pub(crate) inner: LinearFeedback,
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
        Ok(PyLinearFeedback { inner })
    }
}

/// A discrete LTI controller driven by the state error.
#[pyclass(name = "Lti", module = "rotorfault._rfcore", frozen)]
pub struct PyLti {
    pub(crate) inner: Lti,
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
        Ok(PyLti { inner })
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
