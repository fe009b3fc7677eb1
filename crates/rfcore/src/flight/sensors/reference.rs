//! Analytic reference motions: the true state and the true IMU input (body rate, angular
//! acceleration, specific force) at any time, in closed form, so sensors and estimators can be
//! scored against an exact truth instead of a second integrator.
//!
//! [`AnalyticMotion`]: the body turns at a constant body-axis rate `omega` while its centre of
//! mass moves on per-axis sinusoids about a centre plus a uniform circle about the spin axis,
//!
//! ```text
//! q(t) = q0 Exp(omega t)                   exact for a constant body rate
//! w    = R(q0) omega                       the spin in world axes (constant: R(t) omega = w)
//! a(t) = -A Omega^2 sin(Omega t) + Exp(w t) h          h perpendicular to w
//! v(t) =  A Omega cos(Omega t) - w x Exp(w t) h / |w|^2
//! p(t) =  c + A sin(Omega t)   - Exp(w t) h / |w|^2
//! f_body(t) = R(t)^T (a(t) - g)            the accelerometer's specific force
//! ```
//!
//! Hover (`A = 0`, `omega = 0`, `h = 0`), a translational oscillation at fixed attitude (the
//! linear case of Kalman-filter consistency tests) and the spinning hover of a multirotor that
//! has lost a rotor ([`AnalyticMotion::spin`]) are special cases. The motion is kinematic:
//! whatever force and torque it needs is assumed supplied.

use nalgebra::{UnitQuaternion, Vector3};

use crate::flight::sensors::ImuTruth;
use crate::state::RigidBodyState;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticMotion {
    pub centre_m: Vector3<f64>,
    pub amplitude_m: Vector3<f64>,
    pub angular_frequency_rad_s: f64,
    pub initial_attitude: UnitQuaternion<f64>,
    /// Constant body-axis rate, rad/s.
    pub body_rate_rad_s: Vector3<f64>,
    /// `h`: the centripetal acceleration of the circle about the spin axis at t = 0, world,
    /// m/s^2 (perpendicular to the spin; zero for no circle).
    pub circle_acceleration_m_s2: Vector3<f64>,
    pub gravity_m_s2: f64,
}

impl AnalyticMotion {
    /// At rest, level, 1 m above the origin (NED z = -1).
    pub fn hover() -> Self {
        AnalyticMotion {
            centre_m: Vector3::new(0.0, 0.0, -1.0),
            amplitude_m: Vector3::zeros(),
            angular_frequency_rad_s: 0.0,
            initial_attitude: UnitQuaternion::identity(),
            body_rate_rad_s: Vector3::zeros(),
            circle_acceleration_m_s2: Vector3::zeros(),
            gravity_m_s2: crate::airframe::DEFAULT_GRAVITY_M_S2,
        }
    }

    /// The spinning hover of a multirotor (Mueller and D'Andrea's relaxed hover after a rotor
    /// loss): a steady spin at `rate_rad_s` about a body axis tilted `tilt_rad` from body z
    /// towards body x, that axis vertical in the world, and the thrust along body z balancing
    /// gravity: the specific force is constant in body axes, `-g / cos(tilt)` along z, and its
    /// horizontal part `g tan(tilt)` carries the centre of mass round a circle of radius
    /// `g tan(tilt) / rate^2` (2.9 mm at 30 rad/s and 15 deg).
    pub fn spin(rate_rad_s: f64, tilt_rad: f64) -> Self {
        let g = crate::airframe::DEFAULT_GRAVITY_M_S2;
        AnalyticMotion {
            // Pitch by -tilt takes the body spin axis (sin, 0, cos) to world z.
            initial_attitude: UnitQuaternion::from_euler_angles(0.0, -tilt_rad, 0.0),
            body_rate_rad_s: Vector3::new(tilt_rad.sin(), 0.0, tilt_rad.cos()) * rate_rad_s,
            circle_acceleration_m_s2: Vector3::new(g * tilt_rad.tan(), 0.0, 0.0),
            ..AnalyticMotion::hover()
        }
    }

    pub fn attitude_at(&self, t_s: f64) -> UnitQuaternion<f64> {
        self.initial_attitude * UnitQuaternion::from_scaled_axis(self.body_rate_rad_s * t_s)
    }

    /// The spin in world axes, `R(q0) omega`, rad/s.
    fn world_spin(&self) -> Vector3<f64> {
        self.initial_attitude * self.body_rate_rad_s
    }

    /// `Exp(w t) h` and `|w|^2` (the circle's acceleration now).
    fn circle(&self, t_s: f64) -> (Vector3<f64>, f64) {
        let w = self.world_spin();
        let turned = UnitQuaternion::from_scaled_axis(w * t_s) * self.circle_acceleration_m_s2;
        (turned, w.norm_squared())
    }

    fn acceleration_at(&self, t_s: f64) -> Vector3<f64> {
        let w = self.angular_frequency_rad_s;
        -self.amplitude_m * (w * w * (w * t_s).sin()) + self.circle(t_s).0
    }

    pub fn state_at(&self, t_s: f64) -> RigidBodyState {
        let w = self.angular_frequency_rad_s;
        let (turned, spin2) = self.circle(t_s);
        let (mut position_m, mut velocity_m_s) = (
            self.centre_m + self.amplitude_m * (w * t_s).sin(),
            self.amplitude_m * (w * (w * t_s).cos()),
        );
        if spin2 > 0.0 {
            position_m -= turned / spin2;
            velocity_m_s -= self.world_spin().cross(&turned) / spin2;
        }
        RigidBodyState {
            position_m,
            velocity_m_s,
            attitude: self.attitude_at(t_s),
            omega_rad_s: self.body_rate_rad_s,
        }
    }

    pub fn imu_truth_at(&self, t_s: f64) -> ImuTruth {
        let gravity = Vector3::new(0.0, 0.0, self.gravity_m_s2);
        let specific_force_world = self.acceleration_at(t_s) - gravity;
        ImuTruth {
            omega_rad_s: self.body_rate_rad_s,
            angular_acceleration_rad_s2: Vector3::zeros(),
            specific_force_m_s2: self
                .attitude_at(t_s)
                .inverse_transform_vector(&specific_force_world),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closed_form_is_consistent() {
        // Velocity and acceleration against central differences of the position; the attitude's
        // rate against the quaternion's difference (independent of the closed form's derivation).
        let mut m = AnalyticMotion::spin(30.0, 0.3);
        m.circle_acceleration_m_s2.x *= 100.0;
        m.amplitude_m = Vector3::new(0.5, -0.2, 0.1);
        m.angular_frequency_rad_s = 1.3;
        let (t, h) = (0.77, 1e-6);
        let (a, b) = (m.state_at(t - h), m.state_at(t + h));
        let v = (b.position_m - a.position_m) / (2.0 * h);
        assert!((v - m.state_at(t).velocity_m_s).norm() < 1e-7);
        let acc = (b.velocity_m_s - a.velocity_m_s) / (2.0 * h);
        assert!((acc - m.acceleration_at(t)).norm() < 1e-6);
        let dq = a.attitude.inverse() * b.attitude;
        assert!((dq.scaled_axis() / (2.0 * h) - m.body_rate_rad_s).norm() < 1e-6);
        // The spinning hover: the specific force is constant in body axes, along -z.
        let spin = AnalyticMotion::spin(30.0, 15f64.to_radians());
        for t in [0.0, 0.37, 2.9] {
            let f = spin.imu_truth_at(t).specific_force_m_s2;
            let expected = -crate::airframe::DEFAULT_GRAVITY_M_S2 / 15f64.to_radians().cos();
            assert!((f - Vector3::new(0.0, 0.0, expected)).norm() < 1e-12, "{f}");
        }
        // At rest the accelerometer reads -g along body z (FRD, upward reaction).
        let f = AnalyticMotion::hover()
            .imu_truth_at(3.0)
            .specific_force_m_s2;
        assert!(
            (f - Vector3::new(0.0, 0.0, -crate::airframe::DEFAULT_GRAVITY_M_S2)).norm() < 1e-15
        );
    }
}
