//! Many runs in parallel ([`simulate_batch`]), flown four runs at a time in SIMD lanes ([`crate::flight::lanes`]): the rigid-body
//! RK4 step, the vehicle wrench, the actuator lag and the rotor sums step four vehicles per
//! AVX2 register; each run's own controller, limits, faults and recording stay per run.
//!
//! # What flies in lanes, what falls back
//! A run flies in lanes when the batch has no sensor noise and no wind profile (constant wind is
//! fine), fixed-pitch actuators without a rate limit (a first-order lag or
//! none), no quadratic drag and no rotor inertia, and its checks pass; four such runs form a
//! group when their fault times are the same (the rotors and efficiencies may differ: the
//! intervals split at the same times). Every other run, and the runs left over when a set of
//! equal fault times does not fill a group, fly with the scalar simulator
//! ([`crate::flight::simulation::simulate_cancellable`]). [`BatchLanes::Scalar`] flies them all
//! with it.
//!
//! # Sensing in lanes
//! With sensing (`SimulationConfig::sensing`) the truth flies in lanes. Where the runs' sensors
//! share one schedule (every suite whose position fixes do not drop out at random, i.e. motion
//! capture and RTK) so do their truth between nodes, their sensor schedule and their estimators
//! ([`OnboardLanes`]): the group writes one tape in lanes
//! ([`crate::flight::simulation::tape_lanes`]: a node at each RK4 interval's start with the
//! rotor totals the interval starts from and its first RK4 stage, and one at the period's end),
//! the first flying run's clocks give the sample times, every lane's truth at a sample time is
//! extended at once, each run's sensor draws its own sample from its own noise streams, and the
//! estimators read the readings in lanes. Otherwise (GNSS: each run's fixes drop out at random)
//! each run keeps its own sensors, estimator and tape ([`Onboard`]), which the group writes as
//! the scalar integrator does, leaving out the nodes no sample reads (a sample reads the last
//! node at or before its time, so the node of an interval `[a, b)` is read only when a sensor's
//! clock has a sample in it, and the period's end node only by a sample due at the period's
//! end: `Onboard::samples_in`). Either tape's nodes are the scalar ones bit for bit (the lanes'
//! states and rotor sums are, and the rotor thrusts are the scalar products of the lane's
//! efficiencies and channels), so are the sensor samples, the estimates and the commands; a node's
//! dynamics are the lanes' first RK4 stage where the scalar integrator shares its first stage's
//! wrench (the same function of the same inputs).
//!
//! # Why the results are the scalar ones
//! Lane `i` computes what the scalar period ([`crate::flight::simulation::step`]) computes, in
//! the same order, with elementwise IEEE operations: the trajectories are equal bit for bit,
//! checked against the scalar simulator by the tests (faults, saturation, lag, divergence,
//! non-finite commands). A lane that diverges locates its crossing with the scalar code and
//! stops; the others go on.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::analysis::LanePath;
use crate::cancel::Cancel;
use crate::error::Result;
use crate::flight::actuator::Actuators;
use crate::flight::estimation::lanes::math::lane3;
use crate::flight::fault_schedule::FaultSchedule;
use crate::flight::lanes::{
    detected_path, runs_avx2, BodyLanes, Choice, F64x4, Lanes, TotalsLanes, VehicleLanes,
};
use crate::flight::simulation::config::SimulationConfig;
use crate::flight::simulation::divergence::{Divergence, DivergenceKind, Limits};
use crate::flight::simulation::driver::{
    check_batch, check_run, empty_trajectory, end_with, fly_batch_run, truth_samples, BatchRun,
};
use crate::flight::simulation::onboard::Onboard;
use crate::flight::simulation::onboard_lanes::OnboardLanes;
use crate::flight::simulation::recording::{records, NoObserver, Trajectory};
use crate::flight::simulation::step::{located_divergence, push_node};
use crate::flight::simulation::tape::Tape;
use crate::flight::simulation::tape_lanes::TapeLanes;
use crate::flight::vehicle::{RotorTotals, Vehicle};
use crate::state::ControllerInput;

/// How a batch steps its runs: `Auto` flies groups of four in SIMD lanes where it can (AVX2
/// when the CPU has it, the portable build otherwise; same results), `Portable` the same groups
/// in the portable build whatever the CPU (the form a CPU without AVX2 runs: to check on one
/// machine that a result does not depend on AVX2), `Scalar` one run at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BatchLanes {
    #[default]
    Auto,
    Portable,
    Scalar,
}

impl BatchLanes {
    /// The setting's name as Python spells it.
    pub fn name(self) -> &'static str {
        match self {
            BatchLanes::Auto => "auto",
            BatchLanes::Portable => "portable",
            BatchLanes::Scalar => "scalar",
        }
    }
}

/// Runs per group: one AVX2 register of `f64`.
const WIDTH: usize = Group::WIDTH;
/// The lane type of a group.
type Group = F64x4;

/// One run of a group, ready to fly.
pub(super) struct Lane {
    run: BatchRun,
    actuators: Actuators,
    efficiency: Vec<f64>,
    schedule: FaultSchedule,
    limits: Limits,
    trajectory: Trajectory,
    /// The run's sensors and estimator and their tape, with sensing (module docs).
    onboard: Option<(Onboard, Tape)>,
}

/// Where each run of a batch goes.
pub(super) enum Plan {
    Scalar(usize, BatchRun),
    Group(Vec<(usize, Lane)>),
}

/// Many runs in parallel (rayon); results in input order. With sensor noise or sensing, run `i`
/// uses seed `seed + i`, so runs are independent and the batch is reproducible. Every run checks
/// `cancel` once per control period. Groups of four fly in SIMD lanes where they can
/// ([`BatchLanes::Auto`]; same results).
pub fn simulate_batch(
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    runs: Vec<BatchRun>,
    config: &SimulationConfig,
    cancel: &Cancel,
) -> Result<Vec<Trajectory>> {
    simulate_batch_lanes(
        vehicle,
        actuators,
        initial_efficiency,
        runs,
        config,
        cancel,
        BatchLanes::default(),
    )
}

/// [`simulate_batch`] with the lane setting `lanes`: `Auto` flies groups of four runs in SIMD
/// lanes where it can (same results, [`crate::flight::simulation::batch_lanes`]), `Portable` the
/// same groups in the baseline build, `Scalar` one run at a time ([`BatchLanes`]).
pub fn simulate_batch_lanes(
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    runs: Vec<BatchRun>,
    config: &SimulationConfig,
    cancel: &Cancel,
    lanes: BatchLanes,
) -> Result<Vec<Trajectory>> {
    check_batch(config, &runs)?;
    let count = runs.len();
    let plans = plan(vehicle, actuators, initial_efficiency, runs, config, lanes);
    let flown: Vec<Vec<(usize, Trajectory)>> = plans
        .into_par_iter()
        .map(|plan| {
            plan.fly(
                vehicle,
                actuators,
                initial_efficiency,
                config,
                cancel,
                lanes,
            )
        })
        .collect::<Result<_>>()?;
    let mut out: Vec<Option<Trajectory>> = (0..count).map(|_| None).collect();
    for (i, trajectory) in flown.into_iter().flatten() {
        out[i] = Some(trajectory);
    }
    Ok(out.into_iter().flatten().collect())
}

impl Plan {
    /// The batch indices of the runs this plan flies, in the order [`Plan::fly`] returns them.
    pub(super) fn indices(&self) -> Vec<usize> {
        match self {
            Plan::Scalar(i, _) => vec![*i],
            Plan::Group(group) => group.iter().map(|(i, _)| *i).collect(),
        }
    }

    /// Flies the plan's runs: one with the scalar simulator (the batch's rule,
    /// [`fly_batch_run`]) or a group in lanes (in the portable build with `lanes` `Portable`).
    pub(super) fn fly(
        self,
        vehicle: &Vehicle,
        actuators: &Actuators,
        initial_efficiency: &[f64],
        config: &SimulationConfig,
        cancel: &Cancel,
        lanes: BatchLanes,
    ) -> Result<Vec<(usize, Trajectory)>> {
        match self {
            Plan::Scalar(i, run) => {
                let trajectory = fly_batch_run(
                    i,
                    run,
                    vehicle,
                    actuators,
                    initial_efficiency,
                    config,
                    cancel,
                )?;
                Ok(vec![(i, trajectory)])
            }
            Plan::Group(group) => {
                let path = match lanes {
                    BatchLanes::Portable => LanePath::Portable,
                    // `Scalar` plans no group.
                    BatchLanes::Auto | BatchLanes::Scalar => detected_path(),
                };
                fly_group(vehicle, actuators, group, config, cancel, path)
            }
        }
    }
}

/// Whether the batch's setting, vehicle and actuators let runs fly in lanes (module docs).
fn lanes_possible(
    vehicle: &Vehicle,
    actuators: &Actuators,
    config: &SimulationConfig,
    lanes: BatchLanes,
) -> bool {
    lanes != BatchLanes::Scalar
        && config.noise.is_none()
        && config.wind_profile.is_empty()
        && matches!(actuators, Actuators::FixedPitch(_))
        && actuators.lags()[0].rate_limit_per_s == f64::INFINITY
        && VehicleLanes::<f64>::new(vehicle, &config.wind_m_s).is_some()
}

/// A run's fault times, sorted, as bits (the key runs group by).
type FaultTimes = Vec<u64>;

/// Groups of four runs with equal fault times; the rest scalar (module docs).
pub(super) fn plan(
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    runs: Vec<BatchRun>,
    config: &SimulationConfig,
    lanes: BatchLanes,
) -> Vec<Plan> {
    let mut plans = Vec::new();
    if !lanes_possible(vehicle, actuators, config, lanes) {
        return runs
            .into_iter()
            .enumerate()
            .map(|(i, run)| Plan::Scalar(i, run))
            .collect();
    }
    // Filling groups, keyed by the sorted fault times' bits.
    let mut filling: Vec<(FaultTimes, Vec<(usize, Lane)>)> = Vec::new();
    for (i, run) in runs.into_iter().enumerate() {
        let lane = match ready(i, vehicle, actuators, initial_efficiency, run, config) {
            Ok(lane) => lane,
            Err(run) => {
                plans.push(Plan::Scalar(i, run));
                continue;
            }
        };
        let mut key: Vec<u64> = lane.run.faults.iter().map(|f| f.time_s.to_bits()).collect();
        key.sort_unstable();
        let at = match filling.iter().position(|(k, _)| *k == key) {
            Some(at) => at,
            None => {
                filling.push((key, Vec::new()));
                filling.len() - 1
            }
        };
        filling[at].1.push((i, lane));
        if filling[at].1.len() == WIDTH {
            let (_, group) = filling.swap_remove(at);
            plans.push(Plan::Group(group));
        }
    }
    for (_, rest) in filling {
        plans.extend(rest.into_iter().map(|(i, lane)| Plan::Scalar(i, lane.run)));
    }
    plans
}

/// Run `run` checked and set up for a lane, or given back for the scalar simulator (a check
/// fails, so it reports the error; or it starts beyond a limit).
// The run handed back is moved once per run, not per step: its size costs nothing.
#[allow(clippy::result_large_err)]
fn ready(
    index: usize,
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    run: BatchRun,
    config: &SimulationConfig,
) -> std::result::Result<Lane, BatchRun> {
    let mut own = actuators.clone();
    if let Some(command) = &run.initial_command {
        if own.settle(command).is_err() {
            return Err(run);
        }
    }
    let checked = check_run(
        vehicle,
        &own,
        run.controller.as_ref(),
        initial_efficiency,
        &run.faults,
        &run.x0,
        config,
    );
    let Ok(mut schedule) = checked else {
        return Err(run);
    };
    let h = config.dt_s / config.substeps as f64;
    let limits = Limits::new(&config.limits, config.ground_z_m, -run.x0.position_m.z, h);
    let mut efficiency = initial_efficiency.to_vec();
    schedule.apply_due(0.0, &mut efficiency);
    if limits.exceeded(&run.x0).is_some() {
        return Err(run);
    }
    let m = vehicle.rotor_count();
    let mut trajectory = empty_trajectory(config, own.channels() * m, m);
    let onboard = match &config.sensing {
        Some(sensing) => {
            // Run `index` of the batch: seed shifted by it (`fly_batch_run`'s rule).
            let mut own_sensing = *sensing;
            own_sensing.seed = own_sensing.seed.wrapping_add(index as u64);
            let reads_samples = run.controller.reads_samples();
            let Ok((onboard, tape)) = Onboard::new(&own_sensing, &run.x0, &own, reads_samples)
            else {
                return Err(run);
            };
            let rows = config.steps() / config.record_every + 3;
            trajectory.sensing = Some(onboard.record(rows));
            Some((onboard, tape))
        }
        None => None,
    };
    Ok(Lane {
        run,
        actuators: own,
        efficiency,
        schedule,
        limits,
        trajectory,
        onboard,
    })
}

/// Flies a group of four lanes in the compiled form `path` (AVX2 only where the CPU has it:
/// module docs of [`crate::flight::lanes`]).
fn fly_group(
    vehicle: &Vehicle,
    actuators: &Actuators,
    group: Vec<(usize, Lane)>,
    config: &SimulationConfig,
    cancel: &Cancel,
    path: LanePath,
) -> Result<Vec<(usize, Trajectory)>> {
    #[cfg(target_arch = "x86_64")]
    if runs_avx2(path, Choice::Group) {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { fly_group_avx2(vehicle, actuators, group, config, cancel) };
    }
    fly_group_lanes::<Group>(vehicle, actuators, group, config, cancel, path)
}

/// [`fly_group_lanes`] compiled for AVX2 and FMA (Rust contracts no `a * b + c`, so FMA
/// changes no result).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn fly_group_avx2(
    vehicle: &Vehicle,
    actuators: &Actuators,
    group: Vec<(usize, Lane)>,
    config: &SimulationConfig,
    cancel: &Cancel,
) -> Result<Vec<(usize, Trajectory)>> {
    fly_group_lanes::<Group>(vehicle, actuators, group, config, cancel, LanePath::Avx2)
}

/// The control loop of [`crate::flight::simulation::simulate_observed`] for `L::WIDTH` runs.
#[inline(always)]
fn fly_group_lanes<L: Lanes>(
    vehicle: &Vehicle,
    actuators: &Actuators,
    mut group: Vec<(usize, Lane)>,
    config: &SimulationConfig,
    cancel: &Cancel,
    path: LanePath,
) -> Result<Vec<(usize, Trajectory)>> {
    let Some(model) = VehicleLanes::<L>::new(vehicle, &config.wind_m_s) else {
        unreachable!("lanes_possible checked the vehicle");
    };
    let m = vehicle.rotor_count();
    let count = actuators.channels() * m;
    let steps = config.steps();
    let mut body = BodyLanes::<L>::zeros();
    for (i, (_, lane)) in group.iter_mut().enumerate() {
        body.set(i, &lane.run.x0);
        lane.run.controller.reset();
    }
    let mut onboard_lanes = onboard_in_lanes::<L>(&group, m, path);
    let mut period = Period::<L>::new(vehicle, actuators, &group);
    // The scalar driver's start: the tape's first node, the sensors' samples at 0.
    match onboard_lanes.as_mut() {
        Some(onboard_lanes) => {
            let tape = onboard_lanes.tape_mut();
            tape.clear();
            period.push_end_node(tape, &model, 0.0, &body, None);
        }
        None => {
            for (_, lane) in group.iter_mut() {
                if let Some((_, tape)) = lane.onboard.as_mut() {
                    tape.clear();
                    let x0 = lane.run.x0;
                    let channels = lane.actuators.state();
                    push_node(
                        tape,
                        vehicle,
                        config,
                        0.0,
                        &x0,
                        &lane.actuators,
                        channels,
                        &lane.efficiency,
                        None,
                    );
                }
            }
        }
    }
    catch_up(
        &mut group,
        onboard_lanes.as_mut(),
        &[true; WIDTH],
        (vehicle, &model),
        0.0,
        cancel,
    )?;
    let mut active = [true; WIDTH];
    let mut commands = vec![0.0; count * WIDTH];
    let mut rotor_thrust = vec![0.0; m];
    for k in 0..=steps {
        cancel.check()?;
        let t = config.step_time(k);
        if let Some(onboard_lanes) = onboard_lanes.as_mut() {
            onboard_lanes.estimates_at(t);
        }
        for (i, (_, lane)) in group.iter_mut().enumerate() {
            if !active[i] {
                continue;
            }
            let state = body.get(i);
            let command = &mut commands[i * count..(i + 1) * count];
            let controller = lane.run.controller.as_mut();
            // With sensing: the estimate, and the sensors' samples for a controller that reads
            // them (the scalar driver's rule).
            let onboard = lane.onboard.as_ref().map(|(onboard, _)| onboard);
            let estimate = match &onboard_lanes {
                Some(onboard_lanes) => onboard.map(|_| onboard_lanes.estimate(i)),
                None => onboard.map(|o| o.estimate(t)),
            };
            let input = if let (Some(estimate), Some(onboard)) = (&estimate, onboard) {
                onboard.controller_input(estimate, controller.reads_samples())
            } else if controller.reads_samples() {
                truth_samples(
                    vehicle,
                    &lane.actuators,
                    &lane.efficiency,
                    config,
                    t,
                    (&state, &state),
                    &mut rotor_thrust,
                )
            } else {
                ControllerInput::state_only(&state)
            };
            controller.command_with(t, &input, command)?;
            let finite = command.iter().all(|c| c.is_finite());
            if records(k, config.record_every, steps) || !finite {
                let trajectory = &mut lane.trajectory;
                trajectory.push_step(t, &state, &lane.efficiency, &lane.actuators, None);
                trajectory.rotor_command.extend_from_slice(command);
                if let (Some(record), Some(onboard), Some(estimate)) =
                    (trajectory.sensing.as_mut(), onboard, &estimate)
                {
                    record.rows.push(match &onboard_lanes {
                        Some(onboard_lanes) => onboard_lanes.row(i, estimate),
                        None => onboard.row(estimate),
                    });
                }
            }
            if !finite {
                lane.trajectory.divergence = Some(Divergence {
                    time_s: t,
                    kind: DivergenceKind::NonFiniteCommand,
                    state,
                });
                active[i] = false;
            }
        }
        if k == steps || !active.contains(&true) {
            break;
        }
        let t_next = config.step_time(k + 1);
        period.fly(
            vehicle,
            &model,
            config,
            (t, t_next),
            &commands,
            &mut body,
            &mut group,
            onboard_lanes.as_mut().map(|o| o.tape_mut()),
            &mut active,
        );
        catch_up(
            &mut group,
            onboard_lanes.as_mut(),
            &active,
            (vehicle, &model),
            t_next,
            cancel,
        )?;
    }
    Ok(group
        .into_iter()
        .enumerate()
        .map(|(k, (i, mut lane))| {
            // The run's counts (a run that diverged has them already, unchanged since: its lane
            // stopped counting when it stopped).
            if let (Some(record), Some((onboard, _))) =
                (lane.trajectory.sensing.as_mut(), lane.onboard.as_ref())
            {
                match &onboard_lanes {
                    Some(onboard_lanes) => onboard_lanes.finish(k, onboard, record),
                    None => onboard.finish(record),
                }
            }
            (i, lane.trajectory)
        })
        .collect())
}

/// The group's sensors and estimators in lanes when its runs fly on sensors that share one
/// schedule ([`OnboardLanes::new`], its tape with the `rotors` thrusts; its estimators in the
/// compiled form `path`); `None` without sensing or when they do not (each run's own estimator
/// and tape then).
fn onboard_in_lanes<L: Lanes>(
    group: &[(usize, Lane)],
    rotors: usize,
    path: LanePath,
) -> Option<OnboardLanes<L>> {
    let onboards: Vec<&Onboard> = group
        .iter()
        .filter_map(|(_, lane)| lane.onboard.as_ref().map(|(onboard, _)| onboard))
        .collect();
    let starts: Vec<_> = group.iter().map(|(_, lane)| lane.run.x0).collect();
    OnboardLanes::new(&onboards, &starts, rotors, path)
}

/// Every active run's sensors take their samples up to `t_s`, and its estimator reads them: in
/// lanes (`onboard_lanes`, from the group's tape) or each run's own (from its own tape).
#[inline(always)]
fn catch_up<L: Lanes>(
    group: &mut [(usize, Lane)],
    onboard_lanes: Option<&mut OnboardLanes<L>>,
    active: &[bool; WIDTH],
    (vehicle, model): (&Vehicle, &VehicleLanes<L>),
    t_s: f64,
    cancel: &Cancel,
) -> Result<()> {
    match onboard_lanes {
        Some(onboard_lanes) => {
            let active_lanes = (0..WIDTH)
                .filter(|&i| active[i])
                .fold(0, |m, i| m | (1 << i));
            let mut runs = group.iter_mut();
            let mut onboards: [Option<&mut Onboard>; WIDTH] = std::array::from_fn(|_| {
                runs.next()
                    .and_then(|(_, lane)| lane.onboard.as_mut().map(|(o, _)| o))
            });
            onboard_lanes.catch_up(&mut onboards, active_lanes, model, t_s, cancel)
        }
        None => {
            for (i, (_, lane)) in group.iter_mut().enumerate() {
                if let (true, Some((onboard, tape))) = (active[i], lane.onboard.as_mut()) {
                    onboard.catch_up(tape, vehicle, t_s, cancel)?;
                }
            }
            Ok(())
        }
    }
}

/// One control period of a group ([`crate::flight::simulation::step`]'s `Integrator::period`
/// for fixed-pitch channels and constant wind) and its work arrays.
struct Period<L> {
    /// Saturated commands per lane (for the scalar crossing location).
    targets: Vec<Vec<f64>>,
    target_lanes: Vec<L>,
    channel_lanes: Vec<L>,
    /// One lane's channels, to hand to its scalar actuators.
    channel_buffer: Vec<f64>,
    nodes: [Vec<L>; 3],
    efficiency_lanes: Vec<L>,
    rotor_xy_m: Vec<(L, L)>,
    torque_per_thrust_m: Vec<L>,
    time_constant_s: f64,
}

impl<L: Lanes> Period<L> {
    fn new(vehicle: &Vehicle, actuators: &Actuators, group: &[(usize, Lane)]) -> Self {
        let Actuators::FixedPitch(fixed) = actuators else {
            unreachable!("lanes_possible checked the actuators");
        };
        let m = vehicle.rotor_count();
        let mut channel_lanes = vec![L::splat(0.0); m];
        for (i, (_, lane)) in group.iter().enumerate() {
            for (r, &x) in lane.actuators.state().iter().enumerate() {
                channel_lanes[r].set_lane(i, x);
            }
        }
        let mut period = Period {
            targets: vec![vec![0.0; m]; WIDTH],
            target_lanes: vec![L::splat(0.0); m],
            channel_lanes,
            channel_buffer: vec![0.0; m],
            nodes: std::array::from_fn(|_| vec![L::splat(0.0); m]),
            efficiency_lanes: vec![L::splat(0.0); m],
            rotor_xy_m: vehicle
                .rotor_xy_m()
                .iter()
                .map(|&(x, y)| (L::splat(x), L::splat(y)))
                .collect(),
            torque_per_thrust_m: fixed
                .torque_per_thrust_m()
                .iter()
                .map(|&c| L::splat(c))
                .collect(),
            time_constant_s: actuators.lags()[0].time_constant_s,
        };
        period.load_efficiency(group);
        period
    }

    /// Sets `actuators` (lane `i`'s) to the lane's channel states.
    fn load_channels(&mut self, i: usize, actuators: &mut Actuators) {
        for (x, c) in self.channel_buffer.iter_mut().zip(&self.channel_lanes) {
            *x = c.lane(i);
        }
        actuators.set_state(&self.channel_buffer);
    }

    fn load_efficiency(&mut self, group: &[(usize, Lane)]) {
        for (i, (_, lane)) in group.iter().enumerate() {
            for (r, &eta) in lane.efficiency.iter().enumerate() {
                self.efficiency_lanes[r].set_lane(i, eta);
            }
        }
    }

    /// The rotor sums with the channels at `channels` ([`crate::flight::vehicle::RotorTotals`]).
    #[inline(always)]
    fn totals(&self, channels: &[L]) -> TotalsLanes<L> {
        let zero = L::splat(0.0);
        let mut totals = TotalsLanes {
            thrust_n: zero,
            torque_body_nm: [zero; 3],
        };
        for (r, &command) in channels.iter().enumerate() {
            let thrust = self.efficiency_lanes[r] * command;
            let (x, y) = self.rotor_xy_m[r];
            totals.thrust_n = totals.thrust_n + thrust;
            totals.torque_body_nm[0] = totals.torque_body_nm[0] - y * thrust;
            totals.torque_body_nm[1] = totals.torque_body_nm[1] + x * thrust;
            totals.torque_body_nm[2] =
                totals.torque_body_nm[2] + self.torque_per_thrust_m[r] * thrust;
        }
        totals
    }

    /// The channels `elapsed_s` into an interval (the lag's exact response without a rate
    /// limit, [`crate::flight::actuator::Lag::response`]), into node `node`.
    #[inline(always)]
    fn respond(&mut self, node: usize, elapsed_s: f64, decay: f64) {
        let out = &mut self.nodes[node];
        if self.time_constant_s > 0.0 {
            if elapsed_s == 0.0 {
                out.copy_from_slice(&self.channel_lanes);
            } else {
                let decay = L::splat(decay);
                for ((o, &x), &target) in out
                    .iter_mut()
                    .zip(&self.channel_lanes)
                    .zip(&self.target_lanes)
                {
                    *o = target - (target - x) * decay;
                }
            }
        } else {
            out.copy_from_slice(&self.target_lanes);
        }
    }

    /// Integrates the active lanes from `t` to `t_next` with their commands held; a lane whose
    /// step crosses a limit ends with the located divergence and is marked inactive.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn fly(
        &mut self,
        vehicle: &Vehicle,
        model: &VehicleLanes<L>,
        config: &SimulationConfig,
        (t, t_next): (f64, f64),
        commands: &[f64],
        body: &mut BodyLanes<L>,
        group: &mut [(usize, Lane)],
        mut tape_lanes: Option<&mut TapeLanes<L>>,
        active: &mut [bool; WIDTH],
    ) {
        let tape_lanes_used = tape_lanes.is_some();
        let m = self.target_lanes.len();
        for (i, (_, lane)) in group.iter().enumerate() {
            lane.actuators
                .saturate(&commands[i * m..(i + 1) * m], &mut self.targets[i]);
            for (r, &x) in self.targets[i].iter().enumerate() {
                self.target_lanes[r].set_lane(i, x);
            }
        }
        let h = (t_next - t) / config.substeps as f64;
        let actuators = &group[0].1.actuators;
        let half_decay = actuators.decay(0.5 * h)[0];
        let decays = [1.0, half_decay, half_decay * half_decay];
        let mut start_totals: Option<TotalsLanes<L>> = None;
        let sensing = config.sensing.is_some();
        if let Some(tape) = tape_lanes.as_mut() {
            tape.clear();
        } else if sensing {
            for (_, lane) in group.iter_mut() {
                if let Some((_, tape)) = lane.onboard.as_mut() {
                    tape.clear();
                }
            }
        }
        for s in 0..config.substeps {
            let mut a = t + s as f64 * h;
            let b = if s + 1 == config.substeps {
                t_next
            } else {
                t + (s + 1) as f64 * h
            };
            while a < b {
                // The lanes share their fault times, so their intervals.
                let end = group[0].1.schedule.interval_end(a, b);
                let len = end - a;
                let split = (len - h).abs() > 1e-9 * h;
                let mut totals = [start_totals.unwrap_or(TotalsLanes {
                    thrust_n: L::splat(0.0),
                    torque_body_nm: [L::splat(0.0); 3],
                }); 3];
                for (node, elapsed) in [0.0, 0.5 * len, len].into_iter().enumerate() {
                    if node == 0 && start_totals.is_some() {
                        continue;
                    }
                    let decay = if split {
                        group[0].1.actuators.decay(elapsed)[0]
                    } else {
                        decays[node]
                    };
                    self.respond(node, elapsed, decay);
                    totals[node] = self.totals(&self.nodes[node]);
                }
                let next = if sensing {
                    // The first RK4 stage is the dynamics the tape extends a node with.
                    let k1 = model.derivative(body, &totals[0]);
                    match tape_lanes.as_mut() {
                        Some(tape) => self.push_start_node(tape, a, body, &totals[0], &k1),
                        None => self.push_nodes(
                            vehicle,
                            config,
                            (a, end),
                            body,
                            (&totals[0], &k1),
                            group,
                            active,
                        ),
                    }
                    model.rk4_step_from(body, &k1, len, &totals)
                } else {
                    model.rk4_step(body, len, &totals)
                };
                let (n3z, speed2, rate2) = next.limit_parts();
                for (i, (_, lane)) in group.iter_mut().enumerate() {
                    if !active[i] {
                        continue;
                    }
                    let position = next.position_m.map(|p| p.lane(i));
                    if lane.limits.within_parts(
                        n3z.lane(i),
                        position,
                        speed2.lane(i),
                        rate2.lane(i),
                    ) {
                        continue;
                    }
                    let after = next.get(i);
                    self.load_channels(i, &mut lane.actuators);
                    let divergence = located_divergence(
                        vehicle,
                        config,
                        &lane.limits,
                        &mut lane.actuators,
                        &self.targets[i],
                        &lane.efficiency,
                        &body.get(i),
                        (a, len),
                        after,
                    );
                    end_with(
                        &mut lane.trajectory,
                        &mut NoObserver,
                        divergence,
                        &lane.efficiency,
                        &lane.actuators,
                        config,
                        lane.onboard.as_ref().map(|(onboard, _)| onboard),
                    );
                    active[i] = false;
                }
                *body = next;
                std::mem::swap(&mut self.channel_lanes, &mut self.nodes[2]);
                start_totals = Some(totals[2]);
                a = end;
                let mut applied = false;
                for (i, (_, lane)) in group.iter_mut().enumerate() {
                    applied |= lane.schedule.apply_due(a, &mut lane.efficiency) && active[i];
                }
                if applied {
                    self.load_efficiency(group);
                    start_totals = None;
                }
            }
        }
        if let Some(tape) = tape_lanes {
            self.push_end_node(tape, model, t_next, body, start_totals.as_ref());
        }
        for (i, (_, lane)) in group.iter_mut().enumerate() {
            if active[i] {
                self.load_channels(i, &mut lane.actuators);
                // The period's end node (the scalar integrator's last), where a sample reads it.
                if let (false, Some((onboard, tape))) = (tape_lanes_used, lane.onboard.as_mut()) {
                    if !onboard.samples_due_at_or_after(t_next) {
                        continue;
                    }
                    push_node(
                        tape,
                        vehicle,
                        config,
                        t_next,
                        &body.get(i),
                        &lane.actuators,
                        lane.actuators.state(),
                        &lane.efficiency,
                        None,
                    );
                }
            }
        }
    }

    /// The group's tape node at the start `a_s` of an RK4 interval (the lanes' `push_nodes`):
    /// the lanes' state, the channels the interval starts from (the targets for instant rotors)
    /// with the interval's rotor `totals` there and its first RK4 stage `k1`.
    #[inline(always)]
    fn push_start_node(
        &self,
        tape: &mut TapeLanes<L>,
        a_s: f64,
        body: &BodyLanes<L>,
        totals: &TotalsLanes<L>,
        k1: &BodyLanes<L>,
    ) {
        let channels = if self.time_constant_s > 0.0 {
            &self.channel_lanes
        } else {
            &self.target_lanes
        };
        let efficiency = &self.efficiency_lanes;
        tape.push(a_s, body, totals, k1, |r| efficiency[r] * channels[r]);
    }

    /// The group's tape node at `t_s` where the lanes are at `body` with the channels where they
    /// are (the start of a flight, the end of a period): the rotor totals there (`known`: the
    /// last interval's end totals, the same function of the same channels and efficiencies,
    /// unless a fault changed an efficiency there; the scalar integrator's end node reuses them
    /// too) and the dynamics computed there.
    #[inline(always)]
    fn push_end_node(
        &self,
        tape: &mut TapeLanes<L>,
        model: &VehicleLanes<L>,
        t_s: f64,
        body: &BodyLanes<L>,
        known: Option<&TotalsLanes<L>>,
    ) {
        let totals = known
            .copied()
            .unwrap_or_else(|| self.totals(&self.channel_lanes));
        let k1 = model.derivative(body, &totals);
        let (channels, efficiency) = (&self.channel_lanes, &self.efficiency_lanes);
        tape.push(t_s, body, &totals, &k1, |r| efficiency[r] * channels[r]);
    }

    /// Each active lane's tape node at the start `a_s` of an RK4 interval `[a_s, end_s)` where a
    /// sensor samples in it (module docs: a node no sample reads is not written): the lane's state and
    /// the channels the interval starts from (the targets for instant rotors, as the scalar
    /// integrator's `constant` case), with the interval's rotor totals there (`totals`: the
    /// scalar `rotor_totals` bit for bit; the net rotor spin left at zero, which the lanes'
    /// vehicles, without rotor inertia, never read), the constant wind, and the dynamics there,
    /// the interval's first RK4 stage `k1` (as the scalar integrator shares its wrench).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn push_nodes(
        &mut self,
        vehicle: &Vehicle,
        config: &SimulationConfig,
        (a_s, end_s): (f64, f64),
        body: &BodyLanes<L>,
        (totals, k1): (&TotalsLanes<L>, &BodyLanes<L>),
        group: &mut [(usize, Lane)],
        active: &[bool; WIDTH],
    ) {
        let source = if self.time_constant_s > 0.0 {
            &self.channel_lanes
        } else {
            &self.target_lanes
        };
        for (i, (_, lane)) in group.iter_mut().enumerate() {
            let (true, Some((onboard, tape))) = (active[i], lane.onboard.as_mut()) else {
                continue;
            };
            if !onboard.samples_in(a_s, end_s) {
                continue;
            }
            for (x, c) in self.channel_buffer.iter_mut().zip(source) {
                *x = c.lane(i);
            }
            let channels = &self.channel_buffer;
            let totals = RotorTotals {
                thrust_n: totals.thrust_n.lane(i),
                torque_body_nm: Vector3::from_fn(|k, _| totals.torque_body_nm[k].lane(i)),
                spin_rad_s: 0.0,
            };
            push_node(
                tape,
                vehicle,
                config,
                a_s,
                &body.get(i),
                &lane.actuators,
                channels,
                &lane.efficiency,
                Some((&totals, &config.wind_m_s)),
            );
            tape.share_rates(lane3(&k1.velocity_m_s, i), lane3(&k1.omega_rad_s, i));
        }
    }
}

#[cfg(test)]
#[path = "batch_lanes_tests.rs"]
mod tests;
