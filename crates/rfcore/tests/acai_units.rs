//! Issue #19: ACAI verdicts and ranks do not depend on the units of the rows (or of J and m), and
//! every ACAI can carry where the hover wrench lies.
//!
//! The reference is an LP through Clarabel (a dependency of rfcore): the gauge
//! `s* = min { s : B (c + v) = G, |v_k| <= s h_k }` of G about the box centre `c` (half-widths
//! `h`); for a full-rank B, G is inside Omega iff `s* < 1`. It is solved on the well-scaled base
//! matrix; the ACAI sees the same problem with rows rescaled by up to 1e8.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use nalgebra::DMatrix;
use rfcore::analysis::controllability::{controllability_matrix, hover_model};
use rfcore::analysis::numerical_rank;
use rfcore::analysis::{
    acai_from_matrix, acai_from_matrix_with_hover, failure_table, scale_free_rank, AcaiFormula,
    ControlAxes, ControllabilityAnalysis, HoverPoint, Verdict,
};
use rfcore::fixtures::Rng;
use rfcore::fixtures::{preset, preset_text};
use rfcore::{Airframe, Cancel};

/// The gauge of G about the box centre (see the module docs), or None if Clarabel fails.
fn lp_gauge(b: &DMatrix<f64>, lo: &[f64], hi: &[f64], g: &[f64]) -> Option<f64> {
    let (n, m) = b.shape();
    let centre: Vec<f64> = lo.iter().zip(hi).map(|(l, h)| 0.5 * (l + h)).collect();
    let half: Vec<f64> = lo.iter().zip(hi).map(|(l, h)| 0.5 * (h - l)).collect();
    let vars = m + 1;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut rhs = Vec::new();
    for r in 0..n {
        let mut row = vec![0.0; vars];
        for k in 0..m {
            row[k] = b[(r, k)];
        }
        rows.push(row);
        rhs.push(g[r] - (0..m).map(|k| b[(r, k)] * centre[k]).sum::<f64>());
    }
    for k in 0..m {
        for sign in [1.0, -1.0] {
            let mut row = vec![0.0; vars];
            row[k] = sign;
            row[m] = -half[k];
            rows.push(row);
            rhs.push(0.0);
        }
    }
    let p = CscMatrix::<f64>::zeros((vars, vars));
    let mut q = vec![0.0; vars];
    q[m] = 1.0;
    let a = CscMatrix::from(rows.iter().map(|r| r.iter()));
    let cones = [
        SupportedConeT::ZeroConeT(n),
        SupportedConeT::NonnegativeConeT(2 * m),
    ];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-11)
        .tol_gap_rel(1e-11)
        .tol_feas(1e-11)
        .build()
        .unwrap();
    let mut solver = DefaultSolver::new(&p, &q, &a, &rhs, &cones, settings).ok()?;
    solver.solve();
    matches!(
        solver.solution.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    )
    .then(|| solver.solution.x[m])
}

/// Rows of `b` (and entries of `g`) multiplied by `scale`: the same problem in other units.
fn rescaled(b: &DMatrix<f64>, g: &[f64], scale: &[f64]) -> (DMatrix<f64>, Vec<f64>) {
    let mut out = b.clone();
    for (r, s) in scale.iter().enumerate() {
        out.row_mut(r).scale_mut(*s);
    }
    (out, g.iter().zip(scale).map(|(v, s)| v * s).collect())
}

/// Today's formula with every facet kept, computed independently: for each group of n - 1
/// columns, the unit normal in the units of `b` (modified Gram-Schmidt on the group, then the
/// coordinate axis with the largest residual, on the well-scaled base matrix) mapped to the units
/// `scale` (normal `D^-1 nu / |D^-1 nu|`, so `d_j` divides by `|D^-1 nu|`). Returns
/// `(d_j, size_j)` per facet in the rescaled units.
fn reference_distances(
    b: &DMatrix<f64>,
    lo: &[f64],
    hi: &[f64],
    g: &[f64],
    scale: &[f64],
) -> Vec<(f64, f64)> {
    let (n, m) = b.shape();
    let mut out = Vec::new();
    for group in rfcore::analysis::combinations::Combinations::new(m, n - 1) {
        let mut basis: Vec<Vec<f64>> = Vec::new();
        for &k in &group {
            let mut v: Vec<f64> = b.column(k).iter().copied().collect();
            for _ in 0..2 {
                for q in &basis {
                    let d: f64 = v.iter().zip(q).map(|(a, b)| a * b).sum();
                    v.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
                }
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm > 1e-6, "random groups are independent");
            basis.push(v.iter().map(|x| x / norm).collect());
        }
        let mut best = vec![0.0; n];
        for axis in 0..n {
            let mut v = vec![0.0; n];
            v[axis] = 1.0;
            for _ in 0..2 {
                for q in &basis {
                    let d: f64 = v.iter().zip(q).map(|(a, b)| a * b).sum();
                    v.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
                }
            }
            if v.iter().map(|x| x * x).sum::<f64>() > best.iter().map(|x| x * x).sum::<f64>() {
                best = v;
            }
        }
        let norm = best.iter().map(|x| x * x).sum::<f64>().sqrt();
        let nu: Vec<f64> = best.iter().map(|x| x / norm).collect();
        let stretch = nu
            .iter()
            .zip(scale)
            .map(|(x, s)| (x / s).powi(2))
            .sum::<f64>()
            .sqrt();
        let proj: Vec<f64> = (0..m)
            .map(|k| (0..n).map(|r| nu[r] * b[(r, k)]).sum())
            .collect();
        let half_width: f64 = (0..m).map(|k| proj[k].abs() * 0.5 * (hi[k] - lo[k])).sum();
        let centre: f64 = (0..m).map(|k| proj[k] * 0.5 * (hi[k] + lo[k])).sum();
        let along_g: f64 = nu.iter().zip(g).map(|(a, b)| a * b).sum();
        let size: f64 = (0..m)
            .map(|k| proj[k].abs() * 0.5 * (hi[k].abs() + lo[k].abs()))
            .sum::<f64>()
            + along_g.abs();
        out.push((
            (half_width - (centre - along_g).abs()) / stretch,
            size / stretch,
        ));
    }
    out
}

/// Every verdict is invariant to rescaling any row, agrees with the LP, and every value equals
/// today's formula (all facets kept) in the user's units. n = 3..6, m = n + 1..n + 2, rows
/// rescaled by 10^-U(0, 8) (ratios up to 1e8), seeded; G at random and G within 1e-5 (relative,
/// along the ray from the centre) of the boundary, inside or outside.
#[test]
fn verdicts_are_unit_free_and_agree_with_an_lp() {
    let mut rng = Rng(0x5eed_0019);
    let mut checked = 0;
    let mut ambiguous = 0;
    let mut outside = 0;
    let mut worst_value_error = 0.0_f64;
    for n in 3..=6 {
        for case in 0..150 {
            let m = n + 1 + case % 2;
            let b = DMatrix::from_fn(n, m, |_, _| rng.uniform(-1.0, 1.0));
            // Boxes [0, 1], and every third case a box reaching below zero (reversible rotors).
            let lo: Vec<f64> = (0..m)
                .map(|_| {
                    if case % 3 == 0 {
                        -rng.uniform(0.0, 0.5)
                    } else {
                        0.0
                    }
                })
                .collect();
            let hi = vec![1.0; m];
            let u: Vec<f64> = (0..m)
                .map(|k| lo[k] + (hi[k] - lo[k]) * rng.uniform(-0.25, 1.25))
                .collect();
            let g: Vec<f64> = (0..n)
                .map(|r| (0..m).map(|k| b[(r, k)] * u[k]).sum())
                .collect();
            // G itself, then G moved along the ray from the centre to within 1e-5 (relative) of
            // the boundary, on a random side.
            let gauge = lp_gauge(&b, &lo, &hi, &g).expect("the LP solves");
            let centre: Vec<f64> = (0..n)
                .map(|r| (0..m).map(|k| b[(r, k)] * 0.5 * (lo[k] + hi[k])).sum())
                .collect();
            let side = if rng.uniform(0.0, 1.0) < 0.5 {
                1.0 - 1e-5
            } else {
                1.0 + 1e-5
            };
            let near: Vec<f64> = (0..n)
                .map(|r| centre[r] + (g[r] - centre[r]) * side / gauge)
                .collect();
            for g in [g.clone(), near] {
                let gauge = lp_gauge(&b, &lo, &hi, &g).expect("the LP solves");
                let mut verdicts = Vec::new();
                for trial in 0..3 {
                    let scale: Vec<f64> = if trial == 0 {
                        vec![1.0; n]
                    } else {
                        (0..n).map(|_| 10f64.powf(-rng.uniform(0.0, 8.0))).collect()
                    };
                    let (bs, gs) = rescaled(&b, &g, &scale);
                    let margin =
                        acai_from_matrix_with_hover(&bs, &lo, &hi, &gs, AcaiFormula::FacetMargin)
                            .unwrap();
                    let eq13 = acai_from_matrix(&bs, &lo, &hi, &gs, AcaiFormula::Eq13).unwrap();
                    assert_ne!(margin.hover, HoverPoint::RankDeficient, "n={n} case={case}");
                    // Values: today's formula in the rescaled units.
                    let reference = reference_distances(&b, &lo, &hi, &g, &scale);
                    let (want, size) =
                        reference
                            .iter()
                            .copied()
                            .fold(
                                (f64::INFINITY, 0.0),
                                |acc, x| if x.0 < acc.0 { x } else { acc },
                            );
                    let want_eq13 = if want >= 0.0 {
                        want
                    } else {
                        -reference
                            .iter()
                            .map(|x| x.0.abs())
                            .fold(f64::INFINITY, f64::min)
                    };
                    for (got, want) in [(margin.acai, want), (eq13, want_eq13)] {
                        let error = (got - want).abs() / size;
                        worst_value_error = worst_value_error.max(error);
                        assert!(
                            error < 1e-8,
                            "n={n} case={case} trial={trial}: {got} vs {want} (size {size})"
                        );
                    }
                    verdicts.push(margin.hover);
                }
                assert!(
                    verdicts.iter().all(|&v| v == verdicts[0]),
                    "n={n} case={case}: {verdicts:?}"
                );
                if (gauge - 1.0).abs() < 1e-6 {
                    ambiguous += 1;
                    continue;
                }
                let lp = if gauge < 1.0 {
                    HoverPoint::Inside
                } else {
                    HoverPoint::Outside
                };
                assert_eq!(verdicts[0], lp, "n={n} case={case}: gauge {gauge}");
                outside += usize::from(lp == HoverPoint::Outside);
                checked += 1;
            }
        }
    }
    eprintln!(
        "{checked} verdicts checked against the LP ({outside} outside), {ambiguous} within 1e-6 of \
         the boundary; worst value error {worst_value_error:.1e} of the facet size"
    );
    assert!(checked >= 1190 && outside >= 300, "{checked} / {outside}");
}

/// The 6 x 7 wrench of issue #19 (forces beside torques): a facet with a small volume in N and
/// N m was dropped and G, 8.8e-4 outside, read +4.41e-5 "inside".
#[test]
fn issue19_mixed_unit_wrench_is_outside() {
    let b = DMatrix::from_row_slice(
        6,
        7,
        &[
            0.0, -7e-4, -5e-4, -1e-4, -9e-4, -3e-4, 1.3e-3, //
            -4e-4, -1.9e-3, -1e-4, -1.3e-3, -1.8e-3, -4e-4, -1e-4, //
            1.2, -0.4, -1.8, -0.9, -0.7, 0.7, -1.4, //
            -3e-4, -2e-4, 1.5e-3, 1.7e-3, 2e-4, -4e-4, -1e-3, //
            -1.6e-3, 6e-4, 1.1e-3, 0.0, -3e-4, -1.1e-3, 8e-4, //
            -9e-2, 1e-2, 8e-2, -4e-2, 6e-2, -5e-2, 6e-2,
        ],
    );
    let g = [2.99e-4, -3.234e-3, -0.957405, 8.63e-4, -1.442e-3, -0.101647];
    let (lo, hi) = ([0.0; 7], [1.0; 7]);
    let gauge = lp_gauge(&b, &lo, &hi, &g).unwrap();
    assert!(gauge > 1.0 + 1e-3, "the LP finds no u: gauge {gauge}");
    for formula in [AcaiFormula::Eq13, AcaiFormula::FacetMargin] {
        let result = acai_from_matrix_with_hover(&b, &lo, &hi, &g, formula).unwrap();
        assert_eq!(result.hover, HoverPoint::Outside, "{formula:?}: {result:?}");
        assert!(result.acai < 0.0, "{formula:?}: {result:?}");
    }
    // In units where every row is O(1) (and back), the same verdict.
    let scale = [1e3, 1e3, 1.0, 1e3, 1e3, 10.0];
    let (bs, gs) = rescaled(&b, &g, &scale);
    let result = acai_from_matrix_with_hover(&bs, &lo, &hi, &gs, AcaiFormula::Eq13).unwrap();
    assert_eq!(result.hover, HoverPoint::Outside);
}

/// A quadrotor with 1e-5 m arms was "rank deficient" (-inf); the answer is +9.9e-6.
#[test]
fn issue19_tiny_quadrotor_is_full_rank() {
    let (a, k) = (1e-5, 1e-6);
    let b = DMatrix::from_row_slice(
        4,
        4,
        &[1.0, 1.0, 1.0, 1.0, -a, a, a, -a, a, a, -a, -a, k, -k, k, -k],
    );
    let (lo, hi, g) = ([0.0; 4], [6.0; 4], [10.0, 0.0, 0.0, 0.0]);
    let result = acai_from_matrix_with_hover(&b, &lo, &hi, &g, AcaiFormula::Eq13).unwrap();
    assert_eq!(result.hover, HoverPoint::Inside, "{result:?}");
    let want = reference_distances(&b, &lo, &hi, &g, &[1.0; 4])
        .iter()
        .map(|x| x.0)
        .fold(f64::INFINITY, f64::min);
    assert!((want - 9.9e-6).abs() < 0.05e-6, "{want}");
    assert!(
        (result.acai / want - 1.0).abs() < 1e-9,
        "{} vs {want}",
        result.acai
    );
    // The same vehicle through a preset-style airframe: rank B_f = 4, controllable.
    let text = preset_text("quad-x.toml")
        .replace("arm_length_m = 0.275", "arm_length_m = 1e-5")
        .replace("drag_torque_ratio_m = 0.1", "drag_torque_ratio_m = 1e-7");
    let airframe = Airframe::from_toml_str(&text, "tiny quad").unwrap();
    let analysis =
        ControllabilityAnalysis::new(&airframe, ControlAxes::ThrustRollPitchYaw).unwrap();
    let report = analysis.report(&[1.0; 4], AcaiFormula::Eq13).unwrap();
    assert_eq!(report.effectiveness_rank, 4, "{report:?}");
    assert_eq!(report.verdict, Verdict::Controllable, "{report:?}");
    assert!(report.acai > 0.0);
}

/// Item 6: rank C(A, B) read J/m <= 1e-9 as uncontrollable. Inertias from 1e-14 to 1e12 kg m^2
/// (J/m from 1e-14 to 1e12) all give rank 2n.
#[test]
fn controllability_rank_is_unit_free() {
    for inertia in [
        "[4.11e-14, 4.78e-14, 5.99e-14]",
        "[4.11e12, 4.78e12, 5.99e12]",
    ] {
        let text = preset_text("quad-x.toml").replace(
            "inertia_kg_m2 = [0.0411, 0.0478, 0.0599]",
            &format!("inertia_kg_m2 = {inertia}"),
        );
        let airframe = Airframe::from_toml_str(&text, "odd inertia").unwrap();
        for axes in [
            ControlAxes::ThrustRollPitchYaw,
            ControlAxes::ThrustRollPitch,
        ] {
            let (a, b) = hover_model(&airframe, axes);
            let c = controllability_matrix(&a, &b);
            let n = axes.dimension();
            assert!(
                numerical_rank(&c).unwrap() < 2 * n,
                "the plain SVD rank misreads it"
            );
            assert_eq!(scale_free_rank(&c, "C").unwrap(), 2 * n, "{inertia}");
            let analysis = ControllabilityAnalysis::new(&airframe, axes).unwrap();
            let report = analysis.report(&[1.0; 4], AcaiFormula::Eq13).unwrap();
            assert_eq!(report.controllability_rank, 2 * n, "{inertia} {axes:?}");
            assert_eq!(report.verdict, Verdict::Controllable, "{inertia} {axes:?}");
        }
    }
    // A genuinely deficient matrix stays deficient whatever its scaling.
    let deficient =
        DMatrix::from_row_slice(3, 3, &[1e-12, 2e-12, 0.0, 1e6, 2e6, 0.0, 0.0, 0.0, 3.0]);
    assert_eq!(scale_free_rank(&deficient, "m").unwrap(), 2);
    assert_eq!(scale_free_rank(&DMatrix::zeros(2, 3), "m").unwrap(), 0);
}

/// Item 2: every ACAI can carry where G lies. Du Table III's 0 for PPNNPN with rotor 5 failed is
/// flagged outside; so is the -0.0004 of a degraded vehicle whose hover point is far outside.
#[test]
fn acai_carries_the_hover_verdict() {
    let airframe = preset("hexa-ppnnpn");
    let analysis =
        ControllabilityAnalysis::new(&airframe, ControlAxes::ThrustRollPitchYaw).unwrap();
    let rotor5 = [1.0, 1.0, 1.0, 1.0, 0.0, 1.0];
    let result = analysis
        .acai_with_hover(&rotor5, AcaiFormula::Eq13)
        .unwrap();
    assert_eq!(result.acai, 0.0);
    assert_eq!(result.hover, HoverPoint::Outside);
    assert!(!result.hover.is_attainable());
    let degraded = [0.621, 0.001, 0.0, 0.919, 0.455, 0.764];
    let eq13 = analysis
        .acai_with_hover(&degraded, AcaiFormula::Eq13)
        .unwrap();
    let margin = analysis
        .acai_with_hover(&degraded, AcaiFormula::FacetMargin)
        .unwrap();
    assert!(eq13.acai < -0.0004 && eq13.acai > -0.0006, "{eq13:?}");
    eprintln!("eq. (13) {} facet margin {}", eq13.acai, margin.acai);
    assert_eq!(eq13.hover, HoverPoint::Outside);
    assert_eq!(margin.hover, HoverPoint::Outside);
    assert!(margin.acai < -0.5, "{margin:?}");
    // Du Table II: PNPNPN single failures are on the boundary; healthy is inside; three failed
    // rotors cannot span four axes.
    let pnpnpn =
        ControllabilityAnalysis::new(&preset("hexa-pnpnpn"), ControlAxes::ThrustRollPitchYaw)
            .unwrap();
    let on = pnpnpn
        .acai_with_hover(&[0.0, 1.0, 1.0, 1.0, 1.0, 1.0], AcaiFormula::Eq13)
        .unwrap();
    assert_eq!((on.acai, on.hover), (0.0, HoverPoint::OnBoundary));
    assert!(on.hover.is_attainable());
    let healthy = pnpnpn
        .acai_with_hover(&[1.0; 6], AcaiFormula::Eq13)
        .unwrap();
    assert_eq!(healthy.hover, HoverPoint::Inside);
    let three = analysis
        .acai_with_hover(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], AcaiFormula::Eq13)
        .unwrap();
    assert_eq!(
        (three.acai, three.hover),
        (f64::NEG_INFINITY, HoverPoint::RankDeficient)
    );
}

/// The batch with hover equals the single evaluations and the plain batch, bit for bit, and the
/// report's hover field, verdict and ranks agree with it (one rank rule).
#[test]
fn batch_with_hover_matches_single_evaluations_and_reports() {
    let mut rng = Rng(19);
    for name in ["hexa-ppnnpn", "hexa-pnpnpn", "quad-x", "octo-x"] {
        let airframe = preset(name);
        let m = airframe.rotor_count();
        for axes in [
            ControlAxes::ThrustRollPitchYaw,
            ControlAxes::ThrustRollPitch,
        ] {
            let analysis = ControllabilityAnalysis::new(&airframe, axes).unwrap();
            let etas: Vec<f64> = (0..300 * m)
                .map(|_| {
                    let e = rng.uniform(-0.3, 1.0);
                    if e < 0.0 {
                        0.0
                    } else {
                        e
                    }
                })
                .collect();
            for formula in [AcaiFormula::Eq13, AcaiFormula::FacetMargin] {
                let batch = analysis
                    .acai_batch_with_hover(&etas, formula, &Cancel::never())
                    .unwrap();
                let plain = analysis
                    .acai_batch(&etas, formula, &Cancel::never())
                    .unwrap();
                assert_eq!(batch.acai.len(), 300);
                for (i, eta) in etas.chunks(m).enumerate() {
                    let single = analysis.acai_with_hover(eta, formula).unwrap();
                    assert_eq!(batch.acai[i].to_bits(), single.acai.to_bits());
                    assert_eq!(plain[i].to_bits(), single.acai.to_bits());
                    assert_eq!(batch.hover[i], single.hover);
                    let report = analysis.report(eta, formula).unwrap();
                    assert_eq!(report.hover, single.hover);
                    assert_eq!(report.acai.to_bits(), single.acai.to_bits());
                    let n = axes.dimension();
                    assert_eq!(
                        report.effectiveness_rank == n,
                        single.hover != HoverPoint::RankDeficient,
                        "{name} {eta:?}"
                    );
                    let want = match single.hover {
                        HoverPoint::Inside => Verdict::Controllable,
                        HoverPoint::OnBoundary => Verdict::HoverOnBoundary,
                        HoverPoint::Outside => Verdict::HoverOutside,
                        HoverPoint::RankDeficient => Verdict::EffectivenessRankDeficient,
                    };
                    assert_eq!(report.verdict, want);
                    // Eq. (13) and the facet margin never disagree on the sign class.
                    if single.hover == HoverPoint::Inside {
                        assert!(single.acai > 0.0);
                    }
                }
            }
        }
    }
}

/// How often eq. (13) prints a bare 0 where hover is infeasible in the presets' failure tables (up
/// to 3 failed rotors, with and without yaw): every infeasible case is flagged outside.
#[test]
fn failure_tables_flag_every_infeasible_hover() {
    let (mut infeasible, mut bare_zero, mut total) = (0, 0, 0);
    for name in [
        "hexa-ppnnpn",
        "hexa-pnpnpn",
        "quad-x",
        "quad-plus",
        "octo-x",
    ] {
        let airframe = preset(name);
        let max_failed = 3.min(airframe.rotor_count());
        for case in
            failure_table(&airframe, max_failed, AcaiFormula::Eq13, &Cancel::never()).unwrap()
        {
            for report in [&case.all_axes, &case.give_up_yaw] {
                total += 1;
                if report.hover == HoverPoint::Outside {
                    infeasible += 1;
                    bare_zero += usize::from(report.acai == 0.0);
                    assert_eq!(report.verdict, Verdict::HoverOutside);
                } else {
                    assert!(report.acai >= 0.0 || report.acai == f64::NEG_INFINITY);
                }
            }
        }
    }
    eprintln!(
        "{total} reports, {infeasible} with hover infeasible, {bare_zero} of them eq. (13) = 0"
    );
    // The figures of issue #19.
    assert_eq!((infeasible, bare_zero), (104, 72));
}

/// A batch's compact column reads back: every hover point from its code, any other code refused
/// naming the field (Python's `AcaiBatch(acai, hover_code)` and its pickles go through it).
#[test]
fn hover_codes_read_back_and_other_codes_are_refused() {
    for hover in [
        HoverPoint::Inside,
        HoverPoint::OnBoundary,
        HoverPoint::Outside,
        HoverPoint::RankDeficient,
    ] {
        assert_eq!(
            HoverPoint::from_code("hover_code", i64::from(hover.code())).unwrap(),
            hover
        );
    }
    for bad in [2, -3, 300, i64::MIN] {
        let message = HoverPoint::from_code("hover_code[4]", bad)
            .unwrap_err()
            .to_string();
        assert!(
            message.starts_with("hover_code[4]: must be a hover code")
                && message.ends_with(&format!("got {bad}")),
            "{message}"
        );
    }
}
