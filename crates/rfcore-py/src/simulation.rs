//! Bindings for the simulator: actuator and controller specifications as Python classes, one
//! `simulate` call per run and a parallel `simulate_batch`. Translation only.

use nalgebra::{DMatrix, Quaternion, UnitQuaternion, Vector3};
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::actuator::{Actuators, FixedPitch, Lag, VariablePitch};
use rfcore::controller::{
    state_vector, state_vector_derivative, Controller, DiscreteLti, LinearFeedback, OpenLoop,
    ZeroCommand, STATE_DIM,
};
use rfcore::rigid_body::RigidBodyState;
use rfcore::simulation::{
    simulate as core_simulate, simulate_batch as core_batch, BatchRun, DivergenceLimits,
    RotorFault, SensorNoise, SimulationConfig, Trajectory,
};
use rfcore::vehicle::{Aerodynamics, Vehicle};
use rfcore::RfError;

use crate::allocation::PyAllocated;
use crate::ftc::PyUniformPassiveFtc;
use crate::{detached, slice1, to_py_err, PyAirframe};

pub(crate) fn matrix(field: &str, array: &PyReadonlyArray2<'_, f64>) -> PyResult<DMatrix<f64>> {
    let view = array.as_array();
    let (rows, cols) = view.dim();
    let flat: Vec<f64> = view.iter().copied().collect();
    if flat.len() != rows * cols {
        return Err(PyValueError::new_err(format!("{field}: malformed array")));
    }
    Ok(DMatrix::from_row_slice(rows, cols, &flat))
}

/// Fixed-pitch rotors: first-order lag, rate limit, thrust coefficient for rotor speed.
#[pyclass(name = "FixedPitchActuator", module = "rotorfault._rfcore", frozen)]
pub struct PyFixedPitch {
    lag: Lag,
    thrust_coefficient_n_s2: f64,
}

#[pymethods]
impl PyFixedPitch {
    #[new]
    fn new(time_constant_s: f64, rate_limit_per_s: f64, thrust_coefficient_n_s2: f64) -> Self {
        PyFixedPitch {
            lag: Lag {
                time_constant_s,
                rate_limit_per_s,
            },
            thrust_coefficient_n_s2,
        }
    }
}

/// Variable-pitch propellers (Wang et al. eq. (3)).
#[pyclass(name = "VariablePitchActuator", module = "rotorfault._rfcore", frozen)]
pub struct PyVariablePitch {
    coefficients: [f64; 4],
    speed_bounds: (f64, f64),
    pitch_bounds: (f64, f64),
    speed_to_rad_s: f64,
    lag: Lag,
}

#[pymethods]
impl PyVariablePitch {
    #[new]
    fn new(
        coefficients: [f64; 4],
        speed_bounds: (f64, f64),
        pitch_bounds: (f64, f64),
        speed_to_rad_s: f64,
        time_constant_s: f64,
        rate_limit_per_s: f64,
    ) -> Self {
        PyVariablePitch {
            coefficients,
            speed_bounds,
            pitch_bounds,
            speed_to_rad_s,
            lag: Lag {
                time_constant_s,
                rate_limit_per_s,
            },
        }
    }
}

#[derive(FromPyObject)]
pub enum ActuatorArg<'py> {
    Fixed(PyRef<'py, PyFixedPitch>),
    Variable(PyRef<'py, PyVariablePitch>),
}

fn build_actuators(airframe: &PyAirframe, spec: &ActuatorArg<'_>) -> rfcore::Result<Actuators> {
    Ok(match spec {
        ActuatorArg::Fixed(a) => Actuators::FixedPitch(FixedPitch::new(
            &airframe.inner,
            a.lag,
            a.thrust_coefficient_n_s2,
        )?),
        ActuatorArg::Variable(a) => Actuators::VariablePitch(VariablePitch::new(
            &airframe.inner,
            a.coefficients,
            a.speed_bounds,
            a.pitch_bounds,
            a.speed_to_rad_s,
            a.lag,
        )?),
    })
}

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
#[pyclass(name = "DiscreteLti", module = "rotorfault._rfcore", frozen)]
pub struct PyDiscreteLti {
    pub(crate) inner: DiscreteLti,
}

#[pymethods]
impl PyDiscreteLti {
    #[new]
    fn new(
        a: PyReadonlyArray2<'_, f64>,
        b: PyReadonlyArray2<'_, f64>,
        c: PyReadonlyArray2<'_, f64>,
        d: PyReadonlyArray2<'_, f64>,
        x_trim: PyReadonlyArray1<'_, f64>,
        u_trim: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let inner = DiscreteLti::new(
            matrix("A_K", &a)?,
            matrix("B_K", &b)?,
            matrix("C_K", &c)?,
            matrix("D_K", &d)?,
            slice1("x_trim", &x_trim)?,
            slice1("u_trim", &u_trim)?,
        )
        .map_err(to_py_err)?;
        Ok(PyDiscreteLti { inner })
    }
}

/// A Python function `f(t, x) -> commands` (x: the 12-element state vector): the slow path.
struct CallableController {
    function: Py<PyAny>,
    count: usize,
    error: Option<PyErr>,
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
            Ok(values) if values.len() == out.len() && values.iter().all(|v| v.is_finite()) => {
                out.copy_from_slice(&values);
                Ok(())
            }
            Ok(values) => Err(RfError::invalid(
                "controller",
                format!(
                    "the Python controller must return {} finite commands, got {values:?} at t = {t_s}",
                    out.len()
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
    Lti(PyRef<'py, PyDiscreteLti>),
    Allocated(PyRef<'py, PyAllocated>),
    Ftc(PyRef<'py, PyUniformPassiveFtc>),
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
    })
}

/// Timing, limits, wind and noise, in the order the Python layer passes them.
type ConfigArgs = (
    f64,
    usize,
    f64,
    [f64; 4],
    [f64; 3],
    Vec<(f64, [f64; 3])>,
    Option<(f64, [f64; STATE_DIM], u64)>,
    usize,
);

fn config(args: ConfigArgs) -> SimulationConfig {
    let (dt, substeps, t_final, limits, wind, profile, noise, record_every) = args;
    SimulationConfig {
        record_every,
        noise: noise.map(|(relative_std, absolute_std, seed)| SensorNoise {
            relative_std,
            absolute_std,
            seed,
        }),
        control_dt_s: dt,
        substeps,
        duration_s: t_final,
        limits: DivergenceLimits {
            max_tilt_rad: limits[0],
            max_altitude_loss_m: limits[1],
            max_speed_m_s: limits[2],
            max_rate_rad_s: limits[3],
        },
        wind_m_s: Vector3::from(wind),
        wind_profile: profile
            .into_iter()
            .map(|(t, w)| (t, Vector3::from(w)))
            .collect(),
    }
}

fn aerodynamics(aero: [f64; 4]) -> Aerodynamics {
    Aerodynamics {
        linear_drag_n_s_m: aero[0],
        quadratic_drag_n_s2_m2: aero[1],
        rotational_drag_n_m_s: aero[2],
        rotor_inertia_kg_m2: aero[3],
    }
}

/// x0 as `[p (3), v (3), q (w, x, y, z), omega (3)]`.
/// A state from 13 packed numbers: position, velocity, quaternion (w, x, y, z), body rates. A
/// quaternion that is unit to rounding is used exactly as given (so a recorded flight replays bit
/// for bit); any other is normalised.
pub(crate) fn packed_state(x: &[f64; 13]) -> RigidBodyState {
    let q = Quaternion::new(x[6], x[7], x[8], x[9]);
    let attitude = if (q.norm() - 1.0).abs() <= 1e-12 {
        UnitQuaternion::new_unchecked(q)
    } else {
        UnitQuaternion::new_normalize(q)
    };
    RigidBodyState {
        position_m: Vector3::new(x[0], x[1], x[2]),
        velocity_m_s: Vector3::new(x[3], x[4], x[5]),
        attitude,
        omega_rad_s: Vector3::new(x[10], x[11], x[12]),
    }
}

fn faults(list: &[(usize, f64, f64)]) -> Vec<RotorFault> {
    list.iter()
        .map(|&(rotor, time_s, efficiency)| RotorFault {
            rotor,
            time_s,
            efficiency,
        })
        .collect()
}

fn trajectory_dict<'py>(py: Python<'py>, run: Trajectory) -> PyResult<Bound<'py, PyDict>> {
    let n = run.t_s.len();
    let dict = PyDict::new(py);
    let mut columns: [Vec<f64>; 6] = Default::default();
    for s in &run.states {
        columns[0].extend(s.position_m.iter());
        columns[1].extend(s.velocity_m_s.iter());
        let q = s.attitude.quaternion();
        columns[2].extend([q.w, q.i, q.j, q.k]);
        columns[3].extend(s.euler_rad());
        columns[4].extend(s.omega_rad_s.iter());
        columns[5].extend(s.primary_axis().iter());
    }
    let [position, velocity, quaternion, euler, omega, n3] = columns;
    for (name, values) in [
        ("position", position),
        ("velocity", velocity),
        ("quaternion", quaternion),
        ("euler", euler),
        ("omega", omega),
        ("primary_axis", n3),
        ("command", run.commands),
        ("thrust", run.thrust_n),
        ("health", run.health),
        ("measured", run.measured),
    ] {
        let cols = values.len().checked_div(n).unwrap_or(0);
        dict.set_item(name, values.into_pyarray(py).reshape([n, cols])?)?;
    }
    dict.set_item("t", run.t_s.into_pyarray(py))?;
    match run.divergence {
        None => dict.set_item("divergence", py.None())?,
        Some(d) => {
            let event = PyDict::new(py);
            event.set_item("time", d.time_s)?;
            event.set_item("reason", d.reason.name())?;
            event.set_item("description", d.reason.describe())?;
            event.set_item("state", state_vector(&d.state).to_vec())?;
            dict.set_item("divergence", event)?;
        }
    }
    Ok(dict)
}

/// The vehicle, its actuators (settled at `settle` when given) and the command count.
fn vehicle_and_actuators(
    airframe: &PyAirframe,
    actuator: &ActuatorArg<'_>,
    aero: [f64; 4],
    settle: Option<&PyReadonlyArray1<'_, f64>>,
) -> PyResult<(Vehicle, Actuators, usize)> {
    let mut actuators = build_actuators(airframe, actuator).map_err(to_py_err)?;
    let vehicle = Vehicle::new(&airframe.inner, aerodynamics(aero)).map_err(to_py_err)?;
    if let Some(settle) = settle {
        actuators
            .settle(slice1("initial_command", settle)?)
            .map_err(to_py_err)?;
    }
    let count = actuators.channels() * airframe.inner.rotor_count();
    Ok((vehicle, actuators, count))
}

/// One closed-loop run.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    actuator: ActuatorArg<'py>,
    aero: [f64; 4],
    controller: Option<Bound<'py, PyAny>>,
    x0: [f64; 13],
    fault_list: Vec<(usize, f64, f64)>,
    health: PyReadonlyArray1<'py, f64>,
    settle: Option<PyReadonlyArray1<'py, f64>>,
    config_args: ConfigArgs,
) -> PyResult<Bound<'py, PyDict>> {
    let (vehicle, actuators, count) =
        vehicle_and_actuators(airframe, &actuator, aero, settle.as_ref())?;
    let health = slice1("health", &health)?.to_vec();
    let config = config(config_args);
    let faults = faults(&fault_list);
    let x0 = packed_state(&x0);
    let run = match controller {
        Some(c) if c.is_callable() && c.extract::<ControllerArg>().is_err() => {
            let mut callable = CallableController {
                function: c.unbind(),
                count,
                error: None,
            };
            let result = detached(py, || {
                core_simulate(
                    &vehicle,
                    actuators,
                    &mut callable,
                    &health,
                    &faults,
                    x0,
                    &config,
                )
            });
            if let Some(err) = callable.error.take() {
                return Err(err);
            }
            result?
        }
        other => {
            let spec: Option<ControllerArg> = other
                .map(|c| {
                    c.extract().map_err(|_| {
                        pyo3::exceptions::PyTypeError::new_err(format!(
                            "controller: expected a rotorfault controller or a callable f(t, x), got {}",
                            c.get_type().name().map(|n| n.to_string()).unwrap_or_default()
                        ))
                    })
                })
                .transpose()?;
            let mut boxed = boxed(spec.as_ref(), count)?;
            detached(py, || {
                core_simulate(
                    &vehicle,
                    actuators,
                    boxed.as_mut(),
                    &health,
                    &faults,
                    x0,
                    &config,
                )
            })?
        }
    };
    trajectory_dict(py, run)
}

/// Many runs in parallel; each item of `controllers`, `x0s` and `fault_lists` is one run.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn simulate_batch<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    actuator: ActuatorArg<'py>,
    aero: [f64; 4],
    controllers: Vec<Option<ControllerArg<'py>>>,
    x0s: Vec<[f64; 13]>,
    fault_lists: Vec<Vec<(usize, f64, f64)>>,
    health: PyReadonlyArray1<'py, f64>,
    settles: Vec<Option<Vec<f64>>>,
    config_args: ConfigArgs,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let (vehicle, actuators, count) = vehicle_and_actuators(airframe, &actuator, aero, None)?;
    if controllers.len() != x0s.len()
        || fault_lists.len() != x0s.len()
        || settles.len() != x0s.len()
    {
        return Err(PyValueError::new_err(
            "runs: controllers, initial states, fault lists and initial commands must have one entry per run",
        ));
    }
    let health = slice1("health", &health)?.to_vec();
    let config = config(config_args);
    let runs: Vec<BatchRun> = controllers
        .iter()
        .zip(&x0s)
        .zip(&fault_lists)
        .zip(settles)
        .map(|(((c, x0), f), settle)| {
            Ok(BatchRun {
                controller: boxed(c.as_ref(), count)?,
                initial_command: settle,
                x0: packed_state(x0),
                faults: faults(f),
            })
        })
        .collect::<PyResult<_>>()?;
    let results = detached(py, || {
        core_batch(&vehicle, &actuators, &health, runs, &config)
    })?;
    results
        .into_iter()
        .map(|run| trajectory_dict(py, run))
        .collect()
}

/// d/dt of the 12-element state vector with the actuators settled at `command` (no lag): the
/// model Python linearises for control design.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn state_derivative<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    actuator: ActuatorArg<'py>,
    aero: [f64; 4],
    x: [f64; STATE_DIM],
    command: PyReadonlyArray1<'py, f64>,
    health: PyReadonlyArray1<'py, f64>,
    wind: [f64; 3],
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (vehicle, mut actuators, _) = vehicle_and_actuators(airframe, &actuator, aero, None)?;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "x[{i}]: must be finite, got {}",
            x[i]
        )));
    }
    actuators
        .settle(slice1("command", &command)?)
        .map_err(to_py_err)?;
    let health = slice1("health", &health)?;
    rfcore::airframe::check_efficiency("health", health, airframe.inner.rotor_count())
        .map_err(to_py_err)?;
    let dx = state_vector_derivative(&vehicle, &actuators, health, &x, &Vector3::from(wind));
    Ok(dx.to_vec().into_pyarray(py))
}
