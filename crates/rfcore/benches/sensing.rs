//! The speed of closed-loop flights on sensors against the same flights on the truth, both in
//! one run (issue 29: flying on sensors at >= 50 % of the truth-state speed). Every controller the
//! project flies on sensors (Ke, Lanzon, Wang's LQR, the hover LQR and INDI, with their designs
//! from Python) is timed by `python benches/sensing.py`; this bench times the two Rust-built laws
//! and is the one to profile (`perf record` on `--profile-time`).
//!
//! Run from the workspace root with `cargo bench --bench sensing` (add `-- --warm-up-time 1
//! --measurement-time 3` for a quick run). Before criterion's groups it prints a summary line per
//! law: a batch of 16 flights of 10 s of `ke-quadcopter` (Ke's rotor lag and drags, 400 Hz
//! control, 4 RK4 substeps) losing rotor 1 at 2 s (`simulate_batch`, rayon), on the truth and on
//! `Sensing::default()` (ICM-42688-P at 500 Hz, OptiTrack at 240 Hz, DShot rotor speeds, the
//! 15-state error-state Kalman filter), the median of 9 batches each, truth and sensors
//! alternating so both see the same load, in process CPU time (`clock_gettime`, ns resolution;
//! a batch is 60-200 ms of it) and in wall time, and the ratio of their speeds. INDI, which also
//! reads the raw gyro, accelerometer and rotor speeds, spins beyond the gyro's range after the
//! loss (the estimator's clamping path runs); Ke's passive law reads the state.
//!
//! - `closed_loop/{ke,indi}/{truth,mocap}`: a batch of 4 such flights, throughput in control
//!   steps.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::Vector3;
use rfcore::control::indi::{DetectedFailure, IndiController, IndiGains, Setpoint};
use rfcore::control::ke::{CommandLaw, KeGains, UniformPassiveFtc};
use rfcore::control::Controller;
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::simulation::{simulate_batch, BatchRun, RotorFault, Sensing, SimulationConfig};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::RigidBodyState;
use rfcore::Cancel;

#[path = "common/cpu_time.rs"]
mod cpu_time;
use cpu_time::median_pair;

const DT_S: f64 = 1.0 / 400.0;
const DURATION_S: f64 = 10.0;
const FAULT_S: f64 = 2.0;

#[derive(Clone, Copy)]
enum Law {
    Ke,
    Indi,
}

struct Setup {
    vehicle: Vehicle,
    actuators: Actuators,
    start: RigidBodyState,
    faults: Vec<RotorFault>,
}

fn setup() -> Setup {
    let airframe = rfcore::fixtures::preset("ke-quadcopter");
    let drag = Drag {
        linear_drag_n_s_m: 0.3,
        rotational_drag_n_m_s: 2.8e-3,
        ..Drag::default()
    };
    let lag = Lag {
        time_constant_s: 0.025,
        rate_limit_per_s: f64::INFINITY,
    };
    Setup {
        vehicle: Vehicle::new(&airframe, drag).expect("vehicle"),
        actuators: Actuators::FixedPitch(FixedPitch::new(&airframe, lag, 0.0).expect("rotors")),
        start: RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, -10.0),
            ..RigidBodyState::at_rest()
        },
        faults: vec![RotorFault {
            rotor: 0,
            time_s: FAULT_S,
            efficiency: 0.0,
        }],
    }
}

/// A fresh controller of `law` and the hover thrusts it starts from.
fn controller(law: Law) -> (Box<dyn Controller>, Vec<f64>) {
    let airframe = rfcore::fixtures::preset("ke-quadcopter");
    let hover = vec![airframe.mass_kg() * airframe.gravity_m_s2() / 4.0; 4];
    match law {
        Law::Ke => {
            let c = UniformPassiveFtc::new(
                &airframe,
                KeGains::default(),
                CommandLaw::default(),
                vec![(0.0, [0.0, 0.0, -10.0])],
                DT_S,
            )
            .expect("ke");
            (Box::new(c), hover)
        }
        Law::Indi => {
            let setpoint = Setpoint {
                time_s: 0.0,
                position_m: [0.0, 0.0, -10.0],
                velocity_m_s: [0.0; 3],
            };
            let failure = DetectedFailure {
                rotor: 0,
                time_s: FAULT_S,
            };
            let c = IndiController::new(
                &airframe,
                IndiGains::default(),
                vec![failure],
                vec![setpoint],
                DT_S,
            )
            .expect("indi");
            (Box::new(c), hover)
        }
    }
}

fn config(sensing: Option<Sensing>) -> SimulationConfig {
    let mut c = SimulationConfig::new(DT_S, 4, DURATION_S);
    c.sensing = sensing;
    c
}

fn batch(s: &Setup, law: Law, config: &SimulationConfig, runs: usize) -> usize {
    let runs = (0..runs)
        .map(|_| {
            let (controller, hover) = controller(law);
            BatchRun {
                controller,
                initial_command: Some(hover),
                x0: s.start,
                faults: s.faults.clone(),
            }
        })
        .collect();
    let runs = simulate_batch(
        &s.vehicle,
        &s.actuators,
        &[1.0; 4],
        runs,
        config,
        &Cancel::never(),
    )
    .expect("batch");
    assert!(
        runs.iter().all(|r| r.divergence.is_none()),
        "the benched flights must not diverge"
    );
    runs.iter().map(|r| r.states.len()).sum()
}

fn bench_sensing(c: &mut Criterion) {
    let s = setup();
    let truth = config(None);
    let mocap = config(Some(Sensing::default()));
    let steps = (DURATION_S / DT_S) as u64;
    const SUMMARY_RUNS: usize = 16;
    for (name, law) in [("ke", Law::Ke), ("indi", Law::Indi)] {
        let (truth_t, mocap_t) = median_pair(
            9,
            || {
                black_box(batch(&s, law, &truth, SUMMARY_RUNS));
            },
            || {
                black_box(batch(&s, law, &mocap, SUMMARY_RUNS));
            },
        );
        println!(
            "sensing summary, {name}: batch of {SUMMARY_RUNS} flights of 10 s (4000 control steps \
             each, rotor 1 lost at 2 s), CPU time on the truth {:.1} ms, on mocap sensors + \
             estimator {:.1} ms: speed / truth speed = {:.2} (wall {:.1} / {:.1} ms: {:.2})",
            truth_t.cpu_s * 1e3,
            mocap_t.cpu_s * 1e3,
            truth_t.cpu_s / mocap_t.cpu_s,
            truth_t.wall_s * 1e3,
            mocap_t.wall_s * 1e3,
            truth_t.wall_s / mocap_t.wall_s
        );
    }

    let mut group = c.benchmark_group("closed_loop");
    group.throughput(Throughput::Elements(4 * steps));
    group.sample_size(10);
    for (name, law) in [("ke", Law::Ke), ("indi", Law::Indi)] {
        group.bench_function(format!("{name}/truth"), |b| {
            b.iter(|| batch(&s, law, &truth, 4))
        });
        group.bench_function(format!("{name}/mocap"), |b| {
            b.iter(|| batch(&s, law, &mocap, 4))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_sensing);
criterion_main!(benches);
