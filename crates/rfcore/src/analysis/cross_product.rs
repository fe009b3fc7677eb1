//! The generalised cross product of n - 1 columns in n dimensions (the facet normals of the
//! ACAI, [`crate::analysis::acai`]) and the small determinants it is made of.

use nalgebra::DMatrix;

/// Writes into `xi` the generalised cross product of the columns `group` (n - 1 of them) of `b`:
/// `xi_r = (-1)^r det(B_group without row r)`, orthogonal to every column of the group, with norm
/// the (n-1)-volume they span.
pub(crate) fn generalized_cross_product(
    b: &DMatrix<f64>,
    group: &[usize],
    minor: &mut [f64],
    xi: &mut [f64],
) {
    let n = xi.len();
    let d = n - 1;
    for (skip, component) in xi.iter_mut().enumerate() {
        for (row_out, r) in (0..n).filter(|&r| r != skip).enumerate() {
            for (c, &k) in group.iter().enumerate() {
                minor[row_out * d + c] = b[(r, k)];
            }
        }
        let sign = if skip % 2 == 0 { 1.0 } else { -1.0 };
        *component = sign * determinant(&mut minor[..d * d], d);
    }
}

/// Determinant of a row-major `d x d` matrix: closed forms up to 3 x 3, partial-pivoting
/// elimination beyond (the buffer is overwritten).
fn determinant(a: &mut [f64], d: usize) -> f64 {
    match d {
        0 => 1.0,
        1 => a[0],
        2 => a[0] * a[3] - a[1] * a[2],
        3 => {
            a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
                + a[2] * (a[3] * a[7] - a[4] * a[6])
        }
        _ => {
            let mut det = 1.0;
            for col in 0..d {
                let pivot = (col..d)
                    .max_by(|&x, &y| a[x * d + col].abs().total_cmp(&a[y * d + col].abs()))
                    .unwrap_or(col);
                if a[pivot * d + col] == 0.0 {
                    return 0.0;
                }
                if pivot != col {
                    for c in 0..d {
                        a.swap(pivot * d + c, col * d + c);
                    }
                    det = -det;
                }
                let p = a[col * d + col];
                det *= p;
                for r in col + 1..d {
                    let factor = a[r * d + col] / p;
                    for c in col..d {
                        a[r * d + c] -= factor * a[col * d + c];
                    }
                }
            }
            det
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_product_is_orthogonal_in_five_dimensions() {
        let b = DMatrix::from_fn(5, 4, |r, c| {
            ((r * 7 + c * 3) % 5) as f64 + 0.1 * (r as f64) - 0.3 * c as f64
        });
        let mut minor = vec![0.0; 16];
        let mut xi = vec![0.0; 5];
        generalized_cross_product(&b, &[0, 1, 2, 3], &mut minor, &mut xi);
        assert!(xi.iter().any(|v| v.abs() > 1e-6));
        for c in 0..4 {
            let dot: f64 = (0..5).map(|r| xi[r] * b[(r, c)]).sum();
            assert!(dot.abs() < 1e-12, "column {c}: {dot}");
        }
    }

    #[test]
    fn determinant_by_elimination_matches_closed_form() {
        let m = [
            2.0, -1.0, 0.5, 3.0, 1.0, 4.0, -2.0, 0.0, 1.5, 2.5, -1.0, 0.0, 1.0, 0.0, 2.0, 1.0,
        ];
        let expected = DMatrix::from_row_slice(4, 4, &m).determinant();
        let mut a = m;
        assert!((determinant(&mut a, 4) - expected).abs() < 1e-12);
    }
}
