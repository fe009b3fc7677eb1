//! Bindings for the linear feedback about a relaxed hover and its outer loop.

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use rfcore::control::relaxed_hover::{
    RelaxedHoverFeedback, RelaxedHoverOuterLoop, RelaxedHoverTrim,
};

use crate::convert::{matrix, slice1, to_py_err};

/// The outer position loop (defaults: the core's).
///
/// Examples:
///
///     >>> from rotorfault.control import RelaxedHoverOuterLoop
///     >>> loop = RelaxedHoverOuterLoop(max_tilt_rad=0.3)
///     >>> loop.max_tilt_rad, loop.position_gain_s2 > 0
///     (0.3, True)
#[pyclass(name = "RelaxedHoverOuterLoop", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyRelaxedHoverOuterLoop {
    pub(crate) inner: RelaxedHoverOuterLoop,
}

#[pymethods]
impl PyRelaxedHoverOuterLoop {
    #[new]
    #[pyo3(signature = (*, position_gain_s2=None, velocity_gain_s=None, max_tilt_rad=None))]
    fn new(
        position_gain_s2: Option<f64>,
        velocity_gain_s: Option<f64>,
        max_tilt_rad: Option<f64>,
    ) -> PyResult<Self> {
        let d = RelaxedHoverOuterLoop::default();
        let inner = RelaxedHoverOuterLoop {
            position_gain_s2: position_gain_s2.unwrap_or(d.position_gain_s2),
            velocity_gain_s: velocity_gain_s.unwrap_or(d.velocity_gain_s),
            max_tilt_rad: max_tilt_rad.unwrap_or(d.max_tilt_rad),
        };
        inner.check().map_err(to_py_err)?;
        Ok(PyRelaxedHoverOuterLoop { inner })
    }
    #[getter]
    fn position_gain_s2(&self) -> f64 {
        self.inner.position_gain_s2
    }
    #[getter]
    fn velocity_gain_s(&self) -> f64 {
        self.inner.velocity_gain_s
    }
    #[getter]
    fn max_tilt_rad(&self) -> f64 {
        self.inner.max_tilt_rad
    }
}

/// `u = u_trim - K x` about a relaxed hover, with the outer loop.
#[pyclass(name = "RelaxedHoverFeedback", module = "rotorfault._rfcore", frozen)]
pub struct PyRelaxedHoverFeedback {
    pub(crate) inner: RelaxedHoverFeedback,
}

#[pymethods]
impl PyRelaxedHoverFeedback {
    #[new]
    #[pyo3(signature = (*, axis, e1, e2, body_rate_rad_s, circle_offset_m, circle_velocity_m_s, gravity_m_s2,
                        u_trim, gain, position_m, outer_loop=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        axis: [f64; 3],
        e1: [f64; 3],
        e2: [f64; 3],
        body_rate_rad_s: [f64; 3],
        circle_offset_m: [f64; 3],
        circle_velocity_m_s: [f64; 3],
        gravity_m_s2: f64,
        u_trim: PyReadonlyArray1<'_, f64>,
        gain: PyReadonlyArray2<'_, f64>,
        position_m: [f64; 3],
        outer_loop: Option<&PyRelaxedHoverOuterLoop>,
    ) -> PyResult<Self> {
        let trim = RelaxedHoverTrim {
            axis,
            e1,
            e2,
            body_rate_rad_s,
            circle_offset_m,
            circle_velocity_m_s,
            gravity_m_s2,
        };
        let outer = outer_loop.map_or_else(RelaxedHoverOuterLoop::default, |o| o.inner);
        let inner = RelaxedHoverFeedback::new(
            &trim,
            slice1("u_trim", &u_trim)?,
            matrix("gain", &gain)?,
            position_m,
            outer,
        )
        .map_err(to_py_err)?;
        Ok(PyRelaxedHoverFeedback { inner })
    }
}

impl crate::control::class::ControllerClass for PyRelaxedHoverFeedback {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
