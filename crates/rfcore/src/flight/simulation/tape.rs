//! The truth between integration nodes, for sensors on their own clocks: one control period's
//! RK4 interval starts (and its end), each with the rotors' totals the integrator used there, so
//! that a sensor sampling at any time gets the true state, body rate, angular acceleration and
//! specific force at that time, not the latest grid state.
//!
//! From the last node `n` at or before `t` (`tau = t - t_n`, at most one RK4 substep, 0.625 ms at
//! 400 Hz with 4 substeps), with `a`, `alpha` the world acceleration and body angular
//! acceleration of the dynamics at `n` (Taylor extension):
//!
//! ```text
//! p = p_n + v_n tau + a tau^2 / 2      v = v_n + a tau
//! q = q_n Exp(w_n tau + alpha tau^2 / 2)    w = w_n + alpha tau
//! f = specific force of the vehicle at (p, v, q, w) with the node's rotor totals
//! ```
//!
//! Errors are third order in `tau` (position: jerk tau^3 / 6 = 2e-8 m for 400 m/s^3, the jerk of
//! a 10 m/s^2 thrust turning at 40 rad/s) except the rotors' own change within `tau` (actuator
//! lag), which the node's totals hold: at most `tau / time_constant` of a step change (2.5 % for
//! Ke's 25 ms lag). Rotor thrusts (for the rotor-speed sensor) are held from the node.
//!
//! The dynamics at a node are those of the integrator's first RK4 stage there: the scalar
//! integrator hands its wrench over ([`Tape::share_wrench`]) and the batch lanes the stage itself
//! ([`Tape::share_rates`]) instead of the tape evaluating them again.

use nalgebra::Vector3;

use crate::flight::estimation::eskf::exp_quaternion;
use crate::flight::rigid_body::Wrench;
use crate::flight::sensors::ImuTruth;
use crate::flight::vehicle::{RotorTotals, Vehicle};
use crate::state::RigidBodyState;

/// The dynamics at a node, computed when a sample first falls after it.
#[derive(Debug, Clone, Copy)]
struct Rates {
    acceleration: Vector3<f64>,
    angular_acceleration: Vector3<f64>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    t_s: f64,
    state: RigidBodyState,
    totals: RotorTotals,
    wind: Vector3<f64>,
    /// The wrench at the node, when the integrator shared it.
    wrench: Option<Wrench>,
    rates: Option<Rates>,
}

/// One control period's nodes, in time order (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Tape {
    nodes: Vec<Node>,
    /// Each node's rotor thrusts (`rotors` per node), when recorded.
    thrust_n: Vec<f64>,
    rotors: usize,
    /// The node the last lookup found (samples come in time order).
    cursor: usize,
}

impl Tape {
    /// A tape that also records `rotors` thrusts per node (0: none).
    pub(crate) fn new(rotors: usize) -> Self {
        Tape {
            nodes: Vec::with_capacity(16),
            thrust_n: Vec::with_capacity(16 * rotors),
            rotors,
            cursor: 0,
        }
    }

    pub(crate) fn clear(&mut self) {
        self.nodes.clear();
        self.thrust_n.clear();
        self.cursor = 0;
    }

    /// A node at `t_s` (after every node so far): the state, the rotor totals and wind the
    /// dynamics have there, and (when recorded) the rotor thrusts `thrust(i)`.
    pub(crate) fn push(
        &mut self,
        t_s: f64,
        state: &RigidBodyState,
        totals: &RotorTotals,
        wind: &Vector3<f64>,
        thrust: impl Fn(usize) -> f64,
    ) {
        self.nodes.push(Node {
            t_s,
            state: *state,
            totals: *totals,
            wind: *wind,
            wrench: None,
            rates: None,
        });
        self.thrust_n.extend((0..self.rotors).map(thrust));
    }

    /// The wrench of the newest node (`vehicle.wrench_from` at its state, totals and wind), as
    /// the integrator evaluated it for its first RK4 stage.
    pub(crate) fn share_wrench(&mut self, wrench: Wrench) {
        if let Some(node) = self.nodes.last_mut() {
            node.wrench = Some(wrench);
        }
    }

    /// The dynamics at the newest node, world acceleration and body angular acceleration, as
    /// the integrator evaluated them for its first RK4 stage (the lanes' first stage: the same
    /// function of the same inputs as the tape's own `derivative` of `wrench_from`).
    pub(crate) fn share_rates(
        &mut self,
        acceleration: Vector3<f64>,
        angular_acceleration: Vector3<f64>,
    ) {
        if let Some(node) = self.nodes.last_mut() {
            node.rates = Some(Rates {
                acceleration,
                angular_acceleration,
            });
        }
    }

    /// The index of the last node at or before `t_s` (the first node for an earlier time).
    fn locate(&mut self, t_s: f64) -> usize {
        locate(
            &mut self.cursor,
            self.nodes.len(),
            |i| self.nodes[i].t_s,
            t_s,
        )
    }

    /// The true state at `t_s` (module docs) and the node it extends. The tape must hold a node.
    fn extend(&mut self, vehicle: &Vehicle, t_s: f64) -> (RigidBodyState, Vector3<f64>, usize) {
        let i = self.locate(t_s);
        let node = &mut self.nodes[i];
        let rates = *node.rates.get_or_insert_with(|| {
            let wrench = node
                .wrench
                .unwrap_or_else(|| vehicle.wrench_from(&node.state, &node.totals, &node.wind));
            let d = vehicle.body().derivative(&node.state, &wrench);
            Rates {
                acceleration: d.velocity,
                angular_acceleration: d.omega,
            }
        });
        let tau = t_s - node.t_s;
        let s = &node.state;
        let (a, alpha) = (rates.acceleration, rates.angular_acceleration);
        let mut attitude =
            s.attitude * exp_quaternion(&((s.omega_rad_s + alpha * (0.5 * tau)) * tau));
        attitude.renormalize_fast();
        let state = RigidBodyState {
            position_m: s.position_m + (s.velocity_m_s + a * (0.5 * tau)) * tau,
            velocity_m_s: s.velocity_m_s + a * tau,
            attitude,
            omega_rad_s: s.omega_rad_s + alpha * tau,
        };
        (state, alpha, i)
    }

    /// The true state at `t_s` (for sensors that measure only the state).
    pub(crate) fn state_at(&mut self, vehicle: &Vehicle, t_s: f64) -> RigidBodyState {
        self.extend(vehicle, t_s).0
    }

    /// What an IMU measures at `t_s` (module docs). The tape must hold a node.
    pub(crate) fn imu_truth_at(&mut self, vehicle: &Vehicle, t_s: f64) -> ImuTruth {
        let (state, alpha, i) = self.extend(vehicle, t_s);
        let node = &self.nodes[i];
        ImuTruth {
            omega_rad_s: state.omega_rad_s,
            angular_acceleration_rad_s2: alpha,
            specific_force_m_s2: vehicle.specific_force(&state, &node.totals, &node.wind),
        }
    }

    /// The rotor thrusts at `t_s`, N (held from the last node at or before it).
    pub(crate) fn thrust_at(&mut self, t_s: f64) -> &[f64] {
        let i = self.locate(t_s);
        &self.thrust_n[i * self.rotors..(i + 1) * self.rotors]
    }
}

/// The index of the last of `len` nodes (times `time_of(i)`, increasing) at or before `t_s` (the
/// first node for an earlier time), searched from `cursor` on, which it leaves there: a tape's
/// samples come in time order.
#[inline(always)]
pub(super) fn locate(
    cursor: &mut usize,
    len: usize,
    time_of: impl Fn(usize) -> f64,
    t_s: f64,
) -> usize {
    if *cursor >= len || time_of(*cursor) > t_s {
        *cursor = 0;
    }
    while *cursor + 1 < len && time_of(*cursor + 1) <= t_s {
        *cursor += 1;
    }
    *cursor
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::vehicle::Drag;
    use nalgebra::UnitQuaternion;

    #[test]
    fn the_extension_matches_a_fine_integration_to_third_order() {
        // A tumbling, thrusting quadrotor: the truth 0.6 ms after a node against RK4 with
        // 1 us steps from the node; halving tau divides the error by about 8.
        let airframe = crate::fixtures::preset("quad-x");
        let vehicle = Vehicle::new(
            &airframe,
            Drag {
                linear_drag_n_s_m: 0.3,
                ..Drag::default()
            },
        )
        .unwrap();
        let totals = RotorTotals {
            thrust_n: 14.0,
            torque_body_nm: Vector3::new(0.05, -0.08, 0.02),
            spin_rad_s: 0.0,
        };
        let wind = Vector3::new(1.0, -2.0, 0.0);
        let start = RigidBodyState {
            position_m: Vector3::new(1.0, 2.0, -10.0),
            velocity_m_s: Vector3::new(2.0, -1.0, 0.5),
            attitude: UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0),
            omega_rad_s: Vector3::new(3.0, -2.0, 30.0),
        };
        let error = |tau: f64| {
            let mut tape = Tape::new(0);
            tape.push(0.0, &start, &totals, &wind, |_| 0.0);
            let ours = tape.state_at(&vehicle, tau);
            let ours_imu = tape.imu_truth_at(&vehicle, tau);
            let mut x = start;
            let n = 1000;
            for _ in 0..n {
                x = vehicle.body().rk4_step(0.0, &x, tau / n as f64, |_, s| {
                    vehicle.wrench_from(s, &totals, &wind)
                });
            }
            let f = vehicle.specific_force(&x, &totals, &wind);
            [
                (ours.position_m - x.position_m).norm(),
                (ours.velocity_m_s - x.velocity_m_s).norm(),
                ours.attitude.angle_to(&x.attitude),
                (ours.omega_rad_s - x.omega_rad_s).norm(),
                (ours_imu.specific_force_m_s2 - f).norm(),
            ]
        };
        let (big, small) = (error(6e-4), error(3e-4));
        for k in 0..5 {
            // Position and attitude errors are third order (ratio 8), velocity, rate and the
            // specific force second order (ratio 4).
            let order_ratio = if k == 0 || k == 2 { 7.0 } else { 3.5 };
            assert!(big[k] / small[k] > order_ratio, "{k}: {big:?} {small:?}");
        }
        // The module docs' bound: position within jerk tau^3 / 6 for a jerk of 400 m/s^3
        // (1.4e-8 m at 0.6 ms; this tumble's jerk is lower).
        let position_bound_m = 400.0 * 6e-4f64.powi(3) / 6.0;
        assert!(
            big[0] < position_bound_m && big[2] < 1e-7 && big[4] < 1e-3,
            "{big:?}"
        );
    }
}
