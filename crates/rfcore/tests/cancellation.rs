//! Every long call of the core stops when its [`Cancel`] token is set (issue 27: Ctrl-C works
//! everywhere). Each call below would run for many seconds; a thread sets the token 100 ms in and
//! the call must return `RfError::Interrupted` (had it run to the end, it would return `Ok`). The
//! time from the token being set to the call returning is printed (`--nocapture`): the worst
//! case between two checks, which the Python helper adds its 50 ms poll to. A token set before the
//! call stops it before any work.

use std::sync::mpsc::channel;
use std::thread;
use std::time::{Duration, Instant};

use nalgebra::{DMatrix, Vector3};

use rfcore::allocation::active_set::ActiveSetSolver;
use rfcore::allocation::clarabel::ClarabelSettings;
use rfcore::allocation::{allocate_all, allocate_many, AllocationProblem, Method};
use rfcore::analysis::relaxed_hover::{relaxed_hover_cancellable, RelaxedHoverSettings};
use rfcore::analysis::{
    acai_from_matrix_cancellable, failure_table, AcaiFormula, ControlAxes, ControllabilityAnalysis,
    FacetNormals,
};
use rfcore::control::ke::{CommandLaw, KeGains, UniformPassiveFtc};
use rfcore::control::{replay, Controller, OpenLoop};
use rfcore::fixtures::{preset, time_each};
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::simulation::{
    simulate_batch, simulate_cancellable, BatchRun, Sensing, SimulationConfig, MAX_SUBSTEPS,
};
use rfcore::flight::summary::{simulate_summaries, SummaryRun, VerdictCriteria};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::RigidBodyState;
use rfcore::{Airframe, Cancel, Result, RfError};

/// When the watcher sets the token.
const DELAY: Duration = Duration::from_millis(100);

/// Runs `work` with a token a second thread sets after [`DELAY`]; asserts the work was
/// interrupted and returns how long it took to return once the token was set.
fn interrupted<T>(what: &str, work: impl FnOnce(&Cancel) -> Result<T>) -> Duration {
    let cancel = Cancel::new();
    let setter = cancel.clone();
    let (sent, set_at) = channel();
    let watcher = thread::spawn(move || {
        thread::sleep(DELAY);
        sent.send(Instant::now()).unwrap();
        setter.cancel();
    });
    let result = work(&cancel);
    let returned = Instant::now();
    watcher.join().unwrap();
    assert!(
        matches!(result, Err(RfError::Interrupted)),
        "{what}: not interrupted (it ended before the token was set, or ignores it)"
    );
    let latency = returned.saturating_duration_since(set_at.recv().unwrap());
    println!("{what}: returned {latency:?} after the token was set");
    // A token set before the call: nothing is done.
    latency
}

fn cancelled() -> Cancel {
    let cancel = Cancel::new();
    cancel.cancel();
    cancel
}

/// A regular `m`-rotor planar frame, alternating spins.
fn ring(m: usize) -> Airframe {
    let angles: Vec<f64> = (0..m)
        .map(|i| i as f64 * std::f64::consts::TAU / m as f64)
        .collect();
    let spin: Vec<f64> = (0..m)
        .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    Airframe::from_columns(
        "ring",
        &angles,
        &vec![0.3; m],
        &spin,
        &vec![5.0; m],
        &vec![0.0; m],
        &vec![1.0; m],
        2.0,
        &[0.05, 0.05, 0.09],
        0.02,
        9.81,
    )
    .unwrap()
}

#[test]
fn analysis_calls_stop() {
    let ring12 = ring(12);
    let analysis = ControllabilityAnalysis::new(&ring12, ControlAxes::ThrustRollPitchYaw).unwrap();
    let etas = vec![1.0; 12 * 400_000];
    interrupted("acai_batch (12 rotors, 400k rows)", |c| {
        analysis.acai_batch(&etas, AcaiFormula::Eq13, c)
    });
    interrupted("acai_batch_with_hover (12 rotors, 400k rows)", |c| {
        analysis.acai_batch_with_hover(&etas, AcaiFormula::FacetMargin, c)
    });
    // 60,460 failure sets of 1,140 facets each: seconds of work even with the test profile's
    // optimisation and both cores (16 rotors finished inside 100 ms on the CI machine).
    interrupted("failure_table (20 rotors, up to 6 failed)", |c| {
        failure_table(&ring(20), 6, AcaiFormula::Eq13, c)
    });
    // n = 12, m = 22: 705,432 column groups of 11 x 11 determinants.
    let mut state = 7_u64;
    let b = DMatrix::from_fn(12, 22, |_, _| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    interrupted("FacetNormals::new_cancellable (12 x 22)", |c| {
        FacetNormals::new_cancellable(&b, c)
    });
    interrupted("acai_from_matrix_cancellable (12 x 22)", |c| {
        acai_from_matrix_cancellable(&b, &[0.0; 22], &[1.0; 22], &[0.0; 12], AcaiFormula::Eq13, c)
    });
    // 794 branches of carrying rotors (up to 4 of 12 idle), checked once per branch.
    let search = RelaxedHoverSettings {
        max_idle_rotors: 4,
        grid_points: 11,
        ..Default::default()
    };
    interrupted("relaxed_hover_cancellable (12 rotors, up to 4 idle)", |c| {
        relaxed_hover_cancellable(&ring12, &search, c)
    });
    let stop = cancelled();
    assert!(relaxed_hover_cancellable(&ring12, &search, &stop).is_err());
    assert_eq!(
        analysis.acai_batch(&etas[..12], AcaiFormula::Eq13, &stop),
        Err(RfError::Interrupted)
    );
    assert!(failure_table(&ring12, 1, AcaiFormula::Eq13, &stop).is_err());
    assert!(ControllabilityAnalysis::new_cancellable(&ring12, ControlAxes::Wrench, &stop).is_err());
}

fn hover(airframe: &Airframe) -> (Vehicle, Actuators, OpenLoop) {
    let vehicle = Vehicle::new(airframe, Drag::default()).unwrap();
    let m = airframe.rotor_count();
    let f = airframe.mass_kg() * airframe.gravity_m_s2() / m as f64;
    let mut actuators = Actuators::FixedPitch(FixedPitch::new(airframe, Lag::none(), 0.0).unwrap());
    actuators.settle(&vec![f; m]).unwrap();
    let open_loop = OpenLoop::new(vec![0.0], DMatrix::from_element(1, m, f)).unwrap();
    (vehicle, actuators, open_loop)
}

/// Hours of hover at 400 Hz: millions of control steps, recorded sparsely.
fn long_config() -> SimulationConfig {
    let mut config = SimulationConfig::new(0.0025, 4, 20_000.0);
    config.record_every = 100_000;
    // No ground: an open-loop hover drifts, and touching the ground would end the run before the
    // token is set.
    config.ground_z_m = None;
    config
}

#[test]
fn flights_stop() {
    let airframe = preset("quad-x");
    let (vehicle, actuators, mut controller) = hover(&airframe);
    let config = long_config();
    let x0 = RigidBodyState::at_rest();
    interrupted("simulate_cancellable (8M control steps)", |c| {
        simulate_cancellable(
            &vehicle,
            actuators.clone(),
            &mut controller,
            &[1.0; 4],
            &[],
            x0,
            &config,
            c,
        )
    });
    // One control period of 10^5 s with sensors: 3.2e9 IMU samples and filter steps between the
    // driver's once-per-period checks (hours), so the sensors' loop checks on its own.
    let mut sensed = SimulationConfig::new(1e5, MAX_SUBSTEPS, 1e5);
    sensed.ground_z_m = None;
    sensed.sensing = Some(Sensing {
        imu_rate_hz: 32_000.0,
        ..Sensing::default()
    });
    interrupted(
        "simulate_cancellable, sensed (one period of 3.2e9 IMU samples)",
        |c| {
            simulate_cancellable(
                &vehicle,
                actuators.clone(),
                &mut controller,
                &[1.0; 4],
                &[],
                x0,
                &sensed,
                c,
            )
        },
    );
    let runs = || -> Vec<BatchRun> {
        (0..8)
            .map(|_| BatchRun {
                controller: Box::new(hover(&airframe).2) as Box<dyn Controller>,
                initial_command: None,
                x0,
                faults: Vec::new(),
            })
            .collect()
    };
    interrupted("simulate_batch (8 runs of 8M steps)", |c| {
        simulate_batch(&vehicle, &actuators, &[1.0; 4], runs(), &config, c)
    });
    let summaries = || -> Vec<SummaryRun> {
        (0..8)
            .map(|_| {
                let (vehicle, actuators, controller) = hover(&airframe);
                SummaryRun {
                    vehicle,
                    actuators,
                    controller: Box::new(controller),
                    initial_efficiency: vec![1.0; 4],
                    faults: Vec::new(),
                    x0,
                    config: config.clone(),
                    setpoint_m: Vector3::zeros(),
                }
            })
            .collect()
    };
    interrupted("simulate_summaries (8 runs of 8M steps)", |c| {
        simulate_summaries(summaries(), &VerdictCriteria::default(), c)
    });
    let stop = cancelled();
    assert!(simulate_batch(&vehicle, &actuators, &[1.0; 4], runs(), &config, &stop).is_err());
    assert!(simulate_summaries(summaries(), &VerdictCriteria::default(), &stop).is_err());
}

#[test]
fn allocation_and_replay_stop() {
    let airframe = preset("ke-quadcopter");
    let problem = AllocationProblem::new(
        airframe.nominal_effectiveness_matrix(),
        &[1.0, 20.0, 20.0, 0.01],
        &airframe.min_thrust_n(),
        &airframe.max_thrust_n(),
    )
    .unwrap();
    // Beyond the attainable set, so bounds are active and every solve iterates.
    let controls: Vec<f64> = [30.0, 0.5, -0.3, 0.2].repeat(2_000_000);
    let solver = ActiveSetSolver::new(&problem);
    interrupted("allocate_all (2M active-set solves)", |c| {
        allocate_all(&solver, &controls, c)
    });
    let clarabel = Method::Clarabel(ClarabelSettings::default());
    interrupted("allocate_many, clarabel (2M solves)", |c| {
        allocate_many(&problem, &clarabel, &controls, c)
    });
    interrupted("time_each (a billion repeats)", |c| {
        time_each(&problem, &clarabel, &controls[..4], 1_000_000_000, c)
    });
    let mut ftc = UniformPassiveFtc::new(
        &airframe,
        KeGains::default(),
        CommandLaw::Feedforward,
        vec![(0.0, [0.0; 3])],
        0.0025,
    )
    .unwrap();
    let states = vec![RigidBodyState::at_rest(); 2_000_000];
    let times: Vec<f64> = (0..states.len()).map(|k| k as f64 * 0.0025).collect();
    interrupted("replay (Ke's controller, 2M steps)", |c| {
        replay(&mut ftc, &times, &states, c)
    });
    let stop = cancelled();
    assert!(allocate_all(&solver, &controls[..8], &stop).is_err());
    assert!(allocate_many(&problem, &Method::Pinv, &controls[..8], &stop).is_err());
}
