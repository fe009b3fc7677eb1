//! The closed loop: controller at its own rate (zero-order hold), actuators and rigid body
//! integrated with `substeps` RK4 steps per control period, rotor faults on a schedule the
//! controller never sees, and divergence detection that ends a run with an event instead of a
//! panic or a hang.
//!
//! Per control step k (t = k dt): record the state, check divergence, let the controller compute
//! commands from the measured state, then `substeps` times: apply the faults due by then, advance
//! the actuators (see [`crate::flight::actuator`]) and take one RK4 step of the rigid body with the rotor
//! outputs held.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::flight::actuator::{Actuators, RotorOutput};
use crate::control::Controller;
use crate::state::{state_from_vector, state_vector, STATE_DIM};
use crate::error::{require_finite, Result, RfError};
use crate::state::RigidBodyState;
use crate::flight::vehicle::Vehicle;

/// Most control steps one run records (about 2 GB of trajectory).
pub const MAX_CONTROL_STEPS: usize = 10_000_000;
/// Most RK4 steps one run takes (a few minutes on one core).
pub const MAX_RK4_STEPS: usize = 1_000_000_000;

/// Rotor `rotor` (0-based) has efficiency `efficiency` from `time_s` on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorFault {
    pub rotor: usize,
    pub time_s: f64,
    pub efficiency: f64,
}

/// Limits past which a run is declared diverged.
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
}

impl DivergenceReason {
    /// A short identifier (`"tilt"`, `"non_finite_command"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            DivergenceReason::NonFinite => "non_finite_state",
            DivergenceReason::NonFiniteCommand => "non_finite_command",
            DivergenceReason::Tilt => "tilt",
            DivergenceReason::AltitudeLoss => "altitude_loss",
            DivergenceReason::Speed => "speed",
            DivergenceReason::BodyRate => "body_rate",
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
        }
    }
}

/// A run that ended early: when, why, and the state at that moment.
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
    pub control_dt_s: f64,
    /// RK4 steps per control period.
    pub substeps: usize,
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
    /// A run of `duration_s` at control period `control_dt_s` with `substeps` RK4 steps per
    /// period, default limits, no wind, no noise.
    pub fn new(control_dt_s: f64, substeps: usize, duration_s: f64) -> Self {
        SimulationConfig {
            control_dt_s,
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
        if !(self.control_dt_s.is_finite() && self.control_dt_s > 0.0) {
            return Err(RfError::invalid(
                "dt",
                format!("must be > 0 and finite, got {}", self.control_dt_s),
            ));
        }
        if self.record_every == 0 {
            return Err(RfError::invalid("record_every", "must be >= 1"));
        }
        if self.substeps == 0 {
            return Err(RfError::invalid("substeps", "must be >= 1"));
        }
        require_finite("t_final", self.duration_s)?;
        if self.duration_s < 0.0 {
            return Err(RfError::invalid(
                "t_final",
                format!("must be >= 0, got {}", self.duration_s),
            ));
        }
        // Bound memory (every control step is recorded) and work (no run takes hours).
        let steps = (self.duration_s / self.control_dt_s).round();
        if steps > MAX_CONTROL_STEPS as f64 {
            return Err(RfError::invalid(
                "t_final, dt",
                format!(
                    "t_final / dt = {steps} control steps exceed the limit of {MAX_CONTROL_STEPS} \
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

    /// Number of control steps in the run.
    pub fn steps(&self) -> usize {
        (self.duration_s / self.control_dt_s).round() as usize
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

/// Everything recorded at the control rate. Arrays are row-major, one row per control step.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    pub t_s: Vec<f64>,
    pub states: Vec<RigidBodyState>,
    /// Commands applied from this step on (`command_count` per row).
    pub commands: Vec<f64>,
    /// Thrust each rotor produces at this step, after health (m per row), N.
    pub thrust_n: Vec<f64>,
    /// Health of each rotor at this step (m per row).
    pub health: Vec<f64>,
    /// What the controller saw with sensor noise: the 12-element state vector (12 per row);
    /// empty without noise (the controller then saw exactly `states`).
    pub measured: Vec<f64>,
    pub divergence: Option<Divergence>,
}

impl Trajectory {
    /// Records one control step's time, state, health, rotor thrusts and (with sensor noise)
    /// measurement row; the caller adds the commands.
    fn push_step(
        &mut self,
        t_s: f64,
        state: &RigidBodyState,
        health: &[f64],
        actuators: &Actuators,
        measured: Option<&[f64; STATE_DIM]>,
    ) {
        self.t_s.push(t_s);
        self.states.push(*state);
        self.health.extend_from_slice(health);
        self.thrust_n
            .extend((0..health.len()).map(|i| actuators.output(i, health[i]).thrust_n));
        if let Some(row) = measured {
            self.measured.extend_from_slice(row);
        }
    }
}

fn check_faults(faults: &[RotorFault], rotor_count: usize) -> Result<()> {
    for (k, f) in faults.iter().enumerate() {
        if f.rotor >= rotor_count {
            return Err(RfError::invalid(
                format!("faults[{k}].rotor"),
                format!(
                    "rotor numbers run from 1 to {rotor_count}, got {}",
                    f.rotor + 1
                ),
            ));
        }
        require_finite(&format!("faults[{k}].time"), f.time_s)?;
        require_finite(&format!("faults[{k}].efficiency"), f.efficiency)?;
        if !(0.0..=1.0).contains(&f.efficiency) {
            return Err(RfError::invalid(
                format!("faults[{k}].efficiency"),
                format!("must lie in [0, 1], got {}", f.efficiency),
            ));
        }
    }
    Ok(())
}

fn divergence(
    state: &RigidBodyState,
    start_altitude_m: f64,
    limits: &DivergenceLimits,
) -> Option<DivergenceReason> {
    if !state.is_finite() {
        return Some(DivergenceReason::NonFinite);
    }
    // Tilt: angle between body z and world z; n3z = cos(tilt).
    if state.primary_axis().z.clamp(-1.0, 1.0).acos() > limits.max_tilt_rad {
        return Some(DivergenceReason::Tilt);
    }
    if start_altitude_m - (-state.position_m.z) > limits.max_altitude_loss_m {
        return Some(DivergenceReason::AltitudeLoss);
    }
    if state.velocity_m_s.norm() > limits.max_speed_m_s {
        return Some(DivergenceReason::Speed);
    }
    if state.omega_rad_s.norm() > limits.max_rate_rad_s {
        return Some(DivergenceReason::BodyRate);
    }
    None
}

/// One closed-loop run. `actuators` is the initial actuator state (settle it to the trim first
/// for a trimmed start); `health` the initial rotor health. Faults may come in any order.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    vehicle: &Vehicle,
    mut actuators: Actuators,
    controller: &mut dyn Controller,
    initial_health: &[f64],
    faults: &[RotorFault],
    x0: RigidBodyState,
    config: &SimulationConfig,
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
    crate::airframe::check_efficiency("health", initial_health, m)?;
    check_faults(faults, m)?;
    if !x0.is_finite() {
        return Err(RfError::invalid("x0", "must be finite"));
    }
    let mut faults = faults.to_vec();
    faults.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut next_fault = 0;

    let steps = config.steps();
    let h = config.control_dt_s / config.substeps as f64;
    let every = config.record_every;
    let rows = steps / every + 2;
    let mut trajectory = Trajectory {
        t_s: Vec::with_capacity(rows),
        states: Vec::with_capacity(rows),
        commands: Vec::with_capacity(rows * count),
        thrust_n: Vec::with_capacity(rows * m),
        health: Vec::with_capacity(rows * m),
        measured: Vec::with_capacity(if config.noise.is_some() {
            rows * STATE_DIM
        } else {
            0
        }),
        divergence: None,
    };
    controller.reset();
    let mut health = initial_health.to_vec();
    let mut outputs = vec![RotorOutput::default(); m];
    let mut command = vec![0.0; count];
    let mut state = x0;
    let start_altitude = -x0.position_m.z;
    let body = vehicle.body();
    let mut gaussian = config.noise.map(|n| Gaussian::new(n.seed));
    let mut measured_vector = [0.0; STATE_DIM];
    for k in 0..=steps {
        let t = k as f64 * config.control_dt_s;
        while next_fault < faults.len() && faults[next_fault].time_s <= t {
            health[faults[next_fault].rotor] = faults[next_fault].efficiency;
            next_fault += 1;
        }
        if let Some(reason) = divergence(&state, start_altitude, &config.limits) {
            let nan_row = [f64::NAN; STATE_DIM];
            trajectory.push_step(
                t,
                &state,
                &health,
                &actuators,
                config.noise.map(|_| &nan_row),
            );
            trajectory
                .commands
                .extend(std::iter::repeat_n(f64::NAN, count));
            trajectory.divergence = Some(Divergence {
                time_s: t,
                reason,
                state,
            });
            break;
        }
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
        controller.command(t, &measured, &mut command)?;
        let finite = command.iter().all(|c| c.is_finite());
        // Every `every`-th step, the last one, and a step whose command ends the run.
        if k % every == 0 || k == steps || !finite {
            let row = config.noise.map(|_| &measured_vector);
            trajectory.push_step(t, &state, &health, &actuators, row);
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
        for s in 0..config.substeps {
            let t_sub = t + s as f64 * h;
            while next_fault < faults.len() && faults[next_fault].time_s <= t_sub {
                health[faults[next_fault].rotor] = faults[next_fault].efficiency;
                next_fault += 1;
            }
            actuators.advance(&command, h);
            for (i, out) in outputs.iter_mut().enumerate() {
                *out = actuators.output(i, health[i]);
            }
            state = body.rk4_step(t_sub, &state, h, |tau, x| {
                vehicle.wrench(x, &outputs, &config.wind_at(tau))
            });
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
    initial_health: &[f64],
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
                initial_health,
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
    use crate::flight::actuator::{FixedPitch, Lag};
    use crate::airframe::Airframe;
    use crate::control::{OpenLoop, ZeroCommand};
    use crate::flight::vehicle::Aerodynamics;
    use nalgebra::DMatrix;

    fn quad_x() -> Airframe {
        crate::fixtures::preset("quad-x")
    }

    fn still_air(airframe: &Airframe) -> Vehicle {
        Vehicle::new(airframe, Aerodynamics::default()).unwrap()
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
        // 20 m of free fall take sqrt(40 / g) s; detected at the next control step.
        let expected = (40.0 / g).sqrt();
        assert!(
            event.time_s >= expected && event.time_s < expected + 0.0025 + 1e-12,
            "{}",
            event.time_s
        );
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
        assert_eq!(run.health[row(0.5)], 1.0);
        assert_eq!(run.health[row(1.2)], 0.0);
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
        c.control_dt_s = 0.0;
        assert!(run(&c, &[], &mut controller).starts_with("dt: must be > 0"));
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
}
