//! Bindings for the linear feedback about a relaxed hover and its outer loop.

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use rfcore::control::hover_handover::{
    relaxed_hover_handover, IntegralHover, RelaxedHoverHandover,
};
use rfcore::control::relaxed_hover::{
    RelaxedHoverFeedback, RelaxedHoverOuterLoop, RelaxedHoverTrim,
};
use rfcore::control::switch::FailureTimeSwitch;
use rfcore::control::LinearFeedback;

use super::linear::PyLinearFeedback;
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

impl PyRelaxedHoverOuterLoop {
    const FIELDS: &'static [&'static str] = &[
        "position_gain_s2",
        "velocity_gain_s",
        "max_tilt_rad",
        "integral_gain_s3",
        "altitude_integral_gain_s",
    ];
}

crate::convert::pickle_protocol!(PyRelaxedHoverOuterLoop, {
    #[new]
    #[pyo3(signature = (*, position_gain_s2=None, velocity_gain_s=None, max_tilt_rad=None, integral_gain_s3=None, altitude_integral_gain_s=None))]
    fn new(
        position_gain_s2: Option<f64>,
        velocity_gain_s: Option<f64>,
        max_tilt_rad: Option<f64>,
        integral_gain_s3: Option<f64>,
        altitude_integral_gain_s: Option<f64>,
    ) -> PyResult<Self> {
        let d = RelaxedHoverOuterLoop::default();
        let inner = RelaxedHoverOuterLoop {
            position_gain_s2: position_gain_s2.unwrap_or(d.position_gain_s2),
            velocity_gain_s: velocity_gain_s.unwrap_or(d.velocity_gain_s),
            max_tilt_rad: max_tilt_rad.unwrap_or(d.max_tilt_rad),
            integral_gain_s3: integral_gain_s3.unwrap_or(d.integral_gain_s3),
            altitude_integral_gain_s: altitude_integral_gain_s
                .unwrap_or(d.altitude_integral_gain_s),
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
    /// `k_i` on the circle centre's horizontal error, 1/s^3 (0: no integral action).
    #[getter]
    fn integral_gain_s3(&self) -> f64 {
        self.inner.integral_gain_s3
    }
    /// `k_z` on the altitude error, 1/s (0: no integral action).
    #[getter]
    fn altitude_integral_gain_s(&self) -> f64 {
        self.inner.altitude_integral_gain_s
    }
});

/// `u = u_trim - K x` about a relaxed hover, with the outer loop; with `before_failure` and
/// `failure_time_s`, the healthy-vehicle design flies until the failure time (a failure-time switch);
/// with `before_failure_integral_gain` too, the healthy design has integral action on the position
/// error and hands its integrals over (`rfcore::control::hover_handover`).
#[pyclass(name = "RelaxedHoverFeedback", module = "rotorfault._rfcore", frozen)]
pub struct PyRelaxedHoverFeedback {
    pub(crate) inner: RelaxedHoverFeedback,
    before_failure: Option<(LinearFeedback, f64)>,
    handover: Option<RelaxedHoverHandover>,
}

#[pymethods]
impl PyRelaxedHoverFeedback {
    #[new]
    #[pyo3(signature = (*, axis, e1, e2, body_rate_rad_s, circle_offset_m, circle_velocity_m_s, gravity_m_s2,
                        u_trim, gain, position_m, outer_loop=None, before_failure=None, failure_time_s=None,
                        before_failure_integral_gain=None, before_failure_integral_limit_m_s=None,
                        handover_altitude_ratio=None, handover_horizontal_ratio=None))]
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
        before_failure: Option<PyRef<'_, PyLinearFeedback>>,
        failure_time_s: Option<f64>,
        before_failure_integral_gain: Option<PyReadonlyArray2<'_, f64>>,
        before_failure_integral_limit_m_s: Option<[f64; 3]>,
        handover_altitude_ratio: Option<f64>,
        handover_horizontal_ratio: Option<PyReadonlyArray2<'_, f64>>,
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
        let before_failure = match (before_failure, failure_time_s) {
            (None, None) => None,
            (Some(h), Some(t)) => {
                // Built once here so that a bad pair is refused at construction, not per run.
                FailureTimeSwitch::new(Box::new(h.inner.clone()), Box::new(inner.clone()), t)
                    .map_err(to_py_err)?;
                Some((h.inner.clone(), t))
            }
            _ => {
                return Err(to_py_err(rfcore::error::RfError::invalid(
                    "before_failure, failure_time_s",
                    "give both (the healthy-vehicle design and when it hands over) or neither",
                )))
            }
        };
        let handover = match (
            &before_failure,
            before_failure_integral_gain,
            before_failure_integral_limit_m_s,
            handover_altitude_ratio,
            handover_horizontal_ratio,
        ) {
            (_, None, None, None, None) => None,
            (Some((h, t)), Some(gain), Some(limit), Some(ratio), Some(horizontal)) => {
                let horizontal = matrix("handover_horizontal_ratio", &horizontal)?;
                if horizontal.shape() != (2, 2) {
                    return Err(to_py_err(rfcore::error::RfError::shape(
                        "handover_horizontal_ratio",
                        "2 x 2 (north, east)",
                        format!("{} x {}", horizontal.nrows(), horizontal.ncols()),
                    )));
                }
                let horizontal = [
                    [horizontal[(0, 0)], horizontal[(0, 1)]],
                    [horizontal[(1, 0)], horizontal[(1, 1)]],
                ];
                let setpoint = h.trim_position_m();
                let before = IntegralHover::new(
                    h.clone(),
                    matrix("before_failure_integral_gain", &gain)?,
                    setpoint,
                    limit,
                )
                .map_err(to_py_err)?;
                Some(
                    relaxed_hover_handover(before, inner.clone(), *t, ratio, horizontal)
                        .map_err(to_py_err)?,
                )
            }
            _ => {
                return Err(to_py_err(rfcore::error::RfError::invalid(
                    "before_failure_integral_gain, before_failure_integral_limit_m_s, handover_altitude_ratio, handover_horizontal_ratio",
                    "give all four with before_failure and failure_time_s, or none",
                )))
            }
        };
        Ok(PyRelaxedHoverFeedback {
            inner,
            before_failure,
            handover,
        })
    }
    /// When the healthy-vehicle design hands over, s (`None`: no switch).
    #[getter]
    fn failure_time_s(&self) -> Option<f64> {
        self.before_failure.as_ref().map(|(_, t)| *t)
    }
}

impl crate::control::class::ControllerClass for PyRelaxedHoverFeedback {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        if let Some(handover) = &self.handover {
            return Ok(Box::new(handover.clone()));
        }
        let relaxed = Box::new(self.inner.clone());
        match &self.before_failure {
            None => Ok(relaxed),
            Some((before, t)) => Ok(Box::new(
                FailureTimeSwitch::new(Box::new(before.clone()), relaxed, *t).map_err(to_py_err)?,
            )),
        }
    }
}
