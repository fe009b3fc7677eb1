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
//! After every substep the divergence limits are checked; a crossing is located within the
//! substep by re-integrating from its start (bisection on the step length), and the run ends at
//! that time with the state there.
//!
//! # Step size
//! RK4 resolves a motion of rate `lambda` only when `h |lambda|` is small: a rotation at
//! `h |omega| = 0.25` loses 1.7e-6 of its amplitude and 8e-6 rad of phase per step (0.5: 1.1e-4
//! and 2.4e-4; 1: 6e-3), and near 2.8 RK4 is unstable (a torque-free spin diverges). A run is refused when the substep `h = dt /
//! substeps` times the fastest rate it knows of, `max(|omega_0|, 1 / time_constant)`, exceeds
//! [`MAX_RATE_STEP`], and it ends with [`DivergenceReason::StepSize`] (a numerical cause, not the
//! vehicle) when `h |omega|` grows past it during the run.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::control::Controller;
use crate::error::{require_finite, Result, RfError};
use crate::flight::actuator::Actuators;
pub use crate::flight::fault_schedule::{FaultSchedule, RotorFault};
use crate::flight::vehicle::{RotorTotals, Vehicle};
use crate::state::{state_from_vector, state_vector, ControllerInput, RigidBodyState, STATE_DIM};

/// Most control steps one run records (about 2 GB of trajectory).
pub const MAX_CONTROL_STEPS: usize = 10_000_000;
/// Most RK4 steps one run takes (a few minutes on one core).
pub const MAX_RK4_STEPS: usize = 1_000_000_000;

/// Largest `h max(|omega|, 1 / time_constant)` a run accepts (module docs, "Step size").
pub const MAX_RATE_STEP: f64 = 0.25;

/// Relative tolerance below which `duration / dt` counts as a whole number of control steps.
const WHOLE_STEPS_RTOL: f64 = 1e-9;

/// Limits past which a run is declared diverged, checked after every RK4 substep; a crossing
/// is located within its substep (the event's time and state are at the crossing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DivergenceLimits {
    /// Largest angle between body z and world z (down), rad.
    pub max_tilt_rad: f64,
    /// Largest drop below the starting altitude, m.
    pub max_altitude_loss_m: f64,
    /// Largest speed, m/s.
    pub max_speed_m_s: f64,
    /// Largest body rate magnitude, rad/s.
    pub max_rate_rad_s: f64,
}

impl Default for DivergenceLimits {
    fn default() -> Self {
        DivergenceLimits {
            max_tilt_rad: std::f64::consts::FRAC_PI_2,
            max_altitude_loss_m: 100.0,
            max_speed_m_s: 100.0,
            max_rate_rad_s: 200.0,
        }
    }
}

/// Why a run ended early.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DivergenceReason {
    NonFinite,
    /// The controller produced a non-finite command.
    NonFiniteCommand,
    Tilt,
    AltitudeLoss,
    Speed,
    BodyRate,
    /// `h |omega|` grew past [`MAX_RATE_STEP`]: the integrator can no longer resolve the motion
    /// (a numerical failure, not the vehicle's); use more substeps.
    StepSize,
}

impl DivergenceReason {
    /// A short identifier (`"tilt"`, `"non-finite-command"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            DivergenceReason::NonFinite => "non-finite-state",
            DivergenceReason::NonFiniteCommand => "non-finite-command",
            DivergenceReason::Tilt => "tilt",
            DivergenceReason::AltitudeLoss => "altitude-loss",
            DivergenceReason::Speed => "speed",
            DivergenceReason::BodyRate => "body-rate",
            DivergenceReason::StepSize => "step-size",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            DivergenceReason::NonFinite => "state became non-finite",
            DivergenceReason::NonFiniteCommand => "the controller produced a non-finite command",
            DivergenceReason::Tilt => "tilt beyond the limit",
            DivergenceReason::AltitudeLoss => "altitude loss beyond the limit",
            DivergenceReason::Speed => "speed beyond the limit",
            DivergenceReason::BodyRate => "body rate beyond the limit",
            DivergenceReason::StepSize => {
                "body rate too fast for the RK4 substep (numerical): use more substeps"
            }
        }
    }
}

/// A run that ended early: when (the limit crossing, located within the substep), why, and the
/// state at that moment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Divergence {
    pub time_s: f64,
    pub reason: DivergenceReason,
    pub state: RigidBodyState,
}

/// Timing, limits and wind of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Control period, s (e.g. 1/400).
    pub dt_s: f64,
    /// RK4 steps per control period.
    pub substeps: usize,
    /// The run ends exactly here: when it is not a whole number of control periods, the last
    /// control step is shortened (and recorded at `duration_s`).
    pub duration_s: f64,
    pub limits: DivergenceLimits,
    /// Constant wind, world NED, m/s.
    pub wind_m_s: Vector3<f64>,
    /// Optional wind profile added to the constant: piecewise-linear through `(time_s, wind)`
    /// points, held constant outside them.
    pub wind_profile: Vec<(f64, Vector3<f64>)>,
    /// Sensor noise on what the controller sees (`None`: the true state).
    pub noise: Option<SensorNoise>,
    /// Record every this many control steps (1: all). The first and last steps and a divergence
    /// are always recorded; large batches use it to keep memory bounded.
    pub record_every: usize,
}

/// Additive Gaussian noise on each of the 12 measured state components (position, velocity,
/// Euler angles, body rates; see [`crate::state::state_vector`]), with standard deviation
/// `relative_std |x_i| + absolute_std[i]`.
///
/// `relative_std = 10^(-SNR / 20)` is a per-sample signal-to-noise ratio (Wang et al. add noise
/// "with the signal-to-noise ratio as 15 dB ... to all the feedback states" without saying how the
/// signal power is measured; per sample is the causal reading, decided here and documented).
/// Deterministic for a given `seed` on every platform (SplitMix64 and Box-Muller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorNoise {
    pub relative_std: f64,
    pub absolute_std: [f64; STATE_DIM],
    pub seed: u64,
}

impl SensorNoise {
    /// Relative noise at `snr_db` decibels.
    pub fn from_snr_db(snr_db: f64, seed: u64) -> Self {
        SensorNoise {
            relative_std: 10f64.powf(-snr_db / 20.0),
            absolute_std: [0.0; STATE_DIM],
            seed,
        }
    }

    fn check(&self) -> Result<()> {
        if !(self.relative_std.is_finite() && self.relative_std >= 0.0) {
            return Err(RfError::invalid(
                "noise.snr_db",
                "must give a finite, non-negative noise level",
            ));
        }
        for (i, &v) in self.absolute_std.iter().enumerate() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(RfError::invalid(
                    format!("noise.std[{i}]"),
                    format!("must be finite and >= 0, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// Standard normal samples from SplitMix64 through Box-Muller.
struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    fn new(seed: u64) -> Self {
        Gaussian {
            state: seed,
            spare: None,
        }
    }

    fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // 53 random bits in (0, 1]: never 0, so the logarithm below is finite.
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let radius = (-2.0 * u1.ln()).sqrt();
        let angle = 2.0 * std::f64::consts::PI * u2;
        self.spare = Some(radius * angle.sin());
        radius * angle.cos()
    }
}

/// The Python `Simulator`'s defaults: Ke's 400 Hz control rate with 4 RK4 substeps, a 10 s run.
impl Default for SimulationConfig {
    fn default() -> Self {
        SimulationConfig::new(1.0 / 400.0, 4, 10.0)
    }
}

impl SimulationConfig {
    /// A run of `duration_s` at control period `dt_s` with `substeps` RK4 steps per
    /// period, default limits, no wind, no noise.
    pub fn new(dt_s: f64, substeps: usize, duration_s: f64) -> Self {
        SimulationConfig {
            dt_s,
            substeps,
            duration_s,
            limits: DivergenceLimits::default(),
            wind_m_s: Vector3::zeros(),
            wind_profile: Vec::new(),
            noise: None,
            record_every: 1,
        }
    }

    pub fn check(&self) -> Result<()> {
        if !(self.dt_s.is_finite() && self.dt_s > 0.0) {
            return Err(RfError::invalid(
                "dt_s",
                format!("must be > 0 and finite, got {}", self.dt_s),
            ));
        }
        if self.record_every == 0 {
            return Err(RfError::invalid("record_every", "must be >= 1"));
        }
        if self.substeps == 0 {
            return Err(RfError::invalid("substeps", "must be >= 1"));
        }
        require_finite("duration_s", self.duration_s)?;
        if self.duration_s < 0.0 {
            return Err(RfError::invalid(
                "duration_s",
                format!("must be >= 0, got {}", self.duration_s),
            ));
        }
        // Bound memory (every control step is recorded) and work (no run takes hours).
        let steps = self.steps_f64();
        if steps > MAX_CONTROL_STEPS as f64 {
            return Err(RfError::invalid(
                "duration_s, dt_s",
                format!(
                    "duration_s / dt_s = {steps} control steps exceed the limit of {MAX_CONTROL_STEPS} \
                     (every step is recorded): shorten the run or lengthen dt"
                ),
            ));
        }
        if steps * self.substeps as f64 > MAX_RK4_STEPS as f64 {
            return Err(RfError::invalid(
                "substeps",
                format!(
                    "{steps} control steps x {} substeps exceed the limit of {MAX_RK4_STEPS} RK4 steps per run",
                    self.substeps
                ),
            ));
        }
        let l = &self.limits;
        for (field, v) in [
            ("limits.max_tilt_rad", l.max_tilt_rad),
            ("limits.max_altitude_loss_m", l.max_altitude_loss_m),
            ("limits.max_speed_m_s", l.max_speed_m_s),
            ("limits.max_rate_rad_s", l.max_rate_rad_s),
        ] {
            if v.is_nan() || v <= 0.0 {
                return Err(RfError::invalid(
                    field,
                    format!("must be > 0 (infinity for none), got {v}"),
                ));
            }
        }
        for (i, w) in self.wind_m_s.iter().enumerate() {
            require_finite(&format!("wind[{i}]"), *w)?;
        }
        if let Some(noise) = &self.noise {
            noise.check()?;
        }
        for (k, (t, w)) in self.wind_profile.iter().enumerate() {
            require_finite(&format!("wind_profile[{k}].time"), *t)?;
            if w.iter().any(|v| !v.is_finite()) {
                return Err(RfError::invalid(
                    format!("wind_profile[{k}]"),
                    "must be finite",
                ));
            }
            if k > 0 && *t <= self.wind_profile[k - 1].0 {
                return Err(RfError::invalid(
                    format!("wind_profile[{k}].time"),
                    "times must be strictly increasing",
                ));
            }
        }
        Ok(())
    }

    /// Number of control steps in the run: `duration / dt` rounded up (a last, shorter step ends
    /// the run exactly at `duration_s`), or rounded when within 1e-9 of a whole number.
    pub fn steps(&self) -> usize {
        self.steps_f64() as usize
    }

    fn steps_f64(&self) -> f64 {
        let ratio = self.duration_s / self.dt_s;
        let whole = ratio.round();
        if (ratio - whole).abs() <= WHOLE_STEPS_RTOL * whole.max(1.0) {
            whole
        } else {
            ratio.ceil()
        }
    }

    /// Time of control step `k` (`0..=steps()`): `k dt`, the last one exactly `duration_s`.
    pub fn step_time(&self, k: usize) -> f64 {
        if k >= self.steps() {
            self.duration_s
        } else {
            k as f64 * self.dt_s
        }
    }

    /// The recording grid: the times of the control steps a run that does not diverge records
    /// (bit-identical to its [`Trajectory::t_s`]), the last exactly `duration_s`. A run that
    /// diverges records a prefix of it and then its divergence row at the located time.
    pub fn record_times(&self) -> Vec<f64> {
        let steps = self.steps();
        (0..=steps)
            .filter(|&k| records(k, self.record_every, steps))
            .map(|k| self.step_time(k))
            .collect()
    }

    /// Wind at time `t_s` (world, m/s).
    pub fn wind_at(&self, t_s: f64) -> Vector3<f64> {
        let p = &self.wind_profile;
        let extra = match p.iter().position(|(t, _)| *t > t_s) {
            _ if p.is_empty() => Vector3::zeros(),
            Some(0) => p[0].1,
            None => p[p.len() - 1].1,
            Some(k) => {
                let ((t0, w0), (t1, w1)) = (p[k - 1], p[k]);
                w0 + (w1 - w0) * ((t_s - t0) / (t1 - t0))
            }
        };
        self.wind_m_s + extra
    }
}

/// Whether control step `k` of `steps` is recorded (without a divergence there): every
/// `every`-th and the last. The one rule of [`simulate`] and [`SimulationConfig::record_times`].
#[inline]
fn records(k: usize, every: usize, steps: usize) -> bool {
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
    fn push_step(
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

/// The divergence limits in the form checked after every substep (cheap comparisons; the
/// step-size bound folded into the body-rate limit) and the exceedances a crossing is located on.
struct Limits {
    limits: DivergenceLimits,
    start_altitude_m: f64,
    /// `MAX_RATE_STEP / h`: the fastest body rate the substep resolves.
    step_rate_rad_s: f64,
    min_n3z: f64,
    max_speed2: f64,
    max_rate2: f64,
}

impl Limits {
    fn new(limits: &DivergenceLimits, start_altitude_m: f64, h: f64) -> Self {
        let step_rate_rad_s = MAX_RATE_STEP / h;
        let max_rate = limits.max_rate_rad_s.min(step_rate_rad_s);
        Limits {
            limits: *limits,
            start_altitude_m,
            step_rate_rad_s,
            // tilt > max  <=>  n3z = cos(tilt) < cos(max), for max below pi.
            min_n3z: if limits.max_tilt_rad < std::f64::consts::PI {
                limits.max_tilt_rad.cos()
            } else {
                f64::NEG_INFINITY
            },
            max_speed2: limits.max_speed_m_s * limits.max_speed_m_s,
            max_rate2: max_rate * max_rate,
        }
    }

    /// `true` when the state is finite and within every limit (NaN fails every comparison).
    #[inline]
    fn within(&self, s: &RigidBodyState) -> bool {
        let q = s.attitude.quaternion();
        // n3z, the z component of body z in the world frame.
        let n3z = q.w * q.w - q.i * q.i - q.j * q.j + q.k * q.k;
        n3z >= self.min_n3z
            && self.start_altitude_m + s.position_m.z <= self.limits.max_altitude_loss_m
            && s.velocity_m_s.norm_squared() <= self.max_speed2
            && s.omega_rad_s.norm_squared() <= self.max_rate2
            && s.position_m.x.is_finite()
            && s.position_m.y.is_finite()
    }

    /// How far past each limit the state is (positive: beyond), in the order of precedence.
    fn exceedances(&self, s: &RigidBodyState) -> [(DivergenceReason, f64); 5] {
        let l = &self.limits;
        let rate = s.omega_rad_s.norm();
        [
            (
                DivergenceReason::Tilt,
                s.primary_axis().z.clamp(-1.0, 1.0).acos() - l.max_tilt_rad,
            ),
            (
                DivergenceReason::AltitudeLoss,
                self.start_altitude_m + s.position_m.z - l.max_altitude_loss_m,
            ),
            (
                DivergenceReason::Speed,
                s.velocity_m_s.norm() - l.max_speed_m_s,
            ),
            (DivergenceReason::BodyRate, rate - l.max_rate_rad_s),
            (DivergenceReason::StepSize, rate - self.step_rate_rad_s),
        ]
    }

    /// The first limit `s` is beyond, if any.
    fn reason(&self, s: &RigidBodyState) -> Option<DivergenceReason> {
        if !s.is_finite() {
            return Some(DivergenceReason::NonFinite);
        }
        self.exceedances(s)
            .into_iter()
            .find(|(_, e)| *e > 0.0)
            .map(|(r, _)| r)
    }

    /// Where within an interval of length `len` a limit is first crossed: `step(l)` integrates
    /// `l` from the interval's start (within the limits) to a state, and the end state is
    /// beyond. Returns the elapsed time and the reason: the smallest bisected crossing over the
    /// limits the end state exceeds (the end itself when it is non-finite).
    fn locate(
        &self,
        len: f64,
        end: &RigidBodyState,
        mut step: impl FnMut(f64) -> RigidBodyState,
    ) -> (f64, DivergenceReason) {
        if !end.is_finite() {
            return (len, DivergenceReason::NonFinite);
        }
        let mut best = (len, DivergenceReason::NonFinite);
        let mut found = false;
        for (i, (reason, excess)) in self.exceedances(end).into_iter().enumerate() {
            if excess <= 0.0 {
                continue;
            }
            // Bisection on [lo, hi] with the limit not exceeded at lo, exceeded at hi: hi is
            // returned, so the reported state is just beyond the limit.
            let (mut lo, mut hi) = (0.0, if found { best.0 } else { len });
            if found {
                // Only a crossing before the current best can win.
                let at = step(hi);
                if !(at.is_finite() && self.exceedances(&at)[i].1 > 0.0) {
                    continue;
                }
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                let at = step(mid);
                if !at.is_finite() || self.exceedances(&at)[i].1 > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            if !found || hi < best.0 {
                best = (hi, reason);
                found = true;
            }
        }
        best
    }
}

/// Sees every control step of a run as it is flown: the rows a `record_every = 1` trajectory
/// would hold (time, true state, command, efficiency; the divergence row with NaN commands),
/// whatever `record_every` is. Per-run summaries ([`crate::flight::summary`]) use it to score a
/// run without storing it.
pub trait StepObserver {
    fn step(&mut self, t_s: f64, state: &RigidBodyState, command: &[f64], efficiency: &[f64]);
}

/// Observes nothing (plain [`simulate`]).
struct NoObserver;

impl StepObserver for NoObserver {
    #[inline]
    fn step(&mut self, _: f64, _: &RigidBodyState, _: &[f64], _: &[f64]) {}
}

/// The rotors' summed contribution with the channels at `states`.
#[inline]
fn rotor_totals(
    vehicle: &Vehicle,
    actuators: &Actuators,
    states: &[f64],
    efficiency: &[f64],
) -> RotorTotals {
    let mut totals = RotorTotals::default();
    let mut xy = vehicle.rotor_xy_m().iter();
    actuators.for_each_output(states, efficiency, |out| {
        if let Some(&at) = xy.next() {
            totals.add(at, &out);
        }
    });
    totals
}

/// The up-front step-size check (module docs).
fn check_step_size(
    config: &SimulationConfig,
    actuators: &Actuators,
    x0: &RigidBodyState,
) -> Result<()> {
    let h = config.dt_s / config.substeps as f64;
    let spin = x0.omega_rad_s.norm();
    let tau = actuators.time_constant_s();
    let lag_rate = if tau > 0.0 { 1.0 / tau } else { 0.0 };
    let fastest = spin.max(lag_rate);
    let product = h * fastest;
    if product > MAX_RATE_STEP {
        let needed = (config.dt_s * fastest / MAX_RATE_STEP).ceil();
        return Err(RfError::invalid(
            "substeps",
            format!(
                "the RK4 substep h = dt / substeps = {h} s is too long for the fastest rate: \
                 h x max(|omega_0| = {spin} rad/s, 1 / time_constant = {lag_rate} 1/s) = \
                 {product} exceeds {MAX_RATE_STEP}, beyond which RK4 no longer resolves the \
                 motion: use substeps >= {needed} (or a shorter dt)"
            ),
        ));
    }
    Ok(())
}

/// One closed-loop run. `actuators` is the initial actuator state (settle it to the trim first
/// for a trimmed start); `efficiency` the initial rotor efficiency. Faults may come in any order.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    vehicle: &Vehicle,
    actuators: Actuators,
    controller: &mut dyn Controller,
    initial_efficiency: &[f64],
    faults: &[RotorFault],
    x0: RigidBodyState,
    config: &SimulationConfig,
) -> Result<Trajectory> {
    simulate_observed(
        vehicle,
        actuators,
        controller,
        initial_efficiency,
        faults,
        x0,
        config,
        &mut NoObserver,
    )
}

/// [`simulate`], showing every control step to `observer` as it is flown.
#[allow(clippy::too_many_arguments)]
pub fn simulate_observed(
    vehicle: &Vehicle,
    mut actuators: Actuators,
    controller: &mut dyn Controller,
    initial_efficiency: &[f64],
    faults: &[RotorFault],
    x0: RigidBodyState,
    config: &SimulationConfig,
    observer: &mut dyn StepObserver,
) -> Result<Trajectory> {
    config.check()?;
    let m = vehicle.rotor_count();
    if actuators.rotor_count() != m {
        return Err(RfError::shape(
            "actuator",
            format!("{m} rotors"),
            actuators.rotor_count().to_string(),
        ));
    }
    let count = actuators.channels() * m;
    if controller.command_count() != count {
        return Err(RfError::shape(
            "controller",
            format!(
                "{count} commands ({} per rotor x {m} rotors)",
                actuators.channels()
            ),
            controller.command_count().to_string(),
        ));
    }
    crate::airframe::check_efficiency("efficiency", initial_efficiency, m)?;
    let mut schedule = FaultSchedule::new(faults, m)?;
    if !x0.is_finite() {
        return Err(RfError::invalid("x0", "must be finite"));
    }
    check_step_size(config, &actuators, &x0)?;

    let steps = config.steps();
    let h_nominal = config.dt_s / config.substeps as f64;
    let every = config.record_every;
    let rows = steps / every + 3;
    let mut trajectory = Trajectory {
        t_s: Vec::with_capacity(rows),
        states: Vec::with_capacity(rows),
        commands: Vec::with_capacity(rows * count),
        thrust_n: Vec::with_capacity(rows * m),
        efficiency: Vec::with_capacity(rows * m),
        measured: Vec::with_capacity(if config.noise.is_some() {
            rows * STATE_DIM
        } else {
            0
        }),
        divergence: None,
    };
    controller.reset();
    let mut efficiency = initial_efficiency.to_vec();
    let mut command = vec![0.0; count];
    let mut targets = vec![0.0; count];
    // Channel states at the start, middle and end of an interval.
    let mut nodes = [vec![0.0; count], vec![0.0; count], vec![0.0; count]];
    let mut state = x0;
    let limits = Limits::new(&config.limits, -x0.position_m.z, h_nominal);
    let body = vehicle.body();
    let mut gaussian = config.noise.map(|n| Gaussian::new(n.seed));
    let mut measured_vector = [0.0; STATE_DIM];
    let nan_row = [f64::NAN; STATE_DIM];
    let instant = actuators.is_instant();
    let constant_wind = config.wind_profile.is_empty();
    let reads_samples = controller.reads_samples();
    let mut rotor_thrust = vec![0.0; m];

    schedule.apply_due(0.0, &mut efficiency);
    if let Some(reason) = limits.reason(&state) {
        trajectory.push_step(
            0.0,
            &state,
            &efficiency,
            &actuators,
            config.noise.map(|_| &nan_row),
        );
        trajectory
            .commands
            .extend(std::iter::repeat_n(f64::NAN, count));
        observer.step(0.0, &state, &vec![f64::NAN; count], &efficiency);
        trajectory.divergence = Some(Divergence {
            time_s: 0.0,
            reason,
            state,
        });
        return Ok(trajectory);
    }
    for k in 0..=steps {
        let t = config.step_time(k);
        // Measurements are recorded only when they differ from the true state (with noise);
        // without noise the Python layer rebuilds them from the recorded state.
        let measured = match (&config.noise, gaussian.as_mut()) {
            (Some(noise), Some(gaussian)) => {
                measured_vector = state_vector(&state);
                for (i, v) in measured_vector.iter_mut().enumerate() {
                    *v +=
                        (noise.relative_std * v.abs() + noise.absolute_std[i]) * gaussian.sample();
                }
                state_from_vector(&measured_vector)
            }
            _ => state,
        };
        // Raw samples (truth, or the noisy rates) only for a controller that reads them.
        let input = if reads_samples {
            for (i, thrust) in rotor_thrust.iter_mut().enumerate() {
                *thrust = actuators.output(i, efficiency[i]).thrust_n;
            }
            let totals = rotor_totals(vehicle, &actuators, actuators.state(), &efficiency);
            ControllerInput {
                state: &measured,
                gyro_rad_s: Some(measured.omega_rad_s),
                specific_force_m_s2: Some(vehicle.specific_force(
                    &state,
                    &totals,
                    &config.wind_at(t),
                )),
                rotor_thrust_n: Some(&rotor_thrust),
            }
        } else {
            ControllerInput::state_only(&measured)
        };
        controller.command_with(t, &input, &mut command)?;
        let finite = command.iter().all(|c| c.is_finite());
        observer.step(t, &state, &command, &efficiency);
        // Every `every`-th step, the last one, and a step whose command ends the run.
        if records(k, every, steps) || !finite {
            let row = config.noise.map(|_| &measured_vector);
            trajectory.push_step(t, &state, &efficiency, &actuators, row);
            trajectory.commands.extend_from_slice(&command);
        }
        if !finite {
            trajectory.divergence = Some(Divergence {
                time_s: t,
                reason: DivergenceReason::NonFiniteCommand,
                state,
            });
            break;
        }
        if k == steps {
            break;
        }
        let t_next = config.step_time(k + 1);
        let h = (t_next - t) / config.substeps as f64;
        actuators.saturate(&command, &mut targets);
        // The channels do not move within this control step (they jump to the command or sit
        // at it): one rotor evaluation serves every node of every substep.
        let constant = instant || actuators.state() == &targets[..];
        // Lag decays over a half and a whole substep, shared by every substep not split by a
        // fault.
        let half_decay = actuators.decay(0.5 * h);
        let decays = [
            [1.0; 2],
            half_decay,
            [half_decay[0] * half_decay[0], half_decay[1] * half_decay[1]],
        ];
        // Rotor totals at the start of the next interval, when known (same command, efficiency).
        let mut start_totals: Option<RotorTotals> = None;
        for s in 0..config.substeps {
            let mut a = t + s as f64 * h;
            let b = if s + 1 == config.substeps {
                t_next
            } else {
                t + (s + 1) as f64 * h
            };
            while a < b {
                // One RK4 step of body and actuators over [a, end], end = b or the next fault.
                let end = schedule.interval_end(a, b);
                let len = end - a;
                let winds = if constant_wind {
                    [config.wind_m_s; 3]
                } else {
                    [
                        config.wind_at(a),
                        config.wind_at(a + 0.5 * len),
                        config.wind_at(end),
                    ]
                };
                let totals = if constant {
                    let at_start = match start_totals {
                        Some(t) => t,
                        None => rotor_totals(vehicle, &actuators, &targets, &efficiency),
                    };
                    [at_start; 3]
                } else {
                    let mut totals = [RotorTotals::default(); 3];
                    // Shortened by a fault (not by rounding of the substep grid).
                    let split = (len - h).abs() > 1e-9 * h;
                    for (node, elapsed) in [0.0, 0.5 * len, len].into_iter().enumerate() {
                        if node == 0 {
                            if let Some(t) = start_totals {
                                totals[0] = t;
                                continue;
                            }
                        }
                        let decay = if split {
                            actuators.decay(elapsed)
                        } else {
                            decays[node]
                        };
                        actuators.response_with_decay(&targets, elapsed, decay, &mut nodes[node]);
                        totals[node] = rotor_totals(vehicle, &actuators, &nodes[node], &efficiency);
                    }
                    totals
                };
                let next = body.rk4_step_nodes(&state, len, |node, x| {
                    vehicle.wrench_from(x, &totals[node], &winds[node])
                });
                if !limits.within(&next) {
                    // Locate the crossing by re-integrating shorter steps from `state`.
                    let mut channels = vec![0.0; count];
                    let mut step = |l: f64| {
                        let (mid, fin) = (a + 0.5 * l, a + l);
                        let mut tot = [RotorTotals::default(); 3];
                        for (node, elapsed) in [0.0, 0.5 * l, l].into_iter().enumerate() {
                            actuators.response(&targets, elapsed, &mut channels);
                            tot[node] = rotor_totals(vehicle, &actuators, &channels, &efficiency);
                        }
                        let w = [config.wind_at(a), config.wind_at(mid), config.wind_at(fin)];
                        body.rk4_step_nodes(&state, l, |node, x| {
                            vehicle.wrench_from(x, &tot[node], &w[node])
                        })
                    };
                    let (elapsed, reason) = limits.locate(len, &next, &mut step);
                    let at = if elapsed == len { next } else { step(elapsed) };
                    actuators.response(&targets, elapsed, &mut channels);
                    actuators.set_state(&channels);
                    let time_s = a + elapsed;
                    trajectory.push_step(
                        time_s,
                        &at,
                        &efficiency,
                        &actuators,
                        config.noise.map(|_| &nan_row),
                    );
                    trajectory
                        .commands
                        .extend(std::iter::repeat_n(f64::NAN, count));
                    observer.step(time_s, &at, &vec![f64::NAN; count], &efficiency);
                    trajectory.divergence = Some(Divergence {
                        time_s,
                        reason,
                        state: at,
                    });
                    return Ok(trajectory);
                }
                state = next;
                actuators.set_state(if constant { &targets } else { &nodes[2] });
                start_totals = Some(totals[2]);
                a = end;
                if schedule.apply_due(a, &mut efficiency) {
                    start_totals = None;
                }
            }
        }
    }
    Ok(trajectory)
}

/// One run of a batch: its own controller, initial state and faults.
pub struct BatchRun {
    pub controller: Box<dyn Controller>,
    /// Actuator start for this run (settled), or `None` to keep the batch's actuator state.
    pub initial_command: Option<Vec<f64>>,
    pub x0: RigidBodyState,
    pub faults: Vec<RotorFault>,
}

/// Many runs in parallel (rayon); results in input order. With sensor noise, run `i` uses seed
/// `seed + i`, so runs are independent and the batch is reproducible.
pub fn simulate_batch(
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    runs: Vec<BatchRun>,
    config: &SimulationConfig,
) -> Result<Vec<Trajectory>> {
    runs.into_par_iter()
        .enumerate()
        .map(|(i, mut run)| {
            let mut own = config.clone();
            if let Some(noise) = own.noise.as_mut() {
                noise.seed = noise.seed.wrapping_add(i as u64);
            }
            let mut actuators = actuators.clone();
            if let Some(command) = &run.initial_command {
                actuators.settle(command)?;
            }
            simulate(
                vehicle,
                actuators,
                run.controller.as_mut(),
                initial_efficiency,
                &run.faults,
                run.x0,
                &own,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airframe::Airframe;
    use crate::control::{OpenLoop, ZeroCommand};
    use crate::flight::actuator::{FixedPitch, Lag, VariablePitch, VariablePitchLags};
    use crate::flight::vehicle::Drag;
    use nalgebra::DMatrix;

    fn quad_x() -> Airframe {
        crate::fixtures::preset("quad-x")
    }

    fn still_air(airframe: &Airframe) -> Vehicle {
        Vehicle::new(airframe, Drag::default()).unwrap()
    }

    /// Fixed-pitch rotors with no lag or rate limit.
    fn instant_rotors(airframe: &Airframe) -> Actuators {
        Actuators::FixedPitch(FixedPitch::new(airframe, Lag::none(), 0.0).unwrap())
    }

    fn config(duration_s: f64) -> SimulationConfig {
        SimulationConfig::new(0.0025, 2, duration_s)
    }

    fn hover_schedule(airframe: &Airframe) -> OpenLoop {
        let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        OpenLoop::new(vec![0.0], DMatrix::from_element(1, 4, f)).unwrap()
    }

    #[test]
    fn trimmed_hover_stays_put() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let mut actuators = instant_rotors(&airframe);
        let mut controller = hover_schedule(&airframe);
        let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        actuators.settle(&[f; 4]).unwrap();
        let x0 = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, -10.0),
            ..RigidBodyState::at_rest()
        };
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &[],
            x0,
            &config(10.0),
        )
        .unwrap();
        assert_eq!(run.t_s.len(), 4001);
        let end = run.states.last().unwrap();
        assert!(
            (end.position_m - x0.position_m).norm() < 1e-9,
            "{}",
            end.position_m
        );
        assert!(end.omega_rad_s.norm() < 1e-12);
        assert!(run.divergence.is_none());
    }

    #[test]
    fn no_thrust_is_free_fall_until_the_altitude_limit() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let actuators = instant_rotors(&airframe);
        let mut controller = ZeroCommand { count: 4 };
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &[],
            RigidBodyState::at_rest(),
            &config(2.0),
        )
        .unwrap();
        let end = run.states.last().unwrap();
        let g = airframe.gravity_m_s2();
        assert!((end.position_m.z - 0.5 * g * 4.0).abs() < 1e-9);
        let mut short = config(10.0);
        short.limits.max_altitude_loss_m = 20.0;
        let actuators = instant_rotors(&airframe);
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &[],
            RigidBodyState::at_rest(),
            &short,
        )
        .unwrap();
        let event = run.divergence.unwrap();
        assert_eq!(event.reason, DivergenceReason::AltitudeLoss);
        // 20 m of free fall take sqrt(40 / g) s. The crossing is located within its substep
        // (issue #18: it used to be reported at the next control step, up to dt = 2.5 ms late;
        // the located time can be ~1e-15 s early by rounding).
        let expected = (40.0 / g).sqrt();
        assert!((event.time_s - expected).abs() < 1e-12, "{}", event.time_s);
        assert!((event.state.position_m.z - 20.0).abs() < 1e-9);
        assert_eq!(*run.t_s.last().unwrap(), event.time_s);
    }

    #[test]
    fn open_loop_rotor_failure_tumbles_and_is_reported() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        let mut actuators = instant_rotors(&airframe);
        actuators.settle(&[f; 4]).unwrap();
        let mut controller = hover_schedule(&airframe);
        let fault = RotorFault {
            rotor: 0,
            time_s: 1.0,
            efficiency: 0.0,
        };
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &[fault],
            RigidBodyState::at_rest(),
            &config(10.0),
        )
        .unwrap();
        let event = run
            .divergence
            .expect("a vehicle that loses a rotor in open loop tumbles");
        assert_eq!(event.reason, DivergenceReason::Tilt);
        assert!(event.time_s > 1.0 && event.time_s < 3.0, "{}", event.time_s);
        // Health is recorded: 1 before the fault, 0 after.
        let row = |t: f64| (t / 0.0025).round() as usize * 4;
        assert_eq!(run.efficiency[row(0.5)], 1.0);
        assert_eq!(run.efficiency[row(1.2)], 0.0);
        assert_eq!(run.thrust_n[row(1.2)], 0.0);
        assert_eq!(run.commands.len(), run.t_s.len() * 4);
        assert!(
            run.measured.is_empty(),
            "no noise, no separate measurements"
        );
    }

    #[test]
    fn gaussian_samples_have_unit_variance_and_are_reproducible() {
        let mut g = Gaussian::new(7);
        let samples: Vec<f64> = (0..200_000).map(|_| g.sample()).collect();
        let mean = samples.iter().sum::<f64>() / samples.len() as f64;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / samples.len() as f64;
        // Standard errors: 1/sqrt(n) = 0.0022 for the mean, sqrt(2/n) = 0.0032 for the variance.
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.015, "{var}");
        let mut again = Gaussian::new(7);
        assert!(samples[..10].iter().all(|&x| x == again.sample()));
    }

    #[test]
    fn wind_profile_is_piecewise_linear() {
        let mut c = config(1.0);
        c.wind_m_s = Vector3::new(1.0, 0.0, 0.0);
        c.wind_profile = vec![(1.0, Vector3::zeros()), (2.0, Vector3::new(0.0, 4.0, 0.0))];
        assert_eq!(c.wind_at(0.0), Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(c.wind_at(1.5), Vector3::new(1.0, 2.0, 0.0));
        assert_eq!(c.wind_at(5.0), Vector3::new(1.0, 4.0, 0.0));
    }

    #[test]
    fn bad_configuration_is_named() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let actuators = instant_rotors(&airframe);
        let mut controller = ZeroCommand { count: 4 };
        let x0 = RigidBodyState::at_rest();
        let run =
            |cfg: &SimulationConfig, faults: &[RotorFault], controller: &mut dyn Controller| {
                simulate(
                    &vehicle,
                    actuators.clone(),
                    controller,
                    &[1.0; 4],
                    faults,
                    x0,
                    cfg,
                )
                .unwrap_err()
                .to_string()
            };
        let mut c = config(1.0);
        c.dt_s = 0.0;
        assert!(run(&c, &[], &mut controller).starts_with("dt_s: must be > 0"));
        let mut c = config(1.0);
        c.substeps = 0;
        assert!(run(&c, &[], &mut controller).starts_with("substeps"));
        let fault = RotorFault {
            rotor: 4,
            time_s: 1.0,
            efficiency: 0.0,
        };
        assert!(run(&config(1.0), &[fault], &mut controller)
            .starts_with("faults[0].rotor: rotor numbers run from 1 to 4, got 5"));
        let fault = RotorFault {
            rotor: 0,
            time_s: 1.0,
            efficiency: 1.5,
        };
        assert!(run(&config(1.0), &[fault], &mut controller).starts_with("faults[0].efficiency"));
        let mut wrong = ZeroCommand { count: 3 };
        assert!(run(&config(1.0), &[], &mut wrong).starts_with("controller: expected 4 commands"));
    }

    // ---- issue #18: answers that hold at any step size ----------------------------------------

    fn lagged_rotors(airframe: &Airframe, tau: f64, rate: f64) -> Actuators {
        let lag = Lag {
            time_constant_s: tau,
            rate_limit_per_s: rate,
        };
        Actuators::FixedPitch(FixedPitch::new(airframe, lag, 0.0).unwrap())
    }

    /// Position, velocity, attitude angle and body-rate differences, summed.
    fn state_error(a: &RigidBodyState, b: &RigidBodyState) -> f64 {
        (a.position_m - b.position_m).norm()
            + (a.velocity_m_s - b.velocity_m_s).norm()
            + a.attitude.angle_to(&b.attitude)
            + (a.omega_rad_s - b.omega_rad_s).norm()
    }

    fn end_state(
        vehicle: &Vehicle,
        actuators: &Actuators,
        controller: &mut dyn Controller,
        faults: &[RotorFault],
        x0: RigidBodyState,
        cfg: &SimulationConfig,
    ) -> RigidBodyState {
        let run = simulate(
            vehicle,
            actuators.clone(),
            controller,
            &[1.0; 4],
            faults,
            x0,
            cfg,
        )
        .unwrap();
        assert!(run.divergence.is_none(), "{:?}", run.divergence);
        *run.states.last().unwrap()
    }

    #[test]
    fn simulation_ends_exactly_at_a_duration_that_is_not_a_multiple_of_dt() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let g = airframe.gravity_m_s2();
        for (dt, expected) in [
            (0.4, vec![0.0, 0.4, 0.8, 1.0]),
            (0.3, vec![0.0, 0.3, 0.6, 0.9, 1.0]),
            (0.25, vec![0.0, 0.25, 0.5, 0.75, 1.0]),
        ] {
            let mut controller = ZeroCommand { count: 4 };
            let cfg = SimulationConfig::new(dt, 1, 1.0);
            let run = simulate(
                &vehicle,
                instant_rotors(&airframe),
                &mut controller,
                &[1.0; 4],
                &[],
                RigidBodyState::at_rest(),
                &cfg,
            )
            .unwrap();
            assert_eq!(run.t_s.len(), expected.len(), "dt {dt}: {:?}", run.t_s);
            for (t, e) in run.t_s.iter().zip(&expected) {
                assert!((t - e).abs() < 1e-15, "dt {dt}: {:?}", run.t_s);
            }
            assert_eq!(*run.t_s.last().unwrap(), 1.0);
            // Free fall is integrated exactly, including the shortened last step.
            let end = run.states.last().unwrap();
            assert!(
                (end.position_m.z - 0.5 * g).abs() < 1e-12,
                "dt {dt}: {}",
                end.position_m.z
            );
            // Thinned: every second step, and the last one at its true time.
            let mut thin = cfg.clone();
            thin.record_every = 2;
            let run = simulate(
                &vehicle,
                instant_rotors(&airframe),
                &mut controller,
                &[1.0; 4],
                &[],
                RigidBodyState::at_rest(),
                &thin,
            )
            .unwrap();
            let every_second: Vec<f64> = expected
                .iter()
                .enumerate()
                .filter(|(k, _)| k % 2 == 0 || *k == expected.len() - 1)
                .map(|(_, t)| *t)
                .collect();
            assert_eq!(run.t_s.len(), every_second.len(), "{:?}", run.t_s);
            assert_eq!(*run.t_s.last().unwrap(), 1.0);
            // The recording grid the batch stacks onto is the run's own time axis, bit for bit.
            assert_eq!(thin.record_times(), run.t_s);
        }
        // record_every = 7 over 3 s at dt = 0.01: steps 0, 7, ..., 294 and 300 (3.0 s).
        let mut cfg = SimulationConfig::new(0.01, 1, 3.0);
        cfg.record_every = 7;
        let grid = cfg.record_times();
        assert_eq!(grid.len(), 44);
        assert_eq!(grid[1], 7.0 * 0.01);
        assert_eq!((grid[42], grid[43]), (294.0 * 0.01, 3.0));
    }

    /// Constant (partly saturating) thrust commands against a lagged actuator: the coupled
    /// body + actuator system converges at fourth order.
    fn convergence_ratios(actuators: &Actuators, command: &[f64], vehicle: &Vehicle) -> Vec<f64> {
        let duration = 0.6;
        let mut controller = OpenLoop::new(
            vec![0.0],
            DMatrix::from_row_slice(1, command.len(), command),
        )
        .unwrap();
        let x0 = RigidBodyState {
            omega_rad_s: Vector3::new(0.3, -0.2, 0.5),
            ..RigidBodyState::at_rest()
        };
        let run = |n: usize, controller: &mut OpenLoop| {
            end_state(
                vehicle,
                actuators,
                controller,
                &[],
                x0,
                &SimulationConfig::new(duration / n as f64, 1, duration),
            )
        };
        let reference = run(4800, &mut controller);
        let errors: Vec<f64> = [12, 24, 48]
            .iter()
            .map(|&n| state_error(&run(n, &mut controller), &reference))
            .collect();
        errors.windows(2).map(|e| e[0] / e[1]).collect()
    }

    #[test]
    fn simulation_of_body_and_actuators_converges_at_fourth_order() {
        let airframe = quad_x();
        let vehicle = Vehicle::new(
            &airframe,
            Drag {
                rotor_inertia_kg_m2: 5e-5,
                linear_drag_n_s_m: 0.2,
                ..Drag::default()
            },
        )
        .unwrap();
        // Fixed pitch, tau = 0.25 s (h / tau = 0.2 at the coarsest step); rotor 1 saturates.
        let lag = Lag {
            time_constant_s: 0.25,
            rate_limit_per_s: f64::INFINITY,
        };
        let mut fixed = Actuators::FixedPitch(FixedPitch::new(&airframe, lag, 1.5e-5).unwrap());
        fixed.settle(&[3.76; 4]).unwrap();
        let ratios = convergence_ratios(&fixed, &[9.0, 3.0, 4.5, 2.5], &vehicle);
        eprintln!("fixed pitch ratios {ratios:?}");
        for r in &ratios {
            assert!(
                (13.0..19.0).contains(r),
                "fixed pitch: error ratios {ratios:?}"
            );
        }
        // Variable pitch (speed, pitch per rotor): the speed channels with the same lag, the
        // pitch channels their own faster one; rotor 2's speed saturates.
        let hover = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        let k1 = hover / (5000.0f64.powi(2) * 0.2);
        let mut variable = Actuators::VariablePitch(
            VariablePitch::new(
                &airframe,
                [k1, 1e-9, 3e-9, 1e-6],
                (0.0, 5300.0),
                (-0.3, 0.3),
                std::f64::consts::PI / 30.0,
                VariablePitchLags {
                    speed: lag,
                    pitch: Lag {
                        time_constant_s: 0.4,
                        rate_limit_per_s: 0.3,
                    },
                },
            )
            .unwrap(),
        );
        variable
            .settle(&[5000.0, 0.2, 5000.0, 0.2, 5000.0, 0.2, 5000.0, 0.2])
            .unwrap();
        let command = [5100.0, 0.21, 9000.0, 0.2, 4900.0, 0.2, 5000.0, 0.19];
        let ratios = convergence_ratios(&variable, &command, &vehicle);
        eprintln!("variable pitch ratios {ratios:?}");
        for r in &ratios {
            assert!(
                (13.0..19.0).contains(r),
                "variable pitch: error ratios {ratios:?}"
            );
        }
    }

    #[test]
    fn simulation_with_rate_limit_and_saturation_matches_a_fine_step_reference() {
        // A 1.5 s open-loop manoeuvre through saturation and the rate limit at dt = 0.02 s and
        // one substep (the audit's case: the old first-order coupling was 5e-2 m off).
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let rotors = lagged_rotors(&airframe, 0.08, 50.0);
        let mut rotors_settled = rotors.clone();
        let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        rotors_settled.settle(&[f; 4]).unwrap();
        // Yaw one way with the yawing pair saturated (7 N asked, 6.125 N given), then the other
        // way (a 4.7 N step: 50 N/s rate-limited), then hover; a small roll asymmetry.
        let b = airframe.effectiveness_matrix();
        let mut rows = Vec::new();
        for (sign, extra) in [(1.0, 0.1), (-1.0, 0.1), (0.0, 0.0)] {
            for i in 0..4 {
                let w = b[(3, i)].signum() * sign;
                let roll = if i == 1 {
                    extra
                } else if i == 3 {
                    -extra
                } else {
                    0.0
                };
                rows.push(
                    if w > 0.0 {
                        7.0
                    } else if w < 0.0 {
                        2.0 * f - 6.125
                    } else {
                        f
                    } + roll,
                );
            }
        }
        let mut controller =
            OpenLoop::new(vec![0.0, 0.5, 1.0], DMatrix::from_row_slice(3, 4, &rows)).unwrap();
        let x0 = RigidBodyState::at_rest();
        let coarse = end_state(
            &vehicle,
            &rotors_settled,
            &mut controller,
            &[],
            x0,
            &SimulationConfig::new(0.02, 1, 1.5),
        );
        let fine = end_state(
            &vehicle,
            &rotors_settled,
            &mut controller,
            &[],
            x0,
            &SimulationConfig::new(0.02, 40, 1.5),
        );
        let position = (coarse.position_m - fine.position_m).norm();
        let angle = coarse.attitude.angle_to(&fine.attitude);
        eprintln!(
            "manoeuvre: {position:e} m, {angle:e} rad, yaw {}",
            fine.euler_rad()[2]
        );
        assert!(
            position < 2e-4 && angle < 5e-4,
            "{position:e} m, {angle:e} rad"
        );
    }

    #[test]
    fn simulation_fault_acts_at_its_own_time_not_the_next_substep() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let g = airframe.gravity_m_s2();
        let mut actuators = instant_rotors(&airframe);
        let f = airframe.mass_kg() * g / 4.0;
        actuators.settle(&[f; 4]).unwrap();
        let mut controller = hover_schedule(&airframe);
        // Every rotor at half efficiency from 0.2501 s: the vehicle then falls at g / 2.
        let t_fault = 0.2501;
        let faults: Vec<RotorFault> = (0..4)
            .map(|rotor| RotorFault {
                rotor,
                time_s: t_fault,
                efficiency: 0.5,
            })
            .collect();
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &faults,
            RigidBodyState::at_rest(),
            &SimulationConfig::new(0.05, 1, 0.5),
        )
        .unwrap();
        for (k, t) in run.t_s.iter().enumerate() {
            let falling = (t - t_fault).max(0.0);
            let v = run.states[k].velocity_m_s.z;
            assert!((v - 0.5 * g * falling).abs() < 1e-12, "t = {t}: v = {v}");
            let z = run.states[k].position_m.z;
            assert!(
                (z - 0.25 * g * falling * falling).abs() < 1e-12,
                "t = {t}: z = {z}"
            );
        }
        // Health rows: full at 0.25 s, halved from the row after the fault (0.30 s).
        assert_eq!(&run.efficiency[5 * 4..6 * 4], &[1.0; 4]);
        assert_eq!(&run.efficiency[6 * 4..7 * 4], &[0.5; 4]);
        assert_eq!(run.thrust_n[6 * 4], 0.5 * f);
    }

    #[test]
    fn simulation_refuses_a_substep_too_long_for_the_spin_or_the_lag() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let mut controller = ZeroCommand { count: 4 };
        let spinning = RigidBodyState {
            omega_rad_s: Vector3::new(0.0, 0.0, 75.0),
            ..RigidBodyState::at_rest()
        };
        let err = simulate(
            &vehicle,
            instant_rotors(&airframe),
            &mut controller,
            &[1.0; 4],
            &[],
            spinning,
            &SimulationConfig::new(0.05, 1, 3.0),
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.starts_with("substeps: the RK4 substep h = dt / substeps = 0.05 s"),
            "{err}"
        );
        assert!(
            err.contains("|omega_0| = 75 rad/s") && err.contains("substeps >= 15"),
            "{err}"
        );
        // An actuator lag shorter than the substep.
        let err = simulate(
            &vehicle,
            lagged_rotors(&airframe, 0.02, f64::INFINITY),
            &mut controller,
            &[1.0; 4],
            &[],
            RigidBodyState::at_rest(),
            &SimulationConfig::new(0.02, 1, 1.0),
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("1 / time_constant = 50 1/s") && err.contains("substeps >= 4"),
            "{err}"
        );
    }

    #[test]
    fn simulation_torque_free_spin_keeps_its_wobble_at_an_accepted_step() {
        // r = 42 rad/s with a 3 rad/s wobble: dt = 0.05 with one substep used to damp the wobble
        // to 1.5e-4 rad/s in 3 s. The refused step names the fix; the accepted one conserves.
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let body = vehicle.body();
        let mut controller = ZeroCommand { count: 4 };
        let x0 = RigidBodyState {
            omega_rad_s: Vector3::new(3.0, 0.0, 42.0),
            ..RigidBodyState::at_rest()
        };
        let run = |substeps: usize, controller: &mut ZeroCommand| {
            let mut cfg = SimulationConfig::new(0.05, substeps, 3.0);
            cfg.limits.max_tilt_rad = f64::INFINITY;
            simulate(
                &vehicle,
                instant_rotors(&airframe),
                controller,
                &[1.0; 4],
                &[],
                x0,
                &cfg,
            )
        };
        let err = run(1, &mut controller).unwrap_err().to_string();
        assert!(err.contains("substeps >= 9"), "{err}");
        let run = run(9, &mut controller).unwrap();
        assert!(run.divergence.is_none(), "{:?}", run.divergence);
        let end = run.states.last().unwrap();
        let energy = body.rotational_energy_j(&x0);
        let drift = (body.rotational_energy_j(end) - energy).abs() / energy;
        let momentum = body.angular_momentum_world(&x0);
        let moved = (body.angular_momentum_world(end) - momentum).norm() / momentum.norm();
        assert!(
            drift < 1e-5 && moved < 1e-4,
            "energy {drift:e}, momentum {moved:e}"
        );
        // The wobble (transverse rate) stays of the size it started with, not damped away.
        let wobble = end.omega_rad_s.xy().norm();
        assert!(wobble > 2.0, "{wobble}");
    }

    /// Hover thrust plus `d` on the rotors that turn the vehicle to positive yaw, minus on the
    /// others: a pure yaw torque `4 k_mu d`.
    fn yaw_schedule(airframe: &Airframe, d: f64) -> OpenLoop {
        let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        let b = airframe.effectiveness_matrix();
        let row: Vec<f64> = (0..4).map(|i| f + d * b[(3, i)].signum()).collect();
        OpenLoop::new(vec![0.0], DMatrix::from_row_slice(1, 4, &row)).unwrap()
    }

    #[test]
    fn simulation_ends_with_a_step_size_divergence_when_rates_outgrow_the_substep() {
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let mut actuators = instant_rotors(&airframe);
        let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
        actuators.settle(&[f; 4]).unwrap();
        let mut controller = yaw_schedule(&airframe, 1.0);
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &[],
            RigidBodyState::at_rest(),
            &SimulationConfig::new(0.01, 1, 10.0),
        )
        .unwrap();
        let event = run.divergence.expect("the spin-up outgrows h = 0.01 s");
        assert_eq!(event.reason, DivergenceReason::StepSize);
        assert_eq!(event.reason.name(), "step-size");
        // r = (4 k_mu d / Jz) t reaches MAX_RATE_STEP / h = 25 rad/s at t = 25 Jz / (4 k_mu d).
        let jz = airframe.inertia_kg_m2()[2];
        let k_mu = airframe.drag_torque_ratio_m();
        let expected = 25.0 * jz / (4.0 * k_mu);
        assert!(
            (event.time_s - expected).abs() < 1e-9,
            "{} vs {expected}",
            event.time_s
        );
        assert!((event.state.omega_rad_s.z - 25.0).abs() < 1e-7);
    }

    #[test]
    fn simulation_locates_a_limit_crossing_within_the_substep() {
        // Rolling at 2 rad/s from level (free fall, no torque): tilt = 2 t reaches 90 degrees at
        // pi / 4 s. dt = 0.05 s used to report it at 0.80 s (at 91.7 degrees).
        let airframe = quad_x();
        let vehicle = still_air(&airframe);
        let mut controller = ZeroCommand { count: 4 };
        let x0 = RigidBodyState {
            omega_rad_s: Vector3::new(2.0, 0.0, 0.0),
            ..RigidBodyState::at_rest()
        };
        let mut cfg = SimulationConfig::new(0.05, 1, 2.0);
        cfg.record_every = 4;
        let run = simulate(
            &vehicle,
            instant_rotors(&airframe),
            &mut controller,
            &[1.0; 4],
            &[],
            x0,
            &cfg,
        )
        .unwrap();
        let event = run.divergence.unwrap();
        assert_eq!(event.reason, DivergenceReason::Tilt);
        let quarter = std::f64::consts::FRAC_PI_4;
        assert!((event.time_s - quarter).abs() < 1e-7, "{}", event.time_s);
        let tilt = event.state.primary_axis().z.acos();
        assert!((tilt - std::f64::consts::FRAC_PI_2).abs() < 2e-7, "{tilt}");
        // Thinned recording: rows at 0, 0.2, 0.4, 0.6, then the crossing at its own time.
        assert_eq!(run.t_s.len(), 5, "{:?}", run.t_s);
        assert_eq!(*run.t_s.last().unwrap(), event.time_s);
        assert_eq!(*run.states.last().unwrap(), event.state);
        assert!(run.commands[4 * 4..].iter().all(|c| c.is_nan()));
        // A body rate that grows through its limit inside a substep.
        let mut cfg = SimulationConfig::new(0.05, 1, 60.0);
        cfg.limits.max_rate_rad_s = 0.3;
        let mut controller = yaw_schedule(&airframe, 0.01);
        let mut actuators = instant_rotors(&airframe);
        actuators.settle(&[3.76; 4]).unwrap();
        let run = simulate(
            &vehicle,
            actuators,
            &mut controller,
            &[1.0; 4],
            &[],
            RigidBodyState::at_rest(),
            &cfg,
        )
        .unwrap();
        let event = run.divergence.unwrap();
        assert_eq!(event.reason, DivergenceReason::BodyRate);
        let expected =
            0.3 * airframe.inertia_kg_m2()[2] / (4.0 * airframe.drag_torque_ratio_m() * 0.01);
        assert!(
            (event.time_s - expected).abs() < 1e-9,
            "{} vs {expected}",
            event.time_s
        );
    }
}
