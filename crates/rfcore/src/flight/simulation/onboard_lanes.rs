//! The sensors and estimators of a group flown in lanes ([`OnboardLanes`]): each run's sensors
//! stay its own ([`Onboard`]: its own noise streams, biases and delays), read on one schedule
//! from the group's tape in lanes ([`TapeLanes`]), and the group's estimators take the runs'
//! readings together in lanes ([`EstimatorLanes`]), one lane per run. The runs of a group fly one
//! sensor suite, so their samples come at the same times in the same order (the module docs of
//! [`crate::flight::estimation::lanes`]); a suite whose position fixes drop out at random does
//! not, and its runs keep their scalar estimators and tapes ([`OnboardLanes::new`] declines).

use crate::analysis::LanePath;
use crate::cancel::Cancel;
use crate::error::{Result, RfError};
use crate::flight::estimation::lanes::kernels::ImuLanes;
use crate::flight::estimation::lanes::math::{set3, splat3, Mask, V3};
use crate::flight::estimation::lanes::{EstimatorLanes, PositionLanes};
use crate::flight::estimation::Estimate;
use crate::flight::lanes::{Lanes, VehicleLanes};
use crate::flight::simulation::onboard::{row, Next, Onboard};
use crate::flight::simulation::recording::{EstimateRow, SensingRecord};
use crate::flight::simulation::tape_lanes::TapeLanes;
use crate::state::RigidBodyState;

/// The most lanes a group has (an AVX2 register of `f64`).
const MAX_LANES: usize = 4;

pub(crate) struct OnboardLanes<L> {
    estimator: EstimatorLanes<L>,
    /// The group's truth between nodes, for every run's sensors.
    tape: TapeLanes<L>,
    /// Each lane's estimate at the current control step.
    estimates: Vec<Estimate>,
}

impl<L: Lanes> OnboardLanes<L> {
    /// The group's estimators in lanes, lane `i` starting from `starts[i]` with the settings of
    /// `onboards[i]`, and its tape (with `rotors` thrusts per node when a run reads rotor
    /// speeds); `None` when the lanes cannot share one schedule (a position source that drops
    /// fixes, or sensor profiles or estimator settings that differ) or there is not one run per
    /// lane. The estimators run in the compiled form `path`.
    pub(crate) fn new(
        onboards: &[&Onboard],
        starts: &[RigidBodyState],
        rotors: usize,
        path: LanePath,
    ) -> Option<Self> {
        let first = onboards.first()?;
        if onboards.len() != L::WIDTH
            || L::WIDTH > MAX_LANES
            || onboards.iter().any(|o| {
                o.drops_fixes()
                    || o.profile() != first.profile()
                    || o.estimator_settings() != first.estimator_settings()
            })
        {
            return None;
        }
        let estimator = EstimatorLanes::new(*first.estimator_settings(), starts, path).ok()?;
        let feedback = onboards.iter().any(|o| o.reads_rotor_speeds());
        Some(OnboardLanes {
            estimator,
            tape: TapeLanes::new(if feedback { rotors } else { 0 }),
            estimates: Vec::with_capacity(L::WIDTH),
        })
    }

    /// The group's tape (the runs' truth between nodes, in lanes), which the integrator writes.
    pub(crate) fn tape_mut(&mut self) -> &mut TapeLanes<L> {
        &mut self.tape
    }

    /// [`Onboard::catch_up`] for the lanes of `active` (the runs still flying), each run's
    /// sensors `runs[i]` in lane `i`: the runs share their sensors' clocks, so one schedule
    /// (the first active run's, with the rotor-speed clock of the first run that reads rotor
    /// speeds) takes every sample due up to `t_end_s` in time order, the truth there in every
    /// lane at once from the group's tape, each run's sensor its own sample; the estimators read
    /// the readings in lanes as they come, in the order the scalar estimator reads them. A lane
    /// not in `active` reads lane `first active`'s values and counts nothing. The samples and
    /// their order are those of the scalar `Onboard::take_samples` (a change there is a change
    /// here). Inlined into the group's flight, compiled for AVX2 where the group's `LanePath`
    /// asks for it and the CPU has it, as the tape's lanes are.
    #[inline(always)]
    pub(crate) fn catch_up(
        &mut self,
        runs: &mut [Option<&mut Onboard>],
        active: Mask,
        model: &VehicleLanes<L>,
        t_end_s: f64,
        cancel: &Cancel,
    ) -> Result<()> {
        let flying = |i: usize| active & (1 << i) != 0 && runs[i].is_some();
        // The flying lanes' indices, without an allocation per control period.
        let mut indices = [0; MAX_LANES];
        let mut count = 0;
        for i in (0..L::WIDTH).filter(|&i| flying(i)) {
            indices[count] = i;
            count += 1;
        }
        let lanes = &indices[..count];
        let Some(&first) = lanes.first() else {
            return Ok(());
        };
        let rotor = lanes
            .iter()
            .copied()
            .find(|&i| run(runs, i).reads_rotor_speeds());
        let active = lanes.iter().fold(0, |m, &i| m | (1 << i));
        self.estimator.set_active(active);
        loop {
            let leader = run(runs, first);
            let rotor_leader = rotor.map(|i| run(runs, i));
            let Some((which, t)) = leader.next_due(rotor_leader, t_end_s) else {
                break;
            };
            cancel.check()?;
            match which {
                Next::Position => {
                    let truth = self.tape.state_at(t);
                    for &i in lanes {
                        let onboard = run_mut(runs, i);
                        in_step(onboard, which, t)?;
                        onboard.sample_position(&truth.get(i));
                    }
                }
                Next::Magnetometer => {
                    let truth = self.tape.state_at(t);
                    // As the IMU's: every lane starts as the first flying lane's reading.
                    let mut field: Option<V3<L>> = None;
                    for &i in lanes {
                        let m = run_mut(runs, i)
                            .sample_magnetometer(&truth.get(i))
                            .filter(|m| m.time_s == t)
                            .ok_or_else(out_of_step)?;
                        set3(
                            field.get_or_insert_with(|| splat3(&m.field_ut)),
                            i,
                            &m.field_ut,
                        );
                    }
                    if let Some(field) = field {
                        self.estimator.push_magnetometer(t, &field);
                    }
                }
                Next::RotorSpeed => {
                    for &i in lanes {
                        let onboard = run_mut(runs, i);
                        if onboard.reads_rotor_speeds() {
                            in_step(onboard, which, t)?;
                            onboard.sample_rotor_speeds(self.tape.thrust_at(t, i))?;
                        }
                    }
                }
                Next::Imu => {
                    self.fuse_arrived(runs, lanes, t)?;
                    let truth = self.tape.imu_truth_at(model, t);
                    // Every lane starts as the first flying lane's sample (the lanes no longer
                    // flying read it); each other flying lane then takes its own.
                    let mut imu = None;
                    for &i in lanes {
                        let s = run_mut(runs, i).sample_imu(&truth.lane(i));
                        if s.time_s != t {
                            return Err(out_of_step());
                        }
                        imu.get_or_insert_with(|| ImuLanes::splat(&s))
                            .set_lane(i, &s);
                    }
                    if let Some(imu) = imu {
                        self.estimator.push_imu(&imu)?;
                    }
                }
            }
        }
        self.fuse_arrived(runs, lanes, t_end_s)?;
        for &i in lanes {
            run_mut(runs, i).take_rotor_reading(t_end_s);
        }
        Ok(())
    }

    /// Every position fix arrived by `t_s` in the flying `lanes` (the others read the first
    /// flying lane's), in lanes: the same fixes at the same times of validity in every lane, or
    /// the lanes are out of step.
    fn fuse_arrived(
        &mut self,
        runs: &mut [Option<&mut Onboard>],
        lanes: &[usize],
        t_s: f64,
    ) -> Result<()> {
        let first = lanes[0];
        while let Some(b) = run_mut(runs, first).poll_position(t_s) {
            // Every lane starts as the first flying lane's fix (the lanes no longer flying read
            // it); each other flying lane then takes its own.
            let mut fix = PositionLanes::splat(&b);
            for &i in &lanes[1..] {
                let f = run_mut(runs, i)
                    .poll_position(t_s)
                    .filter(|f| fix.matches(f))
                    .ok_or_else(out_of_step)?;
                fix.set_lane(i, &f);
            }
            self.estimator.push_position(&fix);
        }
        if lanes[1..]
            .iter()
            .any(|&i| run_mut(runs, i).poll_position(t_s).is_some())
        {
            return Err(out_of_step());
        }
        Ok(())
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

/// Run `i` of a group's lanes (a lane the caller found flying: it has its run's sensors).
fn run<'a>(runs: &'a [Option<&mut Onboard>], i: usize) -> &'a Onboard {
    runs[i]
        .as_deref()
        .expect("a flying lane has its run's sensors")
}

fn run_mut<'a>(runs: &'a mut [Option<&mut Onboard>], i: usize) -> &'a mut Onboard {
    runs[i]
        .as_deref_mut()
        .expect("a flying lane has its run's sensors")
}

/// `Ok` when the run's next sample of `which` is at `t_s` (the group's schedule), else the lanes
/// are out of step.
fn in_step(onboard: &Onboard, which: Next, t_s: f64) -> Result<()> {
    if onboard.next_sample_time_s(which) == t_s {
        Ok(())
    } else {
        Err(out_of_step())
    }
}

fn out_of_step() -> RfError {
    RfError::invalid(
        "sensing",
        "the sensors of runs flown in lanes fell out of step (an internal error: please report it)",
    )
}
