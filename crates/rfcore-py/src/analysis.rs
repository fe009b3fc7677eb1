//! Bindings for the controllability analysis (Du et al.): ACAI, the test procedure, failure
//! tables. Translation only.

use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::analysis::{
    failure_table as core_failure_table, AcaiFormula, ControlAxes, ControllabilityAnalysis,
    ControllabilityReport,
};

use crate::airframe::PyAirframe;
use crate::convert::{detached, slice1, slice2, to_py_err};

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
pub(crate) fn acai(
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
pub(crate) fn acai_batch<'py>(
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

/// Du's 9-step procedure; returns the report as a dict.
#[pyfunction]
pub(crate) fn controllability<'py>(
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
pub(crate) fn failure_table<'py>(
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

