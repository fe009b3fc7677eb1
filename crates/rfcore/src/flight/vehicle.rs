//! Forces and torques on a multirotor: rotor thrust and reaction torque, gravity, translational
//! drag (linear, Stokes as in Lanzon et al., plus optional quadratic), rotational drag, the
//! propeller gyroscopic moment (Lanzon et al. eq. (5)) and wind.
//!
//! Frames as in [`crate::flight::rigid_body`]: world NED, body FRD. Rotor i sits at
//! `(r_i cos phi_i, r_i sin phi_i, 0)` in the body frame and pushes along body -z, which gives the
//! roll and pitch torques of Du et al. eq. (5). Drag acts on the air-relative velocity
//! `v - wind(t)`.

use nalgebra::Vector3;

use crate::airframe::Airframe;
use crate::error::{require_non_negative, Result, RfError};
use crate::flight::actuator::RotorOutput;
use crate::flight::rigid_body::{RigidBody, Wrench};
use crate::state::RigidBodyState;

/// Aerodynamic and rotor-inertia parameters the papers leave to the user (Lanzon Table 1 gives
/// none of them; see the README's decisions). All default to zero.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Drag {
    /// `k_t`: force `-k_t (v - wind)`, N s/m.
    pub linear_drag_n_s_m: f64,
    /// Force `-c |v - wind| (v - wind)`, N s^2/m^2.
    pub quadratic_drag_n_s2_m2: f64,
    /// `k_r`: torque `-k_r omega`, N m s (sets a spinning vehicle's yaw rate).
    pub rotational_drag_n_m_s: f64,
    /// `I_R`: rotor and propeller inertia about its axis, kg m^2 (gyroscopic moment).
    pub rotor_inertia_kg_m2: f64,
}

impl Drag {
    pub fn check(&self) -> Result<()> {
        for (field, value) in [
            ("drag.linear_n_s_m", self.linear_drag_n_s_m),
            ("drag.quadratic_n_s2_m2", self.quadratic_drag_n_s2_m2),
            ("drag.rotational_n_m_s", self.rotational_drag_n_m_s),
            ("drag.rotor_inertia_kg_m2", self.rotor_inertia_kg_m2),
        ] {
            require_non_negative(field, value)?;
        }
        Ok(())
    }
}

/// The rigid body, rotor positions and aerodynamics of one airframe.
#[derive(Debug, Clone, PartialEq)]
pub struct Vehicle {
    body: RigidBody,
    /// Body-frame (x, y) of each rotor, m.
    rotor_xy_m: Vec<(f64, f64)>,
    aero: Drag,
    gravity_m_s2: f64,
}

impl Vehicle {
    pub fn new(airframe: &Airframe, aero: Drag) -> Result<Self> {
        aero.check()?;
        // The rotor model pushes along body -z; a tilted rotor would need lateral forces here.
        if let Some(i) = airframe
            .rotors()
            .iter()
            .position(|r| !r.placement.is_vertical())
        {
            return Err(RfError::invalid(
                format!("thrust_axis[{i}] (rotor {})", i + 1),
                "the simulator models upright rotors only (thrust axis [0, 0, -1]); \
                 tilted rotors are analysed (acai, failure tables, allocation) but not flown",
            ));
        }
        Ok(Vehicle {
            body: RigidBody::principal(airframe.mass_kg(), airframe.inertia_kg_m2())?,
            rotor_xy_m: airframe
                .rotors()
                .iter()
                .map(|r| {
                    let [x, y, _] = r.placement.position_m();
                    (x, y)
                })
                .collect(),
            aero,
            gravity_m_s2: airframe.gravity_m_s2(),
        })
    }

    pub fn body(&self) -> &RigidBody {
        &self.body
    }

    /// The drag and rotor-inertia terms of the wrench.
    pub(crate) fn aero(&self) -> &Drag {
        &self.aero
    }

    /// Gravity, m/s^2 (the weight is `mass * gravity` along world +z).
    pub(crate) fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }

    /// Replaces the body (tests of a full inertia tensor; airframes give principal ones).
    #[cfg(test)]
    pub(crate) fn set_body_for_tests(&mut self, body: RigidBody) {
        self.body = body;
    }

    pub fn rotor_count(&self) -> usize {
        self.rotor_xy_m.len()
    }

    /// Total force (world) and torque (body) for the current rotor outputs and wind (world, m/s).
    pub fn wrench(
        &self,
        state: &RigidBodyState,
        rotors: &[RotorOutput],
        wind_m_s: &Vector3<f64>,
    ) -> Wrench {
        self.wrench_from(state, &self.rotor_totals(rotors), wind_m_s)
    }

    /// Sums the rotors' contributions once; they are held through a substep while RK4 evaluates
    /// the wrench four times (see [`Vehicle::wrench_from`]).
    #[inline]
    pub fn rotor_totals(&self, rotors: &[RotorOutput]) -> RotorTotals {
        self.rotor_totals_from(rotors.iter().copied())
    }

    /// [`Vehicle::rotor_totals`] of rotor outputs as they are computed (rotor 1 first), without
    /// storing them.
    #[inline]
    pub fn rotor_totals_from(&self, rotors: impl Iterator<Item = RotorOutput>) -> RotorTotals {
        let mut totals = RotorTotals::default();
        for (out, &xy) in rotors.zip(&self.rotor_xy_m) {
            totals.add(xy, &out);
        }
        totals
    }

    /// Body-frame (x, y) of each rotor, m.
    pub fn rotor_xy_m(&self) -> &[(f64, f64)] {
        &self.rotor_xy_m
    }

    /// The wrench for summed rotor contributions; the state-dependent terms are evaluated here.
    #[inline]
    pub fn wrench_from(
        &self,
        state: &RigidBodyState,
        rotors: &RotorTotals,
        wind_m_s: &Vector3<f64>,
    ) -> Wrench {
        let omega = state.omega_rad_s;
        let a = &self.aero;
        let mut torque = rotors.torque_body_nm - a.rotational_drag_n_m_s * omega;
        if a.rotor_inertia_kg_m2 != 0.0 {
            // Rotors carry angular momentum I_R sum(spin) e3 (body); the body feels -omega x h.
            torque -= omega.cross(&Vector3::new(
                0.0,
                0.0,
                a.rotor_inertia_kg_m2 * rotors.spin_rad_s,
            ));
        }
        Wrench {
            force_world_n: self.force_world_n(state, rotors, wind_m_s),
            torque_body_nm: torque,
        }
    }

    /// The force of [`Vehicle::wrench_from`], world NED, N: weight, drag and rotor thrust.
    #[inline]
    pub fn force_world_n(
        &self,
        state: &RigidBodyState,
        rotors: &RotorTotals,
        wind_m_s: &Vector3<f64>,
    ) -> Vector3<f64> {
        let a = &self.aero;
        let air = state.velocity_m_s - wind_m_s;
        let mut drag_coefficient = a.linear_drag_n_s_m;
        if a.quadratic_drag_n_s2_m2 != 0.0 {
            drag_coefficient += a.quadratic_drag_n_s2_m2 * air.norm();
        }
        let weight = Vector3::new(0.0, 0.0, self.body.mass_kg() * self.gravity_m_s2);
        weight - drag_coefficient * air + state.attitude * Vector3::new(0.0, 0.0, -rotors.thrust_n)
    }
}

impl Vehicle {
    /// What an accelerometer at the centre of mass measures, body FRD, m/s^2: every force but
    /// gravity (rotor thrust, drag) per unit mass; about (0, 0, -g) in hover.
    pub fn specific_force(
        &self,
        state: &RigidBodyState,
        rotors: &RotorTotals,
        wind_m_s: &Vector3<f64>,
    ) -> Vector3<f64> {
        let mass = self.body.mass_kg();
        let force = self.force_world_n(state, rotors, wind_m_s);
        let weight = Vector3::new(0.0, 0.0, mass * self.gravity_m_s2);
        state.attitude.inverse() * ((force - weight) / mass)
    }
}

/// The rotors' summed contribution: total thrust (N, along body -z), torque about the centre of
/// mass (body, N m) and net spin along body z (rad/s, for the gyroscopic moment).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RotorTotals {
    pub thrust_n: f64,
    pub torque_body_nm: Vector3<f64>,
    pub spin_rad_s: f64,
}

impl RotorTotals {
    /// Adds the output of a rotor at body-frame `(x, y)`.
    #[inline(always)]
    pub fn add(&mut self, (x, y): (f64, f64), out: &RotorOutput) {
        self.thrust_n += out.thrust_n;
        // r x F with F = (0, 0, -f): (-y f, x f, 0).
        self.torque_body_nm.x -= y * out.thrust_n;
        self.torque_body_nm.y += x * out.thrust_n;
        self.torque_body_nm.z += out.reaction_torque_nm;
        self.spin_rad_s += out.spin_rad_s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn lanzon() -> Airframe {
        crate::fixtures::preset("lanzon-quadrotor")
    }

    fn thrusts(f: [f64; 4], k_mu: f64, w: [f64; 4]) -> Vec<RotorOutput> {
        (0..4)
            .map(|i| RotorOutput {
                thrust_n: f[i],
                reaction_torque_nm: w[i] * k_mu * f[i],
                spin_rad_s: 0.0,
            })
            .collect()
    }

    #[test]
    fn torques_match_the_effectiveness_matrix() {
        let airframe = lanzon();
        let vehicle = Vehicle::new(&airframe, Drag::default()).unwrap();
        let f = [1.0, 2.0, 3.0, 4.5];
        let w = [-1.0, 1.0, -1.0, 1.0];
        let wrench = vehicle.wrench(
            &RigidBodyState::at_rest(),
            &thrusts(f, 2.4e-3, w),
            &Vector3::zeros(),
        );
        let b = airframe.effectiveness_matrix();
        let expected = &b * nalgebra::DVector::from_column_slice(&f);
        assert!((wrench.torque_body_nm.x - expected[1]).abs() < 1e-15);
        assert!((wrench.torque_body_nm.y - expected[2]).abs() < 1e-15);
        assert!((wrench.torque_body_nm.z - expected[3]).abs() < 1e-15);
        // Level: thrust up (-z), weight down (+z).
        assert!((wrench.force_world_n.z - (0.5 * 9.81 - expected[0])).abs() < 1e-13);
    }

    #[test]
    fn thrust_turns_with_the_body_and_drag_opposes_air_velocity() {
        let airframe = lanzon();
        let aero = Drag {
            linear_drag_n_s_m: 0.1,
            quadratic_drag_n_s2_m2: 0.05,
            rotational_drag_n_m_s: 0.01,
            ..Drag::default()
        };
        let vehicle = Vehicle::new(&airframe, aero).unwrap();
        let state = RigidBodyState {
            velocity_m_s: Vector3::new(3.0, 0.0, 0.0),
            attitude: UnitQuaternion::from_euler_angles(0.0, 0.3, 0.0),
            omega_rad_s: Vector3::new(0.0, 0.0, 2.0),
            ..RigidBodyState::at_rest()
        };
        let wind = Vector3::new(1.0, 0.0, 0.0);
        let wrench = vehicle.wrench(&state, &thrusts([1.0; 4], 0.0, [0.0; 4]), &wind);
        // Nose up 0.3 rad: the 4 N of thrust lean backwards, (-4 sin 0.3, 0, -4 cos 0.3) in NED.
        let thrust_world = state.attitude * Vector3::new(0.0, 0.0, -4.0);
        let air = 2.0; // 3 m/s ground speed against 1 m/s tailwind
        let drag_x = -(0.1 + 0.05 * air) * air;
        let expected = thrust_world + Vector3::new(drag_x, 0.0, 0.5 * 9.81);
        assert!((wrench.force_world_n - expected).norm() < 1e-14);
        assert!(
            thrust_world.x < 0.0,
            "nose-up pitch tilts thrust backwards in NED"
        );
        assert!((wrench.torque_body_nm.z + 0.02).abs() < 1e-15);
    }

    #[test]
    fn gyroscopic_moment_follows_lanzon_eq5() {
        let airframe = lanzon();
        let aero = Drag {
            rotor_inertia_kg_m2: 3e-5,
            ..Drag::default()
        };
        let vehicle = Vehicle::new(&airframe, aero).unwrap();
        let spins = [400.0, -380.0, 410.0, -390.0];
        let rotors: Vec<RotorOutput> = spins
            .iter()
            .map(|&s| RotorOutput {
                spin_rad_s: s,
                ..RotorOutput::default()
            })
            .collect();
        let omega = Vector3::new(0.5, -0.2, 3.0);
        let state = RigidBodyState {
            omega_rad_s: omega,
            ..RigidBodyState::at_rest()
        };
        let wrench = vehicle.wrench(&state, &rotors, &Vector3::zeros());
        // Lanzon eq. (5), in his z-up body frame (x forward, y left): m_g = I_R (Omega x e3)
        // (w1 + w3 - w2 - w4) with speed magnitudes w_i (M1, M3 clockwise, spinning +z in FRD).
        let omega_up = Vector3::new(omega.x, -omega.y, -omega.z);
        let magnitudes = spins.map(f64::abs);
        let m_g = 3e-5
            * omega_up.cross(&Vector3::z())
            * (magnitudes[0] + magnitudes[2] - magnitudes[1] - magnitudes[3]);
        let expected = Vector3::new(m_g.x, -m_g.y, -m_g.z); // back to FRD
        assert!((wrench.torque_body_nm - expected).norm() < 1e-15);
        assert_eq!(wrench.torque_body_nm.z, 0.0);
    }

    #[test]
    fn negative_coefficients_are_rejected() {
        let aero = Drag {
            rotational_drag_n_m_s: -1.0,
            ..Drag::default()
        };
        let err = Vehicle::new(&lanzon(), aero).unwrap_err();
        assert!(
            err.to_string().starts_with("drag.rotational_n_m_s"),
            "{err}"
        );
    }
}
