//! The vehicle's state, shared by the simulator (`flight`) and the controllers (`control`): a
//! controller sees a state and a time, never the simulator, so the type lives above both rooms.
//!
//! Frames: world NED, body FRD; the attitude rotates body vectors into the world frame. The full
//! state vector used by linear controllers and linearisation is
//! `x = [p (3, world NED, m), v (3, world, m/s), roll, pitch, yaw (rad, Z-Y-X), p, q, r (rad/s)]`;
//! yaw errors are wrapped to (-pi, pi].

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::error::{Result, RfError};

/// Length of the packed state of [`RigidBodyState::from_packed`]: position, velocity, quaternion
/// (w, x, y, z), body rates.
pub const PACKED_DIM: usize = 13;

/// Position and velocity (world NED), attitude (body to world) and body rates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBodyState {
    pub position_m: Vector3<f64>,
    pub velocity_m_s: Vector3<f64>,
    pub attitude: UnitQuaternion<f64>,
    pub omega_rad_s: Vector3<f64>,
}

impl RigidBodyState {
    /// At rest at the origin, level.
    pub fn at_rest() -> Self {
        RigidBodyState {
            position_m: Vector3::zeros(),
            velocity_m_s: Vector3::zeros(),
            attitude: UnitQuaternion::identity(),
            omega_rad_s: Vector3::zeros(),
        }
    }

    /// Roll, pitch, yaw (rad) of the aerospace Z-Y-X sequence.
    pub fn euler_rad(&self) -> [f64; 3] {
        if !self.attitude.coords.iter().all(|v| v.is_finite()) {
            return [f64::NAN; 3];
        }
        let (roll, pitch, yaw) = self.attitude.euler_angles();
        [roll, pitch, yaw]
    }

    /// The primary axis n3 of Ke et al.: body z expressed in the world frame.
    pub fn primary_axis(&self) -> Vector3<f64> {
        self.attitude * Vector3::z()
    }

    /// `true` when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.position_m.iter().all(|v| v.is_finite())
            && self.velocity_m_s.iter().all(|v| v.is_finite())
            && self.attitude.coords.iter().all(|v| v.is_finite())
            && self.omega_rad_s.iter().all(|v| v.is_finite())
    }
}

/// Everything a controller receives at one control step: the measured state (an estimator's
/// output, or the truth) and, where the vehicle has them, raw samples that incremental laws such as
/// INDI need besides the state. The simulator fills the samples only for a controller that asks for
/// them ([`crate::control::Controller::reads_samples`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerInput<'a> {
    /// The measured state.
    pub state: &'a RigidBodyState,
    /// Body rates as the gyroscope samples them, body FRD, rad/s.
    pub gyro_rad_s: Option<Vector3<f64>>,
    /// Specific force as the accelerometer samples it (non-gravitational force per unit mass), body
    /// FRD, m/s^2: about (0, 0, -g) in hover.
    pub specific_force_m_s2: Option<Vector3<f64>>,
    /// Thrust each rotor actually produces (one per rotor, N): what rotor-speed telemetry gives
    /// through the thrust coefficient, after lag, saturation and loss of efficiency.
    pub rotor_thrust_n: Option<&'a [f64]>,
}

impl<'a> ControllerInput<'a> {
    /// The state alone, no raw samples.
    pub fn state_only(state: &'a RigidBodyState) -> Self {
        ControllerInput {
            state,
            gyro_rad_s: None,
            specific_force_m_s2: None,
            rotor_thrust_n: None,
        }
    }
}

impl RigidBodyState {
    /// A state from [`PACKED_DIM`] numbers: position, velocity, quaternion (w, x, y, z), body rates.
    /// A quaternion that is unit to rounding (|q| - 1 <= 1e-12) is used exactly as given, so a
    /// recorded flight replays bit for bit; any other is normalised.
    pub fn from_packed(x: &[f64; PACKED_DIM]) -> Self {
        let q = Quaternion::new(x[6], x[7], x[8], x[9]);
        let attitude = if (q.norm() - 1.0).abs() <= 1e-12 {
            UnitQuaternion::new_unchecked(q)
        } else {
            UnitQuaternion::new_normalize(q)
        };
        RigidBodyState {
            position_m: Vector3::new(x[0], x[1], x[2]),
            velocity_m_s: Vector3::new(x[3], x[4], x[5]),
            attitude,
            omega_rad_s: Vector3::new(x[10], x[11], x[12]),
        }
    }

    /// Row-major packed states (N x [`PACKED_DIM`], e.g. a recorded flight), checked: whole rows,
    /// finite entries and non-zero quaternions, each error naming `field[row, col]`.
    pub fn from_packed_rows(field: &str, rows: &[f64]) -> Result<Vec<Self>> {
        let columns = "position, velocity, quaternion w x y z, rates";
        states_from_rows::<PACKED_DIM>(field, rows, columns, |k, packed| {
            if Quaternion::new(packed[6], packed[7], packed[8], packed[9]).norm() < 1e-6 {
                return Err(RfError::invalid(
                    format!("{field}[{k}]"),
                    "the quaternion (columns 6-9) must not be zero",
                ));
            }
            Ok(Self::from_packed(packed))
        })
    }
}

/// Row-major state vectors (N x [`STATE_DIM`], e.g. a recorded flight's measurements), checked:
/// whole rows and finite entries, each error naming `field[row, col]`. Each row becomes a state by
/// [`state_from_vector`], the conversion the simulator applies to a noisy measurement, so a
/// recorded measurement history replays bit for bit.
pub fn states_from_vector_rows(field: &str, rows: &[f64]) -> Result<Vec<RigidBodyState>> {
    let columns = "position, velocity, roll pitch yaw, rates";
    states_from_rows::<STATE_DIM>(field, rows, columns, |_, x| Ok(state_from_vector(x)))
}

/// Rows of `D` values (`columns` says what they hold): whole rows and finite entries, checked
/// with `field[row, col]` named, then `make(row index, row)`.
fn states_from_rows<const D: usize>(
    field: &str,
    rows: &[f64],
    columns: &str,
    make: impl Fn(usize, &[f64; D]) -> Result<RigidBodyState>,
) -> Result<Vec<RigidBodyState>> {
    if !rows.len().is_multiple_of(D) {
        return Err(RfError::shape(
            field,
            format!("{D} columns ({columns})"),
            format!("{} values", rows.len()),
        ));
    }
    rows.chunks_exact(D)
        .enumerate()
        .map(|(k, row)| {
            if let Some(j) = row.iter().position(|v| !v.is_finite()) {
                return Err(RfError::invalid(
                    format!("{field}[{k}, {j}]"),
                    format!("must be finite, got {}", row[j]),
                ));
            }
            make(k, &std::array::from_fn(|j| row[j]))
        })
        .collect()
}

/// Length of the full state vector of [`state_vector`].
pub const STATE_DIM: usize = 12;

/// `[p, v, roll, pitch, yaw, omega]` of a state (module docs).
pub fn state_vector(state: &RigidBodyState) -> [f64; STATE_DIM] {
    let [roll, pitch, yaw] = state.euler_rad();
    let (p, v, w) = (state.position_m, state.velocity_m_s, state.omega_rad_s);
    [
        p.x, p.y, p.z, v.x, v.y, v.z, roll, pitch, yaw, w.x, w.y, w.z,
    ]
}

/// The state whose [`state_vector`] is `x` (attitude from the Z-Y-X Euler angles).
pub fn state_from_vector(x: &[f64; STATE_DIM]) -> RigidBodyState {
    RigidBodyState {
        position_m: Vector3::new(x[0], x[1], x[2]),
        velocity_m_s: Vector3::new(x[3], x[4], x[5]),
        attitude: UnitQuaternion::from_euler_angles(x[6], x[7], x[8]),
        omega_rad_s: Vector3::new(x[9], x[10], x[11]),
    }
}

/// `x - x_trim` with the yaw difference wrapped to (-pi, pi].
pub fn state_error(x: &[f64; STATE_DIM], trim: &[f64; STATE_DIM]) -> [f64; STATE_DIM] {
    let mut e = [0.0; STATE_DIM];
    for i in 0..STATE_DIM {
        e[i] = x[i] - trim[i];
    }
    e[8] = wrap_angle(e[8]);
    e
}

fn wrap_angle(a: f64) -> f64 {
    let wrapped =
        (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
    if wrapped == -std::f64::consts::PI {
        std::f64::consts::PI
    } else {
        wrapped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_error_is_wrapped() {
        assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-15);
        assert!((wrap_angle(-0.1) + 0.1).abs() < 1e-15);
        let mut x = [0.0; STATE_DIM];
        x[8] = 3.1;
        let mut trim = [0.0; STATE_DIM];
        trim[8] = -3.1;
        assert!((state_error(&x, &trim)[8] - (6.2 - 2.0 * std::f64::consts::PI)).abs() < 1e-12);
    }

    #[test]
    fn packed_state_keeps_a_unit_quaternion_exactly_and_normalises_any_other() {
        let q = UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1).into_inner();
        let packed = [
            1.0, 2.0, 3.0, 0.1, 0.2, 0.3, q.w, q.i, q.j, q.k, 0.4, 0.5, 0.6,
        ];
        let s = RigidBodyState::from_packed(&packed);
        assert_eq!(s.attitude.quaternion(), &q);
        let mut doubled = packed;
        for v in &mut doubled[6..10] {
            *v *= 2.0;
        }
        let t = RigidBodyState::from_packed(&doubled);
        assert!((t.attitude.quaternion().norm() - 1.0).abs() < 1e-15);
        assert!((t.attitude.angle_to(&s.attitude)).abs() < 1e-15);
        assert_eq!(t.omega_rad_s, Vector3::new(0.4, 0.5, 0.6));
    }
}
