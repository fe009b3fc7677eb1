//! Bindings for one run's record: the `Trajectory` (the one trajectory type, subclassed by
//! `rotorfault.Trajectory`), its `Divergence` and its `SensingCounts`. Translation and shape
//! checks only; the record is the core's (`rfcore::flight::simulation::Trajectory`).

use numpy::{IntoPyArray, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::flight::simulation::{Divergence, EstimateRow, SensingRecord, Trajectory};
use rfcore::state::{state_vector, RigidBodyState, STATE_DIM};

use crate::convert::{real, settings_kwargs};

/// Why and when a run ended early, with the 12-element state vector at that moment; for a
/// `crashed` run, the impact (speed, speed into the ground, tilt), else `None`. Made by the
/// simulator, or keyword-only from Python (a constructed run's event): `time_s` and the impact
/// finite, `state` 12 numbers.
#[pyclass(name = "Divergence", module = "rotorfault._rfcore", frozen, get_all)]
pub struct PyDivergence {
    time_s: f64,
    reason: String,
    description: String,
    state: [f64; STATE_DIM],
    impact_speed_m_s: Option<f64>,
    impact_vertical_speed_m_s: Option<f64>,
    impact_tilt_rad: Option<f64>,
}

/// A finite real number for `field`.
fn finite_real(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    let x = real(field, value)?;
    if !x.is_finite() {
        return Err(PyValueError::new_err(format!("{field}: must be finite, got {x}")));
    }
    Ok(x)
}

/// [`finite_real`], `None` staying `None`.
fn finite(field: &str, value: Option<Bound<'_, PyAny>>) -> PyResult<Option<f64>> {
    value.map(|v| finite_real(field, &v)).transpose()
}

impl PyDivergence {
    const FIELDS: &'static [&'static str] = &[
        "time_s", "reason", "description", "state", "impact_speed_m_s", "impact_vertical_speed_m_s", "impact_tilt_rad",
    ];
}

#[pymethods]
impl PyDivergence {
    fn __getnewargs_ex__<'py>(slf: &Bound<'py, Self>) -> PyResult<((), Bound<'py, PyDict>)> {
        Ok(((), settings_kwargs(slf.as_any(), Self::FIELDS)?))
    }
    #[new]
    #[pyo3(signature = (*, time_s, reason, description, state, impact_speed_m_s=None, impact_vertical_speed_m_s=None, impact_tilt_rad=None))]
    fn new(
        time_s: Bound<'_, PyAny>,
        reason: String,
        description: String,
        state: [f64; STATE_DIM],
        impact_speed_m_s: Option<Bound<'_, PyAny>>,
        impact_vertical_speed_m_s: Option<Bound<'_, PyAny>>,
        impact_tilt_rad: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        Ok(PyDivergence {
            time_s: finite_real("time_s", &time_s)?,
            reason,
            description,
            state,
            impact_speed_m_s: finite("impact_speed_m_s", impact_speed_m_s)?,
            impact_vertical_speed_m_s: finite("impact_vertical_speed_m_s", impact_vertical_speed_m_s)?,
            impact_tilt_rad: finite("impact_tilt_rad", impact_tilt_rad)?,
        })
    }
}

impl From<Divergence> for PyDivergence {
    fn from(d: Divergence) -> Self {
        let impact = d.impact();
        PyDivergence {
            time_s: d.time_s,
            reason: d.reason.name().to_string(),
            description: d.reason.describe().to_string(),
            state: state_vector(&d.state),
            impact_speed_m_s: impact.map(|i| i.speed_m_s),
            impact_vertical_speed_m_s: impact.map(|i| i.vertical_speed_m_s),
            impact_tilt_rad: impact.map(|i| i.tilt_rad),
        }
    }
}

/// The sensor counts class from one list of its fields (each a `u64`).
macro_rules! counts_class {
    ($($name:ident),+ $(,)?) => {
        /// A run's sensor counts (`Trajectory.sensing_counts`); keyword-only from Python (pickling).
        #[pyclass(name = "SensingCounts", module = "rotorfault._rfcore", frozen, get_all)]
        pub struct PySensingCounts {
            $($name: u64),+
        }

        impl PySensingCounts {
            const FIELDS: &'static [&'static str] = &[$(stringify!($name)),+];
        }

        #[pymethods]
        impl PySensingCounts {
            #[new]
            #[pyo3(signature = (*, $($name),+))]
            fn new($($name: u64),+) -> Self {
                PySensingCounts { $($name),+ }
            }
            fn __getnewargs_ex__<'py>(slf: &Bound<'py, Self>) -> PyResult<((), Bound<'py, PyDict>)> {
                Ok(((), settings_kwargs(slf.as_any(), Self::FIELDS)?))
            }
        }
    };
}

counts_class!(
    imu_samples,
    gyro_saturated_samples,
    accel_saturated_samples,
    fused_measurements,
    rejected_measurements,
    late_measurements,
    thinned_measurements,
);

impl From<&SensingRecord> for PySensingCounts {
    fn from(r: &SensingRecord) -> Self {
        PySensingCounts {
            imu_samples: r.imu_samples,
            gyro_saturated_samples: r.gyro_saturated_samples,
            accel_saturated_samples: r.accel_saturated_samples,
            fused_measurements: r.fusion.fused,
            rejected_measurements: r.fusion.rejected,
            late_measurements: r.fusion.late,
            thinned_measurements: r.fusion.thinned,
        }
    }
}

/// One run sampled at the control rate, the one trajectory type (`rotorfault.Trajectory`
/// subclasses it, adding what reads it in Python: tables, plots, derived arrays). Its arrays are
/// NumPy arrays with one row per recorded step, made once: by the simulator from the core's
/// record, or given keyword-only (a batch's views, a constructed run), their shapes checked
/// here. Frozen; picklable.
#[pyclass(name = "Trajectory", module = "rotorfault._rfcore", frozen, subclass, get_all)]
pub struct PyTrajectory {
    /// Time of each row, s.
    t: Py<PyAny>,
    /// NED position, m.
    position: Py<PyAny>,
    /// NED velocity, m/s.
    velocity: Py<PyAny>,
    /// Attitude quaternion `w x y z` (body to world).
    quaternion: Py<PyAny>,
    /// Z-Y-X Euler angles roll, pitch, yaw, rad.
    euler: Py<PyAny>,
    /// Body rates p, q, r (FRD), rad/s.
    omega: Py<PyAny>,
    /// Body z in the world frame (Ke's n3).
    primary_axis: Py<PyAny>,
    /// The commands (N per rotor for fixed pitch; speed and pitch interleaved for variable pitch).
    rotor_command: Py<PyAny>,
    /// The rotors' produced thrusts, N.
    rotor_thrust: Py<PyAny>,
    /// Rotor efficiencies applied at each row (faults included), 0 to 1.
    efficiency: Py<PyAny>,
    /// Sensor readings as the core recorded them (12 columns with sensor noise, else none).
    recorded_measurements: Py<PyAny>,
    /// What the controller flew on: `"truth"`, `"paper-noise"` or the sensor suite's name.
    sensed: String,
    /// Why and when the run ended early, or `None`.
    divergence: Option<Py<PyDivergence>>,
    /// With sensing, the estimate per row (13: position, velocity, quaternion `w x y z`, body
    /// rates); else `None`.
    estimate_state: Option<Py<PyAny>>,
    /// With sensing, the estimate's Euler angles per row, rad; else `None`.
    estimate_euler: Option<Py<PyAny>>,
    /// With sensing, one sigma of the estimator's 15-element error state per row; else `None`.
    estimate_std: Option<Py<PyAny>>,
    /// With sensing, per row: the newest IMU sample's gyroscope was clamped; else `None`.
    gyro_saturated: Option<Py<PyAny>>,
    /// With sensing, per row: the newest IMU sample's accelerometer was clamped; else `None`.
    accel_saturated: Option<Py<PyAny>>,
    /// With sensing, the run's totals (IMU samples, clamped samples, measurements fused, refused
    /// by the gate, late); else `None`.
    sensing_counts: Option<Py<PySensingCounts>>,
}

/// The estimate fields, present together (a run with sensing) or not at all.
const ESTIMATE_FIELDS: [&str; 6] = ["estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated", "sensing_counts"];

/// An array `field` of `ndim` dimensions with `rows` rows and, for a table, a width in `widths`
/// (any width when empty); returns its width.
fn shaped(field: &str, value: &Bound<'_, PyAny>, ndim: usize, rows: Option<usize>, widths: &[usize]) -> PyResult<usize> {
    let array = value.cast::<PyUntypedArray>().map_err(|_| {
        PyTypeError::new_err(format!("{field}: expected a NumPy array, got {}", value.get_type().name().map(|n| n.to_string()).unwrap_or_default()))
    })?;
    let shape = array.shape();
    if shape.len() != ndim {
        return Err(PyValueError::new_err(format!("{field}: expected {ndim} dimensions, got shape {shape:?}")));
    }
    if let Some(rows) = rows {
        if shape[0] != rows {
            return Err(PyValueError::new_err(format!(
                "{field}: expected {rows} rows (one per time in t), got shape {shape:?}"
            )));
        }
    }
    let width = if ndim == 2 { shape[1] } else { 1 };
    if !widths.is_empty() && !widths.contains(&width) {
        let allowed: Vec<String> = widths.iter().map(|w| w.to_string()).collect();
        return Err(PyValueError::new_err(format!(
            "{field}: expected {} columns, got shape {shape:?}",
            allowed.join(" or ")
        )));
    }
    Ok(width)
}

impl PyTrajectory {
    const FIELDS: &'static [&'static str] = &[
        "t", "position", "velocity", "quaternion", "euler", "omega", "primary_axis", "rotor_command",
        "rotor_thrust", "efficiency", "recorded_measurements", "sensed", "divergence",
        "estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated",
        "sensing_counts",
    ];

    /// The core's record as arrays, each made once (the record's own vectors moved, not copied).
    pub(crate) fn from_run(py: Python<'_>, run: Trajectory) -> PyResult<Self> {
        let n = run.t_s.len();
        let sensed = run.sensed().to_string();
        let table = |values: Vec<f64>| -> PyResult<Py<PyAny>> {
            let cols = values.len().checked_div(n).unwrap_or(0);
            Ok(values.into_pyarray(py).reshape([n, cols])?.into_any().unbind())
        };
        let states = &run.states;
        let per_state = |f: fn(&RigidBodyState) -> [f64; 3]| table(rows(states, f));
        let sensing = run.sensing.as_ref();
        let flags = |f: fn(&EstimateRow) -> bool| {
            sensing.map(|r| r.rows.iter().map(f).collect::<Vec<bool>>().into_pyarray(py).into_any().unbind())
        };
        Ok(PyTrajectory {
            position: per_state(|s| s.position_m.into())?,
            velocity: per_state(|s| s.velocity_m_s.into())?,
            quaternion: table(rows(states, |s| {
                let q = s.attitude.quaternion();
                [q.w, q.i, q.j, q.k]
            }))?,
            euler: per_state(|s| s.euler_rad())?,
            omega: per_state(|s| s.omega_rad_s.into())?,
            primary_axis: per_state(|s| s.primary_axis().into())?,
            estimate_state: sensing.map(|r| table(rows(&r.rows, |row| row.state.to_packed()))).transpose()?,
            estimate_euler: sensing.map(|r| table(rows(&r.rows, |row| row.state.euler_rad()))).transpose()?,
            estimate_std: sensing.map(|r| table(rows(&r.rows, |row| row.std))).transpose()?,
            gyro_saturated: flags(|row| row.gyro_saturated),
            accel_saturated: flags(|row| row.accel_saturated),
            sensing_counts: sensing.map(|r| Py::new(py, PySensingCounts::from(r))).transpose()?,
            t: run.t_s.into_pyarray(py).into_any().unbind(),
            rotor_command: table(run.commands)?,
            rotor_thrust: table(run.thrust_n)?,
            efficiency: table(run.efficiency)?,
            recorded_measurements: table(run.measured)?,
            sensed,
            divergence: run.divergence.map(|d| Py::new(py, PyDivergence::from(d))).transpose()?,
        })
    }
}

/// `f` of every row, flattened row-major (no allocation per row).
fn rows<R, const N: usize>(rows: &[R], f: impl Fn(&R) -> [f64; N]) -> Vec<f64> {
    rows.iter().flat_map(f).collect()
}

#[pymethods]
impl PyTrajectory {
    #[new]
    #[pyo3(signature = (*, t, position, velocity, quaternion, euler, omega, primary_axis, rotor_command,
        rotor_thrust, efficiency, recorded_measurements, sensed=None, divergence=None,
        estimate_state=None, estimate_euler=None, estimate_std=None, gyro_saturated=None,
        accel_saturated=None, sensing_counts=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        t: Bound<'_, PyAny>,
        position: Bound<'_, PyAny>,
        velocity: Bound<'_, PyAny>,
        quaternion: Bound<'_, PyAny>,
        euler: Bound<'_, PyAny>,
        omega: Bound<'_, PyAny>,
        primary_axis: Bound<'_, PyAny>,
        rotor_command: Bound<'_, PyAny>,
        rotor_thrust: Bound<'_, PyAny>,
        efficiency: Bound<'_, PyAny>,
        recorded_measurements: Bound<'_, PyAny>,
        sensed: Option<String>,
        divergence: Option<Py<PyDivergence>>,
        estimate_state: Option<Bound<'_, PyAny>>,
        estimate_euler: Option<Bound<'_, PyAny>>,
        estimate_std: Option<Bound<'_, PyAny>>,
        gyro_saturated: Option<Bound<'_, PyAny>>,
        accel_saturated: Option<Bound<'_, PyAny>>,
        sensing_counts: Option<Py<PySensingCounts>>,
    ) -> PyResult<Self> {
        shaped("t", &t, 1, None, &[])?;
        let rows = Some(t.len()?);
        for (field, value, width) in [
            ("position", &position, 3),
            ("velocity", &velocity, 3),
            ("quaternion", &quaternion, 4),
            ("euler", &euler, 3),
            ("omega", &omega, 3),
            ("primary_axis", &primary_axis, 3),
        ] {
            shaped(field, value, 2, rows, &[width])?;
        }
        let rotors = shaped("efficiency", &efficiency, 2, rows, &[])?;
        shaped("rotor_thrust", &rotor_thrust, 2, rows, &[rotors])?;
        shaped("rotor_command", &rotor_command, 2, rows, &[rotors, 2 * rotors])?;
        shaped("recorded_measurements", &recorded_measurements, 2, rows, &[0, STATE_DIM])?;
        let given = [&estimate_state, &estimate_euler, &estimate_std, &gyro_saturated, &accel_saturated]
            .iter()
            .filter(|v| v.is_some())
            .count()
            + usize::from(sensing_counts.is_some());
        if given != 0 && given != ESTIMATE_FIELDS.len() {
            return Err(PyValueError::new_err(format!(
                "{}: give all or none (a run with sensing has all)",
                ESTIMATE_FIELDS.join(", ")
            )));
        }
        for (field, value, ndim, width) in [
            ("estimate_state", &estimate_state, 2, 13),
            ("estimate_euler", &estimate_euler, 2, 3),
            ("estimate_std", &estimate_std, 2, 15),
            ("gyro_saturated", &gyro_saturated, 1, 1),
            ("accel_saturated", &accel_saturated, 1, 1),
        ] {
            if let Some(value) = value {
                shaped(field, value, ndim, rows, &[width])?;
            }
        }
        let keep = |v: Option<Bound<'_, PyAny>>| v.map(Bound::unbind);
        Ok(PyTrajectory {
            t: t.unbind(),
            position: position.unbind(),
            velocity: velocity.unbind(),
            quaternion: quaternion.unbind(),
            euler: euler.unbind(),
            omega: omega.unbind(),
            primary_axis: primary_axis.unbind(),
            rotor_command: rotor_command.unbind(),
            rotor_thrust: rotor_thrust.unbind(),
            efficiency: efficiency.unbind(),
            recorded_measurements: recorded_measurements.unbind(),
            // What a run without noise or sensing flew on (the simulator's name for it).
            sensed: sensed.unwrap_or_else(|| "truth".to_string()),
            divergence,
            estimate_state: keep(estimate_state),
            estimate_euler: keep(estimate_euler),
            estimate_std: keep(estimate_std),
            gyro_saturated: keep(gyro_saturated),
            accel_saturated: keep(accel_saturated),
            sensing_counts,
        })
    }
    /// Whether the run ended early (it has a `divergence`).
    #[getter]
    fn diverged(&self) -> bool {
        self.divergence.is_some()
    }
    /// The field names, in order (the constructor's keywords).
    #[classattr]
    #[pyo3(name = "FIELDS")]
    fn fields() -> Vec<&'static str> {
        Self::FIELDS.to_vec()
    }
    /// `Trajectory(<rows> rows to <end> s, <how it ended>)`: the arrays are too long to print.
    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let this = slf.get();
        let py = slf.py();
        let t = this.t.bind(py);
        let rows = t.len()?;
        let end = if rows == 0 { "no rows".to_string() } else { format!("{rows} rows to {} s", t.get_item(rows - 1)?.str()?) };
        let ended = match &this.divergence {
            None => "no divergence".to_string(),
            Some(d) => {
                let d = d.get();
                format!("{} at {} s", d.reason, d.time_s)
            }
        };
        Ok(format!("{}({end}, {ended}, sensed={:?})", slf.get_type().name()?, this.sensed))
    }
    fn __getnewargs_ex__<'py>(slf: &Bound<'py, Self>) -> PyResult<((), Bound<'py, PyDict>)> {
        Ok(((), settings_kwargs(slf.as_any(), Self::FIELDS)?))
    }
}
