//! Bindings for the simulator: actuator specifications, one `simulate` call per run, a parallel
//! `simulate_batch` and the state derivative for linearisation. Translation only.

use nalgebra::Vector3;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::flight::actuator::{Actuators, FixedPitch, Lag, VariablePitch};
use rfcore::flight::model::state_vector_derivative;
use rfcore::flight::simulation::{
    simulate as core_simulate, simulate_batch as core_batch, BatchRun, DivergenceLimits,
    RotorFault, SensorNoise, SimulationConfig, Trajectory,
};
use rfcore::flight::vehicle::{Aerodynamics, Vehicle};
use rfcore::state::{state_vector, RigidBodyState, STATE_DIM};

use crate::airframe::PyAirframe;
use crate::control::{boxed, CallableController, ControllerArg};
use crate::convert::{detached, slice1, to_py_err};

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
    let x0 = RigidBodyState::from_packed(&x0);
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
                x0: RigidBodyState::from_packed(x0),
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
