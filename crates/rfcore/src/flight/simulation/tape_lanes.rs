//! The truth between integration nodes for a group flown in lanes ([`TapeLanes`]): the scalar
//! [`crate::flight::simulation::tape::Tape`] of every run at once. The runs of a group share
//! their RK4 intervals and their sensors' clocks, so one node per interval start (and the
//! period's end) serves every lane, and a sample time is extended in every lane at once: the
//! module docs of `tape` for the Taylor extension, in the same order of operations lane by lane
//! (checked bit for bit against the scalar tape by the tests).
//!
//! The lanes write every node, as the scalar integrator does for a run flown alone (the per-run
//! tapes of a group whose sensors do not fly in lanes leave out the nodes no sample reads: a
//! sample reads the last node at or before its time, so such a node changes no sample).

use crate::flight::estimation::lanes::math::{
    each, exp_quaternion, lane3, quat_mul, renormalize_fast, V3,
};
use crate::flight::lanes::{BodyLanes, Lanes, TotalsLanes, VehicleLanes};
use crate::flight::sensors::ImuTruth;
use crate::flight::simulation::tape::locate;

/// One node of every lane: the state, the rotor totals, and the dynamics there (the first RK4
/// stage's world acceleration and body angular acceleration).
#[derive(Debug, Clone, Copy)]
struct NodeLanes<L> {
    t_s: f64,
    state: BodyLanes<L>,
    totals: TotalsLanes<L>,
    acceleration: V3<L>,
    angular_acceleration: V3<L>,
}

/// What every lane's IMU measures at one time ([`ImuTruth`] per lane).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ImuTruthLanes<L> {
    omega_rad_s: V3<L>,
    angular_acceleration_rad_s2: V3<L>,
    specific_force_m_s2: V3<L>,
}

impl<L: Lanes> ImuTruthLanes<L> {
    /// Lane `i`'s truth.
    #[inline]
    pub(crate) fn lane(&self, i: usize) -> ImuTruth {
        ImuTruth {
            omega_rad_s: lane3(&self.omega_rad_s, i),
            angular_acceleration_rad_s2: lane3(&self.angular_acceleration_rad_s2, i),
            specific_force_m_s2: lane3(&self.specific_force_m_s2, i),
        }
    }
}

/// One control period's nodes of a group, in time order (module docs).
#[derive(Debug, Clone)]
pub(crate) struct TapeLanes<L> {
    nodes: Vec<NodeLanes<L>>,
    /// Each node's rotor thrusts (`rotors` per node), when recorded.
    thrust_n: Vec<L>,
    rotors: usize,
    /// The node the last lookup found (samples come in time order).
    cursor: usize,
}

impl<L: Lanes> TapeLanes<L> {
    /// A tape that also records `rotors` thrusts per node (0: none).
    pub(crate) fn new(rotors: usize) -> Self {
        TapeLanes {
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

    /// A node at `t_s` (after every node so far): the lanes' `state`, the rotor `totals` there,
    /// the dynamics `k1` there ([`VehicleLanes::derivative`] of `state` under `totals`, the first
    /// RK4 stage) and, when recorded, rotor `r`'s thrust `thrust(r)`.
    #[inline(always)]
    pub(crate) fn push(
        &mut self,
        t_s: f64,
        state: &BodyLanes<L>,
        totals: &TotalsLanes<L>,
        k1: &BodyLanes<L>,
        thrust: impl Fn(usize) -> L,
    ) {
        self.nodes.push(NodeLanes {
            t_s,
            state: *state,
            totals: *totals,
            acceleration: k1.velocity_m_s,
            angular_acceleration: k1.omega_rad_s,
        });
        self.thrust_n.extend((0..self.rotors).map(thrust));
    }

    /// The index of the last node at or before `t_s` (the first node for an earlier time).
    #[inline(always)]
    fn locate(&mut self, t_s: f64) -> usize {
        locate(
            &mut self.cursor,
            self.nodes.len(),
            |i| self.nodes[i].t_s,
            t_s,
        )
    }

    /// Every lane's true state at `t_s` and the node it extends (the scalar `Tape::extend`). The
    /// tape must hold a node.
    #[inline(always)]
    fn extend(&mut self, t_s: f64) -> (BodyLanes<L>, usize) {
        let i = self.locate(t_s);
        let node = &self.nodes[i];
        let tau = t_s - node.t_s;
        let s = &node.state;
        let (a, alpha) = (&node.acceleration, &node.angular_acceleration);
        let (half_tau, tau_l) = (L::splat(0.5 * tau), L::splat(tau));
        let phi: V3<L> = each(|k| (s.omega_rad_s[k] + alpha[k] * half_tau) * tau_l);
        let attitude = renormalize_fast(&quat_mul(&s.attitude, &exp_quaternion(&phi)));
        let state = BodyLanes {
            position_m: each(|k| s.position_m[k] + (s.velocity_m_s[k] + a[k] * half_tau) * tau_l),
            velocity_m_s: each(|k| s.velocity_m_s[k] + a[k] * tau_l),
            attitude,
            omega_rad_s: each(|k| s.omega_rad_s[k] + alpha[k] * tau_l),
        };
        (state, i)
    }

    /// Every lane's true state at `t_s` (for sensors that measure only the state).
    #[inline(always)]
    pub(crate) fn state_at(&mut self, t_s: f64) -> BodyLanes<L> {
        self.extend(t_s).0
    }

    /// What every lane's IMU measures at `t_s` (the scalar `Tape::imu_truth_at`). The tape must
    /// hold a node.
    #[inline(always)]
    pub(crate) fn imu_truth_at(&mut self, model: &VehicleLanes<L>, t_s: f64) -> ImuTruthLanes<L> {
        let (state, i) = self.extend(t_s);
        let node = &self.nodes[i];
        ImuTruthLanes {
            omega_rad_s: state.omega_rad_s,
            angular_acceleration_rad_s2: node.angular_acceleration,
            specific_force_m_s2: model.specific_force(&state, &node.totals),
        }
    }

    /// Lane `lane`'s rotor thrusts at `t_s`, N (held from the last node at or before it).
    pub(crate) fn thrust_at(&mut self, t_s: f64, lane: usize) -> impl Iterator<Item = f64> + '_ {
        let i = self.locate(t_s);
        self.thrust_n[i * self.rotors..(i + 1) * self.rotors]
            .iter()
            .map(move |f| f.lane(lane))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::lanes::F64x4;
    use crate::flight::simulation::tape::Tape;
    use crate::flight::vehicle::{Drag, RotorTotals, Vehicle};
    use crate::state::RigidBodyState;
    use nalgebra::{UnitQuaternion, Vector3};

    #[test]
    fn every_lane_reads_the_scalar_tape_bit_for_bit() {
        // Four tumbling, thrusting, drifting vehicles in wind (one spinning at 500 rad/s, whose
        // rotation over a sample's offset is beyond the exponential's series: the group takes the
        // scalar exponential lane by lane there), two nodes each; samples before, at, between
        // and after the nodes.
        let airframe = crate::fixtures::preset("quad-x");
        let vehicle = Vehicle::new(
            &airframe,
            Drag {
                linear_drag_n_s_m: 0.3,
                rotational_drag_n_m_s: 2e-3,
                ..Drag::default()
            },
        )
        .unwrap();
        let wind = Vector3::new(1.0, -2.0, 0.3);
        let model = VehicleLanes::<F64x4>::new(&vehicle, &wind).unwrap();
        let state = |k: usize, node: usize| RigidBodyState {
            position_m: Vector3::new(1.0 + k as f64, 2.0, -10.0 + node as f64 * 1e-3),
            velocity_m_s: Vector3::new(2.0, -(k as f64), 0.5),
            attitude: UnitQuaternion::from_euler_angles(0.3 * k as f64, -0.2, 1.0 + node as f64),
            omega_rad_s: Vector3::new(3.0, -2.0, [30.0, 0.0, 500.0, -5.0][k]),
        };
        let totals = |k: usize, node: usize| RotorTotals {
            thrust_n: 14.0 + k as f64 + node as f64,
            torque_body_nm: Vector3::new(0.05, -0.08 * k as f64, 0.02),
            spin_rad_s: 0.0,
        };
        let thrust = |k: usize, node: usize, r: usize| 3.0 + 0.1 * (k + 4 * node + 16 * r) as f64;
        let times = [0.0, 6.25e-4];
        let mut lanes = TapeLanes::<F64x4>::new(4);
        let mut scalar: Vec<Tape> = (0..4).map(|_| Tape::new(4)).collect();
        for (node, &t) in times.iter().enumerate() {
            let mut body = BodyLanes::<F64x4>::zeros();
            let mut tl = TotalsLanes {
                thrust_n: F64x4::splat(0.0),
                torque_body_nm: [F64x4::splat(0.0); 3],
            };
            for (k, tape) in scalar.iter_mut().enumerate() {
                let (x, tot) = (state(k, node), totals(k, node));
                body.set(k, &x);
                tl.thrust_n.set_lane(k, tot.thrust_n);
                for c in 0..3 {
                    tl.torque_body_nm[c].set_lane(k, tot.torque_body_nm[c]);
                }
                tape.push(t, &x, &tot, &wind, |r| thrust(k, node, r));
            }
            let k1 = model.derivative(&body, &tl);
            lanes.push(t, &body, &tl, &k1, |r| {
                let mut f = F64x4::splat(0.0);
                for k in 0..4 {
                    f.set_lane(k, thrust(k, node, r));
                }
                f
            });
        }
        let series_limit_rad = crate::flight::estimation::eskf::EXP_SERIES_LIMIT_RAD2.sqrt();
        assert!(500.0 * 4.75e-4 > series_limit_rad && 40.0 * 6.2e-4 < series_limit_rad);
        for t in [-1e-4, 0.0, 1e-4, 6.2e-4, 6.25e-4, 1.1e-3] {
            let imu = lanes.imu_truth_at(&model, t);
            let states = lanes.state_at(t);
            for (k, tape) in scalar.iter_mut().enumerate() {
                let want = tape.imu_truth_at(&vehicle, t);
                let got = imu.lane(k);
                let bits = |v: &Vector3<f64>| v.map(f64::to_bits);
                assert_eq!(bits(&got.omega_rad_s), bits(&want.omega_rad_s), "{t} {k}");
                assert_eq!(
                    bits(&got.angular_acceleration_rad_s2),
                    bits(&want.angular_acceleration_rad_s2)
                );
                assert_eq!(
                    bits(&got.specific_force_m_s2),
                    bits(&want.specific_force_m_s2),
                    "{t} {k}"
                );
                let (a, b) = (states.get(k), tape.state_at(&vehicle, t));
                assert_eq!(bits(&a.position_m), bits(&b.position_m), "{t} {k}");
                assert_eq!(bits(&a.velocity_m_s), bits(&b.velocity_m_s));
                assert_eq!(
                    a.attitude.coords.map(f64::to_bits),
                    b.attitude.coords.map(f64::to_bits),
                    "{t} {k}"
                );
                assert_eq!(bits(&a.omega_rad_s), bits(&b.omega_rad_s));
                let thrusts: Vec<u64> = lanes.thrust_at(t, k).map(f64::to_bits).collect();
                let want: Vec<u64> = tape.thrust_at(t).iter().map(|f| f.to_bits()).collect();
                assert_eq!(thrusts, want);
            }
        }
    }
}
