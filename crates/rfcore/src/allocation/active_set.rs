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
//!    [`RANK_TOL`] of their own norm get a zero step. The cold start's first step (every
//!    variable free) uses the factorisation of all columns, which depends on the matrix only and
//!    is made once per solver. Ratio test: the first variable to reach a
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
//!
//! # Where the parts live
//! The scaled least-squares form is [`crate::allocation::scaling`], the QR and the free-set step
//! [`crate::allocation::factorisation`], the KKT residuals [`crate::allocation::certificate`]. This
//! file holds the active set and its two phases; the entry points that may fall back to Clarabel
//! ([`ActiveSetSolver::solve`], [`ActiveSetSolver::solve_unchecked`],
//! [`ActiveSetSolver::allocate`]) are in [`crate::allocation::allocator`], which composes the
//! active set with [`crate::allocation::clarabel`].

use crate::allocation::certificate::Certificate;
pub use crate::allocation::factorisation::RANK_TOL;
use crate::allocation::factorisation::{
    apply_q, apply_qt, back_substitute, householder_qr, FreeSetFactor,
};
use crate::allocation::problem::{
    require_iteration_bound, require_tolerance, AllocationProblem, AllocationStatus, SolvedBy,
    MAX_VIRTUAL,
};
use crate::allocation::scaling::{ScaledLeastSquares, BIG_WORK, N, ROWS, SMALL_WORK};
use crate::error::Result;

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
    pub(crate) states: [BoundState; N],
    pub(crate) len: usize,
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
    /// The rules: `tolerance > 0` and finite, `max_iterations` in 1..=[`crate::allocation::MAX_ITERATIONS`] when given.
    pub fn check(&self) -> Result<()> {
        require_tolerance(self.tolerance)?;
        if let Some(limit) = self.max_iterations {
            require_iteration_bound(limit)?;
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
    pub(crate) problem: AllocationProblem,
    /// The problem in the solver's internal form.
    pub(crate) scaled: ScaledLeastSquares,
    pub(crate) settings: ActiveSetSettings,
    max_iterations: usize,
    /// The factorisation of all columns (the cold start's first step), made once here since it
    /// depends on the matrix only; `None` above [`SMALL_WORK`] entries (then made per solve).
    all_free: Option<FreeSetFactor<SMALL_WORK>>,
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

/// What phases 1 and 2 reached when it does not certify and the fallback is on (the allocator
/// then falls back to Clarabel).
pub(crate) struct Uncertified {
    pub(crate) t: [f64; N],
    pub(crate) certificate: Certificate,
    pub(crate) iterations: usize,
}

impl ActiveSetSolver {
    /// Prepares a solver with the default [`ActiveSetSettings`].
    pub fn new(problem: &AllocationProblem) -> Self {
        Self::prepare(problem, ActiveSetSettings::default())
    }

    /// Prepares a solver with the given settings, checked first by [`ActiveSetSettings::check`]
    /// (a refusal names the field and the rule; nothing is clamped).
    pub fn with_settings(problem: &AllocationProblem, settings: ActiveSetSettings) -> Result<Self> {
        settings.check()?;
        Ok(Self::prepare(problem, settings))
    }

    /// The solver for settings that hold their rules (the defaults, or checked by the caller).
    fn prepare(problem: &AllocationProblem, settings: ActiveSetSettings) -> Self {
        let m = problem.actuator_count();
        let scaled = ScaledLeastSquares::new(problem);
        let all_free = (scaled.rows * m <= SMALL_WORK).then(|| {
            let free: [usize; N] = std::array::from_fn(|i| i);
            let mut factor = FreeSetFactor::empty();
            scaled.factor_free_set::<SMALL_WORK, 0>(&free[..m], &mut factor);
            factor
        });
        ActiveSetSolver {
            problem: problem.clone(),
            scaled,
            settings,
            max_iterations: settings.max_iterations.unwrap_or(4 * m + 20),
            all_free,
        }
    }

    /// Replaces the iteration bound per phase (1..=[`crate::allocation::MAX_ITERATIONS`]).
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Result<Self> {
        require_iteration_bound(max_iterations)?;
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
        self.scaled.set_bounds(lower, upper)
    }

    pub fn problem(&self) -> &AllocationProblem {
        &self.problem
    }

    /// The certificate ([`Certificate`]) of any commands for `u_c`, with this solver's tolerance.
    pub fn certify(&self, u_c: &[f64], commands: &[f64]) -> Certificate {
        let mut b = [0.0; ROWS];
        self.scaled.rhs(u_c, &mut b);
        let mut t = [0.0; N];
        t[..self.scaled.m].copy_from_slice(&commands[..self.scaled.m]);
        self.scaled
            .certificate(&b, &t, &mut [0.0; N], self.settings.tolerance)
    }

    /// The unconstrained minimiser closest to `T_pref` (bounds ignored): `T_pref + A^+ (b - A
    /// T_pref)` from the QR of the scaled problem, as phase 1's first step computes it (so a small
    /// weight or a weak rotor counts, no rank cut on the curvature). `u_c` has n entries and
    /// `commands` m; false (commands NaN) if `u_c` overflows once scaled.
    pub fn unconstrained(&self, u_c: &[f64], commands: &mut [f64]) -> bool {
        let m = self.scaled.m;
        let mut b = [0.0; ROWS];
        if !self.scaled.rhs(u_c, &mut b) {
            commands[..m].fill(f64::NAN);
            return false;
        }
        let mut t = [0.0; N];
        t[..m].copy_from_slice(&self.scaled.preferred[..m]);
        let mut r = [0.0; ROWS];
        self.scaled.residual(&b, &t, &mut r);
        let mut free = [0usize; N];
        for (i, f) in free.iter_mut().enumerate().take(m) {
            *f = i;
        }
        let mut d = [0.0; N];
        if self.scaled.rows * m <= SMALL_WORK {
            self.scaled
                .lsq_step::<SMALL_WORK, 0>(&free[..m], &r, &t, &mut d);
        } else {
            self.scaled
                .lsq_step::<BIG_WORK, 0>(&free[..m], &r, &t, &mut d);
        }
        for (out, (x, step)) in commands[..m].iter_mut().zip(t.iter().zip(&d)) {
            *out = x + step;
        }
        true
    }

    /// The cold start (when `active` is all free) and phase 1, from `b` (`b_norm = |b|`), with
    /// work arrays of `W >= rows * m` entries: (converged, iterations, closest, commands `t`).
    /// When converged, `g` is the normalised gradient at `t` (phase 1's last release test
    /// computed it from the residual at `t`): what the certificate and phase 2 need.
    // Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn start_and_phase1<const W: usize, const R: usize>(
        &self,
        b: &[f64; ROWS],
        b_norm: f64,
        active: &mut ActiveSet,
        g: &mut [f64; N],
    ) -> (bool, usize, bool, [f64; N]) {
        let m = self.scaled.m;
        let mut t = [0.0; N];
        let cold = active.states[..m].iter().all(|s| *s == BoundState::Free);
        let mut iterations = 0;
        // Known minimiser of the current free set (and whether it is the closest to `T_pref`):
        // skips phase 1's first step.
        let mut at_minimiser = None;
        if cold {
            // Start from the clamped unconstrained solution, holding what the clamp cut.
            for i in 0..m {
                t[i] = self.scaled.preferred[i].clamp(self.scaled.lower[i], self.scaled.upper[i]);
            }
            let mut r = [0.0; ROWS];
            self.scaled.residual_rows::<R>(b, &t, &mut r);
            let mut free = [0usize; N];
            for (i, f) in free.iter_mut().enumerate().take(m) {
                *f = i;
            }
            let mut d = [0.0; N];
            let _ = match &self.all_free {
                Some(factor) => {
                    self.scaled
                        .factored_step::<SMALL_WORK, R>(&free[..m], factor, &r, &t, &mut d)
                }
                None => self.scaled.lsq_step::<W, R>(&free[..m], &r, &t, &mut d),
            };
            iterations += 1;
            let mut inside = true;
            for i in 0..m {
                let guess = t[i] + d[i];
                active.states[i] = if guess <= self.scaled.lower[i] {
                    BoundState::Lower
                } else if guess >= self.scaled.upper[i] {
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
                let (lo, hi) = (self.scaled.lower[i], self.scaled.upper[i]);
                if lo == hi {
                    active.states[i] = BoundState::Lower;
                }
                t[i] = match active.states[i] {
                    BoundState::Lower => lo,
                    BoundState::Upper => hi,
                    BoundState::Free => self.scaled.preferred[i].clamp(lo, hi),
                };
            }
        }
        let (converged, used, closest) = self.phase1::<W, R>(
            b,
            b_norm,
            &mut t,
            &mut active.states,
            self.max_iterations,
            at_minimiser,
            g,
        );
        iterations += used;
        (converged, iterations, closest, t)
    }

    /// Whether phase 2 (the tie rule) may change phase 1's converged answer: only without
    /// regularisation, and when phase 1's answer is not already the closest of the optima (it
    /// ended elsewhere than on a full step, or a held bound has a (near-)zero multiplier, so
    /// other optima may move it).
    pub(crate) fn tie_rule_needed(
        &self,
        closest: bool,
        states: &[BoundState; N],
        g: &[f64; N],
    ) -> bool {
        self.scaled.root_gamma == 0.0 && (!closest || self.degenerate_held(states, g))
    }

    /// [`Self::solve_unchecked`] once `b` is known, with work arrays of `W >= rows * m` entries.
    /// `Err` when it does not certify and the fallback is on (boxed: the rare path, which
    /// allocates anyway). The certificate of phase 1's answer is read off the gradient phase 1
    /// ended with; after a phase 2 that moved the commands it is computed afresh at the new ones.
    pub(crate) fn solve_from<const W: usize, const R: usize>(
        &self,
        b: &[f64; ROWS],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> std::result::Result<SolveReport, Box<Uncertified>> {
        let m = self.scaled.m;
        let tolerance = self.settings.tolerance;
        let b_norm = self.scaled.rhs_norm(b);
        let mut g = [0.0; N];
        let (converged, mut iterations, closest, mut t) =
            self.start_and_phase1::<W, R>(b, b_norm, active, &mut g);
        let mut certificate = if converged {
            self.scaled.certificate_from_gradient(&t, &g, tolerance)
        } else {
            self.scaled
                .certificate_with_rows::<R>(b, b_norm, &t, &mut g, tolerance)
        };
        if converged && certificate.holds() && self.tie_rule_needed(closest, &active.states, &g) {
            let before = t;
            iterations += self.phase2::<W>(&mut t, &mut active.states, &g);
            // Phase 2 changes only the first m entries.
            if t[..m] != before[..m] {
                let after =
                    self.scaled
                        .certificate_with_rows::<R>(b, b_norm, &t, &mut [0.0; N], tolerance);
                if after.holds() {
                    certificate = after;
                } else {
                    t = before;
                }
            }
        }
        if certificate.holds() {
            commands[..m].copy_from_slice(&t[..m]);
            return Ok(SolveReport {
                status: AllocationStatus::Optimal,
                iterations,
                certificate,
                solved_by: SolvedBy::ActiveSet,
            });
        }
        if !self.settings.fallback {
            commands[..m].copy_from_slice(&t[..m]);
            return Ok(SolveReport {
                status: AllocationStatus::IterationLimit,
                iterations,
                certificate,
                solved_by: SolvedBy::ActiveSet,
            });
        }
        Err(Box::new(Uncertified {
            t,
            certificate,
            iterations,
        }))
    }

    /// True when a held variable (not fixed) has a (near-)zero multiplier: phase 2 may move it.
    fn degenerate_held(&self, states: &[BoundState; N], g: &[f64; N]) -> bool {
        (0..self.scaled.m).any(|i| {
            states[i] != BoundState::Free
                && self.scaled.lower[i] != self.scaled.upper[i]
                && g[i].abs() <= DEGENERATE_TOL
        })
    }

    /// Polishes approximate commands `x` (e.g. an interior-point answer): holds what lies within
    /// 1e-7 of a bound (relative to the span), then phases 1 and 2. Returns the commands and a
    /// report (status from the certificate).
    pub(crate) fn polish(
        &self,
        b: &[f64; ROWS],
        x: &[f64],
        active: &mut ActiveSet,
    ) -> ([f64; N], SolveReport) {
        let m = self.scaled.m;
        let mut t = [0.0; N];
        for i in 0..m {
            let (lo, hi) = (self.scaled.lower[i], self.scaled.upper[i]);
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
        let b_norm = self.scaled.rhs_norm(b);
        let (_, mut iterations, _) = self.phase1::<BIG_WORK, 0>(
            b,
            b_norm,
            &mut t,
            &mut active.states,
            self.max_iterations,
            None,
            &mut [0.0; N],
        );
        let mut g = [0.0; N];
        let mut certificate = self
            .scaled
            .certificate(b, &t, &mut g, self.settings.tolerance);
        if self.scaled.root_gamma == 0.0 && certificate.holds() {
            let before = t;
            iterations += self.phase2::<BIG_WORK>(&mut t, &mut active.states, &g);
            let after = self
                .scaled
                .certificate(b, &t, &mut g, self.settings.tolerance);
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
        if !self.scaled.rhs(u_c, &mut b) {
            return None;
        }
        let mut active = ActiveSet::cold(self.scaled.m);
        let (t, report) = self.polish(&b, x, &mut active);
        Some((t[..self.scaled.m].to_vec(), report))
    }

    /// Phase 1 from `t` and `states`; returns (converged, iterations, closest): `closest` when the
    /// answer is a full step of [`Self::lsq_step`], i.e. of the free-set minimisers (held
    /// variables fixed) the one closest to `T_pref`. `at_minimiser`: `t` is already known to be
    /// a free-set minimiser (and whether it is the closest one). When converged, `g` holds the
    /// normalised gradient at the returned `t` (from the residual at exactly that `t`).
    // Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
    #[allow(clippy::needless_range_loop, clippy::too_many_arguments)]
    fn phase1<const W: usize, const R: usize>(
        &self,
        b: &[f64; ROWS],
        b_norm: f64,
        t: &mut [f64; N],
        states: &mut [BoundState; N],
        budget: usize,
        at_minimiser: Option<bool>,
        g: &mut [f64; N],
    ) -> (bool, usize, bool) {
        let m = self.scaled.m;
        let mut iterations = 0;
        let mut excluded = [false; N];
        let mut last_released: Option<usize> = None;
        let mut minimiser = at_minimiser.is_some();
        let mut closest = at_minimiser.unwrap_or(false);
        let mut r = [0.0; ROWS];
        let mut r_valid = false;
        // One factorisation's work arrays per solve, made when the first step needs them (a
        // solve whose cold start lands inside the box never does): each step overwrites what it
        // reads.
        let mut factor: Option<FreeSetFactor<W>> = None;
        loop {
            if !r_valid {
                self.scaled.residual_rows::<R>(b, t, &mut r);
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
                    let factor = factor.get_or_insert_with(FreeSetFactor::empty);
                    self.scaled.factor_free_set::<W, R>(&free[..k], factor);
                    let _ = self
                        .scaled
                        .factored_step::<W, R>(&free[..k], factor, &r, t, &mut d);
                    let (alpha, blocking) = self.ratio_test(&free[..k], &d, t);
                    match (blocking, last_released) {
                        (Some((j, _)), Some(released)) if alpha == 0.0 && j == released => {
                            // The released variable would leave the box at once: hold it again
                            // (back to the previous free set's minimiser).
                            excluded[j] = true;
                            states[j] = if t[j] <= self.scaled.lower[j] {
                                BoundState::Lower
                            } else {
                                BoundState::Upper
                            };
                            let held = if states[j] == BoundState::Lower {
                                self.scaled.lower[j]
                            } else {
                                self.scaled.upper[j]
                            };
                            if t[j] != held {
                                t[j] = held;
                                self.scaled.residual_rows::<R>(b, t, &mut r);
                            }
                        }
                        _ => {
                            for &i in &free[..k] {
                                t[i] = (t[i] + alpha * d[i])
                                    .clamp(self.scaled.lower[i], self.scaled.upper[i]);
                            }
                            if alpha > 0.0 {
                                excluded = [false; N];
                            }
                            last_released = None;
                            r_valid = false;
                            if let Some((j, state)) = blocking {
                                states[j] = state;
                                t[j] = if state == BoundState::Lower {
                                    self.scaled.lower[j]
                                } else {
                                    self.scaled.upper[j]
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
            self.scaled.gradient_rows::<R>(&r, t, b_norm, g);
            let mut worst = (RELEASE_TOL, usize::MAX);
            for i in 0..m {
                if states[i] == BoundState::Free
                    || excluded[i]
                    || self.scaled.lower[i] == self.scaled.upper[i]
                {
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
                ((self.scaled.lower[i] - t[i]) / d[i], BoundState::Lower)
            } else if d[i] > 0.0 {
                ((self.scaled.upper[i] - t[i]) / d[i], BoundState::Upper)
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
    // Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn phase2<const W: usize>(
        &self,
        t: &mut [f64; N],
        states: &mut [BoundState; N],
        g: &[f64; N],
    ) -> usize {
        let m = self.scaled.m;
        let nc = self.scaled.constraint_rows;
        // Eligible: free, or held with a (near-)zero multiplier.
        let mut eligible = [false; N];
        let mut any_held = false;
        for i in 0..m {
            if self.scaled.lower[i] == self.scaled.upper[i] {
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
                    w[c * k + j] = self.scaled.constraint[c * N + i];
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
                u[j] = self.scaled.preferred[i] - t[i];
                size = size.max(t[i].abs()).max(self.scaled.preferred[i].abs());
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
                    states[j] = if t[j] <= self.scaled.lower[j] {
                        BoundState::Lower
                    } else {
                        BoundState::Upper
                    };
                    continue;
                }
                for &i in &free[..k] {
                    t[i] = (t[i] + alpha * d[i]).clamp(self.scaled.lower[i], self.scaled.upper[i]);
                }
                if alpha > 0.0 {
                    excluded = [false; N];
                }
                last_released = None;
                if let Some((j, state)) = blocking {
                    states[j] = state;
                    t[j] = if state == BoundState::Lower {
                        self.scaled.lower[j]
                    } else {
                        self.scaled.upper[j]
                    };
                    continue;
                }
            }
            // Here no step was possible on this free set (the equalities pin it: as many
            // independent constraint rows as free variables) or the step was full. A released
            // variable that cannot move stays free and the multipliers decide what else to
            // release: a tie that needs two variables to move together is only found this way
            // (holding it again stopped short of the closest optimum, issue 27).
            // Multipliers: nu from C_F^T nu = T_F - T_pref,F; mu_i = (T_i - p_i) - c_i^T nu.
            let mut v = [0.0; ROWS];
            for (j, &i) in free[..k].iter().enumerate() {
                v[j] = t[i] - self.scaled.preferred[i];
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
                let mut scale = (t[i] - self.scaled.preferred[i]).abs();
                for c in 0..nc {
                    pull += self.scaled.constraint[c * N + i] * nu[c];
                    scale += (self.scaled.constraint[c * N + i] * nu[c]).abs();
                }
                let mu = t[i] - self.scaled.preferred[i] - pull;
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

    /// A solution broken one way at a time fails its certificate: a multiplier of the wrong sign
    /// (complementarity), a free variable's gradient entry above the tolerance (stationarity), a
    /// free or held command moved by 1e-6 of its range (stationarity), a command past its bound
    /// (bound violation). The solver's own answer holds, and its certificate (read off phase 1's
    /// gradient) is the one computed afresh.
    #[test]
    fn certificate_fails_when_a_multiplier_or_a_command_is_perturbed() {
        let (l, c) = (0.125, 0.0166);
        let matrix = DMatrix::from_row_slice(
            4,
            4,
            &[1.0, 1.0, 1.0, 1.0, -l, l, l, -l, l, -l, l, -l, c, c, -c, -c],
        );
        let upper = 8.5;
        let problem =
            AllocationProblem::new(matrix, &[1.0, 20.0, 20.0, 0.01], &[0.0; 4], &[upper; 4])
                .unwrap();
        let solver = ActiveSetSolver::new(&problem);
        // More thrust and roll torque than the rotors give together: bounds active.
        let u_c = [30.0, 1.5, -0.2, 0.01];
        let mut active = ActiveSet::cold(4);
        let mut commands = [0.0; 4];
        let report = solver.solve_unchecked(&u_c, &mut active, &mut commands);
        assert_eq!(report.solved_by, SolvedBy::ActiveSet);
        assert!(report.certificate.holds(), "{:?}", report.certificate);
        let mut b = [0.0; ROWS];
        assert!(solver.scaled.rhs(&u_c, &mut b));
        let mut t = [0.0; N];
        t[..4].copy_from_slice(&commands);
        let tolerance = solver.settings.tolerance;
        let mut g = [0.0; N];
        assert_eq!(
            solver.scaled.certificate(&b, &t, &mut g, tolerance),
            report.certificate
        );
        let states = active.states();
        let held = (0..4)
            .find(|&i| states[i] != BoundState::Free && g[i].abs() > 1e-6)
            .expect("a held rotor with a nonzero multiplier");
        let free = (0..4)
            .find(|&i| states[i] == BoundState::Free)
            .expect("a free rotor");
        let check = |g: &[f64; N]| solver.scaled.certificate_from_gradient(&t, g, tolerance);
        let recheck = |t: &[f64; N]| solver.scaled.certificate(&b, t, &mut [0.0; N], tolerance);

        let mut wrong = g;
        wrong[held] = -wrong[held];
        let broken = check(&wrong);
        assert!(!broken.holds(), "{broken:?}");
        assert_eq!(broken.complementarity, g[held].abs());
        let mut wrong = g;
        wrong[free] += 2.0 * tolerance;
        let broken = check(&wrong);
        assert!(
            !broken.holds() && broken.stationarity > tolerance,
            "{broken:?}"
        );

        let inward = |x: f64| {
            if x < 0.5 * upper {
                1e-6 * upper
            } else {
                -1e-6 * upper
            }
        };
        let mut moved = t;
        moved[free] += inward(t[free]);
        let broken = recheck(&moved);
        assert!(
            !broken.holds() && broken.stationarity > tolerance,
            "{broken:?}"
        );
        let mut moved = t;
        moved[held] += inward(t[held]);
        let broken = recheck(&moved);
        assert!(
            !broken.holds() && broken.stationarity > tolerance,
            "{broken:?}"
        );
        let mut moved = t;
        moved[held] -= inward(t[held]);
        let broken = recheck(&moved);
        assert!(
            !broken.holds() && broken.bound_violation > tolerance,
            "{broken:?}"
        );
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
