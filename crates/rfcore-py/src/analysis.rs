//! Bindings for the controllability analysis (Du et al.): ACAI, the test procedure, failure
//! tables; relaxed hover in [`relaxed_hover`]. Translation only.

pub(crate) mod relaxed_hover;

use std::sync::OnceLock;

use numpy::{
    IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use pyo3::types::PyTuple;
use rfcore::analysis::text::{self, controllability_text};
use rfcore::analysis::{
    acai_from_matrix_cancellable, failure_table as core_failure_table, AcaiBatch, AcaiFormula,
    AcaiResult, ControlAxes, ControllabilityAnalysis, ControllabilityReport, HoverPoint, Verdict,
};

use rfcore::Cancel;

use crate::airframe::PyAirframe;
use crate::convert::{
    detached, kept, pickle_protocol, rotor_indices, rotor_numbers, slice1, slice2, to_py_err,
    value_protocol,
};

/// `axes`: "thrust-roll-pitch-yaw", "thrust-roll-pitch" (yaw given up) or "wrench" (n = 6).
fn analysis(
    airframe: &PyAirframe,
    axes: &str,
    cancel: &Cancel,
) -> rfcore::Result<ControllabilityAnalysis> {
    ControllabilityAnalysis::new_cancellable(
        &airframe.inner,
        ControlAxes::parse("axes", axes)?,
        cancel,
    )
}

/// Outcome of Du's 9-step test for one airframe and efficiency vector: the core's report, used
/// directly from Python (re-exported as `rotorfault.ControllabilityReport`; no Python copy). It
/// carries the question asked (`airframe` the airframe's name, `efficiency` one per rotor, `axes`
/// and `give_up_yaw`) and the answer: `state_dimension` 2n (8 with yaw, 6 without),
/// `controllability_rank` rank C(A, B) (Step 1), `virtual_control_dimension` n,
/// `effectiveness_rank` rank B_f with the efficiencies applied (Step 2), `acai` rho(G, dOmega)
/// (Steps 3-8; -inf when rank B_f < n; in N and N m), `formula` ("eq13" or "facet-margin": how
/// `acai` reads when G is outside), `verdict` ("controllable" or "uncontrollable: <reason>", Step
/// 9), `controllable`, `hover` (where the hover wrench lies; "outside" with `acai == 0` marks eq.
/// (13)'s misleading 0). Prints as the test's summary (the ACAI named by its formula); frozen,
/// comparable, hashable, picklable.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> report = rf.controllability(rf.Airframe.preset("hexa-pnpnpn"), efficiency=[1, 1, 1, 1, 1, 0.5])
///     >>> report.controllable, round(float(report.acai), 4), report.controllability_rank
///     (True, 0.743, 8)
///     >>> print(report)
///     hexa-pnpnpn: efficiency = [1, 1, 1, 1, 1, 0.5], axes = thrust, roll, pitch, yaw
///       rank C(A, B) = 8 of 8
///       rank B_f     = 4 of 4
///       ACAI eq13    = 0.7430
///       verdict      = controllable
#[pyclass(name = "ControllabilityReport", module = "rotorfault._rfcore", frozen)]
pub struct PyControllabilityReport {
    airframe: String,
    inner: ControllabilityReport,
}

impl PyControllabilityReport {
    /// The fields as a dataclass prints them (repr, equality, hash), in this order.
    const FIELDS: &'static [&'static str] = &[
        "airframe",
        "efficiency",
        "give_up_yaw",
        "state_dimension",
        "controllability_rank",
        "virtual_control_dimension",
        "effectiveness_rank",
        "acai",
        "formula",
        "verdict",
        "controllable",
        "hover",
        "axes",
    ];
}

value_protocol!(PyControllabilityReport, {
    /// The airframe's name.
    #[getter]
    fn airframe(&self) -> &str {
        &self.airframe
    }
    /// The efficiency tested, one per rotor (rotor order).
    #[getter]
    fn efficiency<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, &self.inner.efficiency)
    }
    /// Thrust, roll and pitch only (`axes == "thrust-roll-pitch"`).
    #[getter]
    fn give_up_yaw(&self) -> bool {
        self.inner.axes == ControlAxes::ThrustRollPitch
    }
    #[getter]
    fn axes(&self) -> &'static str {
        self.inner.axes.name()
    }
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
    #[getter]
    fn hover(&self) -> &'static str {
        self.inner.hover.name()
    }
    fn __str__(&self) -> String {
        controllability_text(&self.inner, &self.airframe)
    }
    /// Pickled as its fields, read back by `_controllability_report` (a result has no public
    /// constructor: only the test makes one).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let restore = py
            .import("rotorfault._rfcore")?
            .getattr("_controllability_report")?;
        let r = &self.inner;
        let state = (
            self.airframe.clone(),
            r.efficiency.clone(),
            r.axes.name(),
            r.state_dimension,
            r.controllability_rank,
            r.virtual_control_dimension,
            r.effectiveness_rank,
            r.acai,
            r.formula.name(),
            r.verdict.code(),
            r.hover.name(),
        )
            .into_pyobject(py)?;
        Ok((restore, state))
    }
});

/// A report read back from its pickled fields (`ControllabilityReport.__reduce__`): the names
/// are parsed by the core's own parsers.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub(crate) fn _controllability_report(
    airframe: String,
    efficiency: Vec<f64>,
    axes: &str,
    state_dimension: usize,
    controllability_rank: usize,
    virtual_control_dimension: usize,
    effectiveness_rank: usize,
    acai: f64,
    formula: &str,
    verdict: &str,
    hover: &str,
) -> PyResult<PyControllabilityReport> {
    let inner = ControllabilityReport {
        axes: ControlAxes::parse("axes", axes).map_err(to_py_err)?,
        efficiency,
        state_dimension,
        controllability_rank,
        virtual_control_dimension,
        effectiveness_rank,
        acai,
        formula: AcaiFormula::parse(formula).map_err(to_py_err)?,
        hover: HoverPoint::parse("hover", hover).map_err(to_py_err)?,
        verdict: Verdict::parse("verdict", verdict).map_err(to_py_err)?,
    };
    Ok(PyControllabilityReport { airframe, inner })
}

fn report(airframe: &PyAirframe, report: ControllabilityReport) -> PyControllabilityReport {
    PyControllabilityReport {
        airframe: airframe.inner.name().to_string(),
        inner: report,
    }
}

/// How a printed ACAI reads (`rfcore::analysis::text::format_acai`): 4 decimals, `undefined`
/// for -inf, a star on eq. (13)'s non-negative value when the hover wrench lies outside.
#[pyfunction]
pub(crate) fn format_acai(value: f64, hover: &str) -> PyResult<String> {
    let hover = HoverPoint::parse("hover", hover).map_err(to_py_err)?;
    Ok(text::format_acai(value, hover))
}

/// How a printed ACAI names its formula (`ACAI eq13`, `ACAI facet-margin`).
#[pyfunction]
pub(crate) fn acai_label(formula: &str) -> PyResult<String> {
    Ok(text::acai_label(
        AcaiFormula::parse(formula).map_err(to_py_err)?,
    ))
}

/// An ACAI with where the hover wrench lies (`inside`, `boundary`, `outside`, `rank-deficient`):
/// an eq. (13) value is not a distance when the hover point is outside. Python's `AcaiValue` (a
/// float) holds one and reads `hover` through it: the result crosses the boundary once.
#[pyclass(name = "AcaiResult", module = "rotorfault._rfcore", frozen)]
pub struct PyAcaiResult {
    inner: AcaiResult,
}

impl PyAcaiResult {
    /// The fields as a dataclass prints them (repr, equality, hash), in this order.
    const FIELDS: &'static [&'static str] = &["acai", "hover"];
}

pickle_protocol!(
    PyAcaiResult,
    {
        /// A result from its two fields (`AcaiValue(value, hover)` and its pickles): the hover point
        /// is parsed by the core's own parser.
        #[new]
        fn new(acai: f64, hover: &str) -> PyResult<Self> {
            let hover = HoverPoint::parse("hover", hover).map_err(to_py_err)?;
            Ok(PyAcaiResult {
                inner: AcaiResult { acai, hover },
            })
        }
        #[getter]
        fn acai(&self) -> f64 {
            self.inner.acai
        }
        #[getter]
        fn hover(&self) -> &'static str {
            self.inner.hover.name()
        }
        /// The hover wrench is attainable (inside or on the boundary).
        #[getter]
        fn hover_feasible(&self) -> bool {
            self.inner.hover.is_attainable()
        }
    },
    then = value_protocol
);

/// A batch of ACAIs in one formula with the hover point of each row as a code (1 inside, 0 on
/// the boundary, -1 outside, -2 rank deficient: `HoverPoint::code`). Python's `AcaiBatch` holds
/// one and reads every field through it: the result crosses the boundary once. The NumPy arrays
/// are made from the core's result when first read and then kept, so a field is one object.
#[pyclass(name = "AcaiBatch", module = "rotorfault._rfcore", frozen)]
pub struct PyAcaiBatch {
    inner: AcaiBatch,
    formula: AcaiFormula,
    acai_array: OnceLock<Py<PyArray1<f64>>>,
    hover_code_array: OnceLock<Py<PyArray1<i8>>>,
}

impl PyAcaiBatch {
    /// The fields as a dataclass prints them (repr, pickling), in this order.
    const FIELDS: &'static [&'static str] = &["acai", "hover_code", "formula"];

    fn from_core(inner: AcaiBatch, formula: AcaiFormula) -> Self {
        PyAcaiBatch {
            inner,
            formula,
            acai_array: OnceLock::new(),
            hover_code_array: OnceLock::new(),
        }
    }
}

/// The hover codes of a batch: an int8 array as the batch gives them, else any sequence of
/// integers (a user's list, an int64 array); each code is checked by the core's `from_code`.
fn hover_codes(value: &Bound<'_, PyAny>) -> PyResult<Vec<HoverPoint>> {
    let codes: Vec<i64> = match value.extract::<PyReadonlyArray1<'_, i8>>() {
        Ok(array) => array.as_array().iter().map(|&c| i64::from(c)).collect(),
        Err(_) => value.extract::<Vec<i64>>().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(
                "hover_code: expected a sequence of integer codes (1, 0, -1, -2)",
            )
        })?,
    };
    codes
        .into_iter()
        .enumerate()
        .map(|(k, c)| HoverPoint::from_code(&format!("hover_code[{k}]"), c).map_err(to_py_err))
        .collect()
}

pickle_protocol!(PyAcaiBatch, {
    /// A batch from its three fields (`AcaiBatch(acai, hover_code, formula)` and its pickles):
    /// one hover code per ACAI, each a code of `HoverPoint`, the formula by its name.
    #[new]
    #[pyo3(signature = (acai, hover_code, formula="eq13"))]
    fn new(
        acai: PyReadonlyArray1<'_, f64>,
        hover_code: &Bound<'_, PyAny>,
        formula: &str,
    ) -> PyResult<Self> {
        let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
        let acai = slice1("acai", &acai)?.to_vec();
        let hover = hover_codes(hover_code)?;
        if hover.len() != acai.len() {
            return Err(PyValueError::new_err(format!(
                "hover_code: expected one code per ACAI ({}), got {}",
                acai.len(),
                hover.len()
            )));
        }
        Ok(PyAcaiBatch::from_core(AcaiBatch { acai, hover }, formula))
    }
    #[getter]
    fn acai<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        kept(py, &self.acai_array, || Ok(PyArray1::from_slice(py, &self.inner.acai)))
    }
    #[getter]
    fn hover_code<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i8>>> {
        kept(py, &self.hover_code_array, || {
            let codes: Vec<i8> = self.inner.hover.iter().map(|h| h.code()).collect();
            Ok(codes.into_pyarray(py))
        })
    }
    /// The formula of every value (`eq13` or `facet-margin`).
    #[getter]
    fn formula(&self) -> &'static str {
        self.formula.name()
    }
    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        crate::convert::settings_repr(slf.as_any(), Self::FIELDS)
    }
});

/// ACAI of `airframe` with efficiencies `efficiency` (Du Theorem 3), with the hover point.
#[pyfunction]
pub(crate) fn acai(
    py: Python<'_>,
    airframe: &PyAirframe,
    efficiency: PyReadonlyArray1<'_, f64>,
    axes: &str,
    formula: &str,
) -> PyResult<PyAcaiResult> {
    let efficiency = slice1("efficiency", &efficiency)?;
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let inner = detached(py, |cancel| {
        analysis(airframe, axes, cancel)?.acai_with_hover(efficiency, formula)
    })?;
    Ok(PyAcaiResult { inner })
}

fn check_columns(airframe: &PyAirframe, efficiencies: &PyReadonlyArray2<'_, f64>) -> PyResult<()> {
    let m = airframe.inner.rotor_count();
    if efficiencies.shape()[1] != m {
        return Err(PyValueError::new_err(format!(
            "efficiencies: expected {m} columns (one efficiency per rotor), got {}",
            efficiencies.shape()[1]
        )));
    }
    Ok(())
}

/// ACAI and hover point for every row of `efficiencies` (N x m), in parallel.
#[pyfunction]
pub(crate) fn acai_batch_with_hover(
    py: Python<'_>,
    airframe: &PyAirframe,
    efficiencies: PyReadonlyArray2<'_, f64>,
    axes: &str,
    formula: &str,
) -> PyResult<PyAcaiBatch> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    check_columns(airframe, &efficiencies)?;
    let flat = slice2("efficiencies", &efficiencies)?;
    let inner = detached(py, |cancel| {
        analysis(airframe, axes, cancel)?.acai_batch_with_hover(flat, formula, cancel)
    })?;
    Ok(PyAcaiBatch::from_core(inner, formula))
}

/// ACAI for every row of `efficiencies` (N x m), in parallel.
#[pyfunction]
pub(crate) fn acai_batch<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    efficiencies: PyReadonlyArray2<'py, f64>,
    axes: &str,
    formula: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    check_columns(airframe, &efficiencies)?;
    let flat = slice2("efficiencies", &efficiencies)?;
    let values = detached(py, |cancel| {
        analysis(airframe, axes, cancel)?.acai_batch(flat, formula, cancel)
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
) -> PyResult<PyAcaiResult> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let shape = effectiveness_matrix.shape();
    let (rows, cols) = (shape[0], shape[1]);
    let flat = slice2("effectiveness_matrix", &effectiveness_matrix)?;
    let (f_min, f_max, g_vec) = (
        slice1("f_min", &f_min)?,
        slice1("f_max", &f_max)?,
        slice1("g_vec", &g_vec)?,
    );
    let inner = detached(py, |cancel| {
        let b = nalgebra::DMatrix::from_row_slice(rows, cols, flat);
        acai_from_matrix_cancellable(&b, f_min, f_max, g_vec, formula, cancel)
    })?;
    Ok(PyAcaiResult { inner })
}

/// Du's 9-step procedure.
#[pyfunction]
pub(crate) fn controllability<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    efficiency: PyReadonlyArray1<'py, f64>,
    axes: &str,
    formula: &str,
) -> PyResult<PyControllabilityReport> {
    let efficiency = slice1("efficiency", &efficiency)?;
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let result = detached(py, |cancel| {
        analysis(airframe, axes, cancel)?.report(efficiency, formula)
    })?;
    Ok(report(airframe, result))
}

/// One failure-table row, the core's (`rfcore::analysis::FailureCase`) used directly from Python
/// (`rotorfault.FailureCase` holds one and reads every field through it; no Python copy): `failed`
/// the rotors at efficiency 0 (numbered from 1, as wherever a rotor is named), and the core's
/// three reports for that efficiency: `all_axes` (thrust, roll, pitch, yaw), `give_up_yaw`
/// (thrust, roll, pitch) and `wrench` (n = 6, for fully actuated airframes only, else `None`).
/// Frozen, comparable, hashable, picklable.
#[pyclass(name = "FailureCase", module = "rotorfault._rfcore", frozen)]
pub struct PyFailureCase {
    /// 0-based, as in the core.
    failed: Vec<usize>,
    all_axes: Py<PyControllabilityReport>,
    give_up_yaw: Py<PyControllabilityReport>,
    wrench: Option<Py<PyControllabilityReport>>,
}

impl PyFailureCase {
    /// The fields as a dataclass prints them (repr, equality, hash), in this order.
    const FIELDS: &'static [&'static str] = &["failed", "all_axes", "give_up_yaw", "wrench"];
}

value_protocol!(PyFailureCase, {
    /// The failed rotors, numbered from 1.
    #[getter]
    fn failed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, rotor_numbers(&self.failed))
    }
    /// The report with all four axes (thrust, roll, pitch, yaw).
    #[getter]
    fn all_axes(&self, py: Python<'_>) -> Py<PyControllabilityReport> {
        self.all_axes.clone_ref(py)
    }
    /// The report giving up yaw (thrust, roll and pitch only).
    #[getter]
    fn give_up_yaw(&self, py: Python<'_>) -> Py<PyControllabilityReport> {
        self.give_up_yaw.clone_ref(py)
    }
    /// The full-wrench report (n = 6), for fully actuated airframes only (else `None`).
    #[getter]
    fn wrench(&self, py: Python<'_>) -> Option<Py<PyControllabilityReport>> {
        self.wrench.as_ref().map(|w| w.clone_ref(py))
    }
    /// Pickled as its fields (the reports pickle themselves), read back by `_failure_case`.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let restore = py.import("rotorfault._rfcore")?.getattr("_failure_case")?;
        let state = (
            rotor_numbers(&self.failed),
            self.all_axes(py),
            self.give_up_yaw(py),
            self.wrench(py),
        )
            .into_pyobject(py)?;
        Ok((restore, state))
    }
});

/// A row read back from its pickled fields (`FailureCase.__reduce__`): rotors numbered from 1.
#[pyfunction]
#[pyo3(signature = (failed, all_axes, give_up_yaw, wrench))]
pub(crate) fn _failure_case(
    failed: Vec<usize>,
    all_axes: Py<PyControllabilityReport>,
    give_up_yaw: Py<PyControllabilityReport>,
    wrench: Option<Py<PyControllabilityReport>>,
) -> PyResult<PyFailureCase> {
    Ok(PyFailureCase {
        failed: rotor_indices("failed", &failed)?,
        all_axes,
        give_up_yaw,
        wrench,
    })
}

/// Every combination of up to `max_failed` failed rotors, one [`PyFailureCase`] each.
#[pyfunction]
pub(crate) fn failure_table<'py>(
    py: Python<'py>,
    airframe: &PyAirframe,
    max_failed: usize,
    formula: &str,
) -> PyResult<Vec<PyFailureCase>> {
    let formula = AcaiFormula::parse(formula).map_err(to_py_err)?;
    let cases = detached(py, |cancel| {
        core_failure_table(&airframe.inner, max_failed, formula, cancel)
    })?;
    cases
        .into_iter()
        .map(|case| {
            Ok(PyFailureCase {
                failed: case.failed,
                all_axes: Py::new(py, report(airframe, case.all_axes))?,
                give_up_yaw: Py::new(py, report(airframe, case.give_up_yaw))?,
                wrench: case
                    .wrench
                    .map(|wrench| Py::new(py, report(airframe, wrench)))
                    .transpose()?,
            })
        })
        .collect()
}

/// The crate's one rank rule, free of units (`rfcore::analysis::acai::scale_free_rank`): rows
/// and columns equilibrated by powers of two, then singular values above `RANK_RTOL` times the
/// largest counted. For a controllability matrix with speeds of 1e4 and pitches of 0.1 side by
/// side, where a plain SVD threshold reads the small units as zeros.
#[pyfunction]
pub(crate) fn scale_free_rank(
    py: Python<'_>,
    matrix: PyReadonlyArray2<'_, f64>,
) -> PyResult<usize> {
    let m = crate::convert::matrix("matrix", &matrix)?;
    if m.iter().any(|v| !v.is_finite()) {
        return Err(PyValueError::new_err("matrix: must be finite"));
    }
    detached(py, |_| rfcore::analysis::scale_free_rank(&m, "matrix"))
}
