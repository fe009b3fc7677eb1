//! What a run records: the [`Trajectory`] at the control rate, which control steps it keeps
//! (`records`), and the [`StepObserver`] that sees every step as it is flown.

use crate::flight::actuator::Actuators;
use crate::flight::simulation::divergence::Divergence;
use crate::state::{RigidBodyState, STATE_DIM};

/// Whether control step `k` of `steps` is recorded (without a divergence there): every
/// `every`-th and the last. The one rule of [`crate::flight::simulation::simulate`] and [`crate::flight::simulation::SimulationConfig::record_times`].
#[inline]
pub(crate) fn records(k: usize, every: usize, steps: usize) -> bool {
    k.is_multiple_of(every) || k == steps
}

/// Everything recorded at the control rate. Arrays are row-major, one row per control step.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Time of each row: the recorded control steps (every `record_every`-th, always the first
    /// and the last, which is exactly `duration_s`), and a divergence at its located time.
    pub t_s: Vec<f64>,
    pub states: Vec<RigidBodyState>,
    /// Commands applied from this step on (`command_count` per row).
    pub commands: Vec<f64>,
    /// Thrust each rotor produces at this step, after efficiency (m per row), N.
    pub thrust_n: Vec<f64>,
    /// Health of each rotor at this row's time (m per row): a fault between two rows acts from
    /// its own time and first shows in the row after it.
    pub efficiency: Vec<f64>,
    /// What the controller saw with sensor noise: the 12-element state vector (12 per row);
    /// empty without noise (the controller then saw exactly `states`).
    pub measured: Vec<f64>,
    pub divergence: Option<Divergence>,
}

impl Trajectory {
    /// Records one control step's time, state, efficiency, rotor thrusts and (with sensor noise)
    /// measurement row; the caller adds the commands.
    pub(crate) fn push_step(
        &mut self,
        t_s: f64,
        state: &RigidBodyState,
        efficiency: &[f64],
        actuators: &Actuators,
        measured: Option<&[f64; STATE_DIM]>,
    ) {
        self.t_s.push(t_s);
        self.states.push(*state);
        self.efficiency.extend_from_slice(efficiency);
        self.thrust_n
            .extend((0..efficiency.len()).map(|i| actuators.output(i, efficiency[i]).thrust_n));
        if let Some(row) = measured {
            self.measured.extend_from_slice(row);
        }
    }
}

/// Sees every control step of a run as it is flown: the rows a `record_every = 1` trajectory
/// would hold (time, true state, command, efficiency; the divergence row with NaN commands),
/// whatever `record_every` is. Per-run summaries ([`crate::flight::summary`]) use it to score a
/// run without storing it.
pub trait StepObserver {
    fn step(&mut self, t_s: f64, state: &RigidBodyState, command: &[f64], efficiency: &[f64]);
}

/// Observes nothing (plain [`crate::flight::simulation::simulate`]).
pub(crate) struct NoObserver;

impl StepObserver for NoObserver {
    #[inline]
    fn step(&mut self, _: f64, _: &RigidBodyState, _: &[f64], _: &[f64]) {}
}
