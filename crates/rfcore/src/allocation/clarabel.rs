//! Allocation problems through Clarabel (an interior-point conic solver): the reference for the
//! active-set solver, prioritised allocation, and attainable-set queries.
//!
//! Clarabel solves `min 1/2 x^T P x + q^T x` s.t. `A x + s = b`, `s` in a cone. The box
//! `lower <= T <= upper` is the non-negative cone on `[I; -I] T <= [upper; -lower]`; equality
//! constraints (priorities, directions) are the zero cone. Its answers are accurate to the
//! tolerances of [`ClarabelSettings`], not exact: use it to check and to explore, and the active-set
//! solver in loops.
//!
//! A leaf of the allocation room: it knows the problem, not the active set. Its answers are raw
//! (`ClarabelAnswer`); the allocator ([`crate::allocation::allocator`]) certifies them, polishes
//! them with the active set ([`crate::allocation::allocate_clarabel`]) and uses them as the active
//! set's fallback.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use nalgebra::DMatrix;

use crate::airframe::Airframe;
use crate::allocation::problem::{
    require_iteration_bound, require_tolerance, AllocationProblem, AllocationStatus,
};
use crate::analysis::controllability::ControlAxes;
use crate::error::{require_all_finite, require_entries, Result, RfError};

/// How far a later priority stage may move what an earlier group achieved, relative to the
/// largest value that row can take.
pub const PRIORITY_BAND: f64 = 1e-9;

/// Clarabel's tolerances and iteration bound, with builder-style setters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClarabelSettings {
    /// Absolute and relative duality-gap and feasibility tolerance.
    pub tolerance: f64,
    pub max_iterations: u32,
}

impl Default for ClarabelSettings {
    /// Tight enough that objectives agree with the exact solver to about 1e-10 relative.
    fn default() -> Self {
        ClarabelSettings {
            tolerance: 1e-10,
            max_iterations: 200,
        }
    }
}

impl ClarabelSettings {
    /// The rules: `tolerance > 0` and finite, `max_iterations` in
    /// 1..=[`crate::allocation::MAX_ITERATIONS`]. The fields are public, so every solve checks
    /// them again before Clarabel sees them (two comparisons).
    pub fn check(&self) -> Result<()> {
        require_tolerance(self.tolerance)?;
        require_iteration_bound(self.max_iterations as usize)
    }
    pub fn tolerance(mut self, tolerance: f64) -> Result<Self> {
        ClarabelSettings { tolerance, ..self }.check()?;
        self.tolerance = tolerance;
        Ok(self)
    }
    pub fn max_iterations(mut self, max_iterations: usize) -> Result<Self> {
        require_iteration_bound(max_iterations)?;
        self.max_iterations = max_iterations as u32; // <= MAX_ITERATIONS, so it fits
        Ok(self)
    }

    fn build(&self) -> Result<DefaultSettings<f64>> {
        self.check()?;
        DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(self.max_iterations)
            .tol_gap_abs(self.tolerance)
            .tol_gap_rel(self.tolerance)
            .tol_feas(self.tolerance)
            .tol_ktratio(self.tolerance.sqrt().min(1e-6))
            .build()
            .map_err(|e| RfError::invalid("settings", format!("clarabel rejected them: {e}")))
    }
}

/// A conic program in dense form, assembled row by row.
struct Program {
    n_vars: usize,
    hessian: DMatrix<f64>,
    linear: Vec<f64>,
    /// Rows of `A` and `b`: first the equalities, then the inequalities `a x <= b`.
    equalities: Vec<(Vec<f64>, f64)>,
    inequalities: Vec<(Vec<f64>, f64)>,
}

struct ProgramSolution {
    x: Vec<f64>,
    status: SolverStatus,
    iterations: usize,
}

impl Program {
    fn new(n_vars: usize) -> Self {
        Program {
            n_vars,
            hessian: DMatrix::zeros(n_vars, n_vars),
            linear: vec![0.0; n_vars],
            equalities: Vec::new(),
            inequalities: Vec::new(),
        }
    }

    /// `lower <= x[offset..offset + m] <= upper`.
    fn add_box(&mut self, offset: usize, lower: &[f64], upper: &[f64]) {
        for (i, (&lo, &hi)) in lower.iter().zip(upper).enumerate() {
            let mut row = vec![0.0; self.n_vars];
            row[offset + i] = 1.0;
            self.inequalities.push((row.clone(), hi));
            row[offset + i] = -1.0;
            self.inequalities.push((row, -lo));
        }
    }

    fn solve(&self, settings: &ClarabelSettings) -> Result<ProgramSolution> {
        let upper_p: Vec<Vec<f64>> = (0..self.n_vars)
            .map(|i| {
                (0..self.n_vars)
                    .map(|j| if j >= i { self.hessian[(i, j)] } else { 0.0 })
                    .collect()
            })
            .collect();
        let p = CscMatrix::from(upper_p.iter().map(|r| r.iter()));
        let rows: Vec<&Vec<f64>> = self
            .equalities
            .iter()
            .chain(&self.inequalities)
            .map(|(r, _)| r)
            .collect();
        let b: Vec<f64> = self
            .equalities
            .iter()
            .chain(&self.inequalities)
            .map(|(_, b)| *b)
            .collect();
        let a = CscMatrix::from(rows.iter().map(|r| r.iter()));
        let mut cones = Vec::new();
        if !self.equalities.is_empty() {
            cones.push(SupportedConeT::ZeroConeT(self.equalities.len()));
        }
        if !self.inequalities.is_empty() {
            cones.push(SupportedConeT::NonnegativeConeT(self.inequalities.len()));
        }
        let mut solver = DefaultSolver::new(&p, &self.linear, &a, &b, &cones, settings.build()?)
            .map_err(|e| RfError::invalid("problem", format!("clarabel rejected it: {e}")))?;
        solver.solve();
        Ok(ProgramSolution {
            x: solver.solution.x.clone(),
            status: solver.solution.status,
            iterations: solver.solution.iterations as usize,
        })
    }
}

/// Interior-point iterates sit a hair inside or outside the box: the commands clamped into it.
fn clamped(x: &[f64], lower: &[f64], upper: &[f64]) -> Vec<f64> {
    x.iter()
        .zip(lower.iter().zip(upper))
        .map(|(t, (lo, hi))| t.clamp(*lo, *hi))
        .collect()
}

/// Clarabel's status in the allocation vocabulary: reaching `max_iterations` is reported as
/// such ([`AllocationStatus::IterationLimit`]), the commands being its last iterate.
fn status_of(status: SolverStatus) -> AllocationStatus {
    match status {
        SolverStatus::Solved => AllocationStatus::Optimal,
        SolverStatus::AlmostSolved => AllocationStatus::AlmostOptimal,
        SolverStatus::MaxIterations => AllocationStatus::IterationLimit,
        _ => AllocationStatus::Failed,
    }
}

/// The objective of `problem` for one `u_c`, on top of whatever constraints are added.
fn qp_program(problem: &AllocationProblem, u_c: &[f64], rows: &[usize]) -> Program {
    let m = problem.actuator_count();
    let mut program = Program::new(m);
    let (matrix, w) = (problem.matrix(), problem.weights());
    for i in 0..m {
        for j in 0..m {
            program.hessian[(i, j)] = rows
                .iter()
                .map(|&r| matrix[(r, i)] * w[r] * matrix[(r, j)])
                .sum::<f64>();
        }
        program.hessian[(i, i)] += problem.regularization();
        program.linear[i] = -rows
            .iter()
            .map(|&r| matrix[(r, i)] * w[r] * u_c[r])
            .sum::<f64>()
            - problem.regularization() * problem.preferred()[i];
    }
    program.add_box(0, problem.lower(), problem.upper());
    program
}

/// Clarabel's answer to an allocation problem, before any certificate or polish.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ClarabelAnswer {
    /// Clarabel's commands clamped into the box.
    pub(crate) commands: Vec<f64>,
    pub(crate) status: AllocationStatus,
    pub(crate) iterations: usize,
}

fn answer(
    problem: &AllocationProblem,
    solution: ProgramSolution,
    iterations: usize,
) -> ClarabelAnswer {
    ClarabelAnswer {
        commands: clamped(&solution.x, problem.lower(), problem.upper()),
        status: status_of(solution.status),
        iterations,
    }
}

/// Clarabel's own answer to the box-constrained weighted least-squares allocation (Ke eq. (33)),
/// clamped into the box, after checking `u_c`.
pub(crate) fn solve_allocation(
    problem: &AllocationProblem,
    u_c: &[f64],
    settings: &ClarabelSettings,
) -> Result<ClarabelAnswer> {
    problem.check_virtual_control(u_c)?;
    let rows: Vec<usize> = (0..problem.virtual_dimension()).collect();
    let solution = qp_program(problem, u_c, &rows).solve(settings)?;
    let iterations = solution.iterations;
    Ok(answer(problem, solution, iterations))
}

/// Prioritised allocation: `priorities` lists groups of virtual-control rows, most important
/// first (e.g. `[[0, 1, 2], [3]]`: thrust and roll/pitch, then yaw with what is left). Stage k
/// minimises the weighted residual of group k subject to the box and to every earlier group
/// keeping what its stage achieved (to [`PRIORITY_BAND`]). Rows in no group are ignored. The problem's
/// regularisation applies to the last stage. Clarabel's answer of the last stage (or of the
/// first that fails); [`crate::allocation::allocate_prioritized`] certifies it.
pub(crate) fn solve_prioritized(
    problem: &AllocationProblem,
    u_c: &[f64],
    priorities: &[Vec<usize>],
    settings: &ClarabelSettings,
) -> Result<ClarabelAnswer> {
    problem.check_virtual_control(u_c)?;
    let n = problem.virtual_dimension();
    if priorities.is_empty() {
        return Err(RfError::invalid(
            "priorities",
            "must list at least one group of rows",
        ));
    }
    let mut seen = vec![false; n];
    for (k, group) in priorities.iter().enumerate() {
        if group.is_empty() {
            return Err(RfError::invalid(
                format!("priorities[{k}]"),
                "must not be empty",
            ));
        }
        for &r in group {
            if r >= n {
                return Err(RfError::invalid(
                    format!("priorities[{k}]"),
                    format!("row {r} does not exist (the virtual control has {n} rows)"),
                ));
            }
            if std::mem::replace(&mut seen[r], true) {
                return Err(RfError::invalid(
                    format!("priorities[{k}]"),
                    format!("row {r} appears in more than one group"),
                ));
            }
        }
    }
    let stage_problem = |last: bool| -> Result<AllocationProblem> {
        if last || problem.regularization() == 0.0 {
            Ok(problem.clone())
        } else {
            problem
                .clone()
                .with_regularization(0.0, problem.preferred())
        }
    };
    let m = problem.actuator_count();
    let mut fixed: Vec<(Vec<f64>, f64)> = Vec::new();
    let mut iterations = 0;
    let mut last = None;
    for (k, group) in priorities.iter().enumerate() {
        let is_last = k + 1 == priorities.len();
        let stage = stage_problem(is_last)?;
        let mut program = qp_program(&stage, u_c, group);
        program.inequalities.extend(fixed.iter().cloned());
        let solution = program.solve(settings)?;
        iterations += solution.iterations;
        let stage_answer = answer(problem, solution, iterations);
        if matches!(
            stage_answer.status,
            AllocationStatus::Failed | AllocationStatus::IterationLimit
        ) {
            return Ok(stage_answer);
        }
        let achieved = problem.achieved(&stage_answer.commands);
        // Later stages keep what this group achieved with the (box-feasible) commands, to a
        // band of PRIORITY_BAND relative: exact equalities are degenerate next to active bounds
        // and made Clarabel fail (review finding).
        for &r in group {
            let row: Vec<f64> = (0..m).map(|c| problem.matrix()[(r, c)]).collect();
            let scale: f64 = row
                .iter()
                .zip(problem.lower().iter().zip(problem.upper()))
                .map(|(a, (lo, hi))| a.abs() * lo.abs().max(hi.abs()))
                .sum();
            let band = PRIORITY_BAND * scale.max(f64::MIN_POSITIVE);
            let negated: Vec<f64> = row.iter().map(|v| -v).collect();
            fixed.push((row, achieved[r] + band));
            fixed.push((negated, -(achieved[r] - band)));
        }
        last = Some(stage_answer);
    }
    last.ok_or_else(|| RfError::invalid("priorities", "must list at least one group of rows"))
}

/// The largest step along a direction the rotors can produce (an attainable-set query).
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionalLimit {
    /// The largest `s` with `base + s d` attainable (N or N m per unit of `d`).
    pub scale: f64,
    /// Commands that attain it.
    pub commands: Vec<f64>,
    pub status: AllocationStatus,
}

/// Largest `s` such that `M T = base + s direction` for some `lower <= T <= upper`; `None` when no
/// point of that line is attainable. `s` is negative when `base` itself is unattainable but
/// points behind it are. `direction` must not be zero.
pub fn max_along_direction(
    matrix: &DMatrix<f64>,
    lower: &[f64],
    upper: &[f64],
    direction: &[f64],
    base: &[f64],
    settings: &ClarabelSettings,
) -> Result<Option<DirectionalLimit>> {
    let (n, m) = matrix.shape();
    // Validates the matrix and bounds exactly as an allocation would.
    let problem = AllocationProblem::new(matrix.clone(), &vec![1.0; n], lower, upper)?;
    for (field, v) in [("direction", direction), ("base", base)] {
        require_entries(field, v, n, "one per virtual-control component")?;
        require_all_finite(field, v)?;
    }
    if direction.iter().all(|&d| d == 0.0) {
        return Err(RfError::invalid("direction", "must not be zero"));
    }
    // Variables [T; s]: maximise s subject to M T - s d = base and the box on T.
    let mut program = Program::new(m + 1);
    program.linear[m] = -1.0;
    for r in 0..n {
        let mut row: Vec<f64> = (0..m).map(|c| problem.matrix()[(r, c)]).collect();
        row.push(-direction[r]);
        program.equalities.push((row, base[r]));
    }
    program.add_box(0, problem.lower(), problem.upper());
    let solution = program.solve(settings)?;
    match solution.status {
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => Ok(None),
        status => Ok(Some(DirectionalLimit {
            scale: solution.x[m],
            commands: clamped(&solution.x[..m], lower, upper),
            status: status_of(status),
        })),
    }
}

/// How much thrust an airframe (with its current efficiencies) can produce while holding the
/// torques it controls at zero, against its weight.
#[derive(Debug, Clone, PartialEq)]
pub struct HoverMargin {
    /// Largest total thrust with zero roll and pitch torque (and yaw, unless given up), N.
    pub max_thrust_n: f64,
    /// `m g`, N.
    pub weight_n: f64,
    /// `max_thrust_n - weight_n`: negative means the vehicle cannot hover in balance.
    pub margin_n: f64,
    /// Rotor thrusts that attain `max_thrust_n`.
    pub commands: Vec<f64>,
    pub status: AllocationStatus,
}

/// [`HoverMargin`] of an airframe; `axes` says whether yaw torque must be zero too.
pub fn hover_thrust_margin(
    airframe: &Airframe,
    axes: ControlAxes,
    settings: &ClarabelSettings,
) -> Result<HoverMargin> {
    let matrix = axes.matrix(airframe);
    let direction = axes.thrust_direction();
    let weight_n = airframe.hover_wrench()[0];
    let limit = max_along_direction(
        &matrix,
        &airframe.min_thrust_n(),
        &airframe.max_thrust_n(),
        &direction,
        &vec![0.0; axes.dimension()],
        settings,
    )?;
    Ok(match limit {
        Some(limit) => HoverMargin {
            max_thrust_n: limit.scale,
            weight_n,
            margin_n: limit.scale - weight_n,
            commands: limit.commands,
            status: limit.status,
        },
        // Zero torque is unattainable at any thrust (e.g. every minimum thrust positive and
        // lopsided): no balanced thrust at all.
        None => HoverMargin {
            max_thrust_n: f64::NEG_INFINITY,
            weight_n,
            margin_n: f64::NEG_INFINITY,
            commands: Vec::new(),
            status: AllocationStatus::Failed,
        },
    })
}
