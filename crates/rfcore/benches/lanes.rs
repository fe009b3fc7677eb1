//! SIMD lanes against the scalar simulator, one thread each, in one run (issue #32's target:
//! the lanes >= 3x the scalar path per core for the closed-loop LQR and Ke FTC batches).
//!
//! Run with `cargo bench --bench lanes`. Each batch is 8 runs of 10 s at 400 Hz control (two
//! groups of four lanes), flown in a one-thread rayon pool with `BatchLanes::Scalar` and
//! `BatchLanes::Auto` alternately; the line gives each median process CPU time
//! (`clock_gettime`, which other processes do not inflate) and their ratio.
//! Before timing, the two paths' trajectories are checked equal bit for bit.
//!
//! - `lqr`: the quad-x preset hovering under a linear state feedback (a diagonal PD through the
//!   pseudo-inverse of the effectiveness matrix, the `simulation` bench's gain), 25 ms rotor lag,
//!   perturbed starts;
//! - `ke`: Ke's uniform passive FTC on the ke-quadcopter preset with drag and 25 ms lag, rotor 1
//!   lost at 2 s (the `sensing` bench's flight, truth-fed).

use nalgebra::{UnitQuaternion, Vector3};
use rfcore::control::ke::{CommandLaw, KeGains, UniformPassiveFtc};
use rfcore::control::{Controller, LinearFeedback};
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::simulation::{
    simulate_batch_lanes, BatchLanes, BatchRun, RotorFault, SimulationConfig, Trajectory,
};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::{RigidBodyState, STATE_DIM};
use rfcore::Cancel;

#[path = "common/cpu_time.rs"]
mod cpu_time;
use cpu_time::median_pair;

const DT_S: f64 = 1.0 / 400.0;
const DURATION_S: f64 = 10.0;
const RUNS: usize = 8;
const REPS: usize = 9;

fn start(k: usize) -> RigidBodyState {
    let x = |i: usize| ((k * 5 + i) as f64 * 0.77).sin();
    RigidBodyState {
        position_m: Vector3::new(0.3 * x(0), 0.3 * x(1), -10.0 + 0.2 * x(2)),
        velocity_m_s: Vector3::new(0.5 * x(3), 0.4 * x(4), 0.3 * x(5)),
        attitude: UnitQuaternion::from_euler_angles(0.05 * x(6), 0.05 * x(7), 0.1 * x(8)),
        omega_rad_s: Vector3::zeros(),
    }
}

struct Case {
    name: &'static str,
    vehicle: Vehicle,
    actuators: Actuators,
    runs: Box<dyn Fn() -> Vec<BatchRun> + Send + Sync>,
}

fn lag() -> Lag {
    Lag {
        time_constant_s: 0.025,
        rate_limit_per_s: f64::INFINITY,
    }
}

fn lqr_case() -> Case {
    let airframe = rfcore::fixtures::preset("quad-x");
    let hover = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
    let mut x_trim = [0.0; STATE_DIM];
    x_trim[2] = -10.0;
    let law = LinearFeedback::new(&x_trim, &[hover; 4], rfcore::fixtures::hover_gain(&airframe)).expect("gain");
    Case {
        name: "lqr",
        vehicle: Vehicle::new(&airframe, Drag::default()).expect("vehicle"),
        actuators: Actuators::FixedPitch(FixedPitch::new(&airframe, lag(), 0.0).expect("rotors")),
        runs: Box::new(move || {
            (0..RUNS)
                .map(|k| BatchRun {
                    controller: Box::new(law.clone()) as Box<dyn Controller>,
                    initial_command: Some(vec![hover; 4]),
                    x0: start(k),
                    faults: vec![],
                })
                .collect()
        }),
    }
}

fn ke_case() -> Case {
    let airframe = rfcore::fixtures::preset("ke-quadcopter");
    let hover = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
    let drag = Drag {
        linear_drag_n_s_m: 0.3,
        rotational_drag_n_m_s: 2.8e-3,
        ..Drag::default()
    };
    Case {
        name: "ke",
        vehicle: Vehicle::new(&airframe, drag).expect("vehicle"),
        actuators: Actuators::FixedPitch(FixedPitch::new(&airframe, lag(), 0.0).expect("rotors")),
        runs: Box::new(move || {
            (0..RUNS)
                .map(|k| {
                    let ke = UniformPassiveFtc::new(
                        &airframe,
                        KeGains::default(),
                        CommandLaw::default(),
                        vec![(0.0, [0.0, 0.0, -10.0])],
                        DT_S,
                    )
                    .expect("ke");
                    BatchRun {
                        controller: Box::new(ke) as Box<dyn Controller>,
                        initial_command: Some(vec![hover; 4]),
                        x0: start(k),
                        faults: vec![RotorFault {
                            rotor: 0,
                            time_s: 2.0,
                            efficiency: 0.0,
                        }],
                    }
                })
                .collect()
        }),
    }
}

fn fly(case: &Case, lanes: BatchLanes) -> Vec<Trajectory> {
    let config = SimulationConfig::new(DT_S, 4, DURATION_S);
    simulate_batch_lanes(
        &case.vehicle,
        &case.actuators,
        &[1.0; 4],
        (case.runs)(),
        &config,
        &Cancel::never(),
        lanes,
    )
    .expect("batch")
}

fn main() {
    // `cargo bench` passes `--bench`; a filter argument selects cases by name.
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("one-thread pool");
    for case in [lqr_case(), ke_case()] {
        if !filter.is_empty() && !filter.iter().any(|f| case.name.contains(f.as_str())) {
            continue;
        }
        pool.install(|| {
            let (scalar, lanes) = (fly(&case, BatchLanes::Scalar), fly(&case, BatchLanes::Auto));
            assert!(scalar.iter().all(|t| t.divergence.is_none()), "{}: the benched flights must not diverge", case.name);
            for (a, b) in scalar.iter().zip(&lanes) {
                assert!(a == b, "{}: lanes differ from the scalar path", case.name);
            }
            let (scalar, lanes) = median_pair(
                REPS,
                || drop(fly(&case, BatchLanes::Scalar)),
                || drop(fly(&case, BatchLanes::Auto)),
            );
            let (scalar_s, lanes_s) = (scalar.cpu_s, lanes.cpu_s);
            println!(
                "lanes/{}: {RUNS} runs x {DURATION_S} s, one thread: scalar {:.2} ms, lanes {:.2} ms, \
                 lanes {:.2}x the scalar path (avx2 {})",
                case.name,
                scalar_s * 1e3,
                lanes_s * 1e3,
                scalar_s / lanes_s,
                cfg!(target_arch = "x86_64") && std::arch::is_x86_feature_detected!("avx2"),
            );
        });
    }
}
