//! Test and benchmark support: the presets that ship in the Python package, read from the source
//! tree (the one place the core's tests and benches find them). Not part of the API.

use std::path::PathBuf;

use std::hint::black_box;
use std::time::Instant;

use crate::airframe::Airframe;
use crate::allocation::active_set::{ActiveSet, ActiveSetSolver};
use crate::allocation::scaling::{BIG_WORK, N, ROWS, SMALL_WORK};
use crate::allocation::{allocate_clarabel, allocate_prioritized};
use crate::allocation::{check_rows, weighted_pseudo_inverse, AllocationProblem, Method};
use crate::cancel::Cancel;
use crate::error::{Result, RfError};

/// `python/rotorfault/presets` of this source tree.
pub fn presets_dir() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../python/rotorfault/presets"
    ))
}

/// The text of `presets/{relative}` (e.g. `"quad-x.toml"`, `"ftc/ke-hil.toml"`).
pub fn preset_text(relative: &str) -> String {
    let path = presets_dir().join(relative);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The preset airframe `name` (e.g. `"hexa-pnpnpn"`).
pub fn preset(name: &str) -> Airframe {
    Airframe::from_toml_str(&preset_text(&format!("{name}.toml")), name)
        .unwrap_or_else(|e| panic!("preset {name}: {e}"))
}

/// SplitMix64: the seeded, platform-independent stream the tests and benches draw their random
/// problems from (one generator, so a seed means the same problems everywhere).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// Uniform in `0..n`.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u = self.uniform(1e-12, 1.0);
        let v = self.uniform(0.0, 1.0);
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// Bench support (benches/allocation.rs, benches/allocation_clarabel.py): the mean wall time of one solve, per virtual control (rows of `controls`),
/// each solved `repeats` times in a row on one thread (cold-started). Seconds.
pub fn time_each(
    problem: &AllocationProblem,
    method: &Method,
    controls: &[f64],
    repeats: usize,
    cancel: &Cancel,
) -> Result<Vec<f64>> {
    if repeats == 0 {
        return Err(RfError::invalid("repeats", "must be >= 1, got 0"));
    }
    check_rows(problem, controls)?;
    let n = problem.virtual_dimension();
    let solver = match method {
        Method::ActiveSet(settings) => ActiveSetSolver::with_settings(problem, *settings)?,
        _ => ActiveSetSolver::new(problem),
    };
    let pinv = weighted_pseudo_inverse(problem);
    let mut commands = vec![0.0; problem.actuator_count()];
    let mut times = Vec::with_capacity(controls.len() / n);
    for u_c in controls.chunks(n) {
        let start = Instant::now();
        for _ in 0..repeats {
            // A load per solve (~1 ns next to 0.2-300 us): `repeats` may be huge.
            cancel.check()?;
            match method {
                Method::ActiveSet(_) => {
                    let mut active = ActiveSet::cold(problem.actuator_count());
                    black_box(solver.solve_unchecked(black_box(u_c), &mut active, &mut commands));
                }
                Method::Pinv => pinv.apply(black_box(u_c), &mut commands),
                Method::Clarabel(settings) => {
                    black_box(allocate_clarabel(problem, black_box(u_c), settings)?);
                }
                Method::Prioritized(groups, settings) => {
                    black_box(allocate_prioritized(
                        problem,
                        black_box(u_c),
                        groups,
                        settings,
                    )?);
                }
            }
        }
        times.push(start.elapsed().as_secs_f64() / repeats as f64);
    }
    Ok(times)
}

/// Bench support (benches/allocation.rs): the active set's cold start, phase 1 and phase 2 exactly
/// as [`ActiveSetSolver::solve_unchecked`] runs them, without the certificate: the baseline
/// the certified solve is timed against. Its answers carry no evidence, so this is never an
/// allocation method. `u_c` has n finite entries and `commands` m; returns the iterations
/// (commands NaN when `u_c` overflows once scaled).
pub fn solve_uncertified(
    solver: &ActiveSetSolver,
    u_c: &[f64],
    active: &mut ActiveSet,
    commands: &mut [f64],
) -> usize {
    let scaled = &solver.scaled;
    let m = scaled.m;
    active.len = m;
    let mut b = [0.0; ROWS];
    if !scaled.rhs(u_c, &mut b) {
        commands[..m].fill(f64::NAN);
        return 0;
    }
    let b_norm = scaled.rhs_norm(&b);
    let mut g = [0.0; N];
    // The same instances as the certified solve (`ActiveSetSolver::solve_unchecked`).
    let (t, iterations) = if scaled.rows == 4 && scaled.rows * m <= SMALL_WORK {
        phases::<SMALL_WORK, 4>(solver, &b, b_norm, active, &mut g)
    } else if scaled.rows * m <= SMALL_WORK {
        phases::<SMALL_WORK, 0>(solver, &b, b_norm, active, &mut g)
    } else {
        phases::<BIG_WORK, 0>(solver, &b, b_norm, active, &mut g)
    };
    commands[..m].copy_from_slice(&t[..m]);
    iterations
}

fn phases<const W: usize, const R: usize>(
    solver: &ActiveSetSolver,
    b: &[f64; ROWS],
    b_norm: f64,
    active: &mut ActiveSet,
    g: &mut [f64; N],
) -> ([f64; N], usize) {
    let (converged, mut iterations, closest, mut t) =
        solver.start_and_phase1::<W, R>(b, b_norm, active, g);
    if converged && solver.tie_rule_needed(closest, &active.states, g) {
        iterations += solver.phase2::<W>(&mut t, &mut active.states, g);
    }
    (t, iterations)
}

/// One problem of the ill-conditioned allocation class: 4 axes, 4 to 8 actuators with
/// normal entries, one column scaled by `10^-k`, weights in [0.01, 30], bounds [0, 1..8], and a
/// virtual control made by a point in (or slightly outside) the box, drawn from `rng` (the tests
/// and the bench draw the same sequence from their own seeds).
pub fn ill_conditioned_allocation(rng: &mut Rng, k: i32) -> (AllocationProblem, Vec<f64>) {
    let m = 4 + rng.below(5);
    let mut matrix = nalgebra::DMatrix::from_fn(4, m, |_, _| rng.normal());
    let weak = rng.below(m);
    for r in 0..4 {
        matrix[(r, weak)] *= 10f64.powi(-k);
    }
    let weights: Vec<f64> = (0..4).map(|_| rng.uniform(0.01, 30.0)).collect();
    let upper: Vec<f64> = (0..m).map(|_| rng.uniform(1.0, 8.0)).collect();
    let point: Vec<f64> = upper.iter().map(|&h| rng.uniform(-0.1, 1.1) * h).collect();
    let u_c: Vec<f64> = (0..4)
        .map(|r| (0..m).map(|c| matrix[(r, c)] * point[c]).sum())
        .collect();
    let problem = AllocationProblem::new(matrix, &weights, &vec![0.0; m], &upper)
        .expect("the ill-conditioned class is valid by construction");
    (problem, u_c)
}

/// A hover gain by hand (the closed-loop benches' and the SIMD lanes tests' law): the desired
/// wrench change is a diagonal PD on the state error (altitude; roll / pitch / yaw, with the
/// horizontal position loop closed through the attitude set-point, roll <- east, pitch <- -north,
/// as thrust tilts in NED/FRD), mapped to rotor thrusts by the pseudo-inverse of the 4 x m
/// effectiveness matrix (rows T, L, M, N).
/// Returns K (m x 12) for `u = u_trim - K (x - x_trim)`.
pub fn hover_gain(airframe: &Airframe) -> nalgebra::DMatrix<f64> {
    let m = airframe.mass_kg();
    let g = airframe.gravity_m_s2();
    let [jx, jy, jz] = airframe.inertia_kg_m2();
    // Altitude: omega_n = 4 rad/s, zeta = 0.9; attitude: omega_n = 20 rad/s; position (outer): 2 rad/s.
    let (kp_z, kd_z) = (16.0, 7.2);
    let (kp_att, kd_att) = (400.0, 36.0);
    let (kp_yaw, kd_yaw) = (100.0, 18.0);
    let (kp_xy, kd_xy) = (4.0, 3.6);
    // Wrench change dw = -G e (e = x - x_trim), columns in the order of `state_vector`:
    // [n, e, d, vn, ve, vd, roll, pitch, yaw, p, q, r].
    let mut gw = nalgebra::DMatrix::<f64>::zeros(4, crate::state::STATE_DIM);
    // Thrust (up): more when below the target (d error > 0) or sinking (vd > 0).
    gw[(0, 2)] = -m * kp_z;
    gw[(0, 5)] = -m * kd_z;
    // Roll torque: L = Jx (kp (roll_d - roll) - kd p), roll_d = -(kp_xy e_e + kd_xy e_ve) / g.
    gw[(1, 1)] = jx * kp_att * kp_xy / g;
    gw[(1, 4)] = jx * kp_att * kd_xy / g;
    gw[(1, 6)] = jx * kp_att;
    gw[(1, 9)] = jx * kd_att;
    // Pitch torque: M = Jy (kp (pitch_d - pitch) - kd q), pitch_d = +(kp_xy e_n + kd_xy e_vn) / g.
    gw[(2, 0)] = -jy * kp_att * kp_xy / g;
    gw[(2, 3)] = -jy * kp_att * kd_xy / g;
    gw[(2, 7)] = jy * kp_att;
    gw[(2, 10)] = jy * kd_att;
    // Yaw torque.
    gw[(3, 8)] = jz * kp_yaw;
    gw[(3, 11)] = jz * kd_yaw;
    let pinv = airframe
        .effectiveness_matrix()
        .pseudo_inverse(1e-12)
        .expect("pseudo-inverse of the effectiveness matrix");
    // u = u_trim + pinv dw = u_trim - (pinv G) e.
    pinv * gw
}
