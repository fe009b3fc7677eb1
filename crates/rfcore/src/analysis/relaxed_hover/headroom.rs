//! The largest thrust headroom of a linear rotor problem, exactly:
//!
//! `max t  subject to  M f = v,  lower <= f <= upper - t`
//!
//! (`M`: p x k, rows a force or torque balance; `f`: the carrying rotors' thrusts). The set of
//! `v` reachable with headroom `t` is the zonotope `Z_t = M [lower, upper - t]`; it has the same
//! facet normals for every `t` (its generators only shrink), so with the support function
//! `Q(d) - t P(d)`, `P(d) = sum_i max(d.g_i, 0)`, the largest feasible `t` is the closed form
//!
//! `t* = min over facet normals d with P(d) > 0 of (Q(d) - d.v) / P(d)`,
//!
//! provided `v` lies in the range of `M` and satisfies the facets with `P(d) = 0` (otherwise no
//! `t` works). The facets live in the range of `M` (rank r): normals orthogonal to r - 1
//! linearly independent generators. Rows are equilibrated first (the answer does not change
//! with units). A negative `t*` says how far above their upper bounds the rotors would have to go.

use nalgebra::{DMatrix, DVector};

/// Singular values below this fraction of the largest (rows equilibrated) count as zero.
const RANK_RTOL: f64 = 1e-10;
/// A generator this close to a facet plane (relative to its length) lies in it.
const SNAP_RTOL: f64 = 1e-11;

#[derive(Debug, Clone)]
struct Facet {
    normal: Vec<f64>,
    rising: f64,
    support: f64,
}

/// One linear rotor problem (matrix and bounds), ready to evaluate many right-hand sides.
#[derive(Debug, Clone)]
pub(crate) struct Headroom {
    row_scale: Vec<f64>,
    /// Orthonormal basis of the range of the scaled matrix (p x r).
    range: DMatrix<f64>,
    /// Orthonormal basis of its left null space (p x (p - r)).
    null: DMatrix<f64>,
    /// Generators in range coordinates (r x k).
    generators: DMatrix<f64>,
    facets: Vec<Facet>,
    /// Pseudo-inverse of the generators (k x r): least squares in range coordinates.
    inverse: DMatrix<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    cap: f64,
}

/// `t*` and how far `v` lies outside the range of `M` (relative to `|v|`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct HeadroomValue {
    pub margin: f64,
    pub off_range: f64,
}

impl Headroom {
    pub fn new(matrix: &DMatrix<f64>, lower: &[f64], upper: &[f64]) -> Self {
        let (p, k) = matrix.shape();
        let row_scale: Vec<f64> = (0..p)
            .map(|r| {
                let max = matrix.row(r).amax();
                if max > 0.0 {
                    1.0 / max
                } else {
                    1.0
                }
            })
            .collect();
        let scaled = DMatrix::from_fn(p, k, |r, c| matrix[(r, c)] * row_scale[r]);
        let (range, null) = super::numeric::range_and_null(&scaled, RANK_RTOL);
        let generators = range.transpose() * &scaled;
        let facets = facets(&generators, lower, upper);
        // Minimum-norm least squares: G^T (G G^T)^+ (G has full row rank r).
        let inverse = generators.transpose()
            * super::numeric::symmetric_pinv(&(&generators * generators.transpose()), 1e-14);
        let cap = lower
            .iter()
            .zip(upper)
            .map(|(lo, hi)| hi - lo)
            .fold(f64::INFINITY, f64::min);
        Headroom {
            row_scale,
            range,
            null,
            generators,
            facets,
            inverse,
            lower: lower.to_vec(),
            upper: upper.to_vec(),
            cap,
        }
    }

    pub fn rank(&self) -> usize {
        self.range.ncols()
    }

    /// The left null space as row weights on the unscaled rows: `v` is in the range of `M`
    /// exactly when `null_rows()^T v = 0` (p x (p - r)).
    pub fn null_rows(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.null.nrows(), self.null.ncols(), |r, c| {
            self.null[(r, c)] * self.row_scale[r]
        })
    }

    fn project(&self, v: &[f64]) -> (DVector<f64>, f64) {
        let w = DVector::from_iterator(v.len(), v.iter().zip(&self.row_scale).map(|(x, s)| x * s));
        let inside = self.range.transpose() * &w;
        let off = (&w - &self.range * &inside).norm();
        let size = w.norm();
        (inside, if size > 0.0 { off / size } else { 0.0 })
    }

    /// `t*` for right-hand side `v` (module docs); `-inf` when no `t` is feasible.
    pub fn value(&self, v: &[f64]) -> HeadroomValue {
        let (w, off_range) = self.project(v);
        let mut margin = self.cap;
        if self.rank() == 0 {
            if off_range > 0.0 || v.iter().any(|x| *x != 0.0) {
                margin = f64::NEG_INFINITY;
            }
            return HeadroomValue { margin, off_range };
        }
        for facet in &self.facets {
            let along: f64 = facet.normal.iter().zip(w.iter()).map(|(a, b)| a * b).sum();
            if facet.rising > 0.0 {
                margin = margin.min((facet.support - along) / facet.rising);
            } else if along > facet.support + 1e-12 * (facet.support.abs() + along.abs()) {
                margin = f64::NEG_INFINITY;
            }
        }
        HeadroomValue { margin, off_range }
    }

    /// The largest headroom over `s` in `[low, high]` when the right side is the quadratic
    /// `v(s) = v0 + s v1 + s^2 v2`, and its `s`: exact. Each facet's bound is a quadratic in `s`;
    /// the headroom is their lower envelope (capped), restricted to where the facets that do not
    /// move with `t` hold. The envelope is walked piece by piece (at each breakpoint the quadratic
    /// that dips below the active one takes over) and each piece maximised in closed form.
    /// Requires `v(s)` in the range of `M` (rank = rows); `(-inf, low)` when nothing is feasible.
    pub fn spin_envelope(&self, v: [&[f64]; 3], low: f64, high: f64) -> (f64, f64) {
        let none = (f64::NEG_INFINITY, low);
        let w: Vec<DVector<f64>> = v.iter().map(|x| self.project(x).0).collect();
        let mut soft: Vec<[f64; 3]> = vec![[self.cap, 0.0, 0.0]];
        let mut hard: Vec<[f64; 3]> = Vec::new();
        for facet in &self.facets {
            let along: Vec<f64> = w
                .iter()
                .map(|wk| facet.normal.iter().zip(wk.iter()).map(|(a, b)| a * b).sum())
                .collect();
            if facet.rising > 0.0 {
                let p = facet.rising;
                soft.push([(facet.support - along[0]) / p, -along[1] / p, -along[2] / p]);
            } else {
                hard.push([facet.support - along[0], -along[1], -along[2]]);
            }
        }
        // Feasible pieces of [low, high]: where every hard quadratic is >= 0.
        let mut cuts = vec![low, high];
        for q in &hard {
            if let Some(roots) = super::numeric::quadratic_roots(q[2], q[1], q[0]) {
                cuts.extend(roots.into_iter().filter(|r| *r > low && *r < high));
            }
        }
        cuts.sort_by(f64::total_cmp);
        let eval = |q: &[f64; 3], s: f64| q[0] + s * (q[1] + s * q[2]);
        let mut best = none;
        for piece in cuts.windows(2) {
            let (a, b) = (piece[0], piece[1]);
            let mid = 0.5 * (a + b);
            let tol =
                |q: &[f64; 3]| 1e-12 * (q[0].abs() + (mid * q[1]).abs() + (mid * mid * q[2]).abs());
            if hard.iter().any(|q| eval(q, mid) < -tol(q)) {
                continue;
            }
            let found = envelope_max(&soft, a, b);
            if found.0 > best.0 {
                best = found;
            }
        }
        best
    }

    /// The minimum-norm least-squares thrusts for `v` in the range of `M` (the unique solution
    /// when the rotors are exactly as many as the rank and `v` is in the range).
    pub fn least_squares(&self, v: &[f64]) -> Option<Vec<f64>> {
        let (w, _) = self.project(v);
        Some((&self.inverse * w).iter().copied().collect())
    }

    /// The thrusts with headroom `margin` closest to the middle of the box `[lower, upper -
    /// margin]` (the one choice that depends on neither rotor order nor units), exactly: the
    /// projection's dual, `f(l) = clamp(c + G^T l)` with `G f(l) = w`, solved by semismooth Newton
    /// (a piecewise-linear equation: exact once the clamped set is right). The box is widened by
    /// 1e-10 of the bounds' size so it has an interior when `margin` is the largest headroom
    /// (the thrusts' own headroom may then be that much smaller). `None` when the box is empty or `v` is
    /// not reachable.
    pub fn thrusts(&self, v: &[f64], margin: f64) -> Option<Vec<f64>> {
        let k = self.lower.len();
        let scale = self
            .lower
            .iter()
            .chain(&self.upper)
            .fold(0.0f64, |a, b| a.max(b.abs()))
            .max(f64::MIN_POSITIVE);
        let t = margin - 1e-10 * scale;
        let top: Vec<f64> = (0..k).map(|i| self.upper[i] - t).collect();
        if (0..k).any(|i| top[i] < self.lower[i]) {
            return None;
        }
        let centre: Vec<f64> = (0..k).map(|i| 0.5 * (self.lower[i] + top[i])).collect();
        let (w, _) = self.project(v);
        let g = &self.generators;
        let r = g.nrows();
        if r == 0 {
            return Some(centre);
        }
        let clamp = |l: &DVector<f64>| -> Vec<f64> {
            let shift = g.transpose() * l;
            (0..k)
                .map(|i| (centre[i] + shift[i]).clamp(self.lower[i], top[i]))
                .collect()
        };
        let dual = |l: &DVector<f64>| -> f64 {
            let f = clamp(l);
            let miss = g * DVector::from_column_slice(&f) - &w;
            0.5 * f
                .iter()
                .zip(&centre)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                - l.dot(&miss)
        };
        let size = w.amax() + g.amax() * scale;
        let mut l = DVector::zeros(r);
        for _ in 0..200 {
            let f = clamp(&l);
            let gap = &w - g * DVector::from_column_slice(&f);
            if gap.amax() <= 1e-14 * size {
                return Some(f);
            }
            let shift = g.transpose() * &l;
            let free: Vec<usize> = (0..k)
                .filter(|&i| centre[i] + shift[i] > self.lower[i] && centre[i] + shift[i] < top[i])
                .collect();
            let gf = DMatrix::from_fn(r, free.len(), |a, b| g[(a, free[b])]);
            let hessian = &gf * gf.transpose();
            let mut step = super::numeric::symmetric_pinv(&hessian, 1e-14) * &gap;
            if step.amax() == 0.0 {
                step = gap.clone();
            }
            let base = dual(&l);
            let mut alpha = 1.0;
            let mut moved = false;
            for _ in 0..60 {
                let trial = &l + &step * alpha;
                if dual(&trial) > base {
                    l = trial;
                    moved = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !moved {
                break;
            }
        }
        let f = clamp(&l);
        let gap = &w - g * DVector::from_column_slice(&f);
        (gap.amax() <= 1e-12 * size).then_some(f)
    }
}

/// The largest value on `[a, b]` of the lower envelope of the quadratics `q0 + q1 s + q2 s^2`,
/// and where.
fn envelope_max(qs: &[[f64; 3]], a: f64, b: f64) -> (f64, f64) {
    let eval = |q: &[f64; 3], s: f64| q[0] + s * (q[1] + s * q[2]);
    let slope = |q: &[f64; 3], s: f64| q[1] + 2.0 * s * q[2];
    // The active quadratic just right of s: smallest value, then slope, then curvature.
    let active_at = |s: f64| -> usize {
        let mut best = 0;
        for i in 1..qs.len() {
            let (u, v) = (&qs[i], &qs[best]);
            let key = |q: &[f64; 3]| (eval(q, s), slope(q, s), q[2]);
            let (ku, kv) = (key(u), key(v));
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-13 * (1.0 + x.abs().max(y.abs()));
            let less = if !close(ku.0, kv.0) {
                ku.0 < kv.0
            } else if !close(ku.1, kv.1) {
                ku.1 < kv.1
            } else {
                ku.2 < kv.2
            };
            if less {
                best = i;
            }
        }
        best
    };
    let mut s = a;
    let mut best = (f64::NEG_INFINITY, a);
    for _ in 0..4 * qs.len() + 4 {
        let j = active_at(s);
        let q = &qs[j];
        // Where another quadratic first dips below the active one after s.
        let mut next = b;
        for (i, r) in qs.iter().enumerate() {
            if i == j {
                continue;
            }
            let d = [r[0] - q[0], r[1] - q[1], r[2] - q[2]];
            if let Some(roots) = super::numeric::quadratic_roots(d[2], d[1], d[0]) {
                for root in roots {
                    if root > s + 1e-14 * (1.0 + s.abs()) && root < next && slope(&d, root) < 0.0 {
                        next = root;
                    }
                }
            }
        }
        for candidate in [s, next] {
            let value = eval(q, candidate);
            if value > best.0 {
                best = (value, candidate);
            }
        }
        if q[2] < 0.0 {
            let top = -q[1] / (2.0 * q[2]);
            if top > s && top < next && eval(q, top) > best.0 {
                best = (eval(q, top), top);
            }
        }
        if next >= b {
            break;
        }
        s = next;
    }
    best
}

/// Facet normals of the zonotope `G [lower, upper]` in its own r-dimensional space (both signs),
/// with `P(d)` and `Q(d)` at `t = 0`.
fn facets(g: &DMatrix<f64>, lower: &[f64], upper: &[f64]) -> Vec<Facet> {
    let (r, k) = g.shape();
    if r == 0 {
        return Vec::new();
    }
    let lengths: Vec<f64> = (0..k).map(|i| g.column(i).norm()).collect();
    let mut out = Vec::new();
    let mut push = |normal: Vec<f64>| {
        for sign in [1.0, -1.0] {
            let d: Vec<f64> = normal.iter().map(|x| sign * x).collect();
            let (mut rising, mut support) = (0.0, 0.0);
            for i in 0..k {
                let mut along: f64 = (0..r).map(|a| d[a] * g[(a, i)]).sum();
                if along.abs() <= SNAP_RTOL * lengths[i] {
                    along = 0.0;
                }
                if along > 0.0 {
                    rising += along;
                    support += along * upper[i];
                } else {
                    support += along * lower[i];
                }
            }
            out.push(Facet {
                normal: d,
                rising,
                support,
            });
        }
    };
    if r == 1 {
        push(vec![1.0]);
        return out;
    }
    for subset in combinations(k, r - 1) {
        let normal = cofactor_normal(g, &subset);
        let size: f64 = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
        let scale: f64 = subset.iter().map(|&i| lengths[i]).product();
        if scale > 0.0 && size > 1e-9 * scale {
            push(normal.iter().map(|x| x / size).collect());
        }
    }
    out
}

/// The generalised cross product of the columns `subset` (r - 1 of them) of the r x k matrix
/// `g`: the cofactors of the last column of `[g_subset | e]`, orthogonal to every column used.
fn cofactor_normal(g: &DMatrix<f64>, subset: &[usize]) -> Vec<f64> {
    let r = g.nrows();
    (0..r)
        .map(|row| {
            let minor = DMatrix::from_fn(r - 1, r - 1, |a, b| {
                let source = if a < row { a } else { a + 1 };
                g[(source, subset[b])]
            });
            let sign = if (row + r - 1).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            sign * minor.determinant()
        })
        .collect()
}

/// Every `size`-element subset of `0..n`, in lexicographic order.
pub(crate) fn combinations(n: usize, size: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut current = Vec::with_capacity(size);
    fn walk(
        start: usize,
        n: usize,
        size: usize,
        current: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if current.len() == size {
            out.push(current.clone());
            return;
        }
        for i in start..n {
            if n - i < size - current.len() {
                break;
            }
            current.push(i);
            walk(i + 1, n, size, current, out);
            current.pop();
        }
    }
    walk(0, n, size, &mut current, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The LP by vertex enumeration (an independent method): at an optimum as many bounds are
    /// active as the problem has free dimensions, each rotor at `lower` or at `upper - t`.
    fn by_vertices(m: &DMatrix<f64>, v: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
        let (p, k) = m.shape();
        let mut best = f64::NEG_INFINITY;
        for active in combinations(k, k + 1 - p) {
            for mask in 0..(1u32 << active.len()) {
                // Unknowns f (k) and t; rows: M f = v, then one per active bound.
                let mut a = DMatrix::zeros(k + 1, k + 1);
                let mut b = DVector::zeros(k + 1);
                for r in 0..p {
                    for c in 0..k {
                        a[(r, c)] = m[(r, c)];
                    }
                    b[r] = v[r];
                }
                for (j, &i) in active.iter().enumerate() {
                    a[(p + j, i)] = 1.0;
                    if mask & (1 << j) != 0 {
                        a[(p + j, k)] = 1.0; // f_i + t = upper_i
                        b[p + j] = upper[i];
                    } else {
                        b[p + j] = lower[i];
                    }
                }
                let Some(x) = a.lu().solve(&b) else { continue };
                let t = x[k];
                let ok = (0..k).all(|i| x[i] >= lower[i] - 1e-9 && x[i] <= upper[i] - t + 1e-9);
                if ok && t > best {
                    best = t;
                }
            }
        }
        let cap = lower
            .iter()
            .zip(upper)
            .map(|(a, b)| b - a)
            .fold(f64::INFINITY, f64::min);
        best.min(cap)
    }

    #[test]
    fn square_problem_is_the_smallest_headroom_of_the_unique_solution() {
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, -1.0]);
        let h = Headroom::new(&m, &[0.0, 0.0], &[5.0, 5.0]);
        // f = (3, 1): headroom min(2, 4) = 2.
        let value = h.value(&[4.0, 2.0]);
        assert!((value.margin - 2.0).abs() < 1e-12, "{value:?}");
        let f = h.thrusts(&[4.0, 2.0], value.margin).unwrap();
        assert!(
            (f[0] - 3.0).abs() < 1e-12 && (f[1] - 1.0).abs() < 1e-12,
            "{f:?}"
        );
        // f = (-0.5, 2.5) needs a thrust below its lower bound: infeasible for every t.
        assert_eq!(h.value(&[2.0, -3.0]).margin, f64::NEG_INFINITY);
    }

    #[test]
    fn redundant_problem_matches_vertex_enumeration() {
        let m = DMatrix::from_row_slice(
            3,
            5,
            &[
                1.0, 1.0, 1.0, 1.0, 1.0, 0.3, -0.2, 0.5, -0.4, 0.1, 0.02, -0.03, 0.01, 0.04, -0.05,
            ],
        );
        let lower = [0.0, 0.0, -1.0, 0.0, 0.5];
        let upper = [4.0, 3.0, 4.0, 5.0, 4.0];
        for v in [
            [6.0, 0.1, 0.0],
            [10.0, -0.5, 0.02],
            [15.0, 0.0, 0.0],
            [2.0, 0.8, -0.1],
        ] {
            let h = Headroom::new(&m, &lower, &upper);
            let exact = h.value(&v).margin;
            let bisected = by_vertices(&m, &v, &lower, &upper);
            if exact.is_finite() {
                assert!(
                    (exact - bisected).abs() < 1e-6,
                    "{v:?}: {exact} vs {bisected}"
                );
                let f = h.thrusts(&v, exact).unwrap();
                let headroom = (0..5)
                    .map(|i| upper[i] - f[i])
                    .fold(f64::INFINITY, f64::min);
                assert!((headroom - exact).abs() < 1e-9, "{f:?}");
            } else {
                assert_eq!(bisected, f64::NEG_INFINITY, "{v:?}");
            }
            assert!(exact.is_finite() || bisected == f64::NEG_INFINITY);
        }
    }

    #[test]
    fn rank_deficient_problem_reports_the_null_space() {
        // Two columns in R^3: v must lie in their span.
        let m = DMatrix::from_row_slice(3, 2, &[1.0, 1.0, 0.2, -0.2, 0.0, 0.0]);
        let h = Headroom::new(&m, &[0.0, 0.0], &[5.0, 5.0]);
        assert_eq!(h.rank(), 2);
        let n = h.null_rows();
        assert_eq!(n.ncols(), 1);
        assert!((n[(2, 0)].abs() - 1.0).abs() < 1e-12);
        assert!(h.value(&[2.0, 0.0, 0.0]).off_range < 1e-15);
        assert!(h.value(&[2.0, 0.0, 0.1]).off_range > 1e-3);
    }

    #[test]
    fn spin_envelope_is_the_sampled_maximum() {
        // Thrust and three torques from five rotors; v(s) quadratic in s.
        let m = DMatrix::from_row_slice(
            4,
            5,
            &[
                1.0, 1.0, 1.0, 1.0, 1.0, 0.2, -0.1, -0.2, 0.1, 0.05, 0.1, 0.2, -0.1, -0.2, 0.0,
                0.02, -0.02, 0.02, -0.02, 0.02,
            ],
        );
        let lower = [0.0; 5];
        let upper = [3.0, 3.0, 3.0, 3.0, 2.5];
        let h = Headroom::new(&m, &lower, &upper);
        let v0 = [6.0, 0.01, -0.02, -0.05];
        let v1 = [0.0, 0.01, 0.004, 0.003];
        let v2 = [0.0, -0.0004, 0.0002, 0.0];
        let (t, s) = h.spin_envelope([&v0, &v1, &v2], 0.5, 60.0);
        let at = |s: f64| {
            let v: Vec<f64> = (0..4).map(|r| v0[r] + s * v1[r] + s * s * v2[r]).collect();
            h.value(&v).margin
        };
        assert!((at(s) - t).abs() < 1e-12, "{t} at {s}: {}", at(s));
        let sampled = (0..=200_000)
            .map(|j| at(0.5 + 59.5 * j as f64 / 200_000.0))
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            t >= sampled - 1e-12 && t - sampled < 1e-6,
            "{t} vs {sampled}"
        );
    }

    #[test]
    fn combinations_count() {
        assert_eq!(combinations(6, 3).len(), 20);
        assert_eq!(combinations(4, 0), vec![Vec::<usize>::new()]);
    }
}
