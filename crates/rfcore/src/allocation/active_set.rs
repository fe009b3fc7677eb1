//! The exact active-set solver for [`AllocationProblem`]: the allocation that runs at every
//! control step, so it works in fixed-size arrays (no heap allocation per solve).
//!
//! # Algorithm
//! A primal active-set method on the box-constrained quadratic `1/2 T^T H T - c^T T`
//! (`H = M^T W M + gamma I`, `c = M^T W u_c + gamma T_pref`). Each variable is free or held at its
//! lower or upper bound. Per iteration:
//! 1. On the free set F, solve `H_FF p = -g_F` (`g = H T - c`). `H_FF` may be singular (more
//!    rotors than weighted axes); the equations are then solved by a pivoted Cholesky
//!    factorisation and, of all solutions, the step that lands closest to `T_pref` is taken
//!    (a small null-space least-squares problem), so the answer matches the pseudo-inverse
//!    (Ke eq. (34)/(35)) whenever no bound is active.
//! 2. Ratio test: move along `p` until the first free variable hits a bound; hold it there.
//! 3. After a full step (the free-set minimiser), check the multipliers of the held variables
//!    (`g_i >= 0` at a lower bound, `g_i <= 0` at an upper bound). If one has the wrong sign, the
//!    most violating is released; otherwise the point satisfies the KKT conditions: optimal.
//!
//! Each released variable moves into the box on the next step and the objective never increases,
//! so the method terminates; an iteration bound guards degenerate cycling and ends with
//! [`AllocationStatus::IterationLimit`] and a feasible point. Ties go to the lowest index, so the
//! solver is deterministic. Passing the previous step's [`ActiveSet`] warm-starts it: in a closed
//! loop the active set rarely changes between control steps and one iteration usually suffices.

use crate::allocation::{
    weighted_pseudo_inverse, Allocation, AllocationProblem, AllocationStatus, MAX_ACTUATORS,
    MAX_VIRTUAL, RANK_RTOL,
};
use crate::error::{Result, RfError};

const N: usize = MAX_ACTUATORS;
/// Side of the fixed-size work arrays of [`solve_psd_closest`].
pub(crate) const WORK: usize = N;

/// Multipliers above `-MULTIPLIER_RTOL * scale` count as non-negative (scale: the size of the
/// terms the gradient entry sums, so huge bounds or commands do not blunt the test), so rounding
/// cannot make the solver release and re-add a bound forever.
const MULTIPLIER_RTOL: f64 = 1e-12;
/// A held bound whose multiplier is below this (relative, like [`MULTIPLIER_RTOL`]) is degenerate:
/// it is released once more at the end so the tie rule (closest to `T_pref`) decides.
const DEGENERATE_RTOL: f64 = 1e-9;

/// Where each variable is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum BoundState {
    #[default]
    Free,
    Lower,
    Upper,
}

/// The set of variables held at bounds: returned by a solve, passed to the next to warm-start it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ActiveSet {
    states: [BoundState; N],
    len: usize,
}

impl ActiveSet {
    /// All variables free (a cold start).
    pub fn cold(actuator_count: usize) -> Self {
        ActiveSet {
            states: [BoundState::Free; N],
            len: actuator_count.min(N),
        }
    }
    pub fn states(&self) -> &[BoundState] {
        &self.states[..self.len]
    }
}

/// The active-set solver for one problem: the Hessian and `M^T W` are computed once here; each
/// [`ActiveSetSolver::solve`] then costs a few small factorisations.
#[derive(Debug, Clone)]
pub struct ActiveSetSolver {
    problem: AllocationProblem,
    m: usize,
    n: usize,
    hessian: [f64; N * N],
    /// `M^T W`, m x n row-major.
    weighted_transpose: [f64; N * MAX_VIRTUAL],
    /// `gamma T_pref`.
    regularization_pull: [f64; N],
    root_weights: [f64; MAX_VIRTUAL],
    regularization: f64,
    matrix: [f64; MAX_VIRTUAL * N],
    lower: [f64; N],
    upper: [f64; N],
    preferred: [f64; N],
    /// The unconstrained solution `T = P u_c + o` ([`weighted_pseudo_inverse`]), m x n row-major:
    /// a cold start begins at its clamp, which usually holds the right bounds already.
    pinv_gain: [f64; N * MAX_VIRTUAL],
    pinv_offset: [f64; N],
    pivot_tolerance: f64,
    max_iterations: usize,
}

/// What one solve reports besides the commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolveReport {
    pub status: AllocationStatus,
    pub iterations: usize,
}

impl ActiveSetSolver {
    /// Prepares a solver; the iteration bound defaults to `4 m + 20`.
    pub fn new(problem: &AllocationProblem) -> Self {
        let (n, m) = problem.matrix().shape();
        let mut solver = ActiveSetSolver {
            problem: problem.clone(),
            m,
            n,
            hessian: [0.0; N * N],
            weighted_transpose: [0.0; N * MAX_VIRTUAL],
            regularization_pull: [0.0; N],
            root_weights: [0.0; MAX_VIRTUAL],
            regularization: problem.regularization(),
            matrix: [0.0; MAX_VIRTUAL * N],
            lower: [0.0; N],
            upper: [0.0; N],
            preferred: [0.0; N],
            pinv_gain: [0.0; N * MAX_VIRTUAL],
            pinv_offset: [0.0; N],
            pivot_tolerance: 0.0,
            max_iterations: 4 * m + 20,
        };
        let h = problem.hessian();
        for i in 0..m {
            for j in 0..m {
                solver.hessian[i * N + j] = h[(i, j)];
            }
            for r in 0..n {
                solver.weighted_transpose[i * MAX_VIRTUAL + r] =
                    problem.matrix()[(r, i)] * problem.weights()[r];
            }
            solver.preferred[i] = problem.preferred()[i];
            solver.regularization_pull[i] = problem.regularization() * problem.preferred()[i];
        }
        for r in 0..n {
            for i in 0..m {
                solver.matrix[r * N + i] = problem.matrix()[(r, i)];
            }
            solver.root_weights[r] = problem.weights()[r].sqrt();
        }
        let pinv = weighted_pseudo_inverse(problem);
        for i in 0..m {
            for r in 0..n {
                solver.pinv_gain[i * MAX_VIRTUAL + r] = pinv.gain()[(i, r)];
            }
            solver.pinv_offset[i] = pinv.offset()[i];
        }
        let max_diagonal = (0..m).map(|i| h[(i, i)]).fold(0.0, f64::max);
        solver.pivot_tolerance = RANK_RTOL * max_diagonal;
        solver.load_bounds();
        solver
    }

    fn load_bounds(&mut self) {
        for i in 0..self.m {
            self.lower[i] = self.problem.lower()[i];
            self.upper[i] = self.problem.upper()[i];
        }
    }

    /// Replaces the iteration bound (at least 1).
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Result<Self> {
        if max_iterations == 0 {
            return Err(RfError::invalid("max_iterations", "must be >= 1, got 0"));
        }
        self.max_iterations = max_iterations;
        Ok(self)
    }

    /// Replaces the bounds (e.g. rate limits folded in each step), validated like the problem's.
    pub fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<()> {
        self.problem.set_bounds(lower, upper)?;
        self.load_bounds();
        Ok(())
    }

    pub fn problem(&self) -> &AllocationProblem {
        &self.problem
    }

    /// Solves for `u_c` (n finite entries), checking it; see [`Self::solve_unchecked`].
    pub fn solve(
        &self,
        u_c: &[f64],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> Result<SolveReport> {
        self.problem.check_virtual_control(u_c)?;
        if commands.len() != self.m {
            return Err(RfError::shape(
                "commands",
                format!("{} entries (one per actuator)", self.m),
                commands.len().to_string(),
            ));
        }
        Ok(self.solve_unchecked(u_c, active, commands))
    }

    /// One allocation with a cold start, as an [`Allocation`].
    pub fn allocate(&self, u_c: &[f64]) -> Result<Allocation> {
        let mut active = ActiveSet::cold(self.m);
        let mut commands = vec![0.0; self.m];
        let report = self.solve(u_c, &mut active, &mut commands)?;
        Ok(Allocation {
            achieved: self.problem.achieved(&commands),
            commands,
            status: report.status,
            iterations: report.iterations,
        })
    }

    /// The hot path: `u_c` has n finite entries and `commands` m (callers that validated once).
    /// `active` is the warm start on entry and the final active set on return.
    #[allow(clippy::needless_range_loop)] // parallel fixed-size arrays indexed together
    pub fn solve_unchecked(
        &self,
        u_c: &[f64],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> SolveReport {
        let m = self.m;
        active.len = m;
        let mut c = [0.0; N];
        for (i, ci) in c.iter_mut().enumerate().take(m) {
            let row = &self.weighted_transpose[i * MAX_VIRTUAL..i * MAX_VIRTUAL + self.n];
            *ci =
                self.regularization_pull[i] + row.iter().zip(u_c).map(|(a, u)| a * u).sum::<f64>();
        }
        let mut t = [0.0; N];
        let cold = active.states[..m].iter().all(|s| *s == BoundState::Free);
        for i in 0..m {
            let (lo, hi) = (self.lower[i], self.upper[i]);
            if cold {
                // Start from the clamped unconstrained solution, holding what the clamp cut.
                let row = &self.pinv_gain[i * MAX_VIRTUAL..i * MAX_VIRTUAL + self.n];
                let guess =
                    self.pinv_offset[i] + row.iter().zip(u_c).map(|(p, u)| p * u).sum::<f64>();
                active.states[i] = if guess <= lo {
                    BoundState::Lower
                } else if guess >= hi {
                    BoundState::Upper
                } else {
                    BoundState::Free
                };
            }
            if lo == hi {
                // A fixed variable is held for good (its multiplier may have either sign).
                active.states[i] = BoundState::Lower;
            }
            t[i] = match active.states[i] {
                BoundState::Lower => lo,
                BoundState::Upper => hi,
                BoundState::Free => self.preferred[i].clamp(lo, hi),
            };
        }

        let mut iterations = 0;
        let mut status = AllocationStatus::IterationLimit;
        let mut need_step = true;
        let mut polished = false;
        'outer: loop {
            if need_step {
                if iterations == self.max_iterations {
                    break 'outer;
                }
                iterations += 1;
                match self.step(u_c, &c, &mut t, active) {
                    Step::Blocked((j, state)) => {
                        active.states[j] = state;
                        continue 'outer;
                    }
                    Step::Moved => continue 'outer,
                    Step::Full => {}
                }
            }
            // The point minimises over the free set: check the held variables' multipliers.
            let mut worst = (0.0, usize::MAX);
            for i in 0..m {
                let state = active.states[i];
                if state == BoundState::Free || self.lower[i] == self.upper[i] {
                    continue;
                }
                let (g, scale) = self.gradient_and_scale(i, &t, &c);
                let violation = if state == BoundState::Lower { -g } else { g };
                if violation > MULTIPLIER_RTOL * scale && violation > worst.0 {
                    worst = (violation, i);
                }
            }
            if worst.1 == usize::MAX {
                // Bounds held with a zero multiplier (another optimum leaves them): release them
                // once and step again, so the answer is the optimum closest to T_pref whatever
                // the warm start; a bound the step runs back into is held again.
                let mut released = false;
                if !polished {
                    for i in 0..m {
                        let state = active.states[i];
                        if state != BoundState::Free && self.lower[i] != self.upper[i] {
                            let (g, scale) = self.gradient_and_scale(i, &t, &c);
                            if g.abs() <= DEGENERATE_RTOL * scale {
                                active.states[i] = BoundState::Free;
                                released = true;
                            }
                        }
                    }
                    polished = true;
                }
                if released {
                    need_step = true;
                    continue 'outer;
                }
                status = AllocationStatus::Optimal;
                break 'outer;
            }
            active.states[worst.1] = BoundState::Free;
            need_step = true;
        }
        commands[..m].copy_from_slice(&t[..m]);
        SolveReport { status, iterations }
    }

    /// `g_i` and the size of the terms it sums (`sum_j |H_ij T_j| + |c_i|`), the scale its
    /// rounding error is relative to.
    fn gradient_and_scale(&self, i: usize, t: &[f64; N], c: &[f64; N]) -> (f64, f64) {
        let row = &self.hessian[i * N..i * N + self.m];
        let mut g = -c[i];
        let mut scale = c[i].abs();
        for (h, x) in row.iter().zip(t) {
            g += h * x;
            scale += (h * x).abs();
        }
        (g, scale.max(f64::MIN_POSITIVE))
    }

    fn gradient_entry(&self, i: usize, t: &[f64; N], c: &[f64; N]) -> f64 {
        let row = &self.hessian[i * N..i * N + self.m];
        row.iter().zip(t).map(|(h, x)| h * x).sum::<f64>() - c[i]
    }

    /// One free-set step (steps 1-2 of the module docs).
    fn step(&self, u_c: &[f64], c: &[f64; N], t: &mut [f64; N], active: &ActiveSet) -> Step {
        let mut free = [0usize; N];
        let mut k = 0;
        for i in 0..self.m {
            if active.states[i] == BoundState::Free {
                free[k] = i;
                k += 1;
            }
        }
        if k == 0 {
            return Step::Full;
        }
        let mut system = [0.0; N * N];
        let mut rhs = [0.0; N];
        let mut target = [0.0; N];
        for a in 0..k {
            let i = free[a];
            for b in 0..k {
                system[a * N + b] = self.hessian[i * N + free[b]];
            }
            rhs[a] = -self.gradient_entry(i, t, c);
            target[a] = self.preferred[i] - t[i];
        }
        // Fast paths first (about 3x cheaper); the general pivoted routine when they meet a
        // (near-)singular pivot. All three give the same step: the solution closest to T_pref.
        let mut p = [0.0; N];
        let solved = if k > self.n && self.regularization == 0.0 {
            self.closest_step_wide(&free[..k], u_c, t, &target, &mut p)
        } else {
            let mut factor = system;
            cholesky_solve(
                &mut factor,
                &mut rhs.clone(),
                k,
                self.pivot_tolerance,
                &mut p,
            )
        };
        if !solved {
            solve_psd_closest(&mut system, &rhs, &target, k, self.pivot_tolerance, &mut p);
        }
        if let Some(blocking) = self.move_along(&free[..k], &p, 1.0, t) {
            return Step::Blocked(blocking);
        }
        // A direction whose curvature fell below the rank threshold can still carry gradient
        // (an actuator more than ~3e5 times weaker than the rest): along it the objective is all
        // but linear, so descend along the leftover gradient with an exact line search. This
        // converges, but can zig-zag with the regular directions; such problems may end at the
        // iteration bound (documented).
        let mut residual = [0.0; N];
        let mut significant = false;
        for a in 0..k {
            let (g, scale) = self.gradient_and_scale(free[a], t, c);
            residual[a] = -g;
            significant |= g.abs() > MULTIPLIER_RTOL * scale;
        }
        if !significant {
            return Step::Full;
        }
        let mut slope = 0.0;
        let mut curvature = 0.0;
        for a in 0..k {
            slope += residual[a] * residual[a];
            for b in 0..k {
                curvature += residual[a] * self.hessian[free[a] * N + free[b]] * residual[b];
            }
        }
        let exact = if curvature > 0.0 {
            slope / curvature
        } else {
            f64::INFINITY
        };
        match self.move_along(&free[..k], &residual, exact, t) {
            Some(blocking) => Step::Blocked(blocking),
            None => Step::Moved,
        }
    }

    /// The step for more free variables than weighted axes without regularisation, through the
    /// n x n system of `A_F = W^(1/2) M_F` instead of the singular k x k one:
    /// `p = d + A_F^T (A_F A_F^T)^-1 (W^(1/2) (u_c - M T) - A_F d)`, `d = T_pref - T` on F, is the
    /// free-set minimiser closest to `T_pref`. Returns false if `A_F A_F^T` is (near-)singular.
    fn closest_step_wide(
        &self,
        free: &[usize],
        u_c: &[f64],
        t: &[f64; N],
        target: &[f64; N],
        p: &mut [f64; N],
    ) -> bool {
        let n = self.n;
        let mut r = [0.0; MAX_VIRTUAL];
        for (row, r_row) in r.iter_mut().enumerate().take(n) {
            let m_row = &self.matrix[row * N..row * N + self.m];
            let produced: f64 = m_row.iter().zip(t.iter()).map(|(a, x)| a * x).sum();
            let along_target: f64 = free.iter().zip(target).map(|(&i, d)| m_row[i] * d).sum();
            *r_row = self.root_weights[row] * (u_c[row] - produced - along_target);
        }
        let mut g = [0.0; N * N];
        for r1 in 0..n {
            let row1 = &self.matrix[r1 * N..r1 * N + self.m];
            for r2 in 0..=r1 {
                let row2 = &self.matrix[r2 * N..r2 * N + self.m];
                let dot: f64 = free.iter().map(|&i| row1[i] * row2[i]).sum();
                let value = self.root_weights[r1] * self.root_weights[r2] * dot;
                g[r1 * N + r2] = value;
                g[r2 * N + r1] = value;
            }
        }
        let mut y = [0.0; N];
        let mut rhs = [0.0; N];
        rhs[..n].copy_from_slice(&r[..n]);
        if !cholesky_solve(&mut g, &mut rhs, n, self.pivot_tolerance, &mut y) {
            return false;
        }
        for (a, &i) in free.iter().enumerate() {
            let back: f64 = (0..n)
                .map(|row| self.root_weights[row] * self.matrix[row * N + i] * y[row])
                .sum();
            p[a] = target[a] + back;
        }
        true
    }

    /// Moves the free variables along `direction` by at most `max_alpha`, stopping at the first
    /// bound (the ratio test, lowest index on ties). Returns the variable that hit its bound.
    fn move_along(
        &self,
        free: &[usize],
        direction: &[f64; N],
        max_alpha: f64,
        t: &mut [f64; N],
    ) -> Option<(usize, BoundState)> {
        let mut alpha = max_alpha;
        let mut blocking = None;
        for (a, &i) in free.iter().enumerate() {
            let (limit, state) = if direction[a] < 0.0 {
                ((self.lower[i] - t[i]) / direction[a], BoundState::Lower)
            } else if direction[a] > 0.0 {
                ((self.upper[i] - t[i]) / direction[a], BoundState::Upper)
            } else {
                continue;
            };
            let limit = limit.max(0.0);
            if limit < alpha {
                alpha = limit;
                blocking = Some((i, state));
            }
        }
        for (a, &i) in free.iter().enumerate() {
            t[i] = (t[i] + alpha * direction[a]).clamp(self.lower[i], self.upper[i]);
        }
        if let Some((j, state)) = blocking {
            t[j] = if state == BoundState::Lower {
                self.lower[j]
            } else {
                self.upper[j]
            };
        }
        blocking
    }
}

/// What a free-set step did.
enum Step {
    /// A variable hit a bound and is now held there.
    Blocked((usize, BoundState)),
    /// The point minimises the objective over the free set.
    Full,
    /// A line search along leftover gradient ended inside the box: step again.
    Moved,
}

/// Solves `S p = r` (symmetric, `k x k`, row stride [`N`], overwritten by its Cholesky factor)
/// when every pivot exceeds `tolerance`; returns false otherwise (the caller falls back).
fn cholesky_solve(
    s: &mut [f64; N * N],
    r: &mut [f64; N],
    k: usize,
    tolerance: f64,
    p: &mut [f64; N],
) -> bool {
    if !cholesky_factor(s, k, tolerance) {
        return false;
    }
    cholesky_substitute(s, r, k);
    p[..k].copy_from_slice(&r[..k]);
    true
}

/// Overwrites the lower triangle of `s` (`k x k`, stride [`N`]) with its Cholesky factor `L`;
/// false at the first pivot at or below `tolerance`.
fn cholesky_factor(s: &mut [f64; N * N], k: usize, tolerance: f64) -> bool {
    for j in 0..k {
        let mut d = s[j * N + j];
        for l in 0..j {
            d -= s[j * N + l] * s[j * N + l];
        }
        if d <= tolerance {
            return false;
        }
        let d = d.sqrt();
        s[j * N + j] = d;
        for i in j + 1..k {
            let mut v = s[i * N + j];
            for l in 0..j {
                v -= s[i * N + l] * s[j * N + l];
            }
            s[i * N + j] = v / d;
        }
    }
    true
}

/// Solves `L L^T x = b` in place for the `k x k` lower-triangular `L` in `l` (stride [`N`]).
fn cholesky_substitute(l: &[f64; N * N], b: &mut [f64; N], k: usize) {
    for i in 0..k {
        let mut v = b[i];
        for j in 0..i {
            v -= l[i * N + j] * b[j];
        }
        b[i] = v / l[i * N + i];
    }
    for i in (0..k).rev() {
        let mut v = b[i];
        for j in i + 1..k {
            v -= l[j * N + i] * b[j];
        }
        b[i] = v / l[i * N + i];
    }
}

/// Solves `S p = r` for a symmetric positive semidefinite `k x k` system (row stride [`N`],
/// overwritten), `r` in the range of `S`, choosing among the solutions the one closest to
/// `target`. Pivots at or below `tolerance` mark dependent directions.
///
/// Pivoted Cholesky `P^T S P = [L11; L21] [L11; L21]^T` of rank `r`; the basic solution puts zero
/// on the dependent variables, and the null space is spanned by `[-X; I]`, `X = L11^-T L21^T`,
/// so the closest solution follows from the `(k - r)`-square system `(I + X^T X) z = ...`.
pub(crate) fn solve_psd_closest(
    s: &mut [f64; N * N],
    r: &[f64; N],
    target: &[f64; N],
    k: usize,
    tolerance: f64,
    p: &mut [f64; N],
) {
    let mut perm = [0usize; N];
    for (i, slot) in perm.iter_mut().enumerate().take(k) {
        *slot = i;
    }
    let mut rank = 0;
    for j in 0..k {
        let mut q = j;
        for i in j + 1..k {
            if s[i * N + i] > s[q * N + q] {
                q = i;
            }
        }
        if s[q * N + q] <= tolerance {
            break;
        }
        if q != j {
            perm.swap(j, q);
            for col in 0..k {
                s.swap(j * N + col, q * N + col);
            }
            for row in 0..k {
                s.swap(row * N + j, row * N + q);
            }
        }
        let d = s[j * N + j].sqrt();
        s[j * N + j] = d;
        for i in j + 1..k {
            s[i * N + j] /= d;
        }
        // Schur complement of the trailing block, kept full (both triangles) for later swaps.
        for i in j + 1..k {
            let lij = s[i * N + j];
            for l in j + 1..k {
                s[i * N + l] -= lij * s[l * N + j];
            }
        }
        rank += 1;
    }

    // Basic solution in permuted coordinates: L11 L11^T y = r_1.
    let mut y = [0.0; N];
    for (i, yi) in y.iter_mut().enumerate().take(rank) {
        *yi = r[perm[i]];
    }
    cholesky_substitute(s, &mut y, rank);
    let mut permuted = [0.0; N];
    permuted[..rank].copy_from_slice(&y[..rank]);

    let nullity = k - rank;
    if nullity > 0 {
        // X = L11^-T L21^T, column c solves L11^T x = (row c of L21)^T.
        let mut x = [0.0; N * N];
        for c in 0..nullity {
            let row = rank + c;
            for i in (0..rank).rev() {
                let mut v = s[row * N + i];
                for j in i + 1..rank {
                    v -= s[j * N + i] * x[j * N + c];
                }
                x[i * N + c] = v / s[i * N + i];
            }
        }
        // (I + X^T X) z = -X^T (target_1 - y) + target_2.
        let mut g = [0.0; N * N];
        let mut b = [0.0; N];
        for a in 0..nullity {
            for c in 0..nullity {
                let dot: f64 = (0..rank).map(|i| x[i * N + a] * x[i * N + c]).sum();
                g[a * N + c] = dot + if a == c { 1.0 } else { 0.0 };
            }
            let pull: f64 = (0..rank)
                .map(|i| x[i * N + a] * (target[perm[i]] - y[i]))
                .sum();
            b[a] = target[perm[rank + a]] - pull;
        }
        // I + X^T X >= I: every pivot is at least 1.
        cholesky_factor(&mut g, nullity, 0.0);
        let mut z = b;
        cholesky_substitute(&g, &mut z, nullity);
        for i in 0..rank {
            let shift: f64 = (0..nullity).map(|c| x[i * N + c] * z[c]).sum();
            permuted[i] -= shift;
        }
        permuted[rank..k].copy_from_slice(&z[..nullity]);
    }
    for i in 0..k {
        p[perm[i]] = permuted[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn closest_solution_check(s: DMatrix<f64>, r: &[f64], target: &[f64]) -> Vec<f64> {
        let k = s.nrows();
        let mut sys = [0.0; N * N];
        for i in 0..k {
            for j in 0..k {
                sys[i * N + j] = s[(i, j)];
            }
        }
        let mut rr = [0.0; N];
        let mut tt = [0.0; N];
        rr[..k].copy_from_slice(r);
        tt[..k].copy_from_slice(target);
        let mut p = [0.0; N];
        solve_psd_closest(&mut sys, &rr, &tt, k, 1e-11 * s.amax(), &mut p);
        p[..k].to_vec()
    }

    #[test]
    fn singular_system_gives_the_solution_closest_to_the_target() {
        // S = A^T A with A 2 x 4: rank 2. The closest solution to t is t + A^+ (A^-T r ... ) i.e.
        // the projection of t onto {p : S p = r}: p = t + S^+ (r - S t).
        let a = DMatrix::from_row_slice(2, 4, &[1.0, 2.0, 0.5, -1.0, 0.3, -0.7, 1.1, 0.4]);
        let s = a.transpose() * &a;
        let p_true = DMatrix::from_column_slice(4, 1, &[0.2, -0.4, 0.9, 0.1]);
        let r = &s * &p_true;
        let target = [1.0, 2.0, -3.0, 0.5];
        let p = closest_solution_check(s.clone(), r.as_slice(), &target);
        let t = DMatrix::from_column_slice(4, 1, &target);
        let s_pinv = s.clone().pseudo_inverse(1e-10).unwrap();
        let expected = &t + &s_pinv * (&r - &s * &t);
        for i in 0..4 {
            assert!(
                (p[i] - expected[(i, 0)]).abs() < 1e-10,
                "{p:?} vs {expected}"
            );
        }
    }

    #[test]
    fn regular_system_is_solved_exactly() {
        let s = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let r = [1.0, -2.0, 0.5];
        let p = closest_solution_check(s.clone(), &r, &[9.0; 3]);
        let back = &s * DMatrix::from_column_slice(3, 1, &p);
        for i in 0..3 {
            assert!((back[(i, 0)] - r[i]).abs() < 1e-13);
        }
    }
}
