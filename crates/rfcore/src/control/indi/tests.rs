//! Unit tests of the INDI law (split from `mod.rs` to keep it readable in one sitting).

use super::*;
use nalgebra::UnitQuaternion;

const DT: f64 = 1.0 / 400.0;

fn hover_state() -> RigidBodyState {
    RigidBodyState {
        position_m: Vector3::new(0.0, 0.0, -10.0),
        ..RigidBodyState::at_rest()
    }
}

fn controller(preset: &str, failures: Vec<DetectedFailure>) -> IndiController {
    let airframe = crate::fixtures::preset(preset);
    IndiController::new(
        &airframe,
        IndiGains::default(),
        failures,
        vec![Setpoint::hold(0.0, [0.0, 0.0, -10.0])],
        DT,
    )
    .unwrap()
}

#[test]
fn hover_at_the_setpoint_commands_the_hover_thrusts_with_and_without_samples() {
    let airframe = crate::fixtures::preset("hexa-ppnnpn");
    let mut c = controller("hexa-ppnnpn", vec![]);
    let hover = c.failure_modes()[0].hover_thrust_n.clone();
    let state = hover_state();
    let force = Vector3::new(0.0, 0.0, -airframe.gravity_m_s2());
    let with = ControllerInput {
        state: &state,
        gyro_rad_s: Some(Vector3::zeros()),
        specific_force_m_s2: Some(force),
        rotor_thrust_n: Some(&hover),
    };
    let mut out = [0.0; 6];
    for k in 0..200 {
        c.command_with(k as f64 * DT, &with, &mut out).unwrap();
        for (t, h) in out.iter().zip(&hover) {
            assert!((t - h).abs() < 1e-9, "{k}: {out:?} vs {hover:?}");
        }
    }
    c.reset();
    for k in 0..200 {
        c.command(k as f64 * DT, &state, &mut out).unwrap();
        for (t, h) in out.iter().zip(&hover) {
            assert!((t - h).abs() < 1e-9, "{k}: {out:?} vs {hover:?}");
        }
    }
}

#[test]
fn a_detected_failure_switches_the_allocation_at_its_time_and_commands_the_rotor_to_zero() {
    let failure = DetectedFailure {
        rotor: 0,
        time_s: 0.5,
    };
    let mut c = controller("octo-x", vec![failure]);
    let modes = c.failure_modes();
    assert_eq!((modes.len(), modes[1].failed.clone()), (2, vec![0]));
    let state = hover_state();
    let mut out = [0.0; 8];
    let mut before = [0.0; 8];
    for k in 0..400 {
        let t = k as f64 * DT;
        c.command(t, &state, &mut out).unwrap();
        if t < 0.5 {
            assert!(out[0] > 1.0, "{t}: {out:?}");
            before = out;
        } else {
            assert_eq!(out[0], 0.0, "{t}");
        }
    }
    assert!(
        before.iter().all(|t| (t - before[1]).abs() < 1e-9),
        "{before:?}"
    );
}

#[test]
fn failures_told_at_once_are_flown_together_and_no_set_between_them_is_judged() {
    // Rotors 1 and 2 of ke-quadcopter (adjacent) told at once: the set is refused as a whole;
    // rotors 1 and 3 at once: the single failure of rotor 1 between them is never built.
    let together = |a: usize, b: usize| {
        let airframe = crate::fixtures::preset("ke-quadcopter");
        let failures = vec![
            DetectedFailure {
                rotor: a,
                time_s: 1.0,
            },
            DetectedFailure {
                rotor: b,
                time_s: 1.0,
            },
        ];
        let hold = vec![Setpoint::hold(0.0, [0.0; 3])];
        IndiController::new(&airframe, IndiGains::default(), failures, hold, DT)
    };
    assert!(together(0, 1)
        .unwrap_err()
        .to_string()
        .contains("rotor(s) 1, 2 failed"));
    let c = together(0, 2).unwrap();
    let failed: Vec<Vec<usize>> = c.failure_modes().into_iter().map(|m| m.failed).collect();
    assert_eq!(failed, vec![vec![], vec![0, 2]]);
    assert_eq!((c.mode_at(0.99), c.mode_at(1.0)), (0, 1));
}

#[test]
fn the_same_measurements_give_the_same_commands_after_a_reset() {
    let mut c = controller(
        "ke-quadcopter",
        vec![DetectedFailure {
            rotor: 1,
            time_s: 0.1,
        }],
    );
    let states: Vec<RigidBodyState> = (0..300)
        .map(|k| {
            let t = k as f64 * DT;
            RigidBodyState {
                position_m: Vector3::new(0.1 * t.sin(), -0.2 * t, -10.0 + 0.05 * t),
                velocity_m_s: Vector3::new(0.1 * t.cos(), -0.2, 0.05),
                attitude: UnitQuaternion::from_euler_angles(0.05 * t, -0.03, 2.0 * t),
                omega_rad_s: Vector3::new(0.05, 0.0, 2.0 + t),
            }
        })
        .collect();
    let times: Vec<f64> = (0..300).map(|k| k as f64 * DT).collect();
    let first = crate::control::replay(&mut c, &times, &states, &crate::Cancel::never()).unwrap();
    let second = crate::control::replay(&mut c, &times, &states, &crate::Cancel::never()).unwrap();
    assert_eq!(first, second);
    assert!(first.iter().all(|v| v.is_finite()));
}

#[test]
fn bad_measurements_and_arguments_are_named() {
    let mut c = controller("ke-quadcopter", vec![]);
    let mut state = hover_state();
    let mut out = [0.0; 4];
    c.command(0.0, &state, &mut out).unwrap();
    state.velocity_m_s.y = f64::NAN;
    let err = c.command(DT, &state, &mut out).unwrap_err().to_string();
    assert!(err.starts_with("measured:"), "{err}");
    let state = hover_state();
    let short = [1.0; 3];
    let input = ControllerInput {
        rotor_thrust_n: Some(&short),
        ..ControllerInput::state_only(&state)
    };
    let err = c
        .command_with(DT, &input, &mut out)
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("rotor_thrust_n:"), "{err}");
    let input = ControllerInput {
        gyro_rad_s: Some(Vector3::new(0.0, f64::INFINITY, 0.0)),
        ..ControllerInput::state_only(&state)
    };
    assert!(c
        .command_with(DT, &input, &mut out)
        .unwrap_err()
        .to_string()
        .starts_with("measured:"));

    let airframe = crate::fixtures::preset("ke-quadcopter");
    let hold = vec![Setpoint::hold(0.0, [0.0; 3])];
    let new = |failures: Vec<DetectedFailure>, setpoints: Vec<Setpoint>, dt: f64| {
        IndiController::new(&airframe, IndiGains::default(), failures, setpoints, dt)
            .unwrap_err()
            .to_string()
    };
    let failure = |rotor, time_s| DetectedFailure { rotor, time_s };
    for (err, field) in [
        (new(vec![], hold.clone(), 0.0), "dt_s:"),
        (new(vec![], vec![], DT), "setpoints:"),
        (
            new(
                vec![],
                vec![Setpoint::hold(1.0, [0.0; 3]), Setpoint::hold(1.0, [1.0; 3])],
                DT,
            ),
            "setpoints[1].time:",
        ),
        (
            new(vec![], vec![Setpoint::hold(0.0, [0.0, f64::NAN, 0.0])], DT),
            "setpoints[0].position:",
        ),
        (
            new(vec![failure(4, 1.0)], hold.clone(), DT),
            "failures[0].rotor:",
        ),
        (
            new(vec![failure(1, 1.0), failure(1, 2.0)], hold.clone(), DT),
            "failures[1].rotor:",
        ),
        (
            new(vec![failure(1, f64::NAN)], hold.clone(), DT),
            "failures[0].time:",
        ),
        (
            new(vec![failure(0, 1.0), failure(1, 2.0)], hold.clone(), DT),
            "failures:",
        ),
    ] {
        assert!(err.starts_with(field), "{field}: {err}");
    }
    let gains = IndiGains {
        k_att_p: -1.0,
        ..IndiGains::default()
    };
    let err = IndiController::new(&airframe, gains, vec![], hold, DT)
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("k_att_p:"), "{err}");
}

/// Flies only the spin about body z of a level, still vehicle whose angular acceleration is
/// exactly the law's model (`sum angular_c T_c`, the rotors producing the previous commands), from
/// `spin_rad_s`, for `steps`; returns the spin after each step.
fn spin_only(c: &mut IndiController, spin_rad_s: f64, steps: usize) -> Vec<f64> {
    let angular = c.modes[0].angular.clone();
    let mut produced = c.failure_modes()[0].hover_thrust_n.clone();
    let mut out = vec![0.0; produced.len()];
    let mut r = spin_rad_s;
    let mut spins = Vec::with_capacity(steps);
    for k in 0..steps {
        let state = RigidBodyState {
            omega_rad_s: Vector3::new(0.0, 0.0, r),
            ..hover_state()
        };
        let input = ControllerInput {
            state: &state,
            gyro_rad_s: Some(state.omega_rad_s),
            specific_force_m_s2: None,
            rotor_thrust_n: Some(&produced),
        };
        c.step(k as f64 * DT, &input, &mut out).unwrap();
        r += DT * angular.iter().zip(&out).map(|(a, t)| a.z * t).sum::<f64>();
        produced.clone_from(&out);
        spins.push(r);
    }
    spins
}

/// With a relaxed spin about body z aiming at `r* = 20 rad/s`, the spin row drives the spin from
/// 6 rad/s (past the latch share, 5 rad/s) toward `r*` (`k_spin = 1/s`: within 2 % after 5 s,
/// and never past it); `reset` clears the latched sign: a fresh controller and a reset one then
/// command the same, bit for bit, from a spin the other way, which the latched one does not.
#[test]
fn the_relaxed_spin_row_drives_the_spin_toward_its_target_and_reset_clears_its_sign() {
    let make = || {
        controller("ke-quadcopter", vec![])
            .with_relaxed_spin(RelaxedSpin::new(0.0, [0.0, 0.0, 1.0], 20.0).unwrap())
            .unwrap()
    };
    let mut c = make();
    let spins = spin_only(&mut c, 6.0, 2000);
    let last = *spins.last().unwrap();
    assert!((last - 20.0).abs() < 0.02 * 20.0, "{last}");
    assert!(spins.iter().all(|&r| r > 5.9 && r < 20.0 + 1e-9), "{spins:?}");
    assert!(spins[400] > spins[0] && spins[1200] > spins[400], "{spins:?}");
    assert_eq!(c.memory.spin_sign, 1.0);

    let latched = spin_only(&mut c, -6.0, 40);
    c.reset();
    assert_eq!(c.memory.spin_sign, 0.0);
    let after_reset = spin_only(&mut c, -6.0, 40);
    let fresh = spin_only(&mut make(), -6.0, 40);
    assert_eq!(after_reset, fresh);
    // Latched to +1 the row pushes the spin up from -6 rad/s; cleared, it follows the measured
    // sign to -20 rad/s.
    assert!(latched[39] > -6.0 && fresh[39] < -6.0, "{latched:?} {fresh:?}");
}

/// Steps a level, still hover at the set point with rotors `a` and `b` producing `eff_a` and
/// `eff_b` of their previous commands (the others all of theirs), at `t0 + k DT` for `steps`,
/// with rotor samples from step `sampled_from` on (`usize::MAX`: none); `produced` carries the
/// rotors' thrusts from call to call. Returns the commands of each step.
fn fly_weak_pair(
    c: &mut IndiController,
    produced: &mut Vec<f64>,
    [a, b]: [usize; 2],
    [eff_a, eff_b]: [f64; 2],
    (t0, sampled_from): (f64, usize),
    steps: usize,
) -> Vec<Vec<f64>> {
    let state = hover_state();
    let mut out = vec![0.0; produced.len()];
    let mut all = Vec::with_capacity(steps);
    for k in 0..steps {
        let input = ControllerInput {
            state: &state,
            gyro_rad_s: Some(state.omega_rad_s),
            specific_force_m_s2: None,
            rotor_thrust_n: (k >= sampled_from).then_some(&produced[..]),
        };
        c.step(t0 + k as f64 * DT, &input, &mut out).unwrap();
        produced.clone_from(&out);
        produced[a] *= eff_a;
        produced[b] *= eff_b;
        all.push(out.clone());
    }
    all
}

/// `fly_weak_pair` through the choice (`choice_steps` from 0 s, rotor samples throughout), then
/// 80 steps from `after_s` with the two rotors' weakness swapped (the other rotor now the
/// weaker). Returns the commands of the second leg.
fn fly_choice_then_swap(
    c: &mut IndiController,
    produced: &mut Vec<f64>,
    effs: [f64; 2],
    (choice_steps, after_s): (usize, f64),
) -> Vec<Vec<f64>> {
    fly_weak_pair(c, produced, [0, 2], effs, (0.0, 0), choice_steps);
    fly_weak_pair(c, produced, [0, 2], [effs[1], effs[0]], (after_s, 0), 80)
}

/// Two weak rotors of a quadrotor (an opposing pair, 1 and 3 of ke-quadcopter): the law flies as
/// without a spin axis for `SPIN_AXIS_CHOICE_S` (bit for bit), then the axis of the rotor whose
/// produced / commanded thrust measured the lower (the given axis when the first, its mirror when
/// the second) and keeps it after the other turns weaker; the pair named the other way round with
/// the mirrored axis flies the same (to rounding: the axis is normalised again); ratios equal to within rounding, no rotor
/// samples, or samples for part of the measurement only, keep the given axis; reset clears it.
#[test]
fn the_spin_axis_is_flown_on_the_side_of_the_weaker_of_two_rotors() {
    let axis = [0.06, 0.06, (1.0_f64 - 2.0 * 0.06 * 0.06).sqrt()];
    let choosing = |axis: [f64; 3], pair: [usize; 2]| {
        RelaxedSpin::new(0.1, axis, 0.0)
            .unwrap()
            .choosing_the_weaker_of(pair)
            .unwrap()
    };
    let spin = choosing(axis, [0, 2]);
    assert_eq!(spin.flown_from_s(), 0.1 + SPIN_AXIS_CHOICE_S);
    let [x, y, z] = spin.spin_axis();
    let mirrored = [-x, -y, z];
    assert_eq!(spin.mirrored_axis(), Vector3::from(mirrored));
    let make = |spin: RelaxedSpin| {
        let c = controller("ke-quadcopter", vec![])
            .with_relaxed_spin(spin)
            .unwrap();
        let produced = c.failure_modes()[0].hover_thrust_n.clone();
        (c, produced)
    };
    let choice_steps = ((0.1 + SPIN_AXIS_CHOICE_S) / DT) as usize + 1;
    let after_s = choice_steps as f64 * DT;
    let mut flown = Vec::new();
    for (effs, sampled_from, chosen_mirrored) in [
        ([0.60, 0.66], 0, false),
        ([0.66, 0.60], 0, true),
        ([0.70, 0.70], 0, false),
        ([0.66, 0.60], usize::MAX, false),
        ([0.66, 0.60], 60, false),
    ] {
        let (mut c, mut produced) = make(spin);
        let commands = fly_weak_pair(
            &mut c,
            &mut produced,
            [0, 2],
            effs,
            (0.0, sampled_from),
            choice_steps,
        );
        assert_eq!(
            c.memory.spin_axis_mirrored,
            Some(chosen_mirrored),
            "{effs:?} {sampled_from}"
        );
        // Until the choice, the commands of the law without a spin axis, bit for bit.
        let mut plain = controller("ke-quadcopter", vec![]);
        let mut plain_produced = plain.failure_modes()[0].hover_thrust_n.clone();
        let before = fly_weak_pair(
            &mut plain,
            &mut plain_produced,
            [0, 2],
            effs,
            (0.0, sampled_from),
            choice_steps,
        );
        assert_eq!(
            commands[..choice_steps - 1],
            before[..choice_steps - 1],
            "{effs:?}"
        );
        // Kept when the other rotor turns the weaker later.
        let later = fly_weak_pair(
            &mut c,
            &mut produced,
            [0, 2],
            [effs[1], effs[0]],
            (after_s, 0),
            80,
        );
        assert_eq!(c.memory.spin_axis_mirrored, Some(chosen_mirrored));
        if sampled_from == 0 && effs[0] != effs[1] {
            flown.push((effs, chosen_mirrored, later));
        }
        c.reset();
        assert_eq!(c.memory.spin_axis_mirrored, None);
        assert_eq!(c.memory.spin_choice_sums, [[0.0; 2]; 2]);
        assert!(!c.memory.spin_choice_unmeasured);
    }
    // After the choice, the commands of the law given the chosen side's axis from then on, with
    // no choice (to rounding: the mirrored axis is normalised again), and not those of the other
    // side's on the same flight.
    let close = |p: &[Vec<f64>], q: &[Vec<f64>], tol: f64| {
        p.iter()
            .flatten()
            .zip(q.iter().flatten())
            .all(|(u, v)| (u - v).abs() <= tol * v.abs().max(1.0))
    };
    for (effs, chosen_mirrored, later) in &flown {
        let direct = |axis: [f64; 3]| {
            let spin = RelaxedSpin::new(0.1 + SPIN_AXIS_CHOICE_S, axis, 0.0).unwrap();
            let (mut c, mut produced) = make(spin);
            fly_choice_then_swap(&mut c, &mut produced, *effs, (choice_steps, after_s))
        };
        let (chosen, other) = if *chosen_mirrored {
            (mirrored, spin.spin_axis())
        } else {
            (spin.spin_axis(), mirrored)
        };
        assert!(close(later, &direct(chosen), 1e-12), "{effs:?}");
        assert!(!close(later, &direct(other), 1e-6), "{effs:?}");
    }
    // Rotor 3 the weaker: the pair named (3, 1) with the mirrored axis flies the same (to rounding).
    let (mut c, mut produced) = make(choosing(mirrored, [2, 0]));
    let later = fly_choice_then_swap(&mut c, &mut produced, [0.66, 0.60], (choice_steps, after_s));
    assert_eq!(c.memory.spin_axis_mirrored, Some(false));
    assert!(close(&later, &flown[1].2, 1e-12));
}

#[test]
fn a_choice_of_two_rotors_is_checked() {
    let tilted = RelaxedSpin::new(0.0, [0.1, 0.0, 1.0], 0.0).unwrap();
    for (spin, words) in [
        (tilted.choosing_the_weaker_of([1, 1]), "2 twice"),
        (
            tilted.choosing_the_weaker_of([usize::MAX, usize::MAX]),
            "18446744073709551616 twice",
        ),
        (
            RelaxedSpin::new(0.0, [0.0, 0.0, 1.0], 0.0)
                .unwrap()
                .choosing_the_weaker_of([0, 2]),
            "body z",
        ),
    ] {
        let err = spin.unwrap_err().to_string();
        assert!(
            err.contains("spin_axis_weaker_of") && err.contains(words),
            "{err}"
        );
    }
    let failed = vec![DetectedFailure {
        rotor: 2,
        time_s: 0.2,
    }];
    for (c, pair, words) in [
        (controller("ke-quadcopter", vec![]), [0, 4], "1 to 4, got 5"),
        (
            controller("ke-quadcopter", vec![]),
            [0, usize::MAX],
            "got 18446744073709551616",
        ),
        (
            controller("ke-quadcopter", vec![]),
            [0, 1],
            "not mounted opposite",
        ),
        (
            controller("ke-quadcopter", failed),
            [0, 2],
            "rotor 3 is told failed at 0.2 s",
        ),
        (
            IndiController::new(
                &crate::fixtures::preset("ke-quadcopter"),
                IndiGains::default(),
                vec![],
                vec![Setpoint::hold(0.0, [0.0, 0.0, -10.0])],
                SPIN_AXIS_CHOICE_S,
            )
            .unwrap(),
            [0, 2],
            "control period",
        ),
    ] {
        let err = c
            .with_relaxed_spin(tilted.choosing_the_weaker_of(pair).unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("spin_axis_weaker_of") && err.contains(words),
            "{err}"
        );
    }
    // A failure told after the choice is flown: measured before it.
    let late = vec![DetectedFailure {
        rotor: 2,
        time_s: 5.0,
    }];
    assert!(controller("ke-quadcopter", late)
        .with_relaxed_spin(tilted.choosing_the_weaker_of([0, 2]).unwrap())
        .is_ok());
}
