//! Bindings for the simulator: actuator specifications, one `simulate` call per run, a parallel
//! `simulate_batch` and the state derivative for linearisation. Translation only.

use nalgebra::Vector3;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::flight::actuator::{
    Actuators, FixedPitch, Lag, VariablePitch, VariablePitchLags, VariablePitchPreset,
};
use rfcore::flight::model::state_vector_derivative;
use rfcore::flight::simulation::{
    simulate_batch as core_batch, simulate_cancellable as core_simulate, BatchRun, DivergenceLimits,
    RotorFault, SensorNoise, SimulationConfig, Trajectory,
};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::{state_vector, RigidBodyState, STATE_DIM};

use crate::airframe::PyAirframe;
use crate::control::{boxed, CallableController, ControllerArg};
use crate::sensing::PySensing;
use crate::convert::{
    detached, real, settings_eq, settings_hash, settings_kwargs, settings_replace, settings_repr, slice1, to_py_err,
};

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

/// Variable-pitch propellers (Wang et al. eq. (3)); the speed and pitch channels' lags default
/// to the core's `VariablePitchLags::default()`.
#[pyclass(name = "VariablePitchActuator", module = "rotorfault._rfcore", frozen)]
pub struct PyVariablePitch {
    coefficients: [f64; 4],
    speed_bounds: (f64, f64),
    pitch_bounds: (f64, f64),
    speed_to_rad_s: f64,
    lags: VariablePitchLags,
}

#[pymethods]
impl PyVariablePitch {
    #[new]
    #[pyo3(signature = (coefficients, speed_bounds, pitch_bounds, speed_to_rad_s, *, speed_time_constant_s=None, speed_rate_limit_per_s=None, pitch_time_constant_s=None, pitch_rate_limit_rad_s=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        coefficients: [f64; 4],
        speed_bounds: (f64, f64),
        pitch_bounds: (f64, f64),
        speed_to_rad_s: f64,
        speed_time_constant_s: Option<f64>,
        speed_rate_limit_per_s: Option<f64>,
        pitch_time_constant_s: Option<f64>,
        pitch_rate_limit_rad_s: Option<f64>,
    ) -> PyResult<Self> {
        let d = VariablePitchLags::default();
        let lags = VariablePitchLags {
            speed: Lag {
                time_constant_s: speed_time_constant_s.unwrap_or(d.speed.time_constant_s),
                rate_limit_per_s: speed_rate_limit_per_s.unwrap_or(d.speed.rate_limit_per_s),
            },
            pitch: Lag {
                time_constant_s: pitch_time_constant_s.unwrap_or(d.pitch.time_constant_s),
                rate_limit_per_s: pitch_rate_limit_rad_s.unwrap_or(d.pitch.rate_limit_per_s),
            },
        };
        lags.check().map_err(to_py_err)?;
        Ok(PyVariablePitch {
            coefficients,
            speed_bounds,
            pitch_bounds,
            speed_to_rad_s,
            lags,
        })
    }
    #[getter]
    fn speed_time_constant_s(&self) -> f64 {
        self.lags.speed.time_constant_s
    }
    #[getter]
    fn speed_rate_limit_per_s(&self) -> f64 {
        self.lags.speed.rate_limit_per_s
    }
    #[getter]
    fn pitch_time_constant_s(&self) -> f64 {
        self.lags.pitch.time_constant_s
    }
    #[getter]
    fn pitch_rate_limit_rad_s(&self) -> f64 {
        self.lags.pitch.rate_limit_per_s
    }
}

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

/// One settings class used directly from Python: keyword-only, defaults from the core's
/// `Default`, types checked here (`<prefix>.<field>: expected a real number`), values once by the
/// core's `check`; frozen, comparable, hashable, picklable, `replace(**changes)`, `FIELDS`.
macro_rules! settings_class {
    (
        $(#[$doc:meta])* $py:ident, $pyname:literal, $core:ident, prefix = $prefix:literal, check = $check:expr,
        { $($field:ident => $core_field:ident),+ $(,)? }
    ) => {
        $(#[$doc])*
        #[pyclass(name = $pyname, module = "rotorfault._rfcore", frozen)]
        #[derive(Clone)]
        pub struct $py {
            pub(crate) inner: $core,
        }

        impl $py {
            const FIELDS: &'static [&'static str] = &[$(stringify!($field)),+];
        }

        #[pymethods]
        impl $py {
            #[new]
            #[pyo3(signature = (*, $($field=None),+))]
            fn new($($field: Option<Bound<'_, PyAny>>),+) -> PyResult<Self> {
                let d = $core::default();
                let inner = $core {
                    $($core_field: match $field {
                        Some(v) => real(concat!($prefix, ".", stringify!($field)), &v)?,
                        None => d.$core_field,
                    }),+
                };
                let check: fn(&$core) -> rfcore::Result<()> = $check;
                check(&inner).map_err(to_py_err)?;
                Ok($py { inner })
            }
            $(
                #[getter]
                fn $field(&self) -> f64 {
                    self.inner.$core_field
                }
            )+
            /// The field names, in order.
            #[classattr]
            #[pyo3(name = "FIELDS")]
            fn fields() -> Vec<&'static str> {
                Self::FIELDS.to_vec()
            }
            /// A copy with ``changes`` (validated like a new object).
            #[pyo3(signature = (**changes))]
            fn replace<'py>(slf: &Bound<'py, Self>, changes: Option<&Bound<'py, PyDict>>) -> PyResult<Bound<'py, PyAny>> {
                settings_replace(slf.as_any(), Self::FIELDS, changes)
            }
            fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
                settings_repr(slf.as_any(), Self::FIELDS)
            }
            fn __eq__(slf: &Bound<'_, Self>, other: &Bound<'_, PyAny>) -> PyResult<bool> {
                settings_eq(slf.as_any(), other, Self::FIELDS)
            }
            fn __hash__(slf: &Bound<'_, Self>) -> PyResult<isize> {
                settings_hash(slf.as_any(), Self::FIELDS)
            }
            fn __getnewargs_ex__<'py>(slf: &Bound<'py, Self>) -> PyResult<((), Bound<'py, PyDict>)> {
                Ok(((), settings_kwargs(slf.as_any(), Self::FIELDS)?))
            }
        }
    };
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

#[pymethods]
impl PySensorNoise {
    #[new]
    #[pyo3(signature = (*, relative_std, absolute_std, seed))]
    fn new(relative_std: f64, absolute_std: [f64; STATE_DIM], seed: u64) -> Self {
        PySensorNoise {
            inner: SensorNoise {
                relative_std,
                absolute_std,
                seed,
            },
        }
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
}

/// Timing, limits, ground, wind, noise and recording of a run; defaults are the core's
/// (`SimulationConfig::default`), the rules its `check`. The ground: `ground_z_m` (world NED,
/// default the core's) unless `ground=False` (no ground).
#[pyclass(name = "SimulationConfig", module = "rotorfault._rfcore", frozen)]
pub struct PySimulationConfig {
    pub(crate) inner: SimulationConfig,
}

#[pymethods]
impl PySimulationConfig {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (*, dt_s=None, substeps=None, duration_s=None, limits=None, ground_z_m=None, ground=None, wind_m_s=None, wind_profile=None, noise=None, sensing=None, record_every=None))]
    fn new(
        dt_s: Option<f64>,
        substeps: Option<usize>,
        duration_s: Option<f64>,
        limits: Option<PyRef<'_, PyDivergenceLimits>>,
        ground_z_m: Option<f64>,
        ground: Option<bool>,
        wind_m_s: Option<[f64; 3]>,
        wind_profile: Option<Vec<(f64, [f64; 3])>>,
        noise: Option<PyRef<'_, PySensorNoise>>,
        sensing: Option<PyRef<'_, PySensing>>,
        record_every: Option<usize>,
    ) -> PyResult<Self> {
        let d = SimulationConfig::default();
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

/// Why and when a run ended early, with the 12-element state vector at that moment; for a
/// `crashed` run, the impact (speed, speed into the ground, tilt), else `None`.
#[pyclass(name = "Divergence", module = "rotorfault._rfcore", frozen, get_all)]
pub struct PyDivergence {
    time_s: f64,
    reason: &'static str,
    description: &'static str,
    state: [f64; STATE_DIM],
    impact_speed_m_s: Option<f64>,
    impact_vertical_speed_m_s: Option<f64>,
    impact_tilt_rad: Option<f64>,
}

/// A run's sensor counts (`Trajectory.sensing_counts`).
#[pyclass(name = "SensingCounts", module = "rotorfault._rfcore", frozen, get_all)]
pub struct PySensingCounts {
    imu_samples: u64,
    gyro_saturated_samples: u64,
    accel_saturated_samples: u64,
    fused_measurements: u64,
    rejected_measurements: u64,
    late_measurements: u64,
}

/// A recorded run: one row per recorded control step; arrays are built on access.
#[pyclass(name = "Trajectory", module = "rotorfault._rfcore", frozen)]
pub struct PyTrajectory {
    run: Trajectory,
}

type Array2<'py> = PyResult<Bound<'py, PyArray2<f64>>>;

impl PyTrajectory {
    fn rows<'py>(&self, py: Python<'py>, values: Vec<f64>) -> Array2<'py> {
        let n = self.run.t_s.len();
        let cols = values.len().checked_div(n).unwrap_or(0);
        Ok(values.into_pyarray(py).reshape([n, cols])?)
    }

    fn per_state<const N: usize>(&self, f: impl Fn(&RigidBodyState) -> [f64; N]) -> Vec<f64> {
        self.run.states.iter().flat_map(f).collect()
    }
}

#[pymethods]
impl PyTrajectory {
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.run.t_s.clone().into_pyarray(py)
    }
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.per_state(|s| s.position_m.into()))
    }
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.per_state(|s| s.velocity_m_s.into()))
    }
    #[getter]
    fn quaternion<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(
            py,
            self.per_state(|s| {
                let q = s.attitude.quaternion();
                [q.w, q.i, q.j, q.k]
            }),
        )
    }
    #[getter]
    fn euler<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.per_state(|s| s.euler_rad()))
    }
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.per_state(|s| s.omega_rad_s.into()))
    }
    #[getter]
    fn primary_axis<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.per_state(|s| s.primary_axis().into()))
    }
    #[getter]
    fn command<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.run.commands.clone())
    }
    #[getter]
    fn thrust<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.run.thrust_n.clone())
    }
    #[getter]
    fn efficiency<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.run.efficiency.clone())
    }
    #[getter]
    fn measured<'py>(&self, py: Python<'py>) -> Array2<'py> {
        self.rows(py, self.run.measured.clone())
    }
    /// What the controller flew on: `"truth"`, `"paper-noise"` or the sensor suite's name.
    #[getter]
    fn sensed(&self) -> &'static str {
        self.run.sensed()
    }
    /// With sensing, the estimate the controller saw per row (N x 13: position, velocity,
    /// quaternion w x y z, body rates); else `None`.
    #[getter]
    fn estimate_state<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.run.sensing.as_ref().map(|r| {
            let values = r.rows.iter().flat_map(|row| row.state.to_packed()).collect();
            self.rows(py, values)
        }).transpose()
    }
    /// With sensing, the estimate as the 12-element state vector per row (Euler angles); else
    /// `None`.
    #[getter]
    fn estimate_vector<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.run.sensing.as_ref().map(|r| {
            let values = r.rows.iter().flat_map(|row| state_vector(&row.state)).collect();
            self.rows(py, values)
        }).transpose()
    }
    /// With sensing, one sigma of the estimator's error state per row (N x 15: position m,
    /// velocity m/s, attitude rad, gyro bias rad/s, accelerometer bias m/s^2); else `None`.
    #[getter]
    fn estimate_std<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.run.sensing.as_ref().map(|r| {
            let values = r.rows.iter().flat_map(|row| row.std).collect();
            self.rows(py, values)
        }).transpose()
    }
    /// With sensing, per row: the newest IMU sample's gyroscope (accelerometer) was clamped.
    #[getter]
    fn gyro_saturated(&self) -> Option<Vec<bool>> {
        self.run.sensing.as_ref().map(|r| r.rows.iter().map(|row| row.gyro_saturated).collect())
    }
    #[getter]
    fn accel_saturated(&self) -> Option<Vec<bool>> {
        self.run.sensing.as_ref().map(|r| r.rows.iter().map(|row| row.accel_saturated).collect())
    }
    /// With sensing, counts over the whole run: IMU samples, those with the gyroscope
    /// (accelerometer) clamped, and the estimator's measurements fused, refused by its gate and
    /// late; else `None`.
    #[getter]
    fn sensing_counts(&self) -> Option<PySensingCounts> {
        self.run.sensing.as_ref().map(|r| PySensingCounts {
            imu_samples: r.imu_samples,
            gyro_saturated_samples: r.gyro_saturated_samples,
            accel_saturated_samples: r.accel_saturated_samples,
            fused_measurements: r.fusion.fused,
            rejected_measurements: r.fusion.rejected,
            late_measurements: r.fusion.late,
        })
    }
    #[getter]
    fn divergence(&self) -> Option<PyDivergence> {
        self.run.divergence.map(|d| {
            let impact = d.impact();
            PyDivergence {
                time_s: d.time_s,
                reason: d.reason.name(),
                description: d.reason.describe(),
                state: state_vector(&d.state),
                impact_speed_m_s: impact.map(|i| i.speed_m_s),
                impact_vertical_speed_m_s: impact.map(|i| i.vertical_speed_m_s),
                impact_tilt_rad: impact.map(|i| i.tilt_rad),
            }
        })
    }
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

/// One closed-loop run.
#[pyfunction]
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
) -> PyResult<PyTrajectory> {
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
    Ok(PyTrajectory { run })
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
) -> PyResult<Vec<PyTrajectory>> {
    let (vehicle, actuators, count) = vehicle_and_actuators(airframe, &actuator, &drag, None)?;
    if controllers.len() != x0s.len()
        || fault_lists.len() != x0s.len()
        || settles.len() != x0s.len()
    {
        return Err(PyValueError::new_err(
            "runs: controllers, initial states, fault lists and initial commands must have one entry per run",
        ));
    }
    let efficiency = slice1("efficiency", &efficiency)?.to_vec();
    let config = &config.inner;
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
    let results = detached(py, |cancel| {
        core_batch(&vehicle, &actuators, &efficiency, runs, config, cancel)
    })?;
    Ok(results
        .into_iter()
        .map(|run| PyTrajectory { run })
        .collect())
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
