//! The closed loop: controller at its own rate (zero-order hold), actuators and rigid body
//! integrated together with `substeps` RK4 steps per control period, rotor faults on a schedule
//! the controller never sees, and divergence detection that ends a run with an event instead of a
//! panic or a hang.
//!
//! Per control step k (at `t_k = k dt`; the last step is shortened so the run ends exactly at
//! `duration_s`): record the state, let the controller compute commands from the measured state,
//! then `substeps` RK4 steps of the coupled body and actuators with the command held. Within a
//! substep the actuators follow their exact response (see [`crate::flight::actuator`]) evaluated at the
//! RK4 stage times, so the body sees them evolve; an interval also ends at every fault time
//! ([`FaultSchedule`]), so faults act from exactly their time.
//!
//! After every substep the divergence limits and the ground are checked; a crossing is located
//! within the substep by re-integrating from its start (bisection on the step length), and the
//! run ends at that time with the state there.
//!
//! # Ground
//! The ground is the plane `z = ground_z_m` of the world frame (NED; default 0, so altitudes are
//! heights above it; `None`: no ground). Contact is the centre of mass below it; it ends the run
//! as `crashed` at the located time, with the state there (impact speed, attitude:
//! [`Divergence::impact`]). The simulator has no ground reaction, so a run must start above the
//! ground (a start on or below it is refused).
//!
//! # Step size
//! RK4 resolves a motion of rate `lambda` only when `h |lambda|` is small: a rotation at
//! `h |omega| = 0.25` loses 1.7e-6 of its amplitude and 8e-6 rad of phase per step (0.5: 1.1e-4
//! and 2.4e-4; 1: 6e-3), and near 2.8 RK4 is unstable (a torque-free spin diverges). A run is refused when the substep `h = dt /
//! substeps` times the fastest rate it knows of, `max(|omega_0|, 1 / time_constant)`, exceeds
//! [`MAX_RATE_STEP`], and it ends with [`DivergenceKind::StepSize`] (a numerical cause, not the
//! vehicle) when `h |omega|` grows past it during the run.
//!
//! # Layout (one concept per file; imports run down this list, never back up)
//! - [`columns`]: a batch recorded into one buffer per signal, runs filling their slots.
//! - [`batch_lanes`]: a batch of runs in parallel, four at a time in SIMD lanes (same results).
//! - [`driver`]: one run (checks, then control step by control step) and a batch run's rule.
//! - `onboard`: one run's sensors and estimator, fed from the tape after every period.
//! - [`step`]: one control period of body and actuators (RK4 substeps, faults, divergence
//!   check), and the step-size check.
//! - `tape`: the truth between integration nodes, for sensors on their own clocks.
//! - [`config`]: timing, limits, ground, wind, noise and sensing of a run.
//! - [`recording`]: the trajectory (with the estimate beside the truth), which steps it keeps,
//!   the step observer.
//! - [`sensing`]: which sensors (a named suite) the controller flies on.
//! - [`noise`]: the papers' sensor noise on what the controller sees.
//! - [`divergence`]: divergence limits, kinds and events, and how a crossing is located.

pub mod batch_lanes;
pub mod columns;
pub mod config;
pub mod divergence;
pub mod driver;
#[cfg(test)]
mod ground_tests;
pub mod noise;
mod onboard;
mod onboard_lanes;
pub mod recording;
pub mod sensing;
pub mod step;
mod tape;
mod tape_lanes;
#[cfg(test)]
mod tests;

pub use crate::flight::fault_schedule::{FaultSchedule, RotorFault};
pub use batch_lanes::{simulate_batch, simulate_batch_lanes, BatchLanes};
pub use columns::{simulate_batch_columns, BatchColumns, Column, RunRecord, Sample};
pub use config::{
    SimulationConfig, DEFAULT_GROUND_Z_M, MAX_CONTROL_STEPS, MAX_RK4_STEPS, MAX_SUBSTEPS,
};
pub use divergence::{Divergence, DivergenceLimits, DivergenceKind, Impact, MAX_RATE_STEP};
pub use driver::{simulate, simulate_cancellable, simulate_observed, BatchRun};
pub use noise::SensorNoise;
pub use recording::{EstimateRow, SensingRecord, StepObserver, Trajectory};
pub use sensing::{ImuPart, Sensing, SuiteName};
