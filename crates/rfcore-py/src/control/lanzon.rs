//! Bindings for Lanzon et al.'s spinning-quadrotor controller: its model, its outer-loop gains
//! and the controller (RFL + discretised loop-shaping controller + outer loop).

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use rfcore::control::lanzon::{
    DiscreteController, LanzonController, LanzonModel, LanzonOuterLoop, LanzonReference,
    LanzonVehicle,
};

use crate::convert::{matrix, settings_class, to_py_err};

settings_class!(
    /// Lanzon's control model (`rotorfault._rfcore.LanzonModel`): Table 1 plus `k_r`, `k_t`.
    PyLanzonModel, "LanzonModel", LanzonModel, prefix = "model", check = LanzonModel::check,
    {
        mass_kg => mass_kg,
        gravity_m_s2 => gravity_m_s2,
        inertia_xx_kg_m2 => inertia_xx_kg_m2,
        inertia_zz_kg_m2 => inertia_zz_kg_m2,
        arm_length_m => arm_length_m,
        drag_torque_ratio_m => drag_torque_ratio_m,
        rotational_drag_n_m_s => rotational_drag_n_m_s,
        linear_drag_n_s_m => linear_drag_n_s_m,
    }
);

settings_class!(
    /// The whole vehicle of Lanzon et al.'s design (`rotorfault.control.lanzon.LanzonVehicle`
    /// subclasses it, adding the RFL algebra in Python): the control model plus the verification
    /// model's values. Keyword-only; defaults the core's `LanzonVehicle::default()`; types checked
    /// here (`vehicle.<field>: expected a real number`), values once by the core's
    /// `LanzonVehicle::check` (errors naming `vehicle.<field>`).
    PyLanzonVehicle, "LanzonVehicle", LanzonVehicle, pyclass = subclass, prefix = "vehicle", check = LanzonVehicle::check,
    {
        mass_kg => model.mass_kg,
        gravity_m_s2 => model.gravity_m_s2,
        inertia_xx_kg_m2 => model.inertia_xx_kg_m2,
        inertia_zz_kg_m2 => model.inertia_zz_kg_m2,
        arm_length_m => model.arm_length_m,
        drag_torque_ratio_m => model.drag_torque_ratio_m,
        rotational_drag_n_m_s => model.rotational_drag_n_m_s,
        linear_drag_n_s_m => model.linear_drag_n_s_m,
        rotor_inertia_kg_m2 => rotor_inertia_kg_m2,
        thrust_coefficient_n_s2 => thrust_coefficient_n_s2,
        max_thrust_n => max_thrust_n,
        rate_limit_n_s => rate_limit_n_s,
    },
    methods = {
        /// What the controller flies with: the control model (the core's `LanzonModel`).
        #[getter]
        fn model(&self) -> PyLanzonModel {
            PyLanzonModel { inner: self.inner.model }
        }
    }
);

settings_class!(
    /// The outer loop (28)-(31) (`rotorfault.control.lanzon.OuterLoopGains`): PD (optionally PID)
    /// position and altitude laws with their limits; defaults the core's, rules its `check`.
    PyLanzonOuterLoop, "OuterLoopGains", LanzonOuterLoop, prefix = "outer_loop", check = LanzonOuterLoop::check,
    {
        k_p_xy => k_p_xy,
        k_d_xy => k_d_xy,
        k_p_z => k_p_z,
        k_d_z => k_d_z,
        max_tilt_rad => max_tilt_rad,
        max_vertical_accel_m_s2 => max_vertical_accel_m_s2,
        k_i_xy => k_i_xy,
        k_i_z => k_i_z,
        integral_limit_m_s => integral_limit_m_s,
    }
);

/// Lanzon et al.'s controller: `a_k`..`d_k` the discrete loop-shaping controller at the control
/// period (3 errors in, 3 linear inputs out); `position` (world NED) closes the outer loop,
/// otherwise `attitude_reference` `[phi_d, theta_d, r_d]` (paper frame) is held.
#[pyclass(name = "LanzonController", module = "rotorfault._rfcore", frozen)]
pub struct PyLanzonController {
    pub(crate) inner: LanzonController,
}

#[pymethods]
impl PyLanzonController {
    #[new]
    #[pyo3(signature = (*, model, a_k, b_k, c_k, d_k, attitude_reference=None, position=None, outer_loop=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: &PyLanzonModel,
        a_k: PyReadonlyArray2<'_, f64>,
        b_k: PyReadonlyArray2<'_, f64>,
        c_k: PyReadonlyArray2<'_, f64>,
        d_k: PyReadonlyArray2<'_, f64>,
        attitude_reference: Option<[f64; 3]>,
        position: Option<[f64; 3]>,
        outer_loop: Option<&PyLanzonOuterLoop>,
    ) -> PyResult<Self> {
        let controller = DiscreteController {
            a: matrix("A_K", &a_k)?,
            b: matrix("B_K", &b_k)?,
            c: matrix("C_K", &c_k)?,
            d: matrix("D_K", &d_k)?,
        };
        let reference = match (position, attitude_reference) {
            (Some(_), Some(_)) => return Err(pyo3::exceptions::PyValueError::new_err(
                "position, attitude_reference: give one (the outer loop or fixed inner set points)",
            )),
            (Some(p), None) => LanzonReference::Position {
                position_ned_m: p,
                gains: outer_loop.map(|g| g.inner).unwrap_or_default(),
            },
            (None, r) => {
                LanzonReference::Attitude(r.unwrap_or([0.0, 0.0, model.inner.spin_rate_rad_s()]))
            }
        };
        let inner = LanzonController::new(model.inner, controller, reference).map_err(to_py_err)?;
        Ok(PyLanzonController { inner })
    }
}

impl crate::control::class::ControllerClass for PyLanzonController {
    fn core(&self, _py: Python<'_>) -> PyResult<Box<dyn rfcore::control::Controller>> {
        Ok(Box::new(self.inner.clone()))
    }
}
