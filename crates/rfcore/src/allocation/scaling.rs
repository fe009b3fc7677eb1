//! The active-set solver's internal form of an [`AllocationProblem`]: the bounded least-squares
//! problem `min 1/2 |A T - b|^2`, `lower <= T <= upper`, with `A = [W^(1/2) M; gamma^(1/2) I]`
//! and `b = [W^(1/2) u_c; gamma^(1/2) T_pref]`, after scaling the matrix, weights and
//! regularisation by powers of two (so a problem multiplied by 1e+-150 gives the same commands),
//! rows sorted by decreasing norm, in fixed-size arrays. Also the norms that neither overflow
//! nor underflow, used by the factorisation and the certificate.

use crate::allocation::problem::{AllocationProblem, MAX_ACTUATORS, MAX_VIRTUAL};
use crate::error::Result;

/// Most actuators (columns).
pub(crate) const N: usize = MAX_ACTUATORS;
/// Rows of the stacked least-squares matrix: n weighted rows and m regularisation rows.
pub(crate) const ROWS: usize = MAX_VIRTUAL + N;
/// Work-array sizes (entries, at least `rows * m`): small problems (up to 8 x 8, e.g. 4 axes and
/// up to 16 rotors without regularisation) and the largest.
pub(crate) const SMALL_WORK: usize = 64;
pub(crate) const BIG_WORK: usize = ROWS * N;

/// Squared norms at or inside these bounds are computed directly (sum of squares, no scaling):
/// far from underflow and overflow even for the smallest entry that counts at
/// [`crate::allocation::factorisation::RANK_TOL`].
pub(crate) const SAFE_SQ_MIN: f64 = 1.2e-271; // 2^-900
pub(crate) const SAFE_SQ_MAX: f64 = 8.5e270; // 2^900

#[inline(always)]
pub(crate) fn sum_sq(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

/// The power of two nearest `x` (> 0, finite); 1 for zero.
fn power_of_two(x: f64) -> f64 {
    if x > 0.0 && x.is_finite() {
        2f64.powi(x.log2().round() as i32)
    } else {
        1.0
    }
}

/// Euclidean norm without overflow or underflow of the squares.
pub(crate) fn norm(v: &[f64]) -> f64 {
    let big = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if big == 0.0 || !big.is_finite() {
        return big;
    }
    let s: f64 = v.iter().map(|x| (x / big) * (x / big)).sum();
    big * s.sqrt()
}

/// A problem in the solver's scaled, row-sorted least-squares form (module docs), prepared once
/// per solver.
#[derive(Debug, Clone)]
pub(crate) struct ScaledLeastSquares {
    /// The internally scaled problem (Clarabel fallback).
    pub(crate) problem: AllocationProblem,
    pub(crate) m: usize,
    pub(crate) n: usize,
    pub(crate) rows: usize,
    /// `A`, column-major with leading dimension [`ROWS`], rows sorted by decreasing norm.
    pub(crate) a: [f64; ROWS * N],
    /// Which row of the problem each stored row is: `< n` a weighted row, `n + i` the
    /// regularisation row of actuator i.
    pub(crate) source: [usize; ROWS],
    pub(crate) root_weights: [f64; MAX_VIRTUAL],
    pub(crate) root_gamma: f64,
    /// `1 / s_M`: the virtual control's internal scale.
    pub(crate) u_scale: f64,
    pub(crate) column_norms: [f64; N],
    pub(crate) lower: [f64; N],
    pub(crate) upper: [f64; N],
    pub(crate) preferred: [f64; N],
    /// Phase 2 constraints: rows of the scaled M with a positive weight, unit norm, row-major.
    pub(crate) constraint: [f64; MAX_VIRTUAL * N],
    pub(crate) constraint_rows: usize,
}

impl ScaledLeastSquares {
    /// The scaled form of `problem`.
    pub(crate) fn new(problem: &AllocationProblem) -> Self {
        let (n, m) = problem.matrix().shape();
        let gamma = problem.regularization();
        let s_m = power_of_two(problem.matrix().amax());
        let s_w = power_of_two(problem.weights().iter().fold(0.0f64, |a, &w| a.max(w)));
        let matrix = problem.matrix().map(|v| v / s_m);
        let weights: Vec<f64> = problem.weights().iter().map(|w| w / s_w).collect();
        // gamma / (s_w s_M^2) without overflow; capped (a huge value just pins T to T_pref).
        let root_gamma = (gamma.sqrt() / s_w.sqrt() / s_m).min(1e150);
        let scaled_gamma = root_gamma * root_gamma;
        let scaled =
            AllocationProblem::new(matrix.clone(), &weights, problem.lower(), problem.upper())
                .and_then(|p| p.with_regularization(scaled_gamma, problem.preferred()))
                .expect("a scaled valid problem is valid");
        let rows = n + if gamma > 0.0 { m } else { 0 };
        let mut form = ScaledLeastSquares {
            problem: scaled,
            m,
            n,
            rows,
            a: [0.0; ROWS * N],
            source: [0; ROWS],
            root_weights: [0.0; MAX_VIRTUAL],
            root_gamma: if gamma > 0.0 { root_gamma } else { 0.0 },
            u_scale: 1.0 / s_m,
            column_norms: [0.0; N],
            lower: [0.0; N],
            upper: [0.0; N],
            preferred: [0.0; N],
            constraint: [0.0; MAX_VIRTUAL * N],
            constraint_rows: 0,
        };
        for (root, w) in form.root_weights.iter_mut().zip(&weights) {
            *root = w.sqrt();
        }
        // Stacked rows and their norms; sorted by decreasing norm (stable).
        let row = |k: usize, c: usize| -> f64 {
            if k < n {
                form.root_weights[k] * matrix[(k, c)]
            } else if k - n == c {
                form.root_gamma
            } else {
                0.0
            }
        };
        let mut order: Vec<(f64, usize)> = (0..rows)
            .map(|k| (norm(&(0..m).map(|c| row(k, c)).collect::<Vec<_>>()), k))
            .collect();
        order.sort_by(|x, y| y.0.total_cmp(&x.0));
        for (slot, &(_, k)) in order.iter().enumerate() {
            form.source[slot] = k;
            for c in 0..m {
                form.a[c * ROWS + slot] = row(k, c);
            }
        }
        for c in 0..m {
            form.column_norms[c] = norm(&form.a[c * ROWS..c * ROWS + rows]);
            form.preferred[c] = problem.preferred()[c];
        }
        for r in 0..n {
            if weights[r] > 0.0 {
                let values: Vec<f64> = (0..m).map(|c| matrix[(r, c)]).collect();
                let size = norm(&values);
                if size > 0.0 {
                    let k = form.constraint_rows;
                    for (c, v) in values.iter().enumerate() {
                        form.constraint[k * N + c] = v / size;
                    }
                    form.constraint_rows += 1;
                }
            }
        }
        form.load_bounds();
        form
    }

    fn load_bounds(&mut self) {
        for i in 0..self.m {
            self.lower[i] = self.problem.lower()[i];
            self.upper[i] = self.problem.upper()[i];
        }
    }

    /// Replaces the bounds (not scaled), validated like the problem's.
    pub(crate) fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<()> {
        self.problem.set_bounds(lower, upper)?;
        self.load_bounds();
        Ok(())
    }

    /// `b` for `u_c`, in the stored row order; false if it is not finite (a virtual control too
    /// large for the matrix's scale).
    // Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn rhs(&self, u_c: &[f64], b: &mut [f64; ROWS]) -> bool {
        for slot in 0..self.rows {
            let k = self.source[slot];
            b[slot] = if k < self.n {
                self.root_weights[k] * (u_c[k] * self.u_scale)
            } else {
                self.root_gamma * self.preferred[k - self.n]
            };
        }
        b[..self.rows].iter().all(|v| v.is_finite())
    }

    /// `r = b - A T`.
    // Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn residual(&self, b: &[f64; ROWS], t: &[f64; N], r: &mut [f64; ROWS]) {
        self.residual_rows::<0>(b, t, r);
    }

    /// [`Self::residual`] with the row count `R` known at compile time when `R > 0` (the
    /// 4-axis instance of the active set: unrolled, the same operations in the same order).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn residual_rows<const R: usize>(
        &self,
        b: &[f64; ROWS],
        t: &[f64; N],
        r: &mut [f64; ROWS],
    ) {
        debug_assert!(R == 0 || R == self.rows);
        let rows = if R > 0 { R } else { self.rows };
        r[..rows].copy_from_slice(&b[..rows]);
        for c in 0..self.m {
            let x = t[c];
            if x != 0.0 {
                let col = &self.a[c * ROWS..c * ROWS + rows];
                for (ri, a) in r.iter_mut().zip(col) {
                    *ri -= a * x;
                }
            }
        }
    }

    /// `|b|`.
    pub(crate) fn rhs_norm(&self, b: &[f64; ROWS]) -> f64 {
        let sq = sum_sq(&b[..self.rows]);
        if (SAFE_SQ_MIN..=SAFE_SQ_MAX).contains(&sq) {
            sq.sqrt()
        } else {
            norm(&b[..self.rows])
        }
    }
}
