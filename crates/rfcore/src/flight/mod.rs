//! The flight simulator: one 6-DOF core with pluggable actuator models.
//!
//! - [`rigid_body`]: Newton-Euler dynamics with the full inertia tensor and the RK4 step.
//! - [`actuator`]: fixed-pitch and variable-pitch rotors (lag, rate limit, saturation, efficiency);
//!   [`vpp_preset`]: the variable-pitch preset files that describe one.
//! - [`lanes`]: the RK4 step and vehicle wrench over SIMD lanes (several vehicles at once).
//! - [`vehicle`]: rotor forces and torques, drag, gyroscopic moment, wind.
//! - [`model`]: the model as an ODE in the 12-element state vector, for linearisation.
//! - [`simulation`]: the closed loop with a controller, rotor faults, noise and divergence events.
//! - [`summary`]: per-run summaries scored while a run is flown (campaigns).
//! - [`sensors`]: IMU, position source, magnetometer and rotor speed models with datasheet
//!   profiles; [`estimation`]: the error-state Kalman filter a controller can fly on instead of
//!   the truth; [`random`]: the seeded random streams they draw from.
//!
//! The simulator runs any [`crate::control::Controller`]; controllers never see this room.

pub mod actuator;
pub mod estimation;
pub mod fault_schedule;
pub mod lanes;
pub mod model;
pub mod random;
pub mod rigid_body;
pub mod sensors;
pub mod simulation;
pub mod summary;
pub mod vehicle;
pub mod vpp_preset;
