//! INDI fault-tolerant control (`rfcore::control::indi`) in closed loop with the simulator: the
//! one-step prediction of the angular acceleration against the simulator's, and flights through
//! rotor failures with the verdict taken over the whole window.

use nalgebra::Vector3;

use rfcore::control::indi::{DetectedFailure, IndiController, IndiGains, Setpoint};
use rfcore::control::Controller;
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::simulation::{simulate, RotorFault, SimulationConfig, Trajectory};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::RigidBodyState;
use rfcore::Airframe;

/// The vehicle model a preset flies in these tests. Ke's and Lanzon's are their presets' (ke-hil;
/// `LanzonVehicle`'s defaults); the hexa- and octocopters (Du's Table I, no aerodynamics given)
/// get Ke's rotor lag and drags scaled to their mass, stated here.
struct Model {
    airframe: Airframe,
    time_constant_s: f64,
    rate_limit_n_s: f64,
    thrust_coefficient_n_s2: f64,
    drag: Drag,
}

fn model(name: &str) -> Model {
    let airframe = rfcore::fixtures::preset(name);
    match name {
        "ke-quadcopter" => Model {
            airframe,
            time_constant_s: 0.025,
            rate_limit_n_s: f64::INFINITY,
            thrust_coefficient_n_s2: 0.0,
            drag: Drag {
                linear_drag_n_s_m: 0.3,
                rotational_drag_n_m_s: 2.8e-3,
                ..Drag::default()
            },
        },
        "lanzon-quadrotor" => {
            let (m, g, d) = (
                airframe.mass_kg(),
                airframe.gravity_m_s2(),
                airframe.drag_torque_ratio_m(),
            );
            Model {
                airframe,
                time_constant_s: 0.0,
                rate_limit_n_s: 50.0,
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
                time_constant_s: 0.025,
                rate_limit_n_s: f64::INFINITY,
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

/// One flight: `failed` rotors (0-based) fail at `fault_s` and the controller is told at once.
struct Case {
    preset: &'static str,
    failed: &'static [usize],
    speed_m_s: f64,
}

const FAULT_S: f64 = 3.0;
const DURATION_S: f64 = 25.0;
/// The verdict window starts this long after the failure.
const SETTLE_S: f64 = 5.0;
const ALTITUDE_M: f64 = 10.0;

struct Outcome {
    trajectory: Trajectory,
    /// Largest altitude and horizontal errors from `FAULT_S + SETTLE_S` on, m.
    window_altitude_m: f64,
    window_horizontal_m: f64,
    /// Largest altitude loss and horizontal error over the whole flight, m.
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

fn fly_with(case: &Case, gains: IndiGains) -> Outcome {
    let Model {
        airframe,
        time_constant_s,
        rate_limit_n_s,
        thrust_coefficient_n_s2,
        drag,
    } = model(case.preset);
    let vehicle = Vehicle::new(&airframe, drag).unwrap();
    let lag = Lag {
        time_constant_s,
        rate_limit_per_s: rate_limit_n_s,
    };
    let mut actuators =
        Actuators::FixedPitch(FixedPitch::new(&airframe, lag, thrust_coefficient_n_s2).unwrap());
    let partial: Option<f64> = std::env::var("PARTIAL").ok().map(|v| v.parse().unwrap());
    let failures: Vec<DetectedFailure> = case
        .failed
        .iter()
        .filter(|_| partial.is_none())
        .map(|&rotor| DetectedFailure {
            rotor,
            time_s: FAULT_S
                + std::env::var("DELAY")
                    .map(|d| d.parse::<f64>().unwrap())
                    .unwrap_or(0.0),
        })
        .collect();
    let start = [0.0, 0.0, -ALTITUDE_M];
    let setpoint = Setpoint {
        time_s: 0.0,
        position_m: start,
        velocity_m_s: [case.speed_m_s, 0.0, 0.0],
    };
    let dt = 1.0 / 400.0;
    let mut controller =
        IndiController::new(&airframe, gains, failures, vec![setpoint], dt).unwrap();
    let hover = controller.failure_modes()[0].hover_thrust_n.clone();
    actuators.settle(&hover).unwrap();
    let faults: Vec<RotorFault> = case
        .failed
        .iter()
        .map(|&rotor| RotorFault {
            rotor,
            time_s: FAULT_S,
            efficiency: partial.unwrap_or(0.0),
        })
        .collect();
    let x0 = RigidBodyState {
        position_m: Vector3::from(start),
        velocity_m_s: Vector3::new(case.speed_m_s, 0.0, 0.0),
        ..RigidBodyState::at_rest()
    };
    let mut config = SimulationConfig::new(dt, 4, DURATION_S);
    // Ground at z = 0: a loss of more than the starting altitude is ground contact.
    config.limits.max_altitude_loss_m = ALTITUDE_M;
    let trajectory = simulate(
        &vehicle,
        actuators,
        &mut controller,
        &[1.0; 8][..airframe.rotor_count()],
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
    out.ground_contact |= out
        .trajectory
        .divergence
        .is_some_and(|d| d.state.position_m.z >= 0.0);
    out.spin_rad_s = spin.0 / spin.1.max(1) as f64;
    out
}

fn fly(case: &Case) -> Outcome {
    fly_with(case, IndiGains::default())
}

fn describe(case: &Case, o: &Outcome) -> String {
    let lost = o
        .trajectory
        .divergence
        .map(|d| format!(" lost at {:.2} s ({})", d.time_s, d.reason.name()))
        .unwrap_or_default();
    let failed: Vec<String> = case.failed.iter().map(|r| (r + 1).to_string()).collect();
    format!(
        "{:17} failed [{}] at {:.0} m/s: {} | window alt {:.3} m hor {:.3} m | worst alt {:.3} m hor {:.3} m | spin {:.1} rad/s{lost}",
        case.preset,
        failed.join(","),
        case.speed_m_s,
        if o.holds() { "holds" } else { "DOES NOT HOLD" },
        o.window_altitude_m,
        o.window_horizontal_m,
        o.worst_altitude_m,
        o.worst_horizontal_m,
        o.spin_rad_s,
    )
}

#[test]
fn explore() {
    let cases: [(&str, &[usize]); 11] = [
        ("ke-quadcopter", &[]),
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
    ];
    let mut gains = IndiGains::default();
    if let Ok(t) = std::env::var("DELTA") {
        gains.output_angle_rad = t.parse::<f64>().unwrap().to_radians();
    }
    if let Ok(t) = std::env::var("GYW") {
        gains.given_up_yaw_weight = t.parse().unwrap();
    }
    for speed_m_s in [0.0, 2.0] {
        for (preset, failed) in cases {
            let case = Case {
                preset,
                failed,
                speed_m_s,
            };
            let o = fly_with(&case, gains);
            println!("{}", describe(&case, &o));
        }
    }
}

#[allow(dead_code)]
fn unused(_: &dyn Controller) {}

#[test]
fn debug_case() {
    let preset = std::env::var("CASE").unwrap_or("lanzon-quadrotor".into());
    let failed: Vec<usize> = std::env::var("FAILED")
        .unwrap_or("1".into())
        .split(',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect();
    let speed: f64 = std::env::var("SPEED")
        .unwrap_or("0".into())
        .parse()
        .unwrap();
    let failed: &'static [usize] = Box::leak(failed.into_boxed_slice());
    let preset: &'static str = Box::leak(preset.into_boxed_str());
    let case = Case {
        preset,
        failed,
        speed_m_s: speed,
    };
    let mut gains = IndiGains::default();
    if let Ok(t) = std::env::var("TILT") {
        gains.primary_axis_tilt = t.parse().unwrap();
    }
    if let Ok(t) = std::env::var("DELTA") {
        gains.output_angle_rad = t.parse::<f64>().unwrap().to_radians();
    }
    if let Ok(t) = std::env::var("WYAW") {
        gains.weights[3] = t.parse().unwrap();
    }
    if let Ok(t) = std::env::var("WATT") {
        gains.weights[1] = t.parse().unwrap();
        gains.weights[2] = gains.weights[1];
    }
    if let Ok(t) = std::env::var("KP") {
        gains.k_att_p = t.parse().unwrap();
    }
    if let Ok(t) = std::env::var("KD") {
        gains.k_att_d = t.parse().unwrap();
    }
    if let Ok(t) = std::env::var("WF") {
        gains.filter_frequency_rad_s = t.parse().unwrap();
    }
    let o = fly_with(&case, gains);
    println!("{}", describe(&case, &o));
    let tr = &o.trajectory;
    let m = tr.thrust_n.len() / tr.t_s.len();
    for (k, (t, s)) in tr.t_s.iter().zip(&tr.states).enumerate() {
        if k % 20 != 0 && k + 1 != tr.t_s.len() {
            continue;
        }
        if *t < FAULT_S - 0.1 {
            continue;
        }
        let n3 = s.primary_axis();
        println!("t {:.3} p [{:.2} {:.2} {:.2}] v [{:.2} {:.2} {:.2}] n3 [{:.3} {:.3} {:.3}] w [{:.2} {:.2} {:.2}] T {:?} C {:?}", t, s.position_m.x, s.position_m.y, s.position_m.z, s.velocity_m_s.x, s.velocity_m_s.y, s.velocity_m_s.z, n3.x, n3.y, n3.z, s.omega_rad_s.x, s.omega_rad_s.y, s.omega_rad_s.z, &tr.thrust_n[k*m..(k+1)*m].iter().map(|v| (v*100.0).round()/100.0).collect::<Vec<_>>(), &tr.commands[k*m..(k+1)*m].iter().map(|v| (v*100.0).round()/100.0).collect::<Vec<_>>());
        if *t > 6.0 && std::env::var("LONG").is_err() {
            break;
        }
    }
}

#[test]
fn timing_probe() {
    let case = Case {
        preset: "octo-x",
        failed: &[0],
        speed_m_s: 0.0,
    };
    let t0 = std::time::Instant::now();
    let n = 10;
    for _ in 0..n {
        let _ = fly(&case);
    }
    let el = t0.elapsed().as_secs_f64();
    println!("{:.3} us/step", el / (n as f64 * DURATION_S * 400.0) * 1e6);
    let airframe = rfcore::fixtures::preset("octo-x");
    let t0 = std::time::Instant::now();
    for _ in 0..n {
        let _ = IndiController::new(
            &airframe,
            IndiGains::default(),
            vec![DetectedFailure {
                rotor: 0,
                time_s: 3.0,
            }],
            vec![Setpoint::hold(0.0, [0.0, 0.0, -10.0])],
            0.0025,
        )
        .unwrap();
    }
    println!(
        "construction {:.3} ms",
        t0.elapsed().as_secs_f64() / n as f64 * 1e3
    );
}
