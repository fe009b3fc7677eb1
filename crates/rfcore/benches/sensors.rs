//! The cost of flying on sensors: the sensor models and the estimator per sample and per control
//! step, against the truth-state closed loop in the same run.
//!
//! Run from the workspace root with `cargo bench --bench sensors` (add `-- --warm-up-time 1
//! --measurement-time 3` for a quick run). Before criterion's groups it prints a summary line,
//! timed here in the thread's CPU time (median of 7 repetitions; robust on a loaded machine,
//! where criterion's wall-clock figures are not), and the ratio the issue asks for: the speed of
//! a closed loop that adds the sensors and the estimator to every control step, as a fraction
//! of the truth-state closed loop.
//!
//! - `sensors/imu_sample`: one ICM-42688-P sample (gyro and accelerometer, 12 normals);
//! - `sensors/mocap_sample`: one OptiTrack sample (position and attitude, 9 normals);
//! - `sensors/estimator_imu_step/{hover,spin}`: one `Estimator::push_imu` with the OptiTrack
//!   measurements of that interval fused at their times of validity (240 of 1000 samples carry
//!   one: the covariance propagated once or twice, an update of position and attitude),
//!   averaged over one second of pre-generated samples;
//! - `sensors/sensors_and_estimator_per_control_step`: at Ke's 400 Hz control rate with the
//!   IMU at 1 kHz, what a closed loop adds per control step: 2.5 IMU samples, 0.6 mocap samples,
//!   the estimator and `estimate()`;
//! - `baseline/truth_control_step`: one control step of `simulate` (quad-x, hover thrusts held,
//!   4 RK4 substeps, trajectory recording), 10 s flights (100 s in the summary).

use std::hint::black_box;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::{DMatrix, Vector3};
use rfcore::control::OpenLoop;
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::estimation::{Estimator, EstimatorSettings};
use rfcore::flight::sensors::reference::AnalyticMotion;
use rfcore::flight::sensors::{
    ImuSample, PositionSample, PositionSource, SensorSuite, SensorSuiteProfile,
};
use rfcore::flight::simulation::{simulate, SimulationConfig};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::RigidBodyState;

const CONTROL_DT_S: f64 = 1.0 / 400.0;
const SUBSTEPS: usize = 4;

/// One second of IMU samples and the mocap samples arriving in each IMU interval.
struct Recording {
    imu: Vec<ImuSample>,
    mocap: Vec<Vec<PositionSample>>,
    start: RigidBodyState,
}

fn record(motion: &AnalyticMotion, suite: &SensorSuiteProfile) -> Recording {
    let mut sensors = SensorSuite::new(suite, 4, 1).expect("sensors");
    let (mut imu, mut mocap) = (Vec::new(), Vec::new());
    for _ in 0..1000 {
        let t = sensors.imu.next_sample_time_s();
        let mut arrived = Vec::new();
        while sensors.position.is_due(t) {
            let at = sensors.position.next_sample_time_s();
            sensors.position.sample(&motion.state_at(at));
        }
        while let Some(m) = sensors.position.poll(t) {
            arrived.push(m);
        }
        mocap.push(arrived);
        imu.push(sensors.imu.sample(&motion.imu_truth_at(t)));
    }
    Recording {
        imu,
        mocap,
        start: motion.state_at(0.0),
    }
}

fn run_estimator(template: &Estimator, rec: &Recording) -> RigidBodyState {
    let mut estimator = template.clone();
    for (sample, arrived) in rec.imu.iter().zip(&rec.mocap) {
        for m in arrived {
            estimator.push_position(m);
        }
        estimator.push_imu(sample).expect("imu");
    }
    estimator.estimate().state
}

/// The truth at every IMU and mocap sample time of `steps` control steps (precomputed: a
/// simulator hands over its state, it does not evaluate the analytic motion).
struct Truths {
    imu: Vec<rfcore::flight::sensors::ImuTruth>,
    mocap: Vec<RigidBodyState>,
}

fn truths(suite: &SensorSuiteProfile, motion: &AnalyticMotion, steps: usize) -> Truths {
    let duration = steps as f64 * CONTROL_DT_S;
    let imu_n = (duration * suite.imu.rate_hz) as usize + 2;
    let mocap_n = (duration * suite.position.rate_hz) as usize + 2;
    Truths {
        imu: (0..imu_n)
            .map(|k| motion.imu_truth_at(k as f64 / suite.imu.rate_hz))
            .collect(),
        mocap: (0..mocap_n)
            .map(|k| motion.state_at(k as f64 / suite.position.rate_hz))
            .collect(),
    }
}

/// Sensors and estimator for `steps` control steps at 400 Hz: what a closed loop adds.
fn sensed_loop(
    suite: &SensorSuiteProfile,
    truth: &Truths,
    start: &RigidBodyState,
    steps: usize,
) -> f64 {
    let mut sensors = SensorSuite::new(suite, 4, 2).expect("sensors");
    let settings = EstimatorSettings::for_sensors(suite);
    let mut estimator = Estimator::new(settings, start).expect("estimator");
    let (mut imu_k, mut mocap_k) = (0, 0);
    let mut sink = 0.0;
    for k in 0..steps {
        let t = k as f64 * CONTROL_DT_S;
        while sensors.position.is_due(t) {
            sensors.position.sample(&truth.mocap[mocap_k]);
            mocap_k += 1;
        }
        while let Some(m) = sensors.position.poll(t) {
            estimator.push_position(&m);
        }
        while sensors.imu.is_due(t) {
            let s = sensors.imu.sample(&truth.imu[imu_k]);
            imu_k += 1;
            estimator.push_imu(&s).expect("imu");
        }
        sink += estimator.estimate().state.position_m.z;
    }
    sink
}

fn truth_flight(
    vehicle: &Vehicle,
    actuators: &Actuators,
    hover: RigidBodyState,
    u: &[f64],
    steps: usize,
) -> usize {
    let config = SimulationConfig::new(CONTROL_DT_S, SUBSTEPS, steps as f64 * CONTROL_DT_S);
    let mut controller =
        OpenLoop::new(vec![0.0], DMatrix::from_row_slice(1, u.len(), u)).expect("open loop");
    let run = simulate(
        vehicle,
        actuators.clone(),
        &mut controller,
        &vec![1.0; u.len()],
        &[],
        hover,
        &config,
    )
    .expect("flight");
    run.states.len()
}

/// This thread's CPU time, s: the first field of `/proc/thread-self/schedstat` (ns on the CPU),
/// which other processes on a loaded machine do not inflate; wall time where it is missing.
fn cpu_time_s(wall: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(|| wall.elapsed().as_secs_f64(), |ns| ns * 1e-9)
}

/// Median CPU time of `f` over `reps` calls, s.
fn median_s(reps: usize, mut f: impl FnMut()) -> f64 {
    let origin = Instant::now();
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let start = cpu_time_s(origin);
            f();
            cpu_time_s(origin) - start
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[reps / 2]
}

fn bench_sensors(c: &mut Criterion) {
    let suite = SensorSuiteProfile::mocap();
    let hover = AnalyticMotion::hover();
    let spin = AnalyticMotion::spin(30.0, 15f64.to_radians());
    let settings = EstimatorSettings::for_sensors(&suite);

    let airframe = rfcore::fixtures::preset("quad-x");
    let rotors = airframe.rotor_count();
    let vehicle = Vehicle::new(&airframe, Drag::default()).expect("vehicle");
    let u = vec![airframe.mass_kg() * airframe.gravity_m_s2() / rotors as f64; rotors];
    let mut actuators =
        Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).expect("rotors"));
    actuators.settle(&u).expect("settle");
    let start = RigidBodyState {
        position_m: Vector3::new(0.0, 0.0, -10.0),
        ..RigidBodyState::at_rest()
    };

    // -- summary line with the ratio --------------------------------------------------------------
    let steps = 40_000;
    let truth_s = median_s(7, || {
        black_box(truth_flight(&vehicle, &actuators, start, &u, steps));
    }) / steps as f64;
    let spin_truths = truths(&suite, &spin, steps);
    let spin_start = spin.state_at(0.0);
    let sensed_s = median_s(7, || {
        black_box(sensed_loop(&suite, &spin_truths, &spin_start, steps));
    }) / steps as f64;
    let hover_rec = record(&hover, &suite);
    let template = Estimator::new(settings, &hover_rec.start).expect("estimator");
    let estimator_s = median_s(7, || {
        for _ in 0..20 {
            black_box(run_estimator(&template, &hover_rec));
        }
    }) / 20_000.0;
    let mut imu = SensorSuite::new(&suite, 4, 3).expect("sensors").imu;
    let truth = hover.imu_truth_at(0.0);
    let imu_s = median_s(7, || {
        for _ in 0..100_000 {
            black_box(imu.sample(black_box(&truth)));
        }
    }) / 100_000.0;
    // The same loop with the rates lowered: the ICM-42688-P at its 500 Hz ODR, mocap at 120 Hz.
    let mut light = suite;
    light.imu.rate_hz = 500.0;
    light.position.rate_hz = 120.0;
    let light_truths = truths(&light, &spin, steps);
    let light_s = median_s(7, || {
        black_box(sensed_loop(&light, &light_truths, &spin_start, steps));
    }) / steps as f64;
    println!(
        "sensors summary: IMU sample {:.0} ns; estimator per IMU sample (mocap hover) {:.0} ns; \
         truth closed loop per control step {:.0} ns; sensors + estimator per 400 Hz control \
         step {:.0} ns (IMU 1 kHz, mocap 240 Hz), speed / truth speed = {:.2}; {:.0} ns (IMU \
         500 Hz, mocap 120 Hz), speed / truth speed = {:.2}",
        imu_s * 1e9,
        estimator_s * 1e9,
        truth_s * 1e9,
        sensed_s * 1e9,
        truth_s / (truth_s + sensed_s),
        light_s * 1e9,
        truth_s / (truth_s + light_s)
    );

    // -- criterion groups -------------------------------------------------------------------------
    let mut group = c.benchmark_group("sensors");
    group.throughput(Throughput::Elements(1));
    group.bench_function("imu_sample", |b| b.iter(|| imu.sample(black_box(&truth))));
    let mut mocap = PositionSource::new(suite.position, 4).expect("mocap");
    let state = hover.state_at(0.0);
    group.bench_function("mocap_sample", |b| {
        b.iter(|| {
            mocap.sample(black_box(&state));
            mocap.poll(f64::INFINITY)
        })
    });
    group.throughput(Throughput::Elements(1000));
    group.bench_function("estimator_imu_step/hover", |b| {
        b.iter(|| run_estimator(&template, &hover_rec))
    });
    let spin_rec = record(&spin, &suite);
    let spin_template = Estimator::new(settings, &spin_rec.start).expect("estimator");
    group.bench_function("estimator_imu_step/spin", |b| {
        b.iter(|| run_estimator(&spin_template, &spin_rec))
    });
    group.throughput(Throughput::Elements(4000));
    group.bench_function("sensors_and_estimator_per_control_step", |b| {
        b.iter(|| sensed_loop(&suite, &spin_truths, &spin_start, 4000))
    });
    group.finish();

    let mut group = c.benchmark_group("baseline");
    group.throughput(Throughput::Elements(4000));
    group.bench_function("truth_control_step", |b| {
        b.iter(|| truth_flight(&vehicle, &actuators, black_box(start), &u, 4000))
    });
    group.finish();
}

criterion_group!(benches, bench_sensors);
criterion_main!(benches);
