//! Bindings for Ke et al.'s uniform passive FTC: the controller and its preset files.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use rfcore::control::ke::{CommandLaw, FtcPreset, KeGains, UniformPassiveFtc};

use crate::airframe::PyAirframe;
use crate::convert::to_py_err;

/// The uniform passive fault-tolerant controller (Ke et al.).
#[pyclass(name = "UniformPassiveFtc", module = "rotorfault._rfcore", frozen)]
pub struct PyUniformPassiveFtc {
    pub(crate) inner: UniformPassiveFtc,
}

#[pymethods]
impl PyUniformPassiveFtc {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (airframe, law, setpoints, dt, k_p, k_v, k_vz, accel_limit_m_s2, k_n3, k_omega, k_r, k_cp, epsilon_s, k_rotor, k_rotor_z, weights, k_iz))]
    fn new(
        airframe: &PyAirframe,
        law: &str,
        setpoints: Vec<(f64, [f64; 3])>,
        dt: f64,
        k_p: f64,
        k_v: f64,
        k_vz: f64,
        accel_limit_m_s2: f64,
        k_n3: f64,
        k_omega: f64,
        k_r: f64,
        k_cp: f64,
        epsilon_s: f64,
        k_rotor: f64,
        k_rotor_z: f64,
        weights: [f64; 4],
        k_iz: f64,
    ) -> PyResult<Self> {
        let gains = KeGains {
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
            weights,
            k_iz,
        };
        let law = CommandLaw::parse(law).map_err(to_py_err)?;
        let inner = UniformPassiveFtc::new(&airframe.inner, gains, law, setpoints, dt)
            .map_err(to_py_err)?;
        Ok(PyUniformPassiveFtc { inner })
    }
}

/// A controller preset file as a dict (gains and vehicle values as nested dicts).
#[pyfunction]
pub fn ftc_preset_from_toml<'py>(
    py: Python<'py>,
    text: &str,
    origin: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let preset = FtcPreset::from_toml_str(text, origin).map_err(to_py_err)?;
    let out = PyDict::new(py);
    out.set_item("name", preset.name)?;
    out.set_item("description", preset.description)?;
    out.set_item("source", preset.source)?;
    out.set_item("airframe", preset.airframe)?;
    let g = preset.gains;
    let gains = PyDict::new(py);
    for (key, value) in [
        ("k_p", g.k_p),
        ("k_v", g.k_v),
        ("k_vz", g.k_vz),
        ("accel_limit_m_s2", g.accel_limit_m_s2),
        ("k_n3", g.k_n3),
        ("k_omega", g.k_omega),
        ("k_r", g.k_r),
        ("k_cp", g.k_cp),
        ("epsilon_s", g.epsilon_s),
        ("k_rotor", g.k_rotor),
        ("k_rotor_z", g.k_rotor_z),
        ("k_iz", g.k_iz),
    ] {
        gains.set_item(key, value)?;
    }
    gains.set_item("weights", g.weights.to_vec())?;
    out.set_item("gains", gains)?;
    let vehicle = PyDict::new(py);
    vehicle.set_item(
        "rotor_time_constant_s",
        preset.vehicle.rotor_time_constant_s,
    )?;
    vehicle.set_item(
        "rotational_drag_n_m_s",
        preset.vehicle.rotational_drag_n_m_s,
    )?;
    vehicle.set_item("linear_drag_n_s_m", preset.vehicle.linear_drag_n_s_m)?;
    out.set_item("vehicle", vehicle)?;
    Ok(out)
}

