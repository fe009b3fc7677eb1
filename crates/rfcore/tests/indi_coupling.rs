//! INDI's online inertia-coupling estimate with one torque axis left (`control::indi` module
//! docs, "One torque axis left"): ke-quadcopter (Ke's 25 ms rotor lag and drags) loses two
//! opposing rotors at 3 s, the controller told at once and designed on the nominal inertia
//! `(0.0056, 0.0056, 0.0104)` kg m^2 (`1 + a = +0.14`), the vehicle flown with another one.
//!
//! - The estimate converges to the true vehicle's coefficients `k_x = (J_y - J_z) / J_x`,
//!   `k_y = (J_z - J_x) / J_y` (an independent computation from the true inertia) and the output
//!   side follows the true `1 + a`.
//! - Near `a = -1` (`J_z = 2 J_xy`, where neither side damps the zero dynamics) the side changes
//!   only when the estimate lies beyond the hysteresis margin: it does not chatter with the
//!   estimate's sign.
//! - On the motion-capture sensor suite (`Sensing::default()`: IMU noise and a gyro that clips at
//!   2000 deg/s, mocap fixes, the estimator) the drawn vehicle's flight holds (issue 30's verdict:
//!   within 1 m altitude and 3 m horizontal from 5 s after the failure, not diverged).

use nalgebra::Vector3;

use rfcore::control::indi::{
    CouplingEstimate, DetectedFailure, IndiController, IndiGains, Setpoint, OUTPUT_FLIP_MARGIN,
};
use rfcore::control::Controller;
use rfcore::flight::actuator::{Actuators, FixedPitch, Lag};
use rfcore::flight::simulation::{simulate, RotorFault, Sensing, SimulationConfig, Trajectory};
use rfcore::flight::vehicle::{Drag, Vehicle};
use rfcore::state::{ControllerInput, RigidBodyState};
use rfcore::{Airframe, Result};

const DT: f64 = 1.0 / 400.0;
const FAULT_S: f64 = 3.0;
const SETTLE_S: f64 = 5.0;
const ALTITUDE_M: f64 = 10.0;
/// Rotors 1 and 3 (0-based 0 and 2): two opposing rotors.
const FAILED: [usize; 2] = [0, 2];

/// ke-quadcopter with its inertia scaled per axis (the deciding campaign draws each within +/-20 %).
fn vehicle_with_inertia(scale: [f64; 3]) -> (Airframe, [f64; 3]) {
    let nominal = rfcore::fixtures::preset("ke-quadcopter");
    let j = nominal.inertia_kg_m2();
    let line = format!("inertia_kg_m2 = [{:?}, {:?}, {:?}]", j[0], j[1], j[2]);
    let text = nominal.to_toml_string();
    assert!(text.contains(&line), "{text}");
    let true_j = [0, 1, 2].map(|i| j[i] * scale[i]);
    let drawn = text.replace(
        &line,
        &format!(
            "inertia_kg_m2 = [{:?}, {:?}, {:?}]",
            true_j[0], true_j[1], true_j[2]
        ),
    );
    (Airframe::from_toml_str(&drawn, "drawn").unwrap(), true_j)
}

/// `(k_x, k_y)` and `1 + a = 1 + (k_x - k_y) / 2` of an inertia (principal axes).
fn coupling_of(j: [f64; 3]) -> ([f64; 2], f64) {
    let k = [(j[1] - j[2]) / j[0], (j[2] - j[0]) / j[1]];
    (k, 1.0 + 0.5 * (k[0] - k[1]))
}

/// The controller, recording its coupling estimate after every step.
struct Recording {
    inner: IndiController,
    estimates: Vec<(f64, Option<CouplingEstimate>)>,
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
        self.inner.command_with(t_s, input, out)?;
        self.estimates.push((t_s, self.inner.coupling_estimate()));
        Ok(())
    }
    fn reads_samples(&self) -> bool {
        true
    }
    fn reset(&mut self) {
        self.inner.reset();
        self.estimates.clear();
    }
}

struct Flight {
    trajectory: Trajectory,
    estimates: Vec<(f64, Option<CouplingEstimate>)>,
    /// Largest altitude and horizontal errors from `FAULT_S + SETTLE_S` on, m.
    window_altitude_m: f64,
    window_horizontal_m: f64,
}

impl Flight {
    fn holds(&self) -> bool {
        self.trajectory.divergence.is_none()
            && self.window_altitude_m <= 1.0
            && self.window_horizontal_m <= 3.0
    }

    /// The estimates from `from_s` on (one torque axis left: all `Some`).
    fn estimates_from(&self, from_s: f64) -> Vec<CouplingEstimate> {
        self.estimates
            .iter()
            .filter(|(t, _)| *t >= from_s)
            .map(|(t, e)| e.unwrap_or_else(|| panic!("no estimate at {t} s")))
            .collect()
    }
}

/// `airframe` (the true vehicle) flown `duration_s` by INDI designed on the nominal
/// ke-quadcopter, started `offset_m` off the set point (a tilt that excites the nutation the
/// estimate learns from; a symmetric start never does).
fn fly(airframe: &Airframe, duration_s: f64, sensing: Option<Sensing>) -> Flight {
    let nominal = rfcore::fixtures::preset("ke-quadcopter");
    let drag = Drag {
        linear_drag_n_s_m: 0.3,
        rotational_drag_n_m_s: 2.8e-3,
        ..Drag::default()
    };
    let lag = Lag {
        time_constant_s: 0.025,
        rate_limit_per_s: f64::INFINITY,
    };
    let vehicle = Vehicle::new(airframe, drag).unwrap();
    let mut actuators = Actuators::FixedPitch(FixedPitch::new(airframe, lag, 0.0).unwrap());
    let failures = FAILED
        .iter()
        .map(|&rotor| DetectedFailure {
            rotor,
            time_s: FAULT_S,
        })
        .collect();
    let start = [0.0, 0.0, -ALTITUDE_M];
    let inner = IndiController::new(
        &nominal,
        IndiGains::default(),
        failures,
        vec![Setpoint::hold(0.0, start)],
        DT,
    )
    .unwrap();
    actuators
        .settle(&inner.failure_modes()[0].hover_thrust_n)
        .unwrap();
    let mut controller = Recording {
        inner,
        estimates: Vec::new(),
    };
    let faults: Vec<RotorFault> = FAILED
        .iter()
        .map(|&rotor| RotorFault {
            rotor,
            time_s: FAULT_S,
            efficiency: 0.0,
        })
        .collect();
    let x0 = RigidBodyState {
        position_m: Vector3::new(0.5, 0.3, -ALTITUDE_M),
        ..RigidBodyState::at_rest()
    };
    let mut config = SimulationConfig::new(DT, 4, duration_s);
    config.limits.max_altitude_loss_m = ALTITUDE_M;
    config.sensing = sensing;
    let trajectory = simulate(
        &vehicle,
        actuators,
        &mut controller,
        &[1.0; 4],
        &faults,
        x0,
        &config,
    )
    .unwrap();
    let (mut window_altitude_m, mut window_horizontal_m) = (0.0f64, 0.0f64);
    for (t, s) in trajectory.t_s.iter().zip(&trajectory.states) {
        if *t >= FAULT_S + SETTLE_S {
            let e = s.position_m - Vector3::from(start);
            window_altitude_m = window_altitude_m.max(e.z.abs());
            window_horizontal_m = window_horizontal_m.max(e.xy().norm());
        }
    }
    Flight {
        trajectory,
        estimates: controller.estimates,
        window_altitude_m,
        window_horizontal_m,
    }
}

/// A drawn vehicle 20 % heavier in yaw (and 5 % off in roll and pitch, opposite ways): true
/// `k = (-1.241, 1.218)`, `1 + a = -0.229`, the other side of 0 than the nominal `+0.143`.
const DRAWN_SCALE: [f64; 3] = [0.95, 1.05, 1.2];

/// The estimate learns from the nutation the failure excites. Measured (the larger relative
/// error of the two coefficients): 31 % (the nominal values) until 4 s, 6.6 % at 5 s, below
/// 6 % from 5.25 s to 11 s (least 3.0 % at 8.5 s). Once the nutation has died out the nominal
/// prior takes the estimate back over the forgetting time (13 % at 14 s); a vehicle
/// 25 % heavier in yaw alone returns to the nominal side at 15.4 s and learns the true side
/// again at 23 s as the nutation regrows, holding within 2 mm throughout: stated, not asserted.
#[test]
fn the_coupling_estimate_converges_to_the_drawn_vehicles_and_the_side_follows_it() {
    let (airframe, true_j) = vehicle_with_inertia(DRAWN_SCALE);
    let (k_true, one_plus_a_true) = coupling_of(true_j);
    let (k_nominal, one_plus_a_nominal) = coupling_of([0.0056, 0.0056, 0.0104]);
    assert!(one_plus_a_true < -0.2 && one_plus_a_nominal > 0.1);
    let f = fly(&airframe, 11.0, None);
    assert!(f.holds(), "{:?}", f.trajectory.divergence);
    // Before the failure there is no single-axis mode, so no estimate.
    assert!(f
        .estimates
        .iter()
        .filter(|(t, _)| *t < FAULT_S)
        .all(|(_, e)| e.is_none()));
    // From 2.25 s after the failure (a little over one forgetting time) to the end: each
    // coefficient within 6 % of the true one, and the side the true inertia's.
    let tolerance = 0.06;
    let settled = f.estimates_from(FAULT_S + 2.25);
    assert!(settled.len() > 2000);
    for e in &settled {
        for i in 0..2 {
            let off = (e.coefficients[i] - k_true[i]).abs() / k_true[i].abs();
            assert!(
                off < tolerance,
                "k[{i}] = {} vs true {} (nominal {})",
                e.coefficients[i],
                k_true[i],
                k_nominal[i]
            );
        }
        assert!(e.output_flipped && e.one_plus_a() < 0.0, "{e:?}");
    }
}

/// Near `a = -1` (true `1 + a = -0.006`, inside the +/-0.05 band) on motion capture the noisy
/// estimate's sign changes 22 times, as little as 7.5 ms apart (measured); the side changes 4
/// times, at least 0.96 s apart, each time with the estimate beyond the margin on the new side.
#[test]
fn near_a_equals_minus_one_the_side_does_not_chatter_with_the_estimate() {
    let (airframe, true_j) = vehicle_with_inertia([1.0, 1.0, 1.08]);
    let (_, one_plus_a_true) = coupling_of(true_j);
    assert!(one_plus_a_true.abs() < OUTPUT_FLIP_MARGIN);
    let f = fly(&airframe, 25.0, Some(Sensing::default()));
    assert!(f.holds(), "{:?}", f.trajectory.divergence);
    let after: Vec<(f64, CouplingEstimate)> = f
        .estimates
        .iter()
        .filter_map(|(t, e)| e.map(|e| (*t, e)))
        .collect();
    let (mut sign_changes, mut side_changes) = (0, Vec::new());
    for w in after.windows(2) {
        let ((_, before), (t, now)) = (&w[0], &w[1]);
        if (before.one_plus_a() < 0.0) != (now.one_plus_a() < 0.0) {
            sign_changes += 1;
        }
        if before.output_flipped != now.output_flipped {
            side_changes.push(*t);
            // Flipped is the side of 1 + a < 0 (the nominal inertia's is > 0).
            let beyond = if now.output_flipped {
                -now.one_plus_a()
            } else {
                now.one_plus_a()
            };
            assert!(
                beyond > OUTPUT_FLIP_MARGIN,
                "side changed at {t} s with 1 + a = {}",
                now.one_plus_a()
            );
        }
        if now.one_plus_a().abs() <= OUTPUT_FLIP_MARGIN {
            assert_eq!(now.output_flipped, before.output_flipped, "{t} s");
        }
    }
    // The premise: the estimate itself chatters about 0 here.
    assert!(sign_changes >= 10, "{sign_changes}");
    assert!(
        side_changes.len() * 4 <= sign_changes,
        "{side_changes:?} vs {sign_changes} sign changes"
    );
    assert!(
        side_changes.windows(2).all(|w| w[1] - w[0] > 0.5),
        "{side_changes:?}"
    );
}

/// The drawn vehicle on the motion-capture suite (IMU noise, the gyro clipped at 2000 deg/s
/// while it spins faster, mocap fixes, the estimator): measured within 1 mm altitude and 2 mm
/// horizontal from 5 s after the failure to 25 s.
#[test]
fn the_drawn_vehicle_holds_two_opposing_rotors_on_motion_capture() {
    let (airframe, _) = vehicle_with_inertia(DRAWN_SCALE);
    let f = fly(&airframe, 25.0, Some(Sensing::default()));
    assert!(
        f.holds() && f.window_horizontal_m < 0.1,
        "altitude {} m, horizontal {} m, {:?}",
        f.window_altitude_m,
        f.window_horizontal_m,
        f.trajectory.divergence
    );
    let sensing = f.trajectory.sensing.as_ref().unwrap();
    assert!(sensing.gyro_saturated_samples > 0);
}
