//! Bindings for the INDI fault-tolerant controller (Sun et al.): its gains and the controller, with
//! how it flies each failure set. The controller's rotor indices are 0-based here (the Python
//! layer converts); a failure mode names its rotors from 1.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use rfcore::control::indi::{
    DetectedFailure, FailureMode, IndiController, IndiGains, RelaxedSpin, Setpoint, YawMode,
};
use rfcore::RfError;

use crate::airframe::PyAirframe;
use crate::convert::{pickle_protocol, real, rotor_indices, rotor_numbers, to_py_err};

/// INDI gains (`rotorfault.IndiGains`); defaults from the core's `Default` (Sun's printed values
/// where he prints them), rules from its `check`.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> gains = rf.IndiGains(max_tilt_rad=0.5)
///     >>> gains.max_tilt_rad, gains.yaw
///     (0.5, 'auto')
#[pyclass(name = "IndiGains", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyIndiGains {
    pub(crate) inner: IndiGains,
}

macro_rules! indi_gains {
    ($($name:ident),*) => {
        impl PyIndiGains {
            const FIELDS: &'static [&'static str] =
                &[$(stringify!($name),)* "weights", "model_coupling", "yaw"];
        }

        pickle_protocol!(PyIndiGains, {
            #[new]
            #[pyo3(signature = (*, $($name=None,)* weights=None, model_coupling=None, yaw=None))]
            #[allow(clippy::too_many_arguments)] // keyword-only, one per gain
            fn new(
                $($name: Option<f64>,)*
                weights: Option<[f64; 4]>,
                model_coupling: Option<bool>,
                yaw: Option<&str>,
            ) -> PyResult<Self> {
                let d = IndiGains::default();
                let inner = IndiGains {
                    $($name: $name.unwrap_or(d.$name),)*
                    weights: weights.unwrap_or(d.weights),
                    model_coupling: model_coupling.unwrap_or(d.model_coupling),
                    yaw: yaw.map(YawMode::parse).transpose().map_err(to_py_err)?.unwrap_or(d.yaw),
                };
                inner.check().map_err(to_py_err)?;
                Ok(PyIndiGains { inner })
            }
            $(
                #[getter]
                fn $name(&self) -> f64 {
                    self.inner.$name
                }
            )*
            #[getter]
            fn weights(&self) -> [f64; 4] {
                self.inner.weights
            }
            #[getter]
            fn model_coupling(&self) -> bool {
                self.inner.model_coupling
            }
            #[getter]
            fn yaw(&self) -> &'static str {
                self.inner.yaw.name()
            }
        });
    };
}

indi_gains!(
    k_p_xy,
    k_v_xy,
    k_i_xy,
    k_p_z,
    k_d_z,
    max_speed_m_s,
    max_tilt_rad,
    max_vertical_accel_m_s2,
    integral_limit_m,
    k_att_p,
    k_att_d,
    k_r,
    filter_frequency_rad_s,
    filter_damping,
    output_angle_rad,
    primary_axis_tilt,
    given_up_yaw_axis_tilt,
    mismatch_time_constant_s,
    actuator_time_constant_s,
    given_up_yaw_weight,
    min_yaw_authority,
    k_spin,
    spin_weight
);

/// How the controller flies one set of failed rotors (`rotorfault.control.indi.IndiFailureMode`:
/// the core's `FailureMode`, used directly; no Python copy), decided at construction: the failed
/// and healthy rotors (numbered from 1, as wherever a rotor is named), whether yaw is held or given
/// up (the vehicle spins), whether one roll/pitch torque axis is left (two opposing rotors of a
/// quadrotor: the output is redefined, along `output_direction` in the body x-y plane), the
/// primary axis in the body frame, then the zero dynamics `eta'' = a r^2 eta - ...` (stable when
/// `a < 0`, with the damping ratio `zero_dynamics_damping`) and the thrusts holding the weight
/// with zero roll and pitch torque (N, one per rotor). Frozen, comparable, hashable, picklable
/// (keyword-only constructor from these fields, checked: what pickling calls).
#[pyclass(name = "IndiFailureMode", module = "rotorfault._rfcore", frozen)]
pub struct PyIndiFailureMode {
    inner: FailureMode,
}

impl PyIndiFailureMode {
    const FIELDS: &'static [&'static str] = &[
        "failed", "healthy", "yaw_controlled", "single_axis", "output_direction", "primary_axis",
        "zero_dynamics_a", "zero_dynamics_damping", "hover_thrust_n",
    ];
}

/// `values` as finite floats, `field[k]` naming the first that is not.
fn finite(field: &str, values: &[Bound<'_, PyAny>]) -> PyResult<Vec<f64>> {
    values
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let x = real(&format!("{field}[{k}]"), v)?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(PyValueError::new_err(format!("{field}[{k}]: must be finite, got {x}")))
            }
        })
        .collect()
}

pickle_protocol!(PyIndiFailureMode, {
    /// A failure mode from its fields (what pickling gives back; `IndiController.failure_modes`
    /// makes them): rotors numbered from 1, each rotor failed or healthy once, one hover thrust
    /// per rotor, finite numbers; `zero_dynamics_damping` only with `zero_dynamics_a`.
    #[new]
    #[pyo3(signature = (*, failed, healthy, yaw_controlled, single_axis, output_direction, primary_axis,
        zero_dynamics_a, zero_dynamics_damping, hover_thrust_n))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        failed: Vec<usize>,
        healthy: Vec<usize>,
        yaw_controlled: bool,
        single_axis: bool,
        output_direction: Option<Vec<Bound<'_, PyAny>>>,
        primary_axis: Vec<Bound<'_, PyAny>>,
        zero_dynamics_a: Option<Bound<'_, PyAny>>,
        zero_dynamics_damping: Option<Bound<'_, PyAny>>,
        hover_thrust_n: Vec<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let failed = rotor_indices("failed", &failed)?;
        let healthy = rotor_indices("healthy", &healthy)?;
        let rotors = failed.len() + healthy.len();
        let mut seen = vec![false; rotors];
        for &k in failed.iter().chain(&healthy) {
            match seen.get_mut(k) {
                Some(s) if !*s => *s = true,
                _ => {
                    return Err(PyValueError::new_err(format!(
                        "failed, healthy: each of rotors 1..={rotors} once, got rotor {} {}",
                        k + 1,
                        if k < rotors { "twice" } else { "out of range" }
                    )))
                }
            }
        }
        let hover_thrust_n = finite("hover_thrust_n", &hover_thrust_n)?;
        if hover_thrust_n.len() != rotors {
            return Err(PyValueError::new_err(format!(
                "hover_thrust_n: one per rotor ({rotors}), got {}",
                hover_thrust_n.len()
            )));
        }
        let pair = |field: &str, values: &[f64], n: usize| -> PyResult<()> {
            if values.len() == n {
                Ok(())
            } else {
                Err(PyValueError::new_err(format!("{field}: expected {n} entries, got {}", values.len())))
            }
        };
        let axis = finite("primary_axis", &primary_axis)?;
        pair("primary_axis", &axis, 3)?;
        let output_direction = match output_direction {
            Some(d) => {
                let d = finite("output_direction", &d)?;
                pair("output_direction", &d, 2)?;
                Some([d[0], d[1]])
            }
            None => None,
        };
        let scalar = |field: &str, v: Option<Bound<'_, PyAny>>| -> PyResult<Option<f64>> {
            v.map(|v| match real(field, &v)? {
                x if x.is_finite() => Ok(x),
                x => Err(PyValueError::new_err(format!("{field}: must be finite, got {x}"))),
            })
            .transpose()
        };
        let zero_dynamics = match (scalar("zero_dynamics_a", zero_dynamics_a)?, scalar("zero_dynamics_damping", zero_dynamics_damping)?) {
            (Some(a), zeta) => Some((a, zeta)),
            (None, None) => None,
            (None, Some(_)) => {
                return Err(PyValueError::new_err(
                    "zero_dynamics_damping: given without zero_dynamics_a (a damping ratio of no zero dynamics)",
                ))
            }
        };
        Ok(PyIndiFailureMode {
            inner: FailureMode {
                failed,
                healthy,
                yaw_controlled,
                single_axis,
                output_direction,
                primary_axis: [axis[0], axis[1], axis[2]],
                zero_dynamics,
                hover_thrust_n,
            },
        })
    }
    /// The failed rotors, numbered from 1.
    #[getter]
    fn failed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, rotor_numbers(&self.inner.failed))
    }
    /// The healthy rotors, numbered from 1.
    #[getter]
    fn healthy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, rotor_numbers(&self.inner.healthy))
    }
    #[getter]
    fn yaw_controlled(&self) -> bool {
        self.inner.yaw_controlled
    }
    #[getter]
    fn single_axis(&self) -> bool {
        self.inner.single_axis
    }
    /// The controlled output direction (single axis only), body x-y plane.
    #[getter]
    fn output_direction(&self) -> Option<(f64, f64)> {
        self.inner.output_direction.map(|[x, y]| (x, y))
    }
    /// The primary axis in the body frame.
    #[getter]
    fn primary_axis(&self) -> (f64, f64, f64) {
        let [x, y, z] = self.inner.primary_axis;
        (x, y, z)
    }
    /// `a` of the zero dynamics (one torque axis left only).
    #[getter]
    fn zero_dynamics_a(&self) -> Option<f64> {
        self.inner.zero_dynamics.map(|(a, _)| a)
    }
    /// Their damping ratio (`None` when unstable or not applicable).
    #[getter]
    fn zero_dynamics_damping(&self) -> Option<f64> {
        self.inner.zero_dynamics.and_then(|(_, zeta)| zeta)
    }
    /// Thrusts holding the weight with zero roll and pitch torque, N, one per rotor.
    #[getter]
    fn hover_thrust_n<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, &self.inner.hover_thrust_n)
    }
}, then = value_protocol);

/// The INDI fault-tolerant controller. `failures`: `(rotor, time_s)`, 0-based rotors the
/// controller is told have failed from `time_s` on; `setpoints`: `(time_s, position, velocity)`
/// (NED), times strictly increasing; `relaxed_spin`: `(time_s, spin_axis, spin_rate_rad_s)`, a
/// relaxed hover flown from `time_s` on (the core's `RelaxedSpin`); `spin_axis_weaker_of`: two
/// 0-based rotors, measured from `time_s` and the spin flown on the weaker's side from
/// `RelaxedSpin::flown_from_s` (`RelaxedSpin::choosing_the_weaker_of`).
#[pyclass(name = "IndiController", module = "rotorfault._rfcore", frozen)]
pub struct PyIndiController {
    pub(crate) inner: IndiController,
}

#[pymethods]
impl PyIndiController {
    #[new]
    #[pyo3(signature = (airframe, *, gains, failures, setpoints, dt_s, relaxed_spin=None, spin_axis_weaker_of=None))]
    fn new(
        airframe: &PyAirframe,
        gains: &PyIndiGains,
        failures: Vec<(usize, f64)>,
        setpoints: Vec<(f64, [f64; 3], [f64; 3])>,
        dt_s: f64,
        relaxed_spin: Option<(f64, [f64; 3], f64)>,
        spin_axis_weaker_of: Option<[usize; 2]>,
    ) -> PyResult<Self> {
        let failures = failures
            .into_iter()
            .map(|(rotor, time_s)| DetectedFailure { rotor, time_s })
            .collect();
        let setpoints = setpoints
            .into_iter()
            .map(|(time_s, position_m, velocity_m_s)| Setpoint {
                time_s,
                position_m,
                velocity_m_s,
            })
            .collect();
        // The relaxed spin's own values are checked before the controller's work (its failure
        // modes' LPs); whether it suits those modes only after.
        if spin_axis_weaker_of.is_some() && relaxed_spin.is_none() {
            return Err(to_py_err(RfError::invalid(
                "spin_axis_weaker_of",
                "given without relaxed_spin, the spin whose side it chooses",
            )));
        }
        let spin = relaxed_spin
            .map(|(time_s, axis, rate)| {
                let spin = RelaxedSpin::new(time_s, axis, rate)?;
                match spin_axis_weaker_of {
                    Some(rotors) => spin.choosing_the_weaker_of(rotors),
                    None => Ok(spin),
                }
            })
            .transpose()
            .map_err(to_py_err)?;
        let mut inner = IndiController::new(&airframe.inner, gains.inner, failures, setpoints, dt_s)
            .map_err(to_py_err)?;
        if let Some(spin) = spin {
            inner = inner.with_relaxed_spin(spin).map_err(to_py_err)?;
        }
        Ok(PyIndiController { inner })
    }

    /// How each failure set is flown: `[0]` healthy, `[k]` after the first `k` failures in time
    /// order.
    fn failure_modes(&self) -> Vec<PyIndiFailureMode> {
        self.inner
            .failure_modes()
            .into_iter()
            .map(|inner| PyIndiFailureMode { inner })
            .collect()
    }
}

impl crate::control::class::ControllerClass for PyIndiController {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
