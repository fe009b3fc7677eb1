//! Bindings for the airframe: the validated geometry, thrust limits and efficiencies.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;

use rfcore::Airframe;

use crate::convert::{read_only, slice1, to_py_err};

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
