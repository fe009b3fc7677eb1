//! The active-set allocator against Clarabel on 10,000 random problems, plus its KKT conditions,
//! warm starts and the unconstrained limits of Ke et al. eqs. (34)/(35).

use nalgebra::DMatrix;
use rfcore::allocation::active_set::{ActiveSet, ActiveSetSolver, BoundState};
use rfcore::allocation::allocate_clarabel;
use rfcore::allocation::clarabel::ClarabelSettings;
use rfcore::allocation::{allocate_pinv, AllocationProblem, AllocationStatus};
use rfcore::fixtures::{ill_conditioned_allocation, Rng};

struct Case {
    problem: AllocationProblem,
    u_c: Vec<f64>,
}

/// Random problems per the issue: m = 4..8, n = 3..6 (4 with Ke's weights), full and deficient
/// rank, log-uniform or Ke's weights, random (sometimes degenerate) bounds, attainable and
/// unattainable virtual controls, a quarter with regularisation.
fn random_case(rng: &mut Rng) -> Case {
    let m = 4 + rng.below(5);
    let ke_weights = rng.below(4) == 0;
    let n = if ke_weights { 4 } else { 3 + rng.below(4) };
    let deficient = rng.below(3) == 0;
    let matrix = if deficient {
        let rank = 1 + rng.below(n.min(m) - 1);
        let a = DMatrix::from_fn(n, rank, |_, _| rng.uniform(-1.0, 1.0));
        let b = DMatrix::from_fn(rank, m, |_, _| rng.uniform(-1.0, 1.0));
        a * b
    } else {
        DMatrix::from_fn(n, m, |_, _| rng.uniform(-1.0, 1.0))
    };
    let weights: Vec<f64> = if ke_weights {
        vec![20.0, 20.0, 1.0, 0.01]
    } else {
        (0..n).map(|_| 10f64.powf(rng.uniform(-2.0, 2.0))).collect()
    };
    let lower: Vec<f64> = (0..m).map(|_| rng.uniform(-2.0, 1.0)).collect();
    let upper: Vec<f64> = lower
        .iter()
        .map(|&lo| {
            if rng.below(20) == 0 {
                lo
            } else {
                lo + rng.uniform(0.1, 5.0)
            }
        })
        .collect();
    let inside: Vec<f64> = (0..m).map(|i| rng.uniform(lower[i], upper[i])).collect();
    let mut u_c: Vec<f64> = (0..n)
        .map(|r| (0..m).map(|c| matrix[(r, c)] * inside[c]).sum())
        .collect();
    if rng.below(2) == 0 {
        // Unattainable: stretch and perturb an attainable point.
        for u in u_c.iter_mut() {
            *u = 3.0 * *u + rng.uniform(-2.0, 2.0);
        }
    }
    let mut problem = AllocationProblem::new(matrix, &weights, &lower, &upper).unwrap();
    if rng.below(4) == 0 {
        let preferred: Vec<f64> = (0..m).map(|_| rng.uniform(-1.0, 2.0)).collect();
        problem = problem
            .with_regularization(10f64.powf(rng.uniform(-4.0, -1.0)), &preferred)
            .unwrap();
    }
    Case { problem, u_c }
}

/// The objective's natural scale: its value at the bounded point nearest zero.
fn objective_scale(case: &Case) -> f64 {
    let p = &case.problem;
    let origin: Vec<f64> = (0..p.actuator_count())
        .map(|i| 0.0f64.clamp(p.lower()[i], p.upper()[i]))
        .collect();
    p.objective(&case.u_c, &origin).max(f64::MIN_POSITIVE)
}

/// True when the solution is unique and well-posed: the Hessian restricted to the strictly free
/// variables has curvature at least 1e-3 of its largest entry, and every bound held has a clearly
/// positive multiplier (then any other minimiser would have to move a held variable against a
/// positive gradient). The conditioning requirement is about the reference, not the solver: an
/// interior-point answer accurate to `delta` in the objective is only accurate to about
/// `sqrt(2 delta / curvature)` in T, so nearly flat directions cannot be compared to 1e-6.
fn unique(problem: &AllocationProblem, u_c: &[f64], t: &[f64]) -> bool {
    let h = problem.hessian();
    let g = problem.gradient(u_c, t);
    let scale = h.amax();
    let span = |i: usize| problem.upper()[i] - problem.lower()[i];
    let mut free = Vec::new();
    for i in 0..t.len() {
        let at_lower = t[i] - problem.lower()[i] <= 1e-7 * span(i).max(1.0);
        let at_upper = problem.upper()[i] - t[i] <= 1e-7 * span(i).max(1.0);
        if span(i) == 0.0 {
            continue;
        }
        if at_lower && g[i] <= 1e-3 * scale {
            return false;
        }
        if at_upper && g[i] >= -1e-3 * scale {
            return false;
        }
        if !at_lower && !at_upper {
            free.push(i);
        }
    }
    if free.is_empty() {
        return true;
    }
    let sub = DMatrix::from_fn(free.len(), free.len(), |a, b| h[(free[a], free[b])]);
    sub.symmetric_eigenvalues().min() > 1e-3 * scale
}

#[test]
fn active_set_matches_clarabel_on_10000_random_problems() {
    let mut rng = Rng(20261122);
    let settings = ClarabelSettings::default().tolerance(1e-12).unwrap();
    let (mut compared, mut optimal_clarabel) = (0, 0);
    let mut worst = (0.0f64, 0.0f64, 0.0f64, f64::NEG_INFINITY);
    for trial in 0..10_000 {
        let case = random_case(&mut rng);
        let p = &case.problem;
        let exact = ActiveSetSolver::new(p).allocate(&case.u_c).unwrap();
        assert_eq!(exact.status, AllocationStatus::Optimal, "trial {trial}");
        let bound_scale = p
            .lower()
            .iter()
            .chain(p.upper())
            .fold(0.0f64, |a, b| a.max(b.abs()));
        let kkt = p.kkt_residual(&case.u_c, &exact.commands);
        assert!(
            kkt <= 1e-9 * bound_scale,
            "trial {trial}: KKT residual {kkt}"
        );
        worst.0 = worst.0.max(kkt / bound_scale);

        let reference = allocate_clarabel(p, &case.u_c, &settings).unwrap();
        if reference.status != AllocationStatus::Optimal {
            continue;
        }
        optimal_clarabel += 1;
        let f_exact = p.objective(&case.u_c, &exact.commands);
        let f_ref = p.objective(&case.u_c, &reference.commands);
        let scale = f_ref.max(objective_scale(&case));
        let gap = (f_exact - f_ref) / scale;
        assert!(
            gap.abs() <= 1e-9,
            "trial {trial}: objective {f_exact} vs clarabel {f_ref}"
        );
        // The exact solver is never worse than the interior-point reference beyond rounding.
        assert!(
            gap <= 1e-12,
            "trial {trial}: objective {f_exact} above clarabel's {f_ref}"
        );
        worst.1 = worst.1.max(gap.abs());
        worst.3 = worst.3.max(gap);
        if unique(p, &case.u_c, &exact.commands) {
            compared += 1;
            for (a, b) in exact.commands.iter().zip(&reference.commands) {
                assert!(
                    (a - b).abs() <= 1e-6,
                    "trial {trial}: T {a} vs clarabel {b}"
                );
                worst.2 = worst.2.max((a - b).abs());
            }
        }
    }
    eprintln!(
        "clarabel optimal on {optimal_clarabel}; T compared on {compared} unique solutions; \
         worst KKT/bound {:.1e}, objective gap {:.1e} (largest excess over clarabel {:.1e}), \
         |dT| {:.1e}",
        worst.0, worst.1, worst.3, worst.2
    );
    assert!(
        optimal_clarabel >= 9_900,
        "clarabel solved only {optimal_clarabel}"
    );
    assert!(
        compared >= 3_000,
        "only {compared} unique solutions compared"
    );
}

#[test]
fn warm_start_from_the_previous_active_set_is_nearly_free() {
    // Re-solving from the active set a solve returns takes one iteration unless a bound is held
    // with a zero multiplier (degenerate): those are released once more at the end (the tie
    // rule), which costs a step.
    let mut rng = Rng(7);
    let (mut one, mut most) = (0, 0);
    for _ in 0..500 {
        let case = random_case(&mut rng);
        let solver = ActiveSetSolver::new(&case.problem);
        let m = case.problem.actuator_count();
        let mut active = ActiveSet::cold(m);
        let mut cold = vec![0.0; m];
        solver.solve(&case.u_c, &mut active, &mut cold).unwrap();
        let mut warm = vec![0.0; m];
        let report = solver.solve(&case.u_c, &mut active, &mut warm).unwrap();
        assert_eq!(report.status, AllocationStatus::Optimal);
        // Phase 1 confirms in one iteration; phase 2 (the tie rule) may take one more.
        one += usize::from(report.iterations <= 2);
        most = most.max(report.iterations);
        let f_cold = case.problem.objective(&case.u_c, &cold);
        let f_warm = case.problem.objective(&case.u_c, &warm);
        assert!((f_cold - f_warm).abs() <= 1e-12 * objective_scale(&case).max(f_cold));
    }
    eprintln!("warm re-solve: {one}/500 in one iteration, at most {most}");
    assert!(one >= 300, "{one}");
    assert!(most <= 10, "{most}");
}

#[test]
fn a_stale_warm_start_still_reaches_the_optimum() {
    let mut rng = Rng(11);
    for _ in 0..500 {
        let case = random_case(&mut rng);
        let m = case.problem.actuator_count();
        let solver = ActiveSetSolver::new(&case.problem);
        let mut active = ActiveSet::cold(m);
        let mut scratch = vec![0.0; m];
        // An unrelated active set: every variable held at its upper bound.
        let upper_everywhere: Vec<f64> = case.problem.upper().to_vec();
        let mut stale = ActiveSet::cold(m);
        let stale_solver = ActiveSetSolver::new(&case.problem);
        let target: Vec<f64> = case.problem.achieved(&upper_everywhere);
        stale_solver
            .solve(&target, &mut stale, &mut scratch)
            .unwrap();
        let report = solver.solve(&case.u_c, &mut stale, &mut scratch).unwrap();
        assert_eq!(report.status, AllocationStatus::Optimal);
        let cold = solver.allocate(&case.u_c).unwrap();
        let (fs, fc) = (
            case.problem.objective(&case.u_c, &scratch),
            case.problem.objective(&case.u_c, &cold.commands),
        );
        assert!((fs - fc).abs() <= 1e-11 * objective_scale(&case).max(fc));
        let _ = &mut active;
    }
}

fn ke_matrix() -> DMatrix<f64> {
    // A Ke-like M (eq. (2), Table III values) in one rank-4 reading: Remark 2's angles with a yaw
    // row that matches them. These tests only need a Ke-like matrix, not the preset's numbering.
    let (l, c) = (0.125, 0.0166);
    let s = std::f64::consts::FRAC_1_SQRT_2;
    DMatrix::from_row_slice(
        4,
        4,
        &[
            1.0,
            1.0,
            1.0,
            1.0,
            -l * s,
            l * s,
            l * s,
            -l * s,
            l * s,
            -l * s,
            l * s,
            -l * s,
            c,
            c,
            -c,
            -c,
        ],
    )
}

#[test]
fn ke_eq34_equal_weights_give_the_moore_penrose_solution() {
    let m = ke_matrix();
    let problem = AllocationProblem::new(m.clone(), &[1.0; 4], &[0.0; 4], &[8.5; 4]).unwrap();
    let u_c = [7.0, 0.05, -0.08, 0.01];
    let exact = ActiveSetSolver::new(&problem).allocate(&u_c).unwrap();
    let pinv = m.clone().pseudo_inverse(1e-14).unwrap() * DMatrix::from_column_slice(4, 1, &u_c);
    assert!(
        exact.commands.iter().all(|&t| t > 0.0 && t < 8.5),
        "no bound active"
    );
    for i in 0..4 {
        assert!(
            (exact.commands[i] - pinv[(i, 0)]).abs() <= 1e-12,
            "{:?} vs {pinv}",
            exact.commands
        );
    }
    // Any equal weights give the same answer (Remark 7).
    let scaled = AllocationProblem::new(m, &[37.0; 4], &[0.0; 4], &[8.5; 4]).unwrap();
    let again = ActiveSetSolver::new(&scaled).allocate(&u_c).unwrap();
    for i in 0..4 {
        assert!((again.commands[i] - exact.commands[i]).abs() <= 1e-12);
    }
}

#[test]
fn ke_eq35_zero_yaw_weight_gives_the_pseudo_inverse_of_e1_m() {
    let m = ke_matrix();
    let e1m = m.rows(0, 3).into_owned();
    for &weights in &[
        [20.0, 20.0, 20.0, 0.0],
        [1.0, 20.0, 20.0, 0.0],
        [3.0, 1.0, 7.0, 0.0],
    ] {
        let problem = AllocationProblem::new(m.clone(), &weights, &[0.0; 4], &[8.5; 4]).unwrap();
        let u_c = [7.0, 0.05, -0.08, 0.3]; // the yaw entry is ignored with weight 0
        let expected = e1m.clone().pseudo_inverse(1e-14).unwrap()
            * DMatrix::from_column_slice(3, 1, &u_c[..3]);
        for method in ["active-set", "pinv"] {
            let got = if method == "pinv" {
                allocate_pinv(&problem, &u_c).unwrap()
            } else {
                ActiveSetSolver::new(&problem).allocate(&u_c).unwrap()
            };
            assert!(got.commands.iter().all(|&t| t > 0.0 && t < 8.5));
            for i in 0..4 {
                assert!(
                    (got.commands[i] - expected[(i, 0)]).abs() <= 1e-12,
                    "{method} {weights:?}: {:?} vs {expected}",
                    got.commands
                );
            }
        }
    }
}

#[test]
fn pinv_counts_every_positive_weight() {
    // Issue 20: the pseudo-inverse's rank rule on M^T W M dropped the yaw axis at w_r = 1e-9
    // (yaw 0 of 0.05 asked). With M invertible (n = m) the weighted least-squares answer is
    // M^-1 u_c for every positive weight; with n < m and full row rank, M^+ u_c (the residual is
    // zero, the minimum-norm rule picks the rest). Both against nalgebra's SVD pseudo-inverse.
    let m = ke_matrix();
    let u_c = [7.0, 0.05, -0.08, 0.05];
    let expected =
        m.clone().pseudo_inverse(1e-14).unwrap() * DMatrix::from_column_slice(4, 1, &u_c);
    for w_r in [1.0, 1e-6, 1e-9, 1e-12] {
        let problem =
            AllocationProblem::new(m.clone(), &[1.0, 20.0, 20.0, w_r], &[0.0; 4], &[8.5; 4])
                .unwrap();
        let got = allocate_pinv(&problem, &u_c).unwrap();
        for i in 0..4 {
            assert!(
                (got.commands[i] - expected[(i, 0)]).abs() <= 1e-12,
                "w_r {w_r}: {:?}",
                got.commands
            );
        }
    }
    // A 4 x 6 matrix with weights over 14 decades.
    let mut rng = Rng(20);
    let wide = DMatrix::from_fn(4, 6, |_, _| rng.uniform(-1.0, 1.0));
    let u_c = [12.55, 0.1, -0.05, 0.02];
    let expected =
        wide.clone().pseudo_inverse(1e-14).unwrap() * DMatrix::from_column_slice(4, 1, &u_c);
    let problem =
        AllocationProblem::new(wide, &[2.5e-8, 2.2e6, 2.3e-7, 1e7], &[-1e3; 6], &[1e3; 6]).unwrap();
    let got = allocate_pinv(&problem, &u_c).unwrap();
    for i in 0..6 {
        assert!(
            (got.commands[i] - expected[(i, 0)]).abs() <= 1e-11,
            "{:?} vs {expected}",
            got.commands
        );
    }
}

#[test]
fn ke_small_yaw_weight_sacrifices_yaw_first_when_rotors_saturate() {
    // Ke Section III.E: w_p = w_q >> w_f >> w_r. With an unattainable yaw demand, roll and pitch
    // are met ever more exactly as w_r shrinks (towards eq. (35)), and yaw takes the shortfall.
    let m = ke_matrix();
    let u_c = [7.0, 0.05, -0.08, 0.5];
    let mut previous = f64::INFINITY;
    for w_r in [1.0, 1e-1, 1e-2, 1e-3] {
        let problem =
            AllocationProblem::new(m.clone(), &[1.0, 20.0, 20.0, w_r], &[0.0; 4], &[8.5; 4])
                .unwrap();
        let got = ActiveSetSolver::new(&problem).allocate(&u_c).unwrap();
        let roll_pitch_error = (got.achieved[1] - u_c[1])
            .abs()
            .max((got.achieved[2] - u_c[2]).abs());
        assert!(
            roll_pitch_error < previous,
            "w_r {w_r}: {roll_pitch_error} after {previous}"
        );
        assert!(got.achieved[3] < u_c[3], "yaw is the axis that gives");
        previous = roll_pitch_error;
    }
    assert!(previous < 1e-4);
}

#[test]
#[allow(clippy::needless_range_loop)]
fn fixed_variables_are_held_and_iteration_bound_reports() {
    let m = ke_matrix();
    let problem =
        AllocationProblem::new(m, &[1.0; 4], &[0.0, 2.0, 0.0, 0.0], &[8.5, 2.0, 8.5, 8.5]).unwrap();
    let got = ActiveSetSolver::new(&problem)
        .allocate(&[30.0, 0.5, 0.5, 0.1])
        .unwrap();
    assert_eq!(got.commands[1], 2.0);
    let limited = ActiveSetSolver::new(&problem)
        .with_max_iterations(1)
        .unwrap()
        .with_fallback(false);
    let mut active = ActiveSet::cold(4);
    let mut t = [0.0; 4];
    let report = limited
        .solve(&[30.0, 0.5, 0.5, 0.1], &mut active, &mut t)
        .unwrap();
    // Optimal exactly when the certificate holds, whatever the budget.
    assert_eq!(
        report.status == AllocationStatus::Optimal,
        report.certificate.holds()
    );
    for i in 0..4 {
        assert!(t[i] >= problem.lower()[i] && t[i] <= problem.upper()[i]);
    }
    assert!(
        active.states().contains(&BoundState::Upper)
            || active.states().contains(&BoundState::Lower)
    );
}

#[test]
fn a_huge_bound_does_not_blunt_the_optimality_test() {
    // Review finding: the multiplier tolerance used to grow with the largest bound, so a 1e12
    // "no limit" bound left a wrongly held bound in place and reported it optimal.
    let m = DMatrix::from_row_slice(2, 2, &[0.6, -1.0, 0.3, -2.7]);
    for big in [1e6, 1e12, 1e300] {
        let p = AllocationProblem::new(m.clone(), &[1.0, 1.0], &[0.0, 0.0], &[1.0, big]).unwrap();
        let got = ActiveSetSolver::new(&p).allocate(&[-0.3, 1.8]).unwrap();
        assert_eq!(got.status, AllocationStatus::Optimal);
        assert!(
            (got.commands[0] - 0.8).abs() < 1e-12,
            "{big}: {:?}",
            got.commands
        );
        assert!(got.commands[1].abs() < 1e-12);
    }
}

#[test]
fn degenerate_bounds_are_not_carried_into_the_next_solve() {
    // Review finding: a rotor held at a bound with a zero multiplier stayed there for good under
    // warm starts. Here u_c is reachable with rotor 1 at zero or not; the cold answer (closest to
    // zero) must be reproduced after a warm start from a solve that pinned rotor 1.
    let m = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
    let p = AllocationProblem::new(m, &[1.0], &[0.0, 0.0], &[10.0, 10.0]).unwrap();
    let solver = ActiveSetSolver::new(&p);
    let mut active = ActiveSet::cold(2);
    let mut t = [0.0; 2];
    // A demand that drives rotor 1 to its lower bound is impossible here, so pin it by hand.
    active = {
        let mut a = active;
        solver.solve(&[-1.0], &mut a, &mut t).unwrap(); // both at 0, multipliers positive
        a
    };
    assert!(active.states().iter().all(|s| *s == BoundState::Lower));
    solver.solve(&[3.0], &mut active, &mut t).unwrap();
    assert!(
        (t[0] - 1.5).abs() < 1e-12 && (t[1] - 1.5).abs() < 1e-12,
        "{t:?}"
    );
}

// ---- Issue #20: allocation that is never silently wrong ----

use rfcore::allocation::active_set::ActiveSetSettings;
use rfcore::allocation::allocate_clarabel_unpolished;
use rfcore::allocation::{allocate_many, fallback_count, Method, SolvedBy};
use rfcore::{Airframe, Cancel};

fn preset(name: &str) -> Airframe {
    rfcore::fixtures::preset(name)
}

/// Ours against unpolished Clarabel (tolerance 1e-12): never worse in the objective beyond
/// `rel` of the objective's scale. Returns the relative excess.
fn excess_over_clarabel(p: &AllocationProblem, u_c: &[f64], t: &[f64]) -> f64 {
    let settings = ClarabelSettings::default().tolerance(1e-12).unwrap();
    let reference = allocate_clarabel_unpolished(p, u_c, &settings).unwrap();
    let f = p.objective(u_c, t);
    let f_ref = p.objective(u_c, &reference.commands);
    let origin: Vec<f64> = (0..p.actuator_count())
        .map(|i| 0.0f64.clamp(p.lower()[i], p.upper()[i]))
        .collect();
    let scale = f_ref.max(p.objective(u_c, &origin)).max(f64::MIN_POSITIVE);
    (f - f_ref) / scale
}

/// The ill-conditioned class: 4 x m (m = 4..8), M standard normal, weights in
/// [0.01, 30], upper bounds in [1, 8], v = M times a point slightly outside the box, one column
/// scaled by 10^-k (k = 4..12). Every answer certified, never worse than Clarabel; fallbacks
/// counted (goal 0 for k <= 9).
#[test]
fn ill_conditioned_columns_are_certified_and_exact() {
    let mut rng = Rng(2020);
    let mut fallbacks = [0usize; 13];
    let mut worst = 0.0f64;
    for k in 4usize..=12 {
        for trial in 0..200 {
            let (p, u_c) = ill_conditioned_allocation(&mut rng, k as i32);
            let got = ActiveSetSolver::new(&p).allocate(&u_c).unwrap();
            assert_eq!(got.status, AllocationStatus::Optimal, "k {k} trial {trial}");
            assert!(
                got.certificate.holds(),
                "k {k} trial {trial}: {:?}",
                got.certificate
            );
            let excess = excess_over_clarabel(&p, &u_c, &got.commands);
            assert!(excess <= 1e-9, "k {k} trial {trial}: excess {excess:e}");
            worst = worst.max(excess);
            fallbacks[k] += usize::from(got.solved_by == SolvedBy::Clarabel);
        }
    }
    eprintln!(
        "fallbacks per k (4..12, of 200): {:?}; worst excess {worst:e}",
        &fallbacks[4..]
    );
    assert_eq!(fallbacks[4..=9].iter().sum::<usize>(), 0, "{fallbacks:?}");
}

/// The wide class: n = 3..6, m = 4..16, each column's gain 10^-12..1 (some exactly zero),
/// weights 10^-9..10^9, unidirectional and bidirectional bounds, attainable and unattainable
/// virtual controls. Every result certified and never worse than Clarabel (1e-9 relative).
#[test]
fn property_wide_class_is_certified_and_never_worse_than_clarabel() {
    let mut rng = Rng(4242);
    let (mut fallbacks, mut worst) = (0, 0.0f64);
    for trial in 0..1500 {
        let n = 3 + rng.below(4);
        let m = 4 + rng.below(13);
        let mut matrix = DMatrix::from_fn(n, m, |_, _| rng.normal());
        for c in 0..m {
            let gain = match rng.below(6) {
                0 => 0.0,
                1 | 2 => 10f64.powf(rng.uniform(-12.0, 0.0)),
                _ => 1.0,
            };
            for r in 0..n {
                matrix[(r, c)] *= gain;
            }
        }
        let weights: Vec<f64> = (0..n).map(|_| 10f64.powf(rng.uniform(-9.0, 9.0))).collect();
        let bidirectional = rng.below(2) == 0;
        let upper: Vec<f64> = (0..m).map(|_| rng.uniform(1.0, 8.0)).collect();
        let lower: Vec<f64> = upper
            .iter()
            .map(|&h| if bidirectional { -h } else { 0.0 })
            .collect();
        let stretch = if rng.below(2) == 0 { 1.0 } else { 3.0 };
        let point: Vec<f64> = (0..m)
            .map(|i| stretch * rng.uniform(lower[i], upper[i]))
            .collect();
        let u_c: Vec<f64> = (0..n)
            .map(|r| (0..m).map(|c| matrix[(r, c)] * point[c]).sum())
            .collect();
        let p = AllocationProblem::new(matrix, &weights, &lower, &upper).unwrap();
        let got = ActiveSetSolver::new(&p).allocate(&u_c).unwrap();
        assert_eq!(got.status, AllocationStatus::Optimal, "trial {trial}");
        assert!(
            got.certificate.holds(),
            "trial {trial}: {:?}",
            got.certificate
        );
        let excess = excess_over_clarabel(&p, &u_c, &got.commands);
        assert!(excess <= 1e-9, "trial {trial}: excess {excess:e}");
        worst = worst.max(excess);
        fallbacks += usize::from(got.solved_by == SolvedBy::Clarabel);
    }
    eprintln!("wide class: {fallbacks}/1500 fallbacks, worst excess {worst:e}");
}

fn ke_preset_problem(weights: &[f64]) -> (Airframe, AllocationProblem) {
    let ke = preset("ke-quadcopter");
    let p = AllocationProblem::new(
        ke.effectiveness_matrix(),
        weights,
        &ke.min_thrust_n(),
        &ke.max_thrust_n(),
    )
    .unwrap();
    (ke, p)
}

#[test]
fn regression_small_weights_are_not_dropped() {
    // Issue #20: yaw weight 1e-9 gave yaw 0.000 of 0.05, commands 0.753 N off.
    let u_c = [7.0, 0.05, -0.08, 0.05];
    for w_yaw in [1e-6, 1e-7, 1e-9] {
        let (_, p) = ke_preset_problem(&[1.0, 20.0, 20.0, w_yaw]);
        let exact =
            p.matrix().clone().try_inverse().unwrap() * DMatrix::from_column_slice(4, 1, &u_c);
        assert!((0..4).all(|i| exact[i] > p.lower()[i] && exact[i] < p.upper()[i]));
        let settings = ClarabelSettings::default();
        for (name, got) in [
            (
                "active-set",
                ActiveSetSolver::new(&p).allocate(&u_c).unwrap(),
            ),
            ("clarabel", allocate_clarabel(&p, &u_c, &settings).unwrap()),
        ] {
            assert_eq!(got.status, AllocationStatus::Optimal);
            for i in 0..4 {
                assert!(
                    (got.commands[i] - exact[i]).abs() <= 1e-9,
                    "{name} w_yaw {w_yaw}: {:?} vs {exact}",
                    got.commands
                );
            }
        }
    }
    // Hexacopter with weights spanning 15 decades: an attainable control is met exactly.
    let hexa = preset("hexa-pnpnpn");
    let p = AllocationProblem::new(
        hexa.effectiveness_matrix(),
        &[2.5e-8, 2.2e6, 2.3e-7, 1e7],
        &hexa.min_thrust_n(),
        &hexa.max_thrust_n(),
    )
    .unwrap();
    let inside: Vec<f64> = hexa.max_thrust_n().iter().map(|h| 0.3 * h).collect();
    let u_c = p.achieved(&inside);
    let got = ActiveSetSolver::new(&p).allocate(&u_c).unwrap();
    for r in 0..4 {
        assert!(
            (got.achieved[r] - u_c[r]).abs() <= 1e-9 * u_c[0].abs(),
            "{:?} vs {u_c:?}",
            got.achieved
        );
    }
}

/// Distance to `preferred` of the optimum closest to it (the tie rule), by a second QP through
/// Clarabel: min |T - p|^2 with the achieved control pinned by a huge weight.
fn closest_optimum_distance(p: &AllocationProblem, achieved: &[f64], preferred: &[f64]) -> f64 {
    let n = p.virtual_dimension();
    let pinned = AllocationProblem::new(p.matrix().clone(), &vec![1e10; n], p.lower(), p.upper())
        .unwrap()
        .with_regularization(1.0, preferred)
        .unwrap();
    let settings = ClarabelSettings::default().tolerance(1e-12).unwrap();
    let t = allocate_clarabel_unpolished(&pinned, achieved, &settings)
        .unwrap()
        .commands;
    t.iter()
        .zip(preferred)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn regression_tie_rule_holds_with_active_bounds() {
    let octo = preset("octo-x");
    let preferred = [3.3, 4.7, 0.6, 0.5, 2.6, 5.8, 0.4, 1.0];
    let p = AllocationProblem::new(
        octo.effectiveness_matrix(),
        &[1.0; 4],
        &octo.min_thrust_n(),
        &octo.max_thrust_n(),
    )
    .unwrap()
    .with_regularization(0.0, &preferred)
    .unwrap();
    let u_c = [14.96, 0.94, -2.44, 0.19];
    let got = ActiveSetSolver::new(&p).allocate(&u_c).unwrap();
    let distance: f64 = got
        .commands
        .iter()
        .zip(&preferred)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    let best = closest_optimum_distance(&p, &got.achieved, &preferred);
    eprintln!(
        "octo-x tie: {:?} distance {distance} (closest {best})",
        got.commands
    );
    assert!(distance <= best + 1e-6, "{distance} vs {best}");
    assert!(distance <= 5.9665, "{distance}"); // issue #20: 6.598 before

    // Random attainable controls on the octo-x and a hexacopter.
    let mut rng = Rng(99);
    for name in ["octo-x", "hexa-pnpnpn"] {
        let frame = preset(name);
        let m = frame.rotor_count();
        let mut bad = 0;
        for _ in 0..300 {
            let preferred: Vec<f64> = frame
                .max_thrust_n()
                .iter()
                .map(|h| rng.uniform(0.0, h * 0.8))
                .collect();
            let p = AllocationProblem::new(
                frame.effectiveness_matrix(),
                &[1.0; 4],
                &frame.min_thrust_n(),
                &frame.max_thrust_n(),
            )
            .unwrap()
            .with_regularization(0.0, &preferred)
            .unwrap();
            let point: Vec<f64> = frame
                .max_thrust_n()
                .iter()
                .map(|h| rng.uniform(0.0, *h))
                .collect();
            let u_c = p.achieved(&point);
            let got = ActiveSetSolver::new(&p).allocate(&u_c).unwrap();
            assert_eq!(got.status, AllocationStatus::Optimal);
            let d: f64 = (0..m)
                .map(|i| (got.commands[i] - preferred[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            let best = closest_optimum_distance(&p, &got.achieved, &preferred);
            bad += usize::from(d > best + 1e-5 * (1.0 + best));
        }
        eprintln!("{name}: {bad}/300 farther than the closest optimum");
        assert_eq!(bad, 0, "{name}");
    }
}

#[test]
fn scaling_by_1e150_gives_the_same_commands() {
    let (_, base) = ke_preset_problem(&[1.0, 20.0, 20.0, 0.01]);
    let u_c = [30.0, 0.5, -0.3, 0.2]; // saturating
    let reference = ActiveSetSolver::new(&base).allocate(&u_c).unwrap();
    for s in [1e150, 1e-150, 1e160, 1e-160] {
        let m = base.matrix().map(|v| v * s);
        let scaled_u: Vec<f64> = u_c.iter().map(|u| u * s).collect();
        let w: Vec<f64> = base.weights().iter().map(|w| w * s).collect();
        for (p, u) in [
            (
                AllocationProblem::new(m.clone(), base.weights(), base.lower(), base.upper())
                    .unwrap(),
                scaled_u.clone(),
            ),
            (
                AllocationProblem::new(base.matrix().clone(), &w, base.lower(), base.upper())
                    .unwrap(),
                u_c.to_vec(),
            ),
        ] {
            let got = ActiveSetSolver::new(&p).allocate(&u).unwrap();
            assert_eq!(got.status, AllocationStatus::Optimal, "{s}");
            for i in 0..4 {
                assert!(got.commands[i].is_finite());
                assert!(
                    (got.commands[i] - reference.commands[i]).abs() <= 1e-9 * 8.5,
                    "{s}: {:?} vs {:?}",
                    got.commands,
                    reference.commands
                );
            }
        }
    }
    // A virtual control too large for the matrix's scale is an error naming the field.
    let tiny = AllocationProblem::new(
        base.matrix().map(|v| v * 1e-200),
        base.weights(),
        base.lower(),
        base.upper(),
    )
    .unwrap();
    match ActiveSetSolver::new(&tiny).allocate(&[1e200, 0.0, 0.0, 0.0]) {
        Ok(a) => assert!(a.commands.iter().all(|t| t.is_finite())),
        Err(e) => assert!(e.to_string().starts_with("virtual_control"), "{e}"),
    }
}

#[test]
fn permutation_invariance_and_all_paths_agree() {
    let mut rng = Rng(5);
    for trial in 0..300 {
        let case = random_case(&mut rng);
        let p = &case.problem;
        let (n, m) = p.matrix().shape();
        let single = ActiveSetSolver::new(p).allocate(&case.u_c).unwrap();
        // Batch path.
        let batch = allocate_many(
            p,
            &Method::ActiveSet(Default::default()),
            &case.u_c,
            &Cancel::never(),
        )
        .unwrap();
        assert_eq!(
            fallback_count(&batch),
            usize::from(single.solved_by == SolvedBy::Clarabel)
        );
        // Reusable solver, warm-started from an unrelated solve.
        let solver = ActiveSetSolver::with_settings(p, ActiveSetSettings::default()).unwrap();
        let mut active = ActiveSet::cold(m);
        let mut t = vec![0.0; m];
        solver
            .solve(&p.achieved(p.upper()), &mut active, &mut t)
            .unwrap();
        solver.solve(&case.u_c, &mut active, &mut t).unwrap();
        let f = p.objective(&case.u_c, &single.commands);
        let tol = 1e-10 * (1.0 + f);
        assert!((p.objective(&case.u_c, &batch[0].commands) - f).abs() <= tol);
        assert!(
            (p.objective(&case.u_c, &t) - f).abs() <= tol,
            "trial {trial}"
        );
        for i in 0..m {
            assert_eq!(single.commands[i], batch[0].commands[i], "trial {trial}");
        }
        // Reversed columns give the reversed commands (objective; commands where unique).
        let rev = DMatrix::from_fn(n, m, |r, c| p.matrix()[(r, m - 1 - c)]);
        let flip = |v: &[f64]| v.iter().rev().copied().collect::<Vec<f64>>();
        let mut q =
            AllocationProblem::new(rev, p.weights(), &flip(p.lower()), &flip(p.upper())).unwrap();
        if p.regularization() > 0.0 {
            q = q
                .with_regularization(p.regularization(), &flip(p.preferred()))
                .unwrap();
        }
        let got = ActiveSetSolver::new(&q).allocate(&case.u_c).unwrap();
        let back = flip(&got.commands);
        assert!(
            (p.objective(&case.u_c, &back) - f).abs() <= tol,
            "trial {trial}"
        );
        for i in 0..m {
            assert!(
                (back[i] - single.commands[i]).abs() <= 1e-7 * (1.0 + single.commands[i].abs()),
                "trial {trial}: {back:?} vs {:?}",
                single.commands
            );
        }
    }
}

/// No solver polls the cancel token inside one solve: the iteration bound has a ceiling, the same
/// for both solvers, refused by name above it (a user's 10^9 was accepted, and 2^32 clamped).
#[test]
fn iteration_bounds_have_one_ceiling() {
    use rfcore::allocation::MAX_ITERATIONS;
    let problem = AllocationProblem::new(ke_matrix(), &[1.0; 4], &[0.0; 4], &[8.5; 4]).unwrap();
    let solver = ActiveSetSolver::new(&problem);
    assert!(solver.clone().with_max_iterations(MAX_ITERATIONS).is_ok());
    let refused = solver.with_max_iterations(MAX_ITERATIONS + 1).unwrap_err();
    assert!(refused.to_string().contains("max_iterations"), "{refused}");
    let clarabel = ClarabelSettings::default();
    assert!(clarabel.max_iterations(MAX_ITERATIONS).is_ok());
    assert!(clarabel.max_iterations(MAX_ITERATIONS + 1).is_err());
    assert!(clarabel.max_iterations(0).is_err());
}
