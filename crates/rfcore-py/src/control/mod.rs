//! Bindings for controllers: every built-in controller class, the one conversion of a controller
//! argument into a core controller (`boxed`), a Python callable as the slow path, the allocating
//! controller and replay. Translation only.

pub(crate) mod ke;
pub(crate) mod lanzon;
pub(crate) mod linear;
pub(crate) mod relaxed_hover;
pub(crate) mod tracking;

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use rfcore::allocation::active_set::ActiveSetSolver;
use rfcore::control::{replay as core_replay, Allocated, Controller, ZeroCommand};
use rfcore::state::{
    state_vector, states_from_vector_rows, RigidBodyState, PACKED_DIM, STATE_DIM,
};
use rfcore::RfError;

use crate::allocation::PyAllocationProblem;
use crate::convert::{detached, slice1, slice2, to_py_err};
use ke::PyUniformPassiveFtc;
use lanzon::PyLanzonController;
use linear::{PyLinearFeedback, PyLti, PyOpenLoop};
use relaxed_hover::PyRelaxedHoverFeedback;
use tracking::PyTrackingFeedback;

/// A Python function `f(t, x) -> commands` (x: the 12-element state vector): the slow path.
pub(crate) struct CallableController {
    pub(crate) function: Py<PyAny>,
    pub(crate) count: usize,
    pub(crate) error: Option<PyErr>,
}

impl Controller for CallableController {
    fn command_count(&self) -> usize {
        self.count
    }

    fn command(
        &mut self,
        t_s: f64,
        measured: &RigidBodyState,
        out: &mut [f64],
    ) -> rfcore::Result<()> {
        let result = Python::attach(|py| -> PyResult<Vec<f64>> {
            let x = state_vector(measured).to_vec().into_pyarray(py);
            self.function
                .bind(py)
                .call1((t_s, x))?
                .extract::<Vec<f64>>()
        });
        match result {
            // A non-finite command is a divergence, not an exception: the simulator ends the run
            // with a `non-finite-command` event at this step (as for every controller).
            Ok(values) if values.len() == out.len() => {
                out.copy_from_slice(&values);
                Ok(())
            }
            Ok(values) => Err(RfError::invalid(
                "controller",
                format!(
                    "the Python controller must return {} commands, got {} at t = {t_s}",
                    out.len(),
                    values.len()
                ),
            )),
            Err(err) => {
                // A wrong return type is the controller's contract, not its own exception.
                let wrong_type = Python::attach(|py| err.is_instance_of::<pyo3::exceptions::PyTypeError>(py));
                self.error = Some(if wrong_type {
                    let error = pyo3::exceptions::PyTypeError::new_err(format!(
                        "controller: must return a sequence of {} numbers at t = {t_s}",
                        out.len()
                    ));
                    Python::attach(|py| error.set_cause(py, Some(err)));
                    error
                } else {
                    err
                });
                Err(RfError::invalid("controller", "the Python controller failed"))
            }
        }
    }
}

#[derive(FromPyObject)]
pub enum ControllerArg<'py> {
    OpenLoop(PyRef<'py, PyOpenLoop>),
    LinearFeedback(PyRef<'py, PyLinearFeedback>),
    Lti(PyRef<'py, PyLti>),
    Allocated(PyRef<'py, PyAllocated>),
    Ftc(PyRef<'py, PyUniformPassiveFtc>),
    Lanzon(PyRef<'py, PyLanzonController>),
    Tracking(PyRef<'py, PyTrackingFeedback>),
    RelaxedHover(PyRef<'py, PyRelaxedHoverFeedback>),
}

pub(crate) fn boxed(
    controller: Option<&ControllerArg<'_>>,
    count: usize,
) -> PyResult<Box<dyn Controller>> {
    Ok(match controller {
        None => Box::new(ZeroCommand { count }),
        Some(ControllerArg::OpenLoop(c)) => Box::new(c.inner.clone()),
        Some(ControllerArg::LinearFeedback(c)) => Box::new(c.inner.clone()),
        Some(ControllerArg::Lti(c)) => Box::new(c.inner.clone()),
        Some(ControllerArg::Allocated(c)) => c.controller(c.py())?,
        Some(ControllerArg::Ftc(c)) => Box::new(c.inner.clone()),
        Some(ControllerArg::Lanzon(c)) => Box::new(c.inner.clone()),
        Some(ControllerArg::Tracking(c)) => Box::new(c.inner.clone()),
        Some(ControllerArg::RelaxedHover(c)) => Box::new(c.inner.clone()),
    })
}

/// A virtual-control law followed by active-set allocation. The law is kept as the Python
/// object and turned into a fresh core controller per run by the one `boxed` conversion.
#[pyclass(name = "Allocated", module = "rotorfault._rfcore", frozen)]
pub struct PyAllocated {
    law: Py<PyAny>,
    solver: ActiveSetSolver,
}

impl PyAllocated {
    /// A fresh controller for one run.
    pub(crate) fn controller(&self, py: Python<'_>) -> PyResult<Box<dyn Controller>> {
        let law: ControllerArg = self.law.bind(py).extract()?;
        let law = boxed(Some(&law), 0)?;
        Ok(Box::new(
            Allocated::new(law, self.solver.clone()).map_err(to_py_err)?,
        ))
    }
}

#[pymethods]
impl PyAllocated {
    #[new]
    fn new(law: Bound<'_, PyAny>, problem: &PyAllocationProblem) -> PyResult<Self> {
        let kind: Option<ControllerArg> = law.extract().ok();
        if !matches!(
            kind,
            Some(
                ControllerArg::OpenLoop(_)
                    | ControllerArg::LinearFeedback(_)
                    | ControllerArg::Lti(_)
            )
        ) {
            return Err(PyTypeError::new_err(
                "law: expected OpenLoop, LinearFeedback or Lti (a virtual-control law)",
            ));
        }
        let py = law.py();
        let out = PyAllocated {
            law: law.unbind(),
            solver: problem.solver.clone(),
        };
        out.controller(py)?; // checks the law's output count
        Ok(out)
    }
}

/// Commands of a controller replayed on `states` at `times` (N): an N x command_count array.
/// `states` is N x 13 (position, velocity, quaternion w x y z, body rates: a recorded true state)
/// or N x 12 (the state vector with Euler angles: a recorded measurement, converted to a state as
/// the simulator converts it).
#[pyfunction]
pub fn replay<'py>(
    py: Python<'py>,
    controller: ControllerArg<'py>,
    times: PyReadonlyArray1<'py, f64>,
    states: PyReadonlyArray2<'py, f64>,
    command_count: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let times = slice1("times", &times)?.to_vec();
    let columns = states.shape()[1];
    let rows = slice2("states", &states)?;
    let parsed = match columns {
        PACKED_DIM => RigidBodyState::from_packed_rows("states", rows),
        STATE_DIM => states_from_vector_rows("states", rows),
        _ => {
            return Err(PyValueError::new_err(format!(
                "states: expected {PACKED_DIM} columns (position, velocity, quaternion w x y z, rates) \
                 or {STATE_DIM} (position, velocity, roll pitch yaw, rates), got {columns}"
            )))
        }
    }
    .map_err(to_py_err)?;
    let mut controller = boxed(Some(&controller), command_count)?;
    let rows = times.len();
    let count = controller.command_count();
    let flat = detached(py, || core_replay(controller.as_mut(), &times, &parsed))?;
    numpy::ndarray::Array2::from_shape_vec((rows, count), flat)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| PyValueError::new_err(format!("internal shape error: {e}")))
}
