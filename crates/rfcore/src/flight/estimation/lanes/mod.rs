//! [`Estimator`](crate::flight::estimation::Estimator) for `L::WIDTH` runs at once, one per SIMD
//! lane, each lane computing what the scalar estimator computes from the same samples, bit for
//! bit (the batch driver's sensed groups, [`crate::flight::simulation`]).
//!
//! # What the lanes share
//! The runs of a group fly the same sensor suite, so their sensors sample on the same clocks
//! (`k / rate_hz` from 0) with the same latency: every lane receives its IMU samples, position
//! fixes and magnetometer readings at the same times, in the same order, and the filter's
//! schedule (the fusion horizon, the buffered samples, the queue of measurements and the fixes
//! thinned by the fusion slot) is one schedule. What differs between lanes is carried per lane:
//! the values, a measurement the innovation gate refuses in some lanes (a lane mask: a refused
//! lane keeps its covariance and state), the covariance blocks a lane flushes early when its
//! gyro or accelerometer starts or stops clamping (the block and its flush per lane), and the
//! counts. A suite whose sensors drop out at random (the GNSS profile) breaks the shared
//! schedule: its runs fly with the scalar estimator.
//!
//! # Why a lane equals the scalar estimator
//! The kernels ([`kernels`]) are the scalar ones written over lanes in nalgebra's order of
//! operations (checked bit for bit, [`math`]). The scalar estimator reuses two results that the
//! lanes recompute instead: the inputs at a step's start (the previous step's end inputs, the same
//! function of the same values) and the horizon's steps taken from the output predictor's trail
//! (the scalar tests check that taking them changes nothing). Where a lane's output predictor
//! was corrected by a fusion it is replayed from the horizon; elsewhere it advances one sample,
//! as in the scalar estimator. The group tests compare every lane's estimates, covariance and
//! counts with the scalar estimator's.

pub(crate) mod kernels;
pub(crate) mod math;

use std::collections::VecDeque;

use nalgebra::{UnitQuaternion, Vector3};

use crate::analysis::LanePath;
use crate::error::{Result, RfError};
use crate::flight::estimation::eskf::{skew, ACCEL_BIAS, ATT, ERROR_DIM, GYRO_BIAS, POS, VEL};
use crate::flight::estimation::estimator::{fusion_slot, queue, Pending, TIME_EPS_S};
use crate::flight::estimation::{Estimate, EstimatorSettings, FusionCounts};
use crate::flight::lanes::{runs_avx2, Choice, Lanes};
use crate::flight::sensors::PositionSample;
use crate::state::RigidBodyState;

use kernels::{
    propagate_covariance, reset_covariance, update_block, BlockLanes, CovarianceLanes, ImuLanes,
    KinematicsLanes, NoiseLanes, NominalLanes, StepLanes, ENTRIES,
};
use math::{
    add, all, cross, exp_quaternion, lane3, lane_quat, norm_squared, quat_mul, renormalize_fast,
    rotate, scale, select, select_n, set3, set_mat, set_quat, splat3, sub, Mask, Q, V3,
};

/// A position source's fix in every lane (one time of validity).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PositionLanes<L> {
    pub valid_at_s: f64,
    pub position_m: V3<L>,
    pub velocity_m_s: Option<V3<L>>,
    pub attitude: Option<Q<L>>,
}

impl<L: Lanes> PositionLanes<L> {
    /// `fix` in every lane (lanes are then set one by one, [`PositionLanes::set_lane`]; a lane
    /// left as it is reads this fix).
    pub(crate) fn splat(fix: &PositionSample) -> Self {
        PositionLanes {
            valid_at_s: fix.valid_at_s,
            position_m: splat3(&fix.position_m),
            velocity_m_s: fix.velocity_m_s.map(|v| splat3(&v)),
            attitude: fix.attitude.map(|q| {
                let mut lanes = [L::splat(0.0); 4];
                for i in 0..L::WIDTH {
                    set_quat(&mut lanes, i, &q);
                }
                lanes
            }),
        }
    }

    /// `true` when `fix` has this fix's time of validity and parts (it can share its lanes).
    pub(crate) fn matches(&self, fix: &PositionSample) -> bool {
        fix.valid_at_s == self.valid_at_s
            && fix.velocity_m_s.is_some() == self.velocity_m_s.is_some()
            && fix.attitude.is_some() == self.attitude.is_some()
    }

    /// Lane `i` set to `fix` (one that [`PositionLanes::matches`]).
    pub(crate) fn set_lane(&mut self, i: usize, fix: &PositionSample) {
        set3(&mut self.position_m, i, &fix.position_m);
        if let (Some(v), Some(lanes)) = (fix.velocity_m_s, self.velocity_m_s.as_mut()) {
            set3(lanes, i, &v);
        }
        if let (Some(q), Some(lanes)) = (fix.attitude, self.attitude.as_mut()) {
            set_quat(lanes, i, &q);
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum Measurement<L> {
    Position(V3<L>),
    Velocity(V3<L>),
    Attitude(Q<L>),
    Magnetometer(V3<L>),
}

/// `L::WIDTH` estimators in lanes (module docs).
#[derive(Debug, Clone)]
pub(crate) struct EstimatorLanes<L> {
    settings: EstimatorSettings,
    kinematics: KinematicsLanes<L>,
    horizon: NominalLanes<L>,
    covariance: Box<CovarianceLanes<L>>,
    horizon_time_s: f64,
    horizon_sample: Option<ImuLanes<L>>,
    /// Steps since each lane's last covariance flush (`block_lanes`: the lanes holding one).
    block: Option<BlockLanes<L>>,
    block_lanes: Mask,
    rate_mean: V3<L>,
    force_mean: V3<L>,
    /// Per axis, the lanes whose current horizon sample is clamped (gyro, accelerometer).
    gyro_clamped: [Mask; 3],
    accel_clamped: [Mask; 3],
    buffer: VecDeque<ImuLanes<L>>,
    pending: VecDeque<Pending<Measurement<L>>>,
    output: NominalLanes<L>,
    newest: Option<ImuLanes<L>>,
    gyro_filtered: V3<L>,
    counts: Vec<FusionCounts>,
    /// Samples clamped per lane (the scalar estimator's count; a run's own comes from its IMU).
    #[cfg(test)]
    saturated_samples: Vec<u64>,
    fix_slot: f64,
    /// The lanes whose runs still fly: only they count (a run's counts stop when it ends).
    active: Mask,
    /// The compiled form the lanes run (their group's, [`crate::flight::lanes`]).
    path: LanePath,
    /// Flushes of some lanes' blocks while other lanes held one (for the tests: the per-lane
    /// flush is exercised).
    #[cfg(test)]
    pub(crate) partial_flushes: u64,
}

impl<L: Lanes> EstimatorLanes<L> {
    /// Estimators with `settings` starting from `initial[i]` in lane `i` (the scalar
    /// `Estimator::new` per lane), run in the compiled form `path`.
    pub(crate) fn new(
        settings: EstimatorSettings,
        initial: &[RigidBodyState],
        path: LanePath,
    ) -> Result<Self> {
        settings.check()?;
        if initial.len() != L::WIDTH || initial.iter().any(|x| !x.is_finite()) {
            return Err(RfError::invalid(
                "initial",
                format!("must be {} finite states", L::WIDTH),
            ));
        }
        let zero = [L::splat(0.0); 3];
        let mut start = NominalLanes {
            position_m: zero,
            velocity_m_s: zero,
            attitude: [L::splat(0.0); 4],
            gyro_bias_rad_s: zero,
            accel_bias_m_s2: zero,
        };
        for (i, x) in initial.iter().enumerate() {
            set3(&mut start.position_m, i, &x.position_m);
            set3(&mut start.velocity_m_s, i, &x.velocity_m_s);
            set_quat(&mut start.attitude, i, &x.attitude);
        }
        let s = &settings;
        let mut covariance = Box::new([L::splat(0.0); ENTRIES]);
        for (block, std) in [
            (POS, s.initial_position_std_m),
            (VEL, s.initial_velocity_std_m_s),
            (ATT, s.initial_attitude_std_rad),
            (GYRO_BIAS, s.initial_gyro_bias_std_rad_s),
            (ACCEL_BIAS, s.initial_accel_bias_std_m_s2),
        ] {
            for i in 0..3 {
                covariance[diagonal(block + i)] = L::splat(std * std);
            }
        }
        Ok(EstimatorLanes {
            kinematics: KinematicsLanes {
                gravity_m_s2: [L::splat(0.0), L::splat(0.0), L::splat(s.gravity_m_s2)],
                imu_position_m: splat3(&s.imu_position_m),
            },
            settings,
            horizon: start,
            covariance,
            horizon_time_s: f64::NAN,
            horizon_sample: None,
            block: None,
            block_lanes: 0,
            rate_mean: zero,
            force_mean: zero,
            gyro_clamped: [0; 3],
            accel_clamped: [0; 3],
            buffer: VecDeque::new(),
            pending: VecDeque::new(),
            output: start,
            newest: None,
            gyro_filtered: zero,
            counts: vec![FusionCounts::default(); L::WIDTH],
            #[cfg(test)]
            saturated_samples: vec![0; L::WIDTH],
            fix_slot: f64::NAN,
            active: all::<L>(),
            path,
            #[cfg(test)]
            partial_flushes: 0,
        })
    }

    /// From now on only the lanes of `active` count (the others' runs have ended).
    pub(crate) fn set_active(&mut self, active: Mask) {
        self.active = active;
    }

    fn count(&mut self, lanes: Mask, add: impl Fn(&mut FusionCounts)) {
        for (i, c) in self.counts.iter_mut().enumerate() {
            if lanes & self.active & (1 << i) != 0 {
                add(c);
            }
        }
    }

    /// `Estimator::push_imu` in every lane.
    pub(crate) fn push_imu(&mut self, sample: &ImuLanes<L>) -> Result<()> {
        #[cfg(target_arch = "x86_64")]
        if runs_avx2(self.path, Choice::PushImu) {
            // SAFETY: the CPU has the features `push_imu_avx2` is compiled for.
            return unsafe { self.push_imu_avx2(sample) };
        }
        self.push_imu_body(sample)
    }

    /// [`EstimatorLanes::push_imu`] compiled for AVX2 and FMA with the per-sample steps it
    /// inlines (the horizon, the covariance block, the clamping flags, the output predictor):
    /// their lane operations outside the kernels otherwise took two SSE2 instructions each (the
    /// kernels' reason, `kernels::avx2_or_baseline`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn push_imu_avx2(&mut self, sample: &ImuLanes<L>) -> Result<()> {
        self.push_imu_body(sample)
    }

    #[inline(always)]
    fn push_imu_body(&mut self, sample: &ImuLanes<L>) -> Result<()> {
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
        #[cfg(test)]
        {
            let saturated = (sample.gyro_saturated | sample.accel_saturated) & self.active;
            for (i, n) in self.saturated_samples.iter_mut().enumerate() {
                *n += u64::from(saturated & (1 << i) != 0);
            }
        }
        let Some(previous) = self.newest else {
            self.start(sample);
            return Ok(());
        };
        self.newest = Some(*sample);
        self.buffer.push_back(*sample);
        let corrected = self.advance_horizon(sample.time_s - self.settings.fusion_delay_s);
        // Replayed where a fusion corrected the horizon (or nothing is buffered), advanced one
        // sample elsewhere (the scalar rule per lane).
        self.output = if self.buffer.is_empty() || corrected == all::<L>() {
            self.replayed()
        } else {
            let (advanced, _) = self.output.propagate(
                &previous,
                sample,
                (previous.time_s, sample.time_s),
                &self.kinematics,
                self.path,
            );
            if corrected == 0 {
                advanced
            } else {
                advanced.select(corrected, &self.replayed())
            }
        };
        self.filter_gyro(sample, sample.time_s - previous.time_s);
        Ok(())
    }

    /// `Estimator::push_position` in every lane (the fix's time of validity is every lane's).
    pub(crate) fn push_position(&mut self, fix: &PositionLanes<L>) {
        let period = self.settings.position_fusion_period_s;
        if period > 0.0 {
            let slot = fusion_slot(fix.valid_at_s, period);
            if slot == self.fix_slot {
                let n =
                    1 + u64::from(fix.velocity_m_s.is_some()) + u64::from(fix.attitude.is_some());
                self.count(all::<L>(), |c| c.thinned += n);
                return;
            }
            self.fix_slot = slot;
        }
        self.queue(fix.valid_at_s, Measurement::Position(fix.position_m));
        if let Some(v) = fix.velocity_m_s {
            self.queue(fix.valid_at_s, Measurement::Velocity(v));
        }
        if let Some(q) = fix.attitude {
            self.queue(fix.valid_at_s, Measurement::Attitude(q));
        }
    }

    /// `Estimator::push_magnetometer` in every lane.
    pub(crate) fn push_magnetometer(&mut self, time_s: f64, field_ut: &V3<L>) {
        self.queue(time_s, Measurement::Magnetometer(*field_ut));
    }

    /// Lane `i`'s `Estimator::estimate` (for the tests; the flights read
    /// [`EstimatorLanes::estimates_at`]).
    #[cfg(test)]
    pub(crate) fn estimate(&self, i: usize) -> Estimate {
        let bias_g = lane3(&self.output.gyro_bias_rad_s, i);
        let bias_a = lane3(&self.output.accel_bias_m_s2, i);
        let (time_s, gyro_rad_s, accel_m_s2, gyro_saturated, accel_saturated) = match &self.newest {
            Some(s) => {
                let rate = lane3(&s.gyro_rad_s, i) - bias_g;
                let r = &self.settings.imu_position_m;
                (
                    s.time_s,
                    rate,
                    lane3(&s.accel_m_s2, i) - bias_a - rate.cross(&rate.cross(r)),
                    s.gyro_saturated & (1 << i) != 0,
                    s.accel_saturated & (1 << i) != 0,
                )
            }
            None => (f64::NAN, Vector3::zeros(), Vector3::zeros(), false, false),
        };
        Estimate {
            time_s,
            state: RigidBodyState {
                position_m: lane3(&self.output.position_m, i),
                velocity_m_s: lane3(&self.output.velocity_m_s, i),
                attitude: lane_quat(&self.output.attitude, i),
                omega_rad_s: lane3(&self.gyro_filtered, i),
            },
            gyro_rad_s,
            accel_m_s2,
            gyro_saturated,
            accel_saturated,
        }
    }

    /// Every lane's estimate carried to the control step at `t_s` into `out` (lane `i`'s is
    /// `self.estimate(i).carried(gravity, t_s)`), computed in lanes.
    pub(crate) fn estimates_at(&self, t_s: f64, out: &mut Vec<Estimate>) {
        #[cfg(target_arch = "x86_64")]
        if runs_avx2(self.path, Choice::EstimatesAt) {
            // SAFETY: the CPU has the features `estimates_at_avx2` is compiled for.
            return unsafe { self.estimates_at_avx2(t_s, out) };
        }
        self.estimates_at_body(t_s, out)
    }

    /// [`EstimatorLanes::estimates_at`] compiled for AVX2 and FMA (as `push_imu_avx2`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn estimates_at_avx2(&self, t_s: f64, out: &mut Vec<Estimate>) {
        self.estimates_at_body(t_s, out)
    }

    #[inline(always)]
    fn estimates_at_body(&self, t_s: f64, out: &mut Vec<Estimate>) {
        let x = &self.output;
        let (time_s, rate, accel, gyro_saturated, accel_saturated) = match &self.newest {
            Some(s) => {
                let rate = sub(&s.gyro_rad_s, &x.gyro_bias_rad_s);
                let r = &self.kinematics.imu_position_m;
                let accel = sub(
                    &sub(&s.accel_m_s2, &x.accel_bias_m_s2),
                    &cross(&rate, &cross(&rate, r)),
                );
                (s.time_s, rate, accel, s.gyro_saturated, s.accel_saturated)
            }
            None => {
                let zero = [L::splat(0.0); 3];
                (f64::NAN, zero, zero, 0, 0)
            }
        };
        let (mut position, mut velocity, mut attitude) = (x.position_m, x.velocity_m_s, x.attitude);
        let omega = self.gyro_filtered;
        let dt = t_s - time_s;
        let carried = dt > 0.0;
        if carried {
            let half = L::splat(0.5 * dt);
            let dtl = L::splat(dt);
            let acceleration = add(&rotate(&attitude, &accel), &self.kinematics.gravity_m_s2);
            position = add(
                &position,
                &scale(&add(&velocity, &scale(&acceleration, half)), dtl),
            );
            velocity = add(&velocity, &scale(&acceleration, dtl));
            attitude = renormalize_fast(&quat_mul(&attitude, &exp_quaternion(&scale(&omega, dtl))));
        }
        out.clear();
        // A loop of pushes rather than `extend` over a closure, which LLVM left out of line
        // (compiled for the baseline, outside this AVX2 function).
        for i in 0..L::WIDTH {
            out.push(Estimate {
                time_s: if carried { t_s } else { time_s },
                state: RigidBodyState {
                    position_m: lane3(&position, i),
                    velocity_m_s: lane3(&velocity, i),
                    attitude: lane_quat(&attitude, i),
                    omega_rad_s: lane3(&omega, i),
                },
                gyro_rad_s: lane3(&rate, i),
                accel_m_s2: lane3(&accel, i),
                gyro_saturated: gyro_saturated & (1 << i) != 0,
                accel_saturated: accel_saturated & (1 << i) != 0,
            });
        }
    }

    /// Lane `i`'s covariance diagonal (`Estimator::covariance`'s).
    pub(crate) fn variances(&self, i: usize) -> [f64; ERROR_DIM] {
        std::array::from_fn(|k| self.covariance[diagonal(k)].lane(i))
    }

    /// Lane `i`'s covariance (for the tests).
    #[cfg(test)]
    pub(crate) fn covariance(&self, i: usize) -> crate::flight::estimation::Covariance {
        kernels::lane_covariance(&self.covariance, i)
    }

    pub(crate) fn counts(&self, i: usize) -> FusionCounts {
        self.counts[i]
    }

    #[cfg(test)]
    pub(crate) fn saturated_samples(&self, i: usize) -> u64 {
        self.saturated_samples[i]
    }

    #[inline(always)]
    fn start(&mut self, sample: &ImuLanes<L>) {
        self.newest = Some(*sample);
        self.horizon_sample = Some(*sample);
        self.horizon_time_s = sample.time_s;
        let s = &self.settings;
        let gyro =
            rate_dependent_variance(&sample.gyro_rad_s, s.gyro_scale_error, s.gyro_cross_axis);
        let accel =
            rate_dependent_variance(&sample.accel_m_s2, s.accel_scale_error, s.accel_cross_axis);
        for i in 0..3 {
            let g = &mut self.covariance[diagonal(GYRO_BIAS + i)];
            *g = *g + gyro[i];
            let a = &mut self.covariance[diagonal(ACCEL_BIAS + i)];
            *a = *a + accel[i];
        }
        self.rate_mean = sample.gyro_rad_s;
        self.force_mean = sample.accel_m_s2;
        self.track_clamping(sample);
        self.gyro_filtered = sample.gyro_rad_s;
        self.output = self.horizon;
    }

    fn queue(&mut self, valid_at_s: f64, measurement: Measurement<L>) {
        queue(&mut self.pending, valid_at_s, measurement);
    }

    /// `Estimator::advance_horizon`: the lanes where a measurement was fused on the way.
    #[inline(always)]
    fn advance_horizon(&mut self, target_s: f64) -> Mask {
        let mut corrected = 0;
        while let Some(&next) = self.buffer.front() {
            if next.time_s > target_s + TIME_EPS_S {
                break;
            }
            self.buffer.pop_front();
            while let Some(&p) = self.pending.front() {
                if p.valid_at_s > next.time_s + TIME_EPS_S {
                    break;
                }
                self.pending.pop_front();
                if p.valid_at_s < self.horizon_time_s - TIME_EPS_S {
                    self.count(all::<L>(), |c| c.late += 1);
                    continue;
                }
                self.propagate_horizon(&next, p.valid_at_s);
                corrected |= self.fuse(&p.measurement);
            }
            self.propagate_horizon(&next, next.time_s);
            self.horizon_sample = Some(next);
        }
        corrected
    }

    #[inline(always)]
    fn propagate_horizon(&mut self, next: &ImuLanes<L>, t_s: f64) {
        let Some(a) = self.horizon_sample else {
            return;
        };
        let t0 = self.horizon_time_s;
        if t_s <= t0 {
            return;
        }
        let (state, step) =
            self.horizon
                .propagate(&a, next, (t0, t_s), &self.kinematics, self.path);
        self.horizon = state;
        self.horizon_time_s = t_s;
        self.add_to_block(&step);
        let period = self.settings.covariance_period_s - TIME_EPS_S;
        let due = match &self.block {
            Some(b) => (0..L::WIDTH)
                .filter(|&i| b.step.dt_s.lane(i) >= period)
                .fold(0, |m, i| m | (1 << i)),
            None => 0,
        };
        if due != 0 {
            self.flush_covariance(due);
        }
        self.track_clamping(next);
    }

    /// Every lane's block extended by `step` (a lane without one starts it).
    #[inline(always)]
    fn add_to_block(&mut self, step: &StepLanes<L>) {
        self.block = Some(match &self.block {
            Some(block) if self.block_lanes == all::<L>() => block.extended(step),
            Some(block) if self.block_lanes != 0 => {
                BlockLanes::start(step).select(self.block_lanes, &block.extended(step))
            }
            _ => BlockLanes::start(step),
        });
        self.block_lanes = all::<L>();
    }

    /// `Estimator::flush_covariance` in the lanes of `lanes` that hold a block.
    fn flush_covariance(&mut self, lanes: Mask) {
        let lanes = lanes & self.block_lanes;
        let Some(block) = self.block else {
            return;
        };
        if lanes == 0 {
            return;
        }
        #[cfg(test)]
        {
            self.partial_flushes += u64::from(self.block_lanes & !lanes != 0);
        }
        let noise = self.process_noise(&block.step, lanes);
        if lanes == all::<L>() {
            propagate_covariance(self.path, &mut self.covariance, &block.step, &noise);
        } else {
            let mut p = self.covariance.clone();
            propagate_covariance(self.path, &mut p, &block.step, &noise);
            for (e, n) in self.covariance.iter_mut().zip(p.iter()) {
                *e = select(lanes, *n, *e);
            }
        }
        self.block_lanes &= !lanes;
    }

    /// `Estimator::process_noise`, moving the running means in the lanes of `lanes`.
    fn process_noise(&mut self, step: &StepLanes<L>, lanes: Mask) -> NoiseLanes<L> {
        let s = &self.settings;
        let tau = s.input_mean_time_s;
        let rate = add(&step.rate_end, &self.horizon.gyro_bias_rad_s);
        let force = add(&step.force_end, &self.horizon.accel_bias_m_s2);
        let gyro_extra = rate_dependent_variance(
            &sub(&rate, &self.rate_mean),
            s.gyro_scale_error,
            s.gyro_cross_axis,
        );
        let accel_extra = rate_dependent_variance(
            &sub(&force, &self.force_mean),
            s.accel_scale_error,
            s.accel_cross_axis,
        );
        let mut blend = L::splat(0.0);
        for i in 0..L::WIDTH {
            blend.set_lane(i, 1.0 - (-step.dt_s.lane(i) / tau).exp());
        }
        let rate_mean = add(&self.rate_mean, &scale(&sub(&rate, &self.rate_mean), blend));
        let force_mean = add(
            &self.force_mean,
            &scale(&sub(&force, &self.force_mean), blend),
        );
        self.rate_mean = select_n(lanes, &rate_mean, &self.rate_mean);
        self.force_mean = select_n(lanes, &force_mean, &self.force_mean);
        let walk_g = L::splat(s.gyro_bias_walk_rad_s_rt_s.powi(2));
        let walk_a = L::splat(s.accel_bias_walk_m_s2_rt_s.powi(2));
        let clamped_walk = |clamped: &[Mask; 3], range: f64| -> V3<L> {
            let q = L::splat((s.saturation_walk * range).powi(2));
            std::array::from_fn(|k| select(clamped[k], q, L::splat(0.0)))
        };
        let two_over_tau = L::splat(2.0 / tau);
        let walked = |extra: &V3<L>, walk: L, clamped: V3<L>| -> V3<L> {
            std::array::from_fn(|k| extra[k] * two_over_tau + walk + clamped[k])
        };
        NoiseLanes {
            gyro_psd: L::splat(s.gyro_noise_density_rad_s_rt_hz.powi(2)),
            accel_psd: L::splat(s.accel_noise_density_m_s2_rt_hz.powi(2)),
            gyro_bias_psd: walked(
                &gyro_extra,
                walk_g,
                clamped_walk(&self.gyro_clamped, s.gyro_range_rad_s),
            ),
            accel_bias_psd: walked(
                &accel_extra,
                walk_a,
                clamped_walk(&self.accel_clamped, s.accel_range_m_s2),
            ),
        }
    }

    /// `Estimator::track_clamping` per lane.
    #[inline(always)]
    fn track_clamping(&mut self, sample: &ImuLanes<L>) {
        let s = &self.settings;
        // (lane, covariance index, sigma) of each switch.
        let mut switches: Vec<(usize, usize, f64)> = Vec::new();
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
            for (k, axis) in clamped.iter_mut().enumerate() {
                let now = (0..L::WIDTH)
                    .filter(|&i| reading[k].lane(i).abs() >= range)
                    .fold(0, |m, i| m | (1 << i));
                let changed = now ^ *axis;
                for i in (0..L::WIDTH).filter(|&i| changed & (1 << i) != 0) {
                    switches.push((i, block + k, s.saturation_excess * range));
                }
                *axis = now;
            }
        }
        if switches.is_empty() {
            return;
        }
        let lanes = switches.iter().fold(0, |m, &(i, _, _)| m | (1 << i));
        self.flush_covariance(lanes);
        for (i, index, sigma) in switches {
            let e = &mut self.covariance[diagonal(index)];
            e.set_lane(i, e.lane(i) + sigma * sigma);
        }
    }

    /// `Estimator::fuse` per lane: the lanes fused.
    fn fuse(&mut self, measurement: &Measurement<L>) -> Mask {
        self.flush_covariance(all::<L>());
        let s = &self.settings;
        let x = &self.horizon;
        let mut h = None;
        let (block, residual, std) = match measurement {
            Measurement::Position(z) => {
                let [hz, vt] = s.position_std_m;
                (POS, sub(z, &x.position_m), Vector3::new(hz, hz, vt))
            }
            Measurement::Velocity(z) => (
                VEL,
                sub(z, &x.velocity_m_s),
                Vector3::repeat(s.velocity_std_m_s),
            ),
            Measurement::Attitude(q) => {
                let mut r = [L::splat(0.0); 3];
                for i in 0..L::WIDTH {
                    let d: UnitQuaternion<f64> =
                        lane_quat(&x.attitude, i).inverse() * lane_quat(q, i);
                    set3(&mut r, i, &d.scaled_axis());
                }
                (ATT, r, Vector3::repeat(s.attitude_std_rad))
            }
            Measurement::Magnetometer(z) => {
                let mut r = [L::splat(0.0); 3];
                let mut jacobian = [[L::splat(0.0); 3]; 3];
                for i in 0..L::WIDTH {
                    let predicted =
                        lane_quat(&x.attitude, i).inverse_transform_vector(&s.earth_field_ut);
                    set_mat(&mut jacobian, i, &skew(&predicted));
                    set3(&mut r, i, &(lane3(z, i) - predicted));
                }
                h = Some(jacobian);
                (ATT, r, Vector3::repeat(s.magnetometer_std_ut))
            }
        };
        if std.iter().any(|v| v.is_infinite()) {
            self.count(all::<L>(), |c| c.rejected += 1);
            return 0;
        }
        let (fused, dx) = update_block(
            self.path,
            &mut self.covariance,
            block,
            h.as_ref(),
            &residual,
            &std.component_mul(&std),
            s.innovation_gate,
            all::<L>(),
        );
        self.count(all::<L>() & !fused, |c| c.rejected += 1);
        if fused != 0 {
            self.horizon.inject(&dx, fused);
            reset_covariance(
                self.path,
                &mut self.covariance,
                &[dx[ATT], dx[ATT + 1], dx[ATT + 2]],
                fused,
            );
            self.count(fused, |c| c.fused += 1);
        }
        fused
    }

    /// The output predictor recomputed from the horizon through every buffered sample.
    #[inline(always)]
    fn replayed(&self) -> NominalLanes<L> {
        let mut x = self.horizon;
        if let Some(mut a) = self.horizon_sample {
            let mut t0 = self.horizon_time_s;
            for b in &self.buffer {
                x = x
                    .propagate(&a, b, (t0, b.time_s), &self.kinematics, self.path)
                    .0;
                a = *b;
                t0 = b.time_s;
            }
        }
        x
    }

    #[inline(always)]
    fn filter_gyro(&mut self, sample: &ImuLanes<L>, dt_s: f64) {
        let corrected = sub(&sample.gyro_rad_s, &self.output.gyro_bias_rad_s);
        self.gyro_filtered = match self.settings.gyro_cutoff_hz {
            None => corrected,
            Some(f) => {
                let blend = L::splat(1.0 - (-2.0 * std::f64::consts::PI * f * dt_s).exp());
                add(
                    &self.gyro_filtered,
                    &scale(&sub(&corrected, &self.gyro_filtered), blend),
                )
            }
        };
    }
}

/// The index of the covariance's diagonal entry `k` (column-major).
const fn diagonal(k: usize) -> usize {
    k * ERROR_DIM + k
}

/// `rate_dependent_variance` of the scalar estimator, per lane.
fn rate_dependent_variance<L: Lanes>(u: &V3<L>, scale: f64, cross: f64) -> V3<L> {
    let total = norm_squared(u);
    let (s2, c2) = (L::splat(scale * scale), L::splat(cross * cross));
    std::array::from_fn(|k| s2 * u[k] * u[k] + c2 * (total - u[k] * u[k]))
}

#[cfg(test)]
mod tests;
