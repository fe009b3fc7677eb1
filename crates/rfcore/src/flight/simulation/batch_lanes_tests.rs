//! The lanes fly what the scalar simulator flies, bit for bit (a stricter check than the issue's
//! 1e-12 relative): hover LQR-style feedback and Ke's FTC, with rotor lag, saturation, faults
//! between substeps, divergence and non-finite commands in some lanes and not others; on the
//! truth and on sensors with the estimator (every estimate row and count too).

use nalgebra::{UnitQuaternion, Vector3};

use super::*;
use crate::airframe::Airframe;
use crate::cancel::Cancel;
use crate::control::ke::{CommandLaw, KeGains, UniformPassiveFtc};
use crate::control::{Controller, LinearFeedback};
use crate::flight::actuator::{Actuators, FixedPitch, Lag};
use crate::flight::fault_schedule::RotorFault;
use crate::flight::lanes::{detected_path, portable_choices, Choice};
use crate::flight::simulation::sensing::{Sensing, SuiteName};
use crate::flight::vehicle::{Drag, Vehicle};
use crate::state::{ControllerInput, RigidBodyState, STATE_DIM};

/// Every recorded number of a trajectory as bits (NaN rows compare too), and the events.
fn bits(t: &Trajectory) -> (Vec<u64>, Option<DivergenceKind>) {
    let mut out: Vec<u64> = Vec::new();
    let state = |s: &RigidBodyState| {
        let q = s.attitude.quaternion().coords;
        let all = s
            .position_m
            .iter()
            .chain(&s.velocity_m_s)
            .chain(q.iter())
            .chain(&s.omega_rad_s);
        all.map(|v| v.to_bits()).collect::<Vec<u64>>()
    };
    for s in &t.states {
        out.extend(state(s));
    }
    for v in t
        .t_s
        .iter()
        .chain(&t.rotor_command)
        .chain(&t.rotor_thrust_n)
        .chain(&t.efficiency)
    {
        out.push(v.to_bits());
    }
    out.extend([t.t_s.len(), t.rotor_command.len(), t.rotor_thrust_n.len()].map(|n| n as u64));
    // With sensing: every estimate row (the estimate, its sigmas, the clamping flags) and the
    // run's counts.
    if let Some(record) = &t.sensing {
        for row in &record.rows {
            out.extend(state(&row.state));
            out.extend(row.std.iter().map(|v| v.to_bits()));
            out.extend([row.gyro_saturated, row.accel_saturated].map(u64::from));
        }
        let f = record.fusion;
        out.extend([
            record.rows.len() as u64,
            record.imu_samples,
            record.gyro_saturated_samples,
            record.accel_saturated_samples,
            f.fused,
            f.rejected,
            f.late,
            f.thinned,
        ]);
    }
    out.push(u64::from(t.sensing.is_some()));
    if let Some(d) = &t.divergence {
        out.push(d.time_s.to_bits());
        out.extend(state(&d.state));
    }
    (out, t.divergence.map(|d| d.kind))
}

fn assert_same(lanes: &[Trajectory], scalar: &[Trajectory]) {
    assert_eq!(lanes.len(), scalar.len());
    for (i, (a, b)) in lanes.iter().zip(scalar).enumerate() {
        assert!(bits(a) == bits(b), "run {i}: lanes and scalar differ");
    }
}

/// A diagonal PD on the hover state mapped through the pseudo-inverse of the effectiveness
/// matrix (the closed-loop benches' gain), `u = u_trim - K (x - x_trim)`.
fn hover_feedback(airframe: &Airframe, altitude_m: f64) -> LinearFeedback {
    let (m, g) = (airframe.mass_kg(), airframe.gravity_m_s2());
    let mut x_trim = [0.0; STATE_DIM];
    x_trim[2] = -altitude_m;
    let hover = m * g / airframe.rotor_count() as f64;
    LinearFeedback::new(
        &x_trim,
        &vec![hover; airframe.rotor_count()],
        crate::fixtures::hover_gain(airframe),
    )
    .unwrap()
}

/// A controller whose commands turn NaN from `after_s` on (a broken law ends only its lane).
struct NanAfter {
    law: LinearFeedback,
    after_s: f64,
}

impl Controller for NanAfter {
    fn command_count(&self) -> usize {
        self.law.command_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.law.command(t_s, measured, out)?;
        if t_s >= self.after_s {
            out[1] = f64::NAN;
        }
        Ok(())
    }
}

fn start(k: usize) -> RigidBodyState {
    let x = |i: usize| ((k * 5 + i) as f64 * 0.77).sin();
    RigidBodyState {
        position_m: Vector3::new(0.3 * x(0), 0.3 * x(1), -10.0 + 0.2 * x(2)),
        velocity_m_s: Vector3::new(0.5 * x(3), 0.4 * x(4), 0.3 * x(5)),
        attitude: UnitQuaternion::from_euler_angles(0.1 * x(6), 0.1 * x(7), 0.3 * x(8)),
        omega_rad_s: Vector3::new(0.2 * x(9), 0.1 * x(10), 0.1 * x(11)),
    }
}

/// The batch flown in lanes and one run at a time; flown in the lanes' portable build too, which
/// must fly what the lanes fly (the AVX2 form where this CPU has AVX2 and FMA) bit for bit,
/// taking the baseline form at every place that chooses (counted per place: the group stepper,
/// and on sensors whose estimators fly in lanes, the estimators' IMU sample, estimates and
/// kernels).
fn both(
    vehicle: &Vehicle,
    actuators: &Actuators,
    runs: impl Fn() -> Vec<BatchRun>,
    config: &SimulationConfig,
) -> (Vec<Trajectory>, Vec<Trajectory>) {
    let fly = |lanes| {
        simulate_batch_lanes(
            vehicle,
            actuators,
            &[1.0; 4],
            runs(),
            config,
            &Cancel::never(),
            lanes,
        )
        .unwrap()
    };
    let lanes = fly(BatchLanes::Auto);
    let portable = {
        let _serial = portable_choices::serial();
        let before = portable_choices::snapshot();
        let portable = fly(BatchLanes::Portable);
        let after = portable_choices::snapshot();
        // Elsewhere the choices are compiled out: there is only the portable form.
        if cfg!(target_arch = "x86_64") {
            let estimators_in_lanes = config
                .sensing
                .as_ref()
                .is_some_and(|s| s.suite != SuiteName::Gnss);
            let mut places = vec![Choice::Group];
            if estimators_in_lanes {
                places.extend([Choice::PushImu, Choice::EstimatesAt, Choice::Kernel]);
            }
            for place in places {
                let i = place as usize;
                assert!(after[i] > before[i], "{place:?} took the portable form");
            }
        }
        portable
    };
    assert_eq!(portable.len(), lanes.len());
    for (i, (a, b)) in portable.iter().zip(&lanes).enumerate() {
        assert!(
            bits(a) == bits(b),
            "run {i}: the portable build and the lanes differ"
        );
    }
    (lanes, fly(BatchLanes::Scalar))
}

/// The quad-x with linear drag and 20 ms rotor lag both bit-for-bit batches fly, and its hover
/// thrust per rotor (N).
fn lagged_quad() -> (Airframe, Vehicle, Actuators, f64) {
    let airframe = crate::fixtures::preset("quad-x");
    let vehicle = Vehicle::new(
        &airframe,
        Drag {
            linear_drag_n_s_m: 0.2,
            ..Drag::default()
        },
    )
    .unwrap();
    let lag = Lag {
        time_constant_s: 0.02,
        rate_limit_per_s: f64::INFINITY,
    };
    let actuators = Actuators::FixedPitch(FixedPitch::new(&airframe, lag, 0.0).unwrap());
    let hover = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
    (airframe, vehicle, actuators, hover)
}

#[test]
fn lanes_fly_the_scalar_hover_feedback_batch_bit_for_bit() {
    let (airframe, vehicle, actuators, hover) = lagged_quad();
    let mut config = SimulationConfig::new(0.0025, 2, 2.5);
    config.record_every = 3;
    config.wind_m_s = Vector3::new(0.5, -0.2, 0.0);
    // 11 runs: runs 0-3 and 8 share a fault time between substeps (three groups' worth of
    // lanes with the fault-free runs, one left for the scalar path); run 2 loses a rotor
    // (diverges), run 6 starts far off (saturates), run 5's law breaks at 0.6 s.
    let runs = || -> Vec<BatchRun> {
        (0..11)
            .map(|k| {
                let law = hover_feedback(&airframe, 10.0);
                let faults = if k < 4 || k == 8 {
                    vec![RotorFault {
                        rotor: k % 4,
                        time_s: 0.30013,
                        efficiency: if k == 2 { 0.0 } else { 0.6 },
                    }]
                } else {
                    vec![]
                };
                let mut x0 = start(k);
                if k == 6 {
                    x0.position_m.z = -7.0;
                    x0.velocity_m_s.z = 2.0;
                }
                let controller: Box<dyn Controller> = if k == 5 {
                    Box::new(NanAfter { law, after_s: 0.6 })
                } else {
                    Box::new(law)
                };
                BatchRun {
                    controller,
                    initial_command: Some(vec![hover; 4]),
                    x0,
                    faults,
                }
            })
            .collect()
    };
    let plans = plan(
        &vehicle,
        &actuators,
        &[1.0; 4],
        runs(),
        &config,
        BatchLanes::Auto,
    );
    let groups = plans.iter().filter(|p| matches!(p, Plan::Group(_))).count();
    assert_eq!(
        (groups, plans.len()),
        (2, 5),
        "two groups of four, three runs scalar"
    );
    let (lanes, scalar) = both(&vehicle, &actuators, runs, &config);
    assert_same(&lanes, &scalar);
    // The cases the batch was built to hold.
    assert!(lanes[2].divergence.is_some(), "a dead rotor diverges");
    assert_eq!(
        lanes[5].divergence.map(|d| d.kind),
        Some(DivergenceKind::NonFiniteCommand)
    );
    let max = airframe.max_thrust_n();
    assert!(
        lanes[6]
            .rotor_command
            .chunks(4)
            .any(|c| c.iter().zip(&max).any(|(u, m)| u > m)),
        "run 6 saturates"
    );
    assert!(lanes[0].efficiency.contains(&0.6), "the fault acts");
    assert!(lanes.iter().filter(|t| t.divergence.is_none()).count() >= 8);
}

#[test]
fn lanes_fly_the_scalar_ke_ftc_batch_bit_for_bit() {
    let airframe = crate::fixtures::preset("ke-quadcopter");
    let drag = Drag {
        linear_drag_n_s_m: 0.3,
        rotational_drag_n_m_s: 2.8e-3,
        ..Drag::default()
    };
    let vehicle = Vehicle::new(&airframe, drag).unwrap();
    let lag = Lag {
        time_constant_s: 0.025,
        rate_limit_per_s: f64::INFINITY,
    };
    let actuators = Actuators::FixedPitch(FixedPitch::new(&airframe, lag, 0.0).unwrap());
    let hover = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
    let config = SimulationConfig::new(0.0025, 4, 1.5);
    let runs = || -> Vec<BatchRun> {
        (0..4)
            .map(|k| {
                let ke = UniformPassiveFtc::new(
                    &airframe,
                    KeGains::default(),
                    CommandLaw::default(),
                    vec![(0.0, [0.0, 0.0, -10.0])],
                    0.0025,
                )
                .unwrap();
                BatchRun {
                    controller: Box::new(ke),
                    initial_command: Some(vec![hover; 4]),
                    x0: start(k),
                    faults: vec![RotorFault {
                        rotor: k % 2,
                        time_s: 0.5,
                        efficiency: 0.0,
                    }],
                }
            })
            .collect()
    };
    let (lanes, scalar) = both(&vehicle, &actuators, runs, &config);
    assert_same(&lanes, &scalar);
    assert!(
        lanes.iter().all(|t| t.divergence.is_none()),
        "Ke's FTC holds one dead rotor"
    );
}

/// A hover law that also reads the samples a controller may read (the gyro, the specific force,
/// the rotor thrusts), so that they reach its commands.
struct Sampler(LinearFeedback);
impl Controller for Sampler {
    fn command_count(&self) -> usize {
        4
    }
    fn command(&mut self, t: f64, s: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.0.command(t, s, out)
    }
    fn command_with(&mut self, t: f64, input: &ControllerInput<'_>, out: &mut [f64]) -> Result<()> {
        self.0.command(t, input.state, out)?;
        let f = input.specific_force_m_s2.unwrap();
        let gyro = input.gyro_rad_s.unwrap();
        // On sensors no rotor-speed reading has arrived before the sensor's latency.
        let thrust = input.rotor_thrust_n.map_or(0.0, |r| r[3]);
        out[0] += 1e-3 * f.z + 1e-3 * thrust + 1e-3 * gyro.x;
        Ok(())
    }
    fn reads_samples(&self) -> bool {
        true
    }
}

#[test]
fn a_controller_that_reads_samples_gets_the_scalar_samples_in_a_lane() {
    // Through `truth_samples`, the one function both paths use.
    let airframe = crate::fixtures::preset("quad-x");
    let vehicle = Vehicle::new(&airframe, Drag::default()).unwrap();
    let actuators = Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap());
    let mut config = SimulationConfig::new(0.0025, 2, 0.5);
    let runs = || -> Vec<BatchRun> {
        (0..4)
            .map(|k| BatchRun {
                controller: Box::new(Sampler(hover_feedback(&airframe, 10.0))),
                initial_command: None,
                x0: start(k),
                faults: vec![],
            })
            .collect()
    };
    let (lanes, scalar) = both(&vehicle, &actuators, runs, &config);
    assert_same(&lanes, &scalar);
    // On sensors (instant rotors: the tape's nodes carry the targets), the sensors' samples.
    config.sensing = Some(Sensing {
        seed: 3,
        ..Sensing::default()
    });
    assert!(plan(
        &vehicle,
        &actuators,
        &[1.0; 4],
        runs(),
        &config,
        BatchLanes::Auto
    )
    .iter()
    .all(|p| matches!(p, Plan::Group(_))));
    let (lanes, scalar) = both(&vehicle, &actuators, runs, &config);
    assert_same(&lanes, &scalar);
    let record = lanes[0].sensing.as_ref().unwrap();
    assert!(
        record.imu_samples > 200 && record.fusion.fused > 0,
        "{record:?}"
    );
}

#[test]
fn lanes_fly_the_scalar_sensed_batch_bit_for_bit() {
    // On sensors and the estimator: lag, a fault between substeps (one lane loses a rotor and
    // diverges), a law that breaks, constant wind; each run's own sensor seed.
    let (airframe, vehicle, actuators, hover) = lagged_quad();
    let mut config = SimulationConfig::new(0.0025, 2, 1.5);
    config.record_every = 3;
    config.wind_m_s = Vector3::new(0.5, -0.2, 0.0);
    config.sensing = Some(Sensing {
        seed: 11,
        ..Sensing::default()
    });
    let runs = || -> Vec<BatchRun> {
        (0..8)
            .map(|k| {
                let law = hover_feedback(&airframe, 10.0);
                let faults = if k < 4 {
                    vec![RotorFault {
                        rotor: k % 4,
                        time_s: 0.30013,
                        efficiency: if k == 2 { 0.0 } else { 0.6 },
                    }]
                } else {
                    vec![]
                };
                let controller: Box<dyn Controller> = if k == 5 {
                    Box::new(NanAfter { law, after_s: 0.6 })
                } else {
                    Box::new(law)
                };
                BatchRun {
                    controller,
                    initial_command: Some(vec![hover; 4]),
                    x0: start(k),
                    faults,
                }
            })
            .collect()
    };
    let plans = plan(
        &vehicle,
        &actuators,
        &[1.0; 4],
        runs(),
        &config,
        BatchLanes::Auto,
    );
    assert!(
        plans.iter().all(|p| matches!(p, Plan::Group(_))),
        "two groups"
    );
    let (lanes, scalar) = both(&vehicle, &actuators, runs, &config);
    assert_same(&lanes, &scalar);
    assert!(lanes[2].divergence.is_some(), "a dead rotor diverges");
    assert_eq!(
        lanes[5].divergence.map(|d| d.kind),
        Some(DivergenceKind::NonFiniteCommand)
    );
    assert!(lanes.iter().filter(|t| t.divergence.is_none()).count() >= 6);
    // Each run its own seed: the estimates differ between runs flown from the same start.
    let row = |t: &Trajectory| t.sensing.as_ref().unwrap().rows[5].state.position_m;
    assert_ne!(row(&lanes[4]), row(&lanes[6]));
}

#[test]
fn scalar_setting_and_unsupported_batches_fly_every_run_scalar() {
    let airframe = crate::fixtures::preset("quad-x");
    let vehicle = Vehicle::new(&airframe, Drag::default()).unwrap();
    let lagged = |rate| {
        Actuators::FixedPitch(
            FixedPitch::new(
                &airframe,
                Lag {
                    time_constant_s: 0.02,
                    rate_limit_per_s: rate,
                },
                0.0,
            )
            .unwrap(),
        )
    };
    let config = SimulationConfig::new(0.0025, 2, 0.1);
    let runs = || -> Vec<BatchRun> {
        (0..4)
            .map(|k| BatchRun {
                controller: Box::new(hover_feedback(&airframe, 10.0)),
                initial_command: None,
                x0: start(k),
                faults: vec![],
            })
            .collect()
    };
    let scalar_only = |actuators: &Actuators, lanes| {
        plan(&vehicle, actuators, &[1.0; 4], runs(), &config, lanes)
            .iter()
            .all(|p| matches!(p, Plan::Scalar(..)))
    };
    assert!(!scalar_only(&lagged(f64::INFINITY), BatchLanes::Auto));
    assert!(!scalar_only(&lagged(f64::INFINITY), BatchLanes::Portable));
    assert!(scalar_only(&lagged(f64::INFINITY), BatchLanes::Scalar));
    assert!(
        scalar_only(&lagged(50.0), BatchLanes::Auto),
        "a rate limit is not in the lanes"
    );
    assert_eq!(BatchLanes::Scalar.name(), "scalar");
    assert_eq!(BatchLanes::Portable.name(), "portable");
}

/// Four runs of the hover law from `start(k)`, settled at `hover` N per rotor: run `k`'s law
/// reads the samples ([`Sampler`]) where `reads(k)`, and loses its rotors as `faults(k)` says.
fn four_hover_runs(
    airframe: &Airframe,
    hover: f64,
    reads: impl Fn(usize) -> bool,
    faults: impl Fn(usize) -> Vec<RotorFault>,
) -> Vec<BatchRun> {
    (0..4)
        .map(|k| {
            let law = hover_feedback(airframe, 10.0);
            let controller: Box<dyn Controller> = if reads(k) {
                Box::new(Sampler(law))
            } else {
                Box::new(law)
            };
            BatchRun {
                controller,
                initial_command: Some(vec![hover; 4]),
                x0: start(k),
                faults: faults(k),
            }
        })
        .collect()
}

/// `true` when `runs`, planned as one group of four, fly their estimators in lanes.
fn estimators_fly_in_lanes(
    vehicle: &Vehicle,
    actuators: &Actuators,
    runs: Vec<BatchRun>,
    config: &SimulationConfig,
) -> bool {
    let plans = plan(
        vehicle,
        actuators,
        &[1.0; 4],
        runs,
        config,
        BatchLanes::Auto,
    );
    let [Plan::Group(group)] = &plans[..] else {
        panic!("one group of four");
    };
    onboard_in_lanes::<F64x4>(group, 4, detected_path()).is_some()
}

/// `runs` (a group of four on sensors that share a schedule) flown with their estimators in
/// lanes, equal bit for bit to the scalar batch: the lanes' trajectories.
fn sensed_group_in_lanes(
    vehicle: &Vehicle,
    actuators: &Actuators,
    runs: impl Fn() -> Vec<BatchRun>,
    config: &SimulationConfig,
) -> Vec<Trajectory> {
    assert!(estimators_fly_in_lanes(vehicle, actuators, runs(), config));
    let (lanes, scalar) = both(vehicle, actuators, runs, config);
    assert_same(&lanes, &scalar);
    lanes
}

#[test]
fn estimators_fly_in_lanes_where_the_sensors_share_a_schedule() {
    // RTK (position, velocity, the magnetometer; no dropouts) and motion capture: the group's
    // estimators in lanes; GNSS (fixes drop out at random per run): each run's own. All bit for
    // bit the scalar batch, with one run losing a rotor at 0.3 s and diverging (its lane stops,
    // its counts with it). The estimators' per-lane cases (a fix refused, a gyro clamping in
    // one lane) are checked against the scalar estimator in `estimation::lanes`.
    let (airframe, vehicle, actuators, hover) = lagged_quad();
    let mut config = SimulationConfig::new(0.0025, 2, 2.0);
    config.record_every = 2;
    let runs = || {
        four_hover_runs(
            &airframe,
            hover,
            |_| false,
            |k| {
                vec![RotorFault {
                    rotor: 1,
                    time_s: 0.3,
                    efficiency: if k == 1 { 0.0 } else { 1.0 },
                }]
            },
        )
    };
    for (suite, in_lanes) in [
        (SuiteName::Rtk, true),
        (SuiteName::Gnss, false),
        (SuiteName::Mocap, true),
    ] {
        config.sensing = Some(Sensing {
            suite,
            seed: 5,
            ..Sensing::default()
        });
        assert_eq!(
            estimators_fly_in_lanes(&vehicle, &actuators, runs(), &config),
            in_lanes,
            "{}",
            suite.name()
        );
        let (lanes, scalar) = both(&vehicle, &actuators, runs, &config);
        assert_same(&lanes, &scalar);
        assert!(
            lanes[0].sensing.as_ref().unwrap().fusion.fused > 0,
            "{}",
            suite.name()
        );
        let diverged: Vec<bool> = lanes.iter().map(|t| t.divergence.is_some()).collect();
        assert_eq!(diverged, [false, true, false, false], "{}", suite.name());
    }
}

#[test]
fn runs_that_read_rotor_speeds_share_a_group_with_runs_that_do_not() {
    // About 64 IMU samples per control period (31.9 kHz at 500 Hz): two runs whose laws read
    // the rotor-speed feedback take rotor-speed samples the other two do not, on the group's one
    // schedule (the first version, which took each run's readings in chunks of 64, put the
    // lanes out of step when a chunk ended before a rotor-speed sample).
    let (airframe, vehicle, actuators, hover) = lagged_quad();
    let mut config = SimulationConfig::new(0.002, 2, 0.2);
    config.sensing = Some(Sensing {
        seed: 2,
        imu_rate_hz: 31_900.0,
        ..Sensing::default()
    });
    let runs = || four_hover_runs(&airframe, hover, |k| k < 2, |_| vec![]);
    let lanes = sensed_group_in_lanes(&vehicle, &actuators, runs, &config);
    assert!(lanes[0].sensing.as_ref().unwrap().imu_samples > 6_000);
}

#[test]
fn the_group_schedule_passes_on_when_its_first_run_ends() {
    // The group's sensor schedule is read from its first flying run and the rotor-speed clock
    // from its first run that reads rotor speeds: here run 0, which reads them, loses a rotor
    // and diverges, so the schedule passes to run 1 (which does not read them) and the
    // rotor-speed clock to run 2; the lanes still fly every run as the scalar driver does.
    let (airframe, vehicle, actuators, hover) = lagged_quad();
    let mut config = SimulationConfig::new(0.0025, 2, 1.5);
    config.sensing = Some(Sensing {
        seed: 5,
        ..Sensing::default()
    });
    let runs = || {
        four_hover_runs(
            &airframe,
            hover,
            |k| k % 2 == 0,
            |k| {
                vec![RotorFault {
                    rotor: 0,
                    time_s: 0.30013,
                    efficiency: if k == 0 { 0.0 } else { 1.0 },
                }]
            },
        )
    };
    let lanes = sensed_group_in_lanes(&vehicle, &actuators, runs, &config);
    assert!(lanes[0].divergence.is_some(), "a dead rotor diverges");
    assert!(lanes[1..].iter().all(|t| t.divergence.is_none()));
    let imu = |t: &Trajectory| t.sensing.as_ref().unwrap().imu_samples;
    assert!(imu(&lanes[0]) < imu(&lanes[1]), "run 0 stopped sampling");
}

#[test]
fn lanes_fly_the_scalar_sensed_batch_with_instant_rotors_bit_for_bit() {
    // Rotors without lag: the group's tape nodes take the saturated commands as the channels
    // (the scalar integrator's constant case), and the period's end node the same totals; a
    // law that reads the rotor speeds beside three that do not, a fault within a period. One
    // RK4 interval per period, so that every rotor-speed reading the law gets was taken from
    // an interval's start node (with four, the 1 kHz readings it gets fall in later intervals).
    let (airframe, vehicle, _, hover) = lagged_quad();
    let instant = Lag {
        time_constant_s: 0.0,
        rate_limit_per_s: f64::INFINITY,
    };
    let actuators = Actuators::FixedPitch(FixedPitch::new(&airframe, instant, 0.0).unwrap());
    let mut config = SimulationConfig::new(0.0025, 1, 1.0);
    config.sensing = Some(Sensing {
        seed: 8,
        ..Sensing::default()
    });
    let runs = || {
        four_hover_runs(
            &airframe,
            hover,
            |k| k == 3,
            |k| {
                vec![RotorFault {
                    rotor: k,
                    time_s: 0.40021,
                    efficiency: 0.7,
                }]
            },
        )
    };
    let lanes = sensed_group_in_lanes(&vehicle, &actuators, runs, &config);
    assert!(lanes.iter().all(|t| t.divergence.is_none()));
}
