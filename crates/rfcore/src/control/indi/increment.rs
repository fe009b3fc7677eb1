//! Step 5 of the INDI law: the incremental allocation over the remaining rotors.

use nalgebra::DMatrix;

use crate::allocation::active_set::{ActiveSet, ActiveSetSolver};
use crate::allocation::{AllocationProblem, MAX_ACTUATORS};

/// Step 5 of the law: `min |W^(1/2) (b - G dT)|` over `lower <= dT <= upper` (columns `0..k` of
/// `g`, `k = lower.len()`), the smallest `dT` among equal optima. When the weighted rows have full
/// row rank and no more rows than columns, the unconstrained optimum is the minimum-norm solution
/// `G_w^T (G_w G_w^T)^-1 b_w` (four rows at most: a Cholesky of at most 4 x 4); inside the bounds it
/// is also the bounded optimum (every KKT multiplier zero) and is returned as is. Otherwise (the
/// rotors saturate, or the weighted rows outnumber the rotors or are rank deficient, so the rotors
/// cannot meet every weighted axis either), the active-set solver of [`crate::allocation`]
/// (warm-started from `active`) decides with `saturated_weights` (the priorities once not every
/// axis can be met: yaw after thrust and attitude, module docs step 5). NaN when the problem is not finite (the simulator then
/// reports a non-finite command).
pub(super) fn incremental_allocation(
    g: &[[f64; MAX_ACTUATORS]; 4],
    weights: &[f64; 4],
    saturated_weights: &[f64; 4],
    b: &[f64; 4],
    lower: &[f64],
    upper: &[f64],
    active: &mut ActiveSet,
) -> [f64; MAX_ACTUATORS] {
    let k = lower.len();
    let mut out = [f64::NAN; MAX_ACTUATORS];
    if !b.iter().all(|v| v.is_finite())
        || !g.iter().all(|row| row[..k].iter().all(|v| v.is_finite()))
    {
        return out;
    }
    if let Some(x) = minimum_norm(g, weights, b, k) {
        if (0..k).all(|c| x[c] >= lower[c] && x[c] <= upper[c]) {
            *active = ActiveSet::cold(k);
            return x;
        }
    }
    let matrix = DMatrix::from_fn(4, k, |r, c| g[r][c]);
    if let Ok(problem) = AllocationProblem::new(matrix, saturated_weights, lower, upper) {
        ActiveSetSolver::new(&problem).solve_unchecked(b, active, &mut out[..k]);
    }
    out
}

/// The minimum-norm minimiser of `|W^(1/2) (b - G x)|` (columns `0..k`) when the rows with a
/// positive weight have full row rank and number at most `k`; `None` otherwise.
fn minimum_norm(
    g: &[[f64; MAX_ACTUATORS]; 4],
    weights: &[f64; 4],
    b: &[f64; 4],
    k: usize,
) -> Option<[f64; MAX_ACTUATORS]> {
    let mut rows = [[0.0; MAX_ACTUATORS]; 4];
    let mut rhs = [0.0; 4];
    let mut n = 0;
    for r in 0..4 {
        if weights[r] > 0.0 {
            let w = weights[r].sqrt();
            for c in 0..k {
                rows[n][c] = w * g[r][c];
            }
            rhs[n] = w * b[r];
            n += 1;
        }
    }
    if n == 0 || n > k {
        return None;
    }
    // Cholesky of the Gram matrix S = R R^T (n x n, lower triangle in l).
    let mut l = [[0.0; 4]; 4];
    let mut largest = 0.0f64;
    for i in 0..n {
        for j in 0..=i {
            let gram: f64 = (0..k).map(|c| rows[i][c] * rows[j][c]).sum();
            if i == j {
                largest = largest.max(gram);
            }
            let sum = gram - (0..j).map(|p| l[i][p] * l[j][p]).sum::<f64>();
            if i == j {
                // A pivot lost to rounding against the largest diagonal: (nearly) rank deficient.
                if sum.is_nan() || sum <= 1e-12 * largest {
                    return None;
                }
                l[i][i] = sum.sqrt();
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    // S y = rhs, then x = R^T y.
    let mut y = [0.0; 4];
    for i in 0..n {
        y[i] = (rhs[i] - (0..i).map(|p| l[i][p] * y[p]).sum::<f64>()) / l[i][i];
    }
    for i in (0..n).rev() {
        y[i] = (y[i] - (i + 1..n).map(|p| l[p][i] * y[p]).sum::<f64>()) / l[i][i];
    }
    let mut x = [0.0; MAX_ACTUATORS];
    for (c, xc) in x.iter_mut().enumerate().take(k) {
        *xc = (0..n).map(|i| rows[i][c] * y[i]).sum();
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::Rng;

    fn random_problem(rng: &mut Rng, k: usize) -> ([[f64; MAX_ACTUATORS]; 4], [f64; 4]) {
        let mut g = [[0.0; MAX_ACTUATORS]; 4];
        for row in g.iter_mut() {
            for v in row.iter_mut().take(k) {
                *v = rng.uniform(-1.0, 1.0) * 10f64.powf(rng.uniform(-2.0, 2.0));
            }
        }
        let b = [0.0; 4].map(|_| rng.uniform(-50.0, 50.0));
        (g, b)
    }

    fn solver(
        g: &[[f64; MAX_ACTUATORS]; 4],
        w: &[f64; 4],
        k: usize,
        lo: f64,
        hi: f64,
    ) -> ActiveSetSolver {
        let matrix = DMatrix::from_fn(4, k, |r, c| g[r][c]);
        ActiveSetSolver::new(
            &AllocationProblem::new(matrix, w, &vec![lo; k], &vec![hi; k]).unwrap(),
        )
    }

    #[test]
    fn the_minimum_norm_solution_is_the_active_set_solvers_answer_inside_the_bounds() {
        let mut rng = Rng(7);
        let patterns = [
            [1.0, 1.0, 1.0, 1.0],
            [1.0, 3.0, 3.0, 0.0],
            [1.0, 1.0, 0.0, 0.0],
            [2.0, 1.0, 1.0, 1e-4],
        ];
        let mut compared = 0;
        for trial in 0..400 {
            let k = 2 + trial % 7;
            let w = patterns[trial % patterns.len()];
            let (g, b) = random_problem(&mut rng, k);
            let Some(x) = minimum_norm(&g, &w, &b, k) else {
                continue;
            };
            // Bounds far outside: the constrained and unconstrained optima coincide.
            let big = 1e3 * x[..k].iter().fold(1.0f64, |a, v| a.max(v.abs()));
            let s = solver(&g, &w, k, -big, big);
            let reference = s.allocate(&b).unwrap();
            assert!(reference.certificate.holds(), "{trial}");
            // And a third computation: the SVD pseudo-inverse of the weighted rows.
            let rows: Vec<usize> = (0..4).filter(|&r| w[r] > 0.0).collect();
            let gw = DMatrix::from_fn(rows.len(), k, |i, c| w[rows[i]].sqrt() * g[rows[i]][c]);
            let bw = nalgebra::DVector::from_fn(rows.len(), |i, _| w[rows[i]].sqrt() * b[rows[i]]);
            let svd_x = gw.pseudo_inverse(1e-12).unwrap() * bw;
            for c in 0..k {
                let scale = svd_x.amax().max(1.0);
                assert!((x[c] - svd_x[c]).abs() < 1e-8 * scale, "{trial}: svd");
                let tol = 1e-8
                    * reference
                        .commands
                        .iter()
                        .fold(1.0f64, |a, v| a.max(v.abs()));
                assert!(
                    (x[c] - reference.commands[c]).abs() < tol,
                    "{trial} k {k} w {w:?}: {:?} vs {:?}",
                    &x[..k],
                    reference.commands
                );
            }
            compared += 1;
        }
        assert!(compared > 300, "{compared}");
    }

    #[test]
    fn bounded_answers_are_certified_and_rank_deficient_rows_go_to_the_solver() {
        let mut rng = Rng(11);
        for trial in 0..200 {
            let k = 3 + trial % 6;
            let w = [1.0, 1.0, 1.0, if trial % 2 == 0 { 1.0 } else { 0.0 }];
            let (g, b) = random_problem(&mut rng, k);
            let (lo, hi) = (-0.5, 0.7);
            let mut active = ActiveSet::cold(k);
            let x = incremental_allocation(&g, &w, &w, &b, &vec![lo; k], &vec![hi; k], &mut active);
            assert!(
                x[..k].iter().all(|v| (lo..=hi).contains(v)),
                "{trial}: {:?}",
                &x[..k]
            );
            let certificate = solver(&g, &w, k, lo, hi).certify(&b, &x[..k]);
            assert!(certificate.holds(), "{trial}: {certificate:?}");
        }
        // Two equal weighted rows: rank deficient, no minimum-norm shortcut.
        let mut g = [[0.0; MAX_ACTUATORS]; 4];
        g[0][..3].copy_from_slice(&[1.0, 2.0, 3.0]);
        g[1][..3].copy_from_slice(&[1.0, 2.0, 3.0]);
        assert!(minimum_norm(&g, &[1.0, 1.0, 0.0, 0.0], &[1.0, 2.0, 0.0, 0.0], 3).is_none());
        // More weighted rows than columns: least squares, the solver's.
        assert!(minimum_norm(&g, &[1.0; 4], &[1.0; 4], 2).is_none());
        let mut active = ActiveSet::cold(3);
        let x = incremental_allocation(
            &g,
            &[1.0; 4],
            &[1.0; 4],
            &[f64::NAN; 4],
            &[-1.0; 3],
            &[1.0; 3],
            &mut active,
        );
        assert!(x[..3].iter().all(|v| v.is_nan()));
    }
}
