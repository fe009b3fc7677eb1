//! Bindings for a batch recorded into columns (`simulate_batch_columns`): each signal one NumPy
//! array of shape `(runs, grid_rows + 1, width)`, handed over without a copy (the core's buffer
//! becomes the array's). Translation only; the layout is the core's
//! (`rfcore::flight::simulation::columns`).

use numpy::{IntoPyArray, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use rfcore::flight::simulation::{simulate_batch_columns as core_columns, BatchColumns, BatchLanes, Column, Sample};

use crate::airframe::PyAirframe;
use crate::control::ControllerArg;
use crate::convert::{deprecated, detached};
use crate::flight::{batch_runs, ActuatorArg, PyDrag, PySimulationConfig};
use crate::trajectory::{PyDivergence, PySensingCounts};

/// A batch's recording, one array per signal (`runs x (grid_rows + 1) x width`; see
/// `rotorfault.flight.trajectory.BatchResult`): slot row `j < grid_rows` is the run's row at the
/// `j`-th grid time (NaN after its last), the last slot row an off-grid divergence row (else
/// NaN). Per run: rows on the grid, whether it has an off-grid row, its divergence, its sensing
/// counts and what it flew on. The signals have `Trajectory`'s names (`rotor_command`,
/// `rotor_thrust`, `recorded_measurements`; the old `command`, `thrust`, `measured` warn).
#[pyclass(name = "BatchColumns", module = "rotorfault._rfcore", frozen, get_all)]
pub struct PyBatchColumns {
    grid_rows: usize,
    position: Py<PyAny>,
    velocity: Py<PyAny>,
    quaternion: Py<PyAny>,
    euler: Py<PyAny>,
    omega: Py<PyAny>,
    primary_axis: Py<PyAny>,
    rotor_command: Py<PyAny>,
    rotor_thrust: Py<PyAny>,
    efficiency: Py<PyAny>,
    recorded_measurements: Py<PyAny>,
    estimate_state: Py<PyAny>,
    estimate_euler: Py<PyAny>,
    estimate_std: Py<PyAny>,
    gyro_saturated: Py<PyAny>,
    accel_saturated: Py<PyAny>,
    rows_on_grid: Py<PyAny>,
    off_grid_row: Py<PyAny>,
    divergences: Vec<Option<Py<PyDivergence>>>,
    sensing_counts: Vec<Option<Py<PySensingCounts>>>,
    sensed: Vec<&'static str>,
}

/// The old names of three signals, kept one release (`DeprecationWarning`).
#[pymethods]
impl PyBatchColumns {
    /// Deprecated name of `rotor_command`.
    #[getter]
    fn command(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        deprecated(py, "BatchColumns.command", "BatchColumns.rotor_command")?;
        Ok(self.rotor_command.clone_ref(py))
    }
    /// Deprecated name of `rotor_thrust`.
    #[getter]
    fn thrust(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        deprecated(py, "BatchColumns.thrust", "BatchColumns.rotor_thrust")?;
        Ok(self.rotor_thrust.clone_ref(py))
    }
    /// Deprecated name of `recorded_measurements`.
    #[getter]
    fn measured(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        deprecated(py, "BatchColumns.measured", "BatchColumns.recorded_measurements")?;
        Ok(self.recorded_measurements.clone_ref(py))
    }
}

fn block<T: Sample + numpy::Element>(py: Python<'_>, column: Column<T>, runs: usize, slot_rows: usize) -> PyResult<Py<PyAny>> {
    Ok(column.values.into_pyarray(py).reshape([runs, slot_rows, column.width])?.into_any().unbind())
}

fn flags(py: Python<'_>, values: Vec<bool>, runs: usize, slot_rows: usize) -> PyResult<Py<PyAny>> {
    let slot = if values.is_empty() { 0 } else { slot_rows };
    Ok(values.into_pyarray(py).reshape([runs, slot])?.into_any().unbind())
}

fn to_python<T: Sample + numpy::Element>(py: Python<'_>, c: BatchColumns<T>) -> PyResult<PyBatchColumns> {
    let (n, slot) = (c.runs, c.grid_rows + 1);
    let rows: Vec<i64> = c.records.iter().map(|r| r.grid_rows as i64).collect();
    let off: Vec<bool> = c.records.iter().map(|r| r.off_grid_row).collect();
    Ok(PyBatchColumns {
        grid_rows: c.grid_rows,
        position: block(py, c.position_m, n, slot)?,
        velocity: block(py, c.velocity_m_s, n, slot)?,
        quaternion: block(py, c.quaternion, n, slot)?,
        euler: block(py, c.euler_rad, n, slot)?,
        omega: block(py, c.omega_rad_s, n, slot)?,
        primary_axis: block(py, c.primary_axis, n, slot)?,
        rotor_command: block(py, c.rotor_command, n, slot)?,
        rotor_thrust: block(py, c.rotor_thrust_n, n, slot)?,
        efficiency: block(py, c.efficiency, n, slot)?,
        recorded_measurements: block(py, c.recorded_measurements, n, slot)?,
        estimate_state: block(py, c.estimate_packed, n, slot)?,
        estimate_euler: block(py, c.estimate_euler_rad, n, slot)?,
        estimate_std: block(py, c.estimate_std, n, slot)?,
        gyro_saturated: flags(py, c.gyro_saturated, n, slot)?,
        accel_saturated: flags(py, c.accel_saturated, n, slot)?,
        rows_on_grid: rows.into_pyarray(py).into_any().unbind(),
        off_grid_row: off.into_pyarray(py).into_any().unbind(),
        divergences: c
            .records
            .iter()
            .map(|r| r.divergence.map(|d| Py::new(py, PyDivergence::from(d))).transpose())
            .collect::<PyResult<_>>()?,
        sensing_counts: c
            .records
            .iter()
            .map(|r| r.sensing.as_ref().map(|s| Py::new(py, PySensingCounts::from(s))).transpose())
            .collect::<PyResult<_>>()?,
        sensed: c.records.iter().map(|r| r.sensed).collect(),
    })
}

/// Many runs in parallel, recorded into columns of `dtype` (`"float64"` or `"float32"`); the
/// arguments are `simulate_batch`'s.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn simulate_batch_columns<'py>(
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
    dtype: &str,
    lanes: &str,
) -> PyResult<PyBatchColumns> {
    if dtype != "float64" && dtype != "float32" {
        return Err(PyValueError::new_err(format!(
            "dtype: must be 'float64' or 'float32', got {dtype:?}"
        )));
    }
    let lanes = match lanes {
        "auto" => BatchLanes::Auto,
        "portable" => BatchLanes::Portable,
        "scalar" => BatchLanes::Scalar,
        other => {
            return Err(PyValueError::new_err(format!(
                "lanes: must be 'auto', 'portable' or 'scalar', got {other:?}"
            )))
        }
    };
    let (vehicle, actuators, efficiency, runs) =
        batch_runs(airframe, &actuator, &drag, &controllers, &x0s, &fault_lists, settles, &efficiency)?;
    let config = &config.inner;
    if dtype == "float32" {
        let columns = detached(py, |cancel| core_columns::<f32>(&vehicle, &actuators, &efficiency, runs, config, cancel, lanes))?;
        to_python(py, columns)
    } else {
        let columns = detached(py, |cancel| core_columns::<f64>(&vehicle, &actuators, &efficiency, runs, config, cancel, lanes))?;
        to_python(py, columns)
    }
}

