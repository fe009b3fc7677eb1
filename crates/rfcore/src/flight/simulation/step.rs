//! One control period of the coupled body and actuators: `substeps` RK4 steps with the command
//! held, the actuators following their exact response at the RK4 stage times, intervals ending at
//! every fault time, and the divergence check after every substep (module docs of
//! [`crate::flight::simulation`]). Also the up-front step-size check.

use crate::error::{Result, RfError};
use crate::flight::actuator::Actuators;
use crate::flight::fault_schedule::FaultSchedule;
use crate::flight::rigid_body::Wrench;
use crate::flight::simulation::config::SimulationConfig;
use crate::flight::simulation::divergence::{Divergence, Limits, MAX_RATE_STEP};
use crate::flight::simulation::tape::Tape;
use crate::flight::vehicle::{RotorTotals, Vehicle};
use crate::state::RigidBodyState;

/// The rotors' summed contribution with the channels at `states`.
#[inline]
pub(super) fn rotor_totals(
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
pub(crate) fn check_step_size(
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

/// One run's integrator: what stays fixed over the run and the work arrays every control period
/// reuses.
pub(crate) struct Integrator<'a> {
    vehicle: &'a Vehicle,
    config: &'a SimulationConfig,
    limits: Limits,
    instant: bool,
    constant_wind: bool,
    /// The command of the current period, saturated.
    targets: Vec<f64>,
    /// Channel states at the start, middle and end of an interval.
    nodes: [Vec<f64>; 3],
    /// The period's nodes for sensors on their own clocks (`None`: nobody samples between
    /// control steps; the integration is the same either way).
    tape: Option<Tape>,
}

impl<'a> Integrator<'a> {
    /// For a run of `vehicle` from `x0` (the divergence limits' reference altitude) with
    /// `actuators` (their command count and whether they respond instantly).
    pub(crate) fn new(
        vehicle: &'a Vehicle,
        actuators: &Actuators,
        config: &'a SimulationConfig,
        x0: &RigidBodyState,
    ) -> Self {
        let count = actuators.channels() * vehicle.rotor_count();
        let h_nominal = config.dt_s / config.substeps as f64;
        Integrator {
            vehicle,
            config,
            limits: Limits::new(
                &config.limits,
                config.ground_z_m,
                -x0.position_m.z,
                h_nominal,
            ),
            instant: actuators.is_instant(),
            constant_wind: config.wind_profile.is_empty(),
            targets: vec![0.0; count],
            nodes: [vec![0.0; count], vec![0.0; count], vec![0.0; count]],
            tape: None,
        }
    }

    /// Records every period's nodes on `tape` from now on.
    pub(crate) fn record_on(&mut self, tape: Tape) {
        self.tape = Some(tape);
    }

    /// The nodes of the last period (or of the start, [`Integrator::tape_start`]).
    pub(crate) fn tape(&mut self) -> Option<&mut Tape> {
        self.tape.as_mut()
    }

    /// Starts the tape with one node at `t_s`: `state` with the actuators as they are.
    pub(crate) fn tape_start(
        &mut self,
        t_s: f64,
        state: &RigidBodyState,
        actuators: &Actuators,
        efficiency: &[f64],
    ) {
        if let Some(tape) = self.tape.as_mut() {
            tape.clear();
            push_node(
                tape,
                self.vehicle,
                self.config,
                t_s,
                state,
                actuators,
                actuators.state(),
                efficiency,
                None,
            );
        }
    }

    /// The run's divergence limits.
    pub(crate) fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Integrates `state` and `actuators` from `t` to `t_next` with `command` held, applying the
    /// faults of `schedule` to `efficiency` at their times. A limit crossed within the period
    /// ends it: the divergence at the located crossing is returned, with `actuators` there
    /// (`state` is left at the start of the substep that crossed).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn period(
        &mut self,
        t: f64,
        t_next: f64,
        command: &[f64],
        state: &mut RigidBodyState,
        actuators: &mut Actuators,
        efficiency: &mut [f64],
        schedule: &mut FaultSchedule,
    ) -> Option<Divergence> {
        let (vehicle, config) = (self.vehicle, self.config);
        let body = vehicle.body();
        let h = (t_next - t) / config.substeps as f64;
        actuators.saturate(command, &mut self.targets);
        // The channels do not move within this control step (they jump to the command or sit
        // at it): one rotor evaluation serves every node of every substep.
        let constant = self.instant || actuators.state() == &self.targets[..];
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
        if let Some(tape) = self.tape.as_mut() {
            tape.clear();
        }
        for s in 0..config.substeps {
            let mut a = t + s as f64 * h;
            let b = if s + 1 == config.substeps {
                t_next
            } else {
                t + (s + 1) as f64 * h
            };
            while a < b {
                // One RK4 step of body and actuators over [a, end], end = b, the next fault or
                // the next wind step (evaluated at its left limit at `end`: a step acts from its
                // time on, exactly).
                let end = if self.constant_wind {
                    schedule.interval_end(a, b)
                } else {
                    config.wind_step_before(a, schedule.interval_end(a, b))
                };
                let len = end - a;
                let winds = if self.constant_wind {
                    [config.wind_m_s; 3]
                } else {
                    [
                        config.wind_at(a),
                        config.wind_at(a + 0.5 * len),
                        config.wind_before(end),
                    ]
                };
                let totals = if constant {
                    let at_start = match start_totals {
                        Some(t) => t,
                        None => rotor_totals(vehicle, actuators, &self.targets, efficiency),
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
                        actuators.response_with_decay(
                            &self.targets,
                            elapsed,
                            decay,
                            &mut self.nodes[node],
                        );
                        totals[node] =
                            rotor_totals(vehicle, actuators, &self.nodes[node], efficiency);
                    }
                    totals
                };
                if let Some(tape) = self.tape.as_mut() {
                    let channels = if constant {
                        &self.targets[..]
                    } else {
                        actuators.state()
                    };
                    push_node(
                        tape,
                        vehicle,
                        config,
                        a,
                        state,
                        actuators,
                        channels,
                        efficiency,
                        Some((&totals[0], &winds[0])),
                    );
                }
                // The first stage's wrench is the tape node's (same state, totals and wind).
                let mut first: Option<Wrench> = None;
                let recording = self.tape.is_some();
                let next = body.rk4_step_nodes(state, len, |node, x| {
                    let wrench = vehicle.wrench_from(x, &totals[node], &winds[node]);
                    if recording && first.is_none() {
                        first = Some(wrench);
                    }
                    wrench
                });
                if let (Some(tape), Some(wrench)) = (self.tape.as_mut(), first) {
                    tape.share_wrench(wrench);
                }
                if !self.limits.within(&next) {
                    return Some(located_divergence(
                        vehicle,
                        config,
                        &self.limits,
                        actuators,
                        &self.targets,
                        efficiency,
                        state,
                        (a, len),
                        next,
                    ));
                }
                *state = next;
                actuators.set_state(if constant {
                    &self.targets
                } else {
                    &self.nodes[2]
                });
                start_totals = Some(totals[2]);
                a = end;
                if schedule.apply_due(a, efficiency) {
                    start_totals = None;
                }
            }
        }
        if let Some(tape) = self.tape.as_mut() {
            // The totals at the end are the last interval's end totals (the same function of the
            // same channels and efficiency) unless a fault changed the efficiency there.
            let wind;
            let known = match &start_totals {
                Some(totals) => {
                    wind = config.wind_at(t_next);
                    Some((totals, &wind))
                }
                None => None,
            };
            push_node(
                tape,
                vehicle,
                config,
                t_next,
                state,
                actuators,
                actuators.state(),
                efficiency,
                known,
            );
        }
        None
    }
}

/// The divergence within the interval `[a, a + len]` (`interval`) whose RK4 step from `state`
/// ended at `next`, beyond a limit of `limits`: the crossing located by re-integrating shorter
/// steps from `state` with the channels from `actuators` under `targets`; leaves `actuators` at
/// the crossing.
#[allow(clippy::too_many_arguments)]
pub(super) fn located_divergence(
    vehicle: &Vehicle,
    config: &SimulationConfig,
    limits: &Limits,
    actuators: &mut Actuators,
    targets: &[f64],
    efficiency: &[f64],
    state: &RigidBodyState,
    (a, len): (f64, f64),
    next: RigidBodyState,
) -> Divergence {
    let body = vehicle.body();
    let mut channels = vec![0.0; targets.len()];
    let mut step = |l: f64| {
        let (mid, fin) = (a + 0.5 * l, a + l);
        let mut tot = [RotorTotals::default(); 3];
        for (node, elapsed) in [0.0, 0.5 * l, l].into_iter().enumerate() {
            actuators.response(targets, elapsed, &mut channels);
            tot[node] = rotor_totals(vehicle, actuators, &channels, efficiency);
        }
        let w = [
            config.wind_at(a),
            config.wind_at(mid),
            config.wind_before(fin),
        ];
        body.rk4_step_nodes(state, l, |node, x| {
            vehicle.wrench_from(x, &tot[node], &w[node])
        })
    };
    let (elapsed, kind) = limits.locate(len, &next, &mut step);
    let at = if elapsed == len { next } else { step(elapsed) };
    actuators.response(targets, elapsed, &mut channels);
    actuators.set_state(&channels);
    Divergence {
        time_s: a + elapsed,
        kind,
        state: at,
    }
}

/// One node of `tape`: `state` at `t_s` with the channels at `channels` (rotor totals and wind
/// as given, else computed there).
#[allow(clippy::too_many_arguments)]
pub(super) fn push_node(
    tape: &mut Tape,
    vehicle: &Vehicle,
    config: &SimulationConfig,
    t_s: f64,
    state: &RigidBodyState,
    actuators: &Actuators,
    channels: &[f64],
    efficiency: &[f64],
    known: Option<(&RotorTotals, &nalgebra::Vector3<f64>)>,
) {
    let (totals, wind) = match known {
        Some((totals, wind)) => (*totals, *wind),
        None => (
            rotor_totals(vehicle, actuators, channels, efficiency),
            config.wind_at(t_s),
        ),
    };
    let thrust = |i: usize| actuators.output_at(channels, i, efficiency[i]).thrust_n;
    tape.push(t_s, state, &totals, &wind, thrust);
}
