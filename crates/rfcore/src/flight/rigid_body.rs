//! Rigid-body 6-DOF dynamics (Newton-Euler with the full inertia tensor) and the classical RK4 step.
//!
//! This is the bottom layer of the flight simulator: it knows nothing about rotors. Whoever drives
//! it supplies the total force (world frame) and torque (body frame) as a function of time and
//! state, so thrust orientation, drag and wind can all depend on the state within a step.
//!
//! # Frames and units
//! World frame NED (x north, y east, z down; gravity is `+g` along z), body frame FRD (x forward,
//! y right, z down), as everywhere in rotorfault. The attitude is the unit quaternion rotating body
//! vectors into the world frame. Position m, velocity m/s (world), body rates rad/s, force N,
//! torque N m.
//!
//! # Integration
//! Classical fourth-order Runge-Kutta on the 13-dimensional state, the quaternion integrated as a
//! plain 4-vector (`q' = q (0, omega) / 2`) and renormalised once at the end of each step: the
//! renormalisation moves the state by O(dt^5), so the step stays fourth order, and `|q| = 1` holds
//! to machine precision however long the run.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

use crate::error::{require_finite, require_scale, Result, RfError};
use crate::state::RigidBodyState;

/// Mass and inertia of a rigid body.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidBody {
    mass_kg: f64,
    /// 1 / mass: a multiplication in every derivative instead of a division.
    inverse_mass: f64,
    inertia_kg_m2: Matrix3<f64>,
    inertia_inverse: Matrix3<f64>,
}

impl RigidBody {
    /// `inertia_kg_m2` is the full body-frame inertia tensor about the centre of mass: symmetric
    /// and positive definite.
    pub fn new(mass_kg: f64, inertia_kg_m2: Matrix3<f64>) -> Result<Self> {
        // Divided by in every derivative: a scale (see `crate::error`).
        require_scale("mass_kg", mass_kg, "kg")?;
        for (i, &v) in inertia_kg_m2.iter().enumerate() {
            require_finite(&format!("inertia_kg_m2[{}, {}]", i % 3, i / 3), v)?;
        }
        let asymmetry = (inertia_kg_m2 - inertia_kg_m2.transpose()).abs().max();
        if asymmetry > 1e-12 * inertia_kg_m2.abs().max() {
            return Err(RfError::invalid("inertia_kg_m2", "must be symmetric"));
        }
        if inertia_kg_m2.cholesky().is_none() {
            return Err(RfError::invalid(
                "inertia_kg_m2",
                "must be positive definite",
            ));
        }
        // Positive definite, so the diagonal is positive: each moment is a scale `J^-1` divides by.
        for i in 0..3 {
            require_scale(
                &format!("inertia_kg_m2[{i}, {i}]"),
                inertia_kg_m2[(i, i)],
                "kg m^2",
            )?;
        }
        let inertia_inverse = inertia_kg_m2
            .try_inverse()
            .ok_or_else(|| RfError::invalid("inertia_kg_m2", "must be invertible"))?;
        Ok(RigidBody {
            mass_kg,
            inverse_mass: 1.0 / mass_kg,
            inertia_kg_m2,
            inertia_inverse,
        })
    }

    /// A body with principal axes along the body axes: `J = diag(jx, jy, jz)`.
    pub fn principal(mass_kg: f64, [jx, jy, jz]: [f64; 3]) -> Result<Self> {
        RigidBody::new(mass_kg, Matrix3::from_diagonal(&Vector3::new(jx, jy, jz)))
    }

    pub fn mass_kg(&self) -> f64 {
        self.mass_kg
    }

    pub fn inertia_kg_m2(&self) -> &Matrix3<f64> {
        &self.inertia_kg_m2
    }

    /// `J^-1`, as the derivative uses it (the SIMD lanes need the same bits).
    pub(crate) fn inertia_inverse(&self) -> &Matrix3<f64> {
        &self.inertia_inverse
    }

    /// `1 / mass`, as the derivative uses it.
    pub(crate) fn inverse_mass(&self) -> f64 {
        self.inverse_mass
    }

    /// The time derivative of `state` under `wrench` (Newton-Euler).
    #[inline]
    pub fn derivative(&self, state: &RigidBodyState, wrench: &Wrench) -> StateDerivative {
        let omega = state.omega_rad_s;
        let j_omega = self.inertia_kg_m2 * omega;
        StateDerivative {
            position: state.velocity_m_s,
            velocity: wrench.force_world_n * self.inverse_mass,
            attitude: state.attitude.quaternion() * Quaternion::from_imag(omega) * 0.5,
            omega: self.inertia_inverse * (wrench.torque_body_nm - omega.cross(&j_omega)),
        }
    }

    /// One classical RK4 step of length `dt_s` from time `t_s`. `wrench_at(t, state)` gives the
    /// total force and torque; it is called four times per step.
    pub fn rk4_step<F>(
        &self,
        t_s: f64,
        state: &RigidBodyState,
        dt_s: f64,
        mut wrench_at: F,
    ) -> RigidBodyState
    where
        F: FnMut(f64, &RigidBodyState) -> Wrench,
    {
        let times = [t_s, t_s + 0.5 * dt_s, t_s + dt_s];
        self.rk4_step_nodes(state, dt_s, |node, x| wrench_at(times[node], x))
    }

    /// One classical RK4 step of length `dt_s` whose wrench is given per time node:
    /// `wrench_at(node, state)` with node 0 at the start, 1 at the midpoint (stages 2 and 3),
    /// 2 at the end. Lets a caller evaluate time-dependent inputs (actuator states) once per
    /// node instead of once per stage.
    #[inline]
    pub fn rk4_step_nodes<F>(
        &self,
        state: &RigidBodyState,
        dt_s: f64,
        mut wrench_at: F,
    ) -> RigidBodyState
    where
        F: FnMut(usize, &RigidBodyState) -> Wrench,
    {
        let k1 = self.derivative(state, &wrench_at(0, state));
        let s2 = advanced(state, &k1, 0.5 * dt_s);
        let k2 = self.derivative(&s2, &wrench_at(1, &s2));
        let s3 = advanced(state, &k2, 0.5 * dt_s);
        let k3 = self.derivative(&s3, &wrench_at(1, &s3));
        let s4 = advanced(state, &k3, dt_s);
        let k4 = self.derivative(&s4, &wrench_at(2, &s4));
        let sixth = dt_s / 6.0;
        let attitude = state.attitude.quaternion()
            + (k1.attitude + k2.attitude * 2.0 + k3.attitude * 2.0 + k4.attitude) * sixth;
        RigidBodyState {
            position_m: state.position_m
                + (k1.position + 2.0 * k2.position + 2.0 * k3.position + k4.position) * sixth,
            velocity_m_s: state.velocity_m_s
                + (k1.velocity + 2.0 * k2.velocity + 2.0 * k3.velocity + k4.velocity) * sixth,
            attitude: UnitQuaternion::new_normalize(attitude),
            omega_rad_s: state.omega_rad_s
                + (k1.omega + 2.0 * k2.omega + 2.0 * k3.omega + k4.omega) * sixth,
        }
    }

    /// Angular momentum in the world frame, `R J omega` (kg m^2/s).
    pub fn angular_momentum_world(&self, state: &RigidBodyState) -> Vector3<f64> {
        state.attitude * (self.inertia_kg_m2 * state.omega_rad_s)
    }

    /// Rotational kinetic energy `omega . J omega / 2` (J).
    pub fn rotational_energy_j(&self, state: &RigidBodyState) -> f64 {
        0.5 * state
            .omega_rad_s
            .dot(&(self.inertia_kg_m2 * state.omega_rad_s))
    }
}

/// Total force (world frame, N) and torque about the centre of mass (body frame, N m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wrench {
    pub force_world_n: Vector3<f64>,
    pub torque_body_nm: Vector3<f64>,
}

impl Wrench {
    pub fn zero() -> Self {
        Wrench {
            force_world_n: Vector3::zeros(),
            torque_body_nm: Vector3::zeros(),
        }
    }
}

/// Time derivative of a [`RigidBodyState`]; the attitude part is a raw quaternion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateDerivative {
    pub position: Vector3<f64>,
    pub velocity: Vector3<f64>,
    pub attitude: Quaternion<f64>,
    pub omega: Vector3<f64>,
}

/// `state + h * derivative`, the intermediate states of RK4 (quaternion not renormalised: the
/// derivative is evaluated on the raw 4-vector, which is what makes the scheme RK4).
#[inline]
fn advanced(state: &RigidBodyState, d: &StateDerivative, h: f64) -> RigidBodyState {
    RigidBodyState {
        position_m: state.position_m + d.position * h,
        velocity_m_s: state.velocity_m_s + d.velocity * h,
        attitude: UnitQuaternion::new_unchecked(state.attitude.quaternion() + d.attitude * h),
        omega_rad_s: state.omega_rad_s + d.omega * h,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An asymmetric body (no two principal moments equal, axes not aligned with the body axes).
    fn tumbling_body() -> RigidBody {
        let j = Matrix3::new(
            0.030, 0.002, -0.001, 0.002, 0.045, 0.003, -0.001, 0.003, 0.060,
        );
        RigidBody::new(1.3, j).unwrap()
    }

    fn tumbling_state() -> RigidBodyState {
        RigidBodyState {
            omega_rad_s: Vector3::new(2.0, -1.0, 3.0),
            attitude: UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0),
            ..RigidBodyState::at_rest()
        }
    }

    fn fly(body: &RigidBody, state: RigidBodyState, dt: f64, steps: usize) -> RigidBodyState {
        (0..steps).fold(state, |s, k| {
            body.rk4_step(k as f64 * dt, &s, dt, |_, _| Wrench::zero())
        })
    }

    /// Attitude error angle plus body-rate error, against a reference state.
    fn error(a: &RigidBodyState, b: &RigidBodyState) -> f64 {
        a.attitude.angle_to(&b.attitude) + (a.omega_rad_s - b.omega_rad_s).norm()
    }

    #[test]
    fn rk4_is_fourth_order_on_a_tumbling_body() {
        let body = tumbling_body();
        let t_end = 2.0;
        let reference = fly(&body, tumbling_state(), t_end / 20_000.0, 20_000);
        let errors: Vec<f64> = [100, 200, 400]
            .iter()
            .map(|&n| {
                error(
                    &fly(&body, tumbling_state(), t_end / n as f64, n),
                    &reference,
                )
            })
            .collect();
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            // Fourth order: halving dt divides the error by 2^4 = 16.
            assert!(
                (14.0..18.5).contains(&ratio),
                "errors {errors:?}, ratio {ratio}"
            );
        }
    }

    #[test]
    fn torque_free_body_conserves_momentum_and_energy() {
        let body = tumbling_body();
        let start = tumbling_state();
        let momentum = body.angular_momentum_world(&start);
        let energy = body.rotational_energy_j(&start);
        let mut state = start;
        for k in 0..10_000 {
            state = body.rk4_step(k as f64 * 1e-3, &state, 1e-3, |_, _| Wrench::zero());
            assert!((state.attitude.quaternion().norm() - 1.0).abs() < 1e-14);
        }
        let drift = (body.angular_momentum_world(&state) - momentum).norm() / momentum.norm();
        assert!(drift < 1e-9, "angular momentum drift {drift:e}");
        let drift = (body.rotational_energy_j(&state) - energy).abs() / energy;
        assert!(drift < 1e-9, "energy drift {drift:e}");
    }

    #[test]
    fn free_fall_is_exact() {
        // Constant force: position is a quadratic in t, which RK4 integrates exactly.
        let body = RigidBody::principal(0.72, [0.0056, 0.0056, 0.0104]).unwrap();
        let gravity = Wrench {
            force_world_n: Vector3::new(0.0, 0.0, 0.72 * 9.81),
            torque_body_nm: Vector3::zeros(),
        };
        let start = RigidBodyState {
            velocity_m_s: Vector3::new(1.0, -2.0, -5.0),
            ..RigidBodyState::at_rest()
        };
        let dt = 0.01;
        let end = (0..300).fold(start, |s, k| {
            body.rk4_step(k as f64 * dt, &s, dt, |_, _| gravity)
        });
        let t = 3.0;
        let expected = Vector3::new(1.0 * t, -2.0 * t, -5.0 * t + 0.5 * 9.81 * t * t);
        assert!(
            (end.position_m - expected).norm() < 1e-11,
            "{}",
            end.position_m - expected
        );
        assert!((end.velocity_m_s - Vector3::new(1.0, -2.0, -5.0 + 9.81 * t)).norm() < 1e-12);
        assert_eq!(end.attitude, UnitQuaternion::identity());
    }

    #[test]
    fn constant_torque_about_a_principal_axis_spins_up_quadratically() {
        let body = RigidBody::principal(1.0, [0.01, 0.02, 0.04]).unwrap();
        let torque = Wrench {
            force_world_n: Vector3::zeros(),
            torque_body_nm: Vector3::new(0.0, 0.0, 0.004),
        };
        let dt = 1e-3;
        let end = (0..1000).fold(RigidBodyState::at_rest(), |s, k| {
            body.rk4_step(k as f64 * dt, &s, dt, |_, _| torque)
        });
        // r = (tau / Jz) t = 0.1 rad/s; yaw = (tau / Jz) t^2 / 2 = 0.05 rad at t = 1 s.
        assert!((end.omega_rad_s - Vector3::new(0.0, 0.0, 0.1)).norm() < 1e-12);
        assert!((end.euler_rad()[2] - 0.05).abs() < 1e-12);
        assert!((end.primary_axis() - Vector3::z()).norm() < 1e-12);
    }

    #[test]
    fn bad_mass_properties_are_rejected() {
        assert!(RigidBody::principal(0.0, [1.0; 3])
            .unwrap_err()
            .to_string()
            .starts_with("mass_kg"));
        let err = RigidBody::principal(1.0, [1.0, -1.0, 1.0]).unwrap_err();
        assert!(err.to_string().contains("positive definite"), "{err}");
        let err = RigidBody::new(
            1.0,
            Matrix3::new(1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        )
        .unwrap_err();
        assert!(err.to_string().contains("symmetric"), "{err}");
        let err = RigidBody::principal(1.0, [1.0, f64::NAN, 1.0]).unwrap_err();
        assert!(err.to_string().starts_with("inertia_kg_m2[1, 1]"), "{err}");
    }
}
