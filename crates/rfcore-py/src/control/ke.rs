//! Bindings for Ke et al.'s uniform passive FTC: the controller, its gains and its preset files.

use pyo3::prelude::*;

use rfcore::control::ke::{CommandLaw, FtcPreset, KeGains, UniformPassiveFtc};

use crate::airframe::PyAirframe;
use crate::convert::to_py_err;

/// Ke Table IV gains (`rotorfault.control.ke.KeGains`); defaults from the core's `Default` (the
/// `ke-hil` preset), rules from its `check`.
#[pyclass(name = "KeGains", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyKeGains {
    pub(crate) inner: KeGains,
}

macro_rules! gain_getters {
    ($($name:ident),*) => {
        #[pymethods]
        impl PyKeGains {
            #[new]
            #[pyo3(signature = (*, $($name=None,)* weights=None))]
            fn new($($name: Option<f64>,)* weights: Option<[f64; 4]>) -> PyResult<Self> {
                let d = KeGains::default();
                let inner = KeGains {
                    $($name: $name.unwrap_or(d.$name),)*
                    weights: weights.unwrap_or(d.weights),
                };
                inner.check().map_err(to_py_err)?;
                Ok(PyKeGains { inner })
            }
            $(
                #[getter]
                fn $name(&self) -> f64 {
                    self.inner.$name
                }
            )*
            #[getter]
            fn weights(&self) -> [f64; 4] {
                self.inner.weights
            }
        }
    };
}

gain_getters!(
    k_p,
    k_v,
    k_vz,
    accel_limit_m_s2,
    k_n3,
    k_omega,
    k_r,
    k_cp,
    epsilon_s,
    k_rotor,
    k_rotor_z,
    k_iz
);

/// The uniform passive fault-tolerant controller (Ke et al.).
#[pyclass(name = "UniformPassiveFtc", module = "rotorfault._rfcore", frozen)]
pub struct PyUniformPassiveFtc {
    pub(crate) inner: UniformPassiveFtc,
}

#[pymethods]
impl PyUniformPassiveFtc {
    #[new]
    #[pyo3(signature = (airframe, *, law, setpoints, dt_s, gains))]
    fn new(
        airframe: &PyAirframe,
        law: &str,
        setpoints: Vec<(f64, [f64; 3])>,
        dt_s: f64,
        gains: &PyKeGains,
    ) -> PyResult<Self> {
        let law = CommandLaw::parse(law).map_err(to_py_err)?;
        let inner = UniformPassiveFtc::new(&airframe.inner, gains.inner, law, setpoints, dt_s)
            .map_err(to_py_err)?;
        Ok(PyUniformPassiveFtc { inner })
    }
}

/// A controller preset file: gains plus the vehicle values Ke does not print.
#[pyclass(name = "FtcPreset", module = "rotorfault._rfcore", frozen)]
pub struct PyFtcPreset {
    inner: FtcPreset,
}

#[pymethods]
impl PyFtcPreset {
    /// Parses a preset file; `origin` prefixes error messages.
    #[staticmethod]
    fn from_toml_str(text: &str, origin: &str) -> PyResult<Self> {
        let inner = FtcPreset::from_toml_str(text, origin).map_err(to_py_err)?;
        Ok(PyFtcPreset { inner })
    }
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    #[getter]
    fn description(&self) -> &str {
        &self.inner.description
    }
    #[getter]
    fn source(&self) -> &str {
        &self.inner.source
    }
    #[getter]
    fn airframe(&self) -> &str {
        &self.inner.airframe
    }
    #[getter]
    fn gains(&self) -> PyKeGains {
        PyKeGains {
            inner: self.inner.gains,
        }
    }
    #[getter]
    fn rotor_time_constant_s(&self) -> f64 {
        self.inner.vehicle.rotor_time_constant_s
    }
    #[getter]
    fn rotational_drag_n_m_s(&self) -> f64 {
        self.inner.vehicle.rotational_drag_n_m_s
    }
    #[getter]
    fn linear_drag_n_s_m(&self) -> f64 {
        self.inner.vehicle.linear_drag_n_s_m
    }
}

impl crate::control::ControllerClass for PyUniformPassiveFtc {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
