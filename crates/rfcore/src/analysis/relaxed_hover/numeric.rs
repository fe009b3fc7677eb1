//! Small numerical tools of the relaxed hover search: the spin-axis chart, Nelder-Mead, real
//! roots of a quadratic and a minimum-norm Gauss-Newton step.

use nalgebra::{DMatrix, DVector};

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
        Chart { centre, e1, e2, max_angle }
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

/// Maximises `f` from `start` with the Nelder-Mead simplex (initial edge `step`), restarting
/// from the best point until a restart no longer improves it. Points where `f` is not finite are
/// worse than any finite one. Returns the best point and value.
pub(crate) fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> f64,
    start: &[f64],
    step: &[f64],
    tolerance: &[f64],
) -> (Vec<f64>, f64) {
    let score = |v: f64| if v.is_nan() { f64::NEG_INFINITY } else { v };
    let mut best = start.to_vec();
    let mut best_value = score(f(start));
    let mut scale = 1.0;
    for _restart in 0..3 {
        let (x, value) = simplex(f, &best, step, tolerance, scale);
        let improved = value > best_value + 1e-15 * best_value.abs();
        if value >= best_value {
            best = x;
            best_value = value;
        }
        if !improved {
            break;
        }
        scale *= 0.5;
    }
    (best, best_value)
}

fn simplex(
    f: &mut dyn FnMut(&[f64]) -> f64,
    start: &[f64],
    step: &[f64],
    tolerance: &[f64],
    scale: f64,
) -> (Vec<f64>, f64) {
    let d = start.len();
    let score = |v: f64| if v.is_nan() { f64::NEG_INFINITY } else { v };
    let mut points: Vec<Vec<f64>> = vec![start.to_vec()];
    for i in 0..d {
        let mut p = start.to_vec();
        p[i] += step[i] * scale;
        points.push(p);
    }
    let mut values: Vec<f64> = points.iter().map(|p| score(f(p))).collect();
    for _ in 0..300 * (d + 1) {
        // Order: best (largest) first.
        let mut order: Vec<usize> = (0..=d).collect();
        order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
        points = order.iter().map(|&i| points[i].clone()).collect();
        values = order.iter().map(|&i| values[i]).collect();
        let small = (0..d).all(|i| {
            points.iter().map(|p| (p[i] - points[0][i]).abs()).fold(0.0, f64::max) <= tolerance[i]
        });
        if small {
            break;
        }
        let centroid: Vec<f64> =
            (0..d).map(|i| points[..d].iter().map(|p| p[i]).sum::<f64>() / d as f64).collect();
        let toward = |t: f64| -> Vec<f64> {
            (0..d).map(|i| centroid[i] + t * (points[d][i] - centroid[i])).collect()
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
            let contracted = if fr > values[d] { toward(-0.5) } else { toward(0.5) };
            let fc = score(f(&contracted));
            if fc > values[d].max(fr) {
                points[d] = contracted;
                values[d] = fc;
            } else {
                for j in 1..=d {
                    let shrunk: Vec<f64> =
                        (0..d).map(|i| points[0][i] + 0.5 * (points[j][i] - points[0][i])).collect();
                    values[j] = score(f(&shrunk));
                    points[j] = shrunk;
                }
            }
        }
    }
    let best = (0..=d).max_by(|&a, &b| values[a].total_cmp(&values[b])).unwrap_or(0);
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
            return if c.abs() <= tiny { None } else { Some(Vec::new()) };
        }
        return Some(vec![-c / b]);
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return Some(Vec::new());
    }
    // The numerically stable pair.
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let mut roots = if q == 0.0 { vec![0.0] } else { vec![q / a, c / q] };
    roots.sort_by(f64::total_cmp);
    Some(roots)
}

/// `x - J^+ r` for the scaled variables: one minimum-norm Gauss-Newton step.
pub(crate) fn gauss_newton_step(jacobian: &DMatrix<f64>, residual: &DVector<f64>) -> Option<DVector<f64>> {
    let pinv = jacobian.clone().pseudo_inverse(1e-13 * jacobian.amax().max(f64::MIN_POSITIVE)).ok()?;
    Some(-(pinv * residual))
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
        assert!((x[0] - 0.3).abs() < 1e-9 && (x[1] + 0.1).abs() < 1e-9 && v > -1e-8, "{x:?}");
    }

    #[test]
    fn quadratic_roots_cases() {
        assert_eq!(quadratic_roots(1.0, -3.0, 2.0), Some(vec![1.0, 2.0]));
        assert_eq!(quadratic_roots(0.0, 2.0, -4.0), Some(vec![2.0]));
        assert_eq!(quadratic_roots(1.0, 0.0, 1.0), Some(vec![]));
        assert_eq!(quadratic_roots(0.0, 0.0, 0.0), None);
    }
}
