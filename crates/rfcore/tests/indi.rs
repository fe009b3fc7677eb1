//! INDI fault-tolerant control (`rfcore::control::indi`) in closed loop with the simulator: the
//! one-step prediction of the angular acceleration against the simulator's, and flights through
//! rotor failures with the verdict taken over the whole window.
//!
//! Verdict (issue 30): a flight *holds* when, from 5 s after the failure to the end (25 s), it stays
//! within 1 m altitude and 3 m horizontal of the reference, and never touches the ground (10 m
//! below the start) nor diverges. Failures at 3 s, the controller told at once unless stated.

use nalgebra::Vector3;

use rfcore::control::indi::{
    DetectedFailure, IndiController, IndiGains, IndiStep, Setpoint, YawMode,
};
use rfcore::control::Controller;
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::simulation::{simulate, RotorFault, SimulationConfig, Trajectory};
use rfcore::flight::vehicle::{Drag, RotorTotals, Vehicle};
use rfcore::state::{ControllerInput, RigidBodyState};
use rfcore::{Airframe, Result};

const DT: f64 = 1.0 / 400.0;
const FAULT_S: f64 = 3.0;
const DURATION_S: f64 = 25.0;
/// The verdict window starts this long after the failure.
const SETTLE_S: f64 = 5.0;
const ALTITUDE_M: f64 = 10.0;

/// The vehicle a preset flies here. Ke's and Lanzon's are their presets' (`ke-hil`; the defaults of
/// `LanzonVehicle`: `k_r = m g d / 2.7`, rotor inertia 3e-5 kg m^2, 50 N/s rate limit); the hexa-
/// and octocopters (Du's Table I gives no aerodynamics) get Ke's rotor lag and Ke's drags scaled by
/// mass (test values, stated here).
struct Model {
    airframe: Airframe,
    lag: Lag,
    thrust_coefficient_n_s2: f64,
    drag: Drag,
}

fn model(name: &str) -> Model {
    let airframe = rfcore::fixtures::preset(name);
    let ke_lag = Lag {
        time_constant_s: 0.025,
        rate_limit_per_s: f64::INFINITY,
    };
    match name {
        "lanzon-quadrotor" => {
            let (m, g, d) = (
                airframe.mass_kg(),
                airframe.gravity_m_s2(),
                airframe.drag_torque_ratio_m(),
            );
            Model {
                airframe,
                lag: Lag {
                    time_constant_s: 0.0,
                    rate_limit_per_s: 50.0,
                },
                thrust_coefficient_n_s2: 1e-5,
                drag: Drag {
                    linear_drag_n_s_m: 0.1,
                    rotational_drag_n_m_s: m * g * d / 2.7,
                    rotor_inertia_kg_m2: 3e-5,
                    ..Drag::default()
                },
            }
        }
        _ => {
            let scale = airframe.mass_kg() / 0.72;
            Model {
                airframe,
                lag: ke_lag,
                thrust_coefficient_n_s2: 0.0,
                drag: Drag {
                    linear_drag_n_s_m: 0.3 * scale,
                    rotational_drag_n_m_s: 2.8e-3 * scale,
                    ..Drag::default()
                },
            }
        }
    }
}

/// One flight: rotors `failed` (0-based) lose `efficiency` at `FAULT_S`.
#[derive(Clone, Copy)]
struct Case {
    preset: &'static str,
    failed: &'static [usize],
    speed_m_s: f64,
    efficiency: f64,
    /// The controller is told `Some(delay)` after the failure; `None`: never.
    told_after_s: Option<f64>,
}

impl Case {
    fn total(preset: &'static str, failed: &'static [usize], speed_m_s: f64) -> Self {
        Case {
            preset,
            failed,
            speed_m_s,
            efficiency: 0.0,
            told_after_s: Some(0.0),
        }
    }
}

struct Outcome {
    trajectory: Trajectory,
    /// Largest altitude and horizontal errors from `FAULT_S + SETTLE_S` on, m.
    window_altitude_m: f64,
    window_horizontal_m: f64,
    /// Largest altitude and horizontal errors over the whole flight, m.
    worst_altitude_m: f64,
    worst_horizontal_m: f64,
    /// Mean |r| over the window, rad/s.
    spin_rad_s: f64,
    ground_contact: bool,
}

impl Outcome {
    fn holds(&self) -> bool {
        self.trajectory.divergence.is_none()
            && !self.ground_contact
            && self.window_altitude_m <= 1.0
            && self.window_horizontal_m <= 3.0
    }
}

/// Flies `case` with the vehicle `model` and the controller built from `airframe` (the nominal one
/// it designs on) and `gains`; `wrap` may hide the controller behind another.
fn fly_full(
    case: &Case,
    model: Model,
    nominal: &Airframe,
    gains: IndiGains,
    wrap: impl FnOnce(IndiController) -> Box<dyn Controller>,
    start_offset_m: [f64; 3],
) -> Outcome {
    let Model {
        airframe,
        lag,
        thrust_coefficient_n_s2,
        drag,
    } = model;
    let vehicle = Vehicle::new(&airframe, drag).unwrap();
    let mut actuators =
        Actuators::FixedPitch(FixedPitch::new(&airframe, lag, thrust_coefficient_n_s2).unwrap());
    let failures: Vec<DetectedFailure> = match case.told_after_s {
        Some(delay) => case
            .failed
            .iter()
            .map(|&rotor| DetectedFailure {
                rotor,
                time_s: FAULT_S + delay,
            })
            .collect(),
        None => vec![],
    };
    let start = [0.0, 0.0, -ALTITUDE_M];
    let setpoint = Setpoint {
        time_s: 0.0,
        position_m: start,
        velocity_m_s: [case.speed_m_s, 0.0, 0.0],
    };
    let controller = IndiController::new(nominal, gains, failures, vec![setpoint], DT).unwrap();
    // The rotors start at the true vehicle's hover.
    let weight_ratio = airframe.mass_kg() / nominal.mass_kg();
    let hover: Vec<f64> = controller.failure_modes()[0]
        .hover_thrust_n
        .iter()
        .map(|t| t * weight_ratio)
        .collect();
    actuators.settle(&hover).unwrap();
    let mut controller = wrap(controller);
    let faults: Vec<RotorFault> = case
        .failed
        .iter()
        .map(|&rotor| RotorFault {
            rotor,
            time_s: FAULT_S,
            efficiency: case.efficiency,
        })
        .collect();
    let x0 = RigidBodyState {
        position_m: Vector3::from(start) + Vector3::from(start_offset_m),
        velocity_m_s: Vector3::new(case.speed_m_s, 0.0, 0.0),
        ..RigidBodyState::at_rest()
    };
    let mut config = SimulationConfig::new(DT, 4, DURATION_S);
    // Ground at z = 0: a loss of the starting altitude is ground contact.
    config.limits.max_altitude_loss_m = ALTITUDE_M;
    let m = airframe.rotor_count();
    let trajectory = simulate(
        &vehicle,
        actuators,
        controller.as_mut(),
        &vec![1.0; m],
        &faults,
        x0,
        &config,
    )
    .unwrap();
    let mut out = Outcome {
        window_altitude_m: 0.0,
        window_horizontal_m: 0.0,
        worst_altitude_m: 0.0,
        worst_horizontal_m: 0.0,
        spin_rad_s: 0.0,
        ground_contact: false,
        trajectory,
    };
    let mut spin = (0.0, 0usize);
    for (t, s) in out.trajectory.t_s.iter().zip(&out.trajectory.states) {
        let reference = Vector3::new(case.speed_m_s * t, 0.0, -ALTITUDE_M);
        let e = s.position_m - reference;
        let (alt, hor) = (e.z.abs(), e.xy().norm());
        out.worst_altitude_m = out.worst_altitude_m.max(alt);
        out.worst_horizontal_m = out.worst_horizontal_m.max(hor);
        out.ground_contact |= s.position_m.z >= 0.0;
        if *t >= FAULT_S + SETTLE_S {
            out.window_altitude_m = out.window_altitude_m.max(alt);
            out.window_horizontal_m = out.window_horizontal_m.max(hor);
            spin = (spin.0 + s.omega_rad_s.z.abs(), spin.1 + 1);
        }
    }
    out.spin_rad_s = spin.0 / spin.1.max(1) as f64;
    out
}

fn fly_with(case: &Case, gains: IndiGains) -> Outcome {
    let model = model(case.preset);
    let nominal = model.airframe.clone();
    fly_full(case, model, &nominal, gains, |c| Box::new(c), [0.0; 3])
}

fn fly(case: &Case) -> Outcome {
    fly_with(case, IndiGains::default())
}

fn describe(case: &Case, o: &Outcome) -> String {
    let lost = o
        .trajectory
        .divergence
        .map(|d| format!(", lost at {:.2} s ({})", d.time_s, d.kind.name()))
        .unwrap_or_default();
    let failed: Vec<String> = case.failed.iter().map(|r| (r + 1).to_string()).collect();
    format!(
        "| {} | {} | {:.0} m/s | {} | {:.1} | {:.3} / {:.3} | {:.3} / {:.3}{lost} |",
        case.preset,
        failed.join(", "),
        case.speed_m_s,
        if o.holds() { "holds" } else { "does not hold" },
        o.spin_rad_s,
        o.window_altitude_m,
        o.window_horizontal_m,
        o.worst_altitude_m,
        o.worst_horizontal_m,
    )
}

/// The flights of issue 30 (rotor numbers 1-based in the table), flown in parallel: every case
/// but Lanzon's holds. Lanzon's quadrotor is lost, and how (the measurement the report gives):
/// without rotor 2, rotor 4 (opposite) drops to 0 N at once and the roll torque can no longer turn
/// negative, while the spin (2.7 rad/s at most with `k_r = m g d / 2.7`) is too slow to bring the
/// missing direction round: past 90 degrees of tilt 0.7 s after the failure. Without rotors 2 and
/// 4, `J_z < J_xy` (`a = +0.80`) makes the zero dynamics unstable whatever the output angle: lost
/// 10.8 s after the failure in hover.
#[test]
fn indi_holds_every_vehicle_and_failure_but_lanzons_at_hover_and_at_2_m_s() {
    use rayon::prelude::*;
    let vehicles: [(&str, &[usize]); 11] = [
        ("ke-quadcopter", &[0]),
        ("ke-quadcopter", &[0, 2]),
        ("lanzon-quadrotor", &[1]),
        ("lanzon-quadrotor", &[1, 3]),
        ("hexa-pnpnpn", &[0]),
        ("hexa-ppnnpn", &[0]),
        ("hexa-ppnnpn", &[4]),
        ("octo-x", &[0]),
        ("octo-x", &[0, 4]),
        ("octo-x", &[0, 1]),
        ("ke-quadcopter", &[]),
    ];
    let cases: Vec<Case> = [0.0, 2.0]
        .iter()
        .flat_map(|&speed| vehicles.iter().map(move |&(p, f)| Case::total(p, f, speed)))
        .collect();
    let outcomes: Vec<Outcome> = cases.par_iter().map(fly).collect();
    println!("| vehicle | failed | speed | verdict | spin rad/s | window alt / hor m | worst alt / hor m |");
    let mut misses = Vec::new();
    for (case, o) in cases.iter().zip(&outcomes) {
        let line = describe(case, o);
        println!("{line}");
        if o.holds() == (case.preset == "lanzon-quadrotor") {
            misses.push(line);
        }
    }
    assert!(misses.is_empty(), "{misses:#?}");
    let lost = |failed: &[usize]| {
        let k = cases
            .iter()
            .position(|c| {
                c.preset == "lanzon-quadrotor" && c.failed == failed && c.speed_m_s == 0.0
            })
            .unwrap();
        let d = outcomes[k].trajectory.divergence.unwrap();
        assert_eq!(d.kind.name(), "tilt");
        d.time_s - FAULT_S
    };
    assert!((lost(&[1]) - 0.69).abs() < 0.05, "{}", lost(&[1]));
    assert!(lost(&[1, 3]) > 5.0, "{}", lost(&[1, 3]));
}

/// The coupling decision (module docs, "Filter and inertia coupling"): plain INDI, the inertia
/// coupling left to the filtered gyro, loses ke-quadcopter at 2 m/s after rotors 1 and 3 fail; taken
/// from the model at the current rate, the same flight holds.
#[test]
fn the_modelled_inertia_coupling_holds_the_double_failure_in_forward_flight() {
    let case = Case::total("ke-quadcopter", &[0, 2], 2.0);
    let plain = fly_with(
        &case,
        IndiGains {
            model_coupling: false,
            ..IndiGains::default()
        },
    );
    // Measured: 2.36 m altitude error in the window (the oscillation grows with the spin until
    // the rotors saturate).
    assert!(
        !plain.holds() && plain.window_altitude_m > 2.0,
        "{}",
        describe(&case, &plain)
    );
    let ours = fly(&case);
    assert!(
        ours.holds() && ours.window_horizontal_m < 0.5,
        "{}",
        describe(&case, &ours)
    );
}

/// The output redefinition's side from the measured inertia coupling (module docs, "One torque
/// axis left"): ke-quadcopter's nominal `J_z / J_xy = 1.86` gives `1 + a = +0.14`; a vehicle 25 %
/// heavier in yaw than the controller's model (`J_z / J_xy = 2.32`, `1 + a = -0.32`, inside the
/// deciding campaign's +/-20 % per axis) has the zero dynamics unstable on the nominal side. With
/// the side fixed from the nominal inertia it is lost: measured, a nutation growing from the
/// failure into bang-bang rotor commands at about 20 rad/s of spin and circling (the 49 total
/// losses of the campaign's ke-quadcopter two-opposing cell, all with `J_z / J_xy > 2.08`; here
/// 15.9 m altitude error in the window). With the side chosen from the estimate it holds (6 mm),
/// and the nominal vehicle still holds.
#[test]
fn the_output_side_follows_the_measured_inertia_when_j_z_exceeds_twice_j_xy() {
    let case = Case::total("ke-quadcopter", &[0, 2], 0.0);
    let nominal = rfcore::fixtures::preset("ke-quadcopter");
    let [jx, jy, jz] = nominal.inertia_kg_m2();
    let text = nominal.to_toml_string();
    let line = format!("inertia_kg_m2 = [{jx:?}, {jy:?}, {jz:?}]");
    assert!(text.contains(&line), "{text}");
    let heavy = text.replace(
        &line,
        &format!("inertia_kg_m2 = [{jx:?}, {jy:?}, {:?}]", 1.25 * jz),
    );
    let mut heavy_model = model("ke-quadcopter");
    heavy_model.airframe = Airframe::from_toml_str(&heavy, "test").unwrap();
    // Started 0.6 m off the set point: the tilt it takes excites the zero dynamics (a perfectly
    // symmetric start never does).
    let offset = [0.5, 0.3, 0.0];
    for truth in [heavy_model, model("ke-quadcopter")] {
        let o = fly_full(
            &case,
            truth,
            &nominal,
            IndiGains::default(),
            |c| Box::new(c),
            offset,
        );
        assert!(
            o.holds() && o.window_horizontal_m < 0.1,
            "{}",
            describe(&case, &o)
        );
    }
}

/// The incremental base (module docs): rotor 1 of ke-quadcopter at 40 %, the controller not told.
/// Without the mismatch correction the loop settles with a standing increment and 6 m off station.
#[test]
fn the_mismatch_correction_removes_the_offset_of_an_undetected_partial_loss() {
    let case = Case {
        efficiency: 0.4,
        told_after_s: None,
        ..Case::total("ke-quadcopter", &[0], 0.0)
    };
    let without = fly_with(
        &case,
        IndiGains {
            mismatch_time_constant_s: f64::INFINITY,
            ..IndiGains::default()
        },
    );
    assert!(
        without.window_horizontal_m > 5.0,
        "{}",
        describe(&case, &without)
    );
    let with = fly(&case);
    assert!(
        with.holds() && with.window_horizontal_m < 0.01,
        "{}",
        describe(&case, &with)
    );
}

/// A partial loss the controller is not told of, on a rotor whose loss takes the yaw authority
/// (hexa-ppnnpn, rotor 5 at 5 %): holding yaw (`YawMode::Hold`, the law before the saturation
/// priorities) saturates the rotors and gives up thrust, and the vehicle sinks; with the
/// priorities (`YawMode::Auto`: thrust and attitude first once the rotors saturate) it spins and holds.
#[test]
fn saturated_rotors_give_up_yaw_before_thrust_on_an_undetected_partial_loss() {
    let case = Case {
        efficiency: 0.05,
        told_after_s: None,
        ..Case::total("hexa-ppnnpn", &[4], 0.0)
    };
    let held_yaw = fly_with(
        &case,
        IndiGains {
            yaw: YawMode::Hold,
            ..IndiGains::default()
        },
    );
    assert!(!held_yaw.holds(), "{}", describe(&case, &held_yaw));
    let prioritised = fly(&case);
    assert!(
        prioritised.holds() && prioritised.spin_rad_s > 5.0,
        "{}",
        describe(&case, &prioritised)
    );
}

/// The controller behind the state alone (no gyro, accelerometer or rotor samples).
struct StateOnly(IndiController);

impl Controller for StateOnly {
    fn command_count(&self) -> usize {
        self.0.command_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.0.command(t_s, measured, out)
    }
    fn reset(&mut self) {
        self.0.reset()
    }
}

/// A vehicle 20 % heavier than the controller's model. With the accelerometer, INDI's thrust row
/// settles at the altitude (the increment vanishes only where the measured acceleration is the
/// commanded one); with the state alone the row is dynamic inversion on the model mass, which
/// settles `g (m / m_model - 1) / k_p,z = 0.196 m` low (closed form).
#[test]
fn the_accelerometer_removes_the_altitude_offset_of_a_mass_error() {
    let case = Case::total("ke-quadcopter", &[], 0.0);
    let heavy = || {
        let text = rfcore::fixtures::preset_text("ke-quadcopter.toml")
            .replace("mass_kg = 0.720", "mass_kg = 0.864");
        Model {
            airframe: Airframe::from_toml_str(&text, "heavy").unwrap(),
            ..model("ke-quadcopter")
        }
    };
    let nominal = rfcore::fixtures::preset("ke-quadcopter");
    let gains = IndiGains::default();
    let with = fly_full(&case, heavy(), &nominal, gains, |c| Box::new(c), [0.0; 3]);
    let offset = |o: &Outcome| o.trajectory.states.last().unwrap().position_m.z + ALTITUDE_M;

    assert!(offset(&with).abs() < 1e-3, "{}", offset(&with));
    let without = fly_full(
        &case,
        heavy(),
        &nominal,
        gains,
        |c| Box::new(StateOnly(c)),
        [0.0; 3],
    );
    let expected = nominal.gravity_m_s2() * (0.864 / 0.720 - 1.0) / gains.k_p_z;
    assert!(
        (offset(&without) - expected).abs() < 1e-3,
        "{} vs {expected}",
        offset(&without)
    );
}

/// Starts a metre off the setpoint in every direction (the bench's random starts): the vehicle
/// comes back and, after rotors 1 and 3 fail at 3 s, holds (a metre above, the uncapped vertical
/// demand of 10 m/s^2 would turn the thrust over: `max_vertical_accel_m_s2`).
#[test]
fn starts_a_metre_off_the_setpoint_come_back_and_hold() {
    use rayon::prelude::*;
    let offsets: Vec<[f64; 3]> = (0..8)
        .map(|k| {
            [
                (k & 1) as f64 * 2.0 - 1.0,
                (k >> 1 & 1) as f64 * 2.0 - 1.0,
                (k >> 2 & 1) as f64 * 2.0 - 1.0,
            ]
        })
        .collect();
    offsets.par_iter().for_each(|d| {
        let case = Case::total("ke-quadcopter", &[0, 2], 0.0);
        let model = model(case.preset);
        let nominal = model.airframe.clone();
        let o = fly_full(
            &case,
            model,
            &nominal,
            IndiGains::default(),
            |c| Box::new(c),
            *d,
        );
        assert!(o.holds(), "start off by {d:?}: {}", describe(&case, &o));
    });
}

/// Told 0.2 s late, the controller still holds every case it holds when told at once.
#[test]
fn a_detection_delay_of_200_ms_is_survived() {
    use rayon::prelude::*;
    let cases = [
        ("ke-quadcopter", &[0][..]),
        ("ke-quadcopter", &[0, 2][..]),
        ("hexa-ppnnpn", &[4][..]),
        ("octo-x", &[0, 1][..]),
    ]
    .map(|(preset, failed)| Case {
        told_after_s: Some(0.2),
        ..Case::total(preset, failed, 2.0)
    });
    cases.par_iter().for_each(|case| {
        let o = fly(case);
        assert!(o.holds(), "{}", describe(case, &o));
    });
}

/// Records what each step of the law computed.
struct Recording {
    inner: IndiController,
    steps: Vec<IndiStep>,
}

impl Controller for Recording {
    fn command_count(&self) -> usize {
        self.inner.command_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.command_with(t_s, &ControllerInput::state_only(measured), out)
    }
    fn command_with(
        &mut self,
        t_s: f64,
        input: &ControllerInput<'_>,
        out: &mut [f64],
    ) -> Result<()> {
        self.steps.push(self.inner.step(t_s, input, out)?);
        Ok(())
    }
    fn reads_samples(&self) -> bool {
        true
    }
    fn reset(&mut self) {
        self.inner.reset();
        self.steps.clear();
    }
}

/// The angular acceleration the simulator's vehicle has at `state` with the rotors producing
/// `thrust_n` (the rigid body's own derivative: independent of the controller's model).
fn simulator_angular_acceleration(
    vehicle: &Vehicle,
    state: &RigidBodyState,
    thrust_n: &[f64],
    yaw_ratio: &[f64],
) -> Vector3<f64> {
    let outputs: Vec<_> = thrust_n
        .iter()
        .zip(yaw_ratio)
        .map(|(&t, &k)| rfcore::flight::actuator::RotorOutput {
            thrust_n: t,
            reaction_torque_nm: k * t,
            spin_rad_s: 0.0,
        })
        .collect();
    let totals: RotorTotals = vehicle.rotor_totals(&outputs);
    let wrench = vehicle.wrench_from(state, &totals, &Vector3::zeros());
    vehicle.body().derivative(state, &wrench).omega
}

/// The incremental law's one-step prediction, `omega'_f + J^-1 M_tau dT`, against the simulator's
/// angular acceleration at the same state once the rotors produce the commands (instant rotors:
/// they do from that step on). From a settled hover (a setpoint 1 m aside appears at 1 s) the two
/// agree to rounding (measured 6e-14 of 268 rad/s^2). Through the first second of the spin-up of
/// ke-quadcopter without rotors 1 and 3 they differ by the filter's lag on the torques the law does
/// not model (drag): measured 0.6 % of the RMS acceleration; 2 % allowed.
#[test]
fn the_one_step_prediction_of_the_angular_acceleration_matches_the_simulator() {
    // From a settled hover, one step; after the failure, 1 s from when the filters have passed
    // the loss itself (0.15 s, about 4 / (zeta w_n)).
    for (failed, since_s, tolerance) in [(&[][..], 1.0, 1e-9), (&[0, 2][..], FAULT_S + 0.15, 0.02)]
    {
        let Model { airframe, drag, .. } = model("ke-quadcopter");
        let vehicle = Vehicle::new(&airframe, drag).unwrap();
        let yaw_ratio: Vec<f64> = (0..4)
            .map(|i| airframe.nominal_effectiveness_matrix()[(3, i)])
            .collect();
        let mut actuators =
            Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap());
        let failures = failed
            .iter()
            .map(|&rotor| DetectedFailure {
                rotor,
                time_s: FAULT_S,
            })
            .collect();
        let setpoints = vec![
            Setpoint::hold(0.0, [0.0, 0.0, -ALTITUDE_M]),
            Setpoint::hold(1.0, [0.0, 1.0, -ALTITUDE_M]),
        ];
        let inner =
            IndiController::new(&airframe, IndiGains::default(), failures, setpoints, DT).unwrap();
        actuators
            .settle(&inner.failure_modes()[0].hover_thrust_n)
            .unwrap();
        let mut recording = Recording {
            inner,
            steps: vec![],
        };
        let faults: Vec<RotorFault> = failed
            .iter()
            .map(|&rotor| RotorFault {
                rotor,
                time_s: FAULT_S,
                efficiency: 0.0,
            })
            .collect();
        let x0 = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, -ALTITUDE_M),
            ..RigidBodyState::at_rest()
        };
        let config = SimulationConfig::new(DT, 4, since_s + 1.0);
        let tr = simulate(
            &vehicle,
            actuators,
            &mut recording,
            &[1.0; 4],
            &faults,
            x0,
            &config,
        )
        .unwrap();
        assert!(tr.divergence.is_none());
        let (mut error2, mut scale2, mut n) = (0.0, 0.0, 0);
        for k in 0..tr.t_s.len() - 1 {
            if tr.t_s[k] < since_s || (failed.is_empty() && k > (since_s / DT).round() as usize) {
                continue;
            }
            // Instant rotors produce the commands from step k on (failed ones: 0, as commanded).
            let commanded = &tr.rotor_command[k * 4..(k + 1) * 4];
            let actual =
                simulator_angular_acceleration(&vehicle, &tr.states[k], commanded, &yaw_ratio);
            let predicted = recording.steps[k].angular_acceleration_predicted;
            error2 += (predicted - actual).norm_squared();
            scale2 += actual.norm_squared();
            n += 1;
        }
        let (error, scale) = ((error2 / n as f64).sqrt(), (scale2 / n as f64).sqrt());
        println!("failed {failed:?}: {n} steps, prediction error {error:.3e} rad/s^2 RMS against {scale:.3e}");
        assert!(scale > 1.0, "the test needs a commanded change: {scale}");
        assert!(error <= tolerance * scale, "{error} vs {scale}");
    }
}
