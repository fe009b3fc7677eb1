//! The allocation problem every method solves ([`AllocationProblem`]):
//!
//! ```text
//! minimise  1/2 (u_c - M T)^T W (u_c - M T) + gamma/2 |T - T_pref|^2
//! subject   T_min <= T <= T_max
//! ```
//!
//! with `M` the n x m effectiveness matrix, `W = diag(weights)` (weights >= 0; a zero weight drops
//! that axis, as Ke et al. eq. (35) does with the yaw weight) and an optional regularisation
//! `gamma` toward preferred commands. Ke et al. eq. (33) is this problem with `gamma = 0`. Also the
//! vocabulary of every answer: how it ended ([`AllocationStatus`]) and which method produced it
//! ([`SolvedBy`]).

use nalgebra::DMatrix;

use crate::error::{require_all_finite, require_entries, require_normal, Result, RfError};

/// Most actuators a problem may have (the active-set solver works in fixed-size arrays).
pub const MAX_ACTUATORS: usize = 16;
/// Most virtual-control components a problem may have.
pub const MAX_VIRTUAL: usize = 12;

/// Most iterations a solver may be given (active set per phase, Clarabel per solve). Neither
/// polls the cancel token inside one solve, so this bounds how long Ctrl-C can wait: a Clarabel
/// iteration on a 16-actuator problem takes about 15 us (10,000: about 0.15 s), and both methods
/// converge in tens of iterations (the active set's default is `4 m + 20`, Clarabel's 200).
pub const MAX_ITERATIONS: usize = 10_000;

/// `max_iterations` in 1..=[`MAX_ITERATIONS`], named.
pub fn require_iteration_bound(max_iterations: usize) -> Result<()> {
    if (1..=MAX_ITERATIONS).contains(&max_iterations) {
        return Ok(());
    }
    Err(RfError::invalid(
        "max_iterations",
        format!(
            "must be in 1..={MAX_ITERATIONS} (a solve does not poll Ctrl-C; both solvers converge in tens of iterations), got {max_iterations}"
        ),
    ))
}

/// A solver's `tolerance`: > 0 and finite, named.
pub fn require_tolerance(tolerance: f64) -> Result<()> {
    if tolerance.is_finite() && tolerance > 0.0 {
        return Ok(());
    }
    Err(RfError::invalid(
        "tolerance",
        format!("must be > 0 and finite, got {tolerance}"),
    ))
}

/// Largest magnitude of a matrix entry, weight or regularisation: the solver scales them by
/// powers of two and is tested exact from 1e-160 to 1e300 (see `crate::error`).
pub const MAX_MAGNITUDE: f64 = 1e300;

/// Zero or a normal number of magnitude at most [`MAX_MAGNITUDE`], naming `field`.
fn require_scale_free(field: &str, value: f64) -> Result<()> {
    require_normal(field, value)?;
    if value.abs() > MAX_MAGNITUDE {
        return Err(RfError::invalid(
            field,
            format!("must be at most {MAX_MAGNITUDE:e} in magnitude (the solver scales it by powers of two), got {value:e}"),
        ));
    }
    Ok(())
}

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
        // The solver's scaling divides by the largest entry and weight and by column norms: a
        // subnormal has no reciprocal (see `crate::error`), and the power of two nearest a
        // magnitude above 2^1023.5 is infinite (a 1.5e308 matrix was "solved" by zeros).
        if let Some(i) = matrix
            .iter()
            .position(|v| !(*v == 0.0 || v.is_normal()) || v.abs() > MAX_MAGNITUDE)
        {
            require_scale_free(
                &format!("matrix[{}, {}]", i % n, i / n),
                matrix.as_slice()[i],
            )?;
        }
        require_entries("weights", weights, n, "one per virtual-control component")?;
        for (i, &w) in weights.iter().enumerate() {
            require_scale_free(&format!("weights[{i}]"), w)?;
        }
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
        require_scale_free("regularization", gamma)?;
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
        // The solver works on the problem scaled near its largest weight and largest matrix entry
        // (allocation::scaling), where the regularisation is gamma / (w_max amax(M)^2), rounded
        // to powers of two (a factor of at most 2^1.5): it must stay a normal number there.
        if gamma > 0.0 {
            let w_max = self.weights.iter().fold(0.0f64, |a, &w| a.max(w));
            let m_max = self.matrix.amax();
            let w_max = if w_max > 0.0 { w_max } else { 1.0 };
            let m_max = if m_max > 0.0 { m_max } else { 1.0 };
            let relative = gamma / w_max / m_max / m_max;
            if relative < 4.0 * f64::MIN_POSITIVE {
                return Err(RfError::invalid(
                    "regularization, weights",
                    format!(
                        "the regularisation {gamma:e} relative to the largest weight ({w_max:e}) times the largest \
                         matrix entry squared ({:e}) is {relative:e}, below the normal floating-point range: \
                         weights and regularisation span more than the solver's scaling can hold",
                        m_max * m_max
                    ),
                ));
            }
        }
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
        let mut out = vec![0.0; self.virtual_dimension()];
        self.achieved_into(commands, &mut out);
        out
    }

    /// [`Self::achieved`] into `out` (n entries), without allocating.
    pub fn achieved_into(&self, commands: &[f64], out: &mut [f64]) {
        for (r, slot) in out.iter_mut().enumerate().take(self.virtual_dimension()) {
            *slot = (0..self.actuator_count())
                .map(|c| self.matrix[(r, c)] * commands[c])
                .sum();
        }
    }

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

    /// The objective of the module docs at `commands`.
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
    /// above its tolerance) and neither could its fallback, or Clarabel reached its
    /// `max_iterations`; the commands are feasible, not proven optimal (see the allocation's
    /// certificate).
    IterationLimit,
    /// The unconstrained pseudo-inverse: bounds were not applied.
    Unconstrained,
    /// Clarabel stopped without a solution (numerical trouble, infeasible equality
    /// constraints); the commands are its last iterate.
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
