//! The allocator: composes the room's parts into the methods users call. The active set with its
//! Clarabel fallback ([`ActiveSetSolver::solve_unchecked`] and the entry points built on it),
//! Clarabel's answers certified and polished by the active set ([`allocate_clarabel`],
//! [`allocate_prioritized`]), the pseudo-inverse as an allocation ([`allocate_pinv`]), and the
//! batch paths that choose among them ([`Method`], [`allocate_many`], [`allocate_all`]). Every
//! answer is an [`Allocation`] carrying its certificate.

use rayon::prelude::*;

use crate::allocation::active_set::{ActiveSet, ActiveSetSettings, ActiveSetSolver, SolveReport};
use crate::allocation::certificate::Certificate;
use crate::allocation::clarabel::{
    solve_allocation, solve_prioritized, ClarabelAnswer, ClarabelSettings,
};
use crate::allocation::pinv::{checked_pseudo_inverse, WeightedPseudoInverse};
use crate::allocation::priority::{polish_prioritized, prioritized_certificate};
use crate::allocation::problem::{check_rows, AllocationProblem, AllocationStatus, SolvedBy};
use crate::allocation::scaling::{BIG_WORK, N, ROWS, SMALL_WORK};
use crate::cancel::Cancel;
use crate::error::{Result, RfError};

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

impl ActiveSetSolver {
    /// Solves for `u_c` (n finite entries), checking it; see [`Self::solve_unchecked`].
    pub fn solve(
        &self,
        u_c: &[f64],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> Result<SolveReport> {
        self.problem.check_virtual_control(u_c)?;
        if commands.len() != self.scaled.m {
            return Err(RfError::shape(
                "commands",
                format!("{} entries (one per actuator)", self.scaled.m),
                commands.len().to_string(),
            ));
        }
        let mut b = [0.0; ROWS];
        if !self.scaled.rhs(u_c, &mut b) {
            return Err(RfError::invalid(
                "virtual_control",
                "too large for the scale of the matrix (overflows once scaled)",
            ));
        }
        Ok(self.solve_unchecked(u_c, active, commands))
    }

    /// One allocation with a cold start, as an [`Allocation`].
    pub fn allocate(&self, u_c: &[f64]) -> Result<Allocation> {
        let mut active = ActiveSet::cold(self.scaled.m);
        let mut commands = vec![0.0; self.scaled.m];
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

    /// The hot path: `u_c` has n finite entries and `commands` m (callers that validated once).
    /// `active` is the warm start on entry and the final active set on return. Every path (single
    /// call, reusable solver, batch) ends here: phase 1, phase 2, certificate, fallback.
    pub fn solve_unchecked(
        &self,
        u_c: &[f64],
        active: &mut ActiveSet,
        commands: &mut [f64],
    ) -> SolveReport {
        let m = self.scaled.m;
        active.len = m;
        let mut b = [0.0; ROWS];
        if !self.scaled.rhs(u_c, &mut b) {
            commands[..m].fill(f64::NAN);
            return SolveReport {
                status: AllocationStatus::Failed,
                iterations: 0,
                certificate: Certificate::failed(self.settings.tolerance),
                solved_by: SolvedBy::ActiveSet,
            };
        }
        // Four rows (four weighted axes, no regularisation: the multirotor's thrust and three
        // torques) get their own instance, whose small loops the compiler unrolls.
        let outcome = if self.scaled.rows == 4 && self.scaled.rows * m <= SMALL_WORK {
            self.solve_from::<SMALL_WORK, 4>(&b, active, commands)
        } else if self.scaled.rows * m <= SMALL_WORK {
            self.solve_from::<SMALL_WORK, 0>(&b, active, commands)
        } else {
            self.solve_from::<BIG_WORK, 0>(&b, active, commands)
        };
        match outcome {
            Ok(report) => report,
            Err(own) => self.fallback(
                u_c,
                &b,
                active,
                commands,
                own.iterations,
                (own.t, own.certificate),
            ),
        }
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
        let m = self.scaled.m;
        let scaled_u: Vec<f64> = u_c.iter().map(|u| u * self.scaled.u_scale).collect();
        let settings = ClarabelSettings {
            tolerance: 1e-12,
            max_iterations: 400,
        };
        let reference = allocate_clarabel_unpolished(&self.scaled.problem, &scaled_u, &settings);
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
        let cert_raw = self
            .scaled
            .certificate(b, &raw, &mut [0.0; N], self.settings.tolerance);
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
}

/// Clarabel's answer as an [`Allocation`], with the certificate of its commands.
fn certified(problem: &AllocationProblem, u_c: &[f64], answer: ClarabelAnswer) -> Allocation {
    let certificate = ActiveSetSolver::new(problem).certify(u_c, &answer.commands);
    with_evidence(problem, answer, certificate)
}

/// Clarabel's answer with `certificate`: its status follows the certificate (Clarabel's
/// "solved" whose commands do not certify is reduced accuracy, never `Optimal`).
fn with_evidence(
    problem: &AllocationProblem,
    answer: ClarabelAnswer,
    certificate: Certificate,
) -> Allocation {
    let status = match answer.status {
        AllocationStatus::Optimal if !certificate.holds() => AllocationStatus::AlmostOptimal,
        AllocationStatus::AlmostOptimal if certificate.holds() => AllocationStatus::Optimal,
        other => other,
    };
    Allocation {
        achieved: problem.achieved(&answer.commands),
        certificate,
        commands: answer.commands,
        status,
        iterations: answer.iterations,
        solved_by: SolvedBy::Clarabel,
    }
}

/// The box-constrained weighted least-squares allocation (Ke eq. (33)) through Clarabel, polished:
/// the active set Clarabel's answer identifies is re-solved exactly (the active-set solver's
/// phases 1 and 2), so the commands are exact, not only the objective; when that polish does not
/// certify, Clarabel's own (clamped) answer is returned with its status.
pub fn allocate_clarabel(
    problem: &AllocationProblem,
    u_c: &[f64],
    settings: &ClarabelSettings,
) -> Result<Allocation> {
    let raw = allocate_clarabel_unpolished(problem, u_c, settings)?;
    let solver = ActiveSetSolver::new(problem);
    if let Some((commands, report)) = solver.polish_commands(u_c, &raw.commands) {
        if report.certificate.holds() {
            return Ok(Allocation {
                achieved: problem.achieved(&commands),
                commands,
                status: AllocationStatus::Optimal,
                iterations: raw.iterations + report.iterations,
                certificate: report.certificate,
                solved_by: SolvedBy::Clarabel,
            });
        }
    }
    Ok(raw)
}

/// Clarabel's own answer, clamped into the box (accurate in the objective to its tolerance, not
/// necessarily in the commands): the independent reference of the tests.
pub fn allocate_clarabel_unpolished(
    problem: &AllocationProblem,
    u_c: &[f64],
    settings: &ClarabelSettings,
) -> Result<Allocation> {
    let answer = solve_allocation(problem, u_c, settings)?;
    Ok(certified(problem, u_c, answer))
}

/// Prioritised allocation: `priorities` lists groups of virtual-control rows, most important
/// first (e.g. `[[0, 1, 2], [3]]`: thrust and roll/pitch, then yaw with what is left). Stage k
/// minimises the weighted residual of group k subject to the box and to every earlier group
/// keeping what its stage achieved (to [`crate::allocation::clarabel::PRIORITY_BAND`]). Rows in
/// no group are ignored. The problem's regularisation applies to the last stage; among the optima
/// of the last stage the commands closest to the preferred ones are taken (the tie rule). Clarabel's
/// answer is polished stage by stage ([`crate::allocation::priority`]) and certified by every
/// stage's KKT conditions; `Optimal` only when that certificate holds.
pub fn allocate_prioritized(
    problem: &AllocationProblem,
    u_c: &[f64],
    priorities: &[Vec<usize>],
    settings: &ClarabelSettings,
) -> Result<Allocation> {
    let answer = solve_prioritized(problem, u_c, priorities, settings)?;
    let tolerance = crate::allocation::active_set::DEFAULT_TOLERANCE;
    if answer.status != AllocationStatus::Failed {
        if let Some(polished) = polish_prioritized(problem, u_c, priorities, &answer.commands) {
            let certificate = prioritized_certificate(
                problem,
                u_c,
                priorities,
                &polished.commands,
                Some(&polished.multipliers),
                tolerance,
            );
            if certificate.holds() {
                return Ok(Allocation {
                    achieved: problem.achieved(&polished.commands),
                    commands: polished.commands,
                    status: AllocationStatus::Optimal,
                    iterations: answer.iterations,
                    certificate,
                    solved_by: SolvedBy::Clarabel,
                });
            }
        }
    }
    // Not certified: Clarabel's own answer, whose status follows its (prioritised) certificate.
    let certificate =
        prioritized_certificate(problem, u_c, priorities, &answer.commands, None, tolerance);
    Ok(with_evidence(problem, answer, certificate))
}

/// The unconstrained [`Allocation`] of `u_c` for `problem` (the one `pinv` was built from).
fn pinv_allocation(
    pinv: &WeightedPseudoInverse,
    problem: &AllocationProblem,
    u_c: &[f64],
) -> Allocation {
    let mut commands = vec![0.0; problem.actuator_count()];
    pinv.apply(u_c, &mut commands);
    Allocation {
        achieved: problem.achieved(&commands),
        certificate: ActiveSetSolver::new(problem).certify(u_c, &commands),
        commands,
        status: AllocationStatus::Unconstrained,
        iterations: 0,
        solved_by: SolvedBy::PseudoInverse,
    }
}

/// The unconstrained allocation of one virtual control (status [`AllocationStatus::Unconstrained`]).
pub fn allocate_pinv(problem: &AllocationProblem, u_c: &[f64]) -> Result<Allocation> {
    problem.check_virtual_control(u_c)?;
    Ok(pinv_allocation(
        &checked_pseudo_inverse(problem)?,
        problem,
        u_c,
    ))
}

/// Which solver an allocation uses.
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
    /// [`ActiveSetSolver`] with its settings: exact, the default.
    ActiveSet(ActiveSetSettings),
    /// [`allocate_clarabel`]: the interior-point reference.
    Clarabel(ClarabelSettings),
    /// [`allocate_prioritized`]: groups of rows, most important first.
    Prioritized(Vec<Vec<usize>>, ClarabelSettings),
    /// [`crate::allocation::weighted_pseudo_inverse`]: unconstrained.
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
        active.check()?;
        settings.check()?;
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

/// Active-set allocations of many virtual controls (rows of `controls`, N x n row-major) with a
/// prepared solver, in parallel; validated as in [`allocate_many`]. The one path of the
/// active-set method for one control or many (each row is [`ActiveSetSolver::allocate`]).
/// `cancel` is checked before every row.
pub fn allocate_all(
    solver: &ActiveSetSolver,
    controls: &[f64],
    cancel: &Cancel,
) -> Result<Vec<Allocation>> {
    let problem = solver.problem();
    check_rows(problem, controls)?;
    let n = problem.virtual_dimension();
    if controls.len() == n {
        return Ok(vec![solver.allocate(controls)?]);
    }
    controls
        .par_chunks(n)
        .map(|u_c| {
            cancel.check()?;
            solver.allocate(u_c)
        })
        .collect()
}

/// Allocations of many virtual controls (rows of `controls`, N x n row-major) for one problem,
/// in parallel. Validates every row first, so an error names the row and nothing is computed.
/// `cancel` is checked before every row.
pub fn allocate_many(
    problem: &AllocationProblem,
    method: &Method,
    controls: &[f64],
    cancel: &Cancel,
) -> Result<Vec<Allocation>> {
    check_rows(problem, controls)?;
    let n = problem.virtual_dimension();
    match method {
        Method::ActiveSet(settings) => allocate_all(
            &ActiveSetSolver::with_settings(problem, *settings)?,
            controls,
            cancel,
        ),
        Method::Pinv => {
            let pinv = checked_pseudo_inverse(problem)?;
            controls
                .chunks(n)
                .map(|u_c| {
                    cancel.check()?;
                    Ok(pinv_allocation(&pinv, problem, u_c))
                })
                .collect()
        }
        Method::Clarabel(settings) => controls
            .par_chunks(n)
            .map(|u_c| {
                cancel.check()?;
                allocate_clarabel(problem, u_c, settings)
            })
            .collect(),
        Method::Prioritized(groups, settings) => controls
            .par_chunks(n)
            .map(|u_c| {
                cancel.check()?;
                allocate_prioritized(problem, u_c, groups, settings)
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

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
    fn settings_are_checked_not_clamped() {
        // An iteration bound of 0 was clamped to 1 by `with_settings`, and Clarabel's public
        // fields reached the solver unchecked (review of issue 27).
        let p = quad();
        let zero = ActiveSetSettings {
            max_iterations: Some(0),
            ..ActiveSetSettings::default()
        };
        let err = ActiveSetSolver::with_settings(&p, zero).unwrap_err();
        assert!(err.to_string().starts_with("max_iterations: must be in 1..="), "{err}");
        let nan = ActiveSetSettings {
            tolerance: f64::NAN,
            ..ActiveSetSettings::default()
        };
        let err = ActiveSetSolver::with_settings(&p, nan).unwrap_err();
        assert!(err.to_string().starts_with("tolerance: must be > 0 and finite"), "{err}");
        let u = [7.0, 0.0, 0.0, 0.0];
        for (settings, field) in [
            (ClarabelSettings { tolerance: -1.0, max_iterations: 200 }, "tolerance: must be > 0"),
            (ClarabelSettings { tolerance: 1e-10, max_iterations: 0 }, "max_iterations: must be in 1..="),
        ] {
            assert!(settings.check().unwrap_err().to_string().starts_with(field));
            let err = allocate_clarabel(&p, &u, &settings).unwrap_err();
            assert!(err.to_string().starts_with(field), "{err}");
            let err = Method::parse("clarabel", None, ActiveSetSettings::default(), settings).unwrap_err();
            assert!(err.to_string().starts_with(field), "{err}");
            let method = Method::Clarabel(settings);
            let err = allocate_many(&p, &method, &u, &Cancel::never()).unwrap_err();
            assert!(err.to_string().starts_with(field), "{err}");
        }
        let err = Method::parse("active-set", None, zero, ClarabelSettings::default()).unwrap_err();
        assert!(err.to_string().starts_with("max_iterations"), "{err}");
        let err = allocate_many(&p, &Method::ActiveSet(zero), &u, &Cancel::never()).unwrap_err();
        assert!(err.to_string().starts_with("max_iterations"), "{err}");
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
