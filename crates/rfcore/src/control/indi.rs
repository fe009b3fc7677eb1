//! Incremental nonlinear dynamic inversion (INDI) fault-tolerant control, after Sun, Wang, Chu and
//! de Visser, "Incremental nonlinear fault-tolerant control of a quadrotor with complete loss of two
//! opposing rotors" (IEEE T-RO 37(1), 2021; MATLAB code `SihaoSun/INDI_Quadrotor_FTC`), written
//! for any planar multirotor and any set of failed rotors.
//!
//! **An active controller.** INDI as in Sun is told which rotors failed (after a fault detector):
//! [`DetectedFailure`] lists each failed rotor and the time the controller learns of it. Until then
//! it flies the healthy vehicle; from then on it allocates over the remaining rotors only and
//! commands the failed ones to zero. Partial losses it is not told about reach it, as any
//! disturbance does, through the measured accelerations.
//!
//! # The control law (one control step, body FRD, world NED)
//! 1. **Position loop** (Sun's `URpositionControl`, plus a moving reference): horizontal
//!    `v_t = sat(k_p,xy (p_r - p) + v_r, v_max)`, `a_xy = k_v,xy (v_t - v) + k_i,xy int (v_t - v)`,
//!    limited to `g tan(max_tilt)`; vertical `nu_z = k_p,z (z_r - z) + k_d,z (w_r - w)`. The thrust
//!    direction wanted is `z_d = (g e3 - a) / |g e3 - a|` (body z, pointing down), `a = (a_xy, nu_z)`,
//!    passed through the low-pass filter (value, rate `z_d'`, acceleration `z_d''`).
//! 2. **Reduced attitude of the primary axis `n`** (body frame, unit; body z unless tilted, see
//!    [`IndiGains::primary_axis_tilt`]): `h = R^T z_d`, output `Y = h_xy - n_xy`, `Y' = (h')_xy`
//!    with `h' = lambda + h x omega`, `lambda = R^T z_d'`. The yaw about `n` is free: the vehicle
//!    may spin about its thrust axis.
//! 3. **Pseudo-controls**: `nu_Y = -k_att,p Y - k_att,d Y'`, `nu_r = -k_r r` (yaw rate held at zero
//!    while yaw is controlled), `nu_z` from step 1.
//! 4. **INDI**: with the filtered gyro rate differentiated, `omega'_f`, the filtered rotor thrusts
//!    `T_f` (the same filter) and the filtered vertical acceleration `z''_f` (from the specific
//!    force, the same filter), the outputs one step ahead are
//!    `z'' = z''_f - (n3z / m) 1^T dT`,
//!    `Y'' = K + (h x (omega'_f + J^-1 M_tau dT))_xy`, `K = (h' x omega + lambda x omega + R^T z_d'')_xy`,
//!    `r' = r'_f + (J^-1 M_tau dT)_z`.
//!    Equating them to the pseudo-controls gives `G dT = b` (rows thrust, two attitude, yaw).
//! 5. **Incremental allocation over the remaining rotors**: `min |W^(1/2) (b - G dT)|` with
//!    `T_min - T_f <= dT <= T_max - T_f`, the failed rotors' columns removed, through the exact
//!    active-set solver of [`crate::allocation`] (warm-started; among equal optima the smallest
//!    increment, Sun's pseudo-inverse); the command is `T = T_f + dT`, the failed rotors 0.
//!
//! # When rotors fail (decided once per failure set, at construction)
//! - **Yaw** ([`YawMode`]): given up (weight `weights[3]` replaced by the small
//!   [`IndiGains::given_up_yaw_weight`]; Sun eliminates the row)
//!   when the remaining rotors, at hover, can make less than [`IndiGains::min_yaw_authority`] of
//!   the healthy vehicle's yaw torque in either direction (an attainable-set LP), e.g. any rotor of
//!   a quadrotor or of the PNPNPN hexacopter. The vehicle then spins about `n`.
//! - **One torque axis left** (two opposing rotors of a quadrotor): only one combination
//!   `y = c . Y` of the two attitude outputs can be controlled. Sun's output redefinition: `c` at
//!   the angle `beta + s delta` with `beta` the direction of the angular acceleration the remaining
//!   rotors make, `delta` = [`IndiGains::output_angle_rad`] and `s` the sign of the spin (the yaw
//!   torque at hover) times the sign of `1 + a`, `a = (J_xy - J_z) / J_xy`. Linearised about the
//!   spin `r`, the other combination (the zero dynamics) obeys
//!   `eta'' = a r^2 eta - (1 + a) |r| cot(delta) eta'` : stable when `J_z > J_xy` (`a < 0`) and the
//!   sign is chosen so; its damping ratio `(1 + a) cot(delta) / (2 sqrt(-a))` does not depend on the
//!   spin rate. With `J_z < J_xy` no choice of `delta` is stable ([`FailureMode::zero_dynamics`]).
//!   Sun's `chi = 105 deg` on his Bebop 2 is `delta = 65.67 deg` here (a test derives it).
//! - **No hover**: a failure set whose remaining rotors cannot hold the weight with zero roll and
//!   pitch torque, even spinning, is refused at construction (naming `failures`).
//!
//! # Samples and their substitutes
//! [`Controller::command_with`] reads the gyro, the specific force and the rotor thrusts actually
//! produced ([`ControllerInput`]). Missing samples are replaced, and the law says how: the gyro by
//! the state's body rates; the vertical acceleration by its model `g - n3z sum(T_f) / m` (the
//! thrust row becomes plain dynamic inversion: a mass error then leaves an altitude offset); the
//! rotor thrusts by the previous commands (no actuator lag model).
//!
//! # Floors (stated once)
//! `n3z` in the thrust row is floored at [`MIN_N3Z`] (the law needs the thrust to point up); Sun's
//! saturation of the reference rate `|lambda_i| <= 0.5` 1/s is kept ([`MAX_REFERENCE_RATE`]).

use nalgebra::{DMatrix, Matrix3, Vector2, Vector3};

use crate::airframe::Airframe;
use crate::allocation::active_set::{ActiveSet, ActiveSetSolver};
use crate::allocation::clarabel::{max_along_direction, ClarabelSettings};
use crate::allocation::{AllocationProblem, MAX_ACTUATORS};
use crate::control::filter::SecondOrderLowPass;
use crate::control::Controller;
use crate::error::{require_finite, Result, RfError};
use crate::state::{ControllerInput, RigidBodyState};

/// Floor on `n3z` in the thrust row of `G` (the tilt at which it binds: 87 degrees).
pub const MIN_N3Z: f64 = 0.05;
/// Largest rate of the filtered thrust direction the law feeds forward, 1/s (Sun's saturation).
pub const MAX_REFERENCE_RATE: f64 = 0.5;
/// Rank test for the remaining roll/pitch authority: `det / trace^2` of its Gram matrix below this
/// means one torque axis is left.
const SINGLE_AXIS_RTOL: f64 = 1e-9;

/// Whether the controller holds the yaw rate (module docs, "When rotors fail").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum YawMode {
    /// Hold it while the remaining rotors have the yaw authority ([`IndiGains::min_yaw_authority`]),
    /// give it up otherwise.
    #[default]
    Auto,
    /// Always hold the yaw rate (with the weight `weights[3]`).
    Hold,
    /// Always let it go (spin about the primary axis).
    GiveUp,
}

impl YawMode {
    pub fn parse(text: &str) -> Result<Self> {
        match text {
            "auto" => Ok(YawMode::Auto),
            "hold" => Ok(YawMode::Hold),
            "give-up" => Ok(YawMode::GiveUp),
            other => Err(RfError::invalid(
                "yaw",
                format!("expected \"auto\", \"hold\" or \"give-up\", got {other:?}"),
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            YawMode::Auto => "auto",
            YawMode::Hold => "hold",
            YawMode::GiveUp => "give-up",
        }
    }
}

/// The controller's parameters. Defaults: Sun's printed values (`controlParams.m`) where he prints
/// them, else stated on the field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IndiGains {
    /// Horizontal position gain, 1/s (Sun: 1.0).
    pub k_p_xy: f64,
    /// Horizontal velocity gain, 1/s (Sun: 2.0).
    pub k_v_xy: f64,
    /// Horizontal velocity-integral gain, 1/s^2 (Sun: 0.0).
    pub k_i_xy: f64,
    /// Altitude gain of `nu_z`, 1/s^2 (Sun: 10).
    pub k_p_z: f64,
    /// Vertical-speed gain of `nu_z`, 1/s (Sun: 6).
    pub k_d_z: f64,
    /// Largest horizontal speed the position loop asks for, m/s (Sun: 10).
    pub max_speed_m_s: f64,
    /// Largest tilt of the thrust direction the position loop asks for, rad (Sun: 10 degrees).
    pub max_tilt_rad: f64,
    /// Limit on each horizontal velocity integral, m (Sun: 5).
    pub integral_limit_m: f64,
    /// Reduced-attitude proportional gain, 1/s^2 (Sun: 200).
    pub k_att_p: f64,
    /// Reduced-attitude derivative gain, 1/s (Sun: 30).
    pub k_att_d: f64,
    /// Yaw-rate gain, 1/s (Sun: 5).
    pub k_r: f64,
    /// Natural frequency of the second-order filter, rad/s: 50 (Sun's code filters with a first-order
    /// 0.02 s, the same 50 rad/s; the second-order filter of Smeur et al. 2016, which Sun builds on).
    pub filter_frequency_rad_s: f64,
    /// Damping ratio of the filter: 0.55 (Smeur et al. 2016).
    pub filter_damping: f64,
    /// `delta` of the output redefinition with one torque axis left, rad (module docs): 65.67
    /// degrees, Sun's `chi = 105 deg` on his vehicle. Must lie in (0, pi/2).
    pub output_angle_rad: f64,
    /// Tilt of the primary axis from body z when one rotor of a quadrotor fails (Sun's
    /// `axis_tilt`, 0 to 0.2; his code: 0): `n_xy` of this length, toward the failed rotor when
    /// `J_z > J_xy` (the gyroscopic torque of the tilted spin then lets the opposite rotor carry
    /// thrust), away from it otherwise.
    pub primary_axis_tilt: f64,
    /// `W = diag(thrust, attitude 1, attitude 2, yaw)` of the incremental allocation (Sun: the
    /// unweighted pseudo-inverse, all 1).
    pub weights: [f64; 4],
    /// Time constant of the thrust-mismatch correction, s (ours; infinity turns it off): the slow
    /// low-pass of (previous command - produced thrust) added to the incremental base, so that a
    /// rotor producing less than commanded (an undetected partial loss, a thrust-coefficient
    /// error) leaves no steady output error (module docs, "The incremental base"). 0.5.
    pub mismatch_time_constant_s: f64,
    /// The yaw weight once yaw is given up, in place of `weights[3]`, when more rotors remain than
    /// the thrust and attitude rows use (a hexa- or octocopter): their spare authority still damps
    /// the spin, after thrust and attitude. Otherwise (a quadrotor) the row is dropped, weight 0, as
    /// Sun does. 1e-4 (ours): it keeps the PPNNPN hexacopter without rotor 5 at 33 rad/s instead
    /// of 70 (where the 50 rad/s filter no longer keeps up), and a larger weight trades altitude
    /// for yaw (1e-2: 0.4 m).
    pub given_up_yaw_weight: f64,
    /// Whether yaw is held (module docs).
    pub yaw: YawMode,
    /// [`YawMode::Auto`] holds yaw when the remaining rotors can make at least this fraction of
    /// the healthy vehicle's yaw torque at hover, in both directions: 0.1 (ours; Sun's quadrotor
    /// cases give yaw up whatever the fraction).
    pub min_yaw_authority: f64,
}

impl Default for IndiGains {
    fn default() -> Self {
        IndiGains {
            k_p_xy: 1.0,
            k_v_xy: 2.0,
            k_i_xy: 0.0,
            k_p_z: 10.0,
            k_d_z: 6.0,
            max_speed_m_s: 10.0,
            max_tilt_rad: 10f64.to_radians(),
            integral_limit_m: 5.0,
            k_att_p: 200.0,
            k_att_d: 30.0,
            k_r: 5.0,
            filter_frequency_rad_s: 75.0,
            filter_damping: 0.55,
            output_angle_rad: sun_output_angle_rad(),
            primary_axis_tilt: 0.0,
            weights: [1.0; 4],
            mismatch_time_constant_s: 0.5,
            given_up_yaw_weight: 1e-4,
            yaw: YawMode::Auto,
            min_yaw_authority: 0.1,
        }
    }
}

/// Sun's `chi = 105 deg` as the angle [`IndiGains::output_angle_rad`]: on his Bebop 2 (`b =
/// 0.115 m`, `l = 0.0875 m`, `I_x = 0.0014`, `I_y = 0.0013 kg m^2`, `controlParams.m`) the
/// remaining pair 1-3 makes angular acceleration along `atan2(l / I_y, b / I_x)` in the body x-y
/// plane, and `chi` is measured from body x: `delta = chi - that`.
pub fn sun_output_angle_rad() -> f64 {
    let (b, l, ix, iy): (f64, f64, f64, f64) = (0.115, 0.0875, 0.0014, 0.0013);
    105f64.to_radians() - (l / iy).atan2(b / ix)
}

impl IndiGains {
    /// Rejects gains the law excludes, naming the gain and the rule.
    pub fn check(&self) -> Result<()> {
        let positive = [
            ("k_p_xy", self.k_p_xy),
            ("k_v_xy", self.k_v_xy),
            ("k_p_z", self.k_p_z),
            ("k_d_z", self.k_d_z),
            ("max_speed_m_s", self.max_speed_m_s),
            ("k_att_p", self.k_att_p),
            ("k_att_d", self.k_att_d),
            ("filter_frequency_rad_s", self.filter_frequency_rad_s),
            ("filter_damping", self.filter_damping),
            ("mismatch_time_constant_s", self.mismatch_time_constant_s),
        ];
        for (field, value) in positive {
            if field == "mismatch_time_constant_s" && value == f64::INFINITY {
                continue; // off
            }
            require_finite(field, value)?;
            if value <= 0.0 {
                return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
            }
        }
        for (field, value) in [
            ("k_i_xy", self.k_i_xy),
            ("k_r", self.k_r),
            ("given_up_yaw_weight", self.given_up_yaw_weight),
            ("integral_limit_m", self.integral_limit_m),
        ] {
            require_finite(field, value)?;
            if value < 0.0 {
                return Err(RfError::invalid(
                    field,
                    format!("must be >= 0, got {value}"),
                ));
            }
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        for (field, value) in [
            ("max_tilt_rad", self.max_tilt_rad),
            ("output_angle_rad", self.output_angle_rad),
        ] {
            require_finite(field, value)?;
            if !(value > 0.0 && value < half_pi) {
                return Err(RfError::invalid(
                    field,
                    format!("must lie in (0, pi/2), got {value}"),
                ));
            }
        }
        require_finite("primary_axis_tilt", self.primary_axis_tilt)?;
        if !(0.0..1.0).contains(&self.primary_axis_tilt) {
            return Err(RfError::invalid(
                "primary_axis_tilt",
                format!(
                    "must lie in [0, 1) (the x-y length of a unit axis), got {}",
                    self.primary_axis_tilt
                ),
            ));
        }
        require_finite("min_yaw_authority", self.min_yaw_authority)?;
        if !(0.0..=1.0).contains(&self.min_yaw_authority) {
            return Err(RfError::invalid(
                "min_yaw_authority",
                format!(
                    "must lie in [0, 1] (a fraction of the healthy yaw torque), got {}",
                    self.min_yaw_authority
                ),
            ));
        }
        for (i, &w) in self.weights.iter().enumerate() {
            require_finite(&format!("weights[{i}]"), w)?;
            if w < 0.0 || (i < 3 && w == 0.0) {
                return Err(RfError::invalid(
                    format!("weights[{i}]"),
                    format!(
                        "thrust and attitude weights must be > 0 and the yaw weight >= 0, got {w}"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A rotor the controller is told has failed, from `time_s` on (the detection time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectedFailure {
    /// Rotor index (0-based).
    pub rotor: usize,
    pub time_s: f64,
}

/// A piece of the reference: from `time_s` until the next setpoint, position
/// `position_m + velocity_m_s (t - time_s)` (NED, m) at velocity `velocity_m_s` (the first setpoint
/// also holds before its time, at its position).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    pub time_s: f64,
    pub position_m: [f64; 3],
    pub velocity_m_s: [f64; 3],
}

impl Setpoint {
    /// Holds `position_m` from `time_s`.
    pub fn hold(time_s: f64, position_m: [f64; 3]) -> Self {
        Setpoint {
            time_s,
            position_m,
            velocity_m_s: [0.0; 3],
        }
    }
}

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
struct Mode {
    info: FailureMode,
    /// `(J^-1 M_tau)` column of each healthy rotor (rad/s^2 per N).
    angular: Vec<Vector3<f64>>,
    /// Thrust-row entry of each healthy rotor (N per N).
    thrust: Vec<f64>,
    weights: [f64; 4],
    /// Rows of the attitude outputs after the redefinition (identity, or `c` and `c_perp`).
    rotation: [[f64; 2]; 2],
    primary_axis: Vector3<f64>,
    /// Bounds of the healthy rotors, N.
    lower: Vec<f64>,
    upper: Vec<f64>,
}

/// Filter states and memories, reset at the start of every run.
#[derive(Debug, Clone, Default)]
struct Memory {
    started: bool,
    gyro: [[f64; 2]; 3],
    thrust: Vec<[f64; 2]>,
    vertical: [f64; 2],
    direction: [[f64; 2]; 3],
    integral_xy: [f64; 2],
    previous: Vec<f64>,
    /// Slow low-pass of (previous command - produced thrust) per rotor, N.
    mismatch: Vec<f64>,
    mode: usize,
}

/// The INDI fault-tolerant controller (module docs). Rotor commands are thrusts, N.
#[derive(Debug, Clone)]
pub struct IndiController {
    gains: IndiGains,
    dt_s: f64,
    mass_kg: f64,
    gravity_m_s2: f64,
    rotor_count: usize,
    filter: SecondOrderLowPass,
    setpoints: Vec<Setpoint>,
    /// Failures sorted by time; `modes[k]` flies the first `k` of them.
    failures: Vec<DetectedFailure>,
    modes: Vec<Mode>,
    active: ActiveSet,
    memory: Memory,
}

fn invalid_failures(rule: String) -> RfError {
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

/// The smaller of the largest positive and negative yaw torques the `columns` make while
/// holding the weight with zero roll and pitch torque (0 when one side is out of reach).
fn yaw_authority(airframe: &Airframe, matrix: &DMatrix<f64>, columns: &[usize]) -> Result<f64> {
    let m = columns_of(matrix, columns, 4);
    let lower: Vec<f64> = columns
        .iter()
        .map(|&i| airframe.min_thrust_n()[i])
        .collect();
    let upper: Vec<f64> = columns
        .iter()
        .map(|&i| airframe.max_thrust_n()[i])
        .collect();
    let base = airframe.hover_wrench();
    let mut authority = f64::INFINITY;
    for sign in [1.0, -1.0] {
        let limit = max_along_direction(
            &m,
            &lower,
            &upper,
            &[0.0, 0.0, 0.0, sign],
            &base,
            &ClarabelSettings::default(),
        )?;
        authority = authority.min(limit.map_or(0.0, |l| l.scale.max(0.0)));
    }
    Ok(authority)
}

impl Mode {
    fn new(
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
        let lower: Vec<f64> = healthy
            .iter()
            .map(|&i| airframe.min_thrust_n()[i])
            .collect();
        let upper: Vec<f64> = healthy
            .iter()
            .map(|&i| airframe.max_thrust_n()[i])
            .collect();

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
                "with rotor(s) {names} failed the remaining rotors cannot hold the weight even \
                 spinning: the largest thrust with zero roll and pitch torque is {max_thrust} N \
                 < {weight} N"
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
        let (rotation, output_direction, zero_dynamics) = if single_axis {
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
            let zeta = (a < 0.0)
                .then(|| (1.0 + a).abs() / gains.output_angle_rad.tan() / (2.0 * (-a).sqrt()));
            ([c, [-c[1], c[0]]], Some(c), Some((a, zeta)))
        } else {
            ([[1.0, 0.0], [0.0, 1.0]], None, None)
        };

        let mut primary_axis = Vector3::z();
        if m == 4 && failed.len() == 1 && !single_axis && gains.primary_axis_tilt > 0.0 {
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
        if !yaw_controlled {
            // Only rotors beyond those the thrust and attitude rows use have authority to spare.
            let used = if single_axis { 2 } else { 3 };
            weights[3] = if healthy.len() > used {
                gains.given_up_yaw_weight
            } else {
                0.0
            };
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
            rotation,
            primary_axis,
            lower,
            upper,
        })
    }
}

impl IndiController {
    /// `failures`: the rotors the controller is told have failed and when (module docs);
    /// `setpoints`: the reference, times strictly increasing; `dt_s`: the control period the
    /// simulator calls it at.
    pub fn new(
        airframe: &Airframe,
        gains: IndiGains,
        failures: Vec<DetectedFailure>,
        setpoints: Vec<Setpoint>,
        dt_s: f64,
    ) -> Result<Self> {
        gains.check()?;
        require_finite("dt_s", dt_s)?;
        if dt_s <= 0.0 {
            return Err(RfError::invalid("dt_s", format!("must be > 0, got {dt_s}")));
        }
        if setpoints.is_empty() {
            return Err(RfError::invalid(
                "setpoints",
                "must hold at least one setpoint",
            ));
        }
        for (k, s) in setpoints.iter().enumerate() {
            require_finite(&format!("setpoints[{k}].time"), s.time_s)?;
            for v in s.position_m {
                require_finite(&format!("setpoints[{k}].position"), v)?;
            }
            for v in s.velocity_m_s {
                require_finite(&format!("setpoints[{k}].velocity"), v)?;
            }
            if k > 0 && s.time_s <= setpoints[k - 1].time_s {
                return Err(RfError::invalid(
                    format!("setpoints[{k}].time"),
                    "times must be strictly increasing",
                ));
            }
        }
        let m = airframe.rotor_count();
        if m > MAX_ACTUATORS {
            return Err(RfError::invalid(
                "airframe",
                format!("INDI allocates over at most {MAX_ACTUATORS} rotors, got {m}"),
            ));
        }
        let mut failures = failures;
        for (k, f) in failures.iter().enumerate() {
            require_finite(&format!("failures[{k}].time"), f.time_s)?;
            if f.rotor >= m {
                return Err(RfError::invalid(
                    format!("failures[{k}].rotor"),
                    format!("the airframe has {m} rotors, got rotor index {}", f.rotor),
                ));
            }
            if failures[..k].iter().any(|g| g.rotor == f.rotor) {
                return Err(RfError::invalid(
                    format!("failures[{k}].rotor"),
                    format!("rotor {} is listed twice", f.rotor + 1),
                ));
            }
        }
        failures.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let all: Vec<usize> = (0..m).collect();
        let healthy_authority =
            yaw_authority(airframe, &airframe.nominal_effectiveness_matrix(), &all)?;
        let mut modes = Vec::with_capacity(failures.len() + 1);
        for k in 0..=failures.len() {
            let mut failed: Vec<usize> = failures[..k].iter().map(|f| f.rotor).collect();
            failed.sort_unstable();
            modes.push(Mode::new(airframe, &gains, failed, healthy_authority)?);
        }
        let filter = SecondOrderLowPass::new(
            ("filter_frequency_rad_s", gains.filter_frequency_rad_s),
            ("filter_damping", gains.filter_damping),
            dt_s,
        )?;
        let first = modes[0].info.healthy.len();
        Ok(IndiController {
            gains,
            dt_s,
            mass_kg: airframe.mass_kg(),
            gravity_m_s2: airframe.gravity_m_s2(),
            rotor_count: m,
            filter,
            setpoints,
            failures,
            modes,
            active: ActiveSet::cold(first),
            memory: Memory::default(),
        })
    }

    /// How each failure set is flown: `[0]` the healthy vehicle, `[k]` after the first `k`
    /// failures (in time order).
    pub fn failure_modes(&self) -> Vec<FailureMode> {
        self.modes.iter().map(|m| m.info.clone()).collect()
    }

    pub fn gains(&self) -> &IndiGains {
        &self.gains
    }

    /// The reference position and velocity at `t_s`.
    fn reference(&self, t_s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let k = self
            .setpoints
            .partition_point(|s| s.time_s <= t_s)
            .saturating_sub(1);
        let s = &self.setpoints[k];
        let v = Vector3::from(s.velocity_m_s);
        let elapsed = (t_s - s.time_s).max(0.0);
        (Vector3::from(s.position_m) + v * elapsed, v)
    }

    /// Index of the failure set in force at `t_s`.
    fn mode_at(&self, t_s: f64) -> usize {
        self.failures.partition_point(|f| f.time_s <= t_s)
    }

    /// Step 1 of the law: the desired acceleration (NED) from the position loop; updates the
    /// velocity integral after use.
    fn position_loop(&mut self, t_s: f64, s: &RigidBodyState) -> Vector3<f64> {
        let g = &self.gains;
        let (p_r, v_r) = self.reference(t_s);
        let e_p = p_r - s.position_m;
        let mut v_t = Vector2::new(g.k_p_xy * e_p.x + v_r.x, g.k_p_xy * e_p.y + v_r.y);
        let speed = v_t.norm();
        if speed > g.max_speed_m_s {
            v_t *= g.max_speed_m_s / speed;
        }
        let e_v = v_t - s.velocity_m_s.xy();
        let integral = Vector2::from(self.memory.integral_xy);
        let mut a_xy = e_v * g.k_v_xy + integral * g.k_i_xy;
        let lateral = self.gravity_m_s2 * g.max_tilt_rad.tan();
        if a_xy.norm() > lateral {
            a_xy *= lateral / a_xy.norm();
        }
        let limit = g.integral_limit_m;
        for (i, e) in e_v.iter().enumerate() {
            self.memory.integral_xy[i] =
                (self.memory.integral_xy[i] + e * self.dt_s).clamp(-limit, limit);
        }
        let nu_z = g.k_p_z * e_p.z + g.k_d_z * (v_r.z - s.velocity_m_s.z);
        Vector3::new(a_xy.x, a_xy.y, nu_z)
    }

    /// Filters started at their inputs (a settled start).
    fn start(
        &mut self,
        gyro: &Vector3<f64>,
        thrust: &[f64],
        vertical: f64,
        direction: &Vector3<f64>,
    ) {
        let mem = &mut self.memory;
        mem.started = true;
        for i in 0..3 {
            mem.gyro[i] = SecondOrderLowPass::settled(gyro[i]);
            mem.direction[i] = SecondOrderLowPass::settled(direction[i]);
        }
        mem.thrust = thrust
            .iter()
            .map(|&t| SecondOrderLowPass::settled(t))
            .collect();
        mem.mismatch = vec![0.0; thrust.len()];
        mem.vertical = SecondOrderLowPass::settled(vertical);
    }
}

/// What one step of the law computes besides the commands (for tests: the one-step prediction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IndiStep {
    /// Filtered angular acceleration `omega'_f`, rad/s^2.
    pub angular_acceleration_f: Vector3<f64>,
    /// Predicted angular acceleration once the rotors produce the commands, rad/s^2.
    pub angular_acceleration_predicted: Vector3<f64>,
    /// Filtered vertical acceleration `z''_f` (NED), m/s^2.
    pub vertical_acceleration_f: f64,
}

impl IndiController {
    /// One control step (module docs); writes the commands and returns the intermediate values.
    pub fn step(
        &mut self,
        t_s: f64,
        input: &ControllerInput<'_>,
        out: &mut [f64],
    ) -> Result<IndiStep> {
        let s = input.state;
        // A non-finite sample would poison every filter for good: refuse it (the simulator stops
        // at a non-finite state before calling the controller).
        let samples_finite = input
            .gyro_rad_s
            .is_none_or(|v| v.iter().all(|x| x.is_finite()))
            && input
                .specific_force_m_s2
                .is_none_or(|v| v.iter().all(|x| x.is_finite()))
            && input
                .rotor_thrust_n
                .is_none_or(|v| v.iter().all(|x| x.is_finite()));
        if !s.is_finite() || !t_s.is_finite() || !samples_finite {
            return Err(RfError::invalid(
                "measured",
                format!("the state and samples at t = {t_s} s must be finite"),
            ));
        }
        let m = self.rotor_count;
        if let Some(thrust) = input.rotor_thrust_n {
            if thrust.len() != m {
                return Err(RfError::shape(
                    "rotor_thrust_n",
                    format!("{m} entries (one per rotor)"),
                    thrust.len().to_string(),
                ));
            }
        }
        let mode_index = self.mode_at(t_s);
        if !self.memory.started || mode_index != self.memory.mode {
            self.active = ActiveSet::cold(self.modes[mode_index].info.healthy.len());
        }
        if !self.memory.started {
            self.memory.previous = self.modes[mode_index].info.hover_thrust_n.clone();
        }
        self.memory.mode = mode_index;

        let rot: Matrix3<f64> = s.attitude.to_rotation_matrix().into_inner();
        let omega = input.gyro_rad_s.unwrap_or(s.omega_rad_s);
        let mut thrust_sample = [0.0; MAX_ACTUATORS];
        thrust_sample[..m].copy_from_slice(input.rotor_thrust_n.unwrap_or(&self.memory.previous));
        let thrust_sample = &thrust_sample[..m];
        let n3z_true = rot[(2, 2)];
        let g = self.gravity_m_s2;
        let a_des = self.position_loop(t_s, s);
        let thrust_dir = Vector3::new(-a_des.x, -a_des.y, g - a_des.z);
        let z_des = thrust_dir / thrust_dir.norm();

        // Vertical acceleration sample (NED): measured, or its model from the filtered thrusts.
        let measured_vertical = input.specific_force_m_s2.map(|f| (rot * f).z + g);
        if !self.memory.started {
            let start_vertical = measured_vertical.unwrap_or(0.0);
            self.start(&omega, thrust_sample, start_vertical, &z_des);
        }
        let filter = self.filter;
        let mem = &mut self.memory;
        let mut omega_dot_f = Vector3::zeros();
        for i in 0..3 {
            filter.step(&mut mem.gyro[i], omega[i]);
            omega_dot_f[i] = mem.gyro[i][1];
        }
        for (state, &t) in mem.thrust.iter_mut().zip(thrust_sample) {
            filter.step(state, t);
        }
        let mut z_f = Vector3::zeros();
        let mut z_rate = Vector3::zeros();
        let mut z_acc = Vector3::zeros();
        for i in 0..3 {
            filter.step(&mut mem.direction[i], z_des[i]);
            z_f[i] = mem.direction[i][0];
            z_rate[i] = mem.direction[i][1].clamp(-MAX_REFERENCE_RATE, MAX_REFERENCE_RATE);
            z_acc[i] = filter.acceleration(&mem.direction[i], z_des[i]);
        }
        let keep = (-self.dt_s / self.gains.mismatch_time_constant_s).exp();
        for ((d, &c), &p) in mem
            .mismatch
            .iter_mut()
            .zip(&mem.previous)
            .zip(thrust_sample)
        {
            *d = keep * *d + (1.0 - keep) * (c - p);
        }
        let mode = &self.modes[mode_index];
        let n3z = n3z_true.max(MIN_N3Z);
        let total_f: f64 = mode
            .info
            .healthy
            .iter()
            .zip(&mode.thrust)
            .map(|(&i, c)| c * mem.thrust[i][0])
            .sum();
        let vertical_f = match measured_vertical {
            Some(v) => {
                filter.step(&mut mem.vertical, v);
                mem.vertical[0]
            }
            None => g - n3z * total_f / self.mass_kg,
        };

        // Step 2-3: reduced attitude and pseudo-controls.
        let rt = rot.transpose();
        let h = rt * z_f;
        let lambda = rt * z_rate;
        let h_dot = lambda + h.cross(&omega);
        let n = mode.primary_axis;
        let y = Vector2::new(h.x - n.x, h.y - n.y);
        let y_dot = h_dot.xy();
        let kinematic = (h_dot.cross(&omega) + lambda.cross(&omega) + rt * z_acc).xy();
        let gains = &self.gains;
        let nu_y = -y * gains.k_att_p - y_dot * gains.k_att_d;
        let b_att = nu_y - kinematic - h.cross(&omega_dot_f).xy();
        let b_yaw = -gains.k_r * omega.z - omega_dot_f.z;
        let b_z = a_des.z - vertical_f;

        // Step 4-5: G dT = b over the healthy rotors.
        let k = mode.info.healthy.len();
        let rows = mode.rotation;
        let mut g_rows = [[0.0; MAX_ACTUATORS]; 4];
        for (c, (a, &thrust_entry)) in mode.angular.iter().zip(&mode.thrust).enumerate() {
            let att = h.cross(a).xy();
            g_rows[0][c] = -n3z / self.mass_kg * thrust_entry;
            g_rows[1][c] = rows[0][0] * att.x + rows[0][1] * att.y;
            g_rows[2][c] = rows[1][0] * att.x + rows[1][1] * att.y;
            g_rows[3][c] = a.z;
        }
        let b = [
            b_z,
            rows[0][0] * b_att.x + rows[0][1] * b_att.y,
            rows[1][0] * b_att.x + rows[1][1] * b_att.y,
            b_yaw,
        ];
        let mut base = [0.0; MAX_ACTUATORS];
        let mut lower = [0.0; MAX_ACTUATORS];
        let mut upper = [0.0; MAX_ACTUATORS];
        for (c, &i) in mode.info.healthy.iter().enumerate() {
            base[c] = (mem.thrust[i][0] + mem.mismatch[i]).clamp(mode.lower[c], mode.upper[c]);
            lower[c] = mode.lower[c] - base[c];
            upper[c] = mode.upper[c] - base[c];
        }
        let increment = incremental_allocation(
            &g_rows,
            &mode.weights,
            &b,
            &lower[..k],
            &upper[..k],
            &mut self.active,
        );
        out[..m].fill(0.0);
        let mut predicted = omega_dot_f;
        for (c, &i) in mode.info.healthy.iter().enumerate() {
            out[i] = base[c] + increment[c];
            predicted += mode.angular[c] * increment[c];
        }
        self.memory.previous.copy_from_slice(&out[..m]);
        Ok(IndiStep {
            angular_acceleration_f: omega_dot_f,
            angular_acceleration_predicted: predicted,
            vertical_acceleration_f: vertical_f,
        })
    }
}

/// Step 5 of the law: `min |W^(1/2) (b - G dT)|` over `lower <= dT <= upper` (columns `0..k` of
/// `g`, `k = lower.len()`), the smallest `dT` among equal optima. When the weighted rows have full
/// row rank and no more rows than columns, the unconstrained optimum is the minimum-norm solution
/// `G_w^T (G_w G_w^T)^-1 b_w` (four rows at most: a Cholesky of at most 4 x 4); inside the bounds it
/// is also the bounded optimum (every KKT multiplier zero) and is returned as is. Otherwise, the
/// active-set solver of [`crate::allocation`] (warm-started from `active`) decides. NaN when the
/// problem is not finite (the simulator then reports a non-finite command).
fn incremental_allocation(
    g: &[[f64; MAX_ACTUATORS]; 4],
    weights: &[f64; 4],
    b: &[f64; 4],
    lower: &[f64],
    upper: &[f64],
    active: &mut ActiveSet,
) -> [f64; MAX_ACTUATORS] {
    let k = lower.len();
    let mut out = [f64::NAN; MAX_ACTUATORS];
    if !b.iter().all(|v| v.is_finite())
        || !g.iter().all(|row| row[..k].iter().all(|v| v.is_finite()))
    {
        return out;
    }
    if let Some(x) = minimum_norm(g, weights, b, k) {
        if (0..k).all(|c| x[c] >= lower[c] && x[c] <= upper[c]) {
            *active = ActiveSet::cold(k);
            return x;
        }
    }
    let matrix = DMatrix::from_fn(4, k, |r, c| g[r][c]);
    if let Ok(problem) = AllocationProblem::new(matrix, weights, lower, upper) {
        ActiveSetSolver::new(&problem).solve_unchecked(b, active, &mut out[..k]);
    }
    out
}

/// The minimum-norm minimiser of `|W^(1/2) (b - G x)|` (columns `0..k`) when the rows with a
/// positive weight have full row rank and number at most `k`; `None` otherwise.
fn minimum_norm(
    g: &[[f64; MAX_ACTUATORS]; 4],
    weights: &[f64; 4],
    b: &[f64; 4],
    k: usize,
) -> Option<[f64; MAX_ACTUATORS]> {
    let mut rows = [[0.0; MAX_ACTUATORS]; 4];
    let mut rhs = [0.0; 4];
    let mut n = 0;
    for r in 0..4 {
        if weights[r] > 0.0 {
            let w = weights[r].sqrt();
            for c in 0..k {
                rows[n][c] = w * g[r][c];
            }
            rhs[n] = w * b[r];
            n += 1;
        }
    }
    if n == 0 || n > k {
        return None;
    }
    // Cholesky of the Gram matrix S = R R^T (n x n, lower triangle in l).
    let mut l = [[0.0; 4]; 4];
    let mut largest = 0.0f64;
    for i in 0..n {
        for j in 0..=i {
            let mut sum: f64 = (0..k).map(|c| rows[i][c] * rows[j][c]).sum();
            if i == j {
                largest = largest.max(sum);
            }
            for p in 0..j {
                sum -= l[i][p] * l[j][p];
            }
            if i == j {
                // A pivot lost to rounding against the largest diagonal: (nearly) rank deficient.
                if !(sum > 1e-12 * largest) {
                    return None;
                }
                l[i][i] = sum.sqrt();
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    // S y = rhs, then x = R^T y.
    let mut y = [0.0; 4];
    for i in 0..n {
        y[i] = (rhs[i] - (0..i).map(|p| l[i][p] * y[p]).sum::<f64>()) / l[i][i];
    }
    for i in (0..n).rev() {
        y[i] = (y[i] - (i + 1..n).map(|p| l[p][i] * y[p]).sum::<f64>()) / l[i][i];
    }
    let mut x = [0.0; MAX_ACTUATORS];
    for (c, xc) in x.iter_mut().enumerate().take(k) {
        *xc = (0..n).map(|i| rows[i][c] * y[i]).sum();
    }
    Some(x)
}

impl Controller for IndiController {
    fn command_count(&self) -> usize {
        self.rotor_count
    }

    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.step(t_s, &ControllerInput::state_only(measured), out)
            .map(|_| ())
    }

    fn command_with(
        &mut self,
        t_s: f64,
        input: &ControllerInput<'_>,
        out: &mut [f64],
    ) -> Result<()> {
        self.step(t_s, input, out).map(|_| ())
    }

    fn reads_samples(&self) -> bool {
        true
    }

    fn reset(&mut self) {
        self.memory = Memory::default();
        self.active = ActiveSet::cold(self.modes[0].info.healthy.len());
    }
}
