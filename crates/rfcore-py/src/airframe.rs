//! Bindings for the airframe: the validated geometry, thrust limits and efficiencies.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use rfcore::{Airframe, RotorPlacement};

use crate::convert::{read_only, slice1, slice2, to_py_err};

/// An m x 3 array (read-only) from per-rotor vectors.
fn rows3<'py>(py: Python<'py>, rows: impl Iterator<Item = [f64; 3]>) -> Bound<'py, PyArray2<f64>> {
    let rows: Vec<[f64; 3]> = rows.collect();
    let array = Array2::from_shape_fn((rows.len(), 3), |(i, c)| rows[i][c]).into_pyarray(py);
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

    /// The general form: positions and thrust axes (m x 3, body FRD), per-rotor k_mu optional.
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    fn general(
        name: &str,
        position_m: PyReadonlyArray2<'_, f64>,
        thrust_axis: PyReadonlyArray2<'_, f64>,
        spin_sign: PyReadonlyArray1<'_, f64>,
        rotor_drag_torque_ratio_m: Option<PyReadonlyArray1<'_, f64>>,
        max_thrust_n: PyReadonlyArray1<'_, f64>,
        min_thrust_n: PyReadonlyArray1<'_, f64>,
        efficiency: PyReadonlyArray1<'_, f64>,
        mass_kg: f64,
        inertia_kg_m2: PyReadonlyArray1<'_, f64>,
        drag_torque_ratio_m: f64,
        gravity_m_s2: f64,
    ) -> PyResult<Self> {
        let k = match &rotor_drag_torque_ratio_m {
            Some(k) => Some(slice1("rotor_drag_torque_ratio_m", k)?),
            None => None,
        };
        let inner = Airframe::from_general_columns(
            name,
            slice2("position_m", &position_m)?,
            slice2("thrust_axis", &thrust_axis)?,
            slice1("spin", &spin_sign)?,
            k,
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

    fn with_efficiency(&self, efficiency: PyReadonlyArray1<'_, f64>) -> PyResult<Self> {
        let inner = self
            .inner
            .with_efficiency(slice1("efficiency", &efficiency)?)
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

    /// The 6 x m force/torque matrix (body FRD) with efficiencies applied.
    fn wrench_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let b = self.inner.wrench_matrix();
        let (rows, cols) = b.shape();
        let array = Array2::from_shape_fn((rows, cols), |(r, c)| b[(r, c)]);
        Ok(array.into_pyarray(py))
    }

    /// Rotor positions, m x 3, body FRD (planar rotors: `(r cos phi, r sin phi, 0)`).
    #[getter]
    fn position_m<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows3(
            py,
            self.inner.rotors().iter().map(|r| r.placement.position_m()),
        )
    }
    /// Unit thrust axes, m x 3, body FRD.
    #[getter]
    fn thrust_axis<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows3(
            py,
            self.inner
                .rotors()
                .iter()
                .map(|r| r.placement.thrust_axis()),
        )
    }
    /// Each rotor's k_mu (its own, else the airframe's), m.
    #[getter]
    fn rotor_drag_torque_ratio_m<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(
            py,
            (0..self.inner.rotor_count())
                .map(|i| self.inner.rotor_drag_torque_ratio_m(i))
                .collect(),
        )
    }
    #[getter]
    fn is_planar(&self) -> bool {
        self.inner.is_planar()
    }
    #[getter]
    fn is_fully_actuated(&self) -> PyResult<bool> {
        rfcore::analysis::is_fully_actuated(&self.inner).map_err(to_py_err)
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
                .map(|r| {
                    let [x, y, _] = r.placement.position_m();
                    match r.placement {
                        RotorPlacement::Planar { arm_angle_rad, .. } => arm_angle_rad,
                        RotorPlacement::General { .. } => y.atan2(x),
                    }
                })
                .collect(),
        )
    }
    #[getter]
    fn arm_length_m<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(
            py,
            self.inner
                .rotors()
                .iter()
                .map(|r| match r.placement {
                    RotorPlacement::Planar { arm_length_m, .. } => arm_length_m,
                    RotorPlacement::General { position_m, .. } => {
                        position_m[0].hypot(position_m[1])
                    }
                })
                .collect(),
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
