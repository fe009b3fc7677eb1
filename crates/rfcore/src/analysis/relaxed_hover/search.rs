//! The structured search for relaxed hover solutions of one *branch*: a set of carrying rotors
//! (free between their bounds) with every other working rotor held at its lower bound (idle).
//! The `relaxed_hover` module docs state the equations and why this finds every solution.
//!
//! For a spin axis `n` (body frame, pointing up) the relaxed hover equations are linear in the
//! carrying rotors' thrusts and quadratic in the spin rate `s` (with the rotors' angular momentum
//! `h` held; it is made consistent by a fixed point):
//!
//! `M(n) f = v(n, s) = [m g - n.F_idle,  s^2 (n x J n) + s (k_r n + n x h) - tau_idle]`,
//!
//! `M(n)` = rows `n.a_i` and the torque columns `tau_i`. The rank r of `M` decides the shape of
//! the solution set over the axis sphere, and each shape is solved exactly per axis:
//!
//! - r = 4 ("volume"): every spin rate is possible; the largest headroom over `s` is searched
//!   per axis, then `(n, s)` refined;
//! - r = 3 ("surface"): `v` must be in the range of `M`: one quadratic in `s`, at most two roots
//!   (two sheets over the axis sphere), each refined over `n`;
//! - r = 2 ("curve"): two quadratics with a common root: their resultant vanishes on curves of
//!   axes, found by sign changes on the grid and bisection, then followed to their best point;
//! - r <= 1 ("points"): isolated solutions, found by Newton from every local minimum of the
//!   residual on the grid.

use std::borrow::Cow;

use nalgebra::{DMatrix, DVector};

use super::headroom::Headroom;
use super::model::{Model, V3};
use super::numeric::{gauss_newton_step, nelder_mead, newton, quadratic_roots, Chart};
use super::settings::RelaxedHoverSettings;

/// How many grid maxima per sheet are refined (the best first).
const REFINED_PER_SHEET: usize = 4;
/// Spin-rate samples per sign and axis in the volume search.
const SPIN_SAMPLES: usize = 48;
/// The smallest spin rate a spinning solution may have, as a fraction of the largest allowed:
/// below it the solution is static hover (reported as such).
pub(crate) const SPIN_FLOOR_FRACTION: f64 = 1e-4;

/// How far past a rotor's thrust bound (relative to the largest bound or the weight) a solution may
/// sit and pass the bounds check (`mod.rs`); the searches keep a candidate by the same rule.
pub(crate) const BOUND_TOLERANCE: f64 = 1e-9;

/// A point the search found, before the final check.
#[derive(Debug, Clone)]
pub(crate) struct Candidate {
    pub up: V3,
    pub spin_rate_rad_s: f64,
    /// Every rotor's produced thrust (failed rotors 0, idle rotors at their lower bound).
    pub thrust_n: Vec<f64>,
}

/// What a rotor does in a branch: carries (its index among the carrying rotors), idles at its
/// lower bound, or is off (failed: no thrust).
#[derive(Debug, Clone, Copy)]
enum Role {
    Carrying(usize),
    Idle,
    Off,
}

/// One carrying set with the rest held at their lower bounds.
pub(crate) struct Branch<'a> {
    model: &'a Model,
    settings: &'a RelaxedHoverSettings,
    free: Vec<usize>,
    idle: Vec<usize>,
    /// What each rotor (all m, in rotor order) does in this branch.
    role: Vec<Role>,
    idle_force: V3,
    idle_torque: V3,
    common_axis: Option<V3>,
    chart: Chart,
    fixed: Option<Headroom>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    rank: usize,
    spin_floor: f64,
    grid_points: usize,
}

impl<'a> Branch<'a> {
    /// `None` when there are no carrying rotors or they cannot even carry the weight straight up.
    pub fn new(
        model: &'a Model,
        settings: &'a RelaxedHoverSettings,
        free: Vec<usize>,
        idle: Vec<usize>,
    ) -> Option<Self> {
        if free.is_empty() {
            return None;
        }
        let role = (0..model.rotor_count())
            .map(|i| match free.iter().position(|&j| j == i) {
                Some(c) => Role::Carrying(c),
                None if idle.contains(&i) => Role::Idle,
                None => Role::Off,
            })
            .collect();
        let idle_force: V3 = idle.iter().map(|&i| model.axis[i] * model.lower[i]).sum();
        let idle_torque: V3 = idle.iter().map(|&i| model.torque[i] * model.lower[i]).sum();
        let lower: Vec<f64> = free.iter().map(|&i| model.lower[i]).collect();
        let upper: Vec<f64> = free.iter().map(|&i| model.upper[i]).collect();
        let first = model.axis[free[0]];
        let common_axis = free
            .iter()
            .all(|&i| (model.axis[i] - first).amax() <= 1e-12)
            .then_some(first);
        let weight = model.weight_n();
        let (centre, max_angle) = match common_axis {
            Some(a) => {
                let most: f64 = upper.iter().map(|u| u.max(0.0)).sum::<f64>() + idle_force.norm();
                if most <= 0.0 || weight > most * (1.0 + 1e-12) {
                    return None;
                }
                let angle = (weight / most).clamp(-1.0, 1.0).acos();
                (a, angle.min(std::f64::consts::FRAC_PI_2 - 1e-9))
            }
            None => {
                let sum: V3 = free.iter().map(|&i| model.axis[i]).sum();
                let centre = if sum.norm() > 1e-9 {
                    sum.normalize()
                } else {
                    first
                };
                let spread = free
                    .iter()
                    .map(|&i| model.axis[i].dot(&centre).clamp(-1.0, 1.0).acos())
                    .fold(0.0, f64::max);
                (
                    centre,
                    (std::f64::consts::FRAC_PI_2 + spread).min(std::f64::consts::PI - 1e-6),
                )
            }
        };
        let chart = Chart::new(centre, max_angle);
        let mut branch = Branch {
            model,
            settings,
            free,
            idle,
            role,
            idle_force,
            idle_torque,
            common_axis,
            chart,
            fixed: None,
            lower,
            upper,
            rank: 0,
            spin_floor: SPIN_FLOOR_FRACTION * settings.max_spin_rate_rad_s,
            grid_points: settings.grid_points,
        };
        if common_axis.is_some() {
            let fixed = Headroom::new(&branch.matrix(&centre), &branch.lower, &branch.upper);
            branch.rank = fixed.rank();
            branch.fixed = Some(fixed);
        } else {
            let generic = chart.direction(0.3137, 0.1709).unwrap_or(centre);
            branch.rank =
                Headroom::new(&branch.matrix(&generic), &branch.lower, &branch.upper).rank();
        }
        Some(branch)
    }

    /// Every local optimum of this branch's spinning solutions (before the final check).
    pub fn spinning(&self) -> Vec<(Candidate, (f64, f64))> {
        match self.rank {
            4 => self.volume(),
            3 => self.surface(),
            2 => self.curve(),
            _ => self.points(),
        }
    }

    fn k(&self) -> usize {
        self.free.len()
    }

    /// `M(n)`: thrust along `n` (1 per newton for a common axis: the right side is divided by
    /// `n.a`), then the torque rows.
    fn matrix(&self, n: &V3) -> DMatrix<f64> {
        let k = self.k();
        DMatrix::from_fn(4, k, |r, c| {
            let i = self.free[c];
            match r {
                0 => match self.common_axis {
                    Some(_) => 1.0,
                    None => n.dot(&self.model.axis[i]),
                },
                _ => self.model.torque[i][r - 1],
            }
        })
    }

    fn headroom(&self, n: &V3) -> Cow<'_, Headroom> {
        match &self.fixed {
            Some(h) => Cow::Borrowed(h),
            None => Cow::Owned(Headroom::new(&self.matrix(n), &self.lower, &self.upper)),
        }
    }

    /// Thrust row of `v`: the weight less the idle rotors' share, per unit `n.a` for a common
    /// axis; `None` when the common axis does not point up at all.
    fn thrust_rhs(&self, n: &V3) -> Option<f64> {
        let need = self.model.weight_n() - n.dot(&self.idle_force);
        match self.common_axis {
            Some(a) => {
                let up = n.dot(&a);
                (up > 1e-12).then(|| need / up)
            }
            None => Some(need),
        }
    }

    /// `(s^2 coefficient, s coefficient, constant)` of the torque the carrying rotors must give.
    fn torque_terms(&self, n: &V3, h: &V3) -> (V3, V3, V3) {
        let m = self.model;
        let c2 = n.cross(&(m.inertia * n));
        let c1 = n * m.rotational_drag_n_m_s + n.cross(h);
        (c2, c1, -self.idle_torque)
    }

    fn rhs(&self, n: &V3, s: f64, h: &V3) -> Option<[f64; 4]> {
        let t = self.thrust_rhs(n)?;
        let (c2, c1, c0) = self.torque_terms(n, h);
        let q = c2 * (s * s) + c1 * s + c0;
        Some([t, q.x, q.y, q.z])
    }

    fn full_thrust(&self, free_thrust: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.model.rotor_count()];
        for &i in &self.idle {
            out[i] = self.model.lower[i];
        }
        for (c, &i) in self.free.iter().enumerate() {
            out[i] = free_thrust[c];
        }
        out
    }

    fn momentum(&self, free_thrust: &[f64]) -> V3 {
        self.model.rotor_momentum(&self.full_thrust(free_thrust))
    }

    /// The momentum with the weight shared equally (clamped to the bounds): the search's first
    /// guess, made consistent later.
    fn reference_momentum(&self) -> V3 {
        let share = self.model.weight_n() / self.k() as f64;
        let f: Vec<f64> = (0..self.k())
            .map(|c| share.clamp(self.lower[c], self.upper[c]))
            .collect();
        self.momentum(&f)
    }

    /// Smallest and largest spin-rate magnitude at chart point `(x, y)`: the floor, the circle
    /// the centre of mass may describe (common axis: `g tan(tilt) / s^2 <= r_max`), the cap.
    fn spin_range(&self, x: f64, y: f64) -> (f64, f64) {
        let mut low = self.spin_floor;
        if self.common_axis.is_some() {
            let tilt = self.chart.angle(x, y);
            let radius = self.settings.max_circle_radius_m;
            if radius.is_finite() {
                low = low.max((self.model.gravity_m_s2 * tilt.tan() / radius).sqrt());
            }
        }
        (low, self.settings.max_spin_rate_rad_s)
    }

    fn margin_of(&self, f: &[f64]) -> f64 {
        let scale = self.bound_scale();
        if f.iter()
            .zip(&self.lower)
            .any(|(x, lo)| *x < lo - 1e-12 * scale)
        {
            return f64::NEG_INFINITY;
        }
        f.iter()
            .zip(&self.upper)
            .map(|(x, hi)| hi - x)
            .fold(f64::INFINITY, f64::min)
    }

    fn bound_scale(&self) -> f64 {
        self.lower
            .iter()
            .chain(&self.upper)
            .fold(self.model.weight_n(), |a, b| a.max(b.abs()))
    }

    /// Within the bounds up to the bounds check's own slack (`BOUND_TOLERANCE`): a candidate a
    /// rounding error past a bound passes the final check, so the searches keep it too.
    fn within_bounds(&self, f: &[f64]) -> bool {
        self.margin_of(f) >= -BOUND_TOLERANCE * self.bound_scale()
    }

    /// The unique thrusts for `v` when the carrying rotors are exactly as many as the rank
    /// (least squares in the range of `M` otherwise: the point nearest to consistency).
    fn unique_thrusts(&self, headroom: &Headroom, v: &[f64; 4]) -> Option<Vec<f64>> {
        if self.k() != self.rank {
            return None;
        }
        headroom.least_squares(v)
    }

    /// Grid points `(x, y)` of the unit disk, row-major on an N x N lattice (`None` outside).
    fn grid(&self) -> (usize, f64, Vec<Option<(f64, f64)>>) {
        let n = self.grid_points;
        let spacing = 2.0 / (n - 1) as f64;
        let points = (0..n * n)
            .map(|idx| {
                let (i, j) = (idx / n, idx % n);
                let (x, y) = (-1.0 + i as f64 * spacing, -1.0 + j as f64 * spacing);
                (x * x + y * y <= 1.0 + 1e-12).then_some((x, y))
            })
            .collect();
        (n, spacing, points)
    }

    // -- r = 4: volume ----------------------------------------------------------------------

    fn volume(&self) -> Vec<(Candidate, (f64, f64))> {
        let (side, spacing, grid) = self.grid();
        let h_ref = self.reference_momentum();
        let mut out = Vec::new();
        for sign in [1.0, -1.0] {
            let margins: Vec<f64> = grid
                .iter()
                .map(|p| {
                    p.map_or(f64::NEG_INFINITY, |(x, y)| {
                        self.best_spin(x, y, sign, &h_ref).0
                    })
                })
                .collect();
            for idx in grid_maxima(side, &margins) {
                let (x, y) = grid[idx].expect("maxima lie on the disk");
                if let Some(found) = self.refine_volume(x, y, sign, spacing, h_ref) {
                    out.push(found);
                }
            }
        }
        out
    }

    /// The largest headroom over spin rates of sign `sign` at chart point `(x, y)`, and that
    /// rate (exact: [`Headroom::spin_envelope`]).
    fn best_spin(&self, x: f64, y: f64, sign: f64, h: &V3) -> (f64, f64) {
        let none = (f64::NEG_INFINITY, 0.0);
        let Some(n) = self.chart.direction(x, y) else {
            return none;
        };
        let (low, high) = self.spin_range(x, y);
        let Some(t) = self.thrust_rhs(&n) else {
            return none;
        };
        if low > high {
            return none;
        }
        // v(sign u) for u in [low, high]: coefficients of 1, u, u^2.
        let (c2, c1, c0) = self.torque_terms(&n, h);
        let v0 = [t, c0.x, c0.y, c0.z];
        let v1 = [0.0, sign * c1.x, sign * c1.y, sign * c1.z];
        let v2 = [0.0, c2.x, c2.y, c2.z];
        let (margin, u) = self.headroom(&n).spin_envelope([&v0, &v1, &v2], low, high);
        (margin, sign * u)
    }

    fn refine_volume(
        &self,
        x: f64,
        y: f64,
        sign: f64,
        spacing: f64,
        h_ref: V3,
    ) -> Option<(Candidate, (f64, f64))> {
        let mut point = vec![x, y];
        let mut h = h_ref;
        let mut found = None;
        for _ in 0..30 {
            let step = [0.5 * spacing, 0.5 * spacing];
            let (best, value) = nelder_mead(
                &mut |p| self.best_spin(p[0], p[1], sign, &h).0,
                &point,
                &step,
                &[1e-11, 1e-11],
            );
            if value.is_nan() || value < 0.0 {
                return None;
            }
            point = self.polish_kink(&best, &|p| {
                let (_, s) = self.best_spin(p[0], p[1], sign, &h);
                let n = self.chart.direction(p[0], p[1])?;
                self.unique_thrusts(&self.headroom(&n), &self.rhs(&n, s, &h)?)
            });
            let (margin, s) = self.best_spin(point[0], point[1], sign, &h);
            let n = self.chart.direction(point[0], point[1])?;
            let v = self.rhs(&n, s, &h)?;
            let f = self.headroom(&n).thrusts(&v, margin)?;
            let h_new = self.momentum(&f);
            found = Some((n, s, f));
            let size = h.norm().max(h_new.norm());
            if size == 0.0 || (h_new - h).norm() <= 1e-13 * size {
                break;
            }
            h = h_new;
        }
        let (n, s, f) = found?;
        // The last momentum update can move the optimum above a rotor's bound (the margin
        // checked at the start of the step was the previous momentum's): no relaxed hover.
        self.within_bounds(&f).then(|| (self.candidate(n, s, &f), (point[0], point[1])))
    }

    /// Nelder-Mead stops near, not on, a kinked optimum, where several carrying rotors share the
    /// smallest headroom (on stiff problems, a fast spin, that costs visible margin). Gauss-Newton
    /// on "their headrooms are equal" over the point's coordinates lands on the kink; the result
    /// is kept only if the margin does not drop. `thrusts` gives the unique thrusts at a point
    /// (`None`: not unique, nothing to do).
    fn polish_kink(&self, point: &[f64], thrusts: &dyn Fn(&[f64]) -> Option<Vec<f64>>) -> Vec<f64> {
        let Some(f0) = thrusts(point) else {
            return point.to_vec();
        };
        let k = self.k();
        let d = point.len();
        let scale = self.bound_scale();
        let margin0 = self.margin_of(&f0);
        if !margin0.is_finite() {
            return point.to_vec();
        }
        // Rotors by headroom, smallest first: the kink has the first j of them equal, j up to
        // one more than the point's coordinates (a vertex).
        let mut order: Vec<usize> = (0..k).collect();
        order.sort_by(|&a, &b| (self.upper[a] - f0[a]).total_cmp(&(self.upper[b] - f0[b])));
        let (mut best, mut best_margin) = (point.to_vec(), margin0);
        for j in 2..=k.min(d + 1) {
            let active = &order[..j];
            let residual = |p: &[f64]| -> Option<DVector<f64>> {
                let f = thrusts(p)?;
                let first = self.upper[active[0]] - f[active[0]];
                Some(DVector::from_iterator(
                    j - 1,
                    active[1..]
                        .iter()
                        .map(|&c| (self.upper[c] - f[c] - first) / scale),
                ))
            };
            let mut z = point.to_vec();
            for _ in 0..30 {
                let Some(r) = residual(&z) else { break };
                if r.amax() <= 1e-15 {
                    break;
                }
                let mut jac = DMatrix::zeros(j - 1, d);
                let mut ok = true;
                for c in 0..d {
                    let step = 1e-8 * z[c].abs().max(1e-3);
                    let (mut plus, mut minus) = (z.clone(), z.clone());
                    plus[c] += step;
                    minus[c] -= step;
                    match (residual(&plus), residual(&minus)) {
                        (Some(rp), Some(rm)) => jac.set_column(c, &((rp - rm) / (2.0 * step))),
                        _ => ok = false,
                    }
                }
                let Some(delta) = ok.then(|| gauss_newton_step(&jac, &r)).flatten() else {
                    break;
                };
                z = (0..d).map(|c| z[c] + delta[c]).collect();
            }
            if let Some(f) = thrusts(&z) {
                let m = self.margin_of(&f);
                if m > best_margin {
                    (best, best_margin) = (z, m);
                }
            }
        }
        best
    }

    // -- r = 3: surface ---------------------------------------------------------------------

    fn surface(&self) -> Vec<(Candidate, (f64, f64))> {
        let (side, spacing, grid) = self.grid();
        let h_ref = self.reference_momentum();
        let mut out = Vec::new();
        for sheet in 0..2 {
            let margins: Vec<f64> = grid
                .iter()
                .map(|p| match p {
                    None => f64::NEG_INFINITY,
                    Some((x, y)) => self
                        .surface_eval(*x, *y, sheet, &h_ref, false)
                        .map_or(f64::NEG_INFINITY, |e| e.0),
                })
                .collect();
            for idx in grid_maxima(side, &margins) {
                let (x, y) = grid[idx].expect("maxima lie on the disk");
                // With more carrying rotors than the rank the momentum is held during the search
                // and made consistent here (with as many, it is inside every evaluation).
                let mut point = vec![x, y];
                let mut h = h_ref;
                let mut result = None;
                for _ in 0..30 {
                    let mut objective = |p: &[f64]| {
                        self.surface_eval(p[0], p[1], sheet, &h, false)
                            .map_or(f64::NEG_INFINITY, |e| e.0)
                    };
                    let (best, value) = nelder_mead(
                        &mut objective,
                        &point,
                        &[0.5 * spacing, 0.5 * spacing],
                        &[1e-12, 1e-12],
                    );
                    if value.is_nan() || value < 0.0 {
                        break;
                    }
                    point = self.polish_kink(&best, &|p| {
                        if self.k() != self.rank {
                            return None;
                        }
                        self.surface_eval(p[0], p[1], sheet, &h, true).map(|e| e.2)
                    });
                    let Some((_, s, f, n)) = self.surface_eval(point[0], point[1], sheet, &h, true)
                    else {
                        break;
                    };
                    let h_new = self.momentum(&f);
                    // Within the bounds only (as in the volume search: the momentum moved).
                    result = self.within_bounds(&f).then(|| (self.candidate(n, s, &f), (point[0], point[1])));
                    let size = h.norm().max(h_new.norm());
                    if self.k() == self.rank || size == 0.0 || (h_new - h).norm() <= 1e-13 * size {
                        break;
                    }
                    h = h_new;
                }
                out.extend(result);
            }
        }
        out
    }

    /// Headroom, spin rate, thrusts and axis of root `sheet` at chart point `(x, y)`; with
    /// more carrying rotors than the rank, the thrusts only when `thrusts` is asked for (they
    /// cost a projection).
    fn surface_eval(
        &self,
        x: f64,
        y: f64,
        sheet: usize,
        h_start: &V3,
        thrusts: bool,
    ) -> Option<(f64, f64, Vec<f64>, V3)> {
        let n = self.chart.direction(x, y)?;
        let (low, high) = self.spin_range(x, y);
        let headroom = self.headroom(&n);
        let null = headroom.null_rows();
        if null.ncols() != 1 {
            return None;
        }
        let w = V3::new(null[(1, 0)], null[(2, 0)], null[(3, 0)]);
        let unique = self.k() == self.rank;
        let mut h = *h_start;
        for _ in 0..100 {
            let (c2, c1, c0) = self.torque_terms(&n, &h);
            let t = self.thrust_rhs(&n)?;
            let roots = quadratic_roots(w.dot(&c2), w.dot(&c1), null[(0, 0)] * t + w.dot(&c0))?;
            let s = *roots.get(sheet)?;
            if s.abs() < low || s.abs() > high {
                return None;
            }
            let v = self.rhs(&n, s, &h)?;
            if !unique {
                let margin = headroom.value(&v).margin;
                let f = if thrusts && margin.is_finite() {
                    headroom.thrusts(&v, margin)?
                } else {
                    Vec::new()
                };
                return Some((margin, s, f, n));
            }
            let f = self.unique_thrusts(&headroom, &v)?;
            let h_new = self.momentum(&f);
            let size = h.norm().max(h_new.norm());
            if size == 0.0 || (h_new - h).norm() <= 1e-14 * size {
                return Some((self.margin_of(&f), s, f, n));
            }
            h = h_new;
        }
        None
    }

    // -- r = 2: curves; r <= 1: points --------------------------------------------------------

    /// Curves of solutions: points on them by Newton from the residual's grid minima, each then
    /// moved along its curve to the most headroom (golden-section search over the coordinate the
    /// curve advances most in, the others solved by Newton).
    fn curve(&self) -> Vec<(Candidate, (f64, f64))> {
        let (_, spacing, _) = self.grid();
        let mut out = Vec::new();
        for z in self.converged_points() {
            let z = self.follow_curve(z, spacing);
            if let Some(found) = self.accept(&z) {
                out.push(found);
            }
        }
        out
    }

    /// Isolated solutions: Newton from every local minimum of the residual on the grid.
    fn points(&self) -> Vec<(Candidate, (f64, f64))> {
        self.converged_points()
            .iter()
            .filter_map(|z| self.accept(z))
            .collect()
    }

    /// A Newton solution `z = [x, y, s, f...]` as a candidate, if its thrusts and spin are
    /// allowed.
    fn accept(&self, z: &[f64]) -> Option<(Candidate, (f64, f64))> {
        let n = self.chart.direction(z[0], z[1])?;
        let (low, high) = self.spin_range(z[0], z[1]);
        let f = &z[3..];
        (self.margin_of(f) >= 0.0 && z[2].abs() >= low && z[2].abs() <= high)
            .then(|| (self.candidate(n, z[2], f), (z[0], z[1])))
    }

    /// Solutions reached by Newton from every local minimum (over the grid) of the residual with
    /// the best sampled spin rate and least-squares thrusts; distinct ones only.
    fn converged_points(&self) -> Vec<Vec<f64>> {
        let (side, spacing, grid) = self.grid();
        let h_ref = self.reference_momentum();
        let start = |x: f64, y: f64| -> Option<(Vec<f64>, f64)> {
            let n = self.chart.direction(x, y)?;
            let (low, high) = self.spin_range(x, y);
            if low > high {
                return None;
            }
            let headroom = self.headroom(&n);
            // The right side is v(s) = v0 + s v1 + s^2 v2 and least squares is linear, so the
            // thrusts are f(s) = f0 + s f1 + s^2 f2: three solves per grid point, not one per
            // sampled spin rate.
            let t = self.thrust_rhs(&n)?;
            let (c2, c1, c0) = self.torque_terms(&n, &h_ref);
            let f0 = headroom.least_squares(&[t, c0.x, c0.y, c0.z])?;
            let f1 = headroom.least_squares(&[0.0, c1.x, c1.y, c1.z])?;
            let f2 = headroom.least_squares(&[0.0, c2.x, c2.y, c2.z])?;
            let thrusts = |s: f64, f: &mut [f64]| {
                for (c, x) in f.iter_mut().enumerate() {
                    *x = f0[c] + s * (f1[c] + s * f2[c]);
                }
            };
            let mut f = vec![0.0; self.k()];
            let mut best: Option<(f64, f64)> = None;
            for sign in [1.0, -1.0] {
                for j in 0..SPIN_SAMPLES {
                    let s = sign
                        * low
                        * ((high / low).ln() * j as f64 / (SPIN_SAMPLES - 1) as f64).exp();
                    thrusts(s, &mut f);
                    let r = self.residual_at(&n, s, &f);
                    let size = r.iter().map(|e| e * e).sum::<f64>().sqrt();
                    if best.is_none_or(|b| size < b.1) {
                        best = Some((s, size));
                    }
                }
            }
            let (s, size) = best?;
            thrusts(s, &mut f);
            let mut z = vec![x, y, s];
            z.extend(f);
            Some((z, size))
        };
        let starts: Vec<Option<(Vec<f64>, f64)>> = grid
            .iter()
            .map(|p| p.and_then(|(x, y)| start(x, y)))
            .collect();
        let scores: Vec<f64> = starts
            .iter()
            .map(|s| s.as_ref().map_or(f64::NAN, |s| -s.1))
            .collect();
        let mut found: Vec<Vec<f64>> = Vec::new();
        for idx in local_maxima(side, &scores) {
            let (z, _) = starts[idx].clone().expect("finite");
            let Some(z) = self.newton(z, 60, None) else {
                continue;
            };
            let near = |w: &Vec<f64>| {
                (w[0] - z[0]).hypot(w[1] - z[1]) < 0.25 * spacing
                    && (w[2] - z[2]).abs() <= 1e-3 * (1.0 + z[2].abs())
            };
            if !found.iter().any(near) {
                found.push(z);
            }
        }
        found
    }

    /// From a solution on a curve, the most headroom along it nearby (see [`Branch::curve`]).
    fn follow_curve(&self, mut z: Vec<f64>, spacing: f64) -> Vec<f64> {
        let headroom = |z: &[f64]| {
            self.accept(z)
                .map_or(f64::NEG_INFINITY, |_| self.margin_of(&z[3..]))
        };
        let mut best = headroom(&z);
        let mut reach = spacing;
        for _ in 0..12 {
            let Some(tangent) = self.tangent(&z) else {
                break;
            };
            // The coordinate (x, y or s; the tangent is in scaled variables) the curve advances
            // most in.
            let scale = [1.0, 1.0, z[2].abs().max(1.0)];
            let p = (0..3)
                .max_by(|&a, &b| tangent[a].abs().total_cmp(&tangent[b].abs()))
                .expect("three coordinates");
            let width = reach * scale[p];
            let centre = z[p];
            let solve = |u: f64| -> Option<Vec<f64>> {
                let mut w = z.clone();
                w[p] = u;
                self.newton(w, 30, Some(p))
            };
            let score = |u: f64| solve(u).map_or(f64::NEG_INFINITY, |w| headroom(&w));
            let golden = 0.5 * (5.0f64.sqrt() - 1.0);
            let (mut lo, mut hi) = (centre - width, centre + width);
            let (mut u1, mut u2) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
            let (mut s1, mut s2) = (score(u1), score(u2));
            for _ in 0..30 {
                if s1 >= s2 {
                    (hi, u2, s2) = (u2, u1, s1);
                    u1 = hi - golden * (hi - lo);
                    s1 = score(u1);
                } else {
                    (lo, u1, s1) = (u1, u2, s2);
                    u2 = lo + golden * (hi - lo);
                    s2 = score(u2);
                }
            }
            let u = 0.5 * (lo + hi);
            match solve(u) {
                Some(w) if headroom(&w) > best => {
                    best = headroom(&w);
                    let interior = (u - centre).abs() < 0.9 * width;
                    z = w;
                    if interior {
                        reach *= 0.5;
                    }
                }
                _ => reach *= 0.5,
            }
            if reach < 1e-9 {
                break;
            }
        }
        z
    }

    /// The curve's direction at `z` in scaled variables: the null vector of the equations'
    /// Jacobian.
    fn tangent(&self, z: &[f64]) -> Option<Vec<f64>> {
        let jac = self.jacobian(z)?;
        super::numeric::null_vector(&jac).map(|v| v.iter().copied().collect())
    }

    // -- the exact equations ----------------------------------------------------------------

    /// Scaled residual of `z = [x, y, s]` and the carrying thrusts `f` (the whole model).
    fn residual_vector(&self, z: &[f64], f: &[f64]) -> Option<DVector<f64>> {
        let n = self.chart.direction(z[0], z[1])?;
        Some(DVector::from_row_slice(&self.residual_at(&n, z[2], f)))
    }

    /// [`Branch::residual_vector`] at up axis `n` and spin `s`, without allocating: the search's
    /// inner loop (every grid point, every sampled spin rate, every Newton step) is this call.
    /// The sums run over the rotors in rotor order, as [`Model::force`] and its siblings do on
    /// [`Branch::full_thrust`], so the numbers are theirs to the last bit.
    fn residual_at(&self, n: &V3, s: f64, f: &[f64]) -> [f64; 4] {
        let m = self.model;
        let (mut force, mut torque, mut h) = (V3::zeros(), V3::zeros(), V3::zeros());
        for (i, role) in self.role.iter().enumerate() {
            let thrust = match role {
                Role::Carrying(c) => f[*c],
                Role::Idle => m.lower[i],
                Role::Off => 0.0,
            };
            force += m.axis[i] * thrust;
            torque += m.torque[i] * thrust;
            h += m.momentum[i] * thrust.max(0.0).sqrt();
        }
        let omega = n * s;
        let torque = torque - m.required_torque(&omega, &h);
        let weight = m.weight_n();
        [
            (n.dot(&force) - weight) / weight,
            torque.x / m.torque_scale,
            torque.y / m.torque_scale,
            torque.z / m.torque_scale,
        ]
    }

    /// Variable scales of `z = [x, y, s, f...]` for Newton: chart 1, spin `max(|s|, 1)`, thrust
    /// the weight's share.
    fn scales(&self, z: &[f64]) -> Vec<f64> {
        let k = self.k();
        let share = self.model.weight_n() / k as f64;
        (0..k + 3)
            .map(|i| match i {
                0 | 1 => 1.0,
                2 => z[2].abs().max(1.0),
                _ => share,
            })
            .collect()
    }

    /// The Jacobian of the scaled residual in the scaled variables (central differences).
    fn jacobian(&self, z: &[f64]) -> Option<DMatrix<f64>> {
        let scale = self.scales(z);
        let mut jac = DMatrix::zeros(4, z.len());
        for c in 0..z.len() {
            let step = 1e-7 * scale[c];
            let (mut plus, mut minus) = (z.to_vec(), z.to_vec());
            plus[c] += step;
            minus[c] -= step;
            let rp = self.residual_vector(&plus[..3], &plus[3..])?;
            let rm = self.residual_vector(&minus[..3], &minus[3..])?;
            jac.set_column(c, &((rp - rm) * (scale[c] / (2.0 * step))));
        }
        Some(jac)
    }

    /// Minimum-norm Gauss-Newton on `z = [x, y, s, f...]` (coordinate `fixed` held); `None`
    /// unless the residual falls below 1e-13.
    pub fn newton(&self, z: Vec<f64>, iterations: usize, fixed: Option<usize>) -> Option<Vec<f64>> {
        newton(
            &|z| self.residual_vector(&z[..3], &z[3..]),
            z,
            &|z| self.scales(z),
            fixed,
            iterations,
            1e-13,
        )
    }

    /// Brings a candidate exactly onto the equations (a few Newton steps from where the search
    /// left it), keeping it when it is already there.
    pub fn polish(&self, candidate: Candidate, chart_point: (f64, f64)) -> Candidate {
        let f: Vec<f64> = self.free.iter().map(|&i| candidate.thrust_n[i]).collect();
        let mut z = vec![chart_point.0, chart_point.1, candidate.spin_rate_rad_s];
        z.extend(f);
        match self.residual_vector(&z[..3], &z[3..]) {
            Some(r) if r.amax() <= 1e-13 => candidate,
            _ => match self.newton(z, 20, None) {
                Some(z) => {
                    let n = self
                        .chart
                        .direction(z[0], z[1])
                        .expect("newton stays on the disk");
                    self.candidate(n, z[2], &z[3..])
                }
                None => candidate,
            },
        }
    }

    fn candidate(&self, up: V3, s: f64, free_thrust: &[f64]) -> Candidate {
        Candidate {
            up,
            spin_rate_rad_s: s,
            thrust_n: self.full_thrust(free_thrust),
        }
    }
}

/// Indices of grid points whose value is finite, >= 0 and not below any finite 8-neighbour, the
/// best [`REFINED_PER_SHEET`] first.
pub(super) fn grid_maxima(side: usize, values: &[f64]) -> Vec<usize> {
    let mut found: Vec<usize> = local_maxima(side, values)
        .into_iter()
        .filter(|&i| values[i] >= 0.0)
        .collect();
    found.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    found.truncate(REFINED_PER_SHEET);
    found
}

pub(super) fn local_maxima(side: usize, values: &[f64]) -> Vec<usize> {
    let mut out = Vec::new();
    for i in 0..side {
        for j in 0..side {
            let idx = i * side + j;
            let v = values[idx];
            if !v.is_finite() {
                continue;
            }
            let mut top = true;
            for di in -1i64..=1 {
                for dj in -1i64..=1 {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if (di, dj) == (0, 0) || a < 0 || b < 0 || a >= side as i64 || b >= side as i64
                    {
                        continue;
                    }
                    let w = values[a as usize * side + b as usize];
                    if w.is_finite() && w > v {
                        top = false;
                    }
                }
            }
            if top {
                out.push(idx);
            }
        }
    }
    out
}
