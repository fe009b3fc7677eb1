//! The flight model as an ODE in the 12-element state vector: what linearisation for control
//! design differentiates (Euler-angle kinematics on top of the rigid body and vehicle forces).

use nalgebra::Vector3;

use super::actuator::{Actuators, RotorOutput};
use super::vehicle::Vehicle;
use crate::state::{state_from_vector, STATE_DIM};

/// Time derivative of the 12-element state vector (Euler-angle kinematics) for the rotor
/// outputs the actuators give right now: the model that linearisation for control design uses.
pub fn state_vector_derivative(
    vehicle: &Vehicle,
    actuators: &Actuators,
    efficiency: &[f64],
    x: &[f64; STATE_DIM],
    wind_m_s: &Vector3<f64>,
) -> [f64; STATE_DIM] {
    let state = state_from_vector(x);
    let outputs: Vec<RotorOutput> = (0..vehicle.rotor_count())
        .map(|i| actuators.output(i, efficiency[i]))
        .collect();
    let d = vehicle
        .body()
        .derivative(&state, &vehicle.wrench(&state, &outputs, wind_m_s));
    let (roll, pitch) = (x[6], x[7]);
    let (p, q, r) = (x[9], x[10], x[11]);
    let (sr, cr, tp, cp) = (roll.sin(), roll.cos(), pitch.tan(), pitch.cos());
    [
        d.position.x,
        d.position.y,
        d.position.z,
        d.velocity.x,
        d.velocity.y,
        d.velocity.z,
        p + (q * sr + r * cr) * tp,
        q * cr - r * sr,
        (q * sr + r * cr) / cp,
        d.omega.x,
        d.omega.y,
        d.omega.z,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::state_vector;

    #[test]
    fn state_vector_round_trips_and_euler_rates_match_the_quaternion() {
        use crate::flight::actuator::{FixedPitch, Lag};
        use crate::flight::vehicle::Drag;
        let x = [
            1.0, -2.0, -3.0, 0.5, 0.1, -0.2, 0.1, -0.2, 0.7, 0.3, -0.4, 1.1,
        ];
        let back = state_vector(&state_from_vector(&x));
        for i in 0..STATE_DIM {
            assert!((back[i] - x[i]).abs() < 1e-14, "{i}");
        }
        // Euler rates from the kinematics agree with a finite difference of the quaternion flow.
        let airframe = crate::fixtures::preset("quad-x");
        let vehicle = Vehicle::new(&airframe, Drag::default()).unwrap();
        let mut actuators =
            Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap());
        actuators.settle(&[4.0, 3.0, 4.5, 3.5]).unwrap();
        let dx = state_vector_derivative(&vehicle, &actuators, &[1.0; 4], &x, &Vector3::zeros());
        let h = 1e-6;
        let state = state_from_vector(&x);
        let outputs: Vec<RotorOutput> = (0..4).map(|i| actuators.output(i, 1.0)).collect();
        let next = vehicle.body().rk4_step(0.0, &state, h, |_, s| {
            vehicle.wrench(s, &outputs, &Vector3::zeros())
        });
        let prev = vehicle.body().rk4_step(0.0, &state, -h, |_, s| {
            vehicle.wrench(s, &outputs, &Vector3::zeros())
        });
        let (xn, xp) = (state_vector(&next), state_vector(&prev));
        for i in 0..STATE_DIM {
            let numeric = (xn[i] - xp[i]) / (2.0 * h);
            assert!(
                (numeric - dx[i]).abs() < 1e-6 * (1.0 + dx[i].abs()),
                "{i}: {numeric} vs {}",
                dx[i]
            );
        }
    }
}
