use super::*;
use crate::analysis::{AcaiFormula, ControlAxes, ControllabilityAnalysis};
use crate::fixtures::preset;

fn failed(name: &str, rotors: &[usize]) -> Airframe {
    let a = preset(name);
    let mut eta = vec![1.0; a.rotor_count()];
    for &r in rotors {
        eta[r] = 0.0;
    }
    a.with_efficiency(&eta).unwrap()
}

/// Ke's vehicle as the `ke-hil` preset flies it: rotational damping 2.8e-3 N m s.
fn ke() -> RelaxedHoverSettings {
    RelaxedHoverSettings {
        rotational_drag_n_m_s: 2.8e-3,
        ..Default::default()
    }
}

fn check(result: &RelaxedHoverAnalysis) {
    for s in &result.solutions {
        assert!(s.residual <= RESIDUAL_TOLERANCE, "{s:?}");
    }
}

#[test]
fn healthy_frames_hover_statically() {
    for name in [
        "quad-x",
        "quad-plus",
        "hexa-pnpnpn",
        "hexa-ppnnpn",
        "octo-x",
        "ke-quadcopter",
        "lanzon-quadrotor",
    ] {
        for settings in [RelaxedHoverSettings::default(), ke()] {
            let a = preset(name);
            let result = relaxed_hover(
                &a,
                &RelaxedHoverSettings {
                    max_idle_rotors: 1,
                    ..settings
                },
            )
            .unwrap();
            let best = result.best().unwrap();
            assert_eq!(best.kind, HoverKind::Static, "{name}: {best:?}");
            assert_eq!(best.body_rate_rad_s, [0.0; 3]);
            // Every rotor of these symmetric frames carries an equal share.
            let share = a.mass_kg() * a.gravity_m_s2() / a.rotor_count() as f64;
            for f in &best.thrust_n {
                assert!(
                    (f - share).abs() < 1e-9 * share,
                    "{name}: {:?}",
                    best.thrust_n
                );
            }
            assert!((best.thrust_margin_n - (a.rotors()[0].max_thrust_n - share)).abs() < 1e-9);
            // No spinning solution has more margin than static hover on a healthy frame.
            assert!(result
                .solutions
                .iter()
                .all(|s| s.thrust_margin_n <= best.thrust_margin_n + 1e-9));
        }
    }
}

#[test]
fn two_opposing_rotors_spin_level_at_the_damping_rate() {
    // Ke's quadcopter without rotors 1 and 3: rotors 2 and 4 (both clockwise) carry half the
    // weight each, level, and the yaw torque k_mu m g balances the damping k_r s.
    let a = preset("ke-quadcopter");
    let result = relaxed_hover(&failed("ke-quadcopter", &[0, 2]), &ke()).unwrap();
    check(&result);
    let best = result.best().unwrap();
    let weight = a.mass_kg() * a.gravity_m_s2();
    let expected = a.drag_torque_ratio_m() * weight / 2.8e-3;
    assert!(
        (best.spin_rate_rad_s - expected).abs() < 1e-9 * expected,
        "{best:?}"
    );
    assert_eq!(best.carrying, vec![1, 3]);
    // Relative to the weight, as the spin rate above: the curve search stops on this kinked
    // optimum (the two headrooms equal) to about 1e-10 of the weight (1.0e-9 N of 7.2 N here;
    // it was an absolute 1e-9 N, met by 1.4e-12 N before h39's faster search and missed by
    // 4.9e-11 N after it: rounding, not a different solution).
    assert!(
        (best.thrust_n[1] - 0.5 * weight).abs() < 1e-9 * weight
            && (best.thrust_n[3] - 0.5 * weight).abs() < 1e-9 * weight,
        "{:?}",
        best.thrust_n
    );
    assert!(
        (best.spin_axis[2] + 1.0).abs() < 1e-12,
        "{:?}",
        best.spin_axis
    );
    assert!(best.linear.stabilizable);
}

#[test]
fn lanzon_working_point_is_a_relaxed_hover() {
    // Lanzon's rotor 2 lost, rotor 4 switched off: rotors 1 and 3 carry m g / 2 each, level, at
    // r0 = m g d / k_r (2.7 rad/s with the preset's k_r). The gyroscopic moment is in the model.
    let a = preset("lanzon-quadrotor");
    let weight = a.mass_kg() * a.gravity_m_s2();
    let settings = RelaxedHoverSettings {
        rotational_drag_n_m_s: weight * a.drag_torque_ratio_m() / 2.7,
        rotor_inertia_kg_m2: 3e-5,
        thrust_coefficient_n_s2: 1e-5,
        ..Default::default()
    };
    let result = relaxed_hover(&failed("lanzon-quadrotor", &[1]), &settings).unwrap();
    check(&result);
    let level = result
        .solutions
        .iter()
        .find(|s| s.carrying == vec![0, 2])
        .expect("rotors 1 and 3 alone");
    assert!(
        (level.spin_rate_rad_s.abs() - 2.7).abs() < 1e-9,
        "{level:?}"
    );
    assert!((level.thrust_n[0] - 0.5 * weight).abs() < 1e-9);
    // The best uses rotor 4 as well and has more margin.
    let best = result.best().unwrap();
    assert!(best.thrust_margin_n >= level.thrust_margin_n);
}

#[test]
fn ke_single_failure_best_loads_three_rotors_equally() {
    let a = preset("ke-quadcopter");
    let result = relaxed_hover(&failed("ke-quadcopter", &[0]), &ke()).unwrap();
    check(&result);
    let best = result.best().unwrap();
    assert_eq!(best.carrying, vec![1, 2, 3]);
    assert_eq!(best.kind, HoverKind::Spinning);
    let f = &best.thrust_n;
    assert!(
        (f[1] - f[2]).abs() < 1e-7 && (f[2] - f[3]).abs() < 1e-7,
        "{f:?}"
    );
    assert!((best.thrust_margin_n - (8.5 - f[1])).abs() < 1e-9);
    // The vertical component carries the weight.
    let weight = a.mass_kg() * a.gravity_m_s2();
    assert!((3.0 * f[1] * -best.spin_axis[2] - weight).abs() < 1e-9 * weight);
    // An independent check of the equations: the body rate is the spin about the axis, and the
    // moment balance along the axis is the damping: n . tau(f) = k_r s.
    let tau: V3 = (1..4)
        .map(|i| Model::new(&a, &ke()).unwrap().torque[i] * f[i])
        .sum();
    let n = V3::from(best.spin_axis);
    assert!(
        (n.dot(&tau) - 2.8e-3 * best.spin_rate_rad_s).abs() < 1e-12,
        "{}",
        n.dot(&tau)
    );
    assert!(best.linear.stabilizable);
}

#[test]
fn static_verdicts_match_du_tables() {
    // A single failure leaves static hover holdable exactly where Du's ACAI is > 0 (where it is,
    // spinning may still have more margin: PPNNPN without rotor 1 spins with 2.40 N of headroom).
    for name in ["hexa-pnpnpn", "hexa-ppnnpn"] {
        for r in 0..6 {
            let a = failed(name, &[r]);
            let acai = ControllabilityAnalysis::new(&a, ControlAxes::ThrustRollPitchYaw)
                .unwrap()
                .acai(&a.efficiency(), AcaiFormula::Eq13)
                .unwrap();
            let result = relaxed_hover(
                &a,
                &RelaxedHoverSettings {
                    max_idle_rotors: 1,
                    grid_points: 31,
                    ..Default::default()
                },
            )
            .unwrap();
            assert!(
                result.best().is_some(),
                "{name} rotor {}: every single failure is survivable",
                r + 1
            );
            let holdable_static = result
                .solutions
                .iter()
                .any(|s| s.kind == HoverKind::Static && s.linear.stabilizable);
            assert_eq!(
                holdable_static,
                acai > 0.0,
                "{name} rotor {}: ACAI {acai}, {:#?}",
                r + 1,
                result.solutions
            );
        }
    }
}

#[test]
fn bad_settings_are_named() {
    let a = preset("quad-x");
    for (settings, field) in [
        (
            RelaxedHoverSettings {
                rotational_drag_n_m_s: -1.0,
                ..Default::default()
            },
            "rotational_drag_n_m_s",
        ),
        (
            RelaxedHoverSettings {
                rotor_inertia_kg_m2: 1e-5,
                ..Default::default()
            },
            "thrust_coefficient_n_s2",
        ),
        (
            RelaxedHoverSettings {
                max_spin_rate_rad_s: 0.0,
                ..Default::default()
            },
            "max_spin_rate_rad_s",
        ),
        (
            RelaxedHoverSettings {
                max_circle_radius_m: f64::NAN,
                ..Default::default()
            },
            "max_circle_radius_m",
        ),
        (
            RelaxedHoverSettings {
                grid_points: 60,
                ..Default::default()
            },
            "grid_points",
        ),
    ] {
        let err = relaxed_hover(&a, &settings).unwrap_err();
        assert!(err.to_string().starts_with(field), "{err}");
    }
}

#[test]
fn a_vehicle_that_cannot_lift_itself_has_no_solution() {
    let result = relaxed_hover(
        &failed("ke-quadcopter", &[0, 1, 2]),
        &RelaxedHoverSettings {
            rotational_drag_n_m_s: 2.8e-3,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        !result.solutions.is_empty(),
        "one rotor of 8.5 N lifts 7.06 N"
    );
    let heavy = {
        let a = failed("ke-quadcopter", &[0, 1, 2]);
        let text = a
            .to_toml_string()
            .replace("mass_kg = 0.72", "mass_kg = 0.9");
        Airframe::from_toml_str(&text, "heavy").unwrap()
    };
    let result = relaxed_hover(&heavy, &ke()).unwrap();
    assert!(result.solutions.is_empty() && result.best().is_none());
}

#[test]
fn residual_rejects_a_wrong_solution() {
    let a = failed("ke-quadcopter", &[0, 2]);
    let best = relaxed_hover(&a, &ke()).unwrap().best().unwrap().clone();
    let ok = relaxed_hover_residual(
        &a,
        &ke(),
        best.body_rate_rad_s,
        best.spin_axis,
        &best.thrust_n,
    )
    .unwrap();
    assert!(ok < 1e-12);
    let mut off = best.thrust_n.clone();
    off[1] *= 1.001;
    let bad =
        relaxed_hover_residual(&a, &ke(), best.body_rate_rad_s, best.spin_axis, &off).unwrap();
    assert!(bad > 1e-4, "{bad}");
}

/// A quadrotor whose rotors lean 10 degrees sideways, alternately (non-parallel thrust axes: the
/// general path, per-axis matrices, static hover by Newton since four rotors cannot make every
/// wrench).
fn leaning_quad(failed: &[usize]) -> Airframe {
    let lean = 10f64.to_radians();
    let mut position = Vec::new();
    let mut axis = Vec::new();
    for i in 0..4 {
        let phi = (45.0 + 90.0 * i as f64).to_radians();
        position.extend([0.2 * phi.cos(), 0.2 * phi.sin(), 0.0]);
        let side = if i % 2 == 0 { 1.0 } else { -1.0 } * lean.sin();
        // Tangential lean: along (-sin phi, cos phi).
        axis.extend([-phi.sin() * side, phi.cos() * side, -lean.cos()]);
    }
    let mut eta = vec![1.0; 4];
    for &r in failed {
        eta[r] = 0.0;
    }
    Airframe::from_general_columns(
        "leaning",
        &position,
        &axis,
        &[1.0, -1.0, 1.0, -1.0],
        None,
        &[6.0; 4],
        &[0.0; 4],
        &eta,
        1.0,
        &[0.01, 0.01, 0.02],
        0.016,
        9.81,
    )
    .unwrap()
}

#[test]
fn tilted_rotors_are_analysed() {
    let healthy = relaxed_hover(
        &leaning_quad(&[]),
        &RelaxedHoverSettings {
            max_idle_rotors: 0,
            ..Default::default()
        },
    )
    .unwrap();
    check(&healthy);
    let best = healthy.best().expect("a healthy leaning quad hovers");
    assert_eq!(best.kind, HoverKind::Static, "{best:?}");
    // By symmetry it hovers level with equal thrusts: 9.81 / (4 cos 10 deg) each.
    let share = 9.81 / (4.0 * 10f64.to_radians().cos());
    for f in &best.thrust_n {
        assert!((f - share).abs() < 1e-9, "{:?}", best.thrust_n);
    }
    assert!(
        (best.spin_axis[2] + 1.0).abs() < 1e-12,
        "{:?}",
        best.spin_axis
    );
    // A fully actuated hexarotor (rotors leaning 30 degrees alternately): static hover over a
    // range of attitudes, searched over the up axis; the level one carries the most.
    let lean = 30f64.to_radians();
    let (mut position, mut axis) = (Vec::new(), Vec::new());
    for i in 0..6 {
        let phi = (60.0 * i as f64).to_radians();
        position.extend([0.25 * phi.cos(), 0.25 * phi.sin(), 0.0]);
        let side = if i % 2 == 0 { 1.0 } else { -1.0 } * lean.sin();
        axis.extend([-phi.sin() * side, phi.cos() * side, -lean.cos()]);
    }
    let hexa = Airframe::from_general_columns(
        "omni",
        &position,
        &axis,
        &[1.0, -1.0, 1.0, -1.0, 1.0, -1.0],
        None,
        &[6.0; 6],
        &[0.0; 6],
        &[1.0; 6],
        1.5,
        &[0.03, 0.03, 0.05],
        0.016,
        9.81,
    )
    .unwrap();
    let omni = relaxed_hover(
        &hexa,
        &RelaxedHoverSettings {
            max_idle_rotors: 0,
            grid_points: 31,
            ..Default::default()
        },
    )
    .unwrap();
    check(&omni);
    let best = omni.best().unwrap();
    assert_eq!(best.kind, HoverKind::Static);
    assert!(
        (best.spin_axis[2] + 1.0).abs() < 1e-6,
        "{:?}",
        best.spin_axis
    );
    let one_lost = relaxed_hover(&leaning_quad(&[0]), &ke()).unwrap();
    check(&one_lost);
    assert!(one_lost
        .solutions
        .iter()
        .any(|s| s.kind == HoverKind::Spinning && s.linear.stabilizable));
}

#[test]
fn edge_cases_give_answers_not_panics() {
    // Every rotor failed: nothing carries the vehicle.
    let none = relaxed_hover(&failed("ke-quadcopter", &[0, 1, 2, 3]), &ke()).unwrap();
    assert!(none.solutions.is_empty());
    // A nearly failed rotor (efficiency 1e-9) and a half-efficient one: the commands are the
    // thrusts over the efficiency, the bounds scaled by it.
    let a = preset("ke-quadcopter")
        .with_efficiency(&[1e-9, 0.5, 1.0, 1.0])
        .unwrap();
    let result = relaxed_hover(&a, &ke()).unwrap();
    check(&result);
    let best = result.best().unwrap();
    for (i, eta) in [1e-9, 0.5, 1.0, 1.0].iter().enumerate() {
        assert!(best.thrust_n[i] <= eta * 8.5 * (1.0 + 1e-12), "{best:?}");
        assert!((best.command_n[i] * eta - best.thrust_n[i]).abs() < 1e-12);
    }
    // No gravity: nothing to carry, said so.
    let text: String = preset("quad-x")
        .to_toml_string()
        .lines()
        .map(|l| {
            if l.starts_with("gravity_m_s2") {
                "gravity_m_s2 = 0.0\n".to_string()
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let floating = Airframe::from_toml_str(&text, "floating").unwrap();
    let err = relaxed_hover(&floating, &RelaxedHoverSettings::default()).unwrap_err();
    assert!(err.to_string().starts_with("gravity_m_s2"), "{err}");
}

/// The certify path (`best_relaxed_hover_cancellable`, which skips carrying sets whose margin
/// bound is below the best holdable margin found) returns the full analysis's best, to the bit,
/// and searches fewer strategies where the bound prunes (Ke's quadcopter with rotor 4 partly
/// lost: the two-rotor carrying sets cannot beat the three-rotor spin).
#[test]
fn best_only_search_returns_the_full_analysis_best() {
    let mut pruned_somewhere = false;
    for (name, efficiency) in [
        ("ke-quadcopter", [1.0, 1.0, 1.0, 0.3]),
        ("ke-quadcopter", [0.5, 1.0, 0.5, 1.0]),
        ("lanzon-quadrotor", [0.8, 0.9, 0.9, 0.0]),
        ("quad-x", [1.0, 0.6, 1.0, 1.0]),
    ] {
        let a = preset(name).with_efficiency(&efficiency).unwrap();
        let full = relaxed_hover(&a, &ke()).unwrap();
        let best = best_relaxed_hover_cancellable(&a, &ke(), &Cancel::never()).unwrap();
        check(&best);
        assert_eq!(full.best(), best.best(), "{name} {efficiency:?}");
        pruned_somewhere |= best.solutions.len() < full.solutions.len();
    }
    assert!(pruned_somewhere, "the bound never pruned: the test does not exercise it");
}
