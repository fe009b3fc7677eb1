//! State estimation from the sensors of [`crate::flight::sensors`]: an error-state Kalman filter
//! (ESKF; Sola, "Quaternion kinematics for the error-state Kalman filter", 2017) on a delayed
//! fusion horizon, with an output predictor at the newest IMU sample (the architecture of PX4's
//! EKF2 and ArduPilot's EKF3). It depends on `state` and the sensor types only, never on
//! `control`: a controller receives its [`Estimate`], not the estimator.
//!
//! # State and propagation
//! Nominal state `x = (p, v, q, b_g, b_a)` (world NED position and velocity, body-to-world
//! attitude, gyro and accelerometer biases); error state `dx = (dp, dv, dtheta, db_g, db_a)`
//! with the attitude error on the right, `q_true = q Exp(dtheta)`. Between IMU samples `a`, `b`
//! the inputs are linearly interpolated, bias-corrected and moved to the centre of mass,
//! `w(t) = w_m(t) - b_g`, `f(t) = f_m(t) - b_a - w x (w x r_imu)`, and over `[t0, t1]`:
//!
//! ```text
//! q1 = q0 Exp(w(t_mid) dt)                         exact for a constant rate: right at 30 rad/s
//! a_i = R(q_i) f(t_i) + g                          world-frame acceleration at both ends
//! v1 = v0 + (a_0 + a_1) dt / 2
//! p1 = p0 + v0 dt + (a_0 / 3 + a_1 / 6) dt^2       (exact when a is linear over the step)
//! P1 = F P0 F^T + Q
//! ```
//!
//! with F of `eskf::propagate_covariance` (`A = -R [f]x dt`, `C = -R dt`,
//! `Phi = Exp(w dt)^T`, `D = -J_r(w dt) dt`) and Q the continuous white noises integrated over
//! the step: `N_g^2 dt` on the attitude, `N_a^2 (dt^3/3, dt^2/2, dt)` on position and velocity,
//! and on the biases `(B^2 + 2 sigma_sf^2(u - u_mean) / tau) dt`, where `sigma_sf^2(d)_i =
//! s^2 d_i^2 + c^2 (|d|^2 - d_i^2)` is the variance of the scale (`s`) and cross-axis (`c`)
//! error of the part of the input that departs from its running mean `u_mean` (time constant
//! `tau`, `input_mean_time_s`). The filter has no scale-factor states: when a vehicle spins up
//! after a rotor loss, the error `(S + E) w` (0.15 to 0.4 rad/s at 30 rad/s for an ICM-42688-P)
//! appears as a bias change, and this term lets the bias follow it; in a steady spin it fades and
//! the bias estimate settles. A reading clamped at the range hides an unknown excess that acts
//! like a bias while the clamping lasts: when an axis starts or stops clamping, its bias
//! variance grows by `(saturation_excess range)^2`, while it lasts the bias walks with density
//! `saturation_walk range` (the excess changes with the true rate, e.g. through a spin-up), and
//! the aiding measurements teach the bias state the excess.
//!
//! # Measurements
//! Each fused at its time of validity, gated on the normalised innovation squared; a position
//! source's fixes at most one per `position_fusion_period_s` slot (10 ms: EKF2's one
//! external-vision fix per filter update; the others are counted as thinned):
//!
//! | measurement | residual | Jacobian (block) |
//! |---|---|---|
//! | position (mocap, GNSS) | `z - p` | `I` (dp) |
//! | velocity (GNSS) | `z - v` | `I` (dv) |
//! | attitude (mocap) | `Log(q^-1 q_m)` | `I` (dtheta) |
//! | magnetometer | `z - R^T m_earth` | `[R^T m_earth]x` (dtheta) |
//!
//! `K = P H^T (H P H^T + R)^-1`, `dx = K r`, `P <- P - K (P H^T)^T` (symmetrised), `x <- x + dx`,
//! and the attitude reset `P <- G P G^T`, `G = I - [dtheta / 2]x` on the attitude block.
//!
//! # Latency compensation
//! The filter runs on a fusion horizon `fusion_delay_s` behind the newest IMU sample. IMU samples
//! wait in a buffer until the horizon reaches them; a measurement, stamped with its time of
//! validity, waits in a queue until the horizon passes that time, and is fused there: the horizon
//! is propagated to exactly the validity time (between two IMU samples if need be), updated, and
//! propagated on. The output predictor is the horizon state carried forward through the
//! buffered samples by the same propagation: after a fusion it is recomputed from the horizon
//! (the state re-propagated from the time of validity to now), otherwise advanced one sample.
//! Its value equals that of a filter that had rewound its history to each measurement's time of
//! validity, fused it and re-propagated, without re-propagating the covariance. The covariance
//! is reported at the horizon (see [`Estimator::horizon_time_s`]).

pub mod eskf;
pub(crate) mod lanes;
mod estimator;
mod settings;

pub use eskf::{Covariance, NominalState, ERROR_DIM};
pub use estimator::{Estimate, Estimator, FusionCounts};
pub use settings::{EstimatorSettings, CHI2_3DOF_1E4};

#[cfg(test)]
mod tests;
