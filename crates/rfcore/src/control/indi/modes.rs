//! How the INDI controller flies each set of failed rotors, decided once at construction (module
//! docs of [`crate::control::indi`], "When rotors fail").

use nalgebra::{DMatrix, Vector2, Vector3};

use super::gains::{IndiGains, YawMode};
use crate::airframe::Airframe;
use crate::allocation::active_set::ActiveSetSolver;
use crate::allocation::clarabel::{max_along_direction, ClarabelSettings};
use crate::allocation::AllocationProblem;
use crate::error::{Result, RfError};

/// Rank test for the remaining roll/pitch authority: `det / trace^2` of its Gram matrix below this
/// means one torque axis is left.
const SINGLE_AXIS_RTOL: f64 = 1e-9;

/// How the controller flies one failure set (module docs, "When rotors fail").
#[derive(Debug, Clone, PartialEq)]
pub struct FailureMode {
    /// Failed rotors (0-based, sorted).
    pub failed: Vec<usize>,
    /// Rotors allocated over (0-based).
    pub healthy: Vec<usize>,
    pub yaw_controlled: bool,
    /// One roll/pitch torque axis left: the output is redefined (`c` below).
    pub single_axis: bool,
    /// The controlled output direction `c` in the (Y_x, Y_y) plane (single axis only).
    pub output_direction: Option<[f64; 2]>,
    /// Primary axis `n` in the body frame.
    pub primary_axis: [f64; 3],
    /// Single axis only: `(a, damping ratio)` of the zero dynamics `eta'' = a r^2 eta - ...`
    /// (stable iff `a < 0`); the damping ratio is `None` when `a >= 0`.
    pub zero_dynamics: Option<(f64, Option<f64>)>,
    /// Rotor thrusts that hold the weight with zero roll and pitch torque (the hover the
    /// controller starts from when it has no rotor feedback), N, one per rotor.
    pub hover_thrust_n: Vec<f64>,
}

/// Per-failure-set data the law needs every step.
#[derive(Debug, Clone)]
pub(super) struct Mode {
    pub(super) info: FailureMode,
    /// `(J^-1 M_tau)` column of each healthy rotor (rad/s^2 per N).
    pub(super) angular: Vec<Vector3<f64>>,
    /// Thrust-row entry of each healthy rotor (N per N).
    pub(super) thrust: Vec<f64>,
    pub(super) weights: [f64; 4],
    /// The weights once the rotors saturate: yaw at its given-up weight when [`YawMode::Auto`]
    /// holds it (thrust and reduced attitude first, module docs step 5); `weights` otherwise.
    pub(super) saturated_weights: [f64; 4],
    /// Rows of the attitude outputs after the redefinition (identity, or `c` and `c_perp`).
    pub(super) rotation: [[f64; 2]; 2],
    /// Single axis: the rows with the other sign of `delta`, flown when the measured inertia
    /// coupling says `1 + a` has the other sign than the nominal inertia's (module docs, "One
    /// torque axis left"); `rotation` otherwise.
    pub(super) rotation_flipped: [[f64; 2]; 2],
    /// Single axis: `1 + a` of the nominal inertia, `a = (J_xy - J_z) / J_xy`; 0 otherwise.
    pub(super) one_plus_a: f64,
    pub(super) primary_axis: Vector3<f64>,
    /// Bounds of the healthy rotors, N.
    pub(super) lower: Vec<f64>,
    pub(super) upper: Vec<f64>,
}

pub(super) fn invalid_failures(rule: String) -> RfError {
    RfError::invalid("failures", rule)
}

fn rotor_list(rotors: &[usize]) -> String {
    let names: Vec<String> = rotors.iter().map(|r| (r + 1).to_string()).collect();
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// The nominal 4 x m effectiveness matrix restricted to `columns`.
fn columns_of(matrix: &DMatrix<f64>, columns: &[usize], rows: usize) -> DMatrix<f64> {
    DMatrix::from_fn(rows, columns.len(), |r, c| matrix[(r, columns[c])])
}

/// The thrust limits (N) of the rotors `columns`, in that order: lower, upper.
fn thrust_bounds(airframe: &Airframe, columns: &[usize]) -> (Vec<f64>, Vec<f64>) {
    let limits = |bound: &[f64]| columns.iter().map(|&i| bound[i]).collect();
    (
        limits(&airframe.min_thrust_n()),
        limits(&airframe.max_thrust_n()),
    )
}

/// The largest yaw torque the `four`-row `columns` reach from `base` (thrust, roll, pitch, yaw)
/// within their bounds in either direction, `[positive, negative]` (N m, an attainable-set LP
/// each; a negative reach means that direction is not reached at all); `None` when `base`
/// itself is out of reach.
fn yaw_reach(
    four: &DMatrix<f64>,
    lower: &[f64],
    upper: &[f64],
    base: &[f64; 4],
) -> Result<Option<[f64; 2]>> {
    let mut reach = [0.0; 2];
    for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
        let limit = max_along_direction(
            four,
            lower,
            upper,
            &[0.0, 0.0, 0.0, sign],
            base,
            &ClarabelSettings::default(),
        )?;
        match limit {
            Some(l) => reach[k] = l.scale,
            None => return Ok(None),
        }
    }
    Ok(Some(reach))
}

/// The smaller of the largest positive and negative yaw torques the `columns` make while
/// holding the weight with zero roll and pitch torque (0 when one side is out of reach).
pub(super) fn yaw_authority(
    airframe: &Airframe,
    matrix: &DMatrix<f64>,
    columns: &[usize],
) -> Result<f64> {
    let (lower, upper) = thrust_bounds(airframe, columns);
    let reach = yaw_reach(
        &columns_of(matrix, columns, 4),
        &lower,
        &upper,
        &airframe.hover_wrench(),
    )?;
    Ok(reach.map_or(0.0, |[up, down]| up.max(0.0).min(down.max(0.0))))
}

/// Directions tried for the given-up-yaw axis tilt ([`relieving_tilt_direction`]): every 15 deg.
const TILT_DIRECTIONS: usize = 24;

/// The least |yaw torque| (N m) the `columns` make while holding the weight with roll and pitch
/// torque `torque_xy` (N m): 0 when a yaw-free hover is within reach, infinity when no hover is.
fn least_yaw_torque(
    four: &DMatrix<f64>,
    lower: &[f64],
    upper: &[f64],
    weight: f64,
    torque_xy: [f64; 2],
) -> Result<f64> {
    let base = [weight, torque_xy[0], torque_xy[1], 0.0];
    let Some(reach) = yaw_reach(four, lower, upper, &base)? else {
        return Ok(f64::INFINITY);
    };
    // The attainable yaw torques are [-reach[1], reach[0]].
    let (low, high) = (-reach[1], reach[0]);
    Ok(if low <= 0.0 && high >= 0.0 {
        0.0
    } else {
        low.abs().min(high.abs())
    })
}

/// Given up yaw with spare rotors: the body x-y direction `d` toward which tilting the primary
/// axis most relieves the yaw torque the hover cannot avoid (module docs, "When rotors fail"),
/// `None` when that torque is below `negligible_n_m` (the hover then barely spins, and a tilted
/// axis would only tilt its thrust: hexa-pnpnpn, whose least yaw torque is 0 on the boundary) or
/// no direction relieves it. Spinning at `r`
/// about `n = (alpha d, n_z)`, `n_z = sqrt(1 - alpha^2)`, the body is steady when the rotors make
/// the gyroscopic torque `omega x J omega = r^2 alpha n_z (d_y (J_z - J_y), d_x (J_x - J_z))` in roll and
/// pitch: torque the rotors then need not balance to zero, freeing them to even out the yaw. The
/// direction is the one whose torque, scaled to the unavoidable yaw torque itself, leaves the least
/// yaw torque (an LP per direction, [`TILT_DIRECTIONS`] of them); the spin then settles where the
/// relief (growing as `r^2`) meets the drag.
fn relieving_tilt_direction(
    airframe: &Airframe,
    four: &DMatrix<f64>,
    lower: &[f64],
    upper: &[f64],
    negligible_n_m: f64,
) -> Result<Option<Vector2<f64>>> {
    let weight = airframe.hover_wrench()[0];
    let unavoidable = least_yaw_torque(four, lower, upper, weight, [0.0, 0.0])?;
    if !(unavoidable > negligible_n_m && unavoidable > 0.0 && unavoidable.is_finite()) {
        return Ok(None);
    }
    let [jx, jy, jz] = airframe.inertia_kg_m2();
    let gyroscopic = |d: Vector2<f64>| Vector2::new(d.y * (jz - jy), d.x * (jx - jz));
    let largest = (jz - jy).abs().max((jz - jx).abs());
    if largest == 0.0 {
        return Ok(None);
    }
    let mut best: Option<(f64, Vector2<f64>)> = None;
    for k in 0..TILT_DIRECTIONS {
        let angle = std::f64::consts::TAU * k as f64 / TILT_DIRECTIONS as f64;
        let d = Vector2::new(angle.cos(), angle.sin());
        let torque = gyroscopic(d) * (unavoidable / largest);
        let left = least_yaw_torque(four, lower, upper, weight, [torque.x, torque.y])?;
        if best.is_none_or(|(b, _)| left < b) {
            best = Some((left, d));
        }
    }
    Ok(best.and_then(|(left, d)| (left < unavoidable).then_some(d)))
}

impl Mode {
    pub(super) fn new(
        airframe: &Airframe,
        gains: &IndiGains,
        failed: Vec<usize>,
        healthy_authority: f64,
    ) -> Result<Self> {
        let m = airframe.rotor_count();
        let healthy: Vec<usize> = (0..m).filter(|i| !failed.contains(i)).collect();
        let names = rotor_list(&failed);
        if healthy.is_empty() {
            return Err(invalid_failures("every rotor is listed as failed".into()));
        }
        let matrix = airframe.nominal_effectiveness_matrix();
        let [jx, jy, jz] = airframe.inertia_kg_m2();
        let weight = airframe.hover_wrench()[0];
        let (lower, upper) = thrust_bounds(airframe, &healthy);

        // Hover at all, spinning: the largest thrust with zero roll and pitch torque.
        let three = columns_of(&matrix, &healthy, 3);
        let limit = max_along_direction(
            &three,
            &lower,
            &upper,
            &[1.0, 0.0, 0.0],
            &[0.0; 3],
            &ClarabelSettings::default(),
        )?;
        let max_thrust = limit.as_ref().map_or(f64::NEG_INFINITY, |l| l.scale);
        if max_thrust < weight {
            return Err(invalid_failures(format!(
                "with rotor(s) {names} failed the remaining rotors cannot hold the weight with \
                 zero roll and pitch torque, the hover this controller flies (spinning about the \
                 thrust axis; a relaxed hover about a tilted axis is not attempted): the largest \
                 such thrust is {max_thrust} N < {weight} N"
            )));
        }
        // The hover thrusts (closest to zero among those with zero roll/pitch torque).
        let problem = AllocationProblem::new(three, &[1.0; 3], &lower, &upper)?;
        let hover_alloc = ActiveSetSolver::new(&problem).allocate(&[weight, 0.0, 0.0])?;
        let mut hover_thrust_n = vec![0.0; m];
        for (k, &i) in healthy.iter().enumerate() {
            hover_thrust_n[i] = hover_alloc.commands[k];
        }

        let angular: Vec<Vector3<f64>> = healthy
            .iter()
            .map(|&i| {
                Vector3::new(
                    matrix[(1, i)] / jx,
                    matrix[(2, i)] / jy,
                    matrix[(3, i)] / jz,
                )
            })
            .collect();
        let thrust: Vec<f64> = healthy.iter().map(|&i| matrix[(0, i)]).collect();

        // Roll/pitch authority: two axes or one (Gram matrix of the x-y angular columns).
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for a in &angular {
            sxx += a.x * a.x;
            sxy += a.x * a.y;
            syy += a.y * a.y;
        }
        let trace = sxx + syy;
        if trace == 0.0 {
            return Err(invalid_failures(format!(
                "with rotor(s) {names} failed no roll or pitch torque is left"
            )));
        }
        let single_axis = sxx * syy - sxy * sxy <= SINGLE_AXIS_RTOL * trace * trace;

        let yaw_controlled = match gains.yaw {
            YawMode::Hold => true,
            YawMode::GiveUp => false,
            YawMode::Auto => {
                healthy_authority > 0.0
                    && !single_axis
                    && yaw_authority(airframe, &matrix, &healthy)?
                        >= gains.min_yaw_authority * healthy_authority
            }
        };

        let j_xy = 0.5 * (jx + jy);
        let a = (j_xy - jz) / j_xy;
        let (rotation, rotation_flipped, output_direction, zero_dynamics) = if single_axis {
            // Spin sign: the yaw torque the hover thrusts make.
            let yaw_torque: f64 = healthy
                .iter()
                .map(|&i| matrix[(3, i)] * hover_thrust_n[i])
                .sum();
            if yaw_torque.abs() <= 1e-9 * weight * matrix.amax() {
                return Err(invalid_failures(format!(
                    "with rotor(s) {names} failed one roll/pitch torque axis is left and the \
                     hover makes no yaw torque: no spin to stabilise the other axis"
                )));
            }
            let strongest = angular
                .iter()
                .max_by(|p, q| p.xy().norm().total_cmp(&q.xy().norm()))
                .expect("healthy is not empty");
            let beta = strongest.y.atan2(strongest.x);
            let sign = yaw_torque.signum() * (1.0 + a).signum();
            let chi = beta + sign * gains.output_angle_rad;
            let c = [chi.cos(), chi.sin()];
            let other = beta - sign * gains.output_angle_rad;
            let f = [other.cos(), other.sin()];
            let zeta = (a < 0.0)
                .then(|| (1.0 + a).abs() / gains.output_angle_rad.tan() / (2.0 * (-a).sqrt()));
            (
                [c, [-c[1], c[0]]],
                [f, [-f[1], f[0]]],
                Some(c),
                Some((a, zeta)),
            )
        } else {
            let identity = [[1.0, 0.0], [0.0, 1.0]];
            (identity, identity, None, None)
        };

        // Only rotors beyond those the thrust and attitude rows use have authority to spare.
        let used = if single_axis { 2 } else { 3 };
        let spare = healthy.len() > used;
        let mut primary_axis = Vector3::z();
        if !yaw_controlled && !single_axis && spare && gains.given_up_yaw_axis_tilt > 0.0 {
            let four = columns_of(&matrix, &healthy, 4);
            // A yaw torque below the share of the healthy one that counts as no yaw authority
            // (`min_yaw_authority`) is negligible here too.
            let negligible = gains.min_yaw_authority * healthy_authority;
            if let Some(d) = relieving_tilt_direction(airframe, &four, &lower, &upper, negligible)? {
                let xy = d * gains.given_up_yaw_axis_tilt;
                primary_axis = Vector3::new(xy.x, xy.y, (1.0 - xy.norm_squared()).sqrt());
            }
        } else if m == 4 && failed.len() == 1 && !single_axis && gains.primary_axis_tilt > 0.0 {
            let [x, y, _] = airframe.rotors()[failed[0]].placement.position_m();
            let toward = Vector2::new(x, y);
            if toward.norm() > 0.0 {
                let xy = toward.normalize() * gains.primary_axis_tilt * (jz - j_xy).signum();
                primary_axis = Vector3::new(xy.x, xy.y, (1.0 - xy.norm_squared()).sqrt());
            }
        }

        let mut weights = gains.weights;
        if single_axis {
            weights[2] = 0.0;
        }
        let given_up_weight = if spare {
            gains.given_up_yaw_weight
        } else {
            0.0
        };
        if !yaw_controlled {
            weights[3] = given_up_weight;
        }
        let mut saturated_weights = weights;
        if gains.yaw == YawMode::Auto {
            saturated_weights[3] = saturated_weights[3].min(given_up_weight);
        }
        Ok(Mode {
            info: FailureMode {
                failed,
                healthy,
                yaw_controlled,
                single_axis,
                output_direction,
                primary_axis: [primary_axis.x, primary_axis.y, primary_axis.z],
                zero_dynamics,
                hover_thrust_n,
            },
            angular,
            thrust,
            weights,
            saturated_weights,
            rotation,
            rotation_flipped,
            one_plus_a: if single_axis { 1.0 + a } else { 0.0 },
            primary_axis,
            lower,
            upper,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix4, Vector4};

    fn mode(preset: &str, failed: &[usize]) -> Result<Mode> {
        mode_with(preset, failed, &IndiGains::default())
    }

    fn mode_with(preset: &str, failed: &[usize], gains: &IndiGains) -> Result<Mode> {
        let airframe = crate::fixtures::preset(preset);
        let all: Vec<usize> = (0..airframe.rotor_count()).collect();
        let matrix = airframe.nominal_effectiveness_matrix();
        let authority = yaw_authority(&airframe, &matrix, &all)?;
        Mode::new(&airframe, gains, failed.to_vec(), authority)
    }

    #[test]
    fn yaw_is_given_up_exactly_where_the_remaining_rotors_lack_its_authority() {
        for (preset, failed, yaw, single) in [
            ("ke-quadcopter", &[][..], true, false),
            ("ke-quadcopter", &[0][..], false, false),
            ("ke-quadcopter", &[0, 2][..], false, true),
            ("lanzon-quadrotor", &[1, 3][..], false, true),
            ("hexa-pnpnpn", &[0][..], false, false),
            ("hexa-ppnnpn", &[0][..], true, false),
            ("hexa-ppnnpn", &[4][..], false, false),
            ("octo-x", &[0][..], true, false),
            ("octo-x", &[0, 4][..], true, false),
        ] {
            let m = mode(preset, failed).unwrap().info;
            assert_eq!(
                (m.yaw_controlled, m.single_axis),
                (yaw, single),
                "{preset} {failed:?}"
            );
            // The hover thrusts hold the weight with zero roll and pitch torque.
            let airframe = crate::fixtures::preset(preset);
            let e = airframe.nominal_effectiveness_matrix();
            for (row, want) in [(0, airframe.hover_wrench()[0]), (1, 0.0), (2, 0.0)] {
                let got: f64 = (0..e.ncols())
                    .map(|i| e[(row, i)] * m.hover_thrust_n[i])
                    .sum();
                assert!(
                    (got - want).abs() < 1e-7,
                    "{preset} {failed:?} row {row}: {got}"
                );
            }
            assert!(failed.iter().all(|&i| m.hover_thrust_n[i] == 0.0));
        }
        // Sun's row elimination on a quadrotor (no spare rotor); the small weight with spare rotors.
        assert_eq!(mode("ke-quadcopter", &[0]).unwrap().weights[3], 0.0);
        assert_eq!(mode("hexa-pnpnpn", &[0]).unwrap().weights[3], 1e-4);
        assert_eq!(mode("ke-quadcopter", &[0, 2]).unwrap().weights[2], 0.0);
    }

    #[test]
    fn failure_sets_the_remaining_rotors_cannot_hover_with_are_refused() {
        for (preset, failed) in [
            ("ke-quadcopter", &[0, 1][..]),
            ("ke-quadcopter", &[0, 1, 2][..]),
            ("hexa-pnpnpn", &[0, 1, 2][..]),
        ] {
            let err = mode(preset, failed).unwrap_err().to_string();
            assert!(
                err.starts_with("failures:")
                    && err.contains("cannot hold the weight with zero roll and pitch torque"),
                "{err}"
            );
        }
        let err = mode("ke-quadcopter", &[0, 1, 2, 3])
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("failures: every rotor"), "{err}");
    }

    /// The reduced attitude linearised about a steady spin `r` with body z on the thrust direction:
    /// `x = (Y_x, Y_y, p, q)`, `Y' = (r Y_y - q, -r Y_x + p)`, Euler's equations, one input along
    /// `e` (angular acceleration per unit), output `y = c . Y`. The transfer function's zeros (the
    /// zero dynamics of the output) from `N(s) = det(sI - A + b c^T) - det(sI - A)`, fitted as a
    /// cubic through four points.
    fn zeros(inertia: [f64; 3], r: f64, e: [f64; 2], c: [f64; 2]) -> (f64, Vector4<f64>) {
        let [jx, jy, jz] = inertia;
        let a = Matrix4::new(
            0.0,
            r,
            0.0,
            -1.0,
            -r,
            0.0,
            1.0,
            0.0,
            0.0,
            0.0,
            0.0,
            (jy - jz) / jx * r,
            0.0,
            0.0,
            (jz - jx) / jy * r,
            0.0,
        );
        let b = Vector4::new(0.0, 0.0, e[0], e[1]);
        let cv = Vector4::new(c[0], c[1], 0.0, 0.0);
        let n = |s: f64| {
            let m = Matrix4::identity() * s - a;
            (m + b * cv.transpose()).determinant() - m.determinant()
        };
        let points = [-2.0 * r.abs(), -r.abs(), r.abs(), 2.0 * r.abs()];
        let v = Matrix4::from_fn(|i, j| points[i].powi(3 - j as i32));
        let coefficients = v
            .lu()
            .solve(&Vector4::from_fn(|i, _| n(points[i])))
            .unwrap();
        // Relative degree 2: the cubic coefficient vanishes; the quadratic's discriminant and roots.
        (coefficients[0], coefficients)
    }

    #[test]
    fn the_output_redefinition_makes_the_zero_dynamics_stable_with_the_damping_it_reports() {
        let airframe = crate::fixtures::preset("ke-quadcopter");
        let m = mode("ke-quadcopter", &[0, 2]).unwrap();
        let c = m.info.output_direction.unwrap();
        let strongest = m
            .angular
            .iter()
            .max_by(|p, q| p.xy().norm().total_cmp(&q.xy().norm()))
            .unwrap();
        let e = [strongest.x, strongest.y];
        // The spin the hover's yaw torque drives (its sign), at a few rates.
        let matrix = airframe.nominal_effectiveness_matrix();
        let yaw: f64 = (0..4)
            .map(|i| matrix[(3, i)] * m.info.hover_thrust_n[i])
            .sum();
        let (a, zeta) = m.info.zero_dynamics.unwrap();
        let zeta = zeta.expect("J_z > J_xy: stable");
        assert!(a < 0.0);
        for rate in [5.0, 20.0, 40.0] {
            let r = rate * yaw.signum();
            let (cubic, k) = zeros(airframe.inertia_kg_m2(), r, e, c);
            assert!(cubic.abs() < 1e-9 * k[1].abs(), "{cubic}");
            // n2 s^2 + n1 s + n0: stable iff all of one sign; damping (n1 / n2) / (2 sqrt(n0 / n2)).
            let (n2, n1, n0) = (k[1], k[2], k[3]);
            assert!(n2 * n1 > 0.0 && n2 * n0 > 0.0, "{rate}: {k}");
            let measured = (n1 / n2) / (2.0 * (n0 / n2).sqrt());
            assert!(
                (measured - zeta).abs() < 1e-8,
                "{rate}: {measured} vs {zeta}"
            );
            // The formula of the module docs: eta'' = a r^2 eta - (1 + a) |r| cot(delta) eta'.
            assert!((n0 / n2 + a * r * r).abs() < 1e-8 * r * r, "{rate}");
            // The other sign of delta: the same stiffness, negative damping (unstable).
            let delta = IndiGains::default().output_angle_rad;
            let beta = e[1].atan2(e[0]);
            let chi = (c[1].atan2(c[0]) - beta).signum() * -delta + beta;
            let (_, k) = zeros(airframe.inertia_kg_m2(), r, e, [chi.cos(), chi.sin()]);
            assert!(k[1] * k[2] < 0.0, "{rate}: {k}");
        }
        // J_z < J_xy (Lanzon's printed inertia): a > 0, no stable choice.
        let lanzon = mode("lanzon-quadrotor", &[1, 3]).unwrap();
        let (a, zeta) = lanzon.info.zero_dynamics.unwrap();
        assert!(a > 0.0 && zeta.is_none(), "{a}");
    }

    #[test]
    fn given_up_yaw_tilts_the_axis_where_its_gyroscopic_torque_relieves_the_unavoidable_yaw() {
        let gains = IndiGains {
            given_up_yaw_axis_tilt: 0.05,
            ..IndiGains::default()
        };
        for failed in [4, 5] {
            let airframe = crate::fixtures::preset("hexa-ppnnpn");
            let m = mode_with("hexa-ppnnpn", &[failed], &gains).unwrap();
            assert!(!m.info.yaw_controlled);
            let n = m.primary_axis;
            assert!((n.xy().norm() - 0.05).abs() < 1e-12 && (n.norm() - 1.0).abs() < 1e-12);
            // The independent check: the least yaw torque of a hover whose rotors make the
            // gyroscopic torque of a spin about n, with the weight held, at a few rates, against
            // the same at n = z (no relief) and at n tilted the other way (more yaw).
            let matrix = airframe.nominal_effectiveness_matrix();
            let four = columns_of(&matrix, &m.info.healthy, 4);
            let (lower, upper) = thrust_bounds(&airframe, &m.info.healthy);
            let weight = airframe.hover_wrench()[0];
            let [jx, jy, jz] = airframe.inertia_kg_m2();
            let least = |axis: Vector3<f64>, r: f64| {
                let w = axis * r;
                let jw = Vector3::new(jx * w.x, jy * w.y, jz * w.z);
                let g = w.cross(&jw);
                least_yaw_torque(&four, &lower, &upper, weight / axis.z, [g.x, g.y]).unwrap()
            };
            let level = least(Vector3::z(), 0.0);
            assert!(level > 0.1, "rotor {}: {level}", failed + 1);
            let back = Vector3::new(-n.x, -n.y, n.z);
            for r in [10.0, 20.0] {
                let relieved = least(n, r);
                assert!(relieved < 0.8 * level, "rotor {} r {r}: {relieved} vs {level}", failed + 1);
                assert!(least(back, r) > level, "rotor {} r {r}", failed + 1);
            }
        }
        // Yaw held (rotor 1 of PPNNPN), a yaw-free hover on the boundary (any rotor of PNPNPN:
        // least yaw torque 0), no spare rotor (a quadrotor), or the gain 0: body z.
        for failed in 0..6 {
            assert_eq!(
                mode_with("hexa-pnpnpn", &[failed], &gains).unwrap().info.primary_axis,
                [0.0, 0.0, 1.0]
            );
        }
        assert_eq!(
            mode_with("hexa-ppnnpn", &[0], &gains).unwrap().info.primary_axis,
            [0.0, 0.0, 1.0]
        );
        assert_eq!(
            mode_with("ke-quadcopter", &[0], &gains).unwrap().info.primary_axis,
            [0.0, 0.0, 1.0]
        );
        assert_eq!(
            mode("hexa-ppnnpn", &[5]).unwrap().info.primary_axis,
            [0.0, 0.0, 1.0]
        );
    }

    #[test]
    fn one_failed_rotor_of_a_quadrotor_tilts_the_primary_axis_toward_it_when_j_z_exceeds_j_xy() {
        let gains = IndiGains {
            primary_axis_tilt: 0.1,
            ..IndiGains::default()
        };
        let m = mode_with("ke-quadcopter", &[0], &gains).unwrap().info;
        let [x, y, z] = m.primary_axis;
        // Rotor 1 of ke-quadcopter sits at 45 degrees (front right).
        let s = 0.1 / 2f64.sqrt();
        assert!(
            (x - s).abs() < 1e-15 && (y - s).abs() < 1e-15 && (z - 0.99f64.sqrt()).abs() < 1e-15
        );
        // Lanzon's printed J_z < J_xy: away from rotor 2 (at 90 degrees, right).
        let m = mode_with("lanzon-quadrotor", &[1], &gains).unwrap().info;
        assert!(m.primary_axis[0].abs() < 1e-15 && (m.primary_axis[1] + 0.1).abs() < 1e-15);
        assert_eq!(
            mode("ke-quadcopter", &[0]).unwrap().info.primary_axis,
            [0.0, 0.0, 1.0]
        );
    }
}
