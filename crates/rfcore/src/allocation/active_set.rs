//! The exact active-set solver for [`AllocationProblem`]: the allocation that runs at every
//! control step, so it works in fixed-size arrays (no heap allocation per solve, except in the
//! rare certified fallback).
//!
//! # Algorithm
//! The problem is a bounded least-squares problem `min 1/2 |A T - b|^2`, `lower <= T <= upper`,
//! with `A = [W^(1/2) M; gamma^(1/2) I]` and `b = [W^(1/2) u_c; gamma^(1/2) T_pref]`, solved
//! after an internal scaling (matrix, weights and regularisation by powers of two) so that a
//! problem multiplied by 1e+-150 gives the same commands. Rows of `A` are sorted by decreasing
//! norm once per solver.
//!
//! 1. Phase 1 (a bounded-variable least-squares active set, Stark and Parker): on the free set F,
//!    the step `d = argmin |A_F d - r|` (`r = b - A T`) is computed by a Householder QR of `A_F`
//!    with column pivoting relative to each column's own norm (never the normal equations, so a
//!    weight or a rotor 1e9 times weaker than the others still counts); columns dependent to
//!    [`RANK_TOL`] of their own norm get a zero step. Ratio test: the first variable to reach a
//!    bound is held. At a free-set minimiser, the held variable whose multiplier (the gradient,
//!    normalised by its column norm and the residual scale) has the wrong sign by most is
//!    released. A released variable that would leave the box at once is held again and not
//!    released until the next move (anti-cycling). Iteration bound: `4 m + 20`.
//! 2. Phase 2 (the tie rule, without regularisation): the optimal achieved control `y* = A T*` is
//!    unique, so the set of optima is `{T in the box : M_w T = M_w T*}` (rows with a positive
//!    weight, each normalised, so a small weight is as binding as a large one). Among it the
//!    point closest to `T_pref` is found by a primal active set on `min 1/2 |T - T_pref|^2`
//!    (null-space steps from a QR of `M_w,F^T`).
//! 3. Certificate ([`Certificate`]): the KKT residuals of the result in the problem's scaling.
//!    Status [`AllocationStatus::Optimal`] only when it holds within the tolerance. Otherwise the
//!    solver falls back to Clarabel, polishes its answer with phase 1 from Clarabel's active set,
//!    and records the method that produced the commands ([`SolvedBy`]).

use crate::allocation::clarabel::{allocate_clarabel_unpolished, ClarabelSettings};
use crate::allocation::{
    Allocation, AllocationProblem, AllocationStatus, Certificate, SolvedBy, MAX_ACTUATORS,
    MAX_VIRTUAL,
};
use crate::error::{Result, RfError};

const N: usize = MAX_ACTUATORS;
/// Rows of the stacked least-squares matrix: n weighted rows and m regularisation rows.
const ROWS: usize = MAX_VIRTUAL + N;
/// Work-array sizes (entries, at least `rows * m`): small problems (up to 8 x 8, e.g. 4 axes and
/// up to 16 rotors without regularisation) and the largest.
const SMALL_WORK: usize = 64;
const BIG_WORK: usize = ROWS * N;

/// A column whose part outside the span of the columns already factored is at most this fraction
/// of its own norm is dependent (relative to the column, so the rotor's gain does not matter).
pub const RANK_TOL: f64 = 1e-13;
/// Normalised multipliers below this are treated as zero by the release rule.
const RELEASE_TOL: f64 = 1e-12;
/// Held bounds whose normalised multiplier is below this may be left by the tie rule (phase 2).
const DEGENERATE_TOL: f64 = 1e-9;
/// The default certificate tolerance (relative, see [`Certificate`]).
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

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

/// Settings of the active-set solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveSetSettings {
    /// Certificate tolerance: the answer is `Optimal` when every normalised KKT residual is at
    /// most this (default [`DEFAULT_TOLERANCE`]).
    pub tolerance: f64,
    /// Iteration bound per phase; `None`: `4 m + 20`.
    pub max_iterations: Option<usize>,
    /// Fall back to Clarabel (polished) when the certificate fails (default true).
    pub fallback: bool,
}

impl ActiveSetSettings {
    /// The rules: `tolerance > 0` and finite, `max_iterations >= 1` when given.
    pub fn check(&self) -> Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(RfError::invalid(
                "tolerance",
                format!("must be > 0 and finite, got {}", self.tolerance),
            ));
        }
        if self.max_iterations == Some(0) {
            return Err(RfError::invalid("max_iterations", "must be >= 1, got 0"));
        }
        Ok(())
    }
}

impl Default for ActiveSetSettings {
    fn default() -> Self {
        ActiveSetSettings {
            tolerance: DEFAULT_TOLERANCE,
            max_iterations: None,
            fallback: true,
        }
    }
}

/// The active-set solver for one problem: the scaled, row-sorted matrix is prepared once here.
#[derive(Debug, Clone)]
pub struct ActiveSetSolver {
    problem: AllocationProblem,
    /// The internally scaled problem (Clarabel fallback).
    scaled: AllocationProblem,
    m: usize,
    n: usize,
    rows: usize,
    /// `A`, column-major with leading dimension [`ROWS`], rows sorted by decreasing norm.
    a: [f64; ROWS * N],
    /// Which row of the problem each stored row is: `< n` a weighted row, `n + i` the
    /// regularisation row of actuator i.
    source: [usize; ROWS],
    root_weights: [f64; MAX_VIRTUAL],
    root_gamma: f64,
    /// `1 / s_M`: the virtual control's internal scale.
    u_scale: f64,
    column_norms: [f64; N],
    lower: [f64; N],
    upper: [f64; N],
    preferred: [f64; N],
    /// Phase 2 constraints: rows of the scaled M with a positive weight, unit norm, row-major.
    constraint: [f64; MAX_VIRTUAL * N],
    constraint_rows: usize,
    settings: ActiveSetSettings,
    max_iterations: usize,
}

/// What one solve reports besides the commands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    pub status: AllocationStatus,
    pub iterations: usize,
    /// The KKT residuals of the commands returned.
    pub certificate: Certificate,
    /// Which method produced the commands.
    pub solved_by: SolvedBy,
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
fn norm(v: &[f64]) -> f64 {
    let big = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if big == 0.0 || !big.is_finite() {
        return big;
    }
    let s: f64 = v.iter().map(|x| (x / big) * (x / big)).sum();
    big * s.sqrt()
}

impl ActiveSetSolver {
    /// Prepares a solver with the default [`ActiveSetSettings`].
    pub fn new(problem: &AllocationProblem) -> Self {
        Self::with_settings(problem, ActiveSetSettings::default())
    }

    /// Prepares a solver with the given settings (tolerance validated by [`Self::with_tolerance`]).
    pub fn with_settings(problem: &AllocationProblem, settings: ActiveSetSettings) -> Self {
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
        let mut solver = ActiveSetSolver {
            problem: problem.clone(),
            scaled,
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
            settings,
            max_iterations: settings.max_iterations.unwrap_or(4 * m + 20).max(1),
        };
        for r in 0..n {
            solver.root_weights[r] = weights[r].sqrt();
        }
        // Stacked rows and their norms; sorted by decreasing norm (stable).
        let row = |k: usize, c: usize| -> f64 {
            if k < n {
                solver.root_weights[k] * matrix[(k, c)]
            } else if k - n == c {
                solver.root_gamma
            } else {
                0.0
            }
        };
        let mut order: Vec<(f64, usize)> = (0..rows)
            .map(|k| (norm(&(0..m).map(|c| row(k, c)).collect::<Vec<_>>()), k))
            .collect();
        order.sort_by(|x, y| y.0.total_cmp(&x.0));
        for (slot, &(_, k)) in order.iter().enumerate() {
            solver.source[slot] = k;
            for c in 0..m {
                solver.a[c * ROWS + slot] = row(k, c);
            }
        }
        for c in 0..m {
            solver.column_norms[c] = norm(&solver.a[c * ROWS..c * ROWS + rows]);
            solver.preferred[c] = problem.preferred()[c];
        }
        for r in 0..n {
            if weights[r] > 0.0 {
                let values: Vec<f64> = (0..m).map(|c| matrix[(r, c)]).collect();
                let size = norm(&values);
                if size > 0.0 {
                    let k = solver.constraint_rows;
                    for c in 0..m {
                        solver.constraint[k * N + c] = values[c] / size;
                    }
                    solver.constraint_rows += 1;
                }
            }
        }
        solver.load_bounds();
        solver
    }

    fn load_bounds(&mut self) {
        for i in 0..self.m {
            self.lower[i] = self.problem.lower()[i];
            self.upper[i] = self.problem.upper()[i];
        }
    }

    /// Replaces the iteration bound per phase (at least 1).
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Result<Self> {
        if max_iterations == 0 {
            return Err(RfError::invalid("max_iterations", "must be >= 1, got 0"));
        }
        self.max_iterations = max_iterations;
        self.settings.max_iterations = Some(max_iterations);
        Ok(self)
    }

    /// Replaces the certificate tolerance (> 0, finite).
    pub fn with_tolerance(mut self, tolerance: f64) -> Result<Self> {
        ActiveSetSettings {
            tolerance,
            ..self.settings
        }
        .check()?;
        self.settings.tolerance = tolerance;
        Ok(self)
    }

    /// Turns the Clarabel fallback on or off (on by default).
    pub fn with_fallback(mut self, fallback: bool) -> Self {
        self.settings.fallback = fallback;
        self
    }

    pub fn settings(&self) -> &ActiveSetSettings {
        &self.settings
    }

    /// Replaces the bounds (e.g. rate limits folded in each step), validated like the problem's.
    pub fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<()> {
        self.problem.set_bounds(lower, upper)?;
        self.scaled.set_bounds(lower, upper)?;
        self.load_bounds();
        Ok(())
    }

    pub fn problem(&self) -> &AllocationProblem {
        &self.problem
    }

    /// `b` for `u_c`, in the stored row order; false if it is not finite (a virtual control too
    /// large for the matrix's scale).
    fn rhs(&self, u_c: &[f64], b: &mut [f64; ROWS]) -> bool {
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
        let mut b = [0.0; ROWS];
        if !self.rhs(u_c, &mut b) {
            return Err(RfError::invalid(
                "virtual_control",
                "too large for the scale of the matrix (overflows once scaled)",
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
            certificate: report.certificate,
            solved_by: report.solved_by,
        })
    }

    /// The certificate ([`Certificate`]) of any commands for `u_c`, with this solver's tolerance.
    pub fn certify(&self, u_c: &[f64], commands: &[f64]) -> Certificate {
        let mut b = [0.0; ROWS];
        self.rhs(u_c, &mut b);
        let mut t = [0.0; N];
        t[..self.m].copy_from_slice(&commands[..self.m]);
        self.certificate(&b, &t, &mut [0.0; N])
    }

    /// The unconstrained minimiser closest to `T_pref` (bounds ignored): `T_pref + A^+ (b - A
    /// T_pref)` from the QR of the scaled problem, as phase 1's first step computes it (so a small
    /// weight or a weak rotor counts, no rank cut on the curvature). `u_c` has n entries and
    /// `commands` m; false (commands NaN) if `u_c` overflows once scaled.
    pub fn unconstrained(&self, u_c: &[f64], commands: &mut [f64]) -> bool {
        let m = self.m;
        let mut b = [0.0; ROWS];
        if !self.rhs(u_c, &mut b) {
            commands[..m].fill(f64::NAN);
            return false;
        }
        let mut t = [0.0; N];
        t[..m].copy_from_slice(&self.preferred[..m]);
        let mut r = [0.0; ROWS];
        self.residual(&b, &t, &mut r);
        let mut free = [0usize; N];
        for (i, f) in free.iter_mut().enumerate().take(m) {
            *f = i;
        }
        let mut d = [0.0; N];
        if self.rows * m <= SMALL_WORK {
            self.lsq_step::<SMALL_WORK>(&free[..m], &r, &t, &mut d);
        } else {
            self.lsq_step::<BIG_WORK>(&free[..m], &r, &t, &mut d);
        }
        for (out, (x, step)) in commands[..m].iter_mut().zip(t.iter().zip(&d)) {
            *out = x + step;
        }
        true
    }

    /// The hot path: `u_c` has n finite entries and `commands` m (callers that validated once).
    /// `active` is the warm start on entry and the final active set on return. Every path (single
    /// call, reusable solver, batch) ends here: phase 1, phase 2, certificate, fallback.
    pub fn solve_unchecked(
        &self,
        u_c: &[f64],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> SolveReport {
        let m = self.m;
        active.len = m;
        let mut b = [0.0; ROWS];
        if !self.rhs(u_c, &mut b) {
            commands[..m].fill(f64::NAN);
            return SolveReport {
                status: AllocationStatus::Failed,
                iterations: 0,
                certificate: Certificate::failed(self.settings.tolerance),
                solved_by: SolvedBy::ActiveSet,
            };
        }
        if self.rows * m <= SMALL_WORK {
            self.solve_from::<SMALL_WORK>(u_c, &b, active, commands)
        } else {
            self.solve_from::<BIG_WORK>(u_c, &b, active, commands)
        }
    }

    /// [`Self::solve_unchecked`] once `b` is known, with work arrays of `W >= rows * m` entries.
    fn solve_from<const W: usize>(
        &self,
        u_c: &[f64],
        b: &[f64; ROWS],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> SolveReport {
        let m = self.m;
        let b_norm = self.rhs_norm(b);
        let mut t = [0.0; N];
        let cold = active.states[..m].iter().all(|s| *s == BoundState::Free);
        let mut iterations = 0;
        // Known minimiser of the current free set (and whether it is the closest to `T_pref`):
        // skips phase 1's first step.
        let mut at_minimiser = None;
        if cold {
            // Start from the clamped unconstrained solution, holding what the clamp cut.
            for i in 0..m {
                t[i] = self.preferred[i].clamp(self.lower[i], self.upper[i]);
            }
            let mut r = [0.0; ROWS];
            self.residual(b, &t, &mut r);
            let mut free = [0usize; N];
            for (i, f) in free.iter_mut().enumerate().take(m) {
                *f = i;
            }
            let mut d = [0.0; N];
            let _ = self.lsq_step::<W>(&free[..m], &r, &t, &mut d);
            iterations += 1;
            let mut inside = true;
            for i in 0..m {
                let guess = t[i] + d[i];
                active.states[i] = if guess <= self.lower[i] {
                    BoundState::Lower
                } else if guess >= self.upper[i] {
                    BoundState::Upper
                } else {
                    BoundState::Free
                };
                inside &= active.states[i] == BoundState::Free;
            }
            if inside {
                // The unconstrained minimiser is in the box (the common case): that is the step.
                for i in 0..m {
                    t[i] += d[i];
                }
                at_minimiser = Some(true);
            }
        }
        if at_minimiser.is_none() {
            for i in 0..m {
                let (lo, hi) = (self.lower[i], self.upper[i]);
                if lo == hi {
                    active.states[i] = BoundState::Lower;
                }
                t[i] = match active.states[i] {
                    BoundState::Lower => lo,
                    BoundState::Upper => hi,
                    BoundState::Free => self.preferred[i].clamp(lo, hi),
                };
            }
        }
        // Phase 2 is needed only when phase 1's answer is not already the closest of the optima:
        // it ended elsewhere than on a full step, or a held bound has a zero multiplier (so other
        // optima may move it).
        let (converged, used, closest) = self.phase1::<W>(
            b,
            b_norm,
            &mut t,
            &mut active.states,
            self.max_iterations,
            at_minimiser,
        );
        iterations += used;
        let mut g = [0.0; N];
        let mut certificate = self.certificate_with(b, b_norm, &t, &mut g);
        if converged
            && self.root_gamma == 0.0
            && certificate.holds()
            && (!closest || self.degenerate_held(&active.states, &g))
        {
            let before = t;
            let used = self.phase2::<W>(&mut t, &mut active.states, &g);
            iterations += used;
            let mut g2 = [0.0; N];
            let after = self.certificate_with(b, b_norm, &t, &mut g2);
            if after.holds() {
                certificate = after;
            } else {
                t = before;
            }
        }
        if certificate.holds() {
            commands[..m].copy_from_slice(&t[..m]);
            return SolveReport {
                status: AllocationStatus::Optimal,
                iterations,
                certificate,
                solved_by: SolvedBy::ActiveSet,
            };
        }
        if !self.settings.fallback {
            commands[..m].copy_from_slice(&t[..m]);
            return SolveReport {
                status: AllocationStatus::IterationLimit,
                iterations,
                certificate,
                solved_by: SolvedBy::ActiveSet,
            };
        }
        self.fallback(u_c, b, active, commands, iterations, (t, certificate))
    }

    /// True when a held variable (not fixed) has a (near-)zero multiplier: phase 2 may move it.
    fn degenerate_held(&self, states: &[BoundState; N], g: &[f64; N]) -> bool {
        (0..self.m).any(|i| {
            states[i] != BoundState::Free
                && self.lower[i] != self.upper[i]
                && g[i].abs() <= DEGENERATE_TOL
        })
    }

    /// Clarabel on the scaled problem, then phase 1 (and 2) from the active set it identifies.
    fn fallback(
        &self,
        u_c: &[f64],
        b: &[f64; ROWS],
        active: &mut ActiveSet,
        commands: &mut [f64],
        iterations: usize,
        (t_own, cert_own): ([f64; N], Certificate),
    ) -> SolveReport {
        let m = self.m;
        let scaled_u: Vec<f64> = u_c.iter().map(|u| u * self.u_scale).collect();
        let settings = ClarabelSettings {
            tolerance: 1e-12,
            max_iterations: 400,
        };
        let reference = allocate_clarabel_unpolished(&self.scaled, &scaled_u, &settings);
        let Ok(reference) = reference else {
            commands[..m].copy_from_slice(&t_own[..m]);
            return SolveReport {
                status: AllocationStatus::Failed,
                iterations,
                certificate: cert_own,
                solved_by: SolvedBy::ActiveSet,
            };
        };
        let mut iterations = iterations + reference.iterations;
        let (t, report) = self.polish(b, &reference.commands, active);
        iterations += report.iterations;
        if report.certificate.holds() {
            commands[..m].copy_from_slice(&t[..m]);
            return SolveReport {
                status: AllocationStatus::Optimal,
                iterations,
                certificate: report.certificate,
                solved_by: SolvedBy::Clarabel,
            };
        }
        // Neither certified: the better of the two by certificate, never labelled optimal.
        let mut raw = [0.0; N];
        raw[..m].copy_from_slice(&reference.commands);
        let cert_raw = self.certificate(b, &raw, &mut [0.0; N]);
        let (best, cert, by) = if cert_raw.worst() < cert_own.worst() {
            (raw, cert_raw, SolvedBy::Clarabel)
        } else {
            (t_own, cert_own, SolvedBy::ActiveSet)
        };
        commands[..m].copy_from_slice(&best[..m]);
        SolveReport {
            status: if reference.status == AllocationStatus::Failed {
                AllocationStatus::Failed
            } else {
                AllocationStatus::IterationLimit
            },
            iterations,
            certificate: cert,
            solved_by: by,
        }
    }

    /// Polishes approximate commands `x` (e.g. an interior-point answer): holds what lies within
    /// 1e-7 of a bound (relative to the span), then phases 1 and 2. Returns the commands and a
    /// report (status from the certificate).
    fn polish(
        &self,
        b: &[f64; ROWS],
        x: &[f64],
        active: &mut ActiveSet,
    ) -> ([f64; N], SolveReport) {
        let m = self.m;
        let mut t = [0.0; N];
        for i in 0..m {
            let (lo, hi) = (self.lower[i], self.upper[i]);
            let band = 1e-7 * (hi - lo).max(lo.abs().max(hi.abs())).max(f64::MIN_POSITIVE);
            active.states[i] = if lo == hi || x[i] <= lo + band {
                BoundState::Lower
            } else if x[i] >= hi - band {
                BoundState::Upper
            } else {
                BoundState::Free
            };
            t[i] = match active.states[i] {
                BoundState::Lower => lo,
                BoundState::Upper => hi,
                BoundState::Free => x[i],
            };
        }
        let b_norm = self.rhs_norm(b);
        let (_, mut iterations, _) = self.phase1::<BIG_WORK>(
            b,
            b_norm,
            &mut t,
            &mut active.states,
            self.max_iterations,
            None,
        );
        let mut g = [0.0; N];
        let mut certificate = self.certificate(b, &t, &mut g);
        if self.root_gamma == 0.0 && certificate.holds() {
            let before = t;
            iterations += self.phase2::<BIG_WORK>(&mut t, &mut active.states, &g);
            let after = self.certificate(b, &t, &mut g);
            if after.holds() {
                certificate = after;
            } else {
                t = before;
            }
        }
        let status = if certificate.holds() {
            AllocationStatus::Optimal
        } else {
            AllocationStatus::IterationLimit
        };
        (
            t,
            SolveReport {
                status,
                iterations,
                certificate,
                solved_by: SolvedBy::Clarabel,
            },
        )
    }

    /// Polishes an approximate answer of the original problem (used by the Clarabel method).
    pub fn polish_commands(&self, u_c: &[f64], x: &[f64]) -> Option<(Vec<f64>, SolveReport)> {
        let mut b = [0.0; ROWS];
        if !self.rhs(u_c, &mut b) {
            return None;
        }
        let mut active = ActiveSet::cold(self.m);
        let (t, report) = self.polish(&b, x, &mut active);
        Some((t[..self.m].to_vec(), report))
    }

    /// `r = b - A T`.
    fn residual(&self, b: &[f64; ROWS], t: &[f64; N], r: &mut [f64; ROWS]) {
        r[..self.rows].copy_from_slice(&b[..self.rows]);
        for c in 0..self.m {
            let x = t[c];
            if x != 0.0 {
                let col = &self.a[c * ROWS..c * ROWS + self.rows];
                for (ri, a) in r.iter_mut().zip(col) {
                    *ri -= a * x;
                }
            }
        }
    }

    /// `|b|`.
    fn rhs_norm(&self, b: &[f64; ROWS]) -> f64 {
        let sq = sum_sq(&b[..self.rows]);
        if (SAFE_SQ_MIN..=SAFE_SQ_MAX).contains(&sq) {
            sq.sqrt()
        } else {
            norm(&b[..self.rows])
        }
    }

    /// The normalised gradient at `t` from its residual `r = b - A t` (`b_norm = |b|`).
    fn gradient(&self, r: &[f64; ROWS], t: &[f64; N], b_norm: f64, g: &mut [f64; N]) {
        let mut scale = b_norm;
        for c in 0..self.m {
            scale += self.column_norms[c] * t[c].abs();
        }
        for i in 0..self.m {
            let col = &self.a[i * ROWS..i * ROWS + self.rows];
            let gi: f64 = -col
                .iter()
                .zip(&r[..self.rows])
                .map(|(a, x)| a * x)
                .sum::<f64>();
            let s = self.column_norms[i] * scale;
            g[i] = if s > 0.0 && s.is_finite() {
                gi / s
            } else {
                0.0
            };
        }
    }

    /// The certificate at `t`; `g` receives the normalised gradient.
    fn certificate(&self, b: &[f64; ROWS], t: &[f64; N], g: &mut [f64; N]) -> Certificate {
        self.certificate_with(b, self.rhs_norm(b), t, g)
    }

    /// [`Self::certificate`] with `b_norm = |b|` known.
    fn certificate_with(
        &self,
        b: &[f64; ROWS],
        b_norm: f64,
        t: &[f64; N],
        g: &mut [f64; N],
    ) -> Certificate {
        let mut r = [0.0; ROWS];
        self.residual(b, t, &mut r);
        self.gradient(&r, t, b_norm, g);
        let mut out = Certificate {
            stationarity: 0.0,
            complementarity: 0.0,
            bound_violation: 0.0,
            tolerance: self.settings.tolerance,
        };
        for i in 0..self.m {
            if !g[i].is_finite() || !t[i].is_finite() {
                out.stationarity = f64::INFINITY;
                continue;
            }
            let (lo, hi, x) = (self.lower[i], self.upper[i], t[i]);
            let span = (hi - lo).max(lo.abs()).max(hi.abs());
            let span = if span > 0.0 { span } else { 1.0 };
            out.bound_violation = out
                .bound_violation
                .max((lo - x).max(x - hi).max(0.0) / span);
            if lo == hi {
                continue;
            }
            if x <= lo {
                out.complementarity = out.complementarity.max(-g[i]);
            } else if x >= hi {
                out.complementarity = out.complementarity.max(g[i]);
            } else {
                out.stationarity = out.stationarity.max(g[i].abs());
            }
        }
        out
    }

    /// The step `d = argmin |A_F d - r|` on the free columns; when `A_F` has dependent columns,
    /// the one of those minimisers that lands closest to `T_pref` (`min |T_F + d - T_pref,F|`,
    /// the tie rule on this free set), from a complete orthogonal decomposition: the pivoted QR
    /// `A_F P = Q [R11 R12; 0 0]`, then `[R11 R12] = [T11 0] Z` by Householder reflectors from
    /// the right (LAPACK's RZ), so `d = P Z^T [T11^-1 (Q^T r)_1; (Z P^T (T_pref - T)_F)_2]`.
    /// Returns the numerical rank of `A_F`.
    fn lsq_step<const W: usize>(
        &self,
        free: &[usize],
        r: &[f64; ROWS],
        t: &[f64; N],
        d: &mut [f64; N],
    ) -> usize {
        let k = free.len();
        let rows = self.rows;
        // A_F packed column-major (leading dimension `rows`).
        let mut w = [0.0; W];
        for (j, &i) in free.iter().enumerate() {
            w[j * rows..j * rows + rows].copy_from_slice(&self.a[i * ROWS..i * ROWS + rows]);
        }
        let mut perm = [0usize; N];
        let mut tau = [0.0; N];
        let rank = householder_qr(&mut w, rows, rows, k, &mut perm, &mut tau);
        let mut y = [0.0; ROWS];
        y[..rows].copy_from_slice(&r[..rows]);
        apply_qt(&w, rows, rows, rank, &tau, &mut y);
        if rank == k {
            back_substitute(&w, rows, rank, &mut y);
            for j in 0..k {
                d[free[perm[j]]] = y[j];
            }
            return rank;
        }
        // RZ: row i of [R11 R12] (entries i and rank..k) reduced to T11's diagonal entry.
        let (ld, nz) = (rows, k - rank);
        let mut zv = [0.0; W];
        let mut ztau = [0.0; N];
        for i in (0..rank).rev() {
            let x0 = w[i * ld + i];
            let mut sq = x0 * x0;
            for j in 0..nz {
                let x = w[(rank + j) * ld + i];
                sq += x * x;
            }
            let alpha = if (SAFE_SQ_MIN..=SAFE_SQ_MAX).contains(&sq) {
                sq.sqrt()
            } else {
                let mut row = [0.0; N];
                row[0] = x0;
                for j in 0..nz {
                    row[1 + j] = w[(rank + j) * ld + i];
                }
                norm(&row[..=nz])
            };
            let beta = if x0 >= 0.0 { -alpha } else { alpha };
            let v0 = x0 - beta;
            for j in 0..nz {
                zv[i * nz + j] = w[(rank + j) * ld + i] / v0;
            }
            let tz = (beta - x0) / beta;
            ztau[i] = tz;
            w[i * ld + i] = beta;
            let v = &zv[i * nz..i * nz + nz];
            for l in 0..i {
                let mut dot = w[i * ld + l];
                for j in 0..nz {
                    dot += v[j] * w[(rank + j) * ld + l];
                }
                dot *= tz;
                w[i * ld + l] -= dot;
                for j in 0..nz {
                    w[(rank + j) * ld + l] -= dot * v[j];
                }
            }
        }
        let reflect_z = |i: usize, x: &mut [f64; N]| {
            let v = &zv[i * nz..i * nz + nz];
            let mut dot = x[i];
            for j in 0..nz {
                dot += v[j] * x[rank + j];
            }
            dot *= ztau[i];
            x[i] -= dot;
            for j in 0..nz {
                x[rank + j] -= dot * v[j];
            }
        };
        // x = Z P^T (T_pref - T)_F; its first `rank` entries replaced by the basic part.
        let mut x = [0.0; N];
        for j in 0..k {
            let i = free[perm[j]];
            x[j] = self.preferred[i] - t[i];
        }
        for i in (0..rank).rev() {
            reflect_z(i, &mut x);
        }
        back_substitute(&w, ld, rank, &mut y);
        x[..rank].copy_from_slice(&y[..rank]);
        for i in 0..rank {
            reflect_z(i, &mut x);
        }
        for j in 0..k {
            d[free[perm[j]]] = x[j];
        }
        rank
    }

    /// Phase 1 from `t` and `states`; returns (converged, iterations, closest): `closest` when the
    /// answer is a full step of [`Self::lsq_step`], i.e. of the free-set minimisers (held
    /// variables fixed) the one closest to `T_pref`. `at_minimiser`: `t` is already known to be
    /// a free-set minimiser (and whether it is the closest one).
    fn phase1<const W: usize>(
        &self,
        b: &[f64; ROWS],
        b_norm: f64,
        t: &mut [f64; N],
        states: &mut [BoundState; N],
        budget: usize,
        at_minimiser: Option<bool>,
    ) -> (bool, usize, bool) {
        let m = self.m;
        let mut iterations = 0;
        let mut excluded = [false; N];
        let mut last_released: Option<usize> = None;
        let mut minimiser = at_minimiser.is_some();
        let mut closest = at_minimiser.unwrap_or(false);
        let mut r = [0.0; ROWS];
        let mut r_valid = false;
        loop {
            if !r_valid {
                self.residual(b, t, &mut r);
                r_valid = true;
            }
            if !minimiser {
                let mut free = [0usize; N];
                let mut k = 0;
                for i in 0..m {
                    if states[i] == BoundState::Free {
                        free[k] = i;
                        k += 1;
                    }
                }
                if k > 0 {
                    if iterations == budget {
                        return (false, iterations, false);
                    }
                    iterations += 1;
                    let mut d = [0.0; N];
                    let _ = self.lsq_step::<W>(&free[..k], &r, t, &mut d);
                    let (alpha, blocking) = self.ratio_test(&free[..k], &d, t);
                    match (blocking, last_released) {
                        (Some((j, _)), Some(released)) if alpha == 0.0 && j == released => {
                            // The released variable would leave the box at once: hold it again
                            // (back to the previous free set's minimiser).
                            excluded[j] = true;
                            states[j] = if t[j] <= self.lower[j] {
                                BoundState::Lower
                            } else {
                                BoundState::Upper
                            };
                            let held = if states[j] == BoundState::Lower {
                                self.lower[j]
                            } else {
                                self.upper[j]
                            };
                            if t[j] != held {
                                t[j] = held;
                                self.residual(b, t, &mut r);
                            }
                        }
                        _ => {
                            for &i in &free[..k] {
                                t[i] = (t[i] + alpha * d[i]).clamp(self.lower[i], self.upper[i]);
                            }
                            if alpha > 0.0 {
                                excluded = [false; N];
                            }
                            last_released = None;
                            r_valid = false;
                            if let Some((j, state)) = blocking {
                                states[j] = state;
                                t[j] = if state == BoundState::Lower {
                                    self.lower[j]
                                } else {
                                    self.upper[j]
                                };
                            } else {
                                minimiser = true;
                                closest = true;
                            }
                            continue;
                        }
                    }
                } else {
                    closest = true;
                }
            }
            minimiser = false;
            // A free-set minimiser: release the held variable with the worst multiplier.
            let mut g = [0.0; N];
            self.gradient(&r, t, b_norm, &mut g);
            let mut worst = (RELEASE_TOL, usize::MAX);
            for i in 0..m {
                if states[i] == BoundState::Free || excluded[i] || self.lower[i] == self.upper[i] {
                    continue;
                }
                let violation = if states[i] == BoundState::Lower {
                    -g[i]
                } else {
                    g[i]
                };
                if violation > worst.0 {
                    worst = (violation, i);
                }
            }
            if worst.1 == usize::MAX {
                return (true, iterations, closest);
            }
            if iterations == budget {
                return (false, iterations, false);
            }
            states[worst.1] = BoundState::Free;
            last_released = Some(worst.1);
            closest = false;
        }
    }

    /// Largest `alpha <= 1` keeping `t + alpha d` in the box, and the variable that blocks.
    fn ratio_test(
        &self,
        free: &[usize],
        d: &[f64; N],
        t: &[f64; N],
    ) -> (f64, Option<(usize, BoundState)>) {
        let mut alpha = 1.0;
        let mut blocking = None;
        for &i in free {
            let (limit, state) = if d[i] < 0.0 {
                ((self.lower[i] - t[i]) / d[i], BoundState::Lower)
            } else if d[i] > 0.0 {
                ((self.upper[i] - t[i]) / d[i], BoundState::Upper)
            } else {
                continue;
            };
            let limit = limit.max(0.0);
            if limit < alpha {
                alpha = limit;
                blocking = Some((i, state));
            }
        }
        (alpha, blocking)
    }

    /// Phase 2 (the tie rule): the optimum closest to `T_pref`, keeping `M_w T` (module docs).
    /// `g` is phase 1's normalised gradient. Returns the iterations used.
    fn phase2<const W: usize>(
        &self,
        t: &mut [f64; N],
        states: &mut [BoundState; N],
        g: &[f64; N],
    ) -> usize {
        let m = self.m;
        let nc = self.constraint_rows;
        // Eligible: free, or held with a (near-)zero multiplier.
        let mut eligible = [false; N];
        let mut any_held = false;
        for i in 0..m {
            if self.lower[i] == self.upper[i] {
                continue;
            }
            eligible[i] = states[i] == BoundState::Free || g[i].abs() <= DEGENERATE_TOL;
            any_held |= eligible[i] && states[i] != BoundState::Free;
        }
        let mut iterations = 0;
        let mut excluded = [false; N];
        let mut last_released: Option<usize> = None;
        let mut first = true;
        loop {
            let mut free = [0usize; N];
            let mut k = 0;
            for i in 0..m {
                if eligible[i] && states[i] == BoundState::Free {
                    free[k] = i;
                    k += 1;
                }
            }
            // C_F^T: k x nc, packed column-major (leading dimension k).
            let mut w = [0.0; W];
            for c in 0..nc {
                for (j, &i) in free[..k].iter().enumerate() {
                    w[c * k + j] = self.constraint[c * N + i];
                }
            }
            let mut perm = [0usize; MAX_VIRTUAL];
            let mut tau = [0.0; MAX_VIRTUAL];
            let rank = householder_qr(&mut w, k, k, nc, &mut perm, &mut tau);
            if first && rank == k && !any_held {
                return iterations; // unique: nothing to choose
            }
            first = false;
            if iterations == self.max_iterations {
                return iterations;
            }
            iterations += 1;
            // d = (I - Q1 Q1^T)(T_pref - T) on F.
            let mut u = [0.0; ROWS];
            let mut size = 0.0f64;
            for (j, &i) in free[..k].iter().enumerate() {
                u[j] = self.preferred[i] - t[i];
                size = size.max(t[i].abs()).max(self.preferred[i].abs());
            }
            apply_qt(&w, k, k, rank, &tau, &mut u);
            u[..rank].fill(0.0);
            apply_q(&w, k, k, rank, &tau, &mut u);
            let mut d = [0.0; N];
            let mut moves = false;
            for (j, &i) in free[..k].iter().enumerate() {
                d[i] = u[j];
                moves |= u[j].abs() > 1e-15 * size.max(f64::MIN_POSITIVE);
            }
            if moves {
                let (alpha, blocking) = self.ratio_test(&free[..k], &d, t);
                let bounced = matches!((blocking, last_released),
                    (Some((j, _)), Some(r)) if alpha == 0.0 && j == r);
                if bounced {
                    let j = last_released.unwrap_or(0);
                    excluded[j] = true;
                    states[j] = if t[j] <= self.lower[j] {
                        BoundState::Lower
                    } else {
                        BoundState::Upper
                    };
                    continue;
                }
                for &i in &free[..k] {
                    t[i] = (t[i] + alpha * d[i]).clamp(self.lower[i], self.upper[i]);
                }
                if alpha > 0.0 {
                    excluded = [false; N];
                }
                last_released = None;
                if let Some((j, state)) = blocking {
                    states[j] = state;
                    t[j] = if state == BoundState::Lower {
                        self.lower[j]
                    } else {
                        self.upper[j]
                    };
                    continue;
                }
            } else if let Some(j) = last_released.take() {
                // Released but cannot move: hold it again.
                excluded[j] = true;
                states[j] = if t[j] <= self.lower[j] {
                    BoundState::Lower
                } else {
                    BoundState::Upper
                };
                continue;
            }
            // Multipliers: nu from C_F^T nu = T_F - T_pref,F; mu_i = (T_i - p_i) - c_i^T nu.
            let mut v = [0.0; ROWS];
            for (j, &i) in free[..k].iter().enumerate() {
                v[j] = t[i] - self.preferred[i];
            }
            apply_qt(&w, k, k, rank, &tau, &mut v);
            back_substitute(&w, k, rank, &mut v);
            let mut nu = [0.0; MAX_VIRTUAL];
            for j in 0..rank {
                nu[perm[j]] = v[j];
            }
            let mut worst = (0.0, usize::MAX);
            for i in 0..m {
                if !eligible[i] || states[i] == BoundState::Free || excluded[i] {
                    continue;
                }
                let mut pull = 0.0;
                let mut scale = (t[i] - self.preferred[i]).abs();
                for c in 0..nc {
                    pull += self.constraint[c * N + i] * nu[c];
                    scale += (self.constraint[c * N + i] * nu[c]).abs();
                }
                let mu = t[i] - self.preferred[i] - pull;
                let violation = if states[i] == BoundState::Lower {
                    -mu
                } else {
                    mu
                };
                if violation > 1e-12 * scale.max(size) && violation > worst.0 {
                    worst = (violation, i);
                }
            }
            if worst.1 == usize::MAX {
                return iterations;
            }
            states[worst.1] = BoundState::Free;
            last_released = Some(worst.1);
        }
    }
}

/// Squared norms at or inside these bounds are computed directly (sum of squares, no scaling):
/// far from underflow and overflow even for the smallest entry that counts at [`RANK_TOL`].
const SAFE_SQ_MIN: f64 = 1.2e-271; // 2^-900
const SAFE_SQ_MAX: f64 = 8.5e270; // 2^900

/// Squared column norms inside these bounds let [`householder_qr`] compare ratios by products of
/// two squared norms without overflow or underflow.
const QR_SQ_MIN: f64 = 3.5e-136; // 2^-450
const QR_SQ_MAX: f64 = 2.9e135; // 2^450

#[inline(always)]
fn sum_sq(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

/// Householder QR with column pivoting of the `rows x k` column-major matrix `a` (leading
/// dimension `ld`), the pivot being the column with the largest remaining norm relative to its
/// own original norm; stops when that ratio is at most [`RANK_TOL`]. Returns the rank; `perm[j]`
/// is the original column in position j; reflectors below the diagonal (unit leading entry).
///
/// Works on squared norms (no division or square root in the pivot search); a column whose
/// squared norm is outside [`QR_SQ_MIN`, `QR_SQ_MAX`] sends the whole factorisation to the
/// scaled (overflow- and underflow-free) version [`householder_qr_scaled`].
fn householder_qr(
    a: &mut [f64],
    ld: usize,
    rows: usize,
    k: usize,
    perm: &mut [usize],
    tau: &mut [f64],
) -> usize {
    // Squared original norms (0: a zero column, never a pivot).
    let mut original = [0.0; ROWS];
    for j in 0..k {
        let sq = sum_sq(&a[j * ld..j * ld + rows]);
        if sq == 0.0 {
            if a[j * ld..j * ld + rows].iter().any(|x| *x != 0.0) {
                return householder_qr_scaled(a, ld, rows, k, perm, tau);
            }
        } else if !(QR_SQ_MIN..=QR_SQ_MAX).contains(&sq) {
            return householder_qr_scaled(a, ld, rows, k, perm, tau);
        }
        original[j] = sq;
        perm[j] = j;
    }
    let threshold = RANK_TOL * RANK_TOL;
    let mut rank = 0;
    for s in 0..rows.min(k) {
        // The largest remaining/original squared-norm ratio above the threshold, compared by
        // cross-multiplication (no division).
        let (mut best_sq, mut best_original) = (0.0, 1.0);
        let mut q = usize::MAX;
        for j in s..k {
            let o = original[perm[j]];
            if o == 0.0 {
                continue;
            }
            let sq = sum_sq(&a[j * ld + s..j * ld + rows]);
            if sq > threshold * o && sq * best_original > best_sq * o {
                best_sq = sq;
                best_original = o;
                q = j;
            }
        }
        if q == usize::MAX {
            break;
        }
        if q != s {
            let (left, right) = a.split_at_mut(q * ld);
            left[s * ld..s * ld + rows].swap_with_slice(&mut right[..rows]);
            perm.swap(s, q);
        }
        reflector(a, ld, rows, k, s, best_sq.sqrt(), tau);
        rank += 1;
    }
    rank
}

/// Forms the reflector of column `s` (`alpha`: the norm of `a[s..rows, s]`, > 0) and applies it
/// to columns `s + 1..k`.
#[inline(always)]
fn reflector(
    a: &mut [f64],
    ld: usize,
    rows: usize,
    k: usize,
    s: usize,
    alpha: f64,
    tau: &mut [f64],
) {
    let col = &mut a[s * ld + s..s * ld + rows];
    let x0 = col[0];
    let beta = if x0 >= 0.0 { -alpha } else { alpha };
    let v0 = x0 - beta;
    let inv = 1.0 / v0;
    if inv.is_finite() {
        for e in col[1..].iter_mut() {
            *e *= inv;
        }
    } else {
        for e in col[1..].iter_mut() {
            *e /= v0;
        }
    }
    let t = (beta - x0) / beta;
    tau[s] = t;
    col[0] = beta;
    let (head, tail) = a.split_at_mut((s + 1) * ld);
    let v = &head[s * ld + s + 1..s * ld + rows];
    for j in 0..k - s - 1 {
        let c = &mut tail[j * ld + s..j * ld + rows];
        let mut dot = c[0];
        for (x, y) in v.iter().zip(&c[1..]) {
            dot += x * y;
        }
        dot *= t;
        c[0] -= dot;
        for (y, x) in c[1..].iter_mut().zip(v) {
            *y -= dot * x;
        }
    }
}

/// [`householder_qr`] with every norm computed by the scaled [`norm`] (entries near underflow or
/// overflow).
#[cold]
fn householder_qr_scaled(
    a: &mut [f64],
    ld: usize,
    rows: usize,
    k: usize,
    perm: &mut [usize],
    tau: &mut [f64],
) -> usize {
    let mut norms = [0.0; ROWS];
    for j in 0..k {
        norms[j] = norm(&a[j * ld..j * ld + rows]);
        perm[j] = j;
    }
    let mut rank = 0;
    for s in 0..rows.min(k) {
        let mut best = RANK_TOL;
        let mut q = usize::MAX;
        for j in s..k {
            let original = norms[perm[j]];
            if original == 0.0 {
                continue;
            }
            let ratio = norm(&a[j * ld + s..j * ld + rows]) / original;
            if ratio > best {
                best = ratio;
                q = j;
            }
        }
        if q == usize::MAX {
            break;
        }
        if q != s {
            for r in 0..rows {
                a.swap(s * ld + r, q * ld + r);
            }
            perm.swap(s, q);
        }
        let alpha = norm(&a[s * ld + s..s * ld + rows]);
        reflector(a, ld, rows, k, s, alpha, tau);
        rank += 1;
    }
    rank
}

/// `y <- Q^T y` for the first `rank` reflectors of [`householder_qr`].
fn apply_qt(a: &[f64], ld: usize, rows: usize, rank: usize, tau: &[f64], y: &mut [f64]) {
    for s in 0..rank {
        reflect(a, ld, rows, s, tau[s], y);
    }
}

/// `y <- Q y`.
fn apply_q(a: &[f64], ld: usize, rows: usize, rank: usize, tau: &[f64], y: &mut [f64]) {
    for s in (0..rank).rev() {
        reflect(a, ld, rows, s, tau[s], y);
    }
}

fn reflect(a: &[f64], ld: usize, rows: usize, s: usize, tau: f64, y: &mut [f64]) {
    let mut dot = y[s];
    for r in s + 1..rows {
        dot += a[s * ld + r] * y[r];
    }
    dot *= tau;
    y[s] -= dot;
    for r in s + 1..rows {
        y[r] -= dot * a[s * ld + r];
    }
}

/// Solves `R z = y[..rank]` in place (R upper triangular in `a`).
fn back_substitute(a: &[f64], ld: usize, rank: usize, y: &mut [f64]) {
    for i in (0..rank).rev() {
        let mut v = y[i];
        for j in i + 1..rank {
            v -= a[j * ld + i] * y[j];
        }
        y[i] = v / a[i * ld + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn unconstrained(a: &DMatrix<f64>, b: &[f64], target: &[f64]) -> Vec<f64> {
        let (n, m) = a.shape();
        let problem =
            AllocationProblem::new(a.clone(), &vec![1.0; n], &vec![-1e6; m], &vec![1e6; m])
                .and_then(|p| p.with_regularization(0.0, target))
                .unwrap();
        let mut t = vec![0.0; m];
        assert!(ActiveSetSolver::new(&problem).unconstrained(b, &mut t));
        t
    }

    #[test]
    fn rank_deficient_least_squares_gives_the_solution_closest_to_the_target() {
        // A 2 x 4 (rank 2): the minimisers of |A T - b| closest to t are t + A^+ (b - A t).
        let a = DMatrix::from_row_slice(2, 4, &[1.0, 2.0, 0.5, -1.0, 0.3, -0.7, 1.1, 0.4]);
        let b = [0.7, -1.3];
        let target = [1.0, 2.0, -3.0, 0.5];
        let p = unconstrained(&a, &b, &target);
        let t = DMatrix::from_column_slice(4, 1, &target);
        let a_pinv = a.clone().pseudo_inverse(1e-12).unwrap();
        let expected = &t + &a_pinv * (DMatrix::from_column_slice(2, 1, &b) - &a * &t);
        for i in 0..4 {
            assert!(
                (p[i] - expected[(i, 0)]).abs() < 1e-12,
                "{p:?} vs {expected}"
            );
        }
    }

    #[test]
    fn regular_system_is_solved_exactly() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let b = [1.0, -2.0, 0.5];
        let p = unconstrained(&a, &b, &[9.0; 3]);
        let back = &a * DMatrix::from_column_slice(3, 1, &p);
        for i in 0..3 {
            assert!((back[(i, 0)] - b[i]).abs() < 1e-13);
        }
    }
}
