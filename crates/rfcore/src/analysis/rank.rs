//! The one rank rule of the crate ([`scale_free_rank`]), free of units, and the capped SVD it
//! and the plain [`numerical_rank`] use: every SVD here stops at [`svd_iteration_cap`] sweeps and
//! says so ([`RfError::IterationLimit`]) instead of looping forever on an input it cannot settle.

use nalgebra::{DMatrix, DVector};

use crate::analysis::acai::{inverse_power_of_two, scaled_norm, RANK_RTOL};
use crate::error::{Result, RfError};

/// The rank of `matrix` by one rule for every rank test of this crate, free of units: rows and
/// columns are equilibrated (alternately scaled by powers of two to unit norm, a few sweeps, so a
/// change of units of any row or column is undone), then singular values above `RANK_RTOL` times
/// the largest are counted. `rank(D1 M D2) = rank(M)` for positive diagonal `D1, D2`, so this
/// decides the same question as a plain SVD, without reading a small unit as a zero. `field`
/// names the matrix in errors: a non-finite entry (an SVD of one never converges), or an SVD that
/// reaches [`svd_iteration_cap`].
pub fn scale_free_rank(matrix: &DMatrix<f64>, field: &str) -> Result<usize> {
    scale_free_rank_capped(
        matrix,
        field,
        svd_iteration_cap(matrix.nrows().min(matrix.ncols())),
    )
}

/// [`scale_free_rank`] with the SVD's iteration cap given (tests drive it to the cap).
pub fn scale_free_rank_capped(matrix: &DMatrix<f64>, field: &str, cap: usize) -> Result<usize> {
    if let Some(i) = matrix.iter().position(|v| !v.is_finite()) {
        let (r, c) = (i % matrix.nrows(), i / matrix.nrows());
        return Err(RfError::invalid(
            format!("{field}[{r}, {c}]"),
            format!("must be finite, got {}", matrix[(r, c)]),
        ));
    }
    let mut scaled = matrix.clone();
    for _ in 0..EQUILIBRATION_SWEEPS {
        let mut changed = false;
        for r in 0..scaled.nrows() {
            let s = inverse_power_of_two(scaled_norm(scaled.row(r).iter()));
            if s != 1.0 {
                scaled.row_mut(r).scale_mut(s);
                changed = true;
            }
        }
        for c in 0..scaled.ncols() {
            let s = inverse_power_of_two(scaled_norm(scaled.column(c).iter()));
            if s != 1.0 {
                scaled.column_mut(c).scale_mut(s);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let sv = singular_values(scaled, field, cap)?;
    let largest = sv.iter().cloned().fold(0.0, f64::max);
    if largest == 0.0 {
        return Ok(0);
    }
    Ok(sv.iter().filter(|&&s| s > RANK_RTOL * largest).count())
}

/// Sweeps of the scale-free rank's row and column equilibration (it stops early once no scale
/// changes; a fixed count, so it cannot run on).
const EQUILIBRATION_SWEEPS: usize = 8;

/// Most implicit-shift QR sweeps an SVD of a matrix whose smaller dimension is `k` may take:
/// LAPACK's `dbdsqr` bound, `MAXITR k^2` with `MAXITR = 6` (at least 60). Converging SVDs take
/// about two sweeps per singular value; reaching the cap means the input cannot be settled in
/// double precision, reported as [`RfError::IterationLimit`] instead of an endless loop.
pub fn svd_iteration_cap(k: usize) -> usize {
    (6 * k * k).max(60)
}

/// The singular values of `matrix` (unordered; nalgebra's SVD with `DMatrix::svd`'s own
/// tolerance, so the values are bit for bit those of `svd`) in at most `cap` sweeps; an empty
/// matrix has none. A NaN value (entries spanning more orders of magnitude than double precision
/// holds; `svd` panics on it while sorting) is an error naming `field`, like the cap.
pub fn singular_values(matrix: DMatrix<f64>, field: &str, cap: usize) -> Result<DVector<f64>> {
    if matrix.is_empty() {
        return Ok(DVector::zeros(0));
    }
    let values = matrix
        .try_svd_unordered(false, false, 5.0 * f64::EPSILON, cap)
        .map(|svd| svd.singular_values)
        .ok_or_else(|| {
            RfError::iteration_limit(field, "the singular value decomposition (SVD)", cap)
        })?;
    if values.iter().any(|v| v.is_nan()) {
        return Err(RfError::invalid(
            field,
            "its singular value decomposition lost all precision (NaN): the entries span more \
             orders of magnitude than double precision holds; rescale rows or columns",
        ));
    }
    Ok(values)
}

/// Number of singular values above `RANK_RTOL` times the largest: a plain SVD rank that reads a
/// small unit as a zero. The analysis uses [`scale_free_rank`] instead.
pub fn numerical_rank(matrix: &DMatrix<f64>) -> Result<usize> {
    let cap = svd_iteration_cap(matrix.nrows().min(matrix.ncols()));
    let sv = singular_values(matrix.clone(), "matrix", cap)?;
    let largest = sv.iter().cloned().fold(0.0, f64::max);
    if largest == 0.0 {
        return Ok(0);
    }
    Ok(sv.iter().filter(|&&s| s > RANK_RTOL * largest).count())
}
