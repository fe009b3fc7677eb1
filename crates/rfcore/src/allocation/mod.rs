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
//! - [`allocate_clarabel`] (and [`allocate_prioritized`], attainable-set queries in
//!   [`crate::allocation::clarabel`]): the same problem through the Clarabel interior-point
//!   solver: the reference.
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
//!
//! # Layout (one concept per file; imports run down this list, never back up)
//! - [`allocator`]: composes the rest: the active set with its Clarabel fallback, Clarabel's
//!   answers certified and polished, the pseudo-inverse as an allocation, the batch methods.
//! - [`pinv`]: the weighted pseudo-inverse.
//! - [`active_set`]: the active set and its two phases.
//! - [`clarabel`]: the Clarabel programs (a leaf: it knows only [`problem`]).
//! - [`certificate`]: the KKT certificate and how it is computed.
//! - [`factorisation`]: the pivoted QR and the free-set least-squares step.
//! - [`scaling`]: the problem in the solver's scaled least-squares form; overflow-free norms.
//! - [`priority`]: prioritised allocation's stages, its certificate and the polish that makes
//!   Clarabel's answer exact.
//! - [`problem`]: the problem, its checks, and the status vocabulary of every answer.

pub mod active_set;
pub mod allocator;
pub mod certificate;
pub mod clarabel;
pub mod factorisation;
#[cfg(test)]
mod factorisation_tests;
pub mod pinv;
pub mod priority;
pub mod problem;
pub mod scaling;

pub use allocator::{
    allocate_all, allocate_clarabel, allocate_clarabel_unpolished, allocate_many, allocate_pinv,
    allocate_prioritized, fallback_count, Allocation, Method,
};
pub use certificate::Certificate;
pub use pinv::{weighted_pseudo_inverse, WeightedPseudoInverse};
pub(crate) use problem::check_rows;
pub use problem::{
    AllocationProblem, AllocationStatus, SolvedBy, MAX_ACTUATORS, MAX_ITERATIONS, MAX_VIRTUAL,
};
