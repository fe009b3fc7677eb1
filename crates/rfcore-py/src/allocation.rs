//! Bindings for control allocation: the problem type, batch allocation and attainable-set
//! queries. Translation only.

use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use rfcore::allocation::clarabel::{
    hover_thrust_margin as core_hover_margin, max_along_direction as core_max_along,
    ClarabelSettings,
};
use rfcore::allocation::{allocate_many, time_each, Allocation, AllocationProblem, Method};
use rfcore::analysis::ControlAxes;

use crate::airframe::PyAirframe;
use crate::convert::{detached, matrix, slice1, slice2, to_py_err};

type BoundsPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// A validated allocation problem (matrix, weights, bounds, regularisation).
#[pyclass(name = "AllocationProblem", module = "rotorfault._rfcore", frozen)]
pub struct PyAllocationProblem {
    pub(crate) inner: AllocationProblem,
}

#[pymethods]
impl PyAllocationProblem {
    #[new]
    fn new(
        matrix_: PyReadonlyArray2<'_, f64>,
        weights: PyReadonlyArray1<'_, f64>,
        lower: PyReadonlyArray1<'_, f64>,
        upper: PyReadonlyArray1<'_, f64>,
        regularization: f64,
        preferred: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let preferred = slice1("preferred", &preferred)?;
        let inner = AllocationProblem::new(
            matrix("matrix", &matrix_)?,
            slice1("weights", &weights)?,
            slice1("lower", &lower)?,
            slice1("upper", &upper)?,
        )
        .and_then(|p| p.with_regularization(regularization, preferred))
        .map_err(to_py_err)?;
        Ok(PyAllocationProblem { inner })
    }

    /// The bounds after folding in a rate limit (see `AllocationProblem::rate_limited`).
    fn rate_limited_bounds<'py>(
        &self,
        py: Python<'py>,
        previous: PyReadonlyArray1<'py, f64>,
        max_change: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<BoundsPair<'py>> {
        let limited = self
            .inner
            .rate_limited(
                slice1("previous", &previous)?,
                slice1("max_change", &max_change)?,
            )
            .map_err(to_py_err)?;
        Ok((
            limited.lower().to_vec().into_pyarray(py),
            limited.upper().to_vec().into_pyarray(py),
        ))
    }

    /// Objective and KKT residual of given commands (for checking any solver's answer).
    fn objective(
        &self,
        virtual_control: PyReadonlyArray1<'_, f64>,
        commands: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<(f64, f64)> {
        let u_c = slice1("virtual_control", &virtual_control)?;
        let t = slice1("commands", &commands)?;
        self.inner.evaluate(u_c, t).map_err(to_py_err)
    }
}

fn method(
    name: &str,
    priorities: Option<Vec<Vec<usize>>>,
    tolerance: f64,
    max_iterations: u32,
) -> PyResult<Method> {
    let settings = ClarabelSettings::default()
        .tolerance(tolerance)
        .and_then(|s| s.max_iterations(max_iterations))
        .map_err(to_py_err)?;
    Method::parse(name, priorities, settings).map_err(to_py_err)
}

/// Allocations of N virtual controls: commands (N x m), achieved (N x n), statuses, iterations.
#[pyclass(name = "AllocationBatch", module = "rotorfault._rfcore", frozen)]
pub struct PyAllocationBatch {
    rows: usize,
    results: Vec<Allocation>,
    actuators: usize,
    axes: usize,
}

impl PyAllocationBatch {
    fn matrix<'py>(
        &self,
        py: Python<'py>,
        cols: usize,
        row: impl Fn(&Allocation) -> &[f64],
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let values: Vec<f64> = self
            .results
            .iter()
            .flat_map(|a| row(a).iter().copied())
            .collect();
        numpy::ndarray::Array2::from_shape_vec((self.rows, cols), values)
            .map(|a| a.into_pyarray(py))
            .map_err(|e| PyValueError::new_err(format!("internal shape error: {e}")))
    }
}

#[pymethods]
impl PyAllocationBatch {
    #[getter]
    fn commands<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.matrix(py, self.actuators, |a| &a.commands)
    }
    #[getter]
    fn achieved<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.matrix(py, self.axes, |a| &a.achieved)
    }
    #[getter]
    fn statuses(&self) -> Vec<&'static str> {
        self.results.iter().map(|a| a.status.name()).collect()
    }
    #[getter]
    fn iterations(&self) -> Vec<usize> {
        self.results.iter().map(|a| a.iterations).collect()
    }
}

/// Allocates every row of `controls` (N x n): commands (N x m), achieved (N x n), statuses,
/// iterations.
#[pyfunction]
#[pyo3(signature = (problem, controls, method_name, priorities, tolerance, max_iterations))]
pub fn allocate<'py>(
    py: Python<'py>,
    problem: &PyAllocationProblem,
    controls: PyReadonlyArray2<'py, f64>,
    method_name: &str,
    priorities: Option<Vec<Vec<usize>>>,
    tolerance: f64,
    max_iterations: u32,
) -> PyResult<PyAllocationBatch> {
    let method = method(method_name, priorities, tolerance, max_iterations)?;
    let flat = slice2("virtual_control", &controls)?;
    let rows = controls.shape()[0];
    let problem = &problem.inner;
    let results = detached(py, || allocate_many(problem, &method, flat))?;
    Ok(PyAllocationBatch {
        rows,
        results,
        actuators: problem.actuator_count(),
        axes: problem.virtual_dimension(),
    })
}

/// Benchmark support: mean seconds per solve for each row of `controls` (cold starts, one thread).
#[pyfunction]
pub fn time_allocations<'py>(
    py: Python<'py>,
    problem: &PyAllocationProblem,
    controls: PyReadonlyArray2<'py, f64>,
    method_name: &str,
    repeats: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let method = method(
        method_name,
        None,
        ClarabelSettings::default().tolerance,
        ClarabelSettings::default().max_iterations,
    )?;
    let flat = slice2("virtual_control", &controls)?;
    let problem = &problem.inner;
    let times = detached(py, || time_each(problem, &method, flat, repeats))?;
    Ok(times.into_pyarray(py))
}

/// The largest scale along a direction and the commands that reach it.
#[pyclass(
    name = "DirectionalLimit",
    module = "rotorfault._rfcore",
    frozen,
    get_all
)]
pub struct PyDirectionalLimit {
    scale: f64,
    commands: Vec<f64>,
    status: &'static str,
}

/// The largest total thrust with zero torques, against the weight.
#[pyclass(name = "HoverMargin", module = "rotorfault._rfcore", frozen, get_all)]
pub struct PyHoverMargin {
    max_thrust_n: f64,
    weight_n: f64,
    margin_n: f64,
    commands: Option<Vec<f64>>,
    status: &'static str,
}

/// Largest scale along `direction` from `base`: None when `base` is unattainable.
#[pyfunction]
pub fn max_along_direction<'py>(
    py: Python<'py>,
    matrix_: PyReadonlyArray2<'py, f64>,
    lower: PyReadonlyArray1<'py, f64>,
    upper: PyReadonlyArray1<'py, f64>,
    direction: PyReadonlyArray1<'py, f64>,
    base: PyReadonlyArray1<'py, f64>,
    tolerance: f64,
) -> PyResult<Option<PyDirectionalLimit>> {
    let settings = ClarabelSettings::default()
        .tolerance(tolerance)
        .map_err(to_py_err)?;
    let m = matrix("matrix", &matrix_)?;
    let (lo, hi) = (slice1("lower", &lower)?, slice1("upper", &upper)?);
    let (d, b) = (slice1("direction", &direction)?, slice1("base", &base)?);
    let limit = detached(py, || core_max_along(&m, lo, hi, d, b, &settings))?;
    Ok(limit.map(|l| PyDirectionalLimit {
        scale: l.scale,
        commands: l.commands,
        status: l.status.name(),
    }))
}

/// The hover thrust margin of an airframe.
#[pyfunction]
pub fn hover_thrust_margin<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    axes: &str,
    tolerance: f64,
) -> PyResult<PyHoverMargin> {
    let settings = ClarabelSettings::default()
        .tolerance(tolerance)
        .map_err(to_py_err)?;
    let axes = ControlAxes::parse("axes", axes).map_err(to_py_err)?;
    let airframe = &airframe.inner;
    let h = detached(py, || core_hover_margin(airframe, axes, &settings))?;
    Ok(PyHoverMargin {
        max_thrust_n: h.max_thrust_n,
        weight_n: h.weight_n,
        margin_n: h.margin_n,
        commands: (!h.commands.is_empty()).then_some(h.commands),
        status: h.status.name(),
    })
}
