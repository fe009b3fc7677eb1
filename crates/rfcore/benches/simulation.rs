//! Criterion benchmarks of the flight simulator (quad-x preset, no drag; no actuator lag except
//! in `linear_feedback_lagged`).
//!
//! Run from the workspace root with `cargo bench --bench simulation` (add
//! `-- --warm-up-time 1 --measurement-time 3` for a quick run). The Python-side batch and the
//! comparison with RotorPy live in `benches/simulation_rotorpy.py`.
//!
//! Throughput is `Throughput::Elements(n)` with n = the number of RK4 substeps (one
//! `RigidBody::rk4_step`, i.e. four wrench + derivative evaluations), so criterion's
//! "elem/s" reads as RK4 steps per second:
//!
//! - `simulation/rk4_step/quad-x-hover`: one `RigidBody::rk4_step` with the vehicle wrench
//!   (`Vehicle::wrench`, quad-x hover thrusts held), n = 1;
//! - `simulation/flight_10s/linear_feedback`: one `simulate` call, 10 s at 400 Hz control with 4
//!   RK4 substeps per control period (4,000 control steps, n = 16,000 RK4 steps), a hand-built
//!   `LinearFeedback` (diagonal PD through the pseudo-inverse of the effectiveness matrix),
//!   starting from a small velocity / attitude perturbation about the hover point. Includes
//!   everything `simulate` does per step: trajectory recording, divergence checks after every
//!   substep, the 4,001 controller calls (Euler angles + a 4 x 12 gain product), the actuator
//!   response at the RK4 nodes (constant within a control step for these instant rotors);
//! - `simulation/flight_10s/linear_feedback_lagged`: the same flight with a 25 ms rotor lag and
//!   a 50 N/s rate limit (Ke's and Lanzon's values): the actuator response is evaluated at the
//!   midpoint and end of every substep, the cost of integrating actuators and body together;
//! - `simulation/flight_10s/open_loop`: the same flight with `OpenLoop` holding the hover thrusts
//!   from the trim point (n = 16,000).
//!
//! Note: `cargo bench -- <criterion flags>` also passes the flags to the library's unit-test
//! harness, which rejects them; use `cargo bench --bench simulation -- <flags>` for that.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::{DMatrix, UnitQuaternion, Vector3};
use rfcore::control::{LinearFeedback, OpenLoop};
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag, RotorOutput};
use rfcore::flight::simulation::{simulate, SimulationConfig};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::RigidBodyState;
use rfcore::state::STATE_DIM;
use rfcore::Airframe;

const CONTROL_DT_S: f64 = 1.0 / 400.0;
const SUBSTEPS: usize = 4;
const DURATION_S: f64 = 10.0;

fn quad_x() -> Airframe {
    rfcore::fixtures::preset("quad-x")
}

fn config() -> SimulationConfig {
    SimulationConfig::new(CONTROL_DT_S, SUBSTEPS, DURATION_S)
}

fn bench_simulation(c: &mut Criterion) {
    let airframe = quad_x();
    let rotors = airframe.rotor_count();
    let vehicle = Vehicle::new(&airframe, Drag::default()).expect("vehicle");
    let hover_thrust = airframe.mass_kg() * airframe.gravity_m_s2() / rotors as f64;
    let u_trim = vec![hover_thrust; rotors];
    let mut actuators = Actuators::FixedPitch(
        FixedPitch::new(&airframe, Lag::none(), 0.0).expect("fixed-pitch actuators"),
    );
    actuators.settle(&u_trim).unwrap();
    let target = Vector3::new(0.0, 0.0, -10.0);
    let hover = RigidBodyState {
        position_m: target,
        ..RigidBodyState::at_rest()
    };
    let config = config();
    let efficiency = vec![1.0; rotors];
    let rk4_per_flight = (config.steps() * SUBSTEPS) as u64;
    assert_eq!(rk4_per_flight, 16_000);

    // -- one RK4 step with the vehicle wrench ---------------------------------------------------
    let outputs: Vec<RotorOutput> = (0..rotors).map(|i| actuators.output(i, 1.0)).collect();
    let wind = Vector3::zeros();
    let h = CONTROL_DT_S / SUBSTEPS as f64;
    let body = vehicle.body();
    // Sanity: the hover thrusts balance the weight exactly (the state does not move).
    let after = body.rk4_step(0.0, &hover, h, |_, x| vehicle.wrench(x, &outputs, &wind));
    assert!((after.position_m - target).norm() < 1e-12 && after.velocity_m_s.norm() < 1e-12);
    // Time it from a generic (moving, tilted, rotating) state so nothing is trivially zero.
    let moving = RigidBodyState {
        position_m: target,
        velocity_m_s: Vector3::new(0.3, -0.2, 0.1),
        attitude: UnitQuaternion::from_euler_angles(0.05, -0.03, 0.2),
        omega_rad_s: Vector3::new(0.1, 0.05, -0.02),
    };

    let mut group = c.benchmark_group("simulation");
    group.throughput(Throughput::Elements(1));
    group.bench_function("rk4_step/quad-x-hover", |b| {
        b.iter(|| {
            body.rk4_step(0.0, black_box(&moving), black_box(h), |_, x| {
                vehicle.wrench(x, black_box(&outputs), &wind)
            })
        })
    });

    // -- closed loop: LinearFeedback ------------------------------------------------------------
    let mut x_trim = [0.0; STATE_DIM];
    x_trim[2] = target.z;
    let feedback = LinearFeedback::new(&x_trim, &u_trim, rfcore::fixtures::hover_gain(&airframe)).expect("gain");
    // A perturbed start about the hover point: 0.5 m/s north, 0.3 m/s up, 3 deg roll, 5 deg yaw.
    let perturbed = RigidBodyState {
        velocity_m_s: Vector3::new(0.5, 0.0, -0.3),
        attitude: UnitQuaternion::from_euler_angles(0.05, 0.0, 0.09),
        ..hover
    };
    // Validate before timing: it hovers, no divergence, ends within 1 cm of the start (= target).
    let run = simulate(
        &vehicle,
        actuators.clone(),
        &mut feedback.clone(),
        &efficiency,
        &[],
        perturbed,
        &config,
    )
    .expect("closed-loop flight");
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    assert_eq!(run.states.len(), config.steps() + 1);
    let end = run.states.last().unwrap();
    let miss = (end.position_m - perturbed.position_m).norm();
    assert!(miss < 0.01, "closed loop ends {miss} m from the start");
    let peak = run
        .states
        .iter()
        .map(|s| (s.position_m - target).norm())
        .fold(0.0, f64::max);
    assert!(
        peak > 0.01,
        "the perturbation should move the vehicle ({peak} m)"
    );

    group.throughput(Throughput::Elements(rk4_per_flight));
    group.bench_function("flight_10s/linear_feedback", |b| {
        b.iter(|| {
            let mut controller = feedback.clone();
            simulate(
                &vehicle,
                actuators.clone(),
                &mut controller,
                &efficiency,
                &[],
                black_box(perturbed),
                &config,
            )
            .unwrap()
        })
    });

    // -- closed loop with rotor lag and rate limit -----------------------------------------------
    let lag = Lag {
        time_constant_s: 0.025,
        rate_limit_per_s: 50.0,
    };
    let mut lagged = Actuators::FixedPitch(
        FixedPitch::new(&airframe, lag, 0.0).expect("fixed-pitch actuators with lag"),
    );
    lagged.settle(&u_trim).unwrap();
    let run = simulate(
        &vehicle,
        lagged.clone(),
        &mut feedback.clone(),
        &efficiency,
        &[],
        perturbed,
        &config,
    )
    .expect("closed-loop flight with rotor lag");
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    let end = run.states.last().unwrap();
    let miss = (end.position_m - perturbed.position_m).norm();
    assert!(
        miss < 0.01,
        "lagged closed loop ends {miss} m from the start"
    );
    group.bench_function("flight_10s/linear_feedback_lagged", |b| {
        b.iter(|| {
            let mut controller = feedback.clone();
            simulate(
                &vehicle,
                lagged.clone(),
                &mut controller,
                &efficiency,
                &[],
                black_box(perturbed),
                &config,
            )
            .unwrap()
        })
    });

    // -- open loop: hover thrusts held ----------------------------------------------------------
    let open_loop = OpenLoop::new(vec![0.0], DMatrix::from_row_slice(1, rotors, &u_trim))
        .expect("open-loop schedule");
    let run = simulate(
        &vehicle,
        actuators.clone(),
        &mut open_loop.clone(),
        &efficiency,
        &[],
        hover,
        &config,
    )
    .expect("open-loop flight");
    assert!(run.divergence.is_none());
    let end = run.states.last().unwrap();
    assert!(
        (end.position_m - target).norm() < 0.01,
        "{}",
        end.position_m
    );

    group.bench_function("flight_10s/open_loop", |b| {
        b.iter(|| {
            let mut controller = open_loop.clone();
            simulate(
                &vehicle,
                actuators.clone(),
                &mut controller,
                &efficiency,
                &[],
                black_box(hover),
                &config,
            )
            .unwrap()
        })
    });

    group.finish();
}

criterion_group!(benches, bench_simulation);
criterion_main!(benches);
