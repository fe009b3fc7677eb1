//! Ke et al.'s uniform passive fault-tolerant controller (IEEE TIE, "uniform passive FTC of a
//! quadcopter with one, two or three rotor failures"): one controller, one set of gains, no fault
//! detection and no switching. It never reads rotor efficiency: faults reach it only through the
//! motion it measures.
//!
//! Per control step (equation numbers are Ke's):
//! 1. position loop (8)-(9): `v_d = k_p (p_d - p)`, `a_d = sat(K_v (v_d - v), a)`, desired primary
//!    axis `n3_d = -(a_d - g) / |a_d - g|`;
//! 2. desired virtual control (28) (= (14) plus `k_cp A_2 x~_2`) for thrust, roll and pitch, and
//!    the yaw-rate law (15) with `r_d = 0`;
//! 3. the virtual control the vehicle actually receives, from its motion (12):
//!    `u^_1 = B_2^-1 (x'_2 - A_2 x_2 - D_2)`, `tau^_r = J_z r' + (J_y - J_x) p q`, with the
//!    derivatives realised as `s / (eps s + 1)` and the other terms low-passed by
//!    `1 / (eps s + 1)` (13); the lumped-disturbance estimate is `d^ = LPF(M T) - u^`;
//! 4. the control command (18) `u_c = K_rotor (LPF(u_d) + d^ - LPF(M T))`, in which the two
//!    `LPF(M T)` terms cancel exactly: `u_c = K_rotor (LPF(u_d) - u^)`;
//! 5. the QP allocation (33) with the Table IV weights through the exact active-set solver
//!    (bounds `0 <= T_i <= T_max`: rotor saturation), warm-started every step.
//!
//! # The printed law and the remedy ([`CommandLaw`])
//! In steady state (18) gives `u_1 = k/(k+1) u_d1 - d_1/(k+1)` (Ke eq. (43)): even without a
//! fault a third of the hover thrust is missing at `k_rotor = 2`, which the position loop can only
//! make up with a large altitude offset. [`CommandLaw::Feedforward`] (the default) adds the
//! filtered desired virtual control, `u_c = LPF(u_d) + K_rotor (LPF(u_d) - u^)`: the steady state
//! becomes `u_1 = u_d1 - d_1/(k+1)` (no deficit without a fault, the same partial compensation
//! of a fault), and the closed-loop matrix of (25) is unchanged, `-(I + k_rotor N)`, so Ke's
//! stability argument (Table II) still holds. It uses no fault information. [`CommandLaw::Literal`]
//! is (18) as printed; [`CommandLaw::FullCompensation`] is Remark 5's (29)
//! `u_c = LPF(u_d) + d^` (unstable with two or three failures, eq. (32));
//! The remedy also closes an altitude integral in the position loop (`k_iz`, off in the paper's
//! gains): with a fault, partial compensation leaves `-d_1/(k+1)`, which a proportional position
//! loop can only hold with an altitude offset (about 13 m for one failed rotor at Table IV gains).
//! [`CommandLaw::Baseline`] is a conventional controller for comparison: `u_d` straight into the
//! pseudo-inverse, clipped to the rotor bounds (no estimation, no QP).
//!
//! # Discretisation (stated once)
//! Every filter runs at the control period `dt` with `a = exp(-dt / eps)`:
//! `y_k = a y_(k-1) + (1 - a) x_k` for `1 / (eps s + 1)` (step-invariant, input sampled at the end
//! of the period), and `(x_k - y_k) / eps` for `s / (eps s + 1) = (1 - 1/(eps s + 1)) / eps`.
//! At the first step every filter starts at its input (zero derivatives). `B_2^-1` uses the
//! current `n3z`, floored at [`MIN_N3Z`] (the law needs `n3z > 0`, Remark 3). `M T` uses the
//! previous step's commands (the algebraic loop of Section III-A).

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use crate::airframe::Airframe;
use crate::allocation::active_set::{ActiveSet, ActiveSetSolver};
use crate::allocation::{weighted_pseudo_inverse, AllocationProblem, WeightedPseudoInverse};
use crate::control::Controller;
use crate::error::{
    require_finite, require_non_negative, require_normal, require_scale, Result, RfError,
};
use crate::state::RigidBodyState;

/// Floor on `n3z` in `B_2^-1` (keeps the command finite when the vehicle tips past 87 degrees).
pub const MIN_N3Z: f64 = 0.05;
/// Largest vertical-speed command the remedy's altitude integral may add, m/s (anti-windup).
pub const ALTITUDE_INTEGRAL_LIMIT_M_S: f64 = 10.0;

/// Ke Table IV (plus `k_cp` of Remark 4): the controller's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeGains {
    /// Position gain, 1/s.
    pub k_p: f64,
    /// Horizontal velocity gain, 1/s.
    pub k_v: f64,
    /// Vertical velocity gain, 1/s (Theorem 1: > 0.5).
    pub k_vz: f64,
    /// Saturation `a` of the desired acceleration, m/s^2.
    pub accel_limit_m_s2: f64,
    /// Primary-axis gain (Theorem 1: > 0).
    pub k_n3: f64,
    /// Body-rate gain (Theorem 1: > 0.5).
    pub k_omega: f64,
    /// Yaw-rate gain of (15) (Table IV: 0.3 k_omega).
    pub k_r: f64,
    /// Gyroscopic-term gain of (28) (Remark 4: 0.6).
    pub k_cp: f64,
    /// Filter time constant, s.
    pub epsilon_s: f64,
    /// `k_rotor` of (16).
    pub k_rotor: f64,
    /// `k_rotor,z` of (17).
    pub k_rotor_z: f64,
    /// `W = diag(w_f, w_p, w_q, w_r)` of (33).
    pub weights: [f64; 4],
    /// Altitude integral gain of the remedy, 1/s^2 (not in the paper; 0 turns it off):
    /// `v_z,d = k_p e_z + k_iz int e_z dt` with the integral's contribution limited to
    /// [`ALTITUDE_INTEGRAL_LIMIT_M_S`]. Only [`CommandLaw::Feedforward`] uses it.
    #[serde(default)]
    pub k_iz: f64,
}

/// Table IV, HIL column, with the remedy's altitude integral `k_iz = 0.1`: the `ke-hil` preset
/// (a test ties the two) and the Python `KeGains` defaults (read from here).
impl Default for KeGains {
    fn default() -> Self {
        KeGains {
            k_p: 0.3,
            k_v: 0.1,
            k_vz: 1.0,
            accel_limit_m_s2: 0.15,
            k_n3: 3.0,
            k_omega: 14.0,
            k_r: 0.3 * 14.0,
            k_cp: 0.6,
            epsilon_s: 0.06,
            k_rotor: 2.0,
            k_rotor_z: 0.1,
            weights: [1.0, 20.0, 20.0, 0.01],
            k_iz: 0.1,
        }
    }
}

impl KeGains {
    /// Rejects gains the design excludes, naming the gain and the rule.
    pub fn check(&self) -> Result<()> {
        let positive = [
            ("k_p", self.k_p),
            ("k_v", self.k_v),
            ("accel_limit_m_s2", self.accel_limit_m_s2),
            ("k_n3", self.k_n3),
            ("epsilon_s", self.epsilon_s),
            ("k_rotor", self.k_rotor),
            ("k_rotor_z", self.k_rotor_z),
        ];
        for (field, value) in positive {
            require_finite(field, value)?;
            if value <= 0.0 {
                return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
            }
        }
        // The filter divides by it ((x - f) / eps, exp(-dt / eps)): a scale.
        require_scale("epsilon_s", self.epsilon_s, "s")?;
        for (field, value) in [("k_vz", self.k_vz), ("k_omega", self.k_omega)] {
            require_finite(field, value)?;
            if value <= 0.5 {
                return Err(RfError::invalid(
                    field,
                    format!("must be > 0.5 (Theorem 1), got {value}"),
                ));
            }
        }
        for (field, value) in [("k_r", self.k_r), ("k_cp", self.k_cp), ("k_iz", self.k_iz)] {
            require_finite(field, value)?;
            if value < 0.0 {
                return Err(RfError::invalid(
                    field,
                    format!("must be >= 0, got {value}"),
                ));
            }
        }
        for (i, &w) in self.weights.iter().enumerate() {
            require_normal(&format!("weights[{i}]"), w)?;
            if w < 0.0 || (i < 3 && w == 0.0) {
                return Err(RfError::invalid(
                    format!("weights[{i}]"),
                    format!(
                        "thrust, roll and pitch weights must be > 0 and the yaw weight >= 0, got {w}"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A controller preset file: gains plus the vehicle values Ke does not print (module docs of
/// `python/rotorfault/presets/ftc/README.md`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FtcPreset {
    pub name: String,
    pub description: String,
    pub source: String,
    /// Name of the airframe preset the gains were designed for.
    pub airframe: String,
    pub gains: KeGains,
    pub vehicle: FtcVehicle,
}

/// Simulation values that go with a controller preset.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FtcVehicle {
    /// Rotor first-order lag (Ke Table III: 0.025 s).
    pub rotor_time_constant_s: f64,
    /// Linear rotational damping `k_r` (N m s): not in the paper; sets the steady spin rate.
    pub rotational_drag_n_m_s: f64,
    /// Linear translational drag `k_t` (N s/m): not in the paper (an outdoor vehicle's rotor
    /// drag); it decides how far the failure transient carries the vehicle.
    pub linear_drag_n_s_m: f64,
}

impl FtcPreset {
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let preset: FtcPreset = toml::from_str(text).map_err(|e| RfError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        preset.check()?;
        Ok(preset)
    }

    /// The gains' rules and the vehicle values non-negative (a file read, or a preset made in
    /// Python: one rule, one message).
    pub fn check(&self) -> Result<()> {
        self.gains.check()?;
        let v = &self.vehicle;
        for (field, value) in [
            ("vehicle.rotor_time_constant_s", v.rotor_time_constant_s),
            ("vehicle.rotational_drag_n_m_s", v.rotational_drag_n_m_s),
            ("vehicle.linear_drag_n_s_m", v.linear_drag_n_s_m),
        ] {
            require_non_negative(field, value)?;
        }
        Ok(())
    }
}

/// Which control command the controller forms (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum CommandLaw {
    /// `u_c = LPF(u_d) + K_rotor (LPF(u_d) - u^)`: the documented remedy (default).
    #[default]
    Feedforward,
    /// Ke eq. (18) as printed.
    Literal,
    /// Ke eq. (29), Remark 5: full compensation `u_c = LPF(u_d) + d^`.
    FullCompensation,
    /// Conventional: `T = clip(M^+ u_d)`, no estimation, no QP.
    Baseline,
}

impl CommandLaw {
    pub fn parse(text: &str) -> Result<Self> {
        match text {
            "feedforward" => Ok(CommandLaw::Feedforward),
            "literal" => Ok(CommandLaw::Literal),
            "full-compensation" => Ok(CommandLaw::FullCompensation),
            "baseline" => Ok(CommandLaw::Baseline),
            other => Err(RfError::invalid(
                "law",
                format!(
                    "expected \"feedforward\", \"literal\", \"full-compensation\" or \"baseline\", got {other:?}"
                ),
            )),
        }
    }
}

/// One step of `1 / (eps s + 1)` (module docs), `a = exp(-dt / eps)`.
fn low_pass(state: &mut f64, input: f64, a: f64) {
    *state = a * *state + (1.0 - a) * input;
}

/// The filter states (module docs), reset at the start of every run.
#[derive(Debug, Clone, Default)]
struct Filters {
    started: bool,
    x2: [f64; 3],
    r: f64,
    a2x2: [f64; 3],
    pq: f64,
    u_d: [f64; 4],
    mt: [f64; 4],
    /// Commands of the previous step (`M T` in the estimate).
    previous: [f64; 4],
    /// `k_iz int e_z dt` of the remedy, m/s.
    altitude_integral: f64,
}

/// The controller (module docs). Quadcopters only: four rotors, virtual control
/// `[f, tau_p, tau_q, tau_r]`.
#[derive(Debug, Clone)]
pub struct UniformPassiveFtc {
    gains: KeGains,
    law: CommandLaw,
    dt_s: f64,
    mass_kg: f64,
    inertia_kg_m2: [f64; 3],
    gravity_m_s2: f64,
    /// Nominal effectiveness (efficiency never used), 4 x 4 row-major.
    matrix: [[f64; 4]; 4],
    setpoints: Vec<(f64, Vector3<f64>)>,
    solver: ActiveSetSolver,
    pinv: WeightedPseudoInverse,
    active: ActiveSet,
    filters: Filters,
}

impl UniformPassiveFtc {
    /// `setpoints`: `(time_s, position NED m)` held from their time on (the first also before);
    /// `dt_s` the control period the simulator calls it at.
    pub fn new(
        airframe: &Airframe,
        gains: KeGains,
        law: CommandLaw,
        setpoints: Vec<(f64, [f64; 3])>,
        dt_s: f64,
    ) -> Result<Self> {
        gains.check()?;
        if airframe.rotor_count() != 4 {
            return Err(RfError::invalid(
                "airframe",
                format!(
                    "Ke's controller is for quadcopters (4 rotors), got {}",
                    airframe.rotor_count()
                ),
            ));
        }
        require_finite("dt_s", dt_s)?;
        if dt_s <= 0.0 {
            return Err(RfError::invalid("dt_s", format!("must be > 0, got {dt_s}")));
        }
        require_scale("dt_s", dt_s, "s")?;
        if setpoints.is_empty() {
            return Err(RfError::invalid(
                "setpoints",
                "must hold at least one position",
            ));
        }
        for (k, (t, p)) in setpoints.iter().enumerate() {
            require_finite(&format!("setpoints[{k}].time"), *t)?;
            for v in p {
                require_finite(&format!("setpoints[{k}].position"), *v)?;
            }
            if k > 0 && *t <= setpoints[k - 1].0 {
                return Err(RfError::invalid(
                    format!("setpoints[{k}].time"),
                    "times must be strictly increasing",
                ));
            }
        }
        let nominal = airframe.nominal_effectiveness_matrix();
        let problem = AllocationProblem::new(
            nominal.clone(),
            &gains.weights,
            &airframe.min_thrust_n(),
            &airframe.max_thrust_n(),
        )?;
        let unweighted = AllocationProblem::new(
            nominal.clone(),
            &[1.0; 4],
            &airframe.min_thrust_n(),
            &airframe.max_thrust_n(),
        )?;
        let mut matrix = [[0.0; 4]; 4];
        for (r, row) in matrix.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = nominal[(r, c)];
            }
        }
        Ok(UniformPassiveFtc {
            gains,
            law,
            dt_s,
            mass_kg: airframe.mass_kg(),
            inertia_kg_m2: airframe.inertia_kg_m2(),
            gravity_m_s2: airframe.gravity_m_s2(),
            matrix,
            setpoints: setpoints
                .into_iter()
                .map(|(t, p)| (t, Vector3::from(p)))
                .collect(),
            solver: ActiveSetSolver::new(&problem),
            pinv: weighted_pseudo_inverse(&unweighted),
            active: ActiveSet::cold(4),
            filters: Filters::default(),
        })
    }

    fn setpoint(&self, t_s: f64) -> Vector3<f64> {
        let k = self
            .setpoints
            .partition_point(|(t, _)| *t <= t_s)
            .saturating_sub(1);
        self.setpoints[k].1
    }

    /// The desired virtual control ((8)-(9), (28), (15)) and the pieces the estimator needs.
    fn desired(&self, setpoint: &Vector3<f64>, s: &RigidBodyState) -> Desired {
        let g = &self.gains;
        let [jx, jy, jz] = self.inertia_kg_m2;
        let rot: Matrix3<f64> = s.attitude.to_rotation_matrix().into_inner();
        let (a, b, c, d) = (rot[(0, 0)], rot[(1, 0)], rot[(0, 1)], rot[(1, 1)]);
        let n3 = rot.column(2);
        let (p, q, r) = (s.omega_rad_s.x, s.omega_rad_s.y, s.omega_rad_s.z);

        // (8)-(9), plus the remedy's altitude integral
        let mut v_d = g.k_p * (setpoint - s.position_m);
        if self.law == CommandLaw::Feedforward {
            v_d.z += self.filters.altitude_integral;
        }
        let dv = v_d - s.velocity_m_s;
        let mut a_d = Vector3::new(g.k_v * dv.x, g.k_v * dv.y, g.k_vz * dv.z);
        let norm = a_d.norm();
        if norm > g.accel_limit_m_s2 {
            a_d *= g.accel_limit_m_s2 / norm;
        }
        let gravity = Vector3::new(0.0, 0.0, self.gravity_m_s2);
        let n3_d = -(a_d - gravity) / (a_d - gravity).norm();

        // (28)
        let x1t = [n3.x - n3_d.x, n3.y - n3_d.y];
        let x2 = [s.velocity_m_s.z, p, q];
        let k_mat = [[0.0, 0.0], [-b, a], [-d, c]];
        let x2_d = [
            v_d.z,
            g.k_n3 * (k_mat[1][0] * x1t[0] + k_mat[1][1] * x1t[1]),
            g.k_n3 * (k_mat[2][0] * x1t[0] + k_mat[2][1] * x1t[1]),
        ];
        let x2t = [x2[0] - x2_d[0], x2[1] - x2_d[1], x2[2] - x2_d[2]];
        let a12 = -(jz - jy) / jx * r;
        let a21 = -(jx - jz) / jy * r;
        let a2x2 = [0.0, a12 * x2[2], a21 * x2[1]];
        let a2x2t = [0.0, a12 * x2t[2], a21 * x2t[1]];
        // A_1^T - K' (3 x 2), with A' = C r - q n3x, B' = D r - q n3y, C' = -A r + p n3x,
        // D' = -B r + p n3y.
        let (da, db) = (c * r - q * n3.x, d * r - q * n3.y);
        let (dc, dd) = (-a * r + p * n3.x, -b * r + p * n3.y);
        let a1t_minus_kdot = [
            [0.0, 0.0],
            [-c + g.k_n3 * db, -d - g.k_n3 * da],
            [a + g.k_n3 * dd, b - g.k_n3 * dc],
        ];
        let g3 = -n3.z * g.k_n3;
        let k2 = [g.k_vz, g.k_omega, g.k_omega];
        let d2 = [self.gravity_m_s2, 0.0, 0.0];
        let g3x2 = [0.0, g3 * x2[1], g3 * x2[2]];
        let mut inner = [0.0; 3];
        for i in 0..3 {
            inner[i] = -k2[i] * x2t[i]
                - a2x2[i]
                - d2[i]
                - (a1t_minus_kdot[i][0] * x1t[0] + a1t_minus_kdot[i][1] * x1t[1])
                + g3x2[i]
                + g.k_cp * a2x2t[i];
        }
        let b2_inverse = [-self.mass_kg / n3.z.max(MIN_N3Z), jx, jy];
        // (15) with r_d = 0
        let tau_r_d = -jz * g.k_r * r;
        Desired {
            u_d: [
                b2_inverse[0] * inner[0],
                b2_inverse[1] * inner[1],
                b2_inverse[2] * inner[2],
                tau_r_d,
            ],
            x2,
            a2x2,
            b2_inverse,
        }
    }

    fn produced(&self, t: &[f64; 4]) -> [f64; 4] {
        let mut out = [0.0; 4];
        for (row, o) in self.matrix.iter().zip(out.iter_mut()) {
            *o = row.iter().zip(t).map(|(m, x)| m * x).sum();
        }
        out
    }
}

/// What [`UniformPassiveFtc::desired`] computes in one control step.
struct Desired {
    /// The desired virtual control `u_d = [f_d, tau_p,d, tau_q,d, tau_r,d]`.
    u_d: [f64; 4],
    /// `x_2 = [v_z, p, q]`.
    x2: [f64; 3],
    /// `A_2 x_2`.
    a2x2: [f64; 3],
    /// The diagonal of `B_2^-1` (with the current `n3z`, floored).
    b2_inverse: [f64; 3],
}

impl Controller for UniformPassiveFtc {
    fn command_count(&self) -> usize {
        4
    }

    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        // A non-finite sample would poison every filter for good: refuse it (the simulator stops
        // at a non-finite state before calling the controller).
        if !measured.is_finite() || !t_s.is_finite() {
            return Err(RfError::invalid(
                "measured",
                format!("the state at t = {t_s} s must be finite"),
            ));
        }
        let setpoint = self.setpoint(t_s);
        let Desired {
            u_d,
            x2,
            a2x2,
            b2_inverse,
        } = self.desired(&setpoint, measured);
        if self.law == CommandLaw::Feedforward && self.gains.k_iz > 0.0 {
            // Forward Euler over the control period, after use (the integral lags one step).
            let e_z = setpoint.z - measured.position_m.z;
            self.filters.altitude_integral = (self.filters.altitude_integral
                + self.gains.k_iz * e_z * self.dt_s)
                .clamp(-ALTITUDE_INTEGRAL_LIMIT_M_S, ALTITUDE_INTEGRAL_LIMIT_M_S);
        }
        if self.law == CommandLaw::Baseline {
            let problem = self.solver.problem();
            self.pinv.apply(&u_d, &mut out[..4]);
            for (t, (lo, hi)) in out[..4]
                .iter_mut()
                .zip(problem.lower().iter().zip(problem.upper()))
            {
                *t = t.clamp(*lo, *hi);
            }
            return Ok(());
        }
        let [jx, jy, jz] = self.inertia_kg_m2;
        let (p, q, r) = (
            measured.omega_rad_s.x,
            measured.omega_rad_s.y,
            measured.omega_rad_s.z,
        );
        if !self.filters.started {
            let f = &mut self.filters;
            f.started = true;
            f.x2 = x2;
            f.r = r;
            f.a2x2 = a2x2;
            f.pq = p * q;
            f.u_d = u_d;
            // The first M T: what the allocation of u_d would command (a settled start).
            let mut active = ActiveSet::cold(4);
            let mut first = [0.0; 4];
            self.solver.solve_unchecked(&u_d, &mut active, &mut first);
            self.filters.previous = first;
            self.filters.mt = self.produced(&first);
        }
        let a = (-self.dt_s / self.gains.epsilon_s).exp();
        let lpf = |y: &mut f64, x: f64| low_pass(y, x, a);
        let produced = self.produced(&self.filters.previous);
        let f = &mut self.filters;
        let mut derivative = [0.0; 3];
        for i in 0..3 {
            lpf(&mut f.x2[i], x2[i]);
            derivative[i] = (x2[i] - f.x2[i]) / self.gains.epsilon_s;
            lpf(&mut f.a2x2[i], a2x2[i]);
        }
        lpf(&mut f.r, r);
        let r_dot = (r - f.r) / self.gains.epsilon_s;
        lpf(&mut f.pq, p * q);
        for i in 0..4 {
            lpf(&mut f.u_d[i], u_d[i]);
            lpf(&mut f.mt[i], produced[i]);
        }
        // (12)-(13): the virtual control the vehicle receives, estimated from its motion.
        let mut received = [0.0; 4];
        let d2 = [self.gravity_m_s2, 0.0, 0.0];
        for i in 0..3 {
            received[i] = b2_inverse[i] * (derivative[i] - f.a2x2[i] - d2[i]);
        }
        received[3] = jz * r_dot + (jy - jx) * f.pq;
        let k = [
            self.gains.k_rotor,
            self.gains.k_rotor,
            self.gains.k_rotor,
            self.gains.k_rotor_z,
        ];
        let mut u_c = [0.0; 4];
        for i in 0..4 {
            let estimate = f.mt[i] - received[i]; // d^ of (13)
            u_c[i] = match self.law {
                CommandLaw::Literal => k[i] * (f.u_d[i] + estimate - f.mt[i]),
                CommandLaw::Feedforward => f.u_d[i] + k[i] * (f.u_d[i] + estimate - f.mt[i]),
                CommandLaw::FullCompensation => f.u_d[i] + estimate,
                CommandLaw::Baseline => u_d[i],
            };
        }
        let mut t = [0.0; 4];
        if u_c.iter().all(|v| v.is_finite()) {
            self.solver.solve_unchecked(&u_c, &mut self.active, &mut t);
        } else {
            t = [f64::NAN; 4];
        }
        self.filters.previous = t;
        out[..4].copy_from_slice(&t);
        Ok(())
    }

    fn reset(&mut self) {
        self.filters = Filters::default();
        self.active = ActiveSet::cold(4);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn ke() -> Airframe {
        crate::fixtures::preset("ke-quadcopter")
    }

    #[test]
    fn low_pass_matches_the_continuous_step_response_at_the_samples() {
        // Input held at 1 from t = 0: the continuous filter gives 1 - exp(-t / eps); the
        // discretisation is exact at every sample (step invariance).
        let (dt, eps) = (1.0 / 400.0, 0.06);
        let a = f64::exp(-dt / eps);
        let mut y = 0.0;
        for k in 1..=400 {
            low_pass(&mut y, 1.0, a);
            let exact = 1.0 - f64::exp(-(k as f64) * dt / eps);
            assert!((y - exact).abs() < 1e-14, "{k}: {y} vs {exact}");
        }
    }

    #[test]
    fn hover_at_the_setpoint_commands_the_hover_thrusts() {
        let airframe = ke();
        let weight = airframe.mass_kg() * airframe.gravity_m_s2();
        for law in [
            CommandLaw::Feedforward,
            CommandLaw::FullCompensation,
            CommandLaw::Baseline,
        ] {
            let mut c = UniformPassiveFtc::new(
                &airframe,
                KeGains::default(),
                law,
                vec![(0.0, [0.0, 0.0, -10.0])],
                1.0 / 400.0,
            )
            .unwrap();
            let hover = RigidBodyState {
                position_m: Vector3::new(0.0, 0.0, -10.0),
                velocity_m_s: Vector3::zeros(),
                attitude: UnitQuaternion::identity(),
                omega_rad_s: Vector3::zeros(),
            };
            let mut out = [0.0; 4];
            for k in 0..10 {
                c.command(k as f64 / 400.0, &hover, &mut out).unwrap();
                // 1e-10 N: the QP's normal equations carry w_r c^2 = 2.8e-6 next to w_f = 1,
                // which costs about five of the sixteen digits.
                for t in out {
                    assert!((t - weight / 4.0).abs() < 1e-10, "{law:?}: {out:?}");
                }
            }
        }
    }

    #[test]
    fn a_non_finite_measurement_is_an_error_not_a_poisoned_filter() {
        let airframe = ke();
        let mut c = UniformPassiveFtc::new(
            &airframe,
            KeGains::default(),
            CommandLaw::default(),
            vec![(0.0, [0.0, 0.0, -10.0])],
            0.0025,
        )
        .unwrap();
        let mut state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, -10.0),
            velocity_m_s: Vector3::zeros(),
            attitude: UnitQuaternion::identity(),
            omega_rad_s: Vector3::zeros(),
        };
        let mut out = [0.0; 4];
        c.command(0.0, &state, &mut out).unwrap();
        let good = out;
        state.velocity_m_s.x = f64::NAN;
        let err = c.command(0.0025, &state, &mut out).unwrap_err();
        assert!(err.to_string().starts_with("measured"), "{err}");
        state.velocity_m_s.x = 0.0;
        c.command(0.005, &state, &mut out).unwrap();
        for (a, b) in out.iter().zip(good) {
            assert!((a - b).abs() < 1e-10);
        }
    }

    #[test]
    fn bad_gains_and_airframes_are_rejected() {
        let airframe = ke();
        let mut gains = KeGains::default();
        gains.epsilon_s = 0.0;
        let err = UniformPassiveFtc::new(
            &airframe,
            gains,
            CommandLaw::default(),
            vec![(0.0, [0.0; 3])],
            0.0025,
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("epsilon_s"), "{err}");
        let err = UniformPassiveFtc::new(
            &airframe,
            KeGains::default(),
            CommandLaw::default(),
            vec![],
            0.0025,
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("setpoints"), "{err}");
    }

    #[test]
    fn the_ke_hil_preset_holds_the_default_gains() {
        let preset =
            FtcPreset::from_toml_str(&crate::fixtures::preset_text("ftc/ke-hil.toml"), "ke-hil")
                .unwrap();
        assert_eq!(preset.gains, KeGains::default());
    }
}
