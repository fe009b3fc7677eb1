//! Householder QR with column pivoting relative to each column's own norm (never the normal
//! equations, so a weight or a rotor 1e9 times weaker than the others still counts), its
//! reflectors applied, back substitution, and the free-set least-squares step of the active set
//! built from them (a complete orthogonal decomposition when the free columns are dependent).
//! Work arrays are fixed-size: no heap allocation.

use crate::allocation::scaling::{
    norm, sum_sq, ScaledLeastSquares, N, ROWS, SAFE_SQ_MAX, SAFE_SQ_MIN,
};

/// A column whose part outside the span of the columns already factored is at most this fraction
/// of its own norm is dependent (relative to the column, so the rotor's gain does not matter).
pub const RANK_TOL: f64 = 1e-13;

/// Squared column norms inside these bounds let [`householder_qr`] compare ratios by products of
/// two squared norms without overflow or underflow.
const QR_SQ_MIN: f64 = 3.5e-136; // 2^-450
const QR_SQ_MAX: f64 = 2.9e135; // 2^450

impl ScaledLeastSquares {
    /// The step `d = argmin |A_F d - r|` on the free columns; when `A_F` has dependent columns,
    /// the one of those minimisers that lands closest to `T_pref` (`min |T_F + d - T_pref,F|`,
    /// the tie rule on this free set), from a complete orthogonal decomposition: the pivoted QR
    /// `A_F P = Q [R11 R12; 0 0]`, then `[R11 R12] = [T11 0] Z` by Householder reflectors from
    /// the right (LAPACK's RZ), so `d = P Z^T [T11^-1 (Q^T r)_1; (Z P^T (T_pref - T)_F)_2]`.
    /// Returns the numerical rank of `A_F`.
    ///
    /// `R`: the row count when known at compile time (0: read `self.rows`), so that the loops of
    /// the common 4-axis problem are unrolled (the same operations in the same order).
    pub(crate) fn lsq_step<const W: usize, const R: usize>(
        &self,
        free: &[usize],
        r: &[f64; ROWS],
        t: &[f64; N],
        d: &mut [f64; N],
    ) -> usize {
        let mut factor = FreeSetFactor::<W>::empty();
        self.factor_free_set::<W, R>(free, &mut factor);
        self.factored_step::<W, R>(free, &factor, r, t, d)
    }

    /// The factorisation of [`Self::lsq_step`] on the free columns `free` (it depends on the
    /// matrix only, not on the residual or the commands).
    pub(crate) fn factor_free_set<const W: usize, const R: usize>(
        &self,
        free: &[usize],
        f: &mut FreeSetFactor<W>,
    ) {
        debug_assert!(R == 0 || R == self.rows);
        let k = free.len();
        let rows = if R > 0 { R } else { self.rows };
        // A_F packed column-major (leading dimension `rows`).
        let w = &mut f.w;
        for (j, &i) in free.iter().enumerate() {
            w[j * rows..j * rows + rows].copy_from_slice(&self.a[i * ROWS..i * ROWS + rows]);
        }
        let rank = householder_qr_rows::<R>(w, rows, rows, k, &mut f.perm, &mut f.tau);
        f.rank = rank;
        if rank == k {
            return;
        }
        // RZ: row i of [R11 R12] (entries i and rank..k) reduced to T11's diagonal entry. It
        // leaves Q's reflectors (below the diagonal of the first `rank` columns) as they are.
        let (ld, nz) = (rows, k - rank);
        let (zv, ztau) = (&mut f.zv, &mut f.ztau);
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
    }

    /// The step of [`Self::lsq_step`] from the factorisation of the same free columns
    /// ([`Self::factor_free_set`]); returns the rank.
    pub(crate) fn factored_step<const W: usize, const R: usize>(
        &self,
        free: &[usize],
        f: &FreeSetFactor<W>,
        r: &[f64; ROWS],
        t: &[f64; N],
        d: &mut [f64; N],
    ) -> usize {
        debug_assert!(R == 0 || R == self.rows);
        let k = free.len();
        let rows = if R > 0 { R } else { self.rows };
        let (w, perm, rank) = (&f.w, &f.perm, f.rank);
        let mut y = [0.0; ROWS];
        y[..rows].copy_from_slice(&r[..rows]);
        apply_qt_rows::<R>(w, rows, rows, rank, &f.tau, &mut y);
        if rank == k {
            back_substitute_rows::<R>(w, rows, rank, &mut y);
            for j in 0..k {
                d[free[perm[j]]] = y[j];
            }
            return rank;
        }
        let (ld, nz) = (rows, k - rank);
        // x = Z P^T (T_pref - T)_F; its first `rank` entries replaced by the basic part.
        let mut x = [0.0; N];
        for j in 0..k {
            let i = free[perm[j]];
            x[j] = self.preferred[i] - t[i];
        }
        for i in (0..rank).rev() {
            reflect_z(&f.zv, f.ztau[i], i, rank, nz, &mut x);
        }
        back_substitute_rows::<R>(w, ld, rank, &mut y);
        x[..rank].copy_from_slice(&y[..rank]);
        for i in 0..rank {
            reflect_z(&f.zv, f.ztau[i], i, rank, nz, &mut x);
        }
        for j in 0..k {
            d[free[perm[j]]] = x[j];
        }
        rank
    }
}

/// `x <- Z_i x` for the RZ reflector of row `i` of [`FreeSetFactor`] (`rank` and `nz = k - rank`
/// as there). A function inlined into both sweeps of [`ScaledLeastSquares::factored_step`]: as a
/// closure it was left a call (8-9 % of the 8-rotor solve's time, perf), the same operations in
/// the same order either way.
#[inline(always)]
fn reflect_z(zv: &[f64], ztau: f64, i: usize, rank: usize, nz: usize, x: &mut [f64; N]) {
    let v = &zv[i * nz..i * nz + nz];
    let mut dot = x[i];
    for j in 0..nz {
        dot += v[j] * x[rank + j];
    }
    dot *= ztau;
    x[i] -= dot;
    for j in 0..nz {
        x[rank + j] -= dot * v[j];
    }
}

/// The complete orthogonal decomposition of [`ScaledLeastSquares::lsq_step`] for one free set,
/// in work arrays of `W >= rows * k` entries: the pivoted QR (`w`: R and Q's reflectors, `perm`,
/// `tau`), then, when the free columns are dependent, the RZ reflectors (`zv`, `ztau`; T11 in
/// `w`). The active set keeps the one of all columns (its cold start's first step).
#[derive(Debug, Clone)]
pub(crate) struct FreeSetFactor<const W: usize> {
    w: [f64; W],
    perm: [usize; N],
    tau: [f64; N],
    rank: usize,
    zv: [f64; W],
    ztau: [f64; N],
}

impl<const W: usize> FreeSetFactor<W> {
    pub(crate) fn empty() -> Self {
        FreeSetFactor {
            w: [0.0; W],
            perm: [0; N],
            tau: [0.0; N],
            rank: 0,
            zv: [0.0; W],
            ztau: [0.0; N],
        }
    }
}

/// Householder QR with column pivoting of the `rows x k` column-major matrix `a` (leading
/// dimension `ld`), the pivot being the column with the largest remaining norm relative to its
/// own original norm; stops when that ratio is at most [`RANK_TOL`]. Returns the rank; `perm[j]`
/// is the original column in position j; reflectors below the diagonal (unit leading entry).
///
/// Works on squared norms (no division or square root in the pivot search); a column whose
/// squared norm is outside [`QR_SQ_MIN`, `QR_SQ_MAX`] sends the whole factorisation to the
/// scaled (overflow- and underflow-free) version [`householder_qr_scaled`].
pub(crate) fn householder_qr(
    a: &mut [f64],
    ld: usize,
    rows: usize,
    k: usize,
    perm: &mut [usize],
    tau: &mut [f64],
) -> usize {
    householder_qr_rows::<0>(a, ld, rows, k, perm, tau)
}

/// [`householder_qr`] with `ld = rows = R` known at compile time when `R > 0` (its loops
/// unrolled: the same operations in the same order, so the same results).
#[inline(always)]
pub(crate) fn householder_qr_rows<const R: usize>(
    a: &mut [f64],
    ld: usize,
    rows: usize,
    k: usize,
    perm: &mut [usize],
    tau: &mut [f64],
) -> usize {
    debug_assert!(R == 0 || (ld == R && rows == R));
    let (ld, rows) = if R > 0 { (R, R) } else { (ld, rows) };
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
// Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
#[allow(clippy::needless_range_loop)]
pub(crate) fn apply_qt(a: &[f64], ld: usize, rows: usize, rank: usize, tau: &[f64], y: &mut [f64]) {
    apply_qt_rows::<0>(a, ld, rows, rank, tau, y);
}

/// [`apply_qt`] with `ld = rows = R` known at compile time when `R > 0`.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
pub(crate) fn apply_qt_rows<const R: usize>(
    a: &[f64],
    ld: usize,
    rows: usize,
    rank: usize,
    tau: &[f64],
    y: &mut [f64],
) {
    let (ld, rows) = if R > 0 { (R, R) } else { (ld, rows) };
    for s in 0..rank {
        reflect(a, ld, rows, s, tau[s], y);
    }
}

/// `y <- Q y`.
pub(crate) fn apply_q(a: &[f64], ld: usize, rows: usize, rank: usize, tau: &[f64], y: &mut [f64]) {
    for s in (0..rank).rev() {
        reflect(a, ld, rows, s, tau[s], y);
    }
}

#[inline(always)]
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
pub(crate) fn back_substitute(a: &[f64], ld: usize, rank: usize, y: &mut [f64]) {
    back_substitute_rows::<0>(a, ld, rank, y);
}

/// [`back_substitute`] with `ld = R` known at compile time when `R > 0`.
#[inline(always)]
pub(crate) fn back_substitute_rows<const R: usize>(
    a: &[f64],
    ld: usize,
    rank: usize,
    y: &mut [f64],
) {
    let ld = if R > 0 { R } else { ld };
    for i in (0..rank).rev() {
        let mut v = y[i];
        for j in i + 1..rank {
            v -= a[j * ld + i] * y[j];
        }
        y[i] = v / a[i * ld + i];
    }
}
