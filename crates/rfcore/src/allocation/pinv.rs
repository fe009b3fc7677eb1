//! The weighted pseudo-inverse (Ke et al. eqs. (34)/(35)): the unconstrained allocation as a
//! matrix and an offset, built from the active-set solver's QR of the scaled problem, so it
//! follows the same closest-to-preferred rule as the constrained answers (module docs of
//! [`crate::allocation`]).

use nalgebra::DMatrix;

use crate::allocation::active_set::ActiveSetSolver;
use crate::allocation::problem::AllocationProblem;
use crate::error::{Result, RfError};

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
/// [`RANK_TOL`](crate::allocation::active_set::RANK_TOL) of their own norm share the load by the closest-to-preferred rule.
pub fn weighted_pseudo_inverse(problem: &AllocationProblem) -> WeightedPseudoInverse {
    let (n, m) = problem.matrix().shape();
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
pub(crate) fn checked_pseudo_inverse(problem: &AllocationProblem) -> Result<WeightedPseudoInverse> {
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
