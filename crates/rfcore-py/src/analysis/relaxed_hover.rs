//! Bindings for the relaxed hover analysis (Mueller and D'Andrea): settings, solutions, the
//! analysis and the residual check. Translation only.

use nalgebra::DMatrix;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;

use rfcore::analysis::relaxed_hover::{
    best_relaxed_hover_cancellable as core_best_relaxed_hover,
    relaxed_hover_cancellable as core_relaxed_hover, relaxed_hover_residual as core_residual,
    RelaxedHoverAnalysis, RelaxedHoverSettings, RelaxedHoverSolution,
};

use crate::airframe::PyAirframe;
use crate::convert::{detached, read_only, rotor_numbers, slice1};

fn array2<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    numpy::ndarray::Array2::from_shape_fn((m.nrows(), m.ncols()), |(r, c)| m[(r, c)])
        .into_pyarray(py)
}

/// What the relaxed hover analysis needs beyond the airframe (defaults: the core's).
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> settings = rf.RelaxedHoverSettings(rotational_drag_n_m_s=2.8e-3)
///     >>> settings.rotational_drag_n_m_s, settings.grid_points
///     (0.0028, 61)
#[pyclass(name = "RelaxedHoverSettings", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyRelaxedHoverSettings {
    pub(crate) inner: RelaxedHoverSettings,
}

impl PyRelaxedHoverSettings {
    const FIELDS: &'static [&'static str] = &["rotational_drag_n_m_s", "rotor_inertia_kg_m2", "thrust_coefficient_n_s2", "max_spin_rate_rad_s", "max_circle_radius_m", "max_idle_rotors", "grid_points"];
}

crate::convert::pickle_protocol!(PyRelaxedHoverSettings, {
    #[new]
    #[pyo3(signature = (*, rotational_drag_n_m_s=None, rotor_inertia_kg_m2=None, thrust_coefficient_n_s2=None,
                        max_spin_rate_rad_s=None, max_circle_radius_m=None, max_idle_rotors=None, grid_points=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        rotational_drag_n_m_s: Option<f64>,
        rotor_inertia_kg_m2: Option<f64>,
        thrust_coefficient_n_s2: Option<f64>,
        max_spin_rate_rad_s: Option<f64>,
        max_circle_radius_m: Option<f64>,
        max_idle_rotors: Option<Bound<'_, PyAny>>,
        grid_points: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let counted = |field: &str, v: Option<Bound<'_, PyAny>>, default: usize| -> PyResult<usize> {
            v.map_or(Ok(default), |v| crate::convert::count(field, &v))
        };
        let d = RelaxedHoverSettings::default();
        let inner = RelaxedHoverSettings {
            rotational_drag_n_m_s: rotational_drag_n_m_s.unwrap_or(d.rotational_drag_n_m_s),
            rotor_inertia_kg_m2: rotor_inertia_kg_m2.unwrap_or(d.rotor_inertia_kg_m2),
            thrust_coefficient_n_s2: thrust_coefficient_n_s2.unwrap_or(d.thrust_coefficient_n_s2),
            max_spin_rate_rad_s: max_spin_rate_rad_s.unwrap_or(d.max_spin_rate_rad_s),
            max_circle_radius_m: max_circle_radius_m.unwrap_or(d.max_circle_radius_m),
            max_idle_rotors: counted("max_idle_rotors", max_idle_rotors, d.max_idle_rotors)?,
            grid_points: counted("grid_points", grid_points, d.grid_points)?,
        };
        inner.check().map_err(crate::convert::to_py_err)?;
        Ok(PyRelaxedHoverSettings { inner })
    }
    #[getter]
    fn rotational_drag_n_m_s(&self) -> f64 {
        self.inner.rotational_drag_n_m_s
    }
    #[getter]
    fn rotor_inertia_kg_m2(&self) -> f64 {
        self.inner.rotor_inertia_kg_m2
    }
    #[getter]
    fn thrust_coefficient_n_s2(&self) -> f64 {
        self.inner.thrust_coefficient_n_s2
    }
    #[getter]
    fn max_spin_rate_rad_s(&self) -> f64 {
        self.inner.max_spin_rate_rad_s
    }
    #[getter]
    fn max_circle_radius_m(&self) -> f64 {
        self.inner.max_circle_radius_m
    }
    #[getter]
    fn max_idle_rotors(&self) -> usize {
        self.inner.max_idle_rotors
    }
    #[getter]
    fn grid_points(&self) -> usize {
        self.inner.grid_points
    }
    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "RelaxedHoverSettings(rotational_drag_n_m_s={}, rotor_inertia_kg_m2={}, thrust_coefficient_n_s2={}, \
             max_spin_rate_rad_s={}, max_circle_radius_m={}, max_idle_rotors={}, grid_points={})",
            s.rotational_drag_n_m_s, s.rotor_inertia_kg_m2, s.thrust_coefficient_n_s2, s.max_spin_rate_rad_s,
            s.max_circle_radius_m, s.max_idle_rotors, s.grid_points
        )
    }
});

/// One relaxed hover solution, checked (rotor numbers 1-based).
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
///     >>> settings = rf.RelaxedHoverSettings(rotational_drag_n_m_s=2.8e-3, grid_points=21)
///     >>> best = rf.relaxed_hover(quad, settings).best
///     >>> round(best.spin_rate_rad_s, 2), best.carrying
///     (15.22, [2, 3, 4])
#[pyclass(name = "RelaxedHoverSolution", module = "rotorfault._rfcore", frozen)]
pub struct PyRelaxedHoverSolution {
    inner: RelaxedHoverSolution,
}

#[pymethods]
impl PyRelaxedHoverSolution {
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind.name()
    }
    #[getter]
    fn body_rate_rad_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.body_rate_rad_s.to_vec())
    }
    #[getter]
    fn spin_rate_rad_s(&self) -> f64 {
        self.inner.spin_rate_rad_s
    }
    #[getter]
    fn spin_axis<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.spin_axis.to_vec())
    }
    #[getter]
    fn thrust_direction<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.thrust_direction.to_vec())
    }
    #[getter]
    fn thrust_n<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.thrust_n.clone())
    }
    #[getter]
    fn command_n<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.inner.command_n.clone())
    }
    #[getter]
    fn thrust_margin_n(&self) -> f64 {
        self.inner.thrust_margin_n
    }
    #[getter]
    fn thrust_floor_n(&self) -> f64 {
        self.inner.thrust_floor_n
    }
    #[getter]
    fn carrying(&self) -> Vec<usize> {
        rotor_numbers(&self.inner.carrying)
    }
    #[getter]
    fn idle(&self) -> Vec<usize> {
        rotor_numbers(&self.inner.idle)
    }
    #[getter]
    fn total_thrust_n(&self) -> f64 {
        self.inner.total_thrust_n
    }
    #[getter]
    fn tilt_rad(&self) -> f64 {
        self.inner.tilt_rad
    }
    #[getter]
    fn circle_radius_m(&self) -> f64 {
        self.inner.circle_radius_m
    }
    #[getter]
    fn residual(&self) -> f64 {
        self.inner.residual
    }
    #[getter]
    fn at_spin_rate_limit(&self) -> bool {
        self.inner.at_spin_rate_limit
    }
    #[getter]
    fn at_circle_radius_limit(&self) -> bool {
        self.inner.at_circle_radius_limit
    }
    /// `A` (7 x 7) of the linear model about this solution.
    #[getter]
    fn linear_a<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        array2(py, &self.inner.linear.a)
    }
    /// `B` (7 x carrying rotors).
    #[getter]
    fn linear_b<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        array2(py, &self.inner.linear.b)
    }
    /// `(e1, e2)`: the tangent basis of the reduced attitude (rows of a 2 x 3 array).
    #[getter]
    fn tangent_basis<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let l = &self.inner.linear;
        array2(
            py,
            &DMatrix::from_row_slice(
                2,
                3,
                &[l.e1[0], l.e1[1], l.e1[2], l.e2[0], l.e2[1], l.e2[2]],
            ),
        )
    }
    #[getter]
    fn stabilizable(&self) -> bool {
        self.inner.linear.stabilizable
    }
    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "RelaxedHoverSolution(kind={:?}, spin_rate_rad_s={:.6}, thrust_margin_n={:.6}, carrying={:?}, \
             stabilizable={})",
            s.kind.name(),
            s.spin_rate_rad_s,
            s.thrust_margin_n,
            rotor_numbers(&s.carrying),
            if s.linear.stabilizable { "True" } else { "False" }
        )
    }
}

/// Every relaxed hover solution of an airframe, best first.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
///     >>> settings = rf.RelaxedHoverSettings(rotational_drag_n_m_s=2.8e-3, grid_points=21)
///     >>> analysis = rf.relaxed_hover(quad, settings)
///     >>> len(analysis.solutions) > 0, analysis.best.carrying
///     (True, [2, 3, 4])
#[pyclass(name = "RelaxedHoverAnalysis", module = "rotorfault._rfcore", frozen)]
pub struct PyRelaxedHoverAnalysis {
    solutions: Vec<Py<PyRelaxedHoverSolution>>,
    best: bool,
    settings: RelaxedHoverSettings,
}

#[pymethods]
impl PyRelaxedHoverAnalysis {
    #[getter]
    fn solutions(&self, py: Python<'_>) -> Vec<Py<PyRelaxedHoverSolution>> {
        self.solutions.iter().map(|s| s.clone_ref(py)).collect()
    }
    /// The solution with the most thrust margin a linear feedback can hold, or `None`.
    #[getter]
    fn best(&self, py: Python<'_>) -> Option<Py<PyRelaxedHoverSolution>> {
        self.best.then(|| self.solutions[0].clone_ref(py))
    }
    #[getter]
    fn settings(&self) -> PyRelaxedHoverSettings {
        PyRelaxedHoverSettings {
            inner: self.settings,
        }
    }
    fn __len__(&self) -> usize {
        self.solutions.len()
    }
    fn __repr__(&self, py: Python<'_>) -> String {
        let best = if self.best {
            self.solutions[0].borrow(py).__repr__()
        } else {
            "None".to_string()
        };
        format!(
            "RelaxedHoverAnalysis({} solutions, best={best})",
            self.solutions.len()
        )
    }
}

fn analysis(py: Python<'_>, result: RelaxedHoverAnalysis) -> PyResult<PyRelaxedHoverAnalysis> {
    let best = result.best().is_some();
    let solutions = result
        .solutions
        .into_iter()
        .map(|inner| Py::new(py, PyRelaxedHoverSolution { inner }))
        .collect::<PyResult<Vec<_>>>()?;
    Ok(PyRelaxedHoverAnalysis {
        solutions,
        best,
        settings: result.settings,
    })
}

/// Every relaxed hover solution of `airframe` (efficiencies included), GIL released.
#[pyfunction]
#[pyo3(signature = (airframe, settings, best_only=false))]
pub(crate) fn relaxed_hover(
    py: Python<'_>,
    airframe: &PyAirframe,
    settings: &PyRelaxedHoverSettings,
    best_only: bool,
) -> PyResult<PyRelaxedHoverAnalysis> {
    let (frame, s) = (airframe.inner.clone(), settings.inner);
    let result = detached(py, move |cancel| {
        if best_only {
            core_best_relaxed_hover(&frame, &s, cancel)
        } else {
            core_relaxed_hover(&frame, &s, cancel)
        }
    })?;
    analysis(py, result)
}

/// The scaled relaxed hover residual of a proposed body rate, up axis and thrusts.
#[pyfunction]
pub(crate) fn relaxed_hover_residual(
    airframe: &PyAirframe,
    settings: &PyRelaxedHoverSettings,
    body_rate_rad_s: [f64; 3],
    up: [f64; 3],
    thrust_n: PyReadonlyArray1<'_, f64>,
) -> PyResult<f64> {
    core_residual(
        &airframe.inner,
        &settings.inner,
        body_rate_rad_s,
        up,
        slice1("thrust_n", &thrust_n)?,
    )
    .map_err(crate::convert::to_py_err)
}
