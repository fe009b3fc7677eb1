//! Bindings for state feedback on a moving reference with a saturated error.

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use rfcore::control::tracking::TrackingFeedback;

use crate::convert::{matrix, slice1, to_py_err};

/// `u = u_trim - K sat(x - x_ref(t))`.
#[pyclass(name = "TrackingFeedback", module = "rotorfault._rfcore", frozen)]
pub struct PyTrackingFeedback {
    pub(crate) inner: TrackingFeedback,
}

#[pymethods]
impl PyTrackingFeedback {
    #[new]
    #[pyo3(signature = (*, u_trim, gain, times_s, references, error_limit))]
    fn new(
        u_trim: PyReadonlyArray1<'_, f64>,
        gain: PyReadonlyArray2<'_, f64>,
        times_s: PyReadonlyArray1<'_, f64>,
        references: PyReadonlyArray2<'_, f64>,
        error_limit: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let inner = TrackingFeedback::new(
            slice1("u_trim", &u_trim)?,
            matrix("gain", &gain)?,
            slice1("times_s", &times_s)?.to_vec(),
            matrix("references", &references)?,
            slice1("error_limit", &error_limit)?,
        )
        .map_err(to_py_err)?;
        Ok(PyTrackingFeedback { inner })
    }

    /// The reference state at `t_s`.
    fn reference(&self, t_s: f64) -> Vec<f64> {
        self.inner.reference(t_s).to_vec()
    }
}

impl crate::control::class::ControllerClass for PyTrackingFeedback {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
