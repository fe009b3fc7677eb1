//! Bindings for controllers: every built-in controller class, the one conversion of a controller
//! argument into a core controller (`boxed`), a Python callable as the slow path, the allocating
//! controller and replay. Translation only.

pub(crate) mod class;
pub(crate) mod indi;
pub(crate) mod ke;
pub(crate) mod lanzon;
pub(crate) mod linear;
pub(crate) mod relaxed_hover;
pub(crate) mod tracking;

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyType;

use rfcore::allocation::active_set::ActiveSetSolver;
use rfcore::control::{replay as core_replay, Allocated, Controller, ZeroCommand};
use rfcore::state::{
    state_vector, states_from_vector_rows, RigidBodyState, PACKED_DIM, STATE_DIM,
};
use rfcore::RfError;

use crate::allocation::PyAllocationProblem;
use crate::convert::{detached, slice1, slice2, to_py_err};
pub(crate) use class::ControllerClass;
use indi::PyIndiController;
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


/// The one registry of the Rust controllers the simulator runs (in a loop or a batch): each line
/// `Variant(PyClass) = "kebab-name"` (the name is the class name in kebab case) makes the
/// `ControllerArg` variant every call accepts, the arm of `boxed`, and the `(name, class)` pair
/// Python reads as `rotorfault._rfcore.CONTROLLERS`, from which `rotorfault._typing`, the batch
/// type check and `docs/adding-a-controller.md` are derived (and checked by tests). Adding a
/// controller: `docs/adding-a-controller.md`.
macro_rules! controller_registry {
    ($($variant:ident($class:ty) = $name:literal),+ $(,)?) => {
        /// A built-in controller passed from Python: any class of the registry.
        #[derive(FromPyObject)]
        pub enum ControllerArg<'py> {
            $($variant(PyRef<'py, $class>)),+
        }

        impl ControllerArg<'_> {
            fn core(&self) -> PyResult<Box<dyn Controller>> {
                match self {
                    $(ControllerArg::$variant(c) => c.core(c.py())),+
                }
            }
        }

        /// `(name, class)` of every registered controller, in declaration order.
        pub(crate) fn registry(py: Python<'_>) -> Vec<(&'static str, Bound<'_, PyType>)> {
            vec![$(($name, py.get_type::<$class>())),+]
        }
    };
}

controller_registry! {
    OpenLoop(PyOpenLoop) = "open-loop",
    LinearFeedback(PyLinearFeedback) = "linear-feedback",
    Lti(PyLti) = "lti",
    Allocated(PyAllocated) = "allocated",
    UniformPassiveFtc(PyUniformPassiveFtc) = "uniform-passive-ftc",
    LanzonController(PyLanzonController) = "lanzon-controller",
    TrackingFeedback(PyTrackingFeedback) = "tracking-feedback",
    IndiController(PyIndiController) = "indi-controller",
    RelaxedHoverFeedback(PyRelaxedHoverFeedback) = "relaxed-hover-feedback",
}

/// The core controller for one run: `None` holds every command at zero.
pub(crate) fn boxed(
    controller: Option<&ControllerArg<'_>>,
    count: usize,
) -> PyResult<Box<dyn Controller>> {
    match controller {
        None => Ok(Box::new(ZeroCommand { count })),
        Some(c) => c.core(),
    }
}

/// A virtual-control law followed by active-set allocation. The law is kept as the Python
/// object and turned into a fresh core controller per run by the one `boxed` conversion.
#[pyclass(name = "Allocated", module = "rotorfault._rfcore", frozen)]
pub struct PyAllocated {
    law: Py<PyAny>,
    solver: ActiveSetSolver,
}

impl ControllerClass for PyAllocated {
    /// A fresh controller for one run.
    fn core(&self, py: Python<'_>) -> PyResult<Box<dyn Controller>> {
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
        out.core(py)?; // checks the law's output count
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
    let flat = detached(py, |cancel| {
        core_replay(controller.as_mut(), &times, &parsed, cancel)
    })?;
    numpy::ndarray::Array2::from_shape_vec((rows, count), flat)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| PyValueError::new_err(format!("internal shape error: {e}")))
}
