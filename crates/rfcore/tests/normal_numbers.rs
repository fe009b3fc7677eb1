//! Issue 27: every number the model divides by is a normal, finite scale (subnormal and absurd
//! magnitudes refused with the field's name and the rule, `rfcore::error`'s table), and every
//! iterative method stops at a cap and says so instead of looping forever.

use nalgebra::DMatrix;

use rfcore::allocation::active_set::ActiveSetSolver;
use rfcore::allocation::clarabel::ClarabelSettings;
use rfcore::allocation::{
    allocate_clarabel, allocate_clarabel_unpolished, AllocationProblem, AllocationStatus,
};
use rfcore::analysis::controllability::{controllability_matrix, hover_model};
use rfcore::analysis::rank::{scale_free_rank_capped, singular_values};
use rfcore::analysis::{
    numerical_rank, scale_free_rank, svd_iteration_cap, ControlAxes, ControllabilityAnalysis,
};
use rfcore::control::ke::{CommandLaw, KeGains, UniformPassiveFtc};
use rfcore::control::lanzon::{schur_iteration_cap, spectral_radius, LanzonModel};
use rfcore::error::{MAX_SCALE, MIN_SCALE};
use rfcore::fixtures::{preset, preset_text};
use rfcore::flight::actuator::{FixedPitch, Lag};
use rfcore::flight::rigid_body::RigidBody;
use rfcore::flight::simulation::{SimulationConfig, MAX_SUBSTEPS};
use rfcore::{Airframe, RfError};

const SUBNORMAL: f64 = 1e-310;

/// The quad-x preset with `key = value` replaced in its TOML.
fn quad_with(key: &str, value: &str) -> rfcore::Result<Airframe> {
    let text = preset_text("quad-x.toml");
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("{key} =")))
        .unwrap_or_else(|| panic!("quad-x.toml has no {key}"));
    Airframe::from_toml_str(&text.replace(line, &format!("{key} = {value}")), "quad-x")
}

fn message(result: rfcore::Result<impl std::fmt::Debug>) -> String {
    result.unwrap_err().to_string()
}

#[test]
fn the_subnormal_mass_of_the_issue_is_refused_before_any_work() {
    // Accepted as "> 0" before: its hover model held 1 / 1e-310 = inf and every rank C(A, B)
    // spun forever in the SVD.
    for (key, value, field) in [
        ("mass_kg", "1e-310", "mass_kg"),
        ("mass_kg", "1e300", "mass_kg"),
        (
            "inertia_kg_m2",
            "[1e-310, 0.01, 0.02]",
            "inertia_kg_m2 (Jx)",
        ),
        ("inertia_kg_m2", "[0.01, 1e20, 0.02]", "inertia_kg_m2 (Jy)"),
        ("gravity_m_s2", "1e300", "gravity_m_s2"),
        ("gravity_m_s2", "1e-310", "gravity_m_s2"),
        ("drag_torque_ratio_m", "1e-310", "drag_torque_ratio_m"),
    ] {
        let err = message(quad_with(key, value));
        assert!(
            err.contains(&format!("{field}: must")),
            "{key} = {value}: {err}"
        );
        assert!(err.contains("subnormal"), "{key} = {value}: {err}");
    }
    // The edges of the range, zero where it means "none", and the extremes the tests use.
    quad_with("mass_kg", &format!("{MIN_SCALE:e}")).unwrap();
    quad_with("mass_kg", &format!("{MAX_SCALE:e}")).unwrap();
    quad_with("gravity_m_s2", "0.0").unwrap();
    quad_with("inertia_kg_m2", "[4.11e-14, 4.78e12, 5.99e12]").unwrap();
    quad_with("drag_torque_ratio_m", "0.0").unwrap();
}

#[test]
fn subnormal_lengths_and_coefficients_are_named() {
    let planar = |arm: f64, k_mu: f64| {
        Airframe::from_columns(
            "q",
            &[0.0, 1.6, 3.1, 4.7],
            &[arm, 0.2, 0.2, 0.2],
            &[1.0, -1.0, 1.0, -1.0],
            &[5.0; 4],
            &[0.0; 4],
            &[1.0; 4],
            1.0,
            &[0.01, 0.01, 0.02],
            k_mu,
            9.81,
        )
    };
    let err = message(planar(SUBNORMAL, 0.05));
    assert!(
        err.starts_with("arm_length_m[0] (rotor 1): must be 0 or a normal number"),
        "{err}"
    );
    let err = message(planar(0.2, -SUBNORMAL));
    assert!(
        err.starts_with("drag_torque_ratio_m: must be 0 or a normal"),
        "{err}"
    );
    // Only multiplied, and the analysis is unit-free across 1e+-300: kept (a test flies 1e300 m).
    planar(1e300, 0.05).unwrap();
    planar(0.0, 0.0).unwrap();
    let err = message(Airframe::from_general_columns(
        "g",
        &[0.2, 0.0, 0.0, -0.2, SUBNORMAL, 0.0],
        &[0.0, 0.0, -1.0, 0.0, 0.0, -1.0],
        &[1.0, -1.0],
        None,
        &[5.0; 2],
        &[0.0; 2],
        &[1.0; 2],
        1.0,
        &[0.01, 0.01, 0.02],
        0.05,
        9.81,
    ));
    assert!(
        err.starts_with("position_m[1][1] (rotor 2): must be 0 or a normal"),
        "{err}"
    );
}

#[test]
fn every_scale_the_simulator_and_controllers_divide_by_is_checked() {
    let airframe = preset("quad-x");
    let err = message(RigidBody::principal(SUBNORMAL, [0.01, 0.01, 0.02]));
    assert!(err.starts_with("mass_kg: must lie in"), "{err}");
    let err = message(RigidBody::principal(1.0, [0.01, 1e-300, 0.02]));
    assert!(err.starts_with("inertia_kg_m2[1, 1]: must lie in"), "{err}");
    for (tau, rate, field) in [
        (SUBNORMAL, f64::INFINITY, "actuator.time_constant_s"),
        (1e20, f64::INFINITY, "actuator.time_constant_s"),
        (0.0, SUBNORMAL, "actuator.rate_limit_n_s"),
    ] {
        let lag = Lag {
            time_constant_s: tau,
            rate_limit_per_s: rate,
        };
        let err = message(FixedPitch::new(&airframe, lag, 0.0));
        assert!(err.starts_with(field), "{tau} {rate}: {err}");
    }
    FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap();
    let err = message(FixedPitch::new(&airframe, Lag::none(), SUBNORMAL));
    assert!(err.starts_with("actuator.thrust_coefficient_n_s2"), "{err}");

    let mut config = SimulationConfig::new(SUBNORMAL, 1, 0.0);
    assert!(message(config.check().map(|_| ())).starts_with("dt_s: must lie in"));
    config.dt_s = 0.0025;
    config.duration_s = 0.0025;
    config.substeps = MAX_SUBSTEPS + 1;
    assert!(message(config.check().map(|_| ())).starts_with("substeps: must be at most"));
    config.substeps = MAX_SUBSTEPS;
    config.check().unwrap();

    let ke = preset("ke-quadcopter");
    let new = |gains: KeGains, dt_s: f64| {
        UniformPassiveFtc::new(
            &ke,
            gains,
            CommandLaw::Feedforward,
            vec![(0.0, [0.0; 3])],
            dt_s,
        )
        .map(|_| ())
    };
    let gains = KeGains {
        epsilon_s: SUBNORMAL,
        ..KeGains::default()
    };
    assert!(message(new(gains, 0.0025)).starts_with("epsilon_s: must lie in"));
    assert!(message(new(KeGains::default(), SUBNORMAL)).starts_with("dt_s: must lie in"));
    let gains = KeGains {
        weights: [1.0, 20.0, 20.0, SUBNORMAL],
        ..KeGains::default()
    };
    assert!(message(new(gains, 0.0025)).starts_with("weights[3]: must be 0 or a normal"));
    new(KeGains::default(), 0.0025).unwrap();

    let model = LanzonModel {
        arm_length_m: SUBNORMAL,
        ..LanzonModel::default()
    };
    assert!(message(model.check()).starts_with("model.arm_length_m: must lie in"));
    LanzonModel::default().check().unwrap();
}

#[test]
fn allocation_problems_refuse_subnormal_scales() {
    let m = DMatrix::from_row_slice(2, 2, &[1.0, SUBNORMAL, 0.0, 1.0]);
    let err = message(AllocationProblem::new(m, &[1.0; 2], &[0.0; 2], &[1.0; 2]));
    assert!(
        err.starts_with("matrix[0, 1]: must be 0 or a normal"),
        "{err}"
    );
    let err = message(AllocationProblem::new(
        DMatrix::identity(2, 2),
        &[1.0, SUBNORMAL],
        &[0.0; 2],
        &[1.0; 2],
    ));
    assert!(
        err.starts_with("weights[1]: must be 0 or a normal"),
        "{err}"
    );
    // 1.5e308 rounds to the power of two 2^1024 = inf in the solver's scaling: it answered zeros
    // and called them optimal.
    let err = message(AllocationProblem::new(
        DMatrix::identity(2, 2) * 1.5e308,
        &[1.0; 2],
        &[0.0; 2],
        &[1.0; 2],
    ));
    assert!(
        err.starts_with("matrix[0, 0]: must be at most 1e300 in magnitude"),
        "{err}"
    );
    let err = message(AllocationProblem::new(
        DMatrix::identity(2, 2),
        &[1.5e308, 1.0],
        &[0.0; 2],
        &[1.0; 2],
    ));
    assert!(
        err.starts_with("weights[0]: must be at most 1e300"),
        "{err}"
    );
    // The scale-free solver's own range: 1e-160 and 1e300 stay accepted.
    AllocationProblem::new(
        DMatrix::identity(2, 2) * 1e-160,
        &[1e300; 2],
        &[0.0; 2],
        &[1.0; 2],
    )
    .unwrap();
}

/// An airframe whose moment arm or efficiency leaves a subnormal entry in its matrices (an arm
/// angle of 1e-309 rad: found by the long hostile run, the allocator then refused `matrix[1, 0]`,
/// a matrix the user never wrote) reads that entry as 0; normal entries keep their bits.
#[test]
fn an_airframe_matrix_has_no_subnormal_entry() {
    let text = preset_text("quad-x.toml");
    let tilted = text.replacen("arm_angle_deg = 45", "arm_angle_deg = -6.4e-308", 1);
    let frame = Airframe::from_toml_str(&tilted, "quad-x").unwrap();
    let healthy = Airframe::from_toml_str(&text, "quad-x").unwrap();
    let faint = healthy.with_efficiency(&[SUBNORMAL, 1.0, 1.0, 1.0]).unwrap();
    for (name, b) in [
        ("effectiveness", frame.effectiveness_matrix()),
        ("nominal effectiveness", frame.nominal_effectiveness_matrix()),
        ("wrench", frame.wrench_matrix()),
        ("faint effectiveness", faint.effectiveness_matrix()),
        ("faint wrench", faint.wrench_matrix()),
    ] {
        assert!(b.iter().all(|x| !x.is_subnormal()), "{name}: {b}");
    }
    // The arm angle of -1.1e-309 rad: roll arm 0 (was -0.275 x sin(angle), subnormal), pitch arm 0.275.
    let b = frame.effectiveness_matrix();
    assert_eq!((b[(1, 0)], b[(2, 0)]), (0.0, 0.275));
    assert_eq!(faint.effectiveness_matrix().column(0).iter().filter(|x| **x != 0.0).count(), 0);
    // Normal entries unchanged, bit for bit.
    let columns = 1..4;
    for c in columns {
        assert_eq!(
            frame.effectiveness_matrix().column(c),
            healthy.effectiveness_matrix().column(c)
        );
    }
    AllocationProblem::new(b, &[1.0; 4], &[0.0; 4], &[1.0; 4]).unwrap();
    // Every axes' matrix takes its efficiencies there too (hover_thrust_margin's path).
    for axes in [
        ControlAxes::ThrustRollPitchYaw,
        ControlAxes::ThrustRollPitch,
        ControlAxes::Wrench,
    ] {
        assert!(axes.matrix(&faint).iter().all(|x| !x.is_subnormal()));
    }
    // A general rotor whose thrust axis has a subnormal component.
    let s = std::f64::consts::FRAC_1_SQRT_2 * 0.25;
    let general = Airframe::from_general_columns(
        "general",
        &[s, s, 0.0, -s, s, 0.0, -s, -s, 0.0, s, -s, 0.0],
        &[SUBNORMAL, 0.0, -1.0, 0.0, 0.0, -1.0, 0.0, 0.0, -1.0, 0.0, 0.0, -1.0],
        &[1.0, -1.0, 1.0, -1.0],
        None,
        &[8.0; 4],
        &[0.0; 4],
        &[1.0; 4],
        1.0,
        &[0.01, 0.01, 0.02],
        0.02,
        9.81,
    )
    .unwrap();
    let wrench = ControlAxes::Wrench.matrix(&general);
    assert!(wrench.iter().all(|x| !x.is_subnormal()), "{wrench}");
    assert_eq!(wrench[(0, 0)], 0.0);
}

#[test]
fn the_rank_svd_refuses_infinity_and_stops_at_its_cap() {
    // The matrix the subnormal mass produced (built by hand: that airframe is refused now).
    let airframe = preset("quad-x");
    let (a, mut b) = hover_model(&airframe, ControlAxes::ThrustRollPitchYaw);
    b[(4, 0)] = 1.0 / -SUBNORMAL;
    let c = controllability_matrix(&a, &b);
    let err = message(scale_free_rank(&c, "C(A, B)"));
    assert!(
        err.starts_with("C(A, B)[4, 0]: must be finite, got -inf"),
        "{err}"
    );
    // A cap of one sweep cannot settle a general matrix: an error naming the method and cap.
    let (a6, b6) = hover_model(&airframe, ControlAxes::Wrench);
    let good = controllability_matrix(&a6, &b6);
    let err = scale_free_rank_capped(&good, "C(A, B)", 1).unwrap_err();
    assert_eq!(
        err,
        RfError::IterationLimit {
            field: "C(A, B)".into(),
            method: "the singular value decomposition (SVD)".into(),
            cap: 1
        }
    );
    assert!(err
        .to_string()
        .contains("did not converge within its cap of 1 iterations"));
    assert_eq!(scale_free_rank(&good, "C(A, B)").unwrap(), 12);
    assert_eq!(svd_iteration_cap(12), 864);
    // Entries from 1e-304 to 1e225 (found by a random search): nalgebra's plain SVD returns a NaN
    // singular value there, and `svd()` panicked sorting it. The plain rank now says so; the
    // scale-free rank equilibrates first and answers.
    #[rustfmt::skip]
    let wide = DMatrix::from_column_slice(6, 5, &[
        1.161829837415431e-207, 0.0, 1.6803550910984164e54, -1.0524282807552993e-72,
        -1.1471596953926981e-268, 1.6990633455652647e41, 0.0, 1.933730627302472e-92,
        -1.1331111642180218e54, 0.0, 1.532153336555306e-298, -1.78184540133919e48,
        1.594378926553101e-304, -1.4357922522772844, 1.9394970457300728e-91, 0.0,
        -1.7065085465161032e-68, 1.0224993260382405e-188, 0.0, -1.174250188111994e78,
        1.2745911733012977e174, 0.0, -1.593381189214353e-189, 0.0, -1.8264127891840465e-187,
        -1.5134604041911137e-106, -1.5367119696165966e-286, -1.6150355860658365e225,
        -1463215131213285.5, 0.0,
    ]);
    let err = message(numerical_rank(&wide));
    assert!(
        err.starts_with("matrix: its singular value decomposition lost all precision"),
        "{err}"
    );
    let rank = scale_free_rank(&wide, "wide").unwrap();
    assert!(rank <= 5, "{rank}");
    assert!(singular_values(DMatrix::zeros(0, 3), "empty", 1)
        .unwrap()
        .is_empty());
    // Every preset's analysis converges well inside the cap.
    ControllabilityAnalysis::new(&preset("octo-x"), ControlAxes::Wrench).unwrap();
}

#[test]
fn the_schur_form_of_a_controller_stops_at_its_cap() {
    // A rotation-like 3 x 3 with complex eigenvalues: no real Schur form in one sweep.
    let a = DMatrix::from_row_slice(3, 3, &[0.5, -0.4, 0.1, 0.4, 0.5, 0.2, 0.0, 0.3, 0.2]);
    let err = spectral_radius(&a, "A_K", 1).unwrap_err();
    assert_eq!(
        err,
        RfError::iteration_limit("A_K", "the Schur decomposition (eigenvalues)", 1)
    );
    let radius = spectral_radius(&a, "A_K", schur_iteration_cap(3)).unwrap();
    let reference = a
        .complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max);
    assert_eq!(radius, reference);
    assert_eq!(schur_iteration_cap(3), 900);
}

#[test]
fn allocation_solvers_report_their_iteration_limits() {
    let airframe = preset("ke-quadcopter");
    let problem = AllocationProblem::new(
        airframe.nominal_effectiveness_matrix(),
        &[1.0, 20.0, 20.0, 0.01],
        &airframe.min_thrust_n(),
        &airframe.max_thrust_n(),
    )
    .unwrap();
    let beyond = [30.0, 0.5, -0.3, 0.2];
    // Clarabel stopped after one interior-point iteration: its status says so (the polished
    // method then re-solves exactly and certifies).
    let settings = ClarabelSettings::default().max_iterations(1).unwrap();
    let raw = allocate_clarabel_unpolished(&problem, &beyond, &settings).unwrap();
    assert_eq!(raw.status, AllocationStatus::IterationLimit, "{raw:?}");
    assert!(raw.iterations <= 1 && !raw.certificate.holds());
    let polished = allocate_clarabel(&problem, &beyond, &settings).unwrap();
    assert_eq!(polished.status, AllocationStatus::Optimal);
    let full = allocate_clarabel(&problem, &beyond, &ClarabelSettings::default()).unwrap();
    assert_eq!(full.status, AllocationStatus::Optimal);
    // The active set limited to one iteration per phase, without its fallback.
    let limited = ActiveSetSolver::new(&problem)
        .with_max_iterations(1)
        .unwrap()
        .with_fallback(false);
    let answer = limited.allocate(&beyond).unwrap();
    assert_eq!(
        answer.status,
        AllocationStatus::IterationLimit,
        "{answer:?}"
    );
    assert!(!answer.certificate.holds());
}
