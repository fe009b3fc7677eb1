//! The estimator: the error-state filter run on a delayed fusion horizon, with an output
//! predictor that carries its state to the newest IMU sample (module docs of
//! [`crate::flight::estimation`]).

use std::collections::VecDeque;

use nalgebra::{UnitQuaternion, Vector3};

use crate::error::{Result, RfError};
use crate::flight::estimation::eskf::{
    exp_quaternion, propagate_covariance, reset_covariance, skew, update_block, Block, Covariance,
    Fusion, Inputs, Kinematics, NominalState, ProcessNoise, Step, ACCEL_BIAS, ATT, GYRO_BIAS, POS,
    VEL,
};
use crate::flight::estimation::EstimatorSettings;
use crate::flight::sensors::clock::PERIOD_TOLERANCE;
use crate::flight::sensors::{ImuSample, MagnetometerSample, PositionSample};
use crate::state::RigidBodyState;

/// What a controller may use at the newest IMU sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub time_s: f64,
    /// Position, velocity and attitude of the output predictor; `omega_rad_s` is the
    /// bias-corrected gyro (low-passed when `gyro_cutoff_hz` is set).
    pub state: RigidBodyState,
    /// The newest gyro sample, bias-corrected, unfiltered, rad/s.
    pub gyro_rad_s: Vector3<f64>,
    /// The newest accelerometer sample, bias-corrected and moved to the centre of mass (the
    /// `omega x (omega x r)` of the IMU's lever arm removed), m/s^2: the specific force.
    pub accel_m_s2: Vector3<f64>,
    /// The newest IMU sample was clamped at the gyro's (accelerometer's) range.
    pub gyro_saturated: bool,
    pub accel_saturated: bool,
}

impl Estimate {
    /// The estimate carried to the control step at `t_s` with its sample held (the output
    /// predictor's own step: rotation by the bias-corrected rate, velocity and position by the
    /// specific force plus gravity `gravity_m_s2`, down): at 30 rad/s and 500 Hz the sample is
    /// up to 2 ms, 3.4 degrees of yaw, old. Unchanged for a time not after its own.
    pub(crate) fn carried(mut self, gravity_m_s2: f64, t_s: f64) -> Estimate {
        let dt = t_s - self.time_s;
        if dt > 0.0 {
            let s = &mut self.state;
            let gravity = Vector3::new(0.0, 0.0, gravity_m_s2);
            let acceleration = s.attitude * self.accel_m_s2 + gravity;
            s.position_m += (s.velocity_m_s + acceleration * (0.5 * dt)) * dt;
            s.velocity_m_s += acceleration * dt;
            s.attitude *= exp_quaternion(&(s.omega_rad_s * dt));
            s.attitude.renormalize_fast();
            self.time_s = t_s;
        }
        self
    }
}

/// Measurements fused, refused by the innovation gate, dropped as late (valid before the
/// fusion horizon when they arrived), and position fixes left out by the fusion-rate limit
/// (`EstimatorSettings::position_fusion_period_s`; each counts its position, velocity and
/// attitude once).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FusionCounts {
    pub fused: u64,
    pub rejected: u64,
    pub late: u64,
    pub thinned: u64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Measurement {
    Position(Vector3<f64>),
    Velocity(Vector3<f64>),
    Attitude(UnitQuaternion<f64>),
    Magnetometer(Vector3<f64>),
}

/// A measurement waiting for the fusion horizon to reach its time of validity (`M`: the
/// scalar estimator's measurement, or the lanes' of every lane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pending<M> {
    pub valid_at_s: f64,
    pub measurement: M,
}

/// Queues `measurement` in `pending`, kept in order of validity (after those valid at the same
/// time: they are fused in the order they came).
pub(crate) fn queue<M>(pending: &mut VecDeque<Pending<M>>, valid_at_s: f64, measurement: M) {
    let at = pending
        .iter()
        .rposition(|p| p.valid_at_s <= valid_at_s)
        .map_or(0, |i| i + 1);
    pending.insert(
        at,
        Pending {
            valid_at_s,
            measurement,
        },
    );
}

/// A time within this of another counts as the same time, s.
pub(crate) const TIME_EPS_S: f64 = 1e-9;

/// One step of the output predictor's chain to a buffered sample: the state there, the step's
/// linearisation and the inputs at its end (what `NominalState::propagate_from` returns).
#[derive(Debug, Clone, Copy)]
struct ChainStep {
    state: NominalState,
    step: Step,
    end: Inputs,
}

#[derive(Debug, Clone)]
pub struct Estimator {
    settings: EstimatorSettings,
    kinematics: Kinematics,
    // The fusion horizon: state, covariance, time and the IMU sample at (or just before) it.
    horizon: NominalState,
    covariance: Covariance,
    horizon_time_s: f64,
    horizon_sample: Option<ImuSample>,
    /// The horizon state's inputs at the horizon time, from the step that reached it (`None`
    /// after a fusion changed the state): the next step starts from them.
    horizon_inputs: Option<Inputs>,
    /// Steps since `covariance_time_s` not yet applied to the covariance.
    block: Option<Block>,
    covariance_time_s: f64,
    rate_mean: Vector3<f64>,
    force_mean: Vector3<f64>,
    /// Axes clamped at the range in the horizon's current sample (gyro, accelerometer).
    gyro_clamped: [bool; 3],
    accel_clamped: [bool; 3],
    // Samples after the horizon, oldest first; measurements waiting for it, by validity time.
    buffer: VecDeque<ImuSample>,
    pending: VecDeque<Pending<Measurement>>,
    /// The output predictor's steps to the buffered samples (`trail[i]` reaches `buffer[i]`),
    /// kept while `trail_follows_horizon`: the output chain then starts from the horizon's own
    /// state, inputs and sample, so the horizon's step to the next sample is the chain's first
    /// step, the same function of the same values (bit for bit), and is taken from it instead of
    /// being computed again. A step of the horizon that is not a whole interval (to a
    /// measurement's time of validity) or a fused correction ends the following; a replay of the
    /// output from the horizon starts it again.
    trail: VecDeque<ChainStep>,
    trail_follows_horizon: bool,
    /// `false` only where a test checks that taking the horizon's steps from the trail changes
    /// nothing.
    reuse_trail: bool,
    /// Horizon steps taken from the trail (for the test that they are taken).
    #[cfg(test)]
    pub(crate) chained_steps: u64,
    // The output predictor at the newest sample.
    output: NominalState,
    /// The output state's inputs at the newest sample (as `horizon_inputs`).
    output_inputs: Option<Inputs>,
    newest: Option<ImuSample>,
    gyro_filtered: Vector3<f64>,
    counts: FusionCounts,
    saturated_samples: u64,
    /// The fusion slot (`position_fusion_period_s`) of the newest position fix taken.
    fix_slot: f64,
}

impl Estimator {
    /// An estimator starting from `initial` (its biases zero), with the settings' initial
    /// uncertainty; `initial` is taken as valid at the first IMU sample.
    pub fn new(settings: EstimatorSettings, initial: &RigidBodyState) -> Result<Self> {
        settings.check()?;
        if !initial.is_finite() {
            return Err(RfError::invalid("initial", "must be finite"));
        }
        let start = NominalState {
            position_m: initial.position_m,
            velocity_m_s: initial.velocity_m_s,
            attitude: initial.attitude,
            gyro_bias_rad_s: Vector3::zeros(),
            accel_bias_m_s2: Vector3::zeros(),
        };
        let s = &settings;
        let mut covariance = Covariance::zeros();
        let variances = [
            (POS, s.initial_position_std_m),
            (VEL, s.initial_velocity_std_m_s),
            (ATT, s.initial_attitude_std_rad),
            (GYRO_BIAS, s.initial_gyro_bias_std_rad_s),
            (ACCEL_BIAS, s.initial_accel_bias_std_m_s2),
        ];
        for (block, std) in variances {
            for i in 0..3 {
                covariance[(block + i, block + i)] = std * std;
            }
        }
        Ok(Estimator {
            kinematics: Kinematics {
                gravity_m_s2: Vector3::new(0.0, 0.0, settings.gravity_m_s2),
                imu_position_m: settings.imu_position_m,
            },
            settings,
            horizon: start,
            covariance,
            horizon_time_s: f64::NAN,
            horizon_sample: None,
            horizon_inputs: None,
            block: None,
            covariance_time_s: f64::NAN,
            rate_mean: Vector3::zeros(),
            force_mean: Vector3::zeros(),
            gyro_clamped: [false; 3],
            accel_clamped: [false; 3],
            buffer: VecDeque::new(),
            pending: VecDeque::new(),
            trail: VecDeque::new(),
            trail_follows_horizon: true,
            reuse_trail: true,
            #[cfg(test)]
            chained_steps: 0,
            output: start,
            output_inputs: None,
            newest: None,
            gyro_filtered: Vector3::zeros(),
            counts: FusionCounts::default(),
            saturated_samples: 0,
            fix_slot: f64::NAN,
        })
    }

    pub fn settings(&self) -> &EstimatorSettings {
        &self.settings
    }

    /// Takes the next IMU sample: the horizon advances to `sample.time_s - fusion_delay_s`,
    /// fusing every waiting measurement at its time of validity on the way, and the output
    /// predictor moves to `sample.time_s`.
    pub fn push_imu(&mut self, sample: &ImuSample) -> Result<()> {
        if let Some(newest) = &self.newest {
            if sample.time_s.is_nan() || sample.time_s <= newest.time_s {
                return Err(RfError::invalid(
                    "imu.time_s",
                    format!(
                        "samples must come in increasing time, got {} after {}",
                        sample.time_s, newest.time_s
                    ),
                ));
            }
        }
        if sample.gyro_saturated || sample.accel_saturated {
            self.saturated_samples += 1;
        }
        let Some(previous) = self.newest else {
            self.start(sample);
            return Ok(());
        };
        self.newest = Some(*sample);
        self.buffer.push_back(*sample);
        let corrected = self.advance_horizon(sample.time_s - self.settings.fusion_delay_s);
        if corrected || self.buffer.is_empty() {
            self.replay_output();
        } else {
            let (output, step, end) = self.output.propagate_from(
                self.output_inputs.as_ref(),
                &previous,
                sample,
                previous.time_s,
                sample.time_s,
                &self.kinematics,
            );
            self.output = output;
            self.output_inputs = Some(end);
            if self.trail_follows_horizon {
                self.trail.push_back(ChainStep {
                    state: output,
                    step,
                    end,
                });
            }
        }
        self.filter_gyro(sample, sample.time_s - previous.time_s);
        Ok(())
    }

    /// Queues a position source's measurement (position, and velocity and attitude where it has
    /// them) for fusion at its time of validity, unless a fix of the same fusion slot was taken
    /// (`position_fusion_period_s`: then it is counted as thinned).
    pub fn push_position(&mut self, sample: &PositionSample) {
        let period = self.settings.position_fusion_period_s;
        if period > 0.0 {
            let slot = fusion_slot(sample.valid_at_s, period);
            if slot == self.fix_slot {
                // Counted per measurement, as `fused`, `rejected` and `late` are.
                self.counts.thinned += 1
                    + u64::from(sample.velocity_m_s.is_some())
                    + u64::from(sample.attitude.is_some());
                return;
            }
            self.fix_slot = slot;
        }
        self.queue(sample.valid_at_s, Measurement::Position(sample.position_m));
        if let Some(v) = sample.velocity_m_s {
            self.queue(sample.valid_at_s, Measurement::Velocity(v));
        }
        if let Some(q) = sample.attitude {
            self.queue(sample.valid_at_s, Measurement::Attitude(q));
        }
    }

    pub fn push_magnetometer(&mut self, sample: &MagnetometerSample) {
        self.queue(sample.time_s, Measurement::Magnetometer(sample.field_ut));
    }

    /// The estimate at the newest IMU sample (the initial state before the first).
    pub fn estimate(&self) -> Estimate {
        let (time_s, gyro_rad_s, accel_m_s2, gyro_saturated, accel_saturated) = match &self.newest {
            Some(s) => {
                let rate = s.gyro_rad_s - self.output.gyro_bias_rad_s;
                let r = &self.kinematics.imu_position_m;
                (
                    s.time_s,
                    rate,
                    s.accel_m_s2 - self.output.accel_bias_m_s2 - rate.cross(&rate.cross(r)),
                    s.gyro_saturated,
                    s.accel_saturated,
                )
            }
            None => (f64::NAN, Vector3::zeros(), Vector3::zeros(), false, false),
        };
        Estimate {
            time_s,
            state: RigidBodyState {
                position_m: self.output.position_m,
                velocity_m_s: self.output.velocity_m_s,
                attitude: self.output.attitude,
                omega_rad_s: self.gyro_filtered,
            },
            gyro_rad_s,
            accel_m_s2,
            gyro_saturated,
            accel_saturated,
        }
    }

    /// The filter's state at the fusion horizon (with the biases).
    pub fn horizon_state(&self) -> &NominalState {
        &self.horizon
    }

    /// The time of the fusion horizon, s (NaN before the first IMU sample).
    pub fn horizon_time_s(&self) -> f64 {
        self.horizon_time_s
    }

    /// The error covariance, `[dp, dv, dtheta, dbg, dba]`, at [`Estimator::covariance_time_s`]:
    /// the fusion horizon, or up to `covariance_period_s` before it (the covariance is
    /// propagated in blocks, and always up to the horizon before a measurement is fused).
    pub fn covariance(&self) -> &Covariance {
        &self.covariance
    }

    pub fn covariance_time_s(&self) -> f64 {
        self.covariance_time_s
    }

    /// The error covariance propagated up to the fusion horizon.
    pub fn covariance_at_horizon(&mut self) -> &Covariance {
        self.flush_covariance();
        &self.covariance
    }

    pub fn counts(&self) -> FusionCounts {
        self.counts
    }

    /// IMU samples so far with the gyroscope or accelerometer saturated.
    pub fn saturated_samples(&self) -> u64 {
        self.saturated_samples
    }

    fn start(&mut self, sample: &ImuSample) {
        self.newest = Some(*sample);
        self.horizon_sample = Some(*sample);
        self.horizon_time_s = sample.time_s;
        self.covariance_time_s = sample.time_s;
        // The scale and cross-axis errors of the rate and force already present are unknown
        // biases from the start.
        let s = &self.settings;
        let gyro =
            rate_dependent_variance(&sample.gyro_rad_s, s.gyro_scale_error, s.gyro_cross_axis);
        let accel =
            rate_dependent_variance(&sample.accel_m_s2, s.accel_scale_error, s.accel_cross_axis);
        for i in 0..3 {
            self.covariance[(GYRO_BIAS + i, GYRO_BIAS + i)] += gyro[i];
            self.covariance[(ACCEL_BIAS + i, ACCEL_BIAS + i)] += accel[i];
        }
        self.rate_mean = sample.gyro_rad_s;
        self.force_mean = sample.accel_m_s2;
        self.track_clamping(sample);
        self.gyro_filtered = sample.gyro_rad_s;
        self.output = self.horizon;
        self.output_inputs = None;
        self.trail.clear();
        self.trail_follows_horizon = self.reuse_trail;
    }

    /// An estimator that computes every step of its horizon (the reference of the test that
    /// taking them from the output's trail changes nothing).
    #[cfg(test)]
    pub(crate) fn without_trail_reuse(mut self) -> Self {
        self.reuse_trail = false;
        self.trail_follows_horizon = false;
        self
    }

    /// The horizon leaves the output chain's path (module docs of `trail`).
    fn stop_following(&mut self) {
        self.trail_follows_horizon = false;
        self.trail.clear();
    }

    fn queue(&mut self, valid_at_s: f64, measurement: Measurement) {
        queue(&mut self.pending, valid_at_s, measurement);
    }

    /// Moves the horizon through the buffered samples up to `target_s`; `true` if a
    /// measurement was fused on the way.
    fn advance_horizon(&mut self, target_s: f64) -> bool {
        let mut corrected = false;
        while let Some(&next) = self.buffer.front() {
            if next.time_s > target_s + TIME_EPS_S {
                break;
            }
            self.buffer.pop_front();
            // The chain's step to `next` (the trail's front matches the buffer's).
            let chained = self.trail.pop_front();
            while let Some(&p) = self.pending.front() {
                if p.valid_at_s > next.time_s + TIME_EPS_S {
                    break;
                }
                self.pending.pop_front();
                if p.valid_at_s < self.horizon_time_s - TIME_EPS_S {
                    self.counts.late += 1;
                    continue;
                }
                self.propagate_horizon(&next, p.valid_at_s);
                corrected |= self.fuse(&p.measurement);
            }
            match chained {
                Some(c) if self.trail_follows_horizon => {
                    #[cfg(test)]
                    {
                        self.chained_steps += 1;
                    }
                    self.take_horizon_step(&next, c.state, &c.step, c.end)
                }
                _ => self.propagate_horizon(&next, next.time_s),
            }
            self.horizon_sample = Some(next);
        }
        corrected
    }

    /// Horizon state and covariance from the horizon time to `t_s` (towards sample `next`).
    fn propagate_horizon(&mut self, next: &ImuSample, t_s: f64) {
        let Some(a) = self.horizon_sample else {
            return;
        };
        let t0 = self.horizon_time_s;
        if t_s <= t0 {
            return;
        }
        let (state, step, end) = self.horizon.propagate_from(
            self.horizon_inputs.as_ref(),
            &a,
            next,
            t0,
            t_s,
            &self.kinematics,
        );
        self.stop_following();
        self.take_horizon_step(next, state, &step, end);
    }

    /// The horizon moved by `step` to `state` (towards sample `next`), with the covariance's
    /// block and the clamping it tracks.
    fn take_horizon_step(
        &mut self,
        next: &ImuSample,
        state: NominalState,
        step: &Step,
        end: Inputs,
    ) {
        self.horizon = state;
        self.horizon_inputs = Some(end);
        self.horizon_time_s = end.time_s;
        match self.block.as_mut() {
            Some(block) => block.extend(step),
            None => self.block = Some(Block::start(step)),
        }
        if self
            .block
            .is_some_and(|b| b.step.dt_s >= self.settings.covariance_period_s - TIME_EPS_S)
        {
            self.flush_covariance();
        }
        self.track_clamping(next);
    }

    /// Applies the pending block of steps to the covariance: it is then at the horizon.
    fn flush_covariance(&mut self) {
        if let Some(block) = self.block.take() {
            let noise = self.process_noise(&block.step);
            propagate_covariance(&mut self.covariance, &block.step, &noise);
        }
        self.covariance_time_s = self.horizon_time_s;
    }

    /// White noise of the IMU and the bias walks, with the scale and cross-axis errors of the
    /// input's departure from its running mean.
    fn process_noise(&mut self, step: &Step) -> ProcessNoise {
        let s = &self.settings;
        let tau = s.input_mean_time_s;
        let rate = step.rate_end + self.horizon.gyro_bias_rad_s;
        let force = step.force_end + self.horizon.accel_bias_m_s2;
        let gyro_extra = rate_dependent_variance(
            &(rate - self.rate_mean),
            s.gyro_scale_error,
            s.gyro_cross_axis,
        );
        let accel_extra = rate_dependent_variance(
            &(force - self.force_mean),
            s.accel_scale_error,
            s.accel_cross_axis,
        );
        let blend = 1.0 - (-step.dt_s / tau).exp();
        self.rate_mean += (rate - self.rate_mean) * blend;
        self.force_mean += (force - self.force_mean) * blend;
        let walk_g = s.gyro_bias_walk_rad_s_rt_s.powi(2);
        let walk_a = s.accel_bias_walk_m_s2_rt_s.powi(2);
        // A clamped axis's hidden excess walks (settings' `saturation_walk`).
        let clamped_walk = |clamped: &[bool; 3], range: f64| {
            let q = (s.saturation_walk * range).powi(2);
            Vector3::from_fn(|i, _| if clamped[i] { q } else { 0.0 })
        };
        ProcessNoise {
            gyro_psd: s.gyro_noise_density_rad_s_rt_hz.powi(2),
            accel_psd: s.accel_noise_density_m_s2_rt_hz.powi(2),
            gyro_bias_psd: gyro_extra * (2.0 / tau)
                + Vector3::repeat(walk_g)
                + clamped_walk(&self.gyro_clamped, s.gyro_range_rad_s),
            accel_bias_psd: accel_extra * (2.0 / tau)
                + Vector3::repeat(walk_a)
                + clamped_walk(&self.accel_clamped, s.accel_range_m_s2),
        }
    }

    /// A clamped axis reads its range while the truth is beyond it by an unknown, changing
    /// amount: to the filter, a bias that appears when the clamping starts, walks while it lasts
    /// (`saturation_walk`, in the process noise) and goes when it ends. Each switch
    /// adds `(saturation_excess range)^2` to that axis's bias variance, so the bias state learns
    /// the excess from the aiding measurements.
    fn track_clamping(&mut self, sample: &ImuSample) {
        let s = &self.settings;
        let mut switches: Vec<(usize, f64)> = Vec::new();
        let sensors = [
            (
                GYRO_BIAS,
                &sample.gyro_rad_s,
                s.gyro_range_rad_s,
                &mut self.gyro_clamped,
            ),
            (
                ACCEL_BIAS,
                &sample.accel_m_s2,
                s.accel_range_m_s2,
                &mut self.accel_clamped,
            ),
        ];
        for (block, reading, range, clamped) in sensors {
            for i in 0..3 {
                let now = reading[i].abs() >= range;
                if now != clamped[i] {
                    switches.push((block + i, s.saturation_excess * range));
                    clamped[i] = now;
                }
            }
        }
        if !switches.is_empty() {
            self.flush_covariance();
            for (index, sigma) in switches {
                self.covariance[(index, index)] += sigma * sigma;
            }
        }
    }

    /// One measurement update at the horizon; `true` if fused.
    fn fuse(&mut self, measurement: &Measurement) -> bool {
        self.flush_covariance();
        let s = &self.settings;
        let x = &self.horizon;
        let (block, h, residual, std) = match measurement {
            Measurement::Position(z) => {
                let [hz, vt] = s.position_std_m;
                (POS, None, z - x.position_m, Vector3::new(hz, hz, vt))
            }
            Measurement::Velocity(z) => (
                VEL,
                None,
                z - x.velocity_m_s,
                Vector3::repeat(s.velocity_std_m_s),
            ),
            Measurement::Attitude(q) => (
                ATT,
                None,
                (x.attitude.inverse() * q).scaled_axis(),
                Vector3::repeat(s.attitude_std_rad),
            ),
            Measurement::Magnetometer(z) => {
                let predicted = x.attitude.inverse_transform_vector(&s.earth_field_ut);
                (
                    ATT,
                    Some(skew(&predicted)),
                    z - predicted,
                    Vector3::repeat(s.magnetometer_std_ut),
                )
            }
        };
        if std.iter().any(|v| v.is_infinite()) {
            // A measurement the settings say is not there (infinite noise): nothing to learn.
            self.counts.rejected += 1;
            return false;
        }
        let (fusion, dx) = update_block(
            &mut self.covariance,
            block,
            h.as_ref(),
            &residual,
            &std.component_mul(&std),
            s.innovation_gate,
        );
        match fusion {
            Fusion::Rejected => {
                self.counts.rejected += 1;
                false
            }
            Fusion::Fused => {
                self.stop_following();
                self.horizon.inject(&dx);
                self.horizon_inputs = None;
                reset_covariance(&mut self.covariance, &dx.fixed_rows::<3>(ATT).into_owned());
                self.counts.fused += 1;
                true
            }
        }
    }

    /// The output predictor recomputed: the horizon carried through every buffered sample.
    fn replay_output(&mut self) {
        let mut x = self.horizon;
        let mut inputs = self.horizon_inputs;
        self.trail.clear();
        // The chain starts from the horizon only when the horizon is at its sample (not at a
        // measurement's time between samples).
        self.trail_follows_horizon = self.reuse_trail
            && self
                .horizon_sample
                .is_some_and(|a| a.time_s == self.horizon_time_s);
        if let Some(mut a) = self.horizon_sample {
            let mut t0 = self.horizon_time_s;
            for b in &self.buffer {
                let (next, step, end) =
                    x.propagate_from(inputs.as_ref(), &a, b, t0, b.time_s, &self.kinematics);
                if self.trail_follows_horizon {
                    self.trail.push_back(ChainStep {
                        state: next,
                        step,
                        end,
                    });
                }
                x = next;
                inputs = Some(end);
                a = *b;
                t0 = b.time_s;
            }
        }
        self.output = x;
        self.output_inputs = inputs;
    }

    fn filter_gyro(&mut self, sample: &ImuSample, dt_s: f64) {
        let corrected = sample.gyro_rad_s - self.output.gyro_bias_rad_s;
        self.gyro_filtered = match self.settings.gyro_cutoff_hz {
            None => corrected,
            Some(f) => {
                let blend = 1.0 - (-2.0 * std::f64::consts::PI * f * dt_s).exp();
                self.gyro_filtered + (corrected - self.gyro_filtered) * blend
            }
        };
    }
}

/// The fusion slot (`position_fusion_period_s` = `period_s`) of a fix valid at `valid_at_s`. A
/// fix on a slot boundary (k / rate_hz) can divide to just under the whole number (0.29 / 0.01 =
/// 28.999999999999996): a millionth of a period of tolerance, as the sensors' clocks use, keeps
/// it in its own slot (else 1 fix in 8 at 100 Hz thinned).
pub(crate) fn fusion_slot(valid_at_s: f64, period_s: f64) -> f64 {
    (valid_at_s / period_s + PERIOD_TOLERANCE).floor()
}

/// Per-axis variance of the error `(S + E) u` for scale errors `scale` and cross-axis terms
/// `cross` (1 sigma): `scale^2 u_i^2 + cross^2 (|u|^2 - u_i^2)`.
fn rate_dependent_variance(u: &Vector3<f64>, scale: f64, cross: f64) -> Vector3<f64> {
    let total = u.norm_squared();
    u.map(|ui| scale * scale * ui * ui + cross * cross * (total - ui * ui))
}
