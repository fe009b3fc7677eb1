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
//!    limited to `g tan(max_tilt)`; vertical `nu_z = k_p,z (z_r - z) + k_d,z (w_r - w)`, limited to
//!    `max_vertical_accel_m_s2` (below `g`: the thrust keeps pointing up). The thrust
//!    direction wanted is `z_d = (g e3 - a) / |g e3 - a|` (body z, pointing down), `a = (a_xy, nu_z)`,
//!    passed through the low-pass filter (value, rate `z_d'`, acceleration `z_d''`).
//! 2. **Reduced attitude of the primary axis `n`** (body frame, unit; body z unless tilted, see
//!    [`IndiGains::primary_axis_tilt`]): `h = R^T z_d`, output `Y = h_xy - n_xy`, `Y' = (h')_xy`
//!    with `h' = lambda + h x omega`, `lambda = R^T z_d'`. The yaw about `n` is free: the vehicle
//!    may spin about its thrust axis.
//! 3. **Pseudo-controls**: `nu_Y = -k_att,p Y - k_att,d Y'`, `nu_r = -k_r r` (yaw rate held at zero
//!    while yaw is controlled), `nu_z` from step 1.
//! 4. **INDI**: with the filtered gyro rate differentiated, `omega'_f` (the inertia coupling taken at
//!    the current rate, "Filter and inertia coupling" below), the filtered rotor thrusts
//!    `T_f` (the same filter, [`crate::control::filter`]) and the filtered vertical acceleration
//!    `z''_f` (from the specific force, the same filter), the outputs one step ahead are
//!    `z'' = z''_f - (n3z / m) 1^T dT`,
//!    `Y'' = K + (h x (omega'_f + J^-1 M_tau dT))_xy`, `K = (h' x omega + lambda x omega + R^T z_d'')_xy`,
//!    `r' = r'_f + (J^-1 M_tau dT)_z`
//!    (`M_tau` the torque rows of the nominal effectiveness matrix, `J` the inertia). Equating them
//!    to the pseudo-controls gives `G dT = b` (rows thrust, two attitude, yaw). `K` is evaluated
//!    at the current sample, not filtered: it holds no input.
//! 5. **Incremental allocation over the remaining rotors**: `min |W^(1/2) (b - G dT)|` with
//!    `T_min - base <= dT <= T_max - base`, the failed rotors' columns removed, the smallest `dT`
//!    among equal optima (Sun's pseudo-inverse): the minimum-norm solution when it lies within the
//!    bounds, else the exact active-set solver of [`crate::allocation`], warm-started. The command
//!    is `T = base + dT`, the failed rotors 0.
//!    **Priorities when the rotors saturate** (the minimum-norm solution leaves the bounds): with
//!    [`YawMode::Auto`], the yaw row then takes its given-up weight (below): thrust and reduced
//!    attitude first, yaw with what is left, as Sun et al. prioritise it. A rotor that lost most
//!    of its thrust without the controller being told (a partial loss) otherwise has the law hold
//!    yaw at the cost of thrust: hexa-ppnnpn with rotor 5 at 5 % sank and crashed; with the
//!    priorities it gives up yaw, spins and holds (`tests/indi.rs`). [`YawMode::Hold`] keeps
//!    `weights` when saturated (the law before this rule).
//!
//! # The incremental base
//! `base = T_f + d`: `T_f` the filtered thrusts the rotors produce (in step with `omega'_f`), and
//! `d` a slow low-pass (time constant [`IndiGains::mismatch_time_constant_s`]) of (previous command
//! minus produced thrust). A rotor producing a fraction `e` of its command (a partial loss the
//! controller is not told of, a weak motor) would otherwise settle with a standing increment
//! `(1 - e) T / e` and the output error that sustains it (ke-quadcopter, rotor 1 at 40 %: 6.1 m off
//! station); with `d`, the steady state has `dT = 0` and no output error (`tests/indi.rs`).
//!
//! # When rotors fail (decided once per failure set, at construction)
//! - **Yaw** ([`YawMode`]): given up (weight `weights[3]` replaced by the small
//!   [`IndiGains::given_up_yaw_weight`]; Sun eliminates the row)
//!   when the remaining rotors, at hover, can make less than [`IndiGains::min_yaw_authority`] of
//!   the healthy vehicle's yaw torque in either direction (an attainable-set LP), e.g. any rotor of
//!   a quadrotor or of the PNPNPN hexacopter. The vehicle then spins about `n`.
//! - **The spin axis, yaw given up with spare rotors** ([`IndiGains::given_up_yaw_axis_tilt`]):
//!   spinning about body z, the vehicle spins up until the drag meets the yaw torque the hover
//!   cannot avoid (the least |yaw torque| holding the weight with zero roll and pitch torque, an
//!   LP). On hexa-ppnnpn without rotor 5 or 6 that torque is 23 % of the healthy yaw authority,
//!   and on a heavy vehicle (the rotor that must balance the lost one weak) the spin heads past
//!   200 rad/s. Tilting the primary axis to `n = (alpha d, n_z)`, `n_z = sqrt(1 - alpha^2)`, makes
//!   the steady spin `omega = r n` need the roll and pitch torque `omega x J omega = r^2 alpha n_z
//!   (d_y (J_z - J_y), d_x (J_x - J_z))` from the rotors, which then need not balance roll and pitch to zero
//!   and can even out the yaw: the spin settles where that relief (growing as `r^2`) meets the
//!   drag (Mueller and D'Andrea's relaxed hover in INDI's terms; the campaign's 0.2 settles
//!   near 11 rad/s). `d` is chosen once, the best of 24 directions
//!   by the least yaw torque left (an LP each), when the unavoidable torque is at least
//!   `min_yaw_authority` of the healthy yaw authority (below it the vehicle barely spins and a
//!   tilt would only tilt the thrust).
//! - **One torque axis left** (two opposing rotors of a quadrotor): only one combination
//!   `y = c . Y` of the two attitude outputs can be controlled. Sun's output redefinition: `c` at
//!   the angle `beta + s delta` with `beta` the direction of the angular acceleration the remaining
//!   rotors make, `delta` = [`IndiGains::output_angle_rad`] and `s` the sign of the spin (the yaw
//!   torque at hover) times the sign of `1 + a`, `a = (J_xy - J_z) / J_xy`. Linearised about the
//!   spin `r`, the other combination (the zero dynamics) obeys
//!   `eta'' = a r^2 eta - (1 + a) |r| cot(delta) eta'` : stable when `J_z > J_xy` (`a < 0`) and the
//!   sign is chosen so; its damping ratio `(1 + a) cot(delta) / (2 sqrt(-a))` does not depend on the
//!   spin rate. With `J_z < J_xy` no choice of `delta` is stable ([`FailureMode::zero_dynamics`]).
//!   **The side of `delta` from the measured inertia**: `1 + a = (2 J_xy - J_z) / J_xy` is small
//!   on a quadrotor (its mass near the rotor plane makes `J_z` close to `2 J_xy`: 0.14 for
//!   ke-quadcopter, 0.15 for Sun's Bebop), so an inertia 10-20 % off the model's can turn its sign,
//!   and the side chosen from the nominal inertia then makes the zero dynamics unstable: a nutation
//!   that grows with the spin into bang-bang rotor commands (ke-quadcopter in the deciding campaign:
//!   all 49 total losses it lost had `J_z / J_xy > 2.08`). The law estimates the roll and pitch
//!   coupling coefficients `k_x = (J_y - J_z) / J_x`, `k_y = (J_z - J_x) / J_y` (`omega'_x = k_x q r
//!   + ...`) by least squares of the filtered angular acceleration less the rotors' (the same
//!   filter on both) against the filtered `q r` and `r p`, forgetting over
//!   [`COUPLING_FORGETTING_S`], the nominal values a prior of [`COUPLING_PRIOR_RAD2_S2`]; it flies
//!   the side of `1 + a = 1 + (k_x - k_y) / 2` (changing side when that lies beyond
//!   [`OUTPUT_FLIP_MARGIN`] on the other), and takes the coupling of step 4 from the estimate. Near
//!   `J_z = 2 J_xy` the second attitude output is barely controllable with one torque axis
//!   (the linearised `Y'' + i (1 + a) r Y' - a r^2 Y = i e u`, `Y = Y_x + i Y_y`, loses the
//!   component across `i e` at `a = -1`): only the drag damps it there.
//!   Sun's `chi = 105 deg` on his Bebop 2 is `delta = 65.67 deg` here (a test derives it).
//! - **No hover**: a failure set whose remaining rotors cannot hold the weight with zero roll and
//!   pitch torque (the hover this law builds its failure modes on, spinning about the thrust
//!   axis) is refused at construction, naming `failures`: the relaxed hover below does not lift
//!   that check, so the relaxed hovers that two adjacent or three lost rotors of a quadrotor need
//!   (Mueller and D'Andrea) are not flown.
//! - **A relaxed hover** ([`RelaxedSpin`], [`IndiController::with_relaxed_spin`]): told a spin
//!   axis, from its time on the law holds that axis up and regulates the spin about it (what a
//!   vehicle without rotational drag needs once yaw is given up; `relaxed.rs`). The given axis
//!   takes precedence over the tilt of [`IndiGains::given_up_yaw_axis_tilt`]; refused with one
//!   torque axis left, where the spin itself keeps the vehicle stable. Told two rotors that both
//!   lost thrust by amounts it is not told ([`RelaxedSpin::choosing_the_weaker_of`]), the law
//!   measures them for [`SPIN_AXIS_CHOICE_S`] and flies the axis on the weaker's side.
//!
//! # Samples and their substitutes
//! [`Controller::command_with`] reads the gyro, the specific force and the rotor thrusts actually
//! produced ([`ControllerInput`]). Missing samples are replaced, and the law says how: the gyro by
//! the state's body rates; the vertical acceleration by its model `g - n3z sum(T_f) / m` (the
//! thrust row becomes plain dynamic inversion: a mass error then leaves an altitude offset); the
//! rotor thrusts by an actuator model, the previous commands through a first-order lag
//! ([`IndiGains::actuator_time_constant_s`]; without it the commanded base runs ahead of the
//! measured acceleration by the rotor lag and the loop oscillates).
//!
//! # Filter and inertia coupling (decisions)
//! Sun's code filters with a first-order 0.02 s low-pass; this law uses the second-order filter of
//! Smeur et al. (JGCD 2016), damping 0.55, at Sun's 50 rad/s, so that the gyro is differentiated
//! exactly. Plain INDI leaves every torque but the rotors' to the filtered gyro, the inertia
//! coupling `-J^-1 (omega x J omega)` included; at the 40 rad/s spin of a quadrotor that lost rotors
//! the filter's lag on that large, fast term loses ke-quadcopter flying at 2 m/s after losing rotors
//! 1 and 3 (the oscillation grows with the spin until the rotors saturate: 2.4 m altitude error in
//! the window). The coupling is known from the gyro and `J`, so the law takes it at
//! the current rate and removes its filtered value from `omega'_f`
//! ([`IndiGains::model_coupling`]): the filter then lags only on the unknown torques (drag, rotor
//! gyroscopic moment), and that flight holds to 0.42 m (`tests/indi.rs`).
//!
//! # Floors (stated once)
//! `n3z` in the thrust row is floored at [`MIN_N3Z`] (the law needs the thrust to point up); Sun's
//! saturation of the reference rate `|lambda_i| <= 0.5` 1/s is kept ([`MAX_REFERENCE_RATE`]).

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::airframe::Airframe;
use crate::allocation::active_set::ActiveSet;
use crate::allocation::MAX_ACTUATORS;
use crate::control::filter::SecondOrderLowPass;
use crate::control::Controller;
use crate::error::{require_finite, Result, RfError};
use crate::state::{ControllerInput, RigidBodyState};

mod gains;
mod increment;
mod modes;
mod relaxed;

pub use gains::{sun_output_angle_rad, IndiGains, YawMode};
use increment::incremental_allocation;
pub use modes::FailureMode;
use modes::{yaw_authority, Mode};
pub use relaxed::{RelaxedSpin, SPIN_AXIS_CHOICE_S};

/// Two weak rotors' produced / commanded ratios closer than this (relative) are equal: the spin
/// axis is kept as given (`RelaxedSpin::choosing_the_weaker_of`: the sums' rounding is near
/// 1e-16; the x500 draws that needed the choice differ by 5.3 % and more).
const SPIN_AXIS_CHOICE_RTOL: f64 = 1e-9;
/// Two rotors are mounted opposite each other when their x-y positions sum to within this share
/// of the farther one's distance from the centre.
const OPPOSITE_RTOL: f64 = 1e-9;
/// Floor on `n3z` in the thrust row of `G` (the tilt at which it binds: 87 degrees).
pub const MIN_N3Z: f64 = 0.05;
/// Largest rate of the filtered thrust direction the law feeds forward, 1/s (Sun's saturation).
pub const MAX_REFERENCE_RATE: f64 = 0.5;
/// Forgetting time constant of the inertia-coupling estimate with one torque axis left, s (module
/// docs, "One torque axis left"): a few nutation periods at the slowest spins that need it.
pub const COUPLING_FORGETTING_S: f64 = 2.0;
/// The nominal inertia's coupling weighs in that estimate as a regressor of this rms, (rad/s)^2,
/// over the forgetting time: at hover (no rates) the estimate is the nominal value, and a tilt
/// oscillation of 0.1 rad/s at a 10 rad/s spin already outweighs it.
pub const COUPLING_PRIOR_RAD2_S2: f64 = 0.1;
/// The output direction changes side only when the estimated `1 + a` is at least this far on
/// the other side of 0 (hysteresis: near 0 neither side damps the zero dynamics).
pub const OUTPUT_FLIP_MARGIN: f64 = 0.05;

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
    /// The actuator model's thrusts (used without rotor samples), N.
    modelled: Vec<f64>,
    /// `gamma(omega) = -J^-1 (omega x J omega)` through the filter.
    coupling: [[f64; 2]; 3],
    /// Slow low-pass of (previous command - produced thrust) per rotor, N.
    mismatch: Vec<f64>,
    mode: usize,
    /// The regressors `(q r, r p)` of the inertia-coupling estimate through the filter.
    products: [[f64; 2]; 2],
    /// Per roll/pitch axis, forgetting sums of (regressor^2, regressor x residual).
    coupling_sums: [[f64; 2]; 2],
    /// Single axis: flying the other sign of `delta` (`Mode::rotation_flipped`).
    output_flipped: bool,
    /// The relaxed hover's spin sign once latched (`RelaxedSpin::target`), 0 before.
    spin_sign: f64,
    /// Choosing between two weak rotors (`RelaxedSpin::choosing_the_weaker_of`): per rotor, the
    /// sums of produced and commanded thrust since the spin's time, N.
    spin_choice_sums: [[f64; 2]; 2],
    /// A step of the choice's measurement had no rotor thrust samples.
    spin_choice_unmeasured: bool,
    /// The choice once made: `Some(true)` flies the mirrored axis.
    spin_axis_mirrored: Option<bool>,
}

/// The INDI fault-tolerant controller (module docs). Rotor commands are thrusts, N.
#[derive(Debug, Clone)]
pub struct IndiController {
    gains: IndiGains,
    dt_s: f64,
    mass_kg: f64,
    inertia_kg_m2: [f64; 3],
    gravity_m_s2: f64,
    rotor_count: usize,
    filter: SecondOrderLowPass,
    /// `exp(-dt / actuator_time_constant_s)` of the actuator model.
    actuator_keep: f64,
    setpoints: Vec<Setpoint>,
    /// Failures sorted by time; `modes[j]` flies the first `mode_counts[j]` of them.
    failures: Vec<DetectedFailure>,
    modes: Vec<Mode>,
    mode_counts: Vec<usize>,
    active: ActiveSet,
    memory: Memory,
    /// A relaxed hover to fly from its time on ([`RelaxedSpin`]).
    relaxed: Option<RelaxedSpin>,
    /// Rotor positions in the body x-y plane, m (a spin's two weak rotors must be opposite).
    rotor_xy_m: Vec<[f64; 2]>,
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
        let gravity = airframe.gravity_m_s2();
        if gains.max_vertical_accel_m_s2 >= gravity {
            return Err(RfError::invalid(
                "max_vertical_accel_m_s2",
                format!(
                    "must be below g = {gravity} m/s^2 (a larger downward demand turns the thrust \
                     direction over), got {}",
                    gains.max_vertical_accel_m_s2
                ),
            ));
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
        // One mode per distinct detection time: failures told at once are flown together (a set
        // between them, never flown, is not built nor judged).
        let mut modes = Vec::with_capacity(failures.len() + 1);
        let mut mode_counts = Vec::with_capacity(failures.len() + 1);
        for k in 0..=failures.len() {
            if k > 0 && k < failures.len() && failures[k].time_s == failures[k - 1].time_s {
                continue;
            }
            let mut failed: Vec<usize> = failures[..k].iter().map(|f| f.rotor).collect();
            failed.sort_unstable();
            modes.push(Mode::new(airframe, &gains, failed, healthy_authority)?);
            mode_counts.push(k);
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
            inertia_kg_m2: airframe.inertia_kg_m2(),
            actuator_keep: if gains.actuator_time_constant_s > 0.0 {
                (-dt_s / gains.actuator_time_constant_s).exp()
            } else {
                0.0
            },
            gravity_m_s2: airframe.gravity_m_s2(),
            rotor_count: m,
            filter,
            setpoints,
            failures,
            modes,
            mode_counts,
            active: ActiveSet::cold(first),
            memory: Memory::default(),
            relaxed: None,
            rotor_xy_m: airframe
                .rotors()
                .iter()
                .map(|r| {
                    let [x, y, _] = r.placement.position_m();
                    [x, y]
                })
                .collect(),
        })
    }

    /// This controller flying `relaxed` from [`RelaxedSpin::flown_from_s`] on ([`RelaxedSpin`]:
    /// its axis as the primary axis, a spin-rate loop in place of the yaw row). The given spin
    /// axis takes precedence over every failure mode's own primary axis, the tilt of
    /// [`IndiGains::given_up_yaw_axis_tilt`] and [`IndiGains::primary_axis_tilt`] included.
    /// Refused, naming `spin_axis`, when a failure set flown at or after its time leaves one
    /// torque axis (Sun's output redefinition: there the spin about body z is what keeps the
    /// other axis stable, and no yaw row is left to regulate it); with a choice between two
    /// rotors ([`RelaxedSpin::choosing_the_weaker_of`]), refused naming `spin_axis_weaker_of`
    /// unless both are rotors of this vehicle, mounted opposite each other (the mirrored axis is
    /// the second's only then), neither told failed by the end of the choice (its command is 0:
    /// nothing to measure), and the control period shorter than the choice's measurement.
    pub fn with_relaxed_spin(mut self, relaxed: RelaxedSpin) -> Result<Self> {
        if let Some(rotors) = relaxed.spin_axis_weaker_of() {
            self.check_weaker_of(rotors, relaxed.flown_from_s())?;
        }
        let first = self.mode_at(relaxed.time_s());
        if let Some(mode) = self.modes[first..].iter().find(|m| m.info.single_axis) {
            return Err(RfError::invalid(
                "spin_axis",
                format!(
                    "a relaxed spin from {} s is flown with rotor(s) {:?} failed, which leave one \
                     torque axis: the spin about body z keeps the vehicle stable there (Sun's \
                     output redefinition), so no spin axis may be given",
                    relaxed.time_s(),
                    mode.info.failed
                ),
            ));
        }
        self.relaxed = Some(relaxed);
        Ok(self)
    }

    /// The relaxed hover this controller flies, if any.
    pub fn relaxed_spin(&self) -> Option<RelaxedSpin> {
        self.relaxed
    }

    /// The rules of a choice between two rotors (`with_relaxed_spin`).
    fn check_weaker_of(&self, rotors: [usize; 2], chosen_at_s: f64) -> Result<()> {
        let invalid = |rule: String| Err(RfError::invalid("spin_axis_weaker_of", rule));
        if let Some(&r) = rotors.iter().find(|&&r| r >= self.rotor_count) {
            return invalid(format!(
                "rotor numbers run from 1 to {}, got {}",
                self.rotor_count,
                r as u128 + 1
            ));
        }
        let [a, b] = rotors.map(|r| self.rotor_xy_m[r]);
        let scale = a[0].hypot(a[1]).max(b[0].hypot(b[1]));
        if !(scale > 0.0) || (a[0] + b[0]).hypot(a[1] + b[1]) > OPPOSITE_RTOL * scale {
            return invalid(format!(
                "rotors {} and {} are not mounted opposite each other (positions {a:?} and {b:?} m), \
                 so the mirrored axis is not the second's",
                rotors[0] + 1,
                rotors[1] + 1
            ));
        }
        if let Some(f) = self
            .failures
            .iter()
            .find(|f| rotors.contains(&f.rotor) && f.time_s <= chosen_at_s)
        {
            return invalid(format!(
                "rotor {} is told failed at {} s, by the end of the choice at {chosen_at_s} s: \
                 its command is 0, nothing to measure",
                f.rotor + 1,
                f.time_s
            ));
        }
        if self.dt_s >= SPIN_AXIS_CHOICE_S {
            return invalid(format!(
                "the control period {} s must be shorter than the choice's measurement, {} s",
                self.dt_s, SPIN_AXIS_CHOICE_S
            ));
        }
        Ok(())
    }

    /// How each failure set is flown: `[0]` the healthy vehicle, then one per detection time (the
    /// failures told at that time and all before, in time order).
    pub fn failure_modes(&self) -> Vec<FailureMode> {
        self.modes.iter().map(|m| m.info.clone()).collect()
    }

    pub fn gains(&self) -> &IndiGains {
        &self.gains
    }

    /// The inertia-coupling estimate of the mode flown last, when it has one torque axis left
    /// (module docs, "One torque axis left"); `None` before the first step and in other modes.
    /// For tests and diagnostics: the law reads it itself.
    pub fn coupling_estimate(&self) -> Option<CouplingEstimate> {
        let mem = &self.memory;
        (mem.started && self.modes[mem.mode].info.single_axis).then(|| CouplingEstimate {
            coefficients: estimated_coefficients(
                self.nominal_coefficients(),
                &mem.coupling_sums,
                self.dt_s,
            ),
            output_flipped: mem.output_flipped,
        })
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
        let told = self.failures.partition_point(|f| f.time_s <= t_s);
        // Every failure told by `t_s`: a group boundary, so a built mode.
        self.mode_counts.partition_point(|&k| k < told)
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
        let nu_z = (g.k_p_z * e_p.z + g.k_d_z * (v_r.z - s.velocity_m_s.z))
            .clamp(-g.max_vertical_accel_m_s2, g.max_vertical_accel_m_s2);
        Vector3::new(a_xy.x, a_xy.y, nu_z)
    }

    /// `gamma(omega) = -J^-1 (omega x J omega)`: the angular acceleration the inertia coupling
    /// gives (principal axes), rad/s^2.
    /// With `estimated` (one torque axis left), its roll and pitch coefficients in place of the
    /// nominal inertia's.
    fn coupling(&self, omega: &Vector3<f64>, estimated: Option<[f64; 2]>) -> Vector3<f64> {
        let [jx, jy, jz] = self.inertia_kg_m2;
        let (p, q, r) = (omega.x, omega.y, omega.z);
        let yaw = (jx - jy) * p * q / jz;
        match estimated {
            Some([kx, ky]) => Vector3::new(kx * q * r, ky * r * p, yaw),
            None => Vector3::new((jy - jz) * q * r / jx, (jz - jx) * r * p / jy, yaw),
        }
    }

    /// The coefficients `((J_y - J_z) / J_x, (J_z - J_x) / J_y)` of the roll and pitch coupling:
    /// the nominal inertia's, or with one torque axis left their estimate from the measured
    /// angular acceleration (module docs, "One torque axis left").
    fn coupling_coefficients(&self, single_axis: bool) -> Option<[f64; 2]> {
        single_axis.then(|| {
            estimated_coefficients(
                self.nominal_coefficients(),
                &self.memory.coupling_sums,
                self.dt_s,
            )
        })
    }

    fn nominal_coefficients(&self) -> [f64; 2] {
        let [jx, jy, jz] = self.inertia_kg_m2;
        [(jy - jz) / jx, (jz - jx) / jy]
    }

    /// Filters started at their inputs (a settled start).
    fn start(
        &mut self,
        gyro: &Vector3<f64>,
        coupling: &Vector3<f64>,
        thrust: &[f64],
        vertical: f64,
        direction: &Vector3<f64>,
    ) {
        let mem = &mut self.memory;
        mem.started = true;
        for i in 0..3 {
            mem.gyro[i] = SecondOrderLowPass::settled(gyro[i]);
            mem.coupling[i] = SecondOrderLowPass::settled(coupling[i]);
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

/// The estimate of the roll and pitch coupling coefficients: least squares with the nominal
/// values as a prior of [`COUPLING_PRIOR_RAD2_S2`] over [`COUPLING_FORGETTING_S`].
fn estimated_coefficients(nominal: [f64; 2], sums: &[[f64; 2]; 2], dt_s: f64) -> [f64; 2] {
    let prior = COUPLING_PRIOR_RAD2_S2.powi(2) * COUPLING_FORGETTING_S / dt_s;
    [0, 1].map(|i| (prior * nominal[i] + sums[i][1]) / (prior + sums[i][0]))
}

/// [`IndiController::coupling_estimate`]: the estimated roll and pitch coupling coefficients
/// `(k_x, k_y) = ((J_y - J_z) / J_x, (J_z - J_x) / J_y)` (1), and whether the output flies the
/// other side of `delta` than the nominal inertia's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CouplingEstimate {
    pub coefficients: [f64; 2],
    pub output_flipped: bool,
}

impl CouplingEstimate {
    /// `1 + a = 1 + (k_x - k_y) / 2` of the estimate (`a = (J_xy - J_z) / J_xy`).
    pub fn one_plus_a(&self) -> f64 {
        1.0 + 0.5 * (self.coefficients[0] - self.coefficients[1])
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
            self.memory.modelled = self.memory.previous.clone();
        }
        self.memory.mode = mode_index;
        if input.rotor_thrust_n.is_none() {
            // The actuator model: the previous command through the first-order lag.
            let keep = self.actuator_keep;
            for (a, &c) in self.memory.modelled.iter_mut().zip(&self.memory.previous) {
                *a = keep * *a + (1.0 - keep) * c;
            }
        }

        let rot: Matrix3<f64> = s.attitude.to_rotation_matrix().into_inner();
        let omega = input.gyro_rad_s.unwrap_or(s.omega_rad_s);
        let mut thrust_sample = [0.0; MAX_ACTUATORS];
        thrust_sample[..m].copy_from_slice(input.rotor_thrust_n.unwrap_or(&self.memory.modelled));
        let thrust_sample = &thrust_sample[..m];
        let n3z_true = rot[(2, 2)];
        let g = self.gravity_m_s2;
        let a_des = self.position_loop(t_s, s);
        let thrust_dir = Vector3::new(-a_des.x, -a_des.y, g - a_des.z);
        let z_des = thrust_dir / thrust_dir.norm();

        // Vertical acceleration sample (NED): measured, or its model from the filtered thrusts.
        let measured_vertical = input.specific_force_m_s2.map(|f| (rot * f).z + g);
        let single_axis = self.modes[mode_index].info.single_axis;
        let products = [omega.y * omega.z, omega.z * omega.x];
        if !self.memory.started {
            let start_vertical = measured_vertical.unwrap_or(0.0);
            let coupling = self.coupling(&omega, self.coupling_coefficients(single_axis));
            self.start(&omega, &coupling, thrust_sample, start_vertical, &z_des);
            self.memory.products = products.map(SecondOrderLowPass::settled);
        }
        let coupling = self.coupling(&omega, self.coupling_coefficients(single_axis));
        let nominal_coefficients = self.nominal_coefficients();
        let filter = self.filter;
        let mem = &mut self.memory;
        // The inertia coupling is known: taken at the current rate, its filtered value removed
        // from the filtered acceleration (module docs, step 4).
        let mut omega_dot_f = Vector3::zeros();
        let model_coupling = self.gains.model_coupling;
        for i in 0..3 {
            filter.step(&mut mem.gyro[i], omega[i]);
            filter.step(&mut mem.coupling[i], coupling[i]);
            omega_dot_f[i] = mem.gyro[i][1];
            if model_coupling {
                omega_dot_f[i] += coupling[i] - mem.coupling[i][0];
            }
        }
        for (state, &t) in mem.thrust.iter_mut().zip(thrust_sample) {
            filter.step(state, t);
        }
        for (state, &v) in mem.products.iter_mut().zip(&products) {
            filter.step(state, v);
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
        if single_axis {
            // The inertia coupling's estimate: the filtered angular acceleration less the rotors'
            // (both through the same filter) against the filtered regressor, per axis.
            let keep = (-self.dt_s / COUPLING_FORGETTING_S).exp();
            for i in 0..2 {
                let rotors: f64 = mode
                    .info
                    .healthy
                    .iter()
                    .zip(&mode.angular)
                    .map(|(&r, a)| a[i] * mem.thrust[r][0])
                    .sum();
                let phi = mem.products[i][0];
                let residual = mem.gyro[i][1] - rotors;
                let sums = &mut mem.coupling_sums[i];
                sums[0] = keep * sums[0] + phi * phi;
                sums[1] = keep * sums[1] + phi * residual;
            }
            // `a = (J_xy - J_z) / J_xy`: half the difference of the two coefficients.
            let [kx, ky] =
                estimated_coefficients(nominal_coefficients, &mem.coupling_sums, self.dt_s);
            let one_plus_a = 1.0 + 0.5 * (kx - ky);
            if one_plus_a.abs() > OUTPUT_FLIP_MARGIN {
                mem.output_flipped = one_plus_a * mode.one_plus_a < 0.0;
            }
        }
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
        if let Some(r) = self.relaxed.filter(|r| t_s >= r.time_s()) {
            if let (Some([a, b]), None) = (r.spin_axis_weaker_of(), mem.spin_axis_mirrored) {
                if t_s < r.flown_from_s() {
                    // Only measured thrusts tell a weak rotor: the actuator model's are the
                    // commands' own lag.
                    mem.spin_choice_unmeasured |= input.rotor_thrust_n.is_none();
                    for (sums, rotor) in mem.spin_choice_sums.iter_mut().zip([a, b]) {
                        sums[0] += thrust_sample[rotor];
                        sums[1] += mem.previous[rotor];
                    }
                } else {
                    // The lower produced / commanded ratio is the weaker rotor; ratios equal to
                    // within rounding, or a step without rotor samples, keep the axis as given.
                    let [pa, ca] = mem.spin_choice_sums[0];
                    let [pb, cb] = mem.spin_choice_sums[1];
                    mem.spin_axis_mirrored = Some(
                        !mem.spin_choice_unmeasured
                            && ca > 0.0
                            && cb > 0.0
                            && pb * ca < pa * cb * (1.0 - SPIN_AXIS_CHOICE_RTOL),
                    );
                }
            }
        }
        let relaxed = self.relaxed.filter(|r| t_s >= r.flown_from_s());
        let n = relaxed.map_or(mode.primary_axis, |r| {
            if mem.spin_axis_mirrored == Some(true) {
                r.mirrored_axis()
            } else {
                r.axis()
            }
        });
        let y = Vector2::new(h.x - n.x, h.y - n.y);
        let y_dot = h_dot.xy();
        let kinematic = (h_dot.cross(&omega) + lambda.cross(&omega) + rt * z_acc).xy();
        let gains = &self.gains;
        let nu_y = -y * gains.k_att_p - y_dot * gains.k_att_d;
        let b_att = nu_y - kinematic - h.cross(&omega_dot_f).xy();
        let (b_yaw, weights, saturated_weights) = match relaxed {
            // The spin-rate row on `n . omega'` (relaxed.rs), below thrust and attitude.
            Some(r) => {
                let spin = n.dot(&omega);
                let target = r.target(spin, &mut mem.spin_sign);
                let mut w = mode.weights;
                w[3] = gains.spin_weight;
                (gains.k_spin * (target - spin) - n.dot(&omega_dot_f), w, w)
            }
            None => (
                -gains.k_r * omega.z - omega_dot_f.z,
                mode.weights,
                mode.saturated_weights,
            ),
        };
        let b_z = a_des.z - vertical_f;

        // Step 4-5: G dT = b over the healthy rotors.
        let k = mode.info.healthy.len();
        let rows = if single_axis && mem.output_flipped {
            mode.rotation_flipped
        } else {
            mode.rotation
        };
        let mut g_rows = [[0.0; MAX_ACTUATORS]; 4];
        for (c, (a, &thrust_entry)) in mode.angular.iter().zip(&mode.thrust).enumerate() {
            let att = h.cross(a).xy();
            g_rows[0][c] = -n3z / self.mass_kg * thrust_entry;
            g_rows[1][c] = rows[0][0] * att.x + rows[0][1] * att.y;
            g_rows[2][c] = rows[1][0] * att.x + rows[1][1] * att.y;
            g_rows[3][c] = if relaxed.is_some() { n.dot(a) } else { a.z };
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
            &weights,
            &saturated_weights,
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

#[cfg(test)]
mod tests;
