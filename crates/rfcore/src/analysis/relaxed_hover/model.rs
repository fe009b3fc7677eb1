//! The relaxed hover equations of one airframe: rotor forces, torques, the rotors' angular
//! momentum, and the residual of a candidate solution. Everything the search solves is checked
//! against [`Model::residual`] before it is returned.
//!
//! Conventions (the simulator's, `flight::vehicle` and `flight::actuator`): body FRD; rotor `i`
//! pushes along its unit axis `a_i` with the produced thrust `f_i` (after efficiency) and adds the
//! torque column `tau_i` of the airframe's wrench matrix per newton; it spins about `+a_i` when
//! anticlockwise seen from the side the thrust points to (`w_i = +1`) at `sqrt(f_i / k_f)` rad/s,
//! so the rotors carry the angular momentum `h(f) = I_R sum_i w_i sqrt(f_i / k_f) a_i`.

use nalgebra::{Matrix3, Vector3};

use crate::airframe::Airframe;
use crate::error::{Result, RfError};

use super::settings::RelaxedHoverSettings;

pub(crate) type V3 = Vector3<f64>;

/// An airframe and the settings, as the equations need them (rotor arrays are per rotor, all m).
#[derive(Debug, Clone)]
pub(crate) struct Model {
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
    pub inertia: Matrix3<f64>,
    /// `a_i`, body FRD unit vectors.
    pub axis: Vec<V3>,
    /// `tau_i`: body torque per newton of thrust (arm and reaction torque), m.
    pub torque: Vec<V3>,
    /// Produced-thrust bounds: efficiency times the rotor's command bounds, N.
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    pub efficiency: Vec<f64>,
    /// `I_R w_i a_i / sqrt(k_f)`: the rotor's angular momentum per square-root newton.
    pub momentum: Vec<V3>,
    pub rotational_drag_n_m_s: f64,
    /// Rotors with efficiency > 0, in rotor order.
    pub working: Vec<usize>,
    /// A torque scale for residuals: weight times the largest torque per newton, N m.
    pub torque_scale: f64,
}

impl Model {
    pub fn new(airframe: &Airframe, settings: &RelaxedHoverSettings) -> Result<Self> {
        let wrench = airframe.nominal_wrench_matrix();
        let m = airframe.rotor_count();
        let column =
            |i: usize, r: usize| V3::new(wrench[(r, i)], wrench[(r + 1, i)], wrench[(r + 2, i)]);
        let axis: Vec<V3> = (0..m).map(|i| column(i, 0)).collect();
        let torque: Vec<V3> = (0..m).map(|i| column(i, 3)).collect();
        let gyro = if settings.rotor_inertia_kg_m2 > 0.0 {
            settings.rotor_inertia_kg_m2 / settings.thrust_coefficient_n_s2.sqrt()
        } else {
            0.0
        };
        let rotors = airframe.rotors();
        let momentum = (0..m)
            .map(|i| axis[i] * (gyro * rotors[i].spin.yaw_sign()))
            .collect();
        let efficiency: Vec<f64> = rotors.iter().map(|r| r.efficiency).collect();
        let lower: Vec<f64> = rotors
            .iter()
            .map(|r| r.efficiency * r.min_thrust_n)
            .collect();
        let upper: Vec<f64> = rotors
            .iter()
            .map(|r| r.efficiency * r.max_thrust_n)
            .collect();
        let working = (0..m).filter(|&i| efficiency[i] > 0.0).collect();
        let weight = airframe.mass_kg() * airframe.gravity_m_s2();
        let arm = torque.iter().map(|t| t.norm()).fold(0.0, f64::max);
        if weight.is_nan() || weight <= 0.0 {
            return Err(RfError::invalid(
                "gravity_m_s2",
                "relaxed hover needs a weight to carry: gravity must be > 0",
            ));
        }
        let [jx, jy, jz] = airframe.inertia_kg_m2();
        Ok(Model {
            mass_kg: airframe.mass_kg(),
            gravity_m_s2: airframe.gravity_m_s2(),
            inertia: Matrix3::from_diagonal(&V3::new(jx, jy, jz)),
            axis,
            torque,
            lower,
            upper,
            efficiency,
            momentum,
            rotational_drag_n_m_s: settings.rotational_drag_n_m_s,
            working,
            torque_scale: weight * arm.max(f64::MIN_POSITIVE),
        })
    }

    pub fn weight_n(&self) -> f64 {
        self.mass_kg * self.gravity_m_s2
    }

    pub fn rotor_count(&self) -> usize {
        self.axis.len()
    }

    /// `h(f)`, kg m^2/s (the simulator takes the rotor speed of a non-positive thrust as 0).
    pub fn rotor_momentum(&self, thrust_n: &[f64]) -> V3 {
        self.momentum
            .iter()
            .zip(thrust_n)
            .map(|(c, &f)| c * f.max(0.0).sqrt())
            .sum()
    }

    pub fn force(&self, thrust_n: &[f64]) -> V3 {
        self.axis.iter().zip(thrust_n).map(|(a, &f)| a * f).sum()
    }

    pub fn rotor_torque(&self, thrust_n: &[f64]) -> V3 {
        self.torque.iter().zip(thrust_n).map(|(t, &f)| t * f).sum()
    }

    /// The torque the rotors must supply to hold the body rate `omega` constant:
    /// `omega x (J omega + h) + k_r omega`.
    pub fn required_torque(&self, omega: &V3, momentum: &V3) -> V3 {
        omega.cross(&(self.inertia * omega + momentum)) + self.rotational_drag_n_m_s * omega
    }

    /// The relaxed hover residual of body rate `omega` and thrusts `f` (all m rotors) with the
    /// body axis `up` pointing up: `[n.F - m g, tau(f) - omega x (J omega + h(f)) - k_r omega]`
    /// for a spinning solution (`omega` parallel to `up`), and for a static one (`omega = 0`)
    /// the whole force `F - m g up` in place of its vertical part. Scaled: force by `m g`, torque
    /// by [`Model::torque_scale`]; the largest absolute entry is returned, with the parallelism
    /// of `omega` and `up` as part of it.
    pub fn residual(&self, omega: &V3, up: &V3, thrust_n: &[f64]) -> f64 {
        let weight = self.weight_n();
        let force = self.force(thrust_n);
        let h = self.rotor_momentum(thrust_n);
        let torque = self.rotor_torque(thrust_n) - self.required_torque(omega, &h);
        let force_error = if omega.norm() == 0.0 {
            (force - weight * up).amax() / weight
        } else {
            // The average force is vertical only when the spin axis is; its vertical part carries
            // the weight (the horizontal part turns with the body and averages out).
            let axis_error = omega.cross(up).norm() / omega.norm();
            ((up.dot(&force) - weight) / weight).abs().max(axis_error)
        };
        force_error.max(torque.amax() / self.torque_scale)
    }
}

/// `(e1, e2)`: a right-handed orthonormal pair completing the unit vector `n`, chosen by a rule
/// that depends only on `n` (so the same axis gets the same basis every time).
pub(crate) fn tangent_basis(n: &V3) -> (V3, V3) {
    let helper = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        V3::x()
    } else if n.y.abs() <= n.z.abs() {
        V3::y()
    } else {
        V3::z()
    };
    let e1 = helper.cross(n).normalize();
    let e2 = n.cross(&e1);
    (e1, e2)
}
