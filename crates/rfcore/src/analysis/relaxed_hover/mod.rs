//! Relaxed hover (Mueller and D'Andrea, "Relaxed hover solutions for multicopters", IJRR 2016;
//! "Stability and control of a quadrocopter despite the complete loss of one, two, or three
//! propellers", ICRA 2014): every way a multirotor can stay in place with constant rotor thrusts
//! once static hover is lost, spinning at a constant rate about a vertical axis.
//!
//! # The equations
//! Body FRD, rotor thrusts `f_i` constant within their bounds (efficiency times the rotor's
//! command bounds; a failed rotor gives 0), body rate `omega` constant. With the attitude turning
//! at `omega`, the body force `F = sum a_i f_i` turns with the body; the centre of mass stays in
//! place on average only if `omega` is vertical (or zero) and the force's vertical part carries
//! the weight. With `n` the body axis that points up (world up seen from the body) and the spin
//! rate `s`:
//!
//! - spinning: `omega = s n`, `n . F = m g`, and the moment balance
//!   `tau(f) = omega x (J omega + h(f)) + k_r omega`, with the rotors' angular momentum
//!   `h(f) = I_R sum_i w_i sqrt(f_i / k_f) a_i` (gyroscopic moment, as the simulator has it) and
//!   the aerodynamic rotational damping `k_r`. The horizontal part of `F` turns at `s`: the centre
//!   of mass describes a horizontal circle of radius `|F_perp| / (m s^2)` (without translational
//!   drag), which must stay below `max_circle_radius_m`.
//! - static (`omega = 0`): `F = m g n`, `tau(f) = 0`.
//!
//! `k_r`, `I_R` and `k_f` are not airframe fields (the simulator takes them from its `Drag` and
//! actuator); they are settings here, 0 by default like the simulator's.
//!
//! # Thrust margin
//! A solution's *thrust margin* is its headroom: the smallest distance of a carrying rotor's
//! thrust to its upper bound, `min_i (f_max,i - f_i)` in newtons, the room the vehicle has to
//! steer and climb. The distance to the lower bound (`thrust_floor_n`) is reported beside it but
//! not maximised: a two-sided margin rewards tilting further than needed (on Ke's quadcopter with
//! rotor 1 lost its optimum tilts the axis 54 degrees and spends 68 % more thrust than the weight,
//! to lift every rotor to mid-range), while the headroom optimum tilts 17 degrees with three equal
//! thrusts. With the headroom, a healthy symmetric frame's best solution is static hover: any
//! relaxed hover needs `n . F = m g`, so its largest thrust is at least the static one.
//!
//! # The method (structural; why it finds every solution)
//! 1. *Branches*: every set of working rotors held at their lower bound (idle: off for rotors
//!    that cannot push down), up to `max_idle_rotors` of them; the others carry the vehicle
//!    between their bounds. Each local optimum of the margin has some such set, so enumerating
//!    them enumerates the lower-bound active sets.
//! 2. *Per spin axis, exactly*: for a fixed axis `n` the equations are linear in the carrying
//!    thrusts and quadratic in `s` (with `h` held, made consistent by a fixed point), and the
//!    largest margin of a linear rotor problem has a closed form (the facets of the attainable
//!    zonotope; `headroom`). The rank of the carrying rotors' thrust-and-torque matrix decides the
//!    solution set's shape over the axes: an open set (rank 4: every `s`; the best `s` per axis
//!    exactly, each facet's bound being a quadratic in `s`: the maximum of their lower envelope),
//!    two sheets (rank 3: the roots of one quadratic), curves (rank 2: two quadratics with a
//!    common root) or isolated points (rank 1).
//! 3. *Over the axes*: a grid on the cap of possible up axes (`grid_points` per side of an
//!    azimuthal-equidistant chart, about `2 * max_tilt / (grid_points - 1)` apart); every local
//!    maximum of each sheet refined (Nelder-Mead over the axis with restarts, then Gauss-Newton
//!    onto the kink where several rotors share the margin), curves and points reached by Newton
//!    from the residual's local minima on the grid and curves followed to their best point
//!    (golden-section search along them), then everything brought exactly onto the equations.
//!    A solution set is missed only if it is narrower than the grid spacing in every direction
//!    and no residual minimum of the grid leads to it. Static hover: rotors sharing one thrust
//!    axis hover with it pointing up (one linear problem); tilted rotors that make every wrench
//!    are searched over the up axis like a sheet; tilted rotors that do not (rank < 6) hover
//!    statically at isolated axes or along families, reached by Newton (on a family, one of its
//!    points, not necessarily the one with the most margin).
//! 4. *Checks*: every solution's residual (scaled by `m g` and `m g` times the largest torque
//!    per newton) must be below [`RESIDUAL_TOLERANCE`] and its thrusts inside their bounds, or
//!    the analysis fails naming the check. Solutions equal in axis, spin and thrusts are merged
//!    (a healthy frame spinning about its thrust axis with unchanged thrusts is its static
//!    hover).
//! 5. *One per strategy*: a strategy is a set of carrying rotors, static or spinning, and the
//!    spin direction; its solutions form a continuum (dimension: carrying rotors less one), of
//!    which the one with the most margin is reported. Each comes with its linear model and
//!    whether a linear feedback can hold it (every non-decaying mode reachable from the carrying
//!    rotors). The list is sorted: holdable first, then most margin, then slowest spin; the best
//!    is the first, if holdable.

mod headroom;
mod linear;
mod model;
mod numeric;
mod search;
mod settings;
mod static_hover;

use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::airframe::Airframe;
use crate::cancel::Cancel;
use crate::error::{require_all_finite, Result, RfError};

pub use linear::LINEAR_STATES;
pub use settings::RelaxedHoverSettings;
use model::{Model, V3};
use search::{Branch, Candidate, BOUND_TOLERANCE, SPIN_FLOOR_FRACTION};
use static_hover::static_hover;

/// Largest scaled equation residual a returned solution may have.
pub const RESIDUAL_TOLERANCE: f64 = 1e-9;

/// Static hover (no spin) or a spinning relaxed hover.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HoverKind {
    Static,
    Spinning,
}

impl HoverKind {
    pub fn name(self) -> &'static str {
        match self {
            HoverKind::Static => "static",
            HoverKind::Spinning => "spinning",
        }
    }
}

/// One relaxed hover solution, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxedHoverSolution {
    pub kind: HoverKind,
    /// `omega = s n`, body FRD (rad/s).
    pub body_rate_rad_s: [f64; 3],
    /// `s = omega . n`: positive turns anticlockwise seen from above (rad/s).
    pub spin_rate_rad_s: f64,
    /// `n`: the body axis that points up (world up in body FRD), the spin axis.
    pub spin_axis: [f64; 3],
    /// `F / |F|`: the direction of the rotors' total force, body FRD.
    pub thrust_direction: [f64; 3],
    /// Produced thrust of every rotor (N; failed rotors 0).
    pub thrust_n: Vec<f64>,
    /// The rotor commands that produce it: thrust over efficiency (0 for failed rotors).
    pub command_n: Vec<f64>,
    /// Headroom: smallest `f_max - f` over the carrying rotors (N).
    pub thrust_margin_n: f64,
    /// Smallest `f - f_min` over the carrying rotors (N).
    pub thrust_floor_n: f64,
    /// Rotors producing thrust (0-based, ascending).
    pub carrying: Vec<usize>,
    /// Working rotors producing none (held off).
    pub idle: Vec<usize>,
    /// `|F|` (N).
    pub total_thrust_n: f64,
    /// Angle between the total force and the spin axis (rad).
    pub tilt_rad: f64,
    /// Radius of the circle the centre of mass describes, without translational drag (m).
    pub circle_radius_m: f64,
    /// Largest scaled equation residual ([`Model`] docs): below [`RESIDUAL_TOLERANCE`].
    pub residual: f64,
    /// `|s|` is the largest spin rate searched: the family goes on beyond it.
    pub at_spin_rate_limit: bool,
    /// The circle of the centre of mass has the largest radius allowed.
    pub at_circle_radius_limit: bool,
    /// The linear model about this solution ([`linear`]), inputs the carrying rotors.
    pub linear: LinearModel,
}

/// `x' = A x + B u` about a solution: `x = [a, b, dp, dq, dr, z, w]` (up axis seen from the
/// body, `n + a e1 + b e2`; body-rate deviation; altitude up and its rate), `u` the thrust
/// deviations of `inputs` (the carrying rotors, 0-based).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearModel {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub e1: [f64; 3],
    pub e2: [f64; 3],
    pub inputs: Vec<usize>,
    /// Every mode that does not decay can be moved by the inputs (PBH test): a linear feedback
    /// can hold this solution.
    pub stabilizable: bool,
}

/// Every relaxed hover solution found, best first.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxedHoverAnalysis {
    pub solutions: Vec<RelaxedHoverSolution>,
    pub settings: RelaxedHoverSettings,
}

impl RelaxedHoverAnalysis {
    /// The solution with the most thrust margin (the slowest spin among equal margins) among
    /// those a linear feedback can hold; `None` when there is none.
    pub fn best(&self) -> Option<&RelaxedHoverSolution> {
        self.solutions.first().filter(|s| s.linear.stabilizable)
    }
}

/// Every relaxed hover solution of `airframe` (efficiencies included) with `settings` (module
/// docs: equations, margin, method, checks).
pub fn relaxed_hover(
    airframe: &Airframe,
    settings: &RelaxedHoverSettings,
) -> Result<RelaxedHoverAnalysis> {
    relaxed_hover_cancellable(airframe, settings, &Cancel::never())
}

/// [`relaxed_hover`] that stops with [`RfError::Interrupted`] once `cancel` is cancelled (checked
/// before the static search and once per branch of carrying rotors).
pub fn relaxed_hover_cancellable(
    airframe: &Airframe,
    settings: &RelaxedHoverSettings,
    cancel: &Cancel,
) -> Result<RelaxedHoverAnalysis> {
    search_all(airframe, settings, cancel, false)
}

/// What decides [`RelaxedHoverAnalysis::best`], faster: the branches are searched by number of
/// idle rotors (none, then one, ...) and a branch is skipped when no solution of it can have the
/// margin of the best holdable solution already found ([`margin_bound`]: the carrying rotors'
/// headroom if their thrusts just carry the weight). `best()` is the full analysis's (same
/// candidates in the same order up to the skipped ones, which cannot come first); `solutions`
/// lists fewer strategies. Used by certify, which reads only the best.
pub fn best_relaxed_hover_cancellable(
    airframe: &Airframe,
    settings: &RelaxedHoverSettings,
    cancel: &Cancel,
) -> Result<RelaxedHoverAnalysis> {
    search_all(airframe, settings, cancel, true)
}

fn search_all(
    airframe: &Airframe,
    settings: &RelaxedHoverSettings,
    cancel: &Cancel,
    best_only: bool,
) -> Result<RelaxedHoverAnalysis> {
    settings.check()?;
    cancel.check()?;
    let model = Model::new(airframe, settings)?;
    let mut found: Vec<Candidate> = static_hover(&model, settings);
    let working = model.working.clone();
    let largest_idle = settings
        .max_idle_rotors
        .min(working.len().saturating_sub(1));
    // The bound holds only where every thrust is >= 0 (rotors that cannot push down).
    let prunable = best_only && working.iter().all(|&i| model.lower[i] >= 0.0);
    for size in 0..=largest_idle {
        let mut branches: Vec<Vec<usize>> = headroom::combinations(working.len(), size)
            .into_iter()
            .map(|idle| idle.iter().map(|&j| working[j]).collect())
            .collect();
        if prunable && size > 0 {
            let solutions = solutions_of(&model, settings, &found)?;
            let best = solutions
                .iter()
                .filter(|s| s.linear.stabilizable)
                .map(|s| s.thrust_margin_n)
                .fold(f64::NEG_INFINITY, f64::max);
            // Skipped only when clearly below (the merge and ranking compare margins to 1e-9).
            let below = best - 1e-6 * bound_scale(&model);
            branches.retain(|idle| margin_bound(&model, idle) >= below);
        }
        cancel.check()?;
        let spinning: Vec<Vec<Candidate>> = branches
            .par_iter()
            .map(|idle: &Vec<usize>| -> Result<Vec<Candidate>> {
                cancel.check()?;
                let free: Vec<usize> = working
                    .iter()
                    .copied()
                    .filter(|i| !idle.contains(i))
                    .collect();
                Ok(match Branch::new(&model, settings, free, idle.clone()) {
                    None => Vec::new(),
                    Some(branch) => branch
                        .spinning()
                        .into_iter()
                        .map(|(candidate, chart_point)| branch.polish(candidate, chart_point))
                        .collect(),
                })
            })
            .collect::<Result<_>>()?;
        found.extend(spinning.into_iter().flatten());
    }
    let mut solutions = solutions_of(&model, settings, &found)?;
    solutions.sort_by(|a, b| {
        if better(&model, a, b) {
            std::cmp::Ordering::Less
        } else if better(&model, b, a) {
            std::cmp::Ordering::Greater
        } else {
            a.spin_axis
                .partial_cmp(&b.spin_axis)
                .unwrap_or(std::cmp::Ordering::Equal)
        }
    });
    Ok(RelaxedHoverAnalysis {
        solutions,
        settings: *settings,
    })
}

/// The candidates checked and measured ([`finish`]), the static limits of spinning families
/// and circles too large left out, equal ones merged and one kept per strategy (its best), in
/// the candidates' order.
fn solutions_of(
    model: &Model,
    settings: &RelaxedHoverSettings,
    found: &[Candidate],
) -> Result<Vec<RelaxedHoverSolution>> {
    let floor = 2.0 * SPIN_FLOOR_FRACTION * settings.max_spin_rate_rad_s;
    let mut solutions: Vec<RelaxedHoverSolution> = Vec::new();
    for candidate in found {
        if candidate.spin_rate_rad_s != 0.0 && candidate.spin_rate_rad_s.abs() <= floor {
            continue; // the static limit of a spinning family: reported as static hover
        }
        let solution = finish(model, settings, candidate)?;
        if solution.kind == HoverKind::Spinning
            && solution.circle_radius_m > settings.max_circle_radius_m * (1.0 + 1e-9)
        {
            continue; // outside the definition (only possible with tilted rotors)
        }
        if solutions.iter().any(|s| same(model, s, &solution)) {
            continue;
        }
        // One solution per strategy (carrying rotors, kind, spin direction): its best.
        match solutions.iter().position(|s| same_strategy(s, &solution)) {
            Some(i) if better(model, &solution, &solutions[i]) => solutions[i] = solution,
            Some(_) => {}
            None => solutions.push(solution),
        }
    }
    Ok(solutions)
}

/// An upper bound on the thrust margin of any solution of the branch that idles `idle` (every
/// thrust >= 0): the rotors that carry, `C` (some of the branch's free rotors, the rest at ~0),
/// lift `n . sum a_i f_i = m g - n . F_idle >= m g - |F_idle|` with `n . a_i <= |a_i| <= r`, so
/// `sum_C f_i >= (m g - |F_idle|) / r` (C empty only when the idle rotors carry it: not bounded);
/// with `f_i <= f_max,i - t`, `t <= (sum_C f_max,i - (m g - |F_idle|) / r) / |C|`, the largest
/// over the subsets `C` (the bounds check's slack added).
fn margin_bound(model: &Model, idle: &[usize]) -> f64 {
    let free: Vec<usize> = model
        .working
        .iter()
        .copied()
        .filter(|i| !idle.contains(i))
        .collect();
    let idle_force: V3 = idle.iter().map(|&i| model.axis[i] * model.lower[i]).sum();
    // `n . a_i <= |a_i|`: the airframe check lets a thrust axis be 1e-6 longer than a unit vector.
    let reach = free.iter().map(|&i| model.axis[i].norm()).fold(1.0, f64::max);
    let need = (model.weight_n() - idle_force.norm()) / reach;
    let slack = BOUND_TOLERANCE * bound_scale(model) * (model.rotor_count() as f64 + 1.0);
    if need <= slack || free.len() > 20 {
        // The idle rotors alone could carry it (C empty), or too many subsets: search it.
        return f64::INFINITY;
    }
    let mut bound = f64::NEG_INFINITY;
    for mask in 1u64..(1u64 << free.len()) {
        let members = (0..free.len()).filter(|b| mask & (1 << b) != 0);
        let (sum, count) = members.fold((0.0, 0usize), |(s, c), b| (s + model.upper[free[b]], c + 1));
        bound = bound.max((sum - need) / count as f64);
    }
    bound + slack
}

/// The scaled residual of a proposed solution ([`Model`]): `up` the body axis pointing up,
/// `body_rate_rad_s` zero (static) or parallel to it, thrusts produced per rotor.
pub fn relaxed_hover_residual(
    airframe: &Airframe,
    settings: &RelaxedHoverSettings,
    body_rate_rad_s: [f64; 3],
    up: [f64; 3],
    thrust_n: &[f64],
) -> Result<f64> {
    settings.check()?;
    crate::error::require_len("thrust_n", thrust_n, airframe.rotor_count())?;
    require_all_finite("thrust_n", thrust_n)?;
    require_all_finite("body_rate_rad_s", &body_rate_rad_s)?;
    require_all_finite("up", &up)?;
    let up = V3::from(up);
    if (up.norm() - 1.0).abs() > 1e-9 {
        return Err(RfError::invalid(
            "up",
            format!("must be a unit vector, got length {}", up.norm()),
        ));
    }
    let model = Model::new(airframe, settings)?;
    Ok(model.residual(&V3::from(body_rate_rad_s), &up, thrust_n))
}

fn bound_scale(model: &Model) -> f64 {
    model
        .lower
        .iter()
        .chain(&model.upper)
        .fold(model.weight_n(), |a, b| a.max(b.abs()))
}

/// Holdable first, then more margin, then a slower spin (then spinning the positive way).
fn better(model: &Model, a: &RelaxedHoverSolution, b: &RelaxedHoverSolution) -> bool {
    if a.linear.stabilizable != b.linear.stabilizable {
        return a.linear.stabilizable;
    }
    let margin = a.thrust_margin_n - b.thrust_margin_n;
    if margin.abs() > 1e-9 * bound_scale(model) {
        return margin > 0.0;
    }
    let (sa, sb) = (a.spin_rate_rad_s, b.spin_rate_rad_s);
    if (sa.abs() - sb.abs()).abs() > 1e-9 * (1.0 + sa.abs()) {
        return sa.abs() < sb.abs();
    }
    if sa != sb {
        return sa > sb;
    }
    a.spin_axis.partial_cmp(&b.spin_axis) == Some(std::cmp::Ordering::Less)
}

fn same_strategy(a: &RelaxedHoverSolution, b: &RelaxedHoverSolution) -> bool {
    a.kind == b.kind
        && a.carrying == b.carrying
        && a.spin_rate_rad_s.signum() == b.spin_rate_rad_s.signum()
}

/// Checks a candidate and measures it.
fn finish(
    model: &Model,
    settings: &RelaxedHoverSettings,
    candidate: &Candidate,
) -> Result<RelaxedHoverSolution> {
    let up = candidate.up.normalize();
    let s = candidate.spin_rate_rad_s;
    let omega = up * s;
    let f = &candidate.thrust_n;
    let residual = model.residual(&omega, &up, f);
    let where_ = || {
        format!(
            "spin {s:.6} rad/s about [{:.6}, {:.6}, {:.6}], thrusts {:?} N",
            up.x, up.y, up.z, f
        )
    };
    if residual.is_nan() || residual > RESIDUAL_TOLERANCE {
        return Err(RfError::invalid(
            "relaxed_hover",
            format!(
                "residual check failed: scaled residual {residual:.3e} > {RESIDUAL_TOLERANCE:e} at {}",
                where_()
            ),
        ));
    }
    let scale = bound_scale(model);
    let tol = BOUND_TOLERANCE * scale;
    for (i, &x) in f.iter().enumerate() {
        if x < model.lower[i] - tol || x > model.upper[i] + tol {
            return Err(RfError::invalid(
                "relaxed_hover",
                format!(
                    "bounds check failed: rotor {} thrust {x} outside [{}, {}] at {}",
                    i + 1,
                    model.lower[i],
                    model.upper[i],
                    where_()
                ),
            ));
        }
    }
    let carrying: Vec<usize> = model
        .working
        .iter()
        .copied()
        .filter(|&i| f[i].abs() > 1e-12 * scale)
        .collect();
    let idle: Vec<usize> = model
        .working
        .iter()
        .copied()
        .filter(|i| !carrying.contains(i))
        .collect();
    let margin = carrying
        .iter()
        .map(|&i| model.upper[i] - f[i])
        .fold(f64::INFINITY, f64::min);
    let floor = carrying
        .iter()
        .map(|&i| f[i] - model.lower[i])
        .fold(f64::INFINITY, f64::min);
    let force = model.force(f);
    let total = force.norm();
    let direction = if total > 0.0 { force / total } else { up };
    let tilt = direction.dot(&up).clamp(-1.0, 1.0).acos();
    let perpendicular = (force - up * up.dot(&force)).norm();
    let circle = if s == 0.0 || perpendicular <= 1e-12 * total {
        0.0
    } else {
        perpendicular / (model.mass_kg * s * s)
    };
    let (a, b, e1, e2) = linear::linear_model(model, &up, s, f, &carrying);
    let stabilizable = linear::stabilizable(&a, &b);
    Ok(RelaxedHoverSolution {
        at_spin_rate_limit: s.abs() >= settings.max_spin_rate_rad_s * (1.0 - 1e-6),
        at_circle_radius_limit: circle >= settings.max_circle_radius_m * (1.0 - 1e-6),
        linear: LinearModel {
            a,
            b,
            e1: e1.into(),
            e2: e2.into(),
            inputs: carrying.clone(),
            stabilizable,
        },
        kind: if s == 0.0 {
            HoverKind::Static
        } else {
            HoverKind::Spinning
        },
        body_rate_rad_s: omega.into(),
        spin_rate_rad_s: s,
        spin_axis: up.into(),
        thrust_direction: direction.into(),
        thrust_n: f.clone(),
        command_n: f
            .iter()
            .zip(&model.efficiency)
            .map(|(x, e)| if *e > 0.0 { x / e } else { 0.0 })
            .collect(),
        thrust_margin_n: margin,
        thrust_floor_n: floor,
        carrying,
        idle,
        total_thrust_n: total,
        tilt_rad: tilt,
        circle_radius_m: circle,
        residual,
    })
}

/// Two solutions are one when their axes, spin rates and thrusts agree; a spinning solution
/// with a static one's axis and thrusts is that static hover turning about its thrust axis.
fn same(model: &Model, a: &RelaxedHoverSolution, b: &RelaxedHoverSolution) -> bool {
    let scale = bound_scale(model);
    let thrusts = a
        .thrust_n
        .iter()
        .zip(&b.thrust_n)
        .all(|(x, y)| (x - y).abs() <= 1e-6 * scale);
    let axes = V3::from(a.spin_axis).dot(&V3::from(b.spin_axis)) >= 1.0 - 1e-12;
    if a.kind != b.kind {
        return thrusts && axes;
    }
    let spin =
        (a.spin_rate_rad_s - b.spin_rate_rad_s).abs() <= 1e-6 * (1.0 + a.spin_rate_rad_s.abs());
    thrusts && axes && spin
}

#[cfg(test)]
mod tests;
