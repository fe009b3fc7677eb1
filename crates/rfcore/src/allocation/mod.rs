//! Control allocation: the rotor commands `T` (m actuators) that produce a desired virtual control
//! `u_c` (n components, e.g. thrust and three torques) as well as the rotors allow.
//!
//! One problem type, [`AllocationProblem`], serves every method:
//!
//! ```text
//! minimise  1/2 (u_c - M T)^T W (u_c - M T) + gamma/2 |T - T_pref|^2
//! subject   T_min <= T <= T_max
//! ```
//!
//! with `M` the n x m effectiveness matrix, `W = diag(weights)` (weights >= 0; a zero weight drops
//! that axis, as Ke et al. eq. (35) does with the yaw weight) and an optional regularisation
//! `gamma` toward preferred commands. Ke et al. eq. (33) is this problem with `gamma = 0`.
//!
//! Methods:
//! - [`crate::allocation::active_set::ActiveSetSolver`]: exact, allocation-free, warm-startable; the hot path.
//! - [`crate::allocation::clarabel`]: the same problem (and prioritised and attainable-set variants) through
//!   the Clarabel interior-point solver: the reference.
//! - [`weighted_pseudo_inverse`]: the unconstrained solution (Ke eqs. (34)/(35)); bounds ignored.
//!
//! # Which solution, when there are many
//! With more rotors than weighted axes (a hexacopter, or a zero yaw weight) the minimisers form a
//! set. Every method here returns, among them, the one closest to `T_pref` (zero unless set): for
//! the pseudo-inverse exactly `T_pref + A^+ (b - A T_pref)`, i.e. `M^+ u_c` of Ke eq. (34) when
//! `T_pref = 0`, computed from the same QR as the active set (no rank cut on the weights: every
//! positive weight counts); the active-set solver finds the closest optimum also when
//! bounds are active (its phase 2), with no rank cut on the weights. Every active-set answer
//! carries a [`Certificate`]; it is `Optimal` only when that holds, else the solver falls back to
//! Clarabel ([`SolvedBy`]).


use nalgebra::DMatrix;
use rayon::prelude::*;

pub mod active_set;
pub mod clarabel;

use crate::error::{require_all_finite, require_entries, require_finite, Result, RfError};
use active_set::{ActiveSetSettings, ActiveSetSolver};
use clarabel::{allocate_clarabel, allocate_prioritized, ClarabelSettings};

/// Most actuators a problem may have (the active-set solver works in fixed-size arrays).
pub const MAX_ACTUATORS: usize = 16;
/// Most virtual-control components a problem may have.
pub const MAX_VIRTUAL: usize = 12;

/// A box-constrained weighted least-squares allocation problem (module docs). Validated on
/// construction; every field is read-only afterwards.
#[derive(Debug, Clone, PartialEq)]
pub struct AllocationProblem {
    matrix: DMatrix<f64>,
    weights: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    regularization: f64,
    preferred: Vec<f64>,
}

impl AllocationProblem {
    /// `matrix` is n x m (1 <= n <= [`MAX_VIRTUAL`], 1 <= m <= [`MAX_ACTUATORS`]); `weights` has n
    /// entries >= 0; `lower`/`upper` have m entries with `lower <= upper`. All finite.
    pub fn new(
        matrix: DMatrix<f64>,
        weights: &[f64],
        lower: &[f64],
        upper: &[f64],
    ) -> Result<Self> {
        let (n, m) = matrix.shape();
        if n == 0 || n > MAX_VIRTUAL {
            return Err(RfError::shape(
                "matrix",
                format!("1 to {MAX_VIRTUAL} rows (virtual-control components)"),
                n.to_string(),
            ));
        }
        if m == 0 || m > MAX_ACTUATORS {
            return Err(RfError::shape(
                "matrix",
                format!("1 to {MAX_ACTUATORS} columns (actuators)"),
                m.to_string(),
            ));
        }
        if let Some(i) = matrix.iter().position(|v| !v.is_finite()) {
            return Err(RfError::invalid(
                format!("matrix[{}, {}]", i % n, i / n),
                format!("must be finite, got {}", matrix.as_slice()[i]),
            ));
        }
        require_entries("weights", weights, n, "one per virtual-control component")?;
        require_all_finite("weights", weights)?;
        if let Some(i) = weights.iter().position(|&w| w < 0.0) {
            return Err(RfError::invalid(
                format!("weights[{i}]"),
                format!("must be >= 0, got {}", weights[i]),
            ));
        }
        let mut problem = AllocationProblem {
            matrix,
            weights: weights.to_vec(),
            lower: Vec::new(),
            upper: Vec::new(),
            regularization: 0.0,
            preferred: vec![0.0; m],
        };
        problem.set_bounds(lower, upper)?;
        Ok(problem)
    }

    /// Replaces the bounds (validated as in [`AllocationProblem::new`]).
    pub fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<()> {
        let m = self.actuator_count();
        require_entries("lower", lower, m, "one per actuator")?;
        require_entries("upper", upper, m, "one per actuator")?;
        require_all_finite("lower", lower)?;
        require_all_finite("upper", upper)?;
        if let Some(i) = (0..m).find(|&i| lower[i] > upper[i]) {
            return Err(RfError::invalid(
                format!("lower[{i}]"),
                format!("must not exceed upper[{i}] ({} > {})", lower[i], upper[i]),
            ));
        }
        self.lower = lower.to_vec();
        self.upper = upper.to_vec();
        Ok(())
    }

    /// Adds `gamma/2 |T - preferred|^2` to the objective (`gamma >= 0`, finite).
    pub fn with_regularization(mut self, gamma: f64, preferred: &[f64]) -> Result<Self> {
        require_finite("regularization", gamma)?;
        if gamma < 0.0 {
            return Err(RfError::invalid(
                "regularization",
                format!("must be >= 0, got {gamma}"),
            ));
        }
        require_entries(
            "preferred",
            preferred,
            self.actuator_count(),
            "one per actuator",
        )?;
        require_all_finite("preferred", preferred)?;
        self.regularization = gamma;
        self.preferred = preferred.to_vec();
        Ok(self)
    }

    /// The bounds tightened by a rate limit: each command may move at most `max_change[i]` from
    /// `previous[i]` (e.g. rate x control period). The result always keeps `lower <= upper`: a
    /// previous command outside the bounds is pulled to the nearest bound.
    pub fn rate_limited(&self, previous: &[f64], max_change: &[f64]) -> Result<Self> {
        let m = self.actuator_count();
        require_entries("previous", previous, m, "one per actuator")?;
        require_entries("max_change", max_change, m, "one per actuator")?;
        require_all_finite("previous", previous)?;
        if let Some(i) = max_change.iter().position(|d| d.is_nan() || *d < 0.0) {
            return Err(RfError::invalid(
                format!("max_change[{i}]"),
                format!("must be >= 0 (infinity for none), got {}", max_change[i]),
            ));
        }
        let mut out = self.clone();
        for i in 0..m {
            let (lo, hi) = (self.lower[i], self.upper[i]);
            out.lower[i] = (previous[i] - max_change[i]).clamp(lo, hi);
            out.upper[i] = (previous[i] + max_change[i]).clamp(lo, hi);
        }
        Ok(out)
    }

    pub fn matrix(&self) -> &DMatrix<f64> {
        &self.matrix
    }
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
    pub fn lower(&self) -> &[f64] {
        &self.lower
    }
    pub fn upper(&self) -> &[f64] {
        &self.upper
    }
    pub fn regularization(&self) -> f64 {
        self.regularization
    }
    pub fn preferred(&self) -> &[f64] {
        &self.preferred
    }
    /// m, the number of actuators (columns of M).
    pub fn actuator_count(&self) -> usize {
        self.matrix.ncols()
    }
    /// n, the number of virtual-control components (rows of M).
    pub fn virtual_dimension(&self) -> usize {
        self.matrix.nrows()
    }

    /// Checks a virtual control: n finite entries.
    pub fn check_virtual_control(&self, u_c: &[f64]) -> Result<()> {
        require_entries(
            "virtual_control",
            u_c,
            self.virtual_dimension(),
            "one per virtual-control component",
        )?;
        require_all_finite("virtual_control", u_c)
    }

    /// `M T`.
    pub fn achieved(&self, commands: &[f64]) -> Vec<f64> {
        (0..self.virtual_dimension())
            .map(|r| {
                (0..self.actuator_count())
                    .map(|c| self.matrix[(r, c)] * commands[c])
                    .sum()
            })
            .collect()
    }

    /// The objective of the module docs at `commands`.
    /// Objective and KKT residual of any solver's `commands` for `u_c`, after checking both
    /// (finite, one entry per axis / per actuator): how a user verifies an answer.
    pub fn evaluate(&self, u_c: &[f64], commands: &[f64]) -> Result<(f64, f64)> {
        self.check_virtual_control(u_c)?;
        require_entries(
            "commands",
            commands,
            self.actuator_count(),
            "one per actuator",
        )?;
        require_all_finite("commands", commands)?;
        Ok((
            self.objective(u_c, commands),
            self.kkt_residual(u_c, commands),
        ))
    }

    pub fn objective(&self, u_c: &[f64], commands: &[f64]) -> f64 {
        let achieved = self.achieved(commands);
        let tracking: f64 = (0..self.virtual_dimension())
            .map(|r| self.weights[r] * (u_c[r] - achieved[r]).powi(2))
            .sum();
        let regularization: f64 = commands
            .iter()
            .zip(&self.preferred)
            .map(|(t, p)| (t - p).powi(2))
            .sum();
        0.5 * tracking + 0.5 * self.regularization * regularization
    }

    /// The objective's gradient with respect to the commands, `H T - c` (see [`Self::hessian`]).
    pub fn gradient(&self, u_c: &[f64], commands: &[f64]) -> Vec<f64> {
        let achieved = self.achieved(commands);
        (0..self.actuator_count())
            .map(|c| {
                let tracking: f64 = (0..self.virtual_dimension())
                    .map(|r| self.matrix[(r, c)] * self.weights[r] * (achieved[r] - u_c[r]))
                    .sum();
                tracking + self.regularization * (commands[c] - self.preferred[c])
            })
            .collect()
    }

    /// `H = M^T W M + gamma I`, the objective's (constant) Hessian.
    pub fn hessian(&self) -> DMatrix<f64> {
        let m = self.actuator_count();
        DMatrix::from_fn(m, m, |i, j| {
            let curvature: f64 = (0..self.virtual_dimension())
                .map(|r| self.matrix[(r, i)] * self.weights[r] * self.matrix[(r, j)])
                .sum();
            curvature + if i == j { self.regularization } else { 0.0 }
        })
    }

    /// The KKT (first-order optimality) residual of `commands`: the largest entry of
    /// `|T - clamp(T - g / s, lower, upper)|` with `g` the gradient and `s` the largest entry of
    /// the Hessian, plus any bound violation. In command units (N for thrust); zero exactly at a
    /// solution. The scaling by `s` makes it invariant to the scale of the weights.
    pub fn kkt_residual(&self, u_c: &[f64], commands: &[f64]) -> f64 {
        let gradient = self.gradient(u_c, commands);
        let scale = self.hessian().amax();
        let scale = if scale > 0.0 { scale } else { 1.0 };
        (0..self.actuator_count())
            .map(|i| {
                let (lo, hi, t) = (self.lower[i], self.upper[i], commands[i]);
                let projected = (t - gradient[i] / scale).clamp(lo, hi);
                let violation = (lo - t).max(t - hi).max(0.0);
                (t - projected).abs().max(violation)
            })
            .fold(0.0, f64::max)
    }
}

/// How an allocation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AllocationStatus {
    /// Solved to the solver's tolerance.
    Optimal,
    /// Clarabel finished at reduced accuracy.
    AlmostOptimal,
    /// The active-set solver could not certify its answer (iteration bound, or the certificate
    /// above its tolerance) and neither could its fallback; the commands are feasible, not proven
    /// optimal (see the allocation's certificate).
    IterationLimit,
    /// The unconstrained pseudo-inverse: bounds were not applied.
    Unconstrained,
    /// Clarabel stopped without a solution (iteration limit, numerical trouble, infeasible
    /// equality constraints); the commands are its last iterate.
    Failed,
}

impl AllocationStatus {
    /// A short stable name (`"optimal"`, `"iteration-limit"`, ...), as Python reports it.
    pub fn name(self) -> &'static str {
        match self {
            AllocationStatus::Optimal => "optimal",
            AllocationStatus::AlmostOptimal => "almost-optimal",
            AllocationStatus::IterationLimit => "iteration-limit",
            AllocationStatus::Unconstrained => "unconstrained",
            AllocationStatus::Failed => "failed",
        }
    }
}

/// Which method produced an allocation's commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SolvedBy {
    /// The active-set solver on its own.
    ActiveSet,
    /// Clarabel (as the fallback of the active-set solver, or asked for), polished by the
    /// active set from Clarabel's active set when that certifies.
    Clarabel,
    /// The unconstrained pseudo-inverse.
    PseudoInverse,
}

impl SolvedBy {
    /// `"active-set"`, `"clarabel"` or `"pinv"`.
    pub fn name(self) -> &'static str {
        match self {
            SolvedBy::ActiveSet => "active-set",
            SolvedBy::Clarabel => "clarabel",
            SolvedBy::PseudoInverse => "pinv",
        }
    }
}

/// The KKT residuals of an allocation, dimensionless, in the problem's own scaling: with
/// `A = [W^(1/2) M; gamma^(1/2) I]` and `b` the matching right-hand side (after the internal
/// power-of-two scaling), the gradient entry `g_i = a_i^T (A T - b)` is divided by
/// `|a_i| (|b| + sum_j |a_j| |T_j|)` (a bound on the size of the terms it sums, so it is invariant
/// to scaling the matrix, the virtual control, the weights or one actuator's gain).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Certificate {
    /// Largest normalised gradient entry of a variable strictly inside its bounds.
    pub stationarity: f64,
    /// Largest wrong-signed normalised multiplier of a variable at a bound (the complementarity
    /// conditions `min(T - lower, g) = 0`, `min(upper - T, -g) = 0`).
    pub complementarity: f64,
    /// Largest bound violation, relative to `max(upper - lower, |lower|, |upper|)`.
    pub bound_violation: f64,
    /// The tolerance the three are compared with.
    pub tolerance: f64,
}

impl Certificate {
    /// The largest of the three residuals.
    pub fn worst(&self) -> f64 {
        self.stationarity
            .max(self.complementarity)
            .max(self.bound_violation)
    }
    /// True when every residual is at most the tolerance (NaN never holds).
    pub fn holds(&self) -> bool {
        self.worst() <= self.tolerance
    }
    /// The certificate of no answer.
    pub(crate) fn failed(tolerance: f64) -> Self {
        Certificate {
            stationarity: f64::INFINITY,
            complementarity: f64::INFINITY,
            bound_violation: f64::INFINITY,
            tolerance,
        }
    }
}

/// The result of one allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct Allocation {
    /// Rotor commands T (m).
    pub commands: Vec<f64>,
    /// The virtual control they produce, `M T` (n).
    pub achieved: Vec<f64>,
    pub status: AllocationStatus,
    /// Solver iterations (0 for the pseudo-inverse).
    pub iterations: usize,
    /// KKT residuals of `commands` (for the pseudo-inverse: of the unconstrained problem's
    /// answer against the constrained problem, so usually not holding).
    pub certificate: Certificate,
    /// The method that produced `commands`.
    pub solved_by: SolvedBy,
}

/// How many allocations of a batch were produced by the Clarabel fallback of the active-set
/// method.
pub fn fallback_count(results: &[Allocation]) -> usize {
    results
        .iter()
        .filter(|a| a.solved_by == SolvedBy::Clarabel)
        .count()
}

/// The unconstrained solution as a matrix `P` and offset `o`: `T = P u_c + o`, with
/// `P = A^+ W^(1/2)`, `A = W^(1/2) M` (Ke eq. (34); eq. (35) when a weight is zero), extended by the
/// regularisation and the closest-to-preferred rule of the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct WeightedPseudoInverse {
    gain: DMatrix<f64>,
    offset: Vec<f64>,
}

/// Builds the [`WeightedPseudoInverse`] of a problem (bounds are ignored): column r of `P` is the
/// answer for the unit virtual control `e_r` less the answer for zero (`o`), each from the
/// active-set solver's QR of the scaled problem ([`ActiveSetSolver::unconstrained`]): every
/// positive weight counts however small (no rank cut on `M^T W M`), and columns dependent to
/// [`active_set::RANK_TOL`] of their own norm share the load by the closest-to-preferred rule.
pub fn weighted_pseudo_inverse(problem: &AllocationProblem) -> WeightedPseudoInverse {
    let (n, m) = problem.matrix.shape();
    let solver = ActiveSetSolver::new(problem);
    let mut offset = vec![0.0; m];
    let mut column = vec![0.0; m];
    let mut unit = vec![0.0; n];
    let mut gain = DMatrix::zeros(m, n);
    // A matrix so small that a unit virtual control overflows once scaled (entries near the
    // subnormal range) leaves NaN here; `checked_pseudo_inverse` refuses it for the allocations.
    solver.unconstrained(&unit, &mut offset);
    for r in 0..n {
        unit[r] = 1.0;
        solver.unconstrained(&unit, &mut column);
        unit[r] = 0.0;
        for c in 0..m {
            gain[(c, r)] = column[c] - offset[c];
        }
    }
    WeightedPseudoInverse { gain, offset }
}

impl WeightedPseudoInverse {
    /// `P` (m x n).
    pub fn gain(&self) -> &DMatrix<f64> {
        &self.gain
    }
    /// `o` (m): zero unless a preferred command is set.
    pub fn offset(&self) -> &[f64] {
        &self.offset
    }

    /// The unconstrained [`Allocation`] of `u_c` for `problem` (the one this was built from).
    fn allocation(&self, problem: &AllocationProblem, u_c: &[f64]) -> Allocation {
        let mut commands = vec![0.0; problem.actuator_count()];
        self.apply(u_c, &mut commands);
        Allocation {
            achieved: problem.achieved(&commands),
            certificate: ActiveSetSolver::new(problem).certify(u_c, &commands),
            commands,
            status: AllocationStatus::Unconstrained,
            iterations: 0,
            solved_by: SolvedBy::PseudoInverse,
        }
    }

    /// `T = P u_c + o` written into `commands` (lengths checked by the caller's problem).
    pub fn apply(&self, u_c: &[f64], commands: &mut [f64]) {
        for (c, out) in commands.iter_mut().enumerate() {
            *out = self.offset[c]
                + (0..self.gain.ncols())
                    .map(|r| self.gain[(c, r)] * u_c[r])
                    .sum::<f64>();
        }
    }
}

/// [`weighted_pseudo_inverse`], or an error naming the matrix when its entries are too small in
/// scale for a finite pseudo-inverse (never a NaN allocation).
fn checked_pseudo_inverse(problem: &AllocationProblem) -> Result<WeightedPseudoInverse> {
    let pinv = weighted_pseudo_inverse(problem);
    if pinv.gain.iter().chain(&pinv.offset).all(|v| v.is_finite()) {
        Ok(pinv)
    } else {
        Err(RfError::invalid(
            "matrix",
            "too small in scale for a finite pseudo-inverse (entries near the subnormal range)",
        ))
    }
}

/// The unconstrained allocation of one virtual control (status [`AllocationStatus::Unconstrained`]).
pub fn allocate_pinv(problem: &AllocationProblem, u_c: &[f64]) -> Result<Allocation> {
    problem.check_virtual_control(u_c)?;
    Ok(checked_pseudo_inverse(problem)?.allocation(problem, u_c))
}

/// Which solver an allocation uses.
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
    /// [`ActiveSetSolver`] with its settings: exact, the default.
    ActiveSet(ActiveSetSettings),
    /// [`crate::allocation::clarabel::allocate_clarabel`]: the interior-point reference.
    Clarabel(ClarabelSettings),
    /// [`crate::allocation::clarabel::allocate_prioritized`]: groups of rows, most important first.
    Prioritized(Vec<Vec<usize>>, ClarabelSettings),
    /// [`weighted_pseudo_inverse`]: unconstrained.
    Pinv,
}

impl Method {
    /// The method named `name` (`"active-set"`, `"clarabel"`, `"pinv"`), with `priorities`
    /// (groups of rows, most important first; Clarabel only), the active set's `active` settings
    /// and Clarabel's `settings`.
    pub fn parse(
        name: &str,
        priorities: Option<Vec<Vec<usize>>>,
        active: ActiveSetSettings,
        settings: ClarabelSettings,
    ) -> Result<Self> {
        match (name, priorities) {
            ("active-set", None) => Ok(Method::ActiveSet(active)),
            ("pinv", None) => Ok(Method::Pinv),
            ("clarabel", None) => Ok(Method::Clarabel(settings)),
            ("clarabel", Some(groups)) => Ok(Method::Prioritized(groups, settings)),
            ("active-set" | "pinv", Some(_)) => Err(RfError::invalid(
                "priorities",
                "only method=\"clarabel\" solves prioritised allocations",
            )),
            (other, _) => Err(RfError::invalid(
                "method",
                format!("expected \"active-set\", \"clarabel\" or \"pinv\", got {other:?}"),
            )),
        }
    }
}

/// Checks N x n row-major virtual controls: whole rows, finite entries (named `[row, col]`).
pub(crate) fn check_rows(problem: &AllocationProblem, controls: &[f64]) -> Result<()> {
    let n = problem.virtual_dimension();
    if !controls.len().is_multiple_of(n) {
        return Err(RfError::shape(
            "virtual_control",
            format!("rows of {n} entries"),
            format!("{} values", controls.len()),
        ));
    }
    match controls.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(RfError::invalid(
            format!("virtual_control[{}, {}]", i / n, i % n),
            format!("must be finite, got {}", controls[i]),
        )),
    }
}

/// Active-set allocations of many virtual controls (rows of `controls`, N x n row-major) with a
/// prepared solver, in parallel; validated as in [`allocate_many`]. The one path of the
/// active-set method for one control or many (each row is [`ActiveSetSolver::allocate`]).
pub fn allocate_all(solver: &ActiveSetSolver, controls: &[f64]) -> Result<Vec<Allocation>> {
    let problem = solver.problem();
    check_rows(problem, controls)?;
    let n = problem.virtual_dimension();
    if controls.len() == n {
        return Ok(vec![solver.allocate(controls)?]);
    }
    controls
        .par_chunks(n)
        .map(|u_c| solver.allocate(u_c))
        .collect()
}

/// Allocations of many virtual controls (rows of `controls`, N x n row-major) for one problem,
/// in parallel. Validates every row first, so an error names the row and nothing is computed.
pub fn allocate_many(
    problem: &AllocationProblem,
    method: &Method,
    controls: &[f64],
) -> Result<Vec<Allocation>> {
    check_rows(problem, controls)?;
    let n = problem.virtual_dimension();
    match method {
        Method::ActiveSet(settings) => allocate_all(
            &ActiveSetSolver::with_settings(problem, *settings),
            controls,
        ),
        Method::Pinv => {
            let pinv = checked_pseudo_inverse(problem)?;
            Ok(controls
                .chunks(n)
                .map(|u_c| pinv.allocation(problem, u_c))
                .collect())
        }
        Method::Clarabel(settings) => controls
            .par_chunks(n)
            .map(|u_c| allocate_clarabel(problem, u_c, settings))
            .collect(),
        Method::Prioritized(groups, settings) => controls
            .par_chunks(n)
            .map(|u_c| allocate_prioritized(problem, u_c, groups, settings))
            .collect(),
    }
}


#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> AllocationProblem {
        let l = 0.125;
        let c = 0.0166;
        let m = DMatrix::from_row_slice(
            4,
            4,
            &[1.0, 1.0, 1.0, 1.0, -l, l, l, -l, l, -l, l, -l, c, c, -c, -c],
        );
        AllocationProblem::new(m, &[1.0; 4], &[0.0; 4], &[8.5; 4]).unwrap()
    }

    #[test]
    fn pinv_inverts_a_square_matrix() {
        let p = quad();
        let u = [7.0, 0.1, -0.05, 0.01];
        let a = allocate_pinv(&p, &u).unwrap();
        for (x, y) in a.achieved.iter().zip(u) {
            assert!((x - y).abs() < 1e-12);
        }
    }

    #[test]
    fn pinv_of_a_rank_deficient_matrix_is_the_minimum_norm_solution() {
        // Review finding: nalgebra 0.34's SVD got this rank-2 matrix wrong (u missed by 0.034).
        let m = DMatrix::from_row_slice(
            4,
            3,
            &[
                -0.5, -0.5, 1.2, -0.6, -0.6, -0.2, 0.9, 0.9, 1.1, -1.1, -1.1, 0.9,
            ],
        );
        let t_true = [0.6, 0.6, 0.2];
        let u: Vec<f64> = (0..4)
            .map(|r| (0..3).map(|c| m[(r, c)] * t_true[c]).sum())
            .collect();
        let p = AllocationProblem::new(m, &[1.0; 4], &[-1e3; 3], &[1e3; 3]).unwrap();
        let got = allocate_pinv(&p, &u).unwrap();
        // Columns 1 and 2 are equal: the minimum-norm split of 1.2 is 0.6 / 0.6.
        for (g, e) in got.commands.iter().zip(t_true) {
            assert!((g - e).abs() < 1e-12, "{:?}", got.commands);
        }
    }

    #[test]
    fn bad_input_names_the_field() {
        let p = quad();
        let err = AllocationProblem::new(
            p.matrix().clone(),
            &[1.0, -1.0, 1.0, 1.0],
            &[0.0; 4],
            &[1.0; 4],
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("weights[1]"), "{err}");
        let err = AllocationProblem::new(p.matrix().clone(), &[1.0; 4], &[2.0; 4], &[1.0; 4])
            .unwrap_err();
        assert!(err.to_string().starts_with("lower[0]"), "{err}");
        let err = allocate_pinv(&p, &[1.0, f64::NAN, 0.0, 0.0]).unwrap_err();
        assert!(err.to_string().starts_with("virtual_control[1]"), "{err}");
    }

    #[test]
    fn rate_limit_tightens_and_keeps_order() {
        let p = quad()
            .rate_limited(&[1.0, 9.0, -1.0, 4.0], &[0.5; 4])
            .unwrap();
        assert_eq!(p.lower(), &[0.5, 8.5, 0.0, 3.5]);
        assert_eq!(p.upper(), &[1.5, 8.5, 0.0, 4.5]);
    }
}
