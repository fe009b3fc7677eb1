//! Bindings for the controllability analysis (Du et al.): ACAI, the test procedure, failure
//! tables. Translation only.

use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use rfcore::analysis::{
    failure_table as core_failure_table, AcaiFormula, ControlAxes, ControllabilityAnalysis,
    ControllabilityReport,
};

use crate::airframe::PyAirframe;
use crate::convert::{detached, slice1, slice2, to_py_err};

fn analysis(airframe: &PyAirframe, give_up_yaw: bool) -> rfcore::Result<ControllabilityAnalysis> {
    ControllabilityAnalysis::new(&airframe.inner, ControlAxes::from_give_up_yaw(give_up_yaw))
}

/// One controllability report (Du's procedure) as a named result.
#[pyclass(name = "ControllabilityReport", module = "rotorfault._rfcore", frozen)]
pub struct PyControllabilityReport {
    inner: ControllabilityReport,
}

#[pymethods]
impl PyControllabilityReport {
    #[getter]
    fn state_dimension(&self) -> usize {
        self.inner.state_dimension
    }
    #[getter]
    fn controllability_rank(&self) -> usize {
        self.inner.controllability_rank
    }
    #[getter]
    fn virtual_control_dimension(&self) -> usize {
        self.inner.virtual_control_dimension
    }
    #[getter]
    fn effectiveness_rank(&self) -> usize {
        self.inner.effectiveness_rank
    }
    #[getter]
    fn acai(&self) -> f64 {
        self.inner.acai
    }
    #[getter]
    fn formula(&self) -> &'static str {
        self.inner.formula.name()
    }
    #[getter]
    fn verdict(&self) -> &'static str {
        self.inner.verdict.code()
    }
    #[getter]
    fn controllable(&self) -> bool {
        self.inner.verdict.is_controllable()
    }
}

fn report(report: ControllabilityReport) -> PyControllabilityReport {
    PyControllabilityReport { inner: report }
}

/// ACAI of `airframe` with efficiencies `efficiency` (Du Theorem 3).
#[pyfunction]
pub(crate) fn acai(
    py: Python<'_>,
    airframe: &PyAirframe,
    efficiency: PyReadonlyArray1<'_, f64>,
    give_up_yaw: bool,
    formula: &str,
) -> PyResult<f64> {
    let efficiency = slice1("efficiency", &efficiency)?;
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    detached(py, || analysis(airframe, give_up_yaw)?.acai(efficiency, formula))
}

/// ACAI for every row of `efficiencies` (N x m), in parallel.
#[pyfunction]
pub(crate) fn acai_batch<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    efficiencies: PyReadonlyArray2<'py, f64>,
    give_up_yaw: bool,
    formula: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let m = airframe.inner.rotor_count();
    if efficiencies.shape()[1] != m {
        return Err(PyValueError::new_err(format!(
            "efficiencies: expected {m} columns (one efficiency per rotor), got {}",
            efficiencies.shape()[1]
        )));
    }
    let flat = slice2("efficiencies", &efficiencies)?;
    let values = detached(py, || {
        analysis(airframe, give_up_yaw)?.acai_batch(flat, formula)
    })?;
    Ok(values.into_pyarray(py))
}

/// ACAI of an arbitrary effectiveness matrix (n x m), thrust box and hover wrench.
#[pyfunction]
pub(crate) fn acai_from_matrix(
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
        rfcore::analysis::acai_from_matrix(&b, f_min, f_max, g_vec, formula)
    })
}

/// Du's 9-step procedure.
#[pyfunction]
pub(crate) fn controllability<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    efficiency: PyReadonlyArray1<'py, f64>,
    give_up_yaw: bool,
    formula: &str,
) -> PyResult<PyControllabilityReport> {
    let efficiency = slice1("efficiency", &efficiency)?;
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let result = detached(py, || analysis(airframe, give_up_yaw)?.report(efficiency, formula))?;
    Ok(report(result))
}

/// One failure-table row: failed rotors (0-based), report with yaw, report without yaw.
type FailureRow = (Vec<usize>, PyControllabilityReport, PyControllabilityReport);

/// Every combination of up to `max_failed` failed rotors.
#[pyfunction]
pub(crate) fn failure_table<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    max_failed: usize,
    formula: &str,
) -> PyResult<Vec<FailureRow>> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let cases = detached(py, || {
        core_failure_table(&airframe.inner, max_failed, formula)
    })?;
    Ok(cases
        .into_iter()
        .map(|case| (case.failed, report(case.with_yaw), report(case.without_yaw)))
        .collect())
}

