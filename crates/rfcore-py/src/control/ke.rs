//! Bindings for Ke et al.'s uniform passive FTC: the controller, its gains and its preset files.

use pyo3::prelude::*;
use pyo3::types::PyType;

use rfcore::control::ke::{CommandLaw, FtcPreset, FtcVehicle, KeGains, UniformPassiveFtc};

use crate::airframe::PyAirframe;
use crate::convert::{fixed_reals, real, settings_kwargs, settings_protocol, to_py_err};

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
        impl PyKeGains {
            /// The field names, in order (`weights` last).
            const FIELDS: &'static [&'static str] = &[$(stringify!($name),)* "weights"];
        }

        settings_protocol!(PyKeGains, {
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
        });
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
    fixed_reals("weights", "w_f, w_p, w_q, w_r", value)
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

/// A controller preset: gains plus the vehicle values Ke does not print, as the core holds them
/// (`rotorfault.control.ke.FtcPreset` subclasses it, adding in Python what reads them: the airframe
/// object and the simulator). Keyword-only, every field required, checked by the core's
/// `FtcPreset::check`; `from_toml_str` parses a preset file. Frozen, comparable, hashable,
/// picklable, `replace(**changes)`, `FIELDS`.
#[pyclass(name = "FtcPreset", module = "rotorfault._rfcore", frozen, subclass)]
#[derive(Clone)]
pub struct PyFtcPreset {
    inner: FtcPreset,
}

impl PyFtcPreset {
    const FIELDS: &'static [&'static str] = &[
        "name",
        "description",
        "source",
        "airframe_name",
        "gains",
        "rotor_time_constant_s",
        "rotational_drag_n_m_s",
        "linear_drag_n_s_m",
    ];
}

settings_protocol!(PyFtcPreset, {
    #[new]
    #[pyo3(signature = (*, name, description, source, airframe_name, gains, rotor_time_constant_s, rotational_drag_n_m_s, linear_drag_n_s_m))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        name: String,
        description: String,
        source: String,
        airframe_name: String,
        gains: PyRef<'_, PyKeGains>,
        rotor_time_constant_s: Bound<'_, PyAny>,
        rotational_drag_n_m_s: Bound<'_, PyAny>,
        linear_drag_n_s_m: Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let inner = FtcPreset {
            name,
            description,
            source,
            airframe: airframe_name,
            gains: gains.inner,
            vehicle: FtcVehicle {
                rotor_time_constant_s: real("vehicle.rotor_time_constant_s", &rotor_time_constant_s)?,
                rotational_drag_n_m_s: real("vehicle.rotational_drag_n_m_s", &rotational_drag_n_m_s)?,
                linear_drag_n_s_m: real("vehicle.linear_drag_n_s_m", &linear_drag_n_s_m)?,
            },
        };
        inner.check().map_err(to_py_err)?;
        Ok(PyFtcPreset { inner })
    }
    /// Parses a preset file's `text` (`origin` prefixes error messages) into this class.
    #[classmethod]
    fn from_toml_str<'py>(cls: &Bound<'py, PyType>, text: &str, origin: &str) -> PyResult<Bound<'py, PyAny>> {
        let parsed = Bound::new(cls.py(), PyFtcPreset { inner: FtcPreset::from_toml_str(text, origin).map_err(to_py_err)? })?;
        cls.call((), Some(&settings_kwargs(parsed.as_any(), Self::FIELDS)?))
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
    /// The airframe preset the gains were designed for.
    #[getter]
    fn airframe_name(&self) -> &str {
        &self.inner.airframe
    }
    #[getter]
    fn gains(&self) -> PyKeGains {
        PyKeGains {
            inner: self.inner.gains,
        }
    }
    /// Rotor first-order lag, s (Ke Table III: 0.025).
    #[getter]
    fn rotor_time_constant_s(&self) -> f64 {
        self.inner.vehicle.rotor_time_constant_s
    }
    /// Linear rotational damping `k_r`, N m s (not in the paper: sets the steady spin).
    #[getter]
    fn rotational_drag_n_m_s(&self) -> f64 {
        self.inner.vehicle.rotational_drag_n_m_s
    }
    /// Linear translational drag `k_t`, N s/m (not in the paper).
    #[getter]
    fn linear_drag_n_s_m(&self) -> f64 {
        self.inner.vehicle.linear_drag_n_s_m
    }
});

impl crate::control::class::ControllerClass for PyUniformPassiveFtc {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
