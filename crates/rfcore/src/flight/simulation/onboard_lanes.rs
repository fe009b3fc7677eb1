//! The estimators of a group flown in lanes, in lanes ([`EstimatorLanes`]): each run's sensors
//! stay its own ([`Onboard`], read from its own tape), and the group's estimators take the
//! runs' readings together, one lane per run. The runs of a group fly one sensor suite, so their
//! readings come at the same times in the same order (the module docs of
//! [`crate::flight::estimation::lanes`]); a suite whose position fixes drop out at random does
//! not, and its runs keep their scalar estimators ([`OnboardLanes::new`] declines).

use crate::cancel::Cancel;
use crate::error::{Result, RfError};
use crate::flight::estimation::lanes::kernels::ImuLanes;
use crate::flight::estimation::lanes::math::{set3, set_quat, Mask};
use crate::flight::estimation::lanes::{EstimatorLanes, PositionLanes};
use crate::flight::estimation::Estimate;
use crate::flight::lanes::Lanes;
use crate::flight::simulation::onboard::{row, Onboard, Reading};
use crate::flight::simulation::recording::{EstimateRow, SensingRecord};
use crate::flight::simulation::tape::Tape;
use crate::flight::vehicle::Vehicle;
use crate::state::RigidBodyState;

pub(crate) struct OnboardLanes<L> {
    estimator: EstimatorLanes<L>,
    /// Each lane's readings of the current chunk.
    readings: Vec<Vec<Reading>>,
    /// Each lane's estimate at the current control step.
    estimates: Vec<Estimate>,
}

impl<L: Lanes> OnboardLanes<L> {
    /// The group's estimators in lanes, lane `i` starting from `starts[i]` with the settings of
    /// `onboards[i]`; `None` when the lanes cannot share one schedule (a position source that
    /// drops fixes, or settings that differ) or there is not one run per lane.
    pub(crate) fn new(onboards: &[&Onboard], starts: &[RigidBodyState]) -> Option<Self> {
        let first = onboards.first()?;
        if onboards.len() != L::WIDTH
            || onboards
                .iter()
                .any(|o| o.drops_fixes() || o.estimator_settings() != first.estimator_settings())
        {
            return None;
        }
        let estimator = EstimatorLanes::new(*first.estimator_settings(), starts).ok()?;
        Some(OnboardLanes {
            estimator,
            readings: vec![Vec::new(); L::WIDTH],
            estimates: Vec::with_capacity(L::WIDTH),
        })
    }

    /// [`Onboard::catch_up`] for the lanes of `active` (the runs still flying): each run takes its
    /// samples up to `t_end_s` from its tape, a chunk at a time, and the estimators read the
    /// chunk's readings in lanes. A lane not in `active` reads lane `first active`'s values and
    /// counts nothing.
    pub(crate) fn catch_up(
        &mut self,
        runs: &mut [Option<(&mut Onboard, &mut Tape)>],
        active: Mask,
        vehicle: &Vehicle,
        t_end_s: f64,
        cancel: &Cancel,
    ) -> Result<()> {
        let Some(first) = (0..L::WIDTH).find(|&i| active & (1 << i) != 0) else {
            return Ok(());
        };
        self.estimator.set_active(active);
        loop {
            let mut done = None;
            for (i, run) in runs.iter_mut().enumerate() {
                self.readings[i].clear();
                if active & (1 << i) == 0 {
                    continue;
                }
                let Some((onboard, tape)) = run.as_mut() else {
                    continue;
                };
                let finished =
                    onboard.take_samples(tape, vehicle, t_end_s, cancel, &mut self.readings[i])?;
                if *done.get_or_insert(finished) != finished {
                    return Err(out_of_step());
                }
            }
            let count = self.readings[first].len();
            if (0..L::WIDTH).any(|i| active & (1 << i) != 0 && self.readings[i].len() != count) {
                return Err(out_of_step());
            }
            for k in 0..count {
                self.feed(k, first, active)?;
            }
            if done != Some(false) {
                return Ok(());
            }
        }
    }

    /// The `k`-th reading of every active lane, in lanes (the others take lane `first`'s): the
    /// same kind at the same time in every lane, or the lanes are out of step.
    fn feed(&mut self, k: usize, first: usize, active: Mask) -> Result<()> {
        let readings = &self.readings;
        let reading = |i: usize| -> Result<Reading> {
            let lane = if active & (1 << i) != 0 { i } else { first };
            readings[lane].get(k).copied().ok_or_else(out_of_step)
        };
        let zero = [L::splat(0.0); 3];
        match reading(first)? {
            Reading::Imu(b) => {
                let mut imu = ImuLanes {
                    time_s: b.time_s,
                    gyro_rad_s: zero,
                    accel_m_s2: zero,
                    gyro_saturated: 0,
                    accel_saturated: 0,
                };
                for i in 0..L::WIDTH {
                    let Reading::Imu(s) = reading(i)? else {
                        return Err(out_of_step());
                    };
                    if s.time_s != b.time_s {
                        return Err(out_of_step());
                    }
                    set3(&mut imu.gyro_rad_s, i, &s.gyro_rad_s);
                    set3(&mut imu.accel_m_s2, i, &s.accel_m_s2);
                    imu.gyro_saturated |= u32::from(s.gyro_saturated) << i;
                    imu.accel_saturated |= u32::from(s.accel_saturated) << i;
                }
                self.estimator.push_imu(&imu)
            }
            Reading::Position(b) => {
                let mut fix = PositionLanes {
                    valid_at_s: b.valid_at_s,
                    position_m: zero,
                    velocity_m_s: b.velocity_m_s.map(|_| zero),
                    attitude: b.attitude.map(|_| [L::splat(0.0); 4]),
                };
                for i in 0..L::WIDTH {
                    let Reading::Position(f) = reading(i)? else {
                        return Err(out_of_step());
                    };
                    if f.valid_at_s != b.valid_at_s
                        || f.velocity_m_s.is_some() != b.velocity_m_s.is_some()
                        || f.attitude.is_some() != b.attitude.is_some()
                    {
                        return Err(out_of_step());
                    }
                    set3(&mut fix.position_m, i, &f.position_m);
                    if let (Some(v), Some(lv)) = (f.velocity_m_s, fix.velocity_m_s.as_mut()) {
                        set3(lv, i, &v);
                    }
                    if let (Some(q), Some(lq)) = (f.attitude, fix.attitude.as_mut()) {
                        set_quat(lq, i, &q);
                    }
                }
                self.estimator.push_position(&fix);
                Ok(())
            }
            Reading::Magnetometer(b) => {
                let mut field = zero;
                for i in 0..L::WIDTH {
                    let Reading::Magnetometer(m) = reading(i)? else {
                        return Err(out_of_step());
                    };
                    if m.time_s != b.time_s {
                        return Err(out_of_step());
                    }
                    set3(&mut field, i, &m.field_ut);
                }
                self.estimator.push_magnetometer(b.time_s, &field);
                Ok(())
            }
        }
    }

    /// Every lane's estimate carried to the control step at `t_s` ([`Onboard::estimate`] per
    /// lane), read by [`OnboardLanes::estimate`].
    pub(crate) fn estimates_at(&mut self, t_s: f64) {
        self.estimator.estimates_at(t_s, &mut self.estimates);
    }

    /// Lane `i`'s estimate of the last [`OnboardLanes::estimates_at`].
    pub(crate) fn estimate(&self, i: usize) -> Estimate {
        self.estimates[i]
    }

    /// Lane `i`'s recorded row of `estimate` ([`Onboard::row`]).
    pub(crate) fn row(&self, i: usize, estimate: &Estimate) -> EstimateRow {
        row(estimate, &self.estimator.variances(i))
    }

    /// Lane `i`'s counts into `record` (its run's sample counts from `onboard`).
    pub(crate) fn finish(&self, i: usize, onboard: &Onboard, record: &mut SensingRecord) {
        onboard.finish_with(record, self.estimator.counts(i));
    }
}

fn out_of_step() -> RfError {
    RfError::invalid(
        "sensing",
        "the sensors of runs flown in lanes fell out of step (an internal error: please report it)",
    )
}
