//! A run's timing, limits, ground, wind, noise and sensing ([`SimulationConfig`]), checked before any
//! work: the control steps it takes, when, and what is recorded.

use nalgebra::Vector3;

use crate::error::{require_finite, require_scale, Result, RfError};
use crate::flight::simulation::divergence::DivergenceLimits;
use crate::flight::simulation::noise::SensorNoise;
use crate::flight::simulation::recording::records;
use crate::flight::simulation::sensing::Sensing;
use crate::state::RigidBodyState;

/// Most control steps one run records (about 2 GB of trajectory).
pub const MAX_CONTROL_STEPS: usize = 10_000_000;
/// Most RK4 steps one run takes (a few minutes on one core).
pub const MAX_RK4_STEPS: usize = 1_000_000_000;

/// Most RK4 substeps per control period. The run checks for cancellation once per control period
/// (`driver`), so this bounds the work between two checks: 10,000 substeps of the largest
/// vehicle take well under 100 ms. A step-size guard that asks for more means dt_s is too long.
pub const MAX_SUBSTEPS: usize = 10_000;

/// Relative tolerance below which `duration / dt` counts as a whole number of control steps.
const WHOLE_STEPS_RTOL: f64 = 1e-9;

/// Where the ground is by default: the plane z = 0 of the world frame (NED), so a scenario states
/// its altitudes as heights above the ground (`position[2] = -10`: 10 m up).
pub const DEFAULT_GROUND_Z_M: f64 = 0.0;

/// Timing, limits, ground and wind of a run.
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
    /// The ground plane: world NED `z = ground_z_m` (default [`DEFAULT_GROUND_Z_M`]); `None`: no
    /// ground. The vehicle's centre of mass below it (`position[2] > ground_z_m`) is contact,
    /// which ends the run as [`crate::flight::simulation::DivergenceKind::Crashed`] at the
    /// located time. There is no ground reaction (no landing, no take-off): a run must start above
    /// the ground. The vehicle's extent below its centre of mass (landing gear, a tilted arm) is
    /// not modelled; raise the plane by it (`ground_z_m - extent`) to count it.
    pub ground_z_m: Option<f64>,
    /// Constant wind, world NED, m/s.
    pub wind_m_s: Vector3<f64>,
    /// Optional wind profile added to the constant: piecewise-linear through `(time_s, wind)`
    /// points, held constant outside them; a time given twice is a step (the first value before
    /// it, the second from it on; the integration ends an RK4 step there, like a fault).
    pub wind_profile: Vec<(f64, Vector3<f64>)>,
    /// Sensor noise on what the controller sees (`None`: the true state): the papers' noise.
    pub noise: Option<SensorNoise>,
    /// Sensors and the estimator: the controller flies on the estimate (`None`: on the true
    /// state, or on `noise`; a run has at most one of the two).
    pub sensing: Option<Sensing>,
    /// Record every this many control steps (1: all). The first and last steps and a divergence
    /// are always recorded; large batches use it to keep memory bounded.
    pub record_every: usize,
}

/// The Python `Simulator`'s defaults: Ke's 400 Hz control rate with 4 RK4 substeps, a 10 s run.
impl Default for SimulationConfig {
    fn default() -> Self {
        SimulationConfig::new(1.0 / 400.0, 4, 10.0)
    }
}

impl SimulationConfig {
    /// A run of `duration_s` at control period `dt_s` with `substeps` RK4 steps per
    /// period, default limits, the ground at [`DEFAULT_GROUND_Z_M`], no wind, no noise.
    pub fn new(dt_s: f64, substeps: usize, duration_s: f64) -> Self {
        SimulationConfig {
            dt_s,
            substeps,
            duration_s,
            limits: DivergenceLimits::default(),
            ground_z_m: Some(DEFAULT_GROUND_Z_M),
            wind_m_s: Vector3::zeros(),
            wind_profile: Vec::new(),
            noise: None,
            sensing: None,
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
        require_scale("dt_s", self.dt_s, "s")?;
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
                    "duration_s / dt_s = {steps:.3e} control steps exceed the limit of {MAX_CONTROL_STEPS} \
                     (every step is recorded): shorten the run or lengthen dt"
                ),
            ));
        }
        if steps * self.substeps as f64 > MAX_RK4_STEPS as f64 {
            return Err(RfError::invalid(
                "substeps",
                format!(
                    "{steps:.3e} control steps x {} substeps exceed the limit of {MAX_RK4_STEPS} RK4 steps per run",
                    self.substeps
                ),
            ));
        }
        // Only a run that integrates anything has periods to bound (a zero-length run checks
        // the other settings).
        if steps >= 1.0 && self.substeps > MAX_SUBSTEPS {
            return Err(RfError::invalid(
                "substeps",
                format!(
                    "must be at most {MAX_SUBSTEPS} RK4 steps per control period, got {} (a \
                     finer integration needs a shorter dt_s)",
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
        if let Some(z) = self.ground_z_m {
            if !z.is_finite() {
                return Err(RfError::invalid(
                    "ground_z_m",
                    format!("must be finite (no ground: turn it off), got {z}"),
                ));
            }
        }
        for (i, w) in self.wind_m_s.iter().enumerate() {
            require_finite(&format!("wind[{i}]"), *w)?;
        }
        if let Some(noise) = &self.noise {
            noise.check()?;
        }
        if let Some(sensing) = &self.sensing {
            if self.noise.is_some() {
                return Err(RfError::invalid(
                    "noise, sensing",
                    "a run flies on one of them: the papers' relative noise on the state (noise) \
                     or sensors with the estimator (sensing)",
                ));
            }
            sensing.check()?;
        }
        for (k, (t, w)) in self.wind_profile.iter().enumerate() {
            require_finite(&format!("wind_profile[{k}].time"), *t)?;
            if w.iter().any(|v| !v.is_finite()) {
                return Err(RfError::invalid(
                    format!("wind_profile[{k}]"),
                    "must be finite",
                ));
            }
            // A time given twice is a step (the later point holds from then); three points at
            // one time would leave the value there ambiguous.
            if k > 0 && *t < self.wind_profile[k - 1].0 {
                return Err(RfError::invalid(
                    format!("wind_profile[{k}].time"),
                    "times must not decrease (a time given twice is a step)",
                ));
            }
            if k > 1 && *t == self.wind_profile[k - 1].0 && *t == self.wind_profile[k - 2].0 {
                return Err(RfError::invalid(
                    format!("wind_profile[{k}].time"),
                    "a time may be given at most twice (a step: the value before and after)",
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
    /// (bit-identical to its [`crate::flight::simulation::Trajectory::t_s`]), the last exactly `duration_s`. A run that
    /// diverges records a prefix of it and then its divergence row at the located time.
    pub fn record_times(&self) -> Vec<f64> {
        let steps = self.steps();
        (0..=steps)
            .filter(|&k| records(k, self.record_every, steps))
            .map(|k| self.step_time(k))
            .collect()
    }

    /// Refuses a start (`field`, e.g. `x0`) on or below the ground: without a ground reaction
    /// the vehicle would sink into it at once.
    pub fn check_start(&self, field: &str, x0: &RigidBodyState) -> Result<()> {
        match self.ground_z_m {
            Some(ground) if x0.position_m.z >= ground => Err(RfError::invalid(
                format!("{field}.position[2]"),
                format!(
                    "the run starts on or below the ground: z = {} m (NED, down) is not above \
                     ground_z_m = {ground} m; start in the air (z < {ground}, e.g. {} for 10 m up) \
                     or fly without a ground",
                    x0.position_m.z,
                    ground - 10.0
                ),
            )),
            _ => Ok(()),
        }
    }

    /// Wind at time `t_s` (world, m/s): the profile interpolated linearly, a step (a time given
    /// twice) taking its later value from its time on.
    pub fn wind_at(&self, t_s: f64) -> Vector3<f64> {
        self.wind_m_s + self.profile_at(|t| t > t_s, t_s)
    }

    /// Wind just before `t_s` (the left limit: a step at `t_s` has not happened yet). An RK4
    /// step ending at a step's time evaluates its last stage here, so the step acts from
    /// exactly its time on.
    pub fn wind_before(&self, t_s: f64) -> Vector3<f64> {
        self.wind_m_s + self.profile_at(|t| t >= t_s, t_s)
    }

    /// The profile at `t_s` between the last point before the first that `after` picks and it.
    fn profile_at(&self, after: impl Fn(f64) -> bool, t_s: f64) -> Vector3<f64> {
        let p = &self.wind_profile;
        match p.iter().position(|(t, _)| after(*t)) {
            _ if p.is_empty() => Vector3::zeros(),
            Some(0) => p[0].1,
            None => p[p.len() - 1].1,
            Some(k) => {
                let ((t0, w0), (t1, w1)) = (p[k - 1], p[k]);
                // t0 < t1 here: a step's two points are never on both sides of t_s.
                w0 + (w1 - w0) * ((t_s - t0) / (t1 - t0))
            }
        }
    }

    /// The end of an RK4 step from `from_s` towards `to_s`: `to_s`, or the first wind step
    /// strictly between them (the integration must not carry a step inside a stage).
    pub fn wind_step_before(&self, from_s: f64, to_s: f64) -> f64 {
        self.wind_profile
            .windows(2)
            .map(|w| w[0].0)
            .zip(self.wind_profile.windows(2).map(|w| w[1].0))
            .filter(|(a, b)| a == b)
            .map(|(a, _)| a)
            .find(|&t| t > from_s && t < to_s)
            .unwrap_or(to_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wind_profile_is_piecewise_linear() {
        let mut c = SimulationConfig::new(0.0025, 2, 1.0);
        c.wind_m_s = Vector3::new(1.0, 0.0, 0.0);
        c.wind_profile = vec![(1.0, Vector3::zeros()), (2.0, Vector3::new(0.0, 4.0, 0.0))];
        assert_eq!(c.wind_at(0.0), Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(c.wind_at(1.5), Vector3::new(1.0, 2.0, 0.0));
        assert_eq!(c.wind_at(5.0), Vector3::new(1.0, 4.0, 0.0));
    }

    #[test]
    fn a_time_given_twice_is_a_step() {
        let mut c = SimulationConfig::new(0.0025, 2, 3.0);
        let w = Vector3::new(4.0, 4.0, 0.0);
        c.wind_profile = vec![(1.0, Vector3::zeros()), (1.0, w)];
        c.check().unwrap();
        assert_eq!(c.wind_at(0.999_999), Vector3::zeros());
        assert_eq!(c.wind_at(1.0), w);
        assert_eq!(c.wind_before(1.0), Vector3::zeros());
        assert_eq!(c.wind_before(1.000_001), w);
        assert_eq!(c.wind_at(2.0), w);
        assert_eq!(c.wind_step_before(0.9, 1.1), 1.0);
        assert_eq!(
            c.wind_step_before(1.0, 1.1),
            1.1,
            "a step at the start does not split"
        );
        assert_eq!(c.wind_step_before(0.9, 1.0), 1.0);
        c.wind_profile.push((1.0, Vector3::zeros()));
        let err = c.check().unwrap_err().to_string();
        assert!(err.starts_with("wind_profile[2].time"), "{err}");
        c.wind_profile = vec![(1.0, Vector3::zeros()), (0.5, w)];
        let err = c.check().unwrap_err().to_string();
        assert!(err.contains("must not decrease"), "{err}");
    }
}
