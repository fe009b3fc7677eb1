//! The driver: one closed-loop run ([`simulate`], [`simulate_observed`]) checked before any
//! work, flown control step by control step (measure, command, record, then one
//! `Integrator::period`), and many runs in parallel ([`simulate_batch`]). Runs check a
//! [`Cancel`] token once per control period (`*_cancellable`, the batch) and, with sensing, once
//! per sensor sample inside the period (`Onboard::catch_up`).

use crate::cancel::Cancel;
use crate::control::Controller;
use crate::error::{Result, RfError};
use crate::flight::actuator::Actuators;
use crate::flight::fault_schedule::{FaultSchedule, RotorFault};
use crate::flight::simulation::config::SimulationConfig;
use crate::flight::simulation::divergence::{Divergence, DivergenceKind};
use crate::flight::simulation::noise::Gaussian;
use crate::flight::simulation::onboard::{nan_row, Onboard};
use crate::flight::simulation::recording::{records, NoObserver, StepObserver, Trajectory};
use crate::flight::simulation::step::{check_step_size, rotor_totals, Integrator};
use crate::flight::vehicle::Vehicle;
use crate::state::{state_from_vector, state_vector, ControllerInput, RigidBodyState, STATE_DIM};

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
    simulate_cancellable(
        vehicle,
        actuators,
        controller,
        initial_efficiency,
        faults,
        x0,
        config,
        &Cancel::never(),
    )
}

/// [`simulate`], checking `cancel` once per control period.
#[allow(clippy::too_many_arguments)]
pub fn simulate_cancellable(
    vehicle: &Vehicle,
    actuators: Actuators,
    controller: &mut dyn Controller,
    initial_efficiency: &[f64],
    faults: &[RotorFault],
    x0: RigidBodyState,
    config: &SimulationConfig,
    cancel: &Cancel,
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
        cancel,
    )
}

/// [`simulate`], showing every control step to `observer` as it is flown, and checking `cancel`
/// once per control period (at most [`crate::flight::simulation::MAX_SUBSTEPS`] RK4 steps) and,
/// with sensing, before every sensor sample (one filter step) inside it.
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
    cancel: &Cancel,
) -> Result<Trajectory> {
    let mut schedule = check_run(
        vehicle,
        &actuators,
        controller,
        initial_efficiency,
        faults,
        &x0,
        config,
    )?;
    let m = vehicle.rotor_count();
    let count = actuators.channels() * m;
    let steps = config.steps();
    let every = config.record_every;
    let rows = steps / every + 3;
    let mut trajectory = empty_trajectory(config, count, m);
    controller.reset();
    let mut efficiency = initial_efficiency.to_vec();
    let mut command = vec![0.0; count];
    let mut state = x0;
    let mut integrator = Integrator::new(vehicle, &actuators, config, &x0);
    let mut gaussian = config.noise.map(|n| Gaussian::new(n.seed));
    let mut measured_vector = [0.0; STATE_DIM];
    let reads_samples = controller.reads_samples();
    let mut rotor_thrust = vec![0.0; m];
    // With sensing the controller flies on the estimator, fed by sensors sampling the truth
    // between control steps (the integrator's tape).
    let mut onboard = match &config.sensing {
        Some(sensing) => {
            let (onboard, tape) = Onboard::new(sensing, &x0, &actuators, reads_samples)?;
            integrator.record_on(tape);
            trajectory.sensing = Some(onboard.record(rows));
            Some(onboard)
        }
        None => None,
    };

    schedule.apply_due(0.0, &mut efficiency);
    if let Some(onboard) = onboard.as_mut() {
        integrator.tape_start(0.0, &state, &actuators, &efficiency);
        if let Some(tape) = integrator.tape() {
            onboard.catch_up(tape, vehicle, 0.0, cancel)?;
        }
    }
    if let Some(kind) = integrator.limits().exceeded(&state) {
        let divergence = Divergence {
            time_s: 0.0,
            kind,
            state,
        };
        end_with(
            &mut trajectory,
            observer,
            divergence,
            &efficiency,
            &actuators,
            config,
            onboard.as_ref(),
        );
        return Ok(trajectory);
    }
    for k in 0..=steps {
        cancel.check()?;
        let t = config.step_time(k);
        let estimate = onboard.as_ref().map(|o| o.estimate(t));
        // Measurements are recorded only when they differ from the true state (with noise);
        // without noise the Python layer rebuilds them from the recorded state. With sensing,
        // the estimate (recorded beside the truth).
        let measured = match (&config.noise, gaussian.as_mut(), &estimate) {
            (_, _, Some(estimate)) => estimate.state,
            (Some(noise), Some(gaussian), None) => {
                measured_vector = state_vector(&state);
                for (i, v) in measured_vector.iter_mut().enumerate() {
                    *v +=
                        (noise.relative_std * v.abs() + noise.absolute_std[i]) * gaussian.sample();
                }
                state_from_vector(&measured_vector)
            }
            _ => state,
        };
        // Raw samples (truth, the noisy rates, or the sensors') only for a controller that
        // reads them.
        let input = if let (Some(estimate), Some(onboard)) = (&estimate, onboard.as_ref()) {
            onboard.controller_input(estimate, reads_samples)
        } else if reads_samples {
            truth_samples(
                vehicle,
                &actuators,
                &efficiency,
                config,
                t,
                (&state, &measured),
                &mut rotor_thrust,
            )
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
            trajectory.rotor_command.extend_from_slice(&command);
            if let (Some(record), Some(onboard), Some(estimate)) =
                (trajectory.sensing.as_mut(), onboard.as_ref(), &estimate)
            {
                record.rows.push(onboard.row(estimate));
            }
        }
        if !finite {
            trajectory.divergence = Some(Divergence {
                time_s: t,
                kind: DivergenceKind::NonFiniteCommand,
                state,
            });
            break;
        }
        if k == steps {
            break;
        }
        let t_next = config.step_time(k + 1);
        if let Some(divergence) = integrator.period(
            t,
            t_next,
            &command,
            &mut state,
            &mut actuators,
            &mut efficiency,
            &mut schedule,
        ) {
            end_with(
                &mut trajectory,
                observer,
                divergence,
                &efficiency,
                &actuators,
                config,
                onboard.as_ref(),
            );
            return Ok(trajectory);
        }
        if let (Some(onboard), Some(tape)) = (onboard.as_mut(), integrator.tape()) {
            onboard.catch_up(tape, vehicle, t_next, cancel)?;
        }
    }
    if let (Some(record), Some(onboard)) = (trajectory.sensing.as_mut(), onboard.as_ref()) {
        onboard.finish(record);
    }
    Ok(trajectory)
}

/// An empty trajectory with room for the run's rows.
pub(super) fn empty_trajectory(config: &SimulationConfig, count: usize, m: usize) -> Trajectory {
    let rows = config.steps() / config.record_every + 3;
    Trajectory {
        t_s: Vec::with_capacity(rows),
        states: Vec::with_capacity(rows),
        rotor_command: Vec::with_capacity(rows * count),
        rotor_thrust_n: Vec::with_capacity(rows * m),
        efficiency: Vec::with_capacity(rows * m),
        recorded_measurements: Vec::with_capacity(if config.noise.is_some() {
            rows * STATE_DIM
        } else {
            0
        }),
        divergence: None,
        sensing: None,
    }
}

/// The raw samples of the truth for a controller that reads them (no sensing): the rotors'
/// thrusts (written to `rotor_thrust`), the measured rates and the specific force at `t_s`.
pub(super) fn truth_samples<'a>(
    vehicle: &Vehicle,
    actuators: &Actuators,
    efficiency: &[f64],
    config: &SimulationConfig,
    t_s: f64,
    (state, measured): (&RigidBodyState, &'a RigidBodyState),
    rotor_thrust: &'a mut [f64],
) -> ControllerInput<'a> {
    for (i, thrust) in rotor_thrust.iter_mut().enumerate() {
        *thrust = actuators.output(i, efficiency[i]).thrust_n;
    }
    let totals = rotor_totals(vehicle, actuators, actuators.state(), efficiency);
    let wind = config.wind_at(t_s);
    ControllerInput {
        state: measured,
        gyro_rad_s: Some(measured.omega_rad_s),
        specific_force_m_s2: Some(vehicle.specific_force(state, &totals, &wind)),
        rotor_thrust_n: Some(rotor_thrust),
    }
}

/// The checks of one run before any work (those of [`simulate_observed`]); its fault schedule.
pub(super) fn check_run(
    vehicle: &Vehicle,
    actuators: &Actuators,
    controller: &dyn Controller,
    initial_efficiency: &[f64],
    faults: &[RotorFault],
    x0: &RigidBodyState,
    config: &SimulationConfig,
) -> Result<FaultSchedule> {
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
    let schedule = FaultSchedule::new(faults, m)?;
    if !x0.is_finite() {
        return Err(RfError::invalid("x0", "must be finite"));
    }
    check_step_size(config, actuators, x0)?;
    config.check_start("x0", x0)?;

    Ok(schedule)
}

/// Ends a run with `divergence`: its row (NaN commands; NaN measurements with sensor noise, a
/// NaN estimate with sensing), shown to the observer and recorded with the event.
pub(super) fn end_with(
    trajectory: &mut Trajectory,
    observer: &mut dyn StepObserver,
    divergence: Divergence,
    efficiency: &[f64],
    actuators: &Actuators,
    config: &SimulationConfig,
    onboard: Option<&Onboard>,
) {
    if let (Some(record), Some(onboard)) = (trajectory.sensing.as_mut(), onboard) {
        record.rows.push(nan_row());
        onboard.finish(record);
    }
    let count = actuators.channels() * actuators.rotor_count();
    let nan_row = [f64::NAN; STATE_DIM];
    let Divergence { time_s, state, .. } = divergence;
    trajectory.push_step(
        time_s,
        &state,
        efficiency,
        actuators,
        config.noise.map(|_| &nan_row),
    );
    trajectory
        .rotor_command
        .extend(std::iter::repeat_n(f64::NAN, count));
    observer.step(time_s, &state, &vec![f64::NAN; count], efficiency);
    trajectory.divergence = Some(divergence);
}

/// One run of a batch: its own controller, initial state and faults.
pub struct BatchRun {
    pub controller: Box<dyn Controller>,
    /// Actuator start for this run (settled), or `None` to keep the batch's actuator state.
    pub initial_command: Option<Vec<f64>>,
    pub x0: RigidBodyState,
    pub faults: Vec<RotorFault>,
}

/// A batch's checks before any run: the settings, then each run's start (named `x0s[i]`).
pub(crate) fn check_batch(config: &SimulationConfig, runs: &[BatchRun]) -> Result<()> {
    config.check()?;
    for (i, run) in runs.iter().enumerate() {
        config.check_start(&format!("x0s[{i}]"), &run.x0)?;
    }
    Ok(())
}

/// Run `i` of a batch (its seeds shifted by `i`, its actuators settled at its own start): the
/// one rule of [`simulate_batch`] and the columnar recording.
pub(crate) fn fly_batch_run(
    i: usize,
    mut run: BatchRun,
    vehicle: &Vehicle,
    actuators: &Actuators,
    initial_efficiency: &[f64],
    config: &SimulationConfig,
    cancel: &Cancel,
) -> Result<Trajectory> {
    let mut own = config.clone();
    if let Some(noise) = own.noise.as_mut() {
        noise.seed = noise.seed.wrapping_add(i as u64);
    }
    if let Some(sensing) = own.sensing.as_mut() {
        sensing.seed = sensing.seed.wrapping_add(i as u64);
    }
    let mut actuators = actuators.clone();
    if let Some(command) = &run.initial_command {
        actuators.settle(command)?;
    }
    simulate_cancellable(
        vehicle,
        actuators,
        run.controller.as_mut(),
        initial_efficiency,
        &run.faults,
        run.x0,
        &own,
        cancel,
    )
}
