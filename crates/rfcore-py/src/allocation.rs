//! Bindings for control allocation: the problem type, batch allocation and attainable-set
//! queries. Translation only.

use numpy::{
    IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use std::sync::OnceLock;

use pyo3::prelude::*;
use pyo3::types::{PyFloat, PyList, PyTuple};
use pyo3::IntoPyObjectExt;

use rfcore::allocation::active_set::{ActiveSet, ActiveSetSettings, ActiveSetSolver, SolveReport};
use rfcore::allocation::clarabel::{
    hover_thrust_margin as core_hover_margin, max_along_direction as core_max_along,
    ClarabelSettings,
};
use rfcore::allocation::{
    allocate_all, allocate_many, fallback_count, Allocation, AllocationProblem, AllocationStatus,
    Certificate, Method, SolvedBy, MAX_ACTUATORS, MAX_VIRTUAL,
};
use rfcore::analysis::ControlAxes;
use rfcore::error::RfError;
use rfcore::Cancel;

use crate::airframe::PyAirframe;
use crate::convert::{count, detached, kept, matrix, pickle_protocol, slice1, slice2, to_py_err};

type BoundsPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The solver settings of an allocation problem: the active set's certificate tolerance and
/// iteration bound, Clarabel's tolerance and iteration limit. Defaults are the core's.
#[pyclass(
    name = "AllocationSettings",
    module = "rotorfault._rfcore",
    frozen,
    get_all
)]
#[derive(Clone, Copy)]
pub struct PyAllocationSettings {
    /// Certificate tolerance (relative KKT residuals), [`ActiveSetSettings::tolerance`].
    tolerance: f64,
    /// Iteration bound per active-set phase and Clarabel's limit; None: `4 m + 20` for the
    /// active set and Clarabel's default.
    max_iterations: Option<usize>,
    /// Clarabel's duality-gap and feasibility tolerance.
    clarabel_tolerance: f64,
}

impl PyAllocationSettings {
    const FIELDS: &'static [&'static str] = &["tolerance", "max_iterations", "clarabel_tolerance"];

    fn active(&self) -> ActiveSetSettings {
        ActiveSetSettings {
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            ..ActiveSetSettings::default()
        }
    }
    fn clarabel(&self) -> PyResult<ClarabelSettings> {
        let mut settings = ClarabelSettings::default()
            .tolerance(self.clarabel_tolerance)
            .map_err(|e| to_py_err(rename(e, "tolerance", "clarabel_tolerance")))?;
        if let Some(limit) = self.max_iterations {
            settings = settings.max_iterations(limit).map_err(to_py_err)?;
        }
        Ok(settings)
    }
}

/// The core names Clarabel's tolerance `tolerance`; Python calls it `clarabel_tolerance`.
fn rename(error: RfError, from: &str, to: &str) -> RfError {
    match error {
        RfError::InvalidValue { field, rule } if field == from => RfError::InvalidValue {
            field: to.to_string(),
            rule,
        },
        other => other,
    }
}

pickle_protocol!(PyAllocationSettings, {
    #[new]
    #[pyo3(signature = (*, tolerance=None, max_iterations=None, clarabel_tolerance=None))]
    fn new(
        tolerance: Option<f64>,
        max_iterations: Option<&Bound<'_, PyAny>>,
        clarabel_tolerance: Option<f64>,
    ) -> PyResult<Self> {
        let max_iterations = max_iterations
            .map(|v| count("max_iterations", v))
            .transpose()?;
        let out = PyAllocationSettings {
            tolerance: tolerance.unwrap_or(ActiveSetSettings::default().tolerance),
            max_iterations,
            clarabel_tolerance: clarabel_tolerance.unwrap_or(ClarabelSettings::default().tolerance),
        };
        out.active().check().map_err(to_py_err)?;
        out.clarabel()?;
        Ok(out)
    }
});

/// The KKT residuals of an allocation in the problem's own scaling and the tolerance they are
/// held to (see the core's `Certificate`).
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> allocation = rf.allocate(rf.Airframe.preset("quad-x"), [15.0, 0.0, 0.0, 0.0])
///     >>> allocation.certificate.holds
///     True
#[pyclass(
    name = "Certificate",
    module = "rotorfault._rfcore",
    frozen,
    get_all,
    eq
)]
#[derive(Clone, Copy, PartialEq)]
pub struct PyCertificate {
    stationarity: f64,
    complementarity: f64,
    bound_violation: f64,
    tolerance: f64,
}

impl From<Certificate> for PyCertificate {
    fn from(c: Certificate) -> Self {
        PyCertificate {
            stationarity: c.stationarity,
            complementarity: c.complementarity,
            bound_violation: c.bound_violation,
            tolerance: c.tolerance,
        }
    }
}

impl PyCertificate {
    fn core(&self) -> Certificate {
        Certificate {
            stationarity: self.stationarity,
            complementarity: self.complementarity,
            bound_violation: self.bound_violation,
            tolerance: self.tolerance,
        }
    }
}

#[pymethods]
impl PyCertificate {
    /// Every residual within the tolerance.
    #[getter]
    fn holds(&self) -> bool {
        self.core().holds()
    }
    /// The largest residual.
    #[getter]
    fn worst(&self) -> f64 {
        self.core().worst()
    }
    fn __repr__(&self) -> String {
        format!(
            "Certificate(stationarity={:e}, complementarity={:e}, bound_violation={:e}, tolerance={:e}, holds={})",
            self.stationarity,
            self.complementarity,
            self.bound_violation,
            self.tolerance,
            if self.holds() { "True" } else { "False" }
        )
    }
}

/// A validated allocation problem (matrix, weights, bounds, regularisation) with its prepared
/// active-set solver and settings: every active-set path (one control, a batch, `Allocated`)
/// solves with this one solver.
#[pyclass(name = "AllocationProblem", module = "rotorfault._rfcore", frozen)]
pub struct PyAllocationProblem {
    pub(crate) inner: AllocationProblem,
    pub(crate) solver: ActiveSetSolver,
    settings: PyAllocationSettings,
}

/// One allocation of one virtual control (the fast path of `Allocator.allocate`): the solver's
/// report and fixed-size arrays, no heap allocation; the NumPy arrays are made by the getters,
/// when read.
#[pyclass(name = "SingleAllocation", module = "rotorfault._rfcore", frozen)]
pub struct PySingleAllocation {
    actuators: usize,
    axes: usize,
    commands: [f64; MAX_ACTUATORS],
    achieved: [f64; MAX_VIRTUAL],
    virtual_control: [f64; MAX_VIRTUAL],
    report: SolveReport,
    arrays: Arrays,
}

/// The NumPy arrays of a result, made when first read and then kept: a field read twice is one
/// object (a caller's change to it stays, as it did when Python kept the fields).
#[derive(Default)]
struct Arrays {
    commands: OnceLock<Py<PyAny>>,
    achieved: OnceLock<Py<PyAny>>,
    virtual_control: OnceLock<Py<PyAny>>,
}

#[pymethods]
impl PySingleAllocation {
    #[getter]
    fn commands<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        kept(py, &self.arrays.commands, || {
            Ok(PyArray1::from_slice(py, &self.commands[..self.actuators]).into_any())
        })
    }
    #[getter]
    fn achieved<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        kept(py, &self.arrays.achieved, || {
            Ok(PyArray1::from_slice(py, &self.achieved[..self.axes]).into_any())
        })
    }
    #[getter]
    fn virtual_control<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        kept(py, &self.arrays.virtual_control, || {
            Ok(PyArray1::from_slice(py, &self.virtual_control[..self.axes]).into_any())
        })
    }
    #[getter]
    fn status(&self) -> &'static str {
        self.report.status.name()
    }
    #[getter]
    fn iterations(&self) -> usize {
        self.report.iterations
    }
    #[getter]
    fn certificate(&self) -> PyCertificate {
        self.report.certificate.into()
    }
    #[getter]
    fn solved_by(&self) -> &'static str {
        self.report.solved_by.name()
    }
    /// 1 when the Clarabel fallback produced the commands, else 0.
    #[getter]
    fn fallbacks(&self) -> usize {
        usize::from(self.report.solved_by == SolvedBy::Clarabel)
    }
}

/// `value` as n floats without conversion, into `out`: a C-contiguous 1-D float64 array or a
/// list/tuple of Python floats, with n entries (n <= `out.len()`); false for anything else (the
/// caller's general path converts and names the type or shape error).
fn exact_floats(value: &Bound<'_, PyAny>, out: &mut [f64]) -> bool {
    let n = out.len();
    if let Ok(array) = value.cast::<PyArray1<f64>>() {
        let Ok(view) = array.try_readonly() else {
            return false;
        };
        return match view.as_slice() {
            Ok(s) if s.len() == n => {
                out.copy_from_slice(s);
                true
            }
            _ => false,
        };
    }
    let from = |item: Bound<'_, PyAny>, slot: &mut f64| match item.cast_exact::<PyFloat>() {
        Ok(f) => {
            *slot = f.value();
            true
        }
        Err(_) => false,
    };
    if let Ok(list) = value.cast::<PyList>() {
        list.len() == n
            && list
                .iter()
                .zip(out.iter_mut())
                .all(|(x, slot)| from(x, slot))
    } else if let Ok(tuple) = value.cast::<PyTuple>() {
        tuple.len() == n
            && tuple
                .iter()
                .zip(out.iter_mut())
                .all(|(x, slot)| from(x, slot))
    } else {
        false
    }
}

#[pymethods]
impl PyAllocationProblem {
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        matrix_: PyReadonlyArray2<'_, f64>,
        weights: PyReadonlyArray1<'_, f64>,
        lower: PyReadonlyArray1<'_, f64>,
        upper: PyReadonlyArray1<'_, f64>,
        regularization: f64,
        preferred: PyReadonlyArray1<'_, f64>,
        settings: PyRef<'_, PyAllocationSettings>,
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
        let settings = *settings;
        Ok(PyAllocationProblem {
            solver: ActiveSetSolver::with_settings(&inner, settings.active()).map_err(to_py_err)?,
            inner,
            settings,
        })
    }

    #[getter]
    fn settings(&self) -> PyAllocationSettings {
        self.settings
    }

    /// The active-set allocation of one virtual control given as exactly n floats (see
    /// `exact_floats`); None for anything else, so the caller converts it. The values are checked
    /// by the core's `ActiveSetSolver::solve` (finite entries; not overflowing once scaled),
    /// the problem and settings were checked once, when it was built.
    fn allocate_one(
        &self,
        virtual_control: &Bound<'_, PyAny>,
    ) -> PyResult<Option<PySingleAllocation>> {
        let (axes, actuators) = (self.inner.virtual_dimension(), self.inner.actuator_count());
        let mut u_c = [0.0; MAX_VIRTUAL];
        if !exact_floats(virtual_control, &mut u_c[..axes]) {
            return Ok(None);
        }
        let mut commands = [0.0; MAX_ACTUATORS];
        let mut active = ActiveSet::cold(actuators);
        let report = self
            .solver
            .solve(&u_c[..axes], &mut active, &mut commands[..actuators])
            .map_err(to_py_err)?;
        let mut achieved = [0.0; MAX_VIRTUAL];
        self.inner
            .achieved_into(&commands[..actuators], &mut achieved[..axes]);
        Ok(Some(PySingleAllocation {
            actuators,
            axes,
            commands,
            achieved,
            virtual_control: u_c,
            report,
            arrays: Arrays::default(),
        }))
    }

    /// The call floor of `allocate_one`, for `benches/allocation_calls.py`: the same argument
    /// extraction and the same result object, without the solve. Not an allocation: the
    /// commands are zero and the report says `iteration-limit` with a certificate that fails.
    fn allocate_one_floor(&self, virtual_control: &Bound<'_, PyAny>) -> Option<PySingleAllocation> {
        let (axes, actuators) = (self.inner.virtual_dimension(), self.inner.actuator_count());
        let mut u_c = [0.0; MAX_VIRTUAL];
        if !exact_floats(virtual_control, &mut u_c[..axes]) {
            return None;
        }
        Some(PySingleAllocation {
            actuators,
            axes,
            commands: [0.0; MAX_ACTUATORS],
            achieved: [0.0; MAX_VIRTUAL],
            virtual_control: u_c,
            report: SolveReport {
                status: AllocationStatus::IterationLimit,
                iterations: 0,
                certificate: Certificate {
                    stationarity: f64::INFINITY,
                    complementarity: f64::INFINITY,
                    bound_violation: f64::INFINITY,
                    tolerance: 0.0,
                },
                solved_by: SolvedBy::ActiveSet,
            },
            arrays: Arrays::default(),
        })
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
    problem: &PyAllocationProblem,
    name: &str,
    priorities: Option<Vec<Vec<usize>>>,
) -> PyResult<Method> {
    let settings = problem.settings;
    Method::parse(name, priorities, settings.active(), settings.clarabel()?).map_err(to_py_err)
}

/// Allocations of N virtual controls (Python's `Allocation` holds one and reads every field
/// through it): commands (N x m), achieved (N x n), the virtual controls (N x n), statuses,
/// iterations, certificates, solvers, the fallback count. `single` (one virtual control given as
/// a vector): the arrays are vectors and the per-row fields single values, not tuples.
#[pyclass(name = "AllocationBatch", module = "rotorfault._rfcore", frozen)]
pub struct PyAllocationBatch {
    rows: usize,
    fallbacks: usize,
    results: Vec<Allocation>,
    controls: Vec<f64>,
    actuators: usize,
    axes: usize,
    single: bool,
    arrays: Arrays,
}

impl PyAllocationBatch {
    /// The rows of one field as an (N, `cols`) array, or its one row as a vector when `single`.
    fn matrix<'py>(
        &self,
        py: Python<'py>,
        cols: usize,
        values: Vec<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if self.single {
            return Ok(values.into_pyarray(py).into_any());
        }
        numpy::ndarray::Array2::from_shape_vec((self.rows, cols), values)
            .map(|a| a.into_pyarray(py).into_any())
            .map_err(|e| PyValueError::new_err(format!("internal shape error: {e}")))
    }

    fn column<'py>(
        &self,
        cols: usize,
        row: impl Fn(&Allocation) -> &[f64],
        py: Python<'py>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let values = self
            .results
            .iter()
            .flat_map(|a| row(a).iter().copied())
            .collect();
        self.matrix(py, cols, values)
    }

    /// One value per row: the value itself when `single`, else a tuple.
    fn per_row<'py, T: IntoPyObject<'py> + Clone>(
        &self,
        py: Python<'py>,
        value: impl Fn(&Allocation) -> T,
    ) -> PyResult<Bound<'py, PyAny>> {
        match (self.single, self.results.first()) {
            (true, Some(one)) => value(one).into_bound_py_any(py),
            _ => PyTuple::new(py, self.results.iter().map(value)).map(|t| t.into_any()),
        }
    }
}

#[pymethods]
impl PyAllocationBatch {
    #[getter]
    fn commands<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        kept(py, &self.arrays.commands, || {
            self.column(self.actuators, |a| &a.commands, py)
        })
    }
    #[getter]
    fn achieved<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        kept(py, &self.arrays.achieved, || {
            self.column(self.axes, |a| &a.achieved, py)
        })
    }
    /// The virtual controls allocated, as given (checked by the core).
    #[getter]
    fn virtual_control<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        kept(py, &self.arrays.virtual_control, || {
            self.matrix(py, self.axes, self.controls.clone())
        })
    }
    #[getter]
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.per_row(py, |a| a.status.name())
    }
    #[getter]
    fn iterations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.per_row(py, |a| a.iterations)
    }
    #[getter]
    fn certificate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.per_row(py, |a| PyCertificate::from(a.certificate))
    }
    #[getter]
    fn solved_by<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.per_row(py, |a| a.solved_by.name())
    }
    /// How many answers the active-set method's Clarabel fallback produced (0 for the other
    /// methods).
    #[getter]
    fn fallbacks(&self) -> usize {
        self.fallbacks
    }
}

/// Allocates every row of `controls` (N x n) with the problem's settings: commands (N x m),
/// achieved (N x n), statuses, iterations, certificates, methods, fallback count. `single`: one
/// virtual control given as a vector (one row; the result reads as one allocation).
#[pyfunction]
#[pyo3(signature = (problem, controls, method_name, priorities, single=false))]
pub fn allocate<'py>(
    py: Python<'py>,
    problem: &PyAllocationProblem,
    controls: PyReadonlyArray2<'py, f64>,
    method_name: &str,
    priorities: Option<Vec<Vec<usize>>>,
    single: bool,
) -> PyResult<PyAllocationBatch> {
    let method = method(problem, method_name, priorities)?;
    let flat = slice2("virtual_control", &controls)?;
    let rows = controls.shape()[0];
    if single && rows != 1 {
        return Err(PyValueError::new_err(format!(
            "virtual_control: single: expected one row, got {rows}"
        )));
    }
    let results = match method {
        // One active-set solve is a few microseconds (bounded: `4 m + 20` iterations per phase,
        // then at most one Clarabel fallback), against about 10 us to hand work to `detached`:
        // it runs here, holding the GIL, with a token nothing cancels.
        Method::ActiveSet(_) if rows == 1 => {
            allocate_all(&problem.solver, flat, &Cancel::new()).map_err(to_py_err)?
        }
        Method::ActiveSet(_) => {
            let solver = &problem.solver;
            detached(py, |cancel| allocate_all(solver, flat, cancel))?
        }
        _ => {
            let inner = &problem.inner;
            detached(py, |cancel| allocate_many(inner, &method, flat, cancel))?
        }
    };
    let fallbacks = match method {
        Method::ActiveSet(_) => fallback_count(&results),
        _ => 0,
    };
    Ok(PyAllocationBatch {
        rows,
        fallbacks,
        results,
        controls: flat.to_vec(),
        actuators: problem.inner.actuator_count(),
        axes: problem.inner.virtual_dimension(),
        single,
        arrays: Arrays::default(),
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
    let method = method(problem, method_name, None)?;
    let flat = slice2("virtual_control", &controls)?;
    let problem = &problem.inner;
    let times = detached(py, |cancel| {
        rfcore::fixtures::time_each(problem, &method, flat, repeats, cancel)
    })?;
    Ok(times.into_pyarray(py))
}

/// The largest scale along a direction and the commands that reach it
/// (`rotorfault.DirectionalLimit`, from `max_virtual_control`).
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> limit = rf.max_virtual_control(rf.Airframe.preset("quad-x"), [1, 0, 0, 0])
///     >>> round(limit.scale, 3), limit.status, limit.commands.round(3).tolist()
///     (24.5, 'optimal', [6.125, 6.125, 6.125, 6.125])
#[pyclass(name = "DirectionalLimit", module = "rotorfault._rfcore", frozen)]
pub struct PyDirectionalLimit {
    scale: f64,
    commands: Vec<f64>,
    status: &'static str,
}

#[pymethods]
impl PyDirectionalLimit {
    /// The largest `scale` with `base + scale * direction` attainable.
    #[getter]
    fn scale(&self) -> f64 {
        self.scale
    }
    /// Rotor commands that attain it, in the allocator's units (N for thrust).
    #[getter]
    fn commands<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.commands.clone().into_pyarray(py)
    }
    /// The linear program's status.
    #[getter]
    fn status(&self) -> &'static str {
        self.status
    }
    fn __repr__(&self) -> String {
        format!(
            "DirectionalLimit(scale={}, status={:?})",
            self.scale, self.status
        )
    }
}

/// The largest total thrust with the controlled torques at zero, against the weight
/// (`rotorfault.HoverMargin`, from `hover_thrust_margin`).
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> margin = rf.hover_thrust_margin(rf.Airframe.preset("quad-x"))
///     >>> round(margin.margin_n, 3), round(margin.thrust_to_weight, 4), margin.status
///     (9.457, 1.6287, 'optimal')
#[pyclass(name = "HoverMargin", module = "rotorfault._rfcore", frozen)]
pub struct PyHoverMargin {
    max_thrust_n: f64,
    weight_n: f64,
    margin_n: f64,
    commands: Option<Vec<f64>>,
    status: &'static str,
}

#[pymethods]
impl PyHoverMargin {
    /// The largest total thrust with the controlled torques at zero, N (`-inf`: zero torque is
    /// unattainable at any thrust).
    #[getter]
    fn max_thrust_n(&self) -> f64 {
        self.max_thrust_n
    }
    /// The weight `m g`, N.
    #[getter]
    fn weight_n(&self) -> f64 {
        self.weight_n
    }
    /// `max_thrust_n - weight_n`, N (negative: cannot hover in balance).
    #[getter]
    fn margin_n(&self) -> f64 {
        self.margin_n
    }
    /// Rotor thrusts (N) that attain the maximum; `None` when zero torque is unattainable.
    #[getter]
    fn commands<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.commands.clone().map(|c| c.into_pyarray(py))
    }
    /// The linear program's status.
    #[getter]
    fn status(&self) -> &'static str {
        self.status
    }
    /// `max_thrust_n / weight_n`, dimensionless.
    #[getter]
    fn thrust_to_weight(&self) -> f64 {
        self.max_thrust_n / self.weight_n
    }
    fn __repr__(&self) -> String {
        format!(
            "HoverMargin(max_thrust_n={}, weight_n={}, margin_n={}, status={:?})",
            self.max_thrust_n, self.weight_n, self.margin_n, self.status
        )
    }
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
    // One Clarabel solve, bounded by its iteration cap: nothing to cancel.
    let limit = detached(py, |_| core_max_along(&m, lo, hi, d, b, &settings))?;
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
    let h = detached(py, |_| core_hover_margin(airframe, axes, &settings))?;
    Ok(PyHoverMargin {
        max_thrust_n: h.max_thrust_n,
        weight_n: h.weight_n,
        margin_n: h.margin_n,
        commands: (!h.commands.is_empty()).then_some(h.commands),
        status: h.status.name(),
    })
}
