//! The linear model about a relaxed hover, time-invariant in body axes (Mueller and D'Andrea's
//! reduced attitude): state `x = [a, b, dp, dq, dr, z, w]` with the up axis seen from the body
//! `n_B = n + a e1 + b e2` (`e1, e2` the solution's tangent basis), the body-rate deviation, and
//! the altitude `z` (up) and its rate `w`; input: the carrying rotors' thrust deviations.
//!
//! From `n_B' = n_B x omega`, `J omega' = tau(f) - omega x (J omega + h(f)) - k_r omega` and
//! `m z'' = n_B . F(f) - m g`:
//!
//! - `a' = s b - e2 . dw`, `b' = -s a + e1 . dw`;
//! - `dw' = J^-1 ([J omega + h]x - [omega]x J - k_r I) dw + J^-1 (T - [omega]x H) df` with `T`
//!   the torque columns and `H = dh/df` (column `c_i / (2 sqrt(f_i))`);
//! - `z' = w`, `w' = (a e1.F + b e2.F + n.A df) / m`.
//!
//! The horizontal position is not in it: the centre of mass circles at the spin rate, and an
//! outer loop steers it by tilting the up axis the attitude loop holds.

use nalgebra::{Complex, DMatrix, Matrix3};

use super::model::{tangent_basis, Model, V3};

/// States of the linear model.
pub const LINEAR_STATES: usize = 7;

/// `(A, B, e1, e2)` about `omega = s up` with thrusts `thrust_n` (all rotors); `B` has one
/// column per rotor in `inputs`.
pub(crate) fn linear_model(
    model: &Model,
    up: &V3,
    spin_rate: f64,
    thrust_n: &[f64],
    inputs: &[usize],
) -> (DMatrix<f64>, DMatrix<f64>, V3, V3) {
    let (e1, e2) = tangent_basis(up);
    let omega = up * spin_rate;
    let j = model.inertia;
    let j_inv = j.try_inverse().expect("principal inertias are > 0");
    let h = model.rotor_momentum(thrust_n);
    let force = model.force(thrust_n);
    let cross = |v: &V3| Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0);
    let rate = j_inv
        * (cross(&(j * omega + h))
            - cross(&omega) * j
            - Matrix3::identity() * model.rotational_drag_n_m_s);
    let k = inputs.len();
    let mut a = DMatrix::zeros(LINEAR_STATES, LINEAR_STATES);
    a[(0, 1)] = spin_rate;
    a[(1, 0)] = -spin_rate;
    for c in 0..3 {
        a[(0, 2 + c)] = -e2[c];
        a[(1, 2 + c)] = e1[c];
        for r in 0..3 {
            a[(2 + r, 2 + c)] = rate[(r, c)];
        }
    }
    a[(5, 6)] = 1.0;
    a[(6, 0)] = e1.dot(&force) / model.mass_kg;
    a[(6, 1)] = e2.dot(&force) / model.mass_kg;
    let mut b = DMatrix::zeros(LINEAR_STATES, k);
    for (col, &i) in inputs.iter().enumerate() {
        let f = thrust_n[i];
        let dh = if f > 0.0 {
            model.momentum[i] / (2.0 * f.sqrt())
        } else {
            V3::zeros()
        };
        let torque = j_inv * (model.torque[i] - omega.cross(&dh));
        for r in 0..3 {
            b[(2 + r, col)] = torque[r];
        }
        b[(6, col)] = up.dot(&model.axis[i]) / model.mass_kg;
    }
    (a, b, e1, e2)
}

/// Whether every mode of `(A, B)` that does not decay (real part >= `-tolerance` times the
/// largest eigenvalue magnitude) can be moved by the inputs (Popov-Belevitch-Hautus test).
pub(crate) fn stabilizable(a: &DMatrix<f64>, b: &DMatrix<f64>) -> bool {
    let n = a.nrows();
    let eigenvalues = a.complex_eigenvalues();
    let size = eigenvalues
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    let a_c = a.map(|x| Complex::new(x, 0.0));
    let b_c = b.map(|x| Complex::new(x, 0.0));
    eigenvalues.iter().all(|&lambda| {
        if lambda.re < -1e-9 * size {
            return true;
        }
        // Rank of [A - l I, B] (n rows) from column-pivoted QR of its adjoint (no SVD: module
        // `numeric` says why).
        let mut pbh = DMatrix::zeros(n + b.ncols(), n);
        pbh.view_mut((0, 0), (n, n))
            .copy_from(&(&a_c - DMatrix::identity(n, n) * lambda).adjoint());
        pbh.view_mut((n, 0), (b.ncols(), n))
            .copy_from(&b_c.adjoint());
        let diagonal = pbh.col_piv_qr().r().diagonal();
        let largest = diagonal
            .iter()
            .map(|d| d.norm())
            .fold(0.0, f64::max)
            .max(1e-300);
        diagonal
            .iter()
            .filter(|d| d.norm() > 1e-9 * largest)
            .count()
            == n
    })
}
