//! Prioritised allocation made exact and certified: the stages of the lexicographic problem, the
//! certificate of its answer ([`prioritized_certificate`]) and the polish that turns Clarabel's
//! answer into exact commands ([`polish_prioritized`]).
//!
//! Stage k minimises `|A_k T - b_k|^2` over the optima of the stages before it, with `A_k` the rows
//! of group k that have a positive weight, scaled by `w^(1/2)` (the problem's regularisation
//! `gamma^(1/2) (I, T_pref)` joins the last group's stage); a final stage takes, among the optima
//! of the last group, the commands closest to `T_pref` (the tie rule of the other methods). A
//! stage's objective is strictly convex in `A_k T`, so its optima share `A_k T`: the optima of
//! stages 1..k are the box intersected with `A_j T = A_j T*` for every `j <= k`. Stage k is
//! therefore a least-squares problem with equality constraints `E T = c` (the earlier stages' rows,
//! kept as an orthonormal basis of their span) and the box, whose KKT conditions are
//! `g + E^T lambda = mu` with `g = A_k^T (A_k T - b_k)`, `mu_i >= 0` at a lower bound, `<= 0` at
//! an upper bound and `0` strictly inside. The certificate holds when every stage's conditions
//! hold at the commands, each residual normalised as the single-stage certificate's
//! ([`crate::allocation::certificate`]): so `status == Optimal` only with the evidence that every
//! stage is optimal, not the one-stage problem that a prioritised answer does not solve.

use nalgebra::{DMatrix, DVector};

use crate::allocation::certificate::Certificate;
use crate::allocation::factorisation::{apply_q, apply_qt, back_substitute, householder_qr};
use crate::allocation::problem::AllocationProblem;
use crate::allocation::scaling::ROWS;

/// Normalised multipliers below this are treated as zero by the release rule.
const RELEASE_TOL: f64 = 1e-12;

/// One stage: minimise `|a T - b|^2` (rows of `a` may be zero).
struct Stage {
    a: DMatrix<f64>,
    b: DVector<f64>,
}

/// The stages of a prioritised problem (module docs), the tie stage last.
fn stages(problem: &AllocationProblem, u_c: &[f64], priorities: &[Vec<usize>]) -> Vec<Stage> {
    let m = problem.actuator_count();
    let gamma = problem.regularization();
    let mut out = Vec::with_capacity(priorities.len() + 1);
    for (k, group) in priorities.iter().enumerate() {
        let rows: Vec<usize> = group
            .iter()
            .copied()
            .filter(|&r| problem.weights()[r] > 0.0)
            .collect();
        let extra = if k + 1 == priorities.len() && gamma > 0.0 {
            m
        } else {
            0
        };
        let mut a = DMatrix::zeros(rows.len() + extra, m);
        let mut b = DVector::zeros(rows.len() + extra);
        for (i, &r) in rows.iter().enumerate() {
            let w = problem.weights()[r].sqrt();
            for c in 0..m {
                a[(i, c)] = w * problem.matrix()[(r, c)];
            }
            b[i] = w * u_c[r];
        }
        for c in 0..extra {
            a[(rows.len() + c, c)] = gamma.sqrt();
            b[rows.len() + c] = gamma.sqrt() * problem.preferred()[c];
        }
        out.push(Stage { a, b });
    }
    out.push(Stage {
        a: DMatrix::identity(m, m),
        b: DVector::from_column_slice(problem.preferred()),
    });
    out
}

/// An orthonormal basis (rows) of the span of the rows of `e` and `a`, at most m rows.
fn extend_basis(e: &DMatrix<f64>, a: &DMatrix<f64>) -> DMatrix<f64> {
    let m = a.ncols();
    let rows: Vec<DVector<f64>> = e
        .row_iter()
        .chain(a.row_iter())
        .filter(|r| r.iter().any(|v| *v != 0.0))
        .map(|r| r.transpose() / r.norm().max(f64::MIN_POSITIVE))
        .collect();
    if rows.is_empty() {
        return DMatrix::zeros(0, m);
    }
    // Gram-Schmidt twice over, dropping rows dependent to 1e-10 of their length.
    let mut basis: Vec<DVector<f64>> = Vec::new();
    for r in rows {
        let mut v = r.clone();
        for _ in 0..2 {
            for q in &basis {
                let d = q.dot(&v);
                v -= q * d;
            }
        }
        let norm = v.norm();
        if norm > 1e-10 {
            basis.push(v / norm);
        }
        if basis.len() == m {
            break;
        }
    }
    DMatrix::from_fn(basis.len(), m, |i, j| basis[i][j])
}

/// The columns `free` of `e` transposed, column-major `k x q` (leading dimension `k`), factorised
/// by Householder QR with pivoting: `(packed, rank, perm, tau)`.
fn qr_of_transposed(e: &DMatrix<f64>, free: &[usize]) -> (Vec<f64>, usize, Vec<usize>, Vec<f64>) {
    let (k, q) = (free.len(), e.nrows());
    let mut w = vec![0.0; k.max(1) * q.max(1)];
    for c in 0..q {
        for (j, &i) in free.iter().enumerate() {
            w[c * k + j] = e[(c, i)];
        }
    }
    let mut perm = vec![0usize; q.max(1)];
    let mut tau = vec![0.0; q.max(1)];
    let rank = if k == 0 || q == 0 {
        0
    } else {
        householder_qr(&mut w, k, k, q, &mut perm, &mut tau)
    };
    (w, rank, perm, tau)
}

/// `lambda` (q) minimising `|E_F^T lambda + g_F|` (a basic solution), from [`qr_of_transposed`].
fn fitted_multipliers(e: &DMatrix<f64>, free: &[usize], g: &DVector<f64>) -> DVector<f64> {
    let q = e.nrows();
    let mut lambda = DVector::zeros(q);
    if free.is_empty() || q == 0 {
        return lambda;
    }
    let (w, rank, perm, tau) = qr_of_transposed(e, free);
    let k = free.len();
    let mut y: Vec<f64> = free.iter().map(|&i| -g[i]).collect();
    apply_qt(&w, k, k, rank, &tau, &mut y);
    back_substitute(&w, k, rank, &mut y);
    for j in 0..rank {
        lambda[perm[j]] = y[j];
    }
    lambda
}

/// Where each variable is held during a stage.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Held {
    Free,
    Lower,
    Upper,
}

/// The normalisation of entry i of a stage's stationarity (module docs): `|a_i| (|b| + sum_j
/// |a_j| |x_j|) + sum_r |e_ri lambda_r|`.
fn scales(stage: &Stage, e: &DMatrix<f64>, x: &DVector<f64>, lambda: &DVector<f64>) -> Vec<f64> {
    let m = x.len();
    let norms: Vec<f64> = (0..m).map(|c| stage.a.column(c).norm()).collect();
    let size = stage.b.norm() + (0..m).map(|c| norms[c] * x[c].abs()).sum::<f64>();
    (0..m)
        .map(|i| {
            norms[i] * size
                + (0..e.nrows())
                    .map(|r| (e[(r, i)] * lambda[r]).abs())
                    .sum::<f64>()
        })
        .collect()
}

/// `v` in the box, on a bound when within rounding of it (`1e-14` of the bounds' size): a step
/// that ends there has reached the bound, and the certificate must see it held.
fn snapped(v: f64, lower: f64, upper: f64) -> f64 {
    let band = 1e-14 * lower.abs().max(upper.abs()).max(upper - lower);
    if v <= lower + band {
        lower
    } else if v >= upper - band {
        upper
    } else {
        v
    }
}

/// One stage by a primal active set from the feasible `x` (`E x = c` held by every step, which
/// stays in the null space of `E` on the free variables). Returns the multipliers of `E` at the
/// stage's optimum, or None at the iteration bound.
fn solve_stage(
    stage: &Stage,
    e: &DMatrix<f64>,
    lower: &[f64],
    upper: &[f64],
    x: &mut DVector<f64>,
    budget: usize,
) -> Option<DVector<f64>> {
    let m = x.len();
    let rows = stage.a.nrows();
    let mut held: Vec<Held> = (0..m)
        .map(|i| {
            if lower[i] == upper[i] || x[i] <= lower[i] {
                Held::Lower
            } else if x[i] >= upper[i] {
                Held::Upper
            } else {
                Held::Free
            }
        })
        .collect();
    for i in 0..m {
        x[i] = match held[i] {
            Held::Lower => lower[i],
            Held::Upper => upper[i],
            Held::Free => x[i],
        };
    }
    let span: f64 = (0..m)
        .map(|i| lower[i].abs().max(upper[i].abs()))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut excluded = vec![false; m];
    let mut last_released: Option<usize> = None;
    let mut at_minimiser = false;
    for _ in 0..budget {
        let free: Vec<usize> = (0..m).filter(|&i| held[i] == Held::Free).collect();
        let k = free.len();
        if !at_minimiser && k > 0 && rows > 0 {
            // Null space of E_F: the last k - rank columns of Q from the QR of E_F^T.
            let (w, rank, _, tau) = qr_of_transposed(e, &free);
            let d = k - rank;
            let mut z = DMatrix::zeros(k, d);
            for j in 0..d {
                let mut v = vec![0.0; k];
                v[rank + j] = 1.0;
                apply_q(&w, k, k, rank, &tau, &mut v);
                for i in 0..k {
                    z[(i, j)] = v[i];
                }
            }
            let mut step = DVector::zeros(m);
            if d > 0 {
                // min |A_F Z y - r| (a basic solution), then the step Z y on F.
                let r = &stage.b - &stage.a * &*x;
                let af = DMatrix::from_fn(rows, k, |i, j| stage.a[(i, free[j])]);
                let b = af * &z;
                let mut packed = vec![0.0; rows * d];
                for c in 0..d {
                    for i in 0..rows {
                        packed[c * rows + i] = b[(i, c)];
                    }
                }
                let mut perm = vec![0usize; d];
                let mut tau_b = vec![0.0; d];
                let rank_b = if rows <= ROWS {
                    householder_qr(&mut packed, rows, rows, d, &mut perm, &mut tau_b)
                } else {
                    0
                };
                let mut y: Vec<f64> = r.iter().copied().collect();
                apply_qt(&packed, rows, rows, rank_b, &tau_b, &mut y);
                back_substitute(&packed, rows, rank_b, &mut y);
                let mut coef = DVector::zeros(d);
                for j in 0..rank_b {
                    coef[perm[j]] = y[j];
                }
                let p = z * coef;
                for (j, &i) in free.iter().enumerate() {
                    step[i] = p[j];
                }
            }
            let size = step.amax();
            if size > 1e-15 * span {
                // Ratio test: the first free variable to reach a bound is held.
                let (mut alpha, mut blocking) = (1.0f64, None);
                for &i in &free {
                    let (limit, state) = if step[i] < 0.0 {
                        ((lower[i] - x[i]) / step[i], Held::Lower)
                    } else if step[i] > 0.0 {
                        ((upper[i] - x[i]) / step[i], Held::Upper)
                    } else {
                        continue;
                    };
                    if limit.max(0.0) < alpha {
                        alpha = limit.max(0.0);
                        blocking = Some((i, state));
                    }
                }
                if let (Some((j, state)), Some(released)) = (blocking, last_released) {
                    if alpha == 0.0 && j == released {
                        // The released variable would leave the box at once: hold it again.
                        held[j] = state;
                        excluded[j] = true;
                        last_released = None;
                        continue;
                    }
                }
                for &i in &free {
                    x[i] = snapped(x[i] + alpha * step[i], lower[i], upper[i]);
                }
                if alpha > 0.0 {
                    excluded.fill(false);
                }
                last_released = None;
                if let Some((j, state)) = blocking {
                    held[j] = state;
                    x[j] = if state == Held::Lower {
                        lower[j]
                    } else {
                        upper[j]
                    };
                    continue;
                }
                at_minimiser = true;
                continue;
            }
            // No step on this face: the released variable stays free (a tie may need several).
        }
        at_minimiser = false;
        let g = stage.a.transpose() * (&stage.a * &*x - &stage.b);
        let lambda = fitted_multipliers(e, &free, &g);
        let mult = &g + e.transpose() * &lambda;
        let s = scales(stage, e, x, &lambda);
        let mut worst = (RELEASE_TOL, usize::MAX);
        for i in 0..m {
            if held[i] == Held::Free || excluded[i] || lower[i] == upper[i] || s[i] == 0.0 {
                continue;
            }
            let violation = if held[i] == Held::Lower {
                -mult[i]
            } else {
                mult[i]
            } / s[i];
            if violation > worst.0 {
                worst = (violation, i);
            }
        }
        if worst.1 == usize::MAX {
            return Some(lambda);
        }
        held[worst.1] = Held::Free;
        last_released = Some(worst.1);
    }
    None
}

/// Polished prioritised commands and their evidence: the commands, and for each stage the
/// multipliers of its equalities (the earlier stages' rows), which
/// [`prioritized_certificate`] checks.
pub(crate) struct Polished {
    pub(crate) commands: Vec<f64>,
    pub(crate) multipliers: Vec<DVector<f64>>,
}

/// Every stage by [`solve_stage`] from `start` (clamped into the box): exact commands, or None
/// when a stage reaches its iteration bound (`8 m + 40` per stage). A stage's gradient does not
/// change in later stages (they keep its `A_k T`), and a variable whose multiplier has a strict
/// sign cannot move without leaving the stage's optima, so each stage's multipliers stay valid
/// at the final commands.
pub(crate) fn polish_prioritized(
    problem: &AllocationProblem,
    u_c: &[f64],
    priorities: &[Vec<usize>],
    start: &[f64],
) -> Option<Polished> {
    let (lower, upper) = (problem.lower(), problem.upper());
    let m = problem.actuator_count();
    let mut x = DVector::from_fn(m, |i, _| start[i].clamp(lower[i], upper[i]));
    let mut e = DMatrix::zeros(0, m);
    let mut multipliers = Vec::new();
    for stage in stages(problem, u_c, priorities) {
        multipliers.push(solve_stage(&stage, &e, lower, upper, &mut x, 8 * m + 40)?);
        e = extend_basis(&e, &stage.a);
    }
    Some(Polished {
        commands: x.iter().copied().collect(),
        multipliers,
    })
}

/// The certificate of prioritised commands (module docs): the largest normalised KKT residual
/// over the stages and the bound violation relative to each span. The multipliers of each
/// stage's equalities are `multipliers` (the polish's) or, without them, fitted on the variables
/// strictly inside the box (which may not find the ones that exist when fewer variables are
/// free than earlier rows bind them: then the certificate does not hold).
pub(crate) fn prioritized_certificate(
    problem: &AllocationProblem,
    u_c: &[f64],
    priorities: &[Vec<usize>],
    commands: &[f64],
    multipliers: Option<&[DVector<f64>]>,
    tolerance: f64,
) -> Certificate {
    let (lower, upper) = (problem.lower(), problem.upper());
    let m = problem.actuator_count();
    let mut out = Certificate {
        stationarity: 0.0,
        complementarity: 0.0,
        bound_violation: 0.0,
        tolerance,
    };
    if commands.iter().any(|v| !v.is_finite()) {
        return Certificate::failed(tolerance);
    }
    let x = DVector::from_column_slice(commands);
    for i in 0..m {
        let span = (upper[i] - lower[i])
            .max(lower[i].abs())
            .max(upper[i].abs());
        let span = if span > 0.0 { span } else { 1.0 };
        out.bound_violation = out
            .bound_violation
            .max((lower[i] - x[i]).max(x[i] - upper[i]).max(0.0) / span);
    }
    let free: Vec<usize> = (0..m)
        .filter(|&i| lower[i] < x[i] && x[i] < upper[i])
        .collect();
    let mut e = DMatrix::zeros(0, m);
    for (k, stage) in stages(problem, u_c, priorities).into_iter().enumerate() {
        let g = stage.a.transpose() * (&stage.a * &x - &stage.b);
        let lambda = match multipliers {
            Some(given) if given.len() > k && given[k].len() == e.nrows() => given[k].clone(),
            _ => fitted_multipliers(&e, &free, &g),
        };
        let mult = &g + e.transpose() * &lambda;
        let s = scales(&stage, &e, &x, &lambda);
        for i in 0..m {
            if lower[i] == upper[i] || s[i] == 0.0 {
                continue;
            }
            let r = mult[i] / s[i];
            if !r.is_finite() {
                out.stationarity = f64::INFINITY;
            } else if x[i] <= lower[i] {
                out.complementarity = out.complementarity.max(-r);
            } else if x[i] >= upper[i] {
                out.complementarity = out.complementarity.max(r);
            } else {
                out.stationarity = out.stationarity.max(r.abs());
            }
        }
        e = extend_basis(&e, &stage.a);
    }
    out
}
