//! Bindings for the simulator: actuator specifications, one `simulate` call per run, a parallel
//! `simulate_batch` and the state derivative for linearisation. Translation only.

use nalgebra::Vector3;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use rfcore::flight::actuator::{Actuators, FixedPitch, Lag, VariablePitch, VariablePitchLags};
use rfcore::flight::vpp_preset::VariablePitchPreset;
use rfcore::flight::model::state_vector_derivative;
use rfcore::flight::simulation::{
    simulate_batch as core_batch, simulate_cancellable as core_simulate, BatchRun, DivergenceLimits,
    RotorFault, SensorNoise, SimulationConfig,
};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::{RigidBodyState, STATE_DIM};

use crate::airframe::PyAirframe;
use crate::control::{boxed, CallableController, ControllerArg};
use crate::trajectory::PyTrajectory;
use crate::sensing::PySensing;
use crate::convert::{
    count, deprecated_positional, detached, fixed_reals, real, settings_class, settings_protocol, slice1,
    to_py_err,
};

/// A real number for `field`, or `default` when not given.
fn real_or(field: &str, value: Option<Bound<'_, PyAny>>, default: f64) -> PyResult<f64> {
    value.map_or(Ok(default), |v| real(field, &v))
}

/// Rotors commanded in thrust (`rotorfault.FixedPitchActuator`): first-order lag, rate limit
/// (thrust saturation from the airframe) and the thrust coefficient that gives rotor speed.
/// Keyword-only; defaults the core's (`Lag::none()`, no rotor speed); the rules the core's
/// `FixedPitch::check_parameters`, applied here, when it is made.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> lagged = rf.FixedPitchActuator(time_constant_s=0.02)
///     >>> lagged.time_constant_s, lagged.rate_limit_n_s
///     (0.02, inf)
///     >>> lagged.replace(rate_limit_n_s=50.0).rate_limit_n_s
///     50.0
#[pyclass(name = "FixedPitchActuator", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyFixedPitch {
    lag: Lag,
    thrust_coefficient_n_s2: f64,
}

impl PyFixedPitch {
    const FIELDS: &'static [&'static str] = &["time_constant_s", "rate_limit_n_s", "thrust_coefficient_n_s2"];
}

settings_protocol!(PyFixedPitch, {
    #[new]
    #[pyo3(signature = (*args, time_constant_s=None, rate_limit_n_s=None, thrust_coefficient_n_s2=None))]
    fn new<'py>(
        args: &Bound<'py, PyTuple>,
        time_constant_s: Option<Bound<'py, PyAny>>,
        rate_limit_n_s: Option<Bound<'py, PyAny>>,
        thrust_coefficient_n_s2: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let mut given = [time_constant_s, rate_limit_n_s, thrust_coefficient_n_s2];
        deprecated_positional("FixedPitchActuator", Self::FIELDS, args, &mut given)?;
        let [time_constant_s, rate_limit_n_s, thrust_coefficient_n_s2] = given;
        let d = Lag::none();
        let lag = Lag {
            time_constant_s: real_or("actuator.time_constant_s", time_constant_s, d.time_constant_s)?,
            rate_limit_per_s: real_or("actuator.rate_limit_n_s", rate_limit_n_s, d.rate_limit_per_s)?,
        };
        let thrust_coefficient_n_s2 = real_or("actuator.thrust_coefficient_n_s2", thrust_coefficient_n_s2, 0.0)?;
        FixedPitch::check_parameters(&lag, thrust_coefficient_n_s2).map_err(to_py_err)?;
        Ok(PyFixedPitch { lag, thrust_coefficient_n_s2 })
    }
    /// First-order lag of the thrust, s (0: none; Ke Table III: 0.025).
    #[getter]
    fn time_constant_s(&self) -> f64 {
        self.lag.time_constant_s
    }
    /// Largest rate of change of a rotor's thrust, N/s (`inf`: none; Lanzon: 50).
    #[getter]
    fn rate_limit_n_s(&self) -> f64 {
        self.lag.rate_limit_per_s
    }
    /// `k_f` of `f = k_f omega^2`, N s^2 (0: rotor speed not modelled).
    #[getter]
    fn thrust_coefficient_n_s2(&self) -> f64 {
        self.thrust_coefficient_n_s2
    }
});

/// Variable-pitch propellers (`rotorfault.VariablePitchActuator`, Wang et al. eq. (3)):
/// keyword-only; `k`, `speed_bounds` and `pitch_bounds` required, the rest defaulting to the
/// core's (`VariablePitchLags::default()`, no rotor speed); the rules the core's
/// `VariablePitch::check_parameters`, applied here, when it is made.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> wang = rf.control.vpp.preset("wang").actuator
///     >>> wang.speed_bounds, wang.pitch_bounds
///     ((0.0, 10000.0), (-0.26, 0.26))
///     >>> rf.VariablePitchActuator(k=wang.k, speed_bounds=(0.0, 8000.0), pitch_bounds=wang.pitch_bounds).speed_bounds
///     (0.0, 8000.0)
#[pyclass(name = "VariablePitchActuator", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyVariablePitch {
    coefficients: [f64; 4],
    speed_bounds: (f64, f64),
    pitch_bounds: (f64, f64),
    speed_to_rad_s: f64,
    lags: VariablePitchLags,
}

impl PyVariablePitch {
    const FIELDS: &'static [&'static str] = &[
        "k",
        "speed_bounds",
        "pitch_bounds",
        "speed_to_rad_s",
        "speed_time_constant_s",
        "speed_rate_limit_per_s",
        "pitch_time_constant_s",
        "pitch_rate_limit_rad_s",
    ];
}

fn required<'py>(field: &str, value: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyAny>> {
    value.ok_or_else(|| pyo3::exceptions::PyTypeError::new_err(format!("{field}: required (no default)")))
}

fn bounds(field: &str, value: Option<Bound<'_, PyAny>>) -> PyResult<(f64, f64)> {
    let [lower, upper] = fixed_reals::<2>(field, "lower, upper", &required(field, value)?)?;
    Ok((lower, upper))
}

settings_protocol!(PyVariablePitch, {
    #[new]
    #[pyo3(signature = (*args, k=None, speed_bounds=None, pitch_bounds=None, speed_to_rad_s=None, speed_time_constant_s=None, speed_rate_limit_per_s=None, pitch_time_constant_s=None, pitch_rate_limit_rad_s=None))]
    #[allow(clippy::too_many_arguments)]
    fn new<'py>(
        args: &Bound<'py, PyTuple>,
        k: Option<Bound<'py, PyAny>>,
        speed_bounds: Option<Bound<'py, PyAny>>,
        pitch_bounds: Option<Bound<'py, PyAny>>,
        speed_to_rad_s: Option<Bound<'py, PyAny>>,
        speed_time_constant_s: Option<Bound<'py, PyAny>>,
        speed_rate_limit_per_s: Option<Bound<'py, PyAny>>,
        pitch_time_constant_s: Option<Bound<'py, PyAny>>,
        pitch_rate_limit_rad_s: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let mut given = [
            k,
            speed_bounds,
            pitch_bounds,
            speed_to_rad_s,
            speed_time_constant_s,
            speed_rate_limit_per_s,
            pitch_time_constant_s,
            pitch_rate_limit_rad_s,
        ];
        deprecated_positional("VariablePitchActuator", Self::FIELDS, args, &mut given)?;
        let [k, speed_bounds, pitch_bounds, speed_to_rad_s, speed_tau, speed_rate, pitch_tau, pitch_rate] = given;
        let coefficients = fixed_reals::<4>("actuator.k", "k1, k2, k3, k4", &required("actuator.k", k)?)?;
        let speed_bounds = bounds("actuator.speed_bounds", speed_bounds)?;
        let pitch_bounds = bounds("actuator.pitch_bounds", pitch_bounds)?;
        let speed_to_rad_s = real_or("actuator.speed_to_rad_s", speed_to_rad_s, 0.0)?;
        let d = VariablePitchLags::default();
        let lags = VariablePitchLags {
            speed: Lag {
                time_constant_s: real_or("actuator.speed_time_constant_s", speed_tau, d.speed.time_constant_s)?,
                rate_limit_per_s: real_or("actuator.speed_rate_limit_per_s", speed_rate, d.speed.rate_limit_per_s)?,
            },
            pitch: Lag {
                time_constant_s: real_or("actuator.pitch_time_constant_s", pitch_tau, d.pitch.time_constant_s)?,
                rate_limit_per_s: real_or("actuator.pitch_rate_limit_rad_s", pitch_rate, d.pitch.rate_limit_per_s)?,
            },
        };
        VariablePitch::check_parameters(coefficients, speed_bounds, pitch_bounds, speed_to_rad_s, lags)
            .map_err(to_py_err)?;
        Ok(PyVariablePitch {
            coefficients,
            speed_bounds,
            pitch_bounds,
            speed_to_rad_s,
            lags,
        })
    }
    /// `(k1, k2, k3, k4)` of eq. (3), in the speed unit the bounds use.
    #[getter]
    fn k(&self) -> (f64, f64, f64, f64) {
        let [a, b, c, d] = self.coefficients;
        (a, b, c, d)
    }
    /// `(lower, upper)` rotor speed, in the coefficients' speed unit.
    #[getter]
    fn speed_bounds(&self) -> (f64, f64) {
        self.speed_bounds
    }
    /// `(lower, upper)` blade pitch, rad.
    #[getter]
    fn pitch_bounds(&self) -> (f64, f64) {
        self.pitch_bounds
    }
    /// Speed unit to rad/s for the gyroscopic moment (0: not modelled).
    #[getter]
    fn speed_to_rad_s(&self) -> f64 {
        self.speed_to_rad_s
    }
    /// The speed channel's first-order lag, s.
    #[getter]
    fn speed_time_constant_s(&self) -> f64 {
        self.lags.speed.time_constant_s
    }
    /// The speed channel's rate limit, speed units per second (`inf`: none).
    #[getter]
    fn speed_rate_limit_per_s(&self) -> f64 {
        self.lags.speed.rate_limit_per_s
    }
    /// The pitch channel's first-order lag, s.
    #[getter]
    fn pitch_time_constant_s(&self) -> f64 {
        self.lags.pitch.time_constant_s
    }
    /// The pitch channel's rate limit, rad/s (`inf`: none).
    #[getter]
    fn pitch_rate_limit_rad_s(&self) -> f64 {
        self.lags.pitch.rate_limit_per_s
    }
});

/// A variable-pitch vehicle preset (`presets/vpp/*.toml`), parsed by the core.
#[pyclass(name = "VariablePitchPreset", module = "rotorfault._rfcore", frozen)]
pub struct PyVariablePitchPreset {
    inner: VariablePitchPreset,
}

#[pymethods]
impl PyVariablePitchPreset {
    /// Parses a preset file; `origin` prefixes error messages.
    #[staticmethod]
    fn from_toml_str(text: &str, origin: &str) -> PyResult<Self> {
        let inner = VariablePitchPreset::from_toml_str(text, origin).map_err(to_py_err)?;
        Ok(PyVariablePitchPreset { inner })
    }
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    #[getter]
    fn description(&self) -> &str {
        &self.inner.description
    }
    #[getter]
    fn source(&self) -> &str {
        &self.inner.source
    }
    #[getter]
    fn airframe(&self) -> &str {
        &self.inner.airframe
    }
    #[getter]
    fn coefficients(&self) -> (f64, f64, f64, f64) {
        let [a, b, c, d] = self.inner.coefficients;
        (a, b, c, d)
    }
    #[getter]
    fn speed_bounds(&self) -> (f64, f64) {
        self.inner.speed_bounds
    }
    #[getter]
    fn pitch_bounds(&self) -> (f64, f64) {
        self.inner.pitch_bounds
    }
    #[getter]
    fn speed_to_rad_s(&self) -> f64 {
        self.inner.speed_to_rad_s
    }
    #[getter]
    fn speed_time_constant_s(&self) -> f64 {
        self.inner.speed_time_constant_s
    }
    #[getter]
    fn speed_rate_limit_per_s(&self) -> f64 {
        self.inner.speed_rate_limit_per_s
    }
    #[getter]
    fn pitch_time_constant_s(&self) -> f64 {
        self.inner.pitch_time_constant_s
    }
    #[getter]
    fn pitch_rate_limit_rad_s(&self) -> f64 {
        self.inner.pitch_rate_limit_rad_s
    }
    #[getter]
    fn linear_drag_n_s_m(&self) -> f64 {
        self.inner.linear_drag_n_s_m
    }
    /// The actuator the preset describes (`rotorfault.VariablePitchActuator`), checked by the
    /// rules every one is made by.
    #[getter]
    fn actuator(&self) -> PyResult<PyVariablePitch> {
        let p = &self.inner;
        VariablePitch::check_parameters(p.coefficients, p.speed_bounds, p.pitch_bounds, p.speed_to_rad_s, p.lags())
            .map_err(to_py_err)?;
        Ok(PyVariablePitch {
            coefficients: p.coefficients,
            speed_bounds: p.speed_bounds,
            pitch_bounds: p.pitch_bounds,
            speed_to_rad_s: p.speed_to_rad_s,
            lags: p.lags(),
        })
    }
}

#[derive(FromPyObject)]
pub enum ActuatorArg<'py> {
    Fixed(PyRef<'py, PyFixedPitch>),
    Variable(PyRef<'py, PyVariablePitch>),
}

pub(crate) fn build_actuators(
    airframe: &PyAirframe,
    spec: &ActuatorArg<'_>,
) -> rfcore::Result<Actuators> {
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
            a.lags,
        )?),
    })
}

settings_class!(
    /// Aerodynamic damping and rotor inertia (`rotorfault.Drag`; the papers give none: all 0 by
    /// default).
    ///
    /// Examples:
    ///
    ///     >>> import rotorfault as rf
    ///     >>> drag = rf.Drag(linear_n_s_m=0.1)
    ///     >>> drag.linear_n_s_m, drag.rotational_n_m_s
    ///     (0.1, 0.0)
    PyDrag, "Drag", Drag, prefix = "drag", check = Drag::check,
    {
        linear_n_s_m => linear_drag_n_s_m,
        quadratic_n_s2_m2 => quadratic_drag_n_s2_m2,
        rotational_n_m_s => rotational_drag_n_m_s,
        rotor_inertia_kg_m2 => rotor_inertia_kg_m2,
    }
);

settings_class!(
    /// Limits past which a run ends with an event (`rotorfault.DivergenceLimits`; `math.inf`: no
    /// limit). Their values are checked with the run's settings (`SimulationConfig`).
    ///
    /// Examples:
    ///
    ///     >>> import rotorfault as rf
    ///     >>> limits = rf.DivergenceLimits(max_tilt_rad=1.0)
    ///     >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"), limits=limits)
    ///     >>> run = sim.run(rf.State(position=(0, 0, -100), euler=(1.2, 0, 0)), 0.1)
    ///     >>> run.events[0].kind
    ///     'tilt'
    PyDivergenceLimits, "DivergenceLimits", DivergenceLimits, prefix = "limits", check = |_| Ok(()),
    {
        max_tilt_rad => max_tilt_rad,
        max_altitude_loss_m => max_altitude_loss_m,
        max_speed_m_s => max_speed_m_s,
        max_rate_rad_s => max_rate_rad_s,
    }
);

/// Sensor noise: standard deviation `relative_std |x_i| + absolute_std[i]` on the 12 measured
/// state components, seeded.
#[pyclass(name = "SensorNoise", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PySensorNoise {
    pub(crate) inner: SensorNoise,
}

impl PySensorNoise {
    const FIELDS: &'static [&'static str] = &["relative_std", "absolute_std", "seed"];
}

crate::convert::pickle_protocol!(PySensorNoise, {
    #[new]
    #[pyo3(signature = (*, relative_std, absolute_std, seed))]
    fn new(relative_std: f64, absolute_std: [f64; STATE_DIM], seed: &Bound<'_, PyAny>) -> PyResult<Self> {
        let seed = count("noise.seed", seed)? as u64;
        Ok(PySensorNoise {
            inner: SensorNoise {
                relative_std,
                absolute_std,
                seed,
            },
        })
    }
    #[getter]
    fn relative_std(&self) -> f64 {
        self.inner.relative_std
    }
    #[getter]
    fn absolute_std(&self) -> [f64; STATE_DIM] {
        self.inner.absolute_std
    }
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }
});

/// Timing, limits, ground, wind, noise and recording of a run; defaults are the core's
/// (`SimulationConfig::default`), the rules its `check`. The ground: `ground_z_m` (world NED,
/// default the core's) unless `ground=False` (no ground).
#[pyclass(name = "SimulationConfig", module = "rotorfault._rfcore", frozen)]
pub struct PySimulationConfig {
    pub(crate) inner: SimulationConfig,
}

impl PySimulationConfig {
    const FIELDS: &'static [&'static str] = &[
        "dt_s", "substeps", "duration_s", "limits", "ground_z_m", "ground", "wind_m_s", "wind_profile", "noise",
        "sensing", "record_every",
    ];
}

crate::convert::pickle_protocol!(PySimulationConfig, {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (*, dt_s=None, substeps=None, duration_s=None, limits=None, ground_z_m=None, ground=None, wind_m_s=None, wind_profile=None, noise=None, sensing=None, record_every=None))]
    fn new(
        dt_s: Option<f64>,
        substeps: Option<&Bound<'_, PyAny>>,
        duration_s: Option<f64>,
        limits: Option<PyRef<'_, PyDivergenceLimits>>,
        ground_z_m: Option<f64>,
        ground: Option<bool>,
        wind_m_s: Option<[f64; 3]>,
        wind_profile: Option<Vec<(f64, [f64; 3])>>,
        noise: Option<PyRef<'_, PySensorNoise>>,
        sensing: Option<PyRef<'_, PySensing>>,
        record_every: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let d = SimulationConfig::default();
        // Counts through the one conversion: a huge or negative int is a ValueError naming the field.
        let substeps = substeps.map(|v| count("substeps", v)).transpose()?;
        let record_every = record_every.map(|v| count("record_every", v)).transpose()?;
        let ground_z_m = match (ground.unwrap_or(true), ground_z_m) {
            (true, z) => z.or(d.ground_z_m),
            (false, None) => None,
            (false, Some(z)) => {
                return Err(PyValueError::new_err(format!(
                "ground_z_m, ground: a ground height ({z} m) with ground=False; give one of them"
            )))
            }
        };
        let inner = SimulationConfig {
            dt_s: dt_s.unwrap_or(d.dt_s),
            substeps: substeps.unwrap_or(d.substeps),
            duration_s: duration_s.unwrap_or(d.duration_s),
            limits: limits.map_or(d.limits, |l| l.inner),
            ground_z_m,
            wind_m_s: wind_m_s.map_or(d.wind_m_s, Vector3::from),
            wind_profile: wind_profile.map_or(d.wind_profile, |points| {
                points
                    .into_iter()
                    .map(|(t, w)| (t, Vector3::from(w)))
                    .collect()
            }),
            noise: noise.map(|n| n.inner).or(d.noise),
            sensing: sensing.map(|n| n.inner).or(d.sensing),
            record_every: record_every.unwrap_or(d.record_every),
        };
        inner.check().map_err(to_py_err)?;
        Ok(PySimulationConfig { inner })
    }
    #[getter]
    fn dt_s(&self) -> f64 {
        self.inner.dt_s
    }
    #[getter]
    fn substeps(&self) -> usize {
        self.inner.substeps
    }
    #[getter]
    fn duration_s(&self) -> f64 {
        self.inner.duration_s
    }
    #[getter]
    fn record_every(&self) -> usize {
        self.inner.record_every
    }
    #[getter]
    fn limits(&self) -> PyDivergenceLimits {
        PyDivergenceLimits {
            inner: self.inner.limits,
        }
    }
    /// The ground plane's world NED z, m (`None`: no ground).
    #[getter]
    fn ground_z_m(&self) -> Option<f64> {
        self.inner.ground_z_m
    }
    #[getter]
    fn wind_m_s(&self) -> [f64; 3] {
        self.inner.wind_m_s.into()
    }
    /// Sensors and the estimator the controller flies on (`None`: the truth, or `noise`).
    #[getter]
    fn sensing(&self) -> Option<PySensing> {
        self.inner.sensing.map(|inner| PySensing { inner })
    }
    /// The recording grid: the times a run that does not diverge records (its `t`, bit for bit).
    fn record_times<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.record_times().into_pyarray(py)
    }
    /// Whether the run has a ground plane (`ground_z_m` is not None).
    #[getter]
    fn ground(&self) -> bool {
        self.inner.ground_z_m.is_some()
    }
    /// The wind's time profile: `(time_s, wind_m_s)` points (NED, m/s).
    #[getter]
    fn wind_profile(&self) -> Vec<(f64, [f64; 3])> {
        self.inner.wind_profile.iter().map(|(t, w)| (*t, (*w).into())).collect()
    }
    /// The sensor noise (`None`: the truth, or `sensing`).
    #[getter]
    fn noise(&self) -> Option<PySensorNoise> {
        self.inner.noise.map(|inner| PySensorNoise { inner })
    }
});

fn faults(list: &[(usize, f64, f64)]) -> Vec<RotorFault> {
    list.iter()
        .map(|&(rotor, time_s, efficiency)| RotorFault {
            rotor,
            time_s,
            efficiency,
        })
        .collect()
}

/// The vehicle, its actuators (settled at `settle` when given) and the command count.
fn vehicle_and_actuators(
    airframe: &PyAirframe,
    actuator: &ActuatorArg<'_>,
    drag: &PyDrag,
    settle: Option<&PyReadonlyArray1<'_, f64>>,
) -> PyResult<(Vehicle, Actuators, usize)> {
    let mut actuators = build_actuators(airframe, actuator).map_err(to_py_err)?;
    let vehicle = Vehicle::new(&airframe.inner, drag.inner).map_err(to_py_err)?;
    if let Some(settle) = settle {
        actuators
            .settle(slice1("initial_command", settle)?)
            .map_err(to_py_err)?;
    }
    let count = actuators.channels() * airframe.inner.rotor_count();
    Ok((vehicle, actuators, count))
}

/// One closed-loop run, as a `trajectory_type` (default `Trajectory`; a Python subclass gets the
/// `extra` keywords too), made once.
#[pyfunction]
#[pyo3(signature = (airframe, actuator, drag, controller, x0, fault_list, efficiency, settle, config, *, trajectory_type=None, extra=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    actuator: ActuatorArg<'py>,
    drag: PyRef<'py, PyDrag>,
    controller: Option<Bound<'py, PyAny>>,
    x0: [f64; 13],
    fault_list: Vec<(usize, f64, f64)>,
    efficiency: PyReadonlyArray1<'py, f64>,
    settle: Option<PyReadonlyArray1<'py, f64>>,
    config: PyRef<'py, PySimulationConfig>,
    trajectory_type: Option<Bound<'py, PyType>>,
    extra: Option<Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    PyTrajectory::check_extra(extra.as_ref())?; // before the run, not after it
    let (vehicle, actuators, count) =
        vehicle_and_actuators(airframe, &actuator, &drag, settle.as_ref())?;
    let efficiency = slice1("efficiency", &efficiency)?.to_vec();
    let config = &config.inner;
    let faults = faults(&fault_list);
    let x0 = RigidBodyState::from_packed(&x0);
    let run = match controller {
        Some(c) if c.is_callable() && c.extract::<ControllerArg>().is_err() => {
            let mut callable = CallableController {
                function: c.unbind(),
                count,
                error: None,
            };
            let result = detached(py, |cancel| {
                // One Python thread state for the whole run (kept while detached), so the
                // callback at every step does not create one each time.
                Python::attach(|py| {
                    py.detach(|| {
                        core_simulate(
                            &vehicle,
                            actuators,
                            &mut callable,
                            &efficiency,
                            &faults,
                            x0,
                            config,
                            cancel,
                        )
                    })
                })
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
            detached(py, |cancel| {
                core_simulate(
                    &vehicle,
                    actuators,
                    boxed.as_mut(),
                    &efficiency,
                    &faults,
                    x0,
                    config,
                    cancel,
                )
            })?
        }
    };
    PyTrajectory::from_run(py, run, trajectory_type.as_ref(), extra.as_ref())
}

/// A batch's vehicle, actuators, initial efficiency and runs, checked (one entry per run).
#[allow(clippy::too_many_arguments)]
pub(crate) fn batch_runs(
    airframe: &PyAirframe,
    actuator: &ActuatorArg<'_>,
    drag: &PyDrag,
    controllers: &[Option<ControllerArg<'_>>],
    x0s: &[[f64; 13]],
    fault_lists: &[Vec<(usize, f64, f64)>],
    settles: Vec<Option<Vec<f64>>>,
    efficiency: &PyReadonlyArray1<'_, f64>,
) -> PyResult<(Vehicle, Actuators, Vec<f64>, Vec<BatchRun>)> {
    let (vehicle, actuators, count) = vehicle_and_actuators(airframe, actuator, drag, None)?;
    if controllers.len() != x0s.len()
        || fault_lists.len() != x0s.len()
        || settles.len() != x0s.len()
    {
        return Err(PyValueError::new_err(
            "runs: controllers, initial states, fault lists and initial commands must have one entry per run",
        ));
    }
    let efficiency = slice1("efficiency", efficiency)?.to_vec();
    let runs: Vec<BatchRun> = controllers
        .iter()
        .zip(x0s)
        .zip(fault_lists)
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
    Ok((vehicle, actuators, efficiency, runs))
}

/// Many runs in parallel; each item of `controllers`, `x0s` and `fault_lists` is one run.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn simulate_batch<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    actuator: ActuatorArg<'py>,
    drag: PyRef<'py, PyDrag>,
    controllers: Vec<Option<ControllerArg<'py>>>,
    x0s: Vec<[f64; 13]>,
    fault_lists: Vec<Vec<(usize, f64, f64)>>,
    efficiency: PyReadonlyArray1<'py, f64>,
    settles: Vec<Option<Vec<f64>>>,
    config: PyRef<'py, PySimulationConfig>,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let (vehicle, actuators, efficiency, runs) =
        batch_runs(airframe, &actuator, &drag, &controllers, &x0s, &fault_lists, settles, &efficiency)?;
    let config = &config.inner;
    let results = detached(py, |cancel| {
        core_batch(&vehicle, &actuators, &efficiency, runs, config, cancel)
    })?;
    results.into_iter().map(|run| PyTrajectory::from_run(py, run, None, None)).collect()
}

/// d/dt of the 12-element state vector with the actuators settled at `command` (no lag): the
/// model Python linearises for control design.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn state_derivative<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    actuator: ActuatorArg<'py>,
    drag: PyRef<'py, PyDrag>,
    x: [f64; STATE_DIM],
    command: PyReadonlyArray1<'py, f64>,
    efficiency: PyReadonlyArray1<'py, f64>,
    wind: [f64; 3],
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (vehicle, mut actuators, _) = vehicle_and_actuators(airframe, &actuator, &drag, None)?;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "x[{i}]: must be finite, got {}",
            x[i]
        )));
    }
    actuators
        .settle(slice1("command", &command)?)
        .map_err(to_py_err)?;
    let efficiency = slice1("efficiency", &efficiency)?;
    rfcore::airframe::check_efficiency("efficiency", efficiency, airframe.inner.rotor_count())
        .map_err(to_py_err)?;
    let dx = state_vector_derivative(&vehicle, &actuators, efficiency, &x, &Vector3::from(wind));
    Ok(dx.to_vec().into_pyarray(py))
}
