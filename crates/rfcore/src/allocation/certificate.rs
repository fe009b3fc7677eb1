//! The KKT certificate every active-set answer carries ([`Certificate`]), and how it is computed:
//! the normalised gradient of the scaled least-squares problem (`ScaledLeastSquares`) at the
//! commands, compared with the bounds. The release rule of the active set's phase 1 uses the
//! same normalised gradient as its multipliers.

use crate::allocation::scaling::{ScaledLeastSquares, N, ROWS};

/// The KKT residuals of an allocation, dimensionless, in the problem's own scaling: with
/// `A = [W^(1/2) M; gamma^(1/2) I]` and `b` the matching right-hand side (after the internal
/// power-of-two scaling), the gradient entry `g_i = a_i^T (A T - b)` is divided by
/// `|a_i| (|b| + sum_j |a_j| max(|T_j|, |T_pref,j|))` (a bound on the size of the terms it sums and
/// of the steps from the preferred command, so it is invariant to scaling the matrix, the virtual
/// control, the weights or one actuator's gain).
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

impl ScaledLeastSquares {
    /// The normalised gradient at `t` from its residual `r = b - A t` (`b_norm = |b|`), with the
    /// row count `R` known at compile time when `R > 0` (the 4-axis instance: its dot products
    /// unrolled, the same operations in the same order; 0: read `self.rows`).
    // Indexed on purpose: the iterator forms cost 1-2 % more instructions (callgrind).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn gradient_rows<const R: usize>(
        &self,
        r: &[f64; ROWS],
        t: &[f64; N],
        b_norm: f64,
        g: &mut [f64; N],
    ) {
        debug_assert!(R == 0 || R == self.rows);
        let rows = if R > 0 { R } else { self.rows };
        // The commands are reached from `T_pref` (phase 1 starts there, phase 2 moves towards
        // it), so their rounding is relative to `max(|T|, |T_pref|)`: with `u_c = 0` and a large
        // preferred command, `|T|` alone made rounding look like a failed optimum (issue 27).
        let mut scale = b_norm;
        for c in 0..self.m {
            scale += self.column_norms[c] * t[c].abs().max(self.preferred[c].abs());
        }
        for i in 0..self.m {
            let col = &self.a[i * ROWS..i * ROWS + rows];
            let gi: f64 = -col.iter().zip(&r[..rows]).map(|(a, x)| a * x).sum::<f64>();
            let s = self.column_norms[i] * scale;
            g[i] = if s > 0.0 && s.is_finite() {
                gi / s
            } else {
                0.0
            };
        }
    }

    /// The certificate at `t` with tolerance `tolerance`; `g` receives the normalised gradient.
    pub(crate) fn certificate(
        &self,
        b: &[f64; ROWS],
        t: &[f64; N],
        g: &mut [f64; N],
        tolerance: f64,
    ) -> Certificate {
        self.certificate_with(b, self.rhs_norm(b), t, g, tolerance)
    }

    /// [`Self::certificate`] with `b_norm = |b|` known.
    pub(crate) fn certificate_with(
        &self,
        b: &[f64; ROWS],
        b_norm: f64,
        t: &[f64; N],
        g: &mut [f64; N],
        tolerance: f64,
    ) -> Certificate {
        self.certificate_with_rows::<0>(b, b_norm, t, g, tolerance)
    }

    /// [`Self::certificate_with`] with the row count `R` known at compile time when `R > 0`:
    /// the active set's 4-axis instance certifies a phase-2 answer with the residual and the
    /// gradient unrolled as phase 1's are (the same operations in the same order, so the same
    /// certificate bit for bit), for consistency with phase 1: on the bench's problems phase 2
    /// almost never moves the commands, so this has no measured effect on speed (issue 32).
    #[inline(always)]
    pub(crate) fn certificate_with_rows<const R: usize>(
        &self,
        b: &[f64; ROWS],
        b_norm: f64,
        t: &[f64; N],
        g: &mut [f64; N],
        tolerance: f64,
    ) -> Certificate {
        let mut r = [0.0; ROWS];
        self.residual_rows::<R>(b, t, &mut r);
        self.gradient_rows::<R>(&r, t, b_norm, g);
        self.certificate_from_gradient(t, g, tolerance)
    }

    /// The certificate at `t` from its normalised gradient `g` ([`Self::gradient_rows`] of the
    /// residual at exactly this `t`). The active set's phase 1 ends by computing that gradient
    /// for its release rule, so the solver's certificate is this comparison only: the same
    /// numbers as [`Self::certificate`], without a second residual and gradient.
    pub(crate) fn certificate_from_gradient(
        &self,
        t: &[f64; N],
        g: &[f64; N],
        tolerance: f64,
    ) -> Certificate {
        let mut out = Certificate {
            stationarity: 0.0,
            complementarity: 0.0,
            bound_violation: 0.0,
            tolerance,
        };
        for i in 0..self.m {
            if !g[i].is_finite() || !t[i].is_finite() {
                out.stationarity = f64::INFINITY;
                continue;
            }
            let (lo, hi, x) = (self.lower[i], self.upper[i], t[i]);
            // Only a command outside its bounds has a nonzero violation (the solver's own never
            // has one): the span and the division are paid only then.
            if x < lo || x > hi {
                let span = (hi - lo).max(lo.abs()).max(hi.abs());
                let span = if span > 0.0 { span } else { 1.0 };
                out.bound_violation = out.bound_violation.max((lo - x).max(x - hi) / span);
            }
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
}
