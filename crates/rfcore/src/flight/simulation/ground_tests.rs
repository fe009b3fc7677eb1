//! The ground (issue #28): contact ends a run as `crashed`, located in time, with the impact;
//! checked against free fall, where time and speed at the ground are known in closed form.

use nalgebra::{UnitQuaternion, Vector3};

use super::tests::{hover_schedule, instant_rotors, quad_x, still_air};
use super::*;
use crate::control::ZeroCommand;
use crate::error::Result;
use crate::state::RigidBodyState;

/// At rest (with `velocity_m_s`), at attitude `roll_rad`, `height_m` above a ground at
/// `ground_z_m`.
fn above(
    ground_z_m: f64,
    height_m: f64,
    velocity_m_s: Vector3<f64>,
    roll_rad: f64,
) -> RigidBodyState {
    RigidBodyState {
        position_m: Vector3::new(1.0, -2.0, ground_z_m - height_m),
        velocity_m_s,
        attitude: UnitQuaternion::from_euler_angles(roll_rad, 0.0, 0.0),
        ..RigidBodyState::at_rest()
    }
}

/// A run with the rotors off (free fall), control period 2.5 ms, one substep.
fn fall(x0: RigidBodyState, config: &SimulationConfig) -> Result<Trajectory> {
    let airframe = quad_x();
    simulate(
        &still_air(&airframe),
        instant_rotors(&airframe),
        &mut ZeroCommand { count: 4 },
        &[1.0; 4],
        &[],
        x0,
        config,
    )
}

#[test]
fn a_free_fall_hits_the_ground_at_the_analytic_time_and_speed() {
    // Free fall from h: contact at t = sqrt(2 h / g) at sqrt(2 g h) m/s down; a horizontal
    // velocity u adds to the speed (sqrt(u^2 + 2 g h)) and not to the vertical speed; with no
    // torque the attitude at impact is the start's. RK4 integrates the parabola exactly, so
    // the bisection leaves only rounding: 1e-9 on time and speed.
    let g = quad_x().gravity_m_s2();
    for (ground_z_m, height_m, u, roll_rad) in [
        (0.0, 10.0, 0.0, 0.0),
        (0.0, 1.0, 0.0, 0.0),
        (5.0, 10.0, 0.0, 0.0),
        (-30.0, 7.3, 5.0, 0.4),
    ] {
        let mut config = SimulationConfig::new(0.0025, 1, 5.0);
        config.ground_z_m = Some(ground_z_m);
        let x0 = above(
            ground_z_m,
            height_m,
            Vector3::new(3.0 / 5.0 * u, 4.0 / 5.0 * u, 0.0),
            roll_rad,
        );
        let run = fall(x0, &config).unwrap();
        let event = run.divergence.expect("a free fall reaches the ground");
        assert_eq!(event.kind, DivergenceKind::Crashed);
        assert_eq!(event.kind.name(), "crashed");
        let time = (2.0 * height_m / g).sqrt();
        let vertical = (2.0 * g * height_m).sqrt();
        let impact = event.impact().unwrap();
        let case = format!("ground {ground_z_m}, h {height_m}, u {u}");
        assert!(
            (event.time_s - time).abs() < 1e-9,
            "{case}: t {} vs {time}",
            event.time_s
        );
        assert!(
            (impact.vertical_speed_m_s - vertical).abs() < 1e-9,
            "{case}: {impact:?}"
        );
        assert!(
            (impact.speed_m_s - vertical.hypot(u)).abs() < 1e-9,
            "{case}: {impact:?}"
        );
        assert!(
            (impact.tilt_rad - roll_rad).abs() < 1e-12,
            "{case}: {impact:?}"
        );
        assert!(
            event.state.attitude.angle_to(&x0.attitude) < 1e-12,
            "{case}"
        );
        // At the plane, just past it (the bisection returns the first state beyond it).
        let depth = event.state.position_m.z - ground_z_m;
        assert!((0.0..1e-9).contains(&depth), "{case}: {depth}");
        // The recorded run ends at the contact: its last row is the event, with NaN commands.
        assert_eq!(*run.t_s.last().unwrap(), event.time_s);
        assert_eq!(*run.states.last().unwrap(), event.state);
        assert!(run.rotor_command[run.rotor_command.len() - 4..]
            .iter()
            .all(|c| c.is_nan()));
        assert!(run.t_s[run.t_s.len() - 2] < event.time_s);
    }
}

#[test]
fn without_a_ground_the_fall_goes_through_the_plane() {
    let mut config = SimulationConfig::new(0.0025, 1, 3.0);
    config.ground_z_m = None;
    let run = fall(above(0.0, 10.0, Vector3::zeros(), 0.0), &config).unwrap();
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    assert_eq!(*run.t_s.last().unwrap(), 3.0);
    let g = quad_x().gravity_m_s2();
    let end = run.states.last().unwrap();
    assert!(
        (end.position_m.z - (0.5 * g * 9.0 - 10.0)).abs() < 1e-9,
        "{}",
        end.position_m.z
    );
    // With the ground, the same run crashes; with the default ground (z = 0), at the same time.
    let mut grounded = config.clone();
    grounded.ground_z_m = SimulationConfig::default().ground_z_m;
    assert_eq!(grounded.ground_z_m, Some(DEFAULT_GROUND_Z_M));
    let crashed = fall(above(0.0, 10.0, Vector3::zeros(), 0.0), &grounded).unwrap();
    assert_eq!(crashed.divergence.unwrap().kind, DivergenceKind::Crashed);
}

#[test]
fn a_trimmed_hover_stays_clear_of_the_ground() {
    // 0.5 m above the ground for 10 s at the hover thrust: no contact.
    let airframe = quad_x();
    let f = airframe.mass_kg() * airframe.gravity_m_s2() / 4.0;
    let mut actuators = instant_rotors(&airframe);
    actuators.settle(&[f; 4]).unwrap();
    let x0 = above(0.0, 0.5, Vector3::zeros(), 0.0);
    let run = simulate(
        &still_air(&airframe),
        actuators,
        &mut hover_schedule(&airframe),
        &[1.0; 4],
        &[],
        x0,
        &SimulationConfig::new(0.0025, 2, 10.0),
    )
    .unwrap();
    assert!(run.divergence.is_none(), "{:?}", run.divergence);
    assert_eq!(*run.t_s.last().unwrap(), 10.0);
    assert!((run.states.last().unwrap().position_m - x0.position_m).norm() < 1e-9);
}

#[test]
fn the_ground_comes_before_a_larger_altitude_loss_limit_and_after_a_smaller_one() {
    let g = quad_x().gravity_m_s2();
    let mut config = SimulationConfig::new(0.0025, 1, 5.0);
    config.limits.max_altitude_loss_m = 10.5;
    let run = fall(above(0.0, 10.0, Vector3::zeros(), 0.0), &config).unwrap();
    assert_eq!(run.divergence.unwrap().kind, DivergenceKind::Crashed);
    config.limits.max_altitude_loss_m = 9.5;
    let event = fall(above(0.0, 10.0, Vector3::zeros(), 0.0), &config)
        .unwrap()
        .divergence
        .unwrap();
    assert_eq!(event.kind, DivergenceKind::AltitudeLoss);
    assert!((event.time_s - (19.0 / g).sqrt()).abs() < 1e-9);
    assert!(event.impact().is_none());
}

#[test]
fn a_batch_crashes_exactly_like_single_runs() {
    let airframe = quad_x();
    let vehicle = still_air(&airframe);
    let actuators = instant_rotors(&airframe);
    let config = SimulationConfig::new(0.0025, 2, 3.0);
    let starts = [
        above(0.0, 2.0, Vector3::zeros(), 0.0),
        above(0.0, 200.0, Vector3::zeros(), 0.0),
        above(0.0, 5.0, Vector3::new(1.0, 0.0, -2.0), 0.2),
    ];
    let runs = starts
        .iter()
        .map(|&x0| BatchRun {
            controller: Box::new(ZeroCommand { count: 4 }),
            initial_command: None,
            x0,
            faults: vec![],
        })
        .collect();
    let batch = simulate_batch(&vehicle, &actuators, &[1.0; 4], runs, &config, &crate::Cancel::never()).unwrap();
    for (x0, run) in starts.iter().zip(&batch) {
        let single = fall(*x0, &config).unwrap();
        assert_eq!((&run.t_s, &run.states), (&single.t_s, &single.states));
        assert_eq!(run.divergence, single.divergence);
        // Bit for bit (the crash row's commands are NaN, which `==` never equals).
        let bits = |c: &[f64]| c.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&run.rotor_command), bits(&single.rotor_command));
    }
    let kinds: Vec<_> = batch.iter().map(|r| r.divergence.map(|d| d.kind)).collect();
    assert_eq!(
        kinds,
        [
            Some(DivergenceKind::Crashed),
            None,
            Some(DivergenceKind::Crashed)
        ]
    );
}

#[test]
fn bad_ground_settings_and_starts_underground_are_refused_by_name() {
    let x0 = above(0.0, 10.0, Vector3::zeros(), 0.0);
    for z in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut config = SimulationConfig::new(0.0025, 1, 1.0);
        config.ground_z_m = Some(z);
        let err = fall(x0, &config).unwrap_err().to_string();
        assert!(err.starts_with("ground_z_m: must be finite"), "{err}");
    }
    // On the ground (no ground reaction: it would sink at once) and below it.
    let config = SimulationConfig::new(0.0025, 1, 1.0);
    for height in [0.0, -3.0] {
        let err = fall(above(0.0, height, Vector3::zeros(), 0.0), &config)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("x0.position[2]: the run starts on or below the ground"),
            "{err}"
        );
    }
    // The same start is a flight without a ground.
    let mut off = config.clone();
    off.ground_z_m = None;
    assert!(fall(above(0.0, 0.0, Vector3::zeros(), 0.0), &off).is_ok());
    // In a batch, the run is named.
    let airframe = quad_x();
    let runs = [10.0, 0.0]
        .iter()
        .map(|&h| BatchRun {
            controller: Box::new(ZeroCommand { count: 4 }),
            initial_command: None,
            x0: above(0.0, h, Vector3::zeros(), 0.0),
            faults: vec![],
        })
        .collect();
    let err = simulate_batch(
        &still_air(&airframe),
        &instant_rotors(&airframe),
        &[1.0; 4],
        runs,
        &config,
        &crate::Cancel::never(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.starts_with("x0s[1].position[2]: the run starts on or below the ground"),
        "{err}"
    );
}
