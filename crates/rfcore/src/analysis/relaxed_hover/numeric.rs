//! Small numerical tools of the relaxed hover search: the spin-axis chart, Nelder-Mead, real
//! roots of a quadratic and a minimum-norm Gauss-Newton step.

use nalgebra::{DMatrix, DVector, Dim, Matrix, OMatrix, SMatrix};

use super::model::{tangent_basis, V3};

/// The azimuthal-equidistant chart of the cap of directions within `max_angle` of `centre`:
/// `(x, y)` in the unit disk maps to the direction at angle `|(x, y)| max_angle` from `centre`,
/// towards `x e1 + y e2`. Smooth everywhere inside, the centre included.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Chart {
    pub centre: V3,
    e1: V3,
    e2: V3,
    pub max_angle: f64,
}

impl Chart {
    pub fn new(centre: V3, max_angle: f64) -> Self {
        let (e1, e2) = tangent_basis(&centre);
        Chart {
            centre,
            e1,
            e2,
            max_angle,
        }
    }

    /// The direction at chart point `(x, y)`, `None` outside the unit disk.
    pub fn direction(&self, x: f64, y: f64) -> Option<V3> {
        let rho = (x * x + y * y).sqrt();
        if rho.is_nan() || rho > 1.0 {
            return None;
        }
        let angle = rho * self.max_angle;
        // sin(angle) / rho, continuous at the centre.
        let along = if rho > 1e-8 {
            angle.sin() / rho
        } else {
            self.max_angle * (1.0 - angle * angle / 6.0)
        };
        Some(self.centre * angle.cos() + (self.e1 * x + self.e2 * y) * along)
    }

    /// Angle between the chart point's direction and the centre.
    pub fn angle(&self, x: f64, y: f64) -> f64 {
        (x * x + y * y).sqrt() * self.max_angle
    }
}

/// Maximises `f` from `start` with the Nelder-Mead simplex (initial edges `step` along each
/// coordinate), restarting from the best point with a turned and smaller simplex until a restart
/// no longer improves it (the optimum of a min of smooth functions sits on a kink, where a
/// simplex aligned with the kink can stall). Points where `f` is not finite are worse than any
/// finite one. Returns the best point and value.
pub(crate) fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> f64,
    start: &[f64],
    step: &[f64],
    tolerance: &[f64],
) -> (Vec<f64>, f64) {
    let score = |v: f64| if v.is_nan() { f64::NEG_INFINITY } else { v };
    let d = start.len();
    let mut best = start.to_vec();
    let mut best_value = score(f(start));
    let mut stalled = 0;
    for restart in 0..24 {
        // Edges: the coordinate steps turned by a restart-dependent rotation (a Householder
        // reflection of a fixed pseudo-random direction), shrinking slowly.
        let scale = 0.7f64.powi(restart);
        let edges: Vec<Vec<f64>> = (0..d)
            .map(|i| {
                let mut e = vec![0.0; d];
                e[i] = 1.0;
                if restart > 0 && d > 1 {
                    let u: Vec<f64> = (0..d)
                        .map(|j| ((restart as usize * 7 + j * 3) as f64 * 0.618_034).sin())
                        .collect();
                    let norm2: f64 = u.iter().map(|x| x * x).sum();
                    let dot: f64 = u.iter().zip(&e).map(|(a, b)| a * b).sum();
                    for j in 0..d {
                        e[j] -= 2.0 * dot * u[j] / norm2;
                    }
                }
                (0..d).map(|j| e[j] * step[j] * scale).collect()
            })
            .collect();
        let (x, value) = simplex(f, &best, &edges, tolerance);
        let improved = value > best_value + 1e-15 * best_value.abs().max(1e-300);
        if value >= best_value {
            best = x;
            best_value = value;
        }
        stalled = if improved { 0 } else { stalled + 1 };
        if stalled >= 3 {
            break;
        }
    }
    (best, best_value)
}

fn simplex(
    f: &mut dyn FnMut(&[f64]) -> f64,
    start: &[f64],
    edges: &[Vec<f64>],
    tolerance: &[f64],
) -> (Vec<f64>, f64) {
    let d = start.len();
    let score = |v: f64| if v.is_nan() { f64::NEG_INFINITY } else { v };
    let mut points: Vec<Vec<f64>> = vec![start.to_vec()];
    for edge in edges {
        points.push((0..d).map(|j| start[j] + edge[j]).collect());
    }
    let mut values: Vec<f64> = points.iter().map(|p| score(f(p))).collect();
    for _ in 0..300 * (d + 1) {
        // Order: best (largest) first.
        let mut order: Vec<usize> = (0..=d).collect();
        order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
        points = order.iter().map(|&i| points[i].clone()).collect();
        values = order.iter().map(|&i| values[i]).collect();
        let small = (0..d).all(|i| {
            points
                .iter()
                .map(|p| (p[i] - points[0][i]).abs())
                .fold(0.0, f64::max)
                <= tolerance[i]
        });
        if small {
            break;
        }
        let centroid: Vec<f64> = (0..d)
            .map(|i| points[..d].iter().map(|p| p[i]).sum::<f64>() / d as f64)
            .collect();
        let toward = |t: f64| -> Vec<f64> {
            (0..d)
                .map(|i| centroid[i] + t * (points[d][i] - centroid[i]))
                .collect()
        };
        let reflected = toward(-1.0);
        let fr = score(f(&reflected));
        if fr > values[0] {
            let expanded = toward(-2.0);
            let fe = score(f(&expanded));
            if fe > fr {
                points[d] = expanded;
                values[d] = fe;
            } else {
                points[d] = reflected;
                values[d] = fr;
            }
        } else if fr > values[d - 1] {
            points[d] = reflected;
            values[d] = fr;
        } else {
            let contracted = if fr > values[d] {
                toward(-0.5)
            } else {
                toward(0.5)
            };
            let fc = score(f(&contracted));
            if fc > values[d].max(fr) {
                points[d] = contracted;
                values[d] = fc;
            } else {
                for j in 1..=d {
                    let shrunk: Vec<f64> = (0..d)
                        .map(|i| points[0][i] + 0.5 * (points[j][i] - points[0][i]))
                        .collect();
                    values[j] = score(f(&shrunk));
                    points[j] = shrunk;
                }
            }
        }
    }
    let best = (0..=d)
        .max_by(|&a, &b| values[a].total_cmp(&values[b]))
        .unwrap_or(0);
    (points[best].clone(), values[best])
}

/// Real roots of `a s^2 + b s + c = 0`, ascending; the linear and constant cases included
/// (`a` and `b` count as zero relative to the coefficients' size). A constant zero has every
/// `s` as a root: reported as `None`.
pub(crate) fn quadratic_roots(a: f64, b: f64, c: f64) -> Option<Vec<f64>> {
    let size = a.abs().max(b.abs()).max(c.abs());
    if size == 0.0 {
        return None;
    }
    let tiny = 1e-13 * size;
    if a.abs() <= tiny {
        if b.abs() <= tiny {
            return if c.abs() <= tiny {
                None
            } else {
                Some(Vec::new())
            };
        }
        return Some(vec![-c / b]);
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return Some(Vec::new());
    }
    // The numerically stable pair.
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let mut roots = if q == 0.0 {
        vec![0.0]
    } else {
        vec![q / a, c / q]
    };
    roots.sort_by(f64::total_cmp);
    Some(roots)
}

// nalgebra 0.34's SVD loses accuracy on rank-deficient matrices (dimforge/nalgebra#1172: here a
// pseudo-inverse off by 2e-7 and a range basis off by 4e-4 on a 4 x 4 rotor matrix of rank 3), so
// this module uses none: column-pivoted QR (Householder) for ranges and null spaces, symmetric
// eigendecompositions (Jacobi-accurate) for pseudo-inverses and null vectors.

/// Orthonormal bases of the range (p x r) and of the left null space (p x (p - r)) of `m`
/// (p x k), the rank from column-pivoted QR: diagonal entries of R above `rtol` times the largest.
pub(crate) fn range_and_null(m: &DMatrix<f64>, rtol: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (p, k) = m.shape();
    let padded = DMatrix::from_fn(p, k.max(p), |r, c| if c < k { m[(r, c)] } else { 0.0 });
    let qr = padded.col_piv_qr();
    let q = qr.q();
    let r = qr.r();
    let diagonal: Vec<f64> = (0..r.nrows().min(r.ncols())).map(|i| r[(i, i)]).collect();
    let largest = diagonal.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    let rank = diagonal
        .iter()
        .filter(|d| largest > 0.0 && d.abs() > rtol * largest)
        .count();
    (
        q.columns(0, rank).into_owned(),
        q.columns(rank, p - rank).into_owned(),
    )
}

/// The pseudo-inverse of a symmetric positive semi-definite matrix (eigenvalues below `rtol`
/// times the largest count as zero).
pub(crate) fn symmetric_pinv(h: &DMatrix<f64>, rtol: f64) -> DMatrix<f64> {
    let n = h.nrows();
    if n == 0 {
        return DMatrix::zeros(0, 0);
    }
    let symmetric = (h + h.transpose()) * 0.5;
    // The search's Newton steps invert 2x2 to 4x4 matrices thousands of times per analysis: the
    // same eigen-decomposition on a fixed-size matrix (no allocation), the same numbers.
    match n {
        2 => fixed_pinv2(&symmetric, rtol),
        3 => fixed_pinv3(&symmetric, rtol),
        4 => fixed_pinv4(&symmetric, rtol),
        _ => {
            let eig = symmetric.symmetric_eigen();
            pinv_from(&eig.eigenvalues, &eig.eigenvectors, rtol)
        }
    }
}

/// [`symmetric_pinv`] of an `N x N` matrix through `nalgebra`'s fixed-size types (one
/// function per size: the eigen-decomposition needs a concrete dimension).
macro_rules! fixed_pinv {
    ($name:ident, $n:literal) => {
        fn $name(symmetric: &DMatrix<f64>, rtol: f64) -> DMatrix<f64> {
            let fixed: SMatrix<f64, $n, $n> = symmetric.fixed_view::<$n, $n>(0, 0).into_owned();
            let eig = fixed.symmetric_eigen();
            let inverse = pinv_from(&eig.eigenvalues, &eig.eigenvectors, rtol);
            DMatrix::from_fn($n, $n, |r, c| inverse[(r, c)])
        }
    };
}
fixed_pinv!(fixed_pinv2, 2);
fixed_pinv!(fixed_pinv3, 3);
fixed_pinv!(fixed_pinv4, 4);

/// `V diag(1 / l) V^T` over the eigenvalues `l` above `rtol` times the largest.
fn pinv_from<R, C, S1, S2>(
    eigenvalues: &Matrix<f64, R, nalgebra::U1, S1>,
    eigenvectors: &Matrix<f64, R, C, S2>,
    rtol: f64,
) -> OMatrix<f64, R, R>
where
    R: Dim,
    C: Dim,
    S1: nalgebra::RawStorage<f64, R, nalgebra::U1>,
    S2: nalgebra::RawStorage<f64, R, C>,
    nalgebra::DefaultAllocator: nalgebra::allocator::Allocator<R, R>,
{
    let largest = eigenvalues.amax();
    let n = eigenvalues.len();
    let (rows, _) = eigenvalues.shape_generic();
    OMatrix::<f64, R, R>::from_fn_generic(rows, rows, |r, c| {
        let mut sum = 0.0;
        for k in 0..n {
            let l = eigenvalues[k];
            let inverse = if largest > 0.0 && l > rtol * largest { 1.0 / l } else { 0.0 };
            sum += eigenvectors[(r, k)] * inverse * eigenvectors[(c, k)];
        }
        sum
    })
}

/// The minimum-norm least-squares solution of `J x = r` (J^+ r).
pub(crate) fn min_norm_solve(j: &DMatrix<f64>, r: &DVector<f64>) -> DVector<f64> {
    if j.nrows() <= j.ncols() {
        j.transpose() * (symmetric_pinv(&(j * j.transpose()), 1e-14) * r)
    } else {
        symmetric_pinv(&(j.transpose() * j), 1e-14) * (j.transpose() * r)
    }
}

/// Minimum-norm Gauss-Newton on `residual(z) = 0` in scaled variables (`z_i / scale_i`;
/// coordinate `fixed` held), Jacobian by central differences, each step backtracked until the
/// residual shrinks; `None` unless its largest entry falls below `tolerance`.
pub(crate) fn newton(
    residual: &dyn Fn(&[f64]) -> Option<DVector<f64>>,
    mut z: Vec<f64>,
    scale: &dyn Fn(&[f64]) -> Vec<f64>,
    fixed: Option<usize>,
    iterations: usize,
    tolerance: f64,
) -> Option<Vec<f64>> {
    let columns: Vec<usize> = (0..z.len()).filter(|&c| Some(c) != fixed).collect();
    for _ in 0..iterations {
        let r = residual(&z)?;
        if r.amax() <= tolerance {
            return Some(z);
        }
        let s = scale(&z);
        let mut jac = DMatrix::zeros(r.len(), columns.len());
        for (j, &c) in columns.iter().enumerate() {
            let step = 1e-7 * s[c];
            let (mut plus, mut minus) = (z.clone(), z.clone());
            plus[c] += step;
            minus[c] -= step;
            jac.set_column(
                j,
                &((residual(&plus)? - residual(&minus)?) * (s[c] / (2.0 * step))),
            );
        }
        let delta = gauss_newton_step(&jac, &r)?;
        let mut factor = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let mut trial = z.clone();
            for (j, &c) in columns.iter().enumerate() {
                trial[c] += factor * delta[j] * s[c];
            }
            if residual(&trial).is_some_and(|rt| rt.norm() < r.norm()) {
                z = trial;
                accepted = true;
                break;
            }
            factor *= 0.5;
        }
        if !accepted {
            return None;
        }
    }
    residual(&z).filter(|r| r.amax() <= tolerance).map(|_| z)
}

/// `-J^+ r`: one minimum-norm Gauss-Newton step.
pub(crate) fn gauss_newton_step(
    jacobian: &DMatrix<f64>,
    residual: &DVector<f64>,
) -> Option<DVector<f64>> {
    let step = -min_norm_solve(jacobian, residual);
    step.iter().all(|x| x.is_finite()).then_some(step)
}

/// The unit vector `x` minimising `|J x|` (a null vector of `J` when it has one).
pub(crate) fn null_vector(j: &DMatrix<f64>) -> Option<DVector<f64>> {
    let eig = (j.transpose() * j).symmetric_eigen();
    let smallest = (0..eig.eigenvalues.len())
        .min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))?;
    Some(eig.eigenvectors.column(smallest).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chart_covers_the_cap_smoothly() {
        let chart = Chart::new(V3::new(0.0, 0.0, -1.0), 1.0);
        let n = chart.direction(0.0, 0.0).unwrap();
        assert_eq!(n, V3::new(0.0, 0.0, -1.0));
        let n = chart.direction(1.0, 0.0).unwrap();
        assert!((n.dot(&chart.centre) - 1.0f64.cos()).abs() < 1e-15);
        assert!(chart.direction(0.8, 0.8).is_none());
        let a = chart.direction(1e-9, 0.0).unwrap();
        let b = chart.direction(2e-8, 0.0).unwrap();
        assert!(((a - n.scale(0.0)).norm() - 1.0).abs() < 1e-12 && (a - b).norm() < 3e-8);
    }

    #[test]
    fn nelder_mead_finds_a_kinked_maximum() {
        let mut f = |p: &[f64]| -((p[0] - 0.3).abs() + 2.0 * (p[1] + 0.1).abs());
        let (x, v) = nelder_mead(&mut f, &[0.0, 0.0], &[0.1, 0.1], &[1e-12, 1e-12]);
        assert!(
            (x[0] - 0.3).abs() < 1e-9 && (x[1] + 0.1).abs() < 1e-9 && v > -1e-8,
            "{x:?}"
        );
    }

    #[test]
    fn range_and_null_of_a_rank_three_rotor_matrix() {
        // Four PPNNPN rotors (60 to 240 degrees): thrust and three torques of rank 3, where
        // nalgebra's SVD gives a range basis off by 4e-4.
        let (r, w) = (0.275f64, [-1.0, 1.0, 1.0, -1.0]);
        let m = DMatrix::from_fn(4, 4, |row, c| {
            let phi = (60.0 + 60.0 * c as f64).to_radians();
            match row {
                0 => 1.0,
                1 => -r * phi.sin(),
                2 => r * phi.cos(),
                _ => w[c] * 0.1,
            }
        });
        let (range, null) = range_and_null(&m, 1e-10);
        assert_eq!((range.ncols(), null.ncols()), (3, 1));
        assert!((&range * range.transpose() * &m - &m).amax() < 1e-15);
        assert!((null.transpose() * &m).amax() < 1e-15);
        let x = min_norm_solve(
            &m,
            &(&m * DVector::from_column_slice(&[1.0, 2.0, 3.0, 4.0])),
        );
        assert!((&m * &x - &m * DVector::from_column_slice(&[1.0, 2.0, 3.0, 4.0])).amax() < 1e-14);
    }

    #[test]
    fn quadratic_roots_cases() {
        assert_eq!(quadratic_roots(1.0, -3.0, 2.0), Some(vec![1.0, 2.0]));
        assert_eq!(quadratic_roots(0.0, 2.0, -4.0), Some(vec![2.0]));
        assert_eq!(quadratic_roots(1.0, 0.0, 1.0), Some(vec![]));
        assert_eq!(quadratic_roots(0.0, 0.0, 0.0), None);
    }
}
