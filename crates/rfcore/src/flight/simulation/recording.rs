//! What a run records: the [`Trajectory`] at the control rate (with sensing, the estimate beside
//! the truth: [`SensingRecord`]), which control steps it keeps (`records`), and the
//! [`StepObserver`] that sees every step as it is flown.

use crate::flight::actuator::Actuators;
use crate::flight::estimation::{FusionCounts, ERROR_DIM};
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
    pub rotor_command: Vec<f64>,
    /// Thrust each rotor produces at this step, after efficiency (m per row), N.
    pub rotor_thrust_n: Vec<f64>,
    /// Health of each rotor at this row's time (m per row): a fault between two rows acts from
    /// its own time and first shows in the row after it.
    pub efficiency: Vec<f64>,
    /// What the controller saw with sensor noise: the 12-element state vector (12 per row);
    /// empty without noise (the controller then saw exactly `states`).
    pub recorded_measurements: Vec<f64>,
    pub divergence: Option<Divergence>,
    /// With sensing: the estimate the controller flew on, one row per recorded row.
    pub sensing: Option<SensingRecord>,
}

/// What the estimator gave the controller at one recorded control step, beside the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateRow {
    /// The estimate the controller saw (position, velocity and attitude of the output predictor,
    /// the bias-corrected gyro); NaN on a divergence row (no command was computed there).
    pub state: RigidBodyState,
    /// One sigma of the error state `[dp, dv, dtheta, dbg, dba]` (m, m/s, rad, rad/s, m/s^2):
    /// the square roots of the covariance's diagonal at the fusion horizon.
    pub std: [f64; ERROR_DIM],
    /// The newest IMU sample was clamped at the gyroscope's (accelerometer's) range.
    pub gyro_saturated: bool,
    pub accel_saturated: bool,
}

/// A run's sensing: which sensors, the estimate at every recorded step, and counts over the
/// whole run.
#[derive(Debug, Clone, PartialEq)]
pub struct SensingRecord {
    /// The sensor suite's name (`mocap`, `gnss`, `rtk`).
    pub name: &'static str,
    pub rows: Vec<EstimateRow>,
    pub imu_samples: u64,
    /// IMU samples with a gyroscope (accelerometer) axis clamped at its range.
    pub gyro_saturated_samples: u64,
    pub accel_saturated_samples: u64,
    /// The estimator's measurements: fused, refused by its gate, late.
    pub fusion: FusionCounts,
}

impl Trajectory {
    /// What the controller flew on: `"truth"`, `"paper-noise"` (the papers' relative noise on the
    /// state) or the sensor suite's name.
    pub fn sensed(&self) -> &'static str {
        match &self.sensing {
            Some(record) => record.name,
            None if !self.recorded_measurements.is_empty() => "paper-noise",
            None => "truth",
        }
    }

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
        self.rotor_thrust_n
            .extend((0..efficiency.len()).map(|i| actuators.output(i, efficiency[i]).thrust_n));
        if let Some(row) = measured {
            self.recorded_measurements.extend_from_slice(row);
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
