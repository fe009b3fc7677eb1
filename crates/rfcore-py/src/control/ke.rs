//! Bindings for Ke et al.'s uniform passive FTC: the controller, its gains and its preset files.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::control::ke::{CommandLaw, FtcPreset, KeGains, UniformPassiveFtc};

use crate::airframe::PyAirframe;
use crate::convert::{real, settings_eq, settings_hash, settings_kwargs, settings_replace, settings_repr, to_py_err};

/// Ke Table IV gains: the one `KeGains` class, used directly from Python (re-exported as
/// `rotorfault.control.ke.KeGains`). Keyword-only; defaults from the core's `Default` (the `ke-hil`
/// preset); types checked here, values once, by the core's `check`, with its messages. Frozen,
/// comparable, hashable, picklable; `replace(**changes)` gives a validated copy.
///
/// Examples:
///
///     >>> from rotorfault.control import KeGains
///     >>> gains = KeGains(k_p=1.5)
///     >>> gains.k_p
///     1.5
#[pyclass(name = "KeGains", module = "rotorfault._rfcore", frozen)]
#[derive(Clone)]
pub struct PyKeGains {
    pub(crate) inner: KeGains,
}

macro_rules! gains_class {
    ($($name:ident),*) => {
        /// The field names, in order (`weights` last).
        const KE_GAIN_FIELDS: &[&str] = &[$(stringify!($name),)* "weights"];

        #[pymethods]
        impl PyKeGains {
            #[new]
            #[pyo3(signature = (*, $($name=None,)* weights=None))]
            fn new($($name: Option<Bound<'_, PyAny>>,)* weights: Option<Bound<'_, PyAny>>) -> PyResult<Self> {
                let d = KeGains::default();
                let inner = KeGains {
                    $($name: match $name { Some(v) => real(stringify!($name), &v)?, None => d.$name },)*
                    weights: match weights { Some(v) => gain_weights(&v)?, None => d.weights },
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
            /// `(w_f, w_p, w_q, w_r)`: the allocation weights.
            #[getter]
            fn weights(&self) -> (f64, f64, f64, f64) {
                let [a, b, c, e] = self.inner.weights;
                (a, b, c, e)
            }
            /// The field names, in order.
            #[classattr]
            #[pyo3(name = "FIELDS")]
            fn fields() -> Vec<&'static str> {
                KE_GAIN_FIELDS.to_vec()
            }
            /// A copy with ``changes`` (validated like a new object).
            #[pyo3(signature = (**changes))]
            fn replace<'py>(slf: &Bound<'py, Self>, changes: Option<&Bound<'py, PyDict>>) -> PyResult<Bound<'py, PyAny>> {
                settings_replace(slf.as_any(), KE_GAIN_FIELDS, changes)
            }
            fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
                settings_repr(slf.as_any(), KE_GAIN_FIELDS)
            }
            fn __eq__(slf: &Bound<'_, Self>, other: &Bound<'_, PyAny>) -> PyResult<bool> {
                settings_eq(slf.as_any(), other, KE_GAIN_FIELDS)
            }
            fn __hash__(slf: &Bound<'_, Self>) -> PyResult<isize> {
                settings_hash(slf.as_any(), KE_GAIN_FIELDS)
            }
            fn __getnewargs_ex__<'py>(slf: &Bound<'py, Self>) -> PyResult<((), Bound<'py, PyDict>)> {
                Ok(((), settings_kwargs(slf.as_any(), KE_GAIN_FIELDS)?))
            }
        }
    };
}

gains_class!(
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

/// The four allocation weights `(w_f, w_p, w_q, w_r)` (values checked by the core).
fn gain_weights(value: &Bound<'_, PyAny>) -> PyResult<[f64; 4]> {
    let items: Vec<Bound<'_, PyAny>> = value
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("weights: expected 4 numbers (w_f, w_p, w_q, w_r), got {}", value.get_type().name().map(|n| n.to_string()).unwrap_or_default())))?
        .collect::<PyResult<_>>()?;
    if items.len() != 4 {
        return Err(PyValueError::new_err(format!("weights: expected 4 entries (w_f, w_p, w_q, w_r), got {}", items.len())));
    }
    let mut out = [0.0; 4];
    for (k, item) in items.iter().enumerate() {
        out[k] = real(&format!("weights[{k}]"), item)?;
    }
    Ok(out)
}

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

impl crate::control::class::ControllerClass for PyUniformPassiveFtc {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
