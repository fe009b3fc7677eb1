//! Python bindings for rfcore: translation only. Arrays come in as read-only numpy views, heavy
//! calls run with the GIL released, and every core error becomes a `ValueError` carrying the
//! core's message (which names the field and the rule). No logic lives here.

use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::{
    failure_table as core_failure_table, AcaiFormula, Airframe, ControlAxes,
    ControllabilityAnalysis, ControllabilityReport, RfError,
};

mod allocation;
mod ftc;
mod simulation;

pub(crate) fn to_py_err(error: RfError) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// Runs `work` with the GIL released and converts core errors: the one helper every heavy call uses.
pub(crate) fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> rfcore::Result<T> + Send,
{
    py.detach(work).map_err(to_py_err)
}

/// Borrows a contiguous 1-D array as a slice, naming the field if it is not contiguous.
pub(crate) fn slice1<'a>(field: &str, array: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a contiguous array")))
}

pub(crate) fn slice2<'a>(field: &str, array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{field}: must be a C-contiguous array")))
}

fn read_only<'py>(py: Python<'py>, values: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    let array = values.into_pyarray(py);
    array.readwrite().make_nonwriteable();
    array
}

/// A validated multirotor airframe (the Rust side of `rotorfault.Airframe`).
#[pyclass(name = "Airframe", module = "rotorfault._rfcore", frozen)]
pub(crate) struct PyAirframe {
    pub(crate) inner: Airframe,
}

#[pymethods]
impl PyAirframe {
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        name: &str,
        arm_angle_rad: PyReadonlyArray1<'_, f64>,
        arm_length_m: PyReadonlyArray1<'_, f64>,
        spin_sign: PyReadonlyArray1<'_, f64>,
        max_thrust_n: PyReadonlyArray1<'_, f64>,
        min_thrust_n: PyReadonlyArray1<'_, f64>,
        efficiency: PyReadonlyArray1<'_, f64>,
        mass_kg: f64,
        inertia_kg_m2: PyReadonlyArray1<'_, f64>,
        drag_torque_ratio_m: f64,
        gravity_m_s2: f64,
    ) -> PyResult<Self> {
        let inner = Airframe::from_columns(
            name,
            slice1("arm_angle_rad", &arm_angle_rad)?,
            slice1("arm_length_m", &arm_length_m)?,
            slice1("spin", &spin_sign)?,
            slice1("max_thrust_n", &max_thrust_n)?,
            slice1("min_thrust_n", &min_thrust_n)?,
            slice1("efficiency", &efficiency)?,
            mass_kg,
            slice1("inertia_kg_m2", &inertia_kg_m2)?,
            drag_torque_ratio_m,
            gravity_m_s2,
        )
        .map_err(to_py_err)?;
        Ok(PyAirframe { inner })
    }

    /// Parses a TOML airframe document; `origin` prefixes error messages.
    #[staticmethod]
    fn from_toml_str(text: &str, origin: &str) -> PyResult<Self> {
        let inner = Airframe::from_toml_str(text, origin).map_err(to_py_err)?;
        Ok(PyAirframe { inner })
    }

    fn with_efficiency(&self, eta: PyReadonlyArray1<'_, f64>) -> PyResult<Self> {
        let inner = self
            .inner
            .with_efficiency(slice1("eta", &eta)?)
            .map_err(to_py_err)?;
        Ok(PyAirframe { inner })
    }

    /// The airframe as TOML text in the preset schema (exact round trip).
    fn to_toml_str(&self) -> String {
        self.inner.to_toml_string()
    }

    /// B_f (4 x m) with efficiencies applied.
    fn effectiveness_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let b = self.inner.effectiveness_matrix();
        let (rows, cols) = b.shape();
        let array = Array2::from_shape_fn((rows, cols), |(r, c)| b[(r, c)]);
        Ok(array.into_pyarray(py))
    }

    #[getter]
    fn name(&self) -> &str {
        self.inner.name()
    }
    #[getter]
    fn description(&self) -> &str {
        self.inner.description()
    }
    #[getter]
    fn rotor_count(&self) -> usize {
        self.inner.rotor_count()
    }
    #[getter]
    fn mass_kg(&self) -> f64 {
        self.inner.mass_kg()
    }
    #[getter]
    fn drag_torque_ratio_m(&self) -> f64 {
        self.inner.drag_torque_ratio_m()
    }
    #[getter]
    fn gravity_m_s2(&self) -> f64 {
        self.inner.gravity_m_s2()
    }
    #[getter]
    fn inertia_kg_m2<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.inertia_kg_m2().to_vec())
    }
    #[getter]
    fn arm_angle_rad<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(
            py,
            self.inner
                .rotors()
                .iter()
                .map(|r| r.arm_angle_rad)
                .collect(),
        )
    }
    #[getter]
    fn arm_length_m<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(
            py,
            self.inner.rotors().iter().map(|r| r.arm_length_m).collect(),
        )
    }
    #[getter]
    fn spin_sign<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(
            py,
            self.inner
                .rotors()
                .iter()
                .map(|r| r.spin.yaw_sign())
                .collect(),
        )
    }
    #[getter]
    fn max_thrust_n<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.max_thrust_n())
    }
    #[getter]
    fn min_thrust_n<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.min_thrust_n())
    }
    #[getter]
    fn efficiency<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.efficiency())
    }
}

fn analysis(airframe: &PyAirframe, give_up_yaw: bool) -> rfcore::Result<ControllabilityAnalysis> {
    ControllabilityAnalysis::new(&airframe.inner, ControlAxes::from_give_up_yaw(give_up_yaw))
}

fn report_dict<'py>(
    py: Python<'py>,
    report: &ControllabilityReport,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("state_dimension", report.state_dimension)?;
    dict.set_item("controllability_rank", report.controllability_rank)?;
    dict.set_item(
        "virtual_control_dimension",
        report.virtual_control_dimension,
    )?;
    dict.set_item("effectiveness_rank", report.effectiveness_rank)?;
    dict.set_item("acai", report.acai)?;
    dict.set_item("formula", report.formula.name())?;
    dict.set_item("verdict", report.verdict.code())?;
    dict.set_item("controllable", report.verdict.is_controllable())?;
    Ok(dict)
}

/// ACAI of `airframe` with efficiencies `eta` (Du Theorem 3).
#[pyfunction]
fn acai(
    py: Python<'_>,
    airframe: &PyAirframe,
    eta: PyReadonlyArray1<'_, f64>,
    give_up_yaw: bool,
    formula: &str,
) -> PyResult<f64> {
    let eta = slice1("eta", &eta)?;
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    detached(py, || analysis(airframe, give_up_yaw)?.acai(eta, formula))
}

/// ACAI for every row of `etas` (N x m), in parallel.
#[pyfunction]
fn acai_batch<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    etas: PyReadonlyArray2<'py, f64>,
    give_up_yaw: bool,
    formula: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let m = airframe.inner.rotor_count();
    if etas.shape()[1] != m {
        return Err(PyValueError::new_err(format!(
            "etas: expected {m} columns (one efficiency per rotor), got {}",
            etas.shape()[1]
        )));
    }
    let flat = slice2("etas", &etas)?;
    let values = detached(py, || {
        analysis(airframe, give_up_yaw)?.acai_batch(flat, formula)
    })?;
    Ok(values.into_pyarray(py))
}

/// ACAI of an arbitrary effectiveness matrix (n x m), thrust box and hover wrench.
#[pyfunction]
fn acai_from_matrix(
    py: Python<'_>,
    effectiveness_matrix: PyReadonlyArray2<'_, f64>,
    f_min: PyReadonlyArray1<'_, f64>,
    f_max: PyReadonlyArray1<'_, f64>,
    g_vec: PyReadonlyArray1<'_, f64>,
    formula: &str,
) -> PyResult<f64> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let shape = effectiveness_matrix.shape();
    let (rows, cols) = (shape[0], shape[1]);
    let flat = slice2("effectiveness_matrix", &effectiveness_matrix)?;
    let (f_min, f_max, g_vec) = (
        slice1("f_min", &f_min)?,
        slice1("f_max", &f_max)?,
        slice1("g_vec", &g_vec)?,
    );
    detached(py, || {
        let b = nalgebra::DMatrix::from_row_slice(rows, cols, flat);
        rfcore::acai_from_matrix(&b, f_min, f_max, g_vec, formula)
    })
}

/// Du's 9-step procedure; returns the report as a dict.
#[pyfunction]
fn controllability<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    eta: PyReadonlyArray1<'py, f64>,
    give_up_yaw: bool,
    formula: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let eta = slice1("eta", &eta)?;
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let report = detached(py, || analysis(airframe, give_up_yaw)?.report(eta, formula))?;
    report_dict(py, &report)
}

/// One failure-table row: failed rotors (0-based), report with yaw, report without yaw.
type FailureRow<'py> = (Vec<usize>, Bound<'py, PyDict>, Bound<'py, PyDict>);

/// Every combination of up to `max_failed` failed rotors.
#[pyfunction]
fn failure_table<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    max_failed: usize,
    formula: &str,
) -> PyResult<Vec<FailureRow<'py>>> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let cases = detached(py, || {
        core_failure_table(&airframe.inner, max_failed, formula)
    })?;
    cases
        .iter()
        .map(|case| {
            Ok((
                case.failed.clone(),
                report_dict(py, &case.with_yaw)?,
                report_dict(py, &case.without_yaw)?,
            ))
        })
        .collect()
}

#[pymodule]
fn _rfcore(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<PyAirframe>()?;
    module.add_class::<simulation::PyFixedPitch>()?;
    module.add_class::<simulation::PyVariablePitch>()?;
    module.add_class::<simulation::PyOpenLoop>()?;
    module.add_class::<simulation::PyLinearFeedback>()?;
    module.add_class::<simulation::PyDiscreteLti>()?;
    module.add_class::<allocation::PyAllocationProblem>()?;
    module.add_class::<allocation::PyAllocated>()?;
    module.add_class::<ftc::PyUniformPassiveFtc>()?;
    module.add_function(wrap_pyfunction!(ftc::ftc_preset_from_toml, module)?)?;
    module.add_function(wrap_pyfunction!(ftc::replay, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::allocate, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::time_allocations, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::max_along_direction, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::hover_thrust_margin, module)?)?;
    module.add_function(wrap_pyfunction!(simulation::simulate, module)?)?;
    module.add_function(wrap_pyfunction!(simulation::simulate_batch, module)?)?;
    module.add_function(wrap_pyfunction!(simulation::state_derivative, module)?)?;
    module.add_function(wrap_pyfunction!(acai, module)?)?;
    module.add_function(wrap_pyfunction!(acai_batch, module)?)?;
    module.add_function(wrap_pyfunction!(acai_from_matrix, module)?)?;
    module.add_function(wrap_pyfunction!(controllability, module)?)?;
    module.add_function(wrap_pyfunction!(failure_table, module)?)?;
    module.add("RANK_RTOL", rfcore::RANK_RTOL)?;
    module.add("ZERO_RTOL", rfcore::ZERO_RTOL)?;
    module.add("DEFAULT_GRAVITY_M_S2", rfcore::DEFAULT_GRAVITY_M_S2)?;
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
