//! Static hover (no spin) with every working rotor free: the relaxed hover equations at zero
//! body rate. Rotors sharing one thrust axis are solved exactly (the axis points up); tilted
//! rotors by the headroom over the axis sphere, or by Newton where their wrench matrix has rank
//! < 6 (the solutions then form a set a grid does not meet).

use nalgebra::{DMatrix, DVector};

use super::headroom::Headroom;
use super::model::{Model, V3};
use super::numeric::{nelder_mead, newton, Chart};
use super::search::{grid_maxima, local_maxima, Candidate};
use super::settings::RelaxedHoverSettings;

/// Static hover (no spin) with every working rotor free: for rotors sharing one thrust axis, the
/// axis points up and `[sum f, tau(f)] = [m g, 0]`; otherwise the force must point along the up
/// axis: `[n.F, e1.F, e2.F, tau] = [m g, 0, 0, 0]`, searched over the axis like a sheet.
pub(crate) fn static_hover(model: &Model, settings: &RelaxedHoverSettings) -> Vec<Candidate> {
    let free = model.working.clone();
    if free.is_empty() {
        return Vec::new();
    }
    let lower: Vec<f64> = free.iter().map(|&i| model.lower[i]).collect();
    let upper: Vec<f64> = free.iter().map(|&i| model.upper[i]).collect();
    let weight = model.weight_n();
    let first = model.axis[free[0]];
    let common = free
        .iter()
        .all(|&i| (model.axis[i] - first).amax() <= 1e-12);
    let solve = |n: &V3, rows: DMatrix<f64>, v: &[f64]| -> Option<Candidate> {
        let headroom = Headroom::new(&rows, &lower, &upper);
        let value = headroom.value(v);
        if value.margin.is_nan() || value.margin < 0.0 || value.off_range > 1e-12 {
            return None;
        }
        let f = headroom.thrusts(v, value.margin)?;
        let mut thrust = vec![0.0; model.rotor_count()];
        for (c, &i) in free.iter().enumerate() {
            thrust[i] = f[c];
        }
        Some(Candidate {
            up: *n,
            spin_rate_rad_s: 0.0,
            thrust_n: thrust,
        })
    };
    let torque_rows = |r: usize, c: usize| model.torque[free[c]][r];
    if common {
        let rows = DMatrix::from_fn(4, free.len(), |r, c| {
            if r == 0 {
                1.0
            } else {
                torque_rows(r - 1, c)
            }
        });
        return solve(&first, rows, &[weight, 0.0, 0.0, 0.0])
            .into_iter()
            .collect();
    }
    let sum: V3 = free.iter().map(|&i| model.axis[i]).sum();
    let centre = if sum.norm() > 1e-9 {
        sum.normalize()
    } else {
        first
    };
    let chart = Chart::new(centre, std::f64::consts::PI - 1e-6);
    let rows_at = |n: &V3| {
        let (e1, e2) = super::model::tangent_basis(n);
        DMatrix::from_fn(6, free.len(), |r, c| {
            let a = model.axis[free[c]];
            match r {
                0 => n.dot(&a),
                1 => e1.dot(&a),
                2 => e2.dot(&a),
                _ => torque_rows(r - 3, c),
            }
        })
    };
    let v = [weight, 0.0, 0.0, 0.0, 0.0, 0.0];
    let generic = chart.direction(0.3137, 0.1709).unwrap_or(centre);
    let rank = Headroom::new(&rows_at(&generic), &lower, &upper).rank();
    let side = settings.grid_points;
    if rank < 6 {
        // The static solutions form a lower-dimensional set over the axes, which a grid does not
        // meet: Newton from the residual's local minima on the grid reaches them.
        return static_points(model, &free, &chart, side, &rows_at, &lower, &upper);
    }
    let value_at = |x: f64, y: f64| -> f64 {
        chart.direction(x, y).map_or(f64::NEG_INFINITY, |n| {
            let h = Headroom::new(&rows_at(&n), &lower, &upper);
            let value = h.value(&v);
            if value.off_range > 1e-12 {
                f64::NEG_INFINITY
            } else {
                value.margin
            }
        })
    };
    let spacing = 2.0 / (side - 1) as f64;
    let grid: Vec<Option<(f64, f64)>> = (0..side * side)
        .map(|idx| {
            let (x, y) = (
                -1.0 + (idx / side) as f64 * spacing,
                -1.0 + (idx % side) as f64 * spacing,
            );
            (x * x + y * y <= 1.0).then_some((x, y))
        })
        .collect();
    let values: Vec<f64> = grid
        .iter()
        .map(|p| p.map_or(f64::NEG_INFINITY, |(x, y)| value_at(x, y)))
        .collect();
    let mut out = Vec::new();
    for idx in grid_maxima(side, &values) {
        let (x, y) = grid[idx].expect("on the disk");
        let (best, value) = nelder_mead(
            &mut |p| value_at(p[0], p[1]),
            &[x, y],
            &[0.5 * spacing, 0.5 * spacing],
            &[1e-12, 1e-12],
        );
        if value >= 0.0 {
            if let Some(n) = chart.direction(best[0], best[1]) {
                out.extend(solve(&n, rows_at(&n), &v));
            }
        }
    }
    out
}

/// Static hover of tilted rotors whose wrench matrix has rank < 6: `F(f) = m g n`, `tau(f) = 0`
/// solved by Newton over `[x, y, f...]` from every local minimum of the least-squares residual
/// on the axis grid. Where the solutions form a family, Newton lands on one of its points, not
/// on the one with the most margin.
fn static_points(
    model: &Model,
    free: &[usize],
    chart: &Chart,
    side: usize,
    rows_at: &dyn Fn(&V3) -> DMatrix<f64>,
    lower: &[f64],
    upper: &[f64],
) -> Vec<Candidate> {
    let weight = model.weight_n();
    let full = |f: &[f64]| {
        let mut out = vec![0.0; model.rotor_count()];
        for (c, &i) in free.iter().enumerate() {
            out[i] = f[c];
        }
        out
    };
    let residual = |z: &[f64]| -> Option<DVector<f64>> {
        let n = chart.direction(z[0], z[1])?;
        let thrust = full(&z[2..]);
        let force = (model.force(&thrust) - n * weight) / weight;
        let torque = model.rotor_torque(&thrust) / model.torque_scale;
        Some(DVector::from_vec(vec![
            force.x, force.y, force.z, torque.x, torque.y, torque.z,
        ]))
    };
    let share = weight / free.len() as f64;
    let scale = |z: &[f64]| -> Vec<f64> {
        (0..z.len())
            .map(|i| if i < 2 { 1.0 } else { share })
            .collect()
    };
    let spacing = 2.0 / (side - 1) as f64;
    let v = [0.0, 0.0, weight, 0.0, 0.0, 0.0];
    let starts: Vec<Option<(Vec<f64>, f64)>> = (0..side * side)
        .map(|idx| {
            let (x, y) = (
                -1.0 + (idx / side) as f64 * spacing,
                -1.0 + (idx % side) as f64 * spacing,
            );
            let n = chart.direction(x, y)?;
            let f = Headroom::new(&rows_at(&n), lower, upper).least_squares(&v)?;
            let mut z = vec![x, y];
            z.extend(f);
            let size = residual(&z)?.norm();
            Some((z, size))
        })
        .collect();
    let scores: Vec<f64> = starts
        .iter()
        .map(|s| s.as_ref().map_or(f64::NAN, |s| -s.1))
        .collect();
    let mut out: Vec<Candidate> = Vec::new();
    for idx in local_maxima(side, &scores) {
        let (z, _) = starts[idx].clone().expect("finite");
        let Some(z) = newton(&residual, z, &scale, None, 60, 1e-13) else {
            continue;
        };
        let f = &z[2..];
        let inside = f
            .iter()
            .zip(lower.iter().zip(upper))
            .all(|(x, (lo, hi))| *x >= *lo - 1e-12 * share && *x <= *hi + 1e-12 * share);
        let Some(n) = chart.direction(z[0], z[1]) else {
            continue;
        };
        if inside && !out.iter().any(|c| (c.up - n).norm() < 1e-9) {
            out.push(Candidate {
                up: n,
                spin_rate_rad_s: 0.0,
                thrust_n: full(f),
            });
        }
    }
    out
}
