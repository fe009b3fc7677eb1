//! Flying on sensors (`SimulationConfig::sensing`): the controller flies on the estimator fed by
//! the sensor models sampling the truth between control steps. Checked here in closed loop on
//! Ke's quadrotor (`ke-quadcopter`, Ke's 25 ms rotor lag and drags) with the motion-capture suite
//! (`Sensing::default()`: ICM-42688-P at 500 Hz, OptiTrack PrimeX 13 at 240 Hz, DShot rotor
//! speeds): determinism by seed, a batch equal to single runs, the estimator's error against the
//! position source's stated noise (an independent figure: a filter that fuses the IMU must beat
//! the raw fixes), the sensors' clocks and the gyro-saturation flags, and Ke's and INDI's flights
//! with truth and with sensors side by side, each with its verdict.
//!
//! Verdict (as issue 30's): a flight *holds* when, from 5 s after the failure to the end (25 s),
//! it stays within 1 m altitude and 3 m horizontal of the reference and does not diverge (the
//! ground, 10 m below the start, ends a run as diverged). Failures at 3 s.

use nalgebra::Vector3;

use rfcore::control::indi::{DetectedFailure, IndiController, IndiGains, Setpoint};
use rfcore::control::ke::{CommandLaw, KeGains, UniformPassiveFtc};
use rfcore::control::Controller;
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::sensors::PositionSourceProfile;
use rfcore::flight::simulation::{
    simulate, simulate_batch, BatchRun, RotorFault, Sensing, SimulationConfig, Trajectory,
};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::RigidBodyState;
use rfcore::Cancel;

const DT: f64 = 1.0 / 400.0;
const ALTITUDE_M: f64 = 10.0;
const FAULT_S: f64 = 3.0;
const DURATION_S: f64 = 25.0;
const SETTLE_S: f64 = 5.0;

/// Which rotors (0-based) a case loses at `FAULT_S`.
const CASES: [(&str, &[usize]); 3] = [("hover", &[]), ("one", &[0]), ("two-opposite", &[0, 2])];

#[derive(Clone, Copy, PartialEq, Debug)]
enum Law {
    Ke,
    Indi,
}

struct Flight {
    vehicle: Vehicle,
    actuators: Actuators,
    faults: Vec<RotorFault>,
    x0: RigidBodyState,
    law: Law,
    failed: Vec<usize>,
}

/// `law` holding 10 m on `ke-quadcopter`, rotors `failed` lost at `FAULT_S` (INDI told at once;
/// Ke's law is passive, told nothing).
fn flight(law: Law, failed: &[usize]) -> Flight {
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
    let vehicle = Vehicle::new(&airframe, drag).unwrap();
    let actuators = Actuators::FixedPitch(FixedPitch::new(&airframe, lag, 0.0).unwrap());
    Flight {
        vehicle,
        actuators,
        faults: failed
            .iter()
            .map(|&rotor| RotorFault {
                rotor,
                time_s: FAULT_S,
                efficiency: 0.0,
            })
            .collect(),
        x0: RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, -ALTITUDE_M),
            ..RigidBodyState::at_rest()
        },
        law,
        failed: failed.to_vec(),
    }
}

impl Flight {
    /// A fresh controller and the actuators settled at its hover.
    fn controller(&self) -> (Box<dyn Controller>, Actuators) {
        let airframe = rfcore::fixtures::preset("ke-quadcopter");
        let mut actuators = self.actuators.clone();
        match self.law {
            Law::Indi => {
                let failures = self
                    .failed
                    .iter()
                    .map(|&rotor| DetectedFailure {
                        rotor,
                        time_s: FAULT_S,
                    })
                    .collect();
                let setpoint = Setpoint {
                    time_s: 0.0,
                    position_m: [0.0, 0.0, -ALTITUDE_M],
                    velocity_m_s: [0.0; 3],
                };
                let c = IndiController::new(
                    &airframe,
                    IndiGains::default(),
                    failures,
                    vec![setpoint],
                    DT,
                )
                .unwrap();
                actuators
                    .settle(&c.failure_modes()[0].hover_thrust_n)
                    .unwrap();
                (Box::new(c), actuators)
            }
            Law::Ke => {
                let c = UniformPassiveFtc::new(
                    &airframe,
                    KeGains::default(),
                    CommandLaw::default(),
                    vec![(0.0, [0.0, 0.0, -ALTITUDE_M])],
                    DT,
                )
                .unwrap();
                let hover = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
                actuators.settle(&[hover; 4]).unwrap();
                (Box::new(c), actuators)
            }
        }
    }

    fn fly(&self, sensing: Option<Sensing>) -> Trajectory {
        let (mut controller, actuators) = self.controller();
        simulate(
            &self.vehicle,
            actuators,
            controller.as_mut(),
            &[1.0; 4],
            &self.faults,
            self.x0,
            &config(sensing),
        )
        .unwrap()
    }
}

fn config(sensing: Option<Sensing>) -> SimulationConfig {
    let mut c = SimulationConfig::new(DT, 4, DURATION_S);
    c.sensing = sensing;
    c
}

/// The verdict on a whole flight (module docs), with its worst deviations in the window.
struct Verdict {
    holds: bool,
    altitude_m: f64,
    horizontal_m: f64,
}

fn verdict(run: &Trajectory) -> Verdict {
    let (mut altitude_m, mut horizontal_m) = (0.0f64, 0.0f64);
    for (t, s) in run.t_s.iter().zip(&run.states) {
        if *t >= FAULT_S + SETTLE_S {
            altitude_m = altitude_m.max((s.position_m.z + ALTITUDE_M).abs());
            horizontal_m = horizontal_m.max(s.position_m.xy().norm());
        }
    }
    let reached_end = run.t_s.last().is_some_and(|&t| t >= DURATION_S - 1e-9);
    Verdict {
        holds: run.divergence.is_none() && reached_end && altitude_m <= 1.0 && horizontal_m <= 3.0,
        altitude_m,
        horizontal_m,
    }
}

/// Over the rows from `from_s` on: RMS of the attitude error (rad, the angle between estimated
/// and true attitude) and of the 3-D position error (m), and the RMS of the filter's own
/// attitude and position sigmas (3-D: the root of the summed variances).
struct EstimatorError {
    attitude_rad: f64,
    position_m: f64,
    attitude_sigma_rad: f64,
    position_sigma_m: f64,
}

fn estimator_error(run: &Trajectory, from_s: f64) -> EstimatorError {
    let record = run.sensing.as_ref().unwrap();
    let (mut att, mut pos, mut att_var, mut pos_var, mut n) = (0.0, 0.0, 0.0, 0.0, 0usize);
    for ((t, truth), row) in run.t_s.iter().zip(&run.states).zip(&record.rows) {
        if *t < from_s || !row.state.position_m.x.is_finite() {
            continue;
        }
        att += truth.attitude.angle_to(&row.state.attitude).powi(2);
        pos += (truth.position_m - row.state.position_m).norm_squared();
        pos_var += row.std[0..3].iter().map(|s| s * s).sum::<f64>();
        att_var += row.std[6..9].iter().map(|s| s * s).sum::<f64>();
        n += 1;
    }
    let n = n as f64;
    EstimatorError {
        attitude_rad: (att / n).sqrt(),
        position_m: (pos / n).sqrt(),
        attitude_sigma_rad: (att_var / n).sqrt(),
        position_sigma_m: (pos_var / n).sqrt(),
    }
}

/// The motion-capture fixes' own 3-D RMS error (the profile's per-axis noise times sqrt 3):
/// attitude rad, position m.
fn raw_mocap_errors() -> (f64, f64) {
    let p = PositionSourceProfile::optitrack_primex_13();
    let sqrt3 = 3f64.sqrt();
    (
        sqrt3 * p.attitude_noise_rad.unwrap(),
        sqrt3 * p.horizontal_noise_m,
    )
}

#[test]
fn estimator_beats_the_raw_fixes_and_knows_its_error_in_hover_and_after_rotor_loss() {
    // INDI (told of the failure at once) on mocap. After one or two lost rotors the vehicle
    // spins beyond the gyro's 2000 deg/s = 34.9 rad/s range: the flags count clamped samples and
    // the filter learns the hidden excess from the mocap attitude. Targets: below the raw fixes'
    // 3-D error (0.14 deg, 0.35 mm) and within a factor 2 of the filter's own sigma.
    let (raw_att, raw_pos) = raw_mocap_errors();
    for (name, failed) in CASES {
        let run = flight(Law::Indi, failed).fly(Some(Sensing::default()));
        let e = estimator_error(&run, 1.0);
        let r = run.sensing.as_ref().unwrap();
        println!(
            "INDI {name}, mocap: attitude RMS {:.4} deg (sigma {:.4}), position RMS {:.3} mm \
             (sigma {:.3}); gyro clamped in {} of {} IMU samples; fused {}, rejected {}, late {}, \
             thinned {}",
            e.attitude_rad.to_degrees(),
            e.attitude_sigma_rad.to_degrees(),
            e.position_m * 1e3,
            e.position_sigma_m * 1e3,
            r.gyro_saturated_samples,
            r.imu_samples,
            r.fusion.fused,
            r.fusion.rejected,
            r.fusion.late,
            r.fusion.thinned,
        );
        assert!(e.attitude_rad < raw_att, "{name}: {} rad", e.attitude_rad);
        assert!(e.position_m < raw_pos, "{name}: {} m", e.position_m);
        for (what, rms, sigma) in [
            ("attitude", e.attitude_rad, e.attitude_sigma_rad),
            ("position", e.position_m, e.position_sigma_m),
        ] {
            assert!(
                (0.5..2.0).contains(&(rms / sigma)),
                "{name} {what}: {rms} vs sigma {sigma}"
            );
        }
        // The sensors' clocks: the IMU at 500 Hz from t = 0 (both ends), the mocap at 240 Hz
        // (those still in flight at the end: latency 2.9 ms), one fix taken per 10 ms fusion
        // slot (every slot holds a fix) with position and attitude fused, the others thinned.
        assert_eq!(r.imu_samples, (DURATION_S * 500.0) as u64 + 1);
        let fixes = (DURATION_S * 240.0) as u64;
        let slots = (DURATION_S / 0.01).round() as u64;
        let taken = r.fusion.fused + r.fusion.rejected + r.fusion.late;
        assert_eq!(taken % 2, 0, "{name}: {:?}", r.fusion);
        assert!(taken / 2 <= slots + 1 && taken / 2 >= slots - 1, "{name}: {:?}", r.fusion);
        assert_eq!(r.fusion.thinned % 2, 0, "{name}: {:?}", r.fusion);
        assert!((taken + r.fusion.thinned) / 2 <= fixes + 1);
        assert!((taken + r.fusion.thinned) / 2 >= fixes - 1);
        assert!(r.fusion.rejected <= 2, "{name}: {:?}", r.fusion);
        if failed.is_empty() {
            assert_eq!(r.gyro_saturated_samples, 0);
        } else {
            // Spinning from about a second after the failure to the end.
            assert!(
                r.gyro_saturated_samples > 20 * 500 / 2,
                "{name}: {}",
                r.gyro_saturated_samples
            );
            let flagged = r.rows.iter().filter(|row| row.gyro_saturated).count();
            let beyond = run
                .states
                .iter()
                .filter(|s| s.omega_rad_s.amax() > 2000f64.to_radians())
                .count();
            assert!(
                flagged > 0 && flagged.abs_diff(beyond) * 50 < beyond,
                "{flagged} vs {beyond}"
            );
        }
    }
}

#[test]
fn same_seed_same_flight_and_a_batch_flies_each_run_as_alone() {
    let f = flight(Law::Indi, &[0]);
    let sensing = Sensing {
        seed: 7,
        ..Sensing::default()
    };
    let mut cfg = config(Some(sensing));
    cfg.duration_s = 6.0;
    let alone = |seed: u64| {
        let mut c = cfg.clone();
        c.sensing = Some(Sensing { seed, ..sensing });
        let (mut controller, actuators) = f.controller();
        simulate(
            &f.vehicle,
            actuators,
            controller.as_mut(),
            &[1.0; 4],
            &f.faults,
            f.x0,
            &c,
        )
        .unwrap()
    };
    let (a, b, other) = (alone(7), alone(7), alone(8));
    assert_eq!(a, b);
    assert_ne!(a.states, other.states);
    assert_ne!(a.sensing, other.sensing);
    // The estimate differs from the truth the controller would have seen.
    let row = &a.sensing.as_ref().unwrap().rows[1000];
    assert_ne!(row.state.position_m, a.states[1000].position_m);

    let runs = (0..2)
        .map(|_| {
            let (controller, _) = f.controller();
            BatchRun {
                controller,
                x0: f.x0,
                initial_command: None,
                faults: f.faults.clone(),
            }
        })
        .collect();
    let (_, settled) = f.controller();
    let batch = simulate_batch(
        &f.vehicle,
        &settled,
        &[1.0; 4],
        runs,
        &cfg,
        &Cancel::never(),
    )
    .unwrap();
    assert_eq!(batch[0], a);
    assert_eq!(batch[1], other);
}

#[test]
fn ke_and_indi_with_truth_and_with_mocap_side_by_side() {
    // Each law and case flown twice, on the truth and on mocap with the estimator; the verdicts
    // are stated, and each law's flights on mocap must keep the verdict it has on the truth.
    // Measured (this file's vehicle and 25 s runs): INDI holds all three on both, within 4 mm
    // horizontal on mocap; Ke's passive law holds the hover on both (18 mm on mocap) and holds
    // neither loss on either (one rotor: 15 m off station at 25 s, its slow position loop; two
    // opposite: diverges), so mocap sensing changes no verdict here. Ke's paper scenarios on its
    // own vehicle (`ke-hil`) with sensors: tests/flight/test_sensing.py.
    for law in [Law::Ke, Law::Indi] {
        for (name, failed) in CASES {
            let f = flight(law, failed);
            let truth = verdict(&f.fly(None));
            let run = f.fly(Some(Sensing::default()));
            let sensed = verdict(&run);
            println!(
                "{law:?} {name}: truth {} (altitude {:.3} m, horizontal {:.3} m); mocap {} \
                 (altitude {:.3} m, horizontal {:.3} m)",
                if truth.holds {
                    "holds"
                } else {
                    "does not hold"
                },
                truth.altitude_m,
                truth.horizontal_m,
                if sensed.holds {
                    "holds"
                } else {
                    "does not hold"
                },
                sensed.altitude_m,
                sensed.horizontal_m,
            );
            assert_eq!(sensed.holds, truth.holds, "{law:?} {name}");
        }
    }
}
