//! Lanzon, Freddi and Longhi (JGCD 2014): a quadrotor with rotor 2 failed, flown spinning about
//! its thrust axis. One controller, designed in Python (`rotorfault.control.lanzon`) and run here:
//!
//! 1. the measured state in the paper's z-up frames (the `lanzon-quadrotor` preset: rotor 1
//!    front, 2 right, 3 rear, 4 left in FRD; `phi = roll`, `theta = -pitch`, `psi = -yaw`,
//!    `(p, q, r) -> (p, -q, -r)`, position and velocity `(x, -y, -z)`);
//! 2. with an outer loop, the set points of (28)-(31): PD laws give the Earth-frame accelerations
//!    `z~1, z~2` (horizontal) and `u~3 = g + (k_t / m) z' + a_z` (vertical); the yaw-synchronised
//!    rotation (31) `[u~1; u~2] = [[S, C], [-C, S]]^T [z~1; z~2]` (eq. (32) reads `z~1, z~2`);
//!    then (29b): `r_d = u~3 d m / k_r`, `phi_d = u~1 / u~3`, `theta_d = u~2 / u~3`, with the tilt
//!    set points limited to `max_tilt_rad` and `u~3` to `g +- max_vertical_accel_m_s2`;
//!    without one, fixed set points (Scenario A);
//! 3. the discretised loop-shaping controller on the errors `[phi_d - phi, theta_d - theta,
//!    r_d - r]`: `v = C xi + D e`, `xi+ = A xi + B e`;
//! 4. the robust feedback linearisation (20)-(21) in closed form (derivation in the Python module):
//!    `u^ = alpha(x^) + beta(x^) v` with `alpha = M^-1 (-b + L T^-1 phi_c)`, `beta = M^-1 M(0)`;
//! 5. `u = u^ + [m g, 0, m g d]` and the rotor thrusts by eq. (9), rotor 2 commanded to zero.
//!
//! `cos(phi)` and `cos(theta)` are floored at [`MIN_COS`] in magnitude so that the law stays
//! finite near +-90 degrees (the paper restricts both angles to (-pi/2, pi/2)). Commands are not
//! clipped: the actuators saturate and rate-limit them.

use nalgebra::{DMatrix, DVector, Matrix3, Schur, Vector3};

use super::integral::PositionIntegral;
use super::{require_shaped_finite, Controller};
use crate::error::{
    require_all_finite, require_finite, require_non_negative, require_scale, Result, RfError,
};
use crate::state::{state_vector, RigidBodyState};

/// Floor on `|cos(phi)|`, `|cos(theta)|` in the linearising law.
pub const MIN_COS: f64 = 1e-3;
/// Number of rotor commands (a quadrotor).
pub const ROTORS: usize = 4;

/// The control model's parameters (Lanzon Table 1 plus `k_r`, `k_t`, which the paper omits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LanzonModel {
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
    /// `I_xx = I_yy`, kg m^2.
    pub inertia_xx_kg_m2: f64,
    pub inertia_zz_kg_m2: f64,
    pub arm_length_m: f64,
    /// `d`, m.
    pub drag_torque_ratio_m: f64,
    /// `k_r`, N m s.
    pub rotational_drag_n_m_s: f64,
    /// `k_t`, N s/m.
    pub linear_drag_n_s_m: f64,
}

/// Table 1 with `k_r = m g d / 2.7` (Table 2's spin) and `k_t = 0.1`.
impl Default for LanzonModel {
    fn default() -> Self {
        LanzonModel {
            mass_kg: 0.5,
            gravity_m_s2: 9.81,
            inertia_xx_kg_m2: 5.9e-3,
            inertia_zz_kg_m2: 1.16e-3,
            arm_length_m: 0.255,
            drag_torque_ratio_m: 2.4e-3,
            rotational_drag_n_m_s: 0.5 * 9.81 * 2.4e-3 / 2.7,
            linear_drag_n_s_m: 0.1,
        }
    }
}

/// The whole vehicle of the paper's design (`rotorfault.control.lanzon.LanzonVehicle`): the
/// control model plus the verification model's values the controller never reads (they go to the
/// simulator's airframe, actuator and drag). Checked here, once, when the vehicle is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LanzonVehicle {
    pub model: LanzonModel,
    /// `I_R`, kg m^2 (gyroscopic moment (5)); 0 for none.
    pub rotor_inertia_kg_m2: f64,
    /// `k_f` in `f = k_f omega^2`, N s^2; 0 for none.
    pub thrust_coefficient_n_s2: f64,
    pub max_thrust_n: f64,
    pub rate_limit_n_s: f64,
}

/// The paper's vehicle (Table 1, [`LanzonModel::default`]) with the verification model's values
/// the paper does not give: `I_R` 3e-5 kg m^2 (a 10-inch propeller with its motor bell), `k_f`
/// 1e-5 N s^2 (5 N at 707 rad/s), thrust limit 5 N, rate limit 50 N/s (Section II.B). The one
/// source of these defaults (Python reads them through the bindings).
impl Default for LanzonVehicle {
    fn default() -> Self {
        LanzonVehicle {
            model: LanzonModel::default(),
            rotor_inertia_kg_m2: 3e-5,
            thrust_coefficient_n_s2: 1e-5,
            max_thrust_n: 5.0,
            rate_limit_n_s: 50.0,
        }
    }
}

impl LanzonVehicle {
    /// The model's rules ([`LanzonModel::check_as`]), thrust and rate limits finite and > 0,
    /// `I_R` and `k_f` finite and >= 0; errors name `vehicle.<field>`.
    pub fn check(&self) -> Result<()> {
        self.model.check_as("vehicle")?;
        for (field, value) in [
            ("vehicle.max_thrust_n", self.max_thrust_n),
            ("vehicle.rate_limit_n_s", self.rate_limit_n_s),
        ] {
            require_finite(field, value)?;
            if value <= 0.0 {
                return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
            }
        }
        require_non_negative("vehicle.rotor_inertia_kg_m2", self.rotor_inertia_kg_m2)?;
        require_non_negative(
            "vehicle.thrust_coefficient_n_s2",
            self.thrust_coefficient_n_s2,
        )
    }
}

impl LanzonModel {
    /// Every parameter finite and positive (`k_t` may be zero); errors name `model.<field>`.
    pub fn check(&self) -> Result<()> {
        self.check_as("model")
    }

    /// [`LanzonModel::check`] with errors naming `<prefix>.<field>` (the object the caller made:
    /// [`LanzonVehicle::check`] names `vehicle.<field>`).
    pub fn check_as(&self, prefix: &str) -> Result<()> {
        // Every one is divided by in the law (eq. (9), (20)-(24), r0 = m g d / k_r): scales.
        for (field, value, unit) in [
            ("mass_kg", self.mass_kg, "kg"),
            ("gravity_m_s2", self.gravity_m_s2, "m/s^2"),
            ("inertia_xx_kg_m2", self.inertia_xx_kg_m2, "kg m^2"),
            ("inertia_zz_kg_m2", self.inertia_zz_kg_m2, "kg m^2"),
            ("arm_length_m", self.arm_length_m, "m"),
            ("drag_torque_ratio_m", self.drag_torque_ratio_m, "m"),
            ("rotational_drag_n_m_s", self.rotational_drag_n_m_s, "N m s"),
        ] {
            require_scale(&format!("{prefix}.{field}"), value, unit)?;
        }
        require_non_negative(
            &format!("{prefix}.linear_drag_n_s_m"),
            self.linear_drag_n_s_m,
        )
    }

    /// `r0 = m g d / k_r`: the spin of the working point, rad/s.
    pub fn spin_rate_rad_s(&self) -> f64 {
        self.mass_kg * self.gravity_m_s2 * self.drag_torque_ratio_m / self.rotational_drag_n_m_s
    }

    /// `f(x^)` of (24), hat coordinates `[phi, theta, p, q, r - r0]`.
    pub fn drift(&self, x: &[f64; 5]) -> [f64; 5] {
        let (ixx, izz, kr) = (
            self.inertia_xx_kg_m2,
            self.inertia_zz_kg_m2,
            self.rotational_drag_n_m_s,
        );
        let [phi, theta, p, q, dr] = *x;
        let r = dr + self.spin_rate_rad_s();
        let (sf, cf) = phi.sin_cos();
        let tt = theta.sin() / floor_cos(theta.cos());
        [
            p + q * sf * tt + r * cf * tt,
            q * cf - r * sf,
            (-kr * p - q * r * (izz - ixx)) / ixx,
            (-kr * q - p * r * (ixx - izz)) / ixx,
            -kr * dr / izz,
        ]
    }

    /// `M(x^)` of eq. (25).
    pub fn decoupling_matrix(&self, phi: f64, theta: f64) -> Matrix3<f64> {
        let (ixx, izz, l, d) = (
            self.inertia_xx_kg_m2,
            self.inertia_zz_kg_m2,
            self.arm_length_m,
            self.drag_torque_ratio_m,
        );
        let (sf, cf) = phi.sin_cos();
        let tt = theta.sin() / floor_cos(theta.cos());
        Matrix3::new(
            l / (2.0 * ixx),
            sf * tt / ixx,
            cf * tt / izz - l / (2.0 * d * ixx),
            0.0,
            cf / ixx,
            -sf / izz,
            0.0,
            0.0,
            1.0 / izz,
        )
    }

    /// `phi_c(x^) = [phi, phi', theta, theta', r - r0]` and `b(x^) = [L_f^2 h1, L_f^2 h2, L_f h3]`.
    pub fn brunovsky_and_lie(&self, x: &[f64; 5]) -> ([f64; 5], Vector3<f64>) {
        let f = self.drift(x);
        let [phi, theta, _, q, dr] = *x;
        let r = dr + self.spin_rate_rad_s();
        let (sf, cf) = phi.sin_cos();
        let ct = floor_cos(theta.cos());
        let tt = theta.sin() / ct;
        let da1_dphi = q * cf * tt - r * sf * tt;
        let da1_dtheta = (q * sf + r * cf) / (ct * ct);
        let b1 = da1_dphi * f[0] + da1_dtheta * f[1] + f[2] + sf * tt * f[3] + cf * tt * f[4];
        let b2 = (-q * sf - r * cf) * f[0] + cf * f[3] - sf * f[4];
        ([phi, f[0], theta, f[1], dr], Vector3::new(b1, b2, f[4]))
    }

    /// `L T^-1` (3 x 5) of (21a): rows 2, 4, 5 of `T A_r`, times `T^-1`.
    fn l_t_inv(&self) -> DMatrix<f64> {
        let (ixx, izz, kr) = (
            self.inertia_xx_kg_m2,
            self.inertia_zz_kg_m2,
            self.rotational_drag_n_m_s,
        );
        let r0 = self.spin_rate_rad_s();
        let c = r0 * (ixx - izz) / ixx;
        #[rustfmt::skip]
        let a = DMatrix::from_row_slice(5, 5, &[
            0.0, r0, 1.0, 0.0, 0.0,
            -r0, 0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, -kr / ixx, c, 0.0,
            0.0, 0.0, -c, -kr / ixx, 0.0,
            0.0, 0.0, 0.0, 0.0, -kr / izz,
        ]);
        #[rustfmt::skip]
        let t = DMatrix::from_row_slice(5, 5, &[
            1.0, 0.0, 0.0, 0.0, 0.0,
            0.0, r0, 1.0, 0.0, 0.0,
            0.0, 1.0, 0.0, 0.0, 0.0,
            -r0, 0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 1.0,
        ]);
        // T is a permutation with a shear: invertible for every r0.
        let t_inv = t
            .clone()
            .try_inverse()
            .unwrap_or_else(|| DMatrix::identity(5, 5));
        let ta = &t * a;
        let mut l = DMatrix::zeros(3, 5);
        for (row, src) in [1usize, 3, 4].iter().enumerate() {
            l.set_row(row, &ta.row(*src));
        }
        l * t_inv
    }
}

fn floor_cos(c: f64) -> f64 {
    if c.abs() >= MIN_COS {
        c
    } else if c < 0.0 {
        -MIN_COS
    } else {
        MIN_COS
    }
}

/// The gentle PD outer loop of (28)-(31); the paper leaves the linear laws open. With `k_i_xy`
/// or `k_i_z` above 0 (not the paper's: it has no integral action, the default) the laws become
/// PID: the integral of the position error, each axis clamped to `integral_limit_m_s`, removes
/// the steady error a constant disturbance or a model error (mass, thrust) leaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LanzonOuterLoop {
    /// Horizontal position gain, 1/s^2.
    pub k_p_xy: f64,
    /// Horizontal velocity gain, 1/s.
    pub k_d_xy: f64,
    /// Altitude gain, 1/s^2.
    pub k_p_z: f64,
    /// Climb-rate gain, 1/s.
    pub k_d_z: f64,
    /// Limit on the roll and pitch set points, rad.
    pub max_tilt_rad: f64,
    /// Limit on the commanded vertical acceleration, m/s^2.
    pub max_vertical_accel_m_s2: f64,
    /// Horizontal position-integral gain, 1/s^3 (0: the paper's PD law).
    pub k_i_xy: f64,
    /// Altitude-integral gain, 1/s^3 (0: the paper's PD law).
    pub k_i_z: f64,
    /// Limit on each axis's position-error integral (anti-windup), m s.
    pub integral_limit_m_s: f64,
}

impl Default for LanzonOuterLoop {
    fn default() -> Self {
        LanzonOuterLoop {
            k_p_xy: 0.25,
            k_d_xy: 0.7,
            k_p_z: 0.5,
            k_d_z: 1.0,
            max_tilt_rad: 0.1,
            max_vertical_accel_m_s2: 3.0,
            k_i_xy: 0.0,
            k_i_z: 0.0,
            integral_limit_m_s: 10.0,
        }
    }
}

impl LanzonOuterLoop {
    pub fn check(&self) -> Result<()> {
        for (field, value) in [
            ("outer_loop.k_p_xy", self.k_p_xy),
            ("outer_loop.k_d_xy", self.k_d_xy),
            ("outer_loop.k_p_z", self.k_p_z),
            ("outer_loop.k_d_z", self.k_d_z),
            ("outer_loop.k_i_xy", self.k_i_xy),
            ("outer_loop.k_i_z", self.k_i_z),
        ] {
            require_finite(field, value)?;
            if value < 0.0 {
                return Err(RfError::invalid(
                    field,
                    format!("must be >= 0, got {value}"),
                ));
            }
        }
        require_finite("outer_loop.max_tilt_rad", self.max_tilt_rad)?;
        if !(self.max_tilt_rad > 0.0 && self.max_tilt_rad < std::f64::consts::FRAC_PI_2) {
            return Err(RfError::invalid(
                "outer_loop.max_tilt_rad",
                format!("must be in (0, pi/2), got {}", self.max_tilt_rad),
            ));
        }
        require_finite(
            "outer_loop.max_vertical_accel_m_s2",
            self.max_vertical_accel_m_s2,
        )?;
        if self.max_vertical_accel_m_s2 <= 0.0 {
            return Err(RfError::invalid(
                "outer_loop.max_vertical_accel_m_s2",
                format!("must be > 0, got {}", self.max_vertical_accel_m_s2),
            ));
        }
        require_finite("outer_loop.integral_limit_m_s", self.integral_limit_m_s)?;
        if self.integral_limit_m_s <= 0.0 {
            return Err(RfError::invalid(
                "outer_loop.integral_limit_m_s",
                format!("must be > 0, got {}", self.integral_limit_m_s),
            ));
        }
        Ok(())
    }
}

/// Where the inner loop's set points come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LanzonReference {
    /// Fixed `[phi_d, theta_d, r_d]` (paper frame, rad and rad/s): Scenario A.
    Attitude([f64; 3]),
    /// The outer loop to a position (world NED, m): Scenario B.
    Position {
        position_ned_m: [f64; 3],
        gains: LanzonOuterLoop,
    },
}

/// The inner loop's discrete loop-shaping controller `xi+ = A xi + B e`, `v = C xi + D e`
/// (3 errors in, 3 linear inputs out).
#[derive(Debug, Clone)]
pub struct DiscreteController {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub d: DMatrix<f64>,
}

impl DiscreteController {
    /// Sizes, finite entries and a stable `A` (spectral radius below 1), each error naming
    /// `A_K`, `B_K`, `C_K` or `D_K`.
    pub fn check(&self) -> Result<()> {
        let n = self.a.nrows();
        require_shaped_finite([
            ("A_K", &self.a, n, n),
            ("B_K", &self.b, n, 3),
            ("C_K", &self.c, 3, n),
            ("D_K", &self.d, 3, 3),
        ])?;
        if n > 0 {
            let radius = spectral_radius(&self.a, "A_K", schur_iteration_cap(n))?;
            if !(radius < 1.0) {
                return Err(RfError::invalid(
                    "A_K",
                    format!(
                        "the discretised controller must be stable (spectral radius < 1), got {radius}: \
                         a faster control rate or a slower design"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Most Francis (QR) sweeps the Schur form of an `n x n` matrix may take: LAPACK `dlahqr`'s
/// `30 max(10, n)` per eigenvalue, for all `n`. Converging matrices take a few per eigenvalue.
pub fn schur_iteration_cap(n: usize) -> usize {
    30 * n.max(10) * n.max(1)
}

/// Largest eigenvalue modulus of `a` from its real Schur form in at most `cap` sweeps (nalgebra's
/// tolerance, as `complex_eigenvalues` uses); [`RfError::IterationLimit`] naming `field` instead
/// of an endless loop on a matrix the iteration cannot settle.
pub fn spectral_radius(a: &DMatrix<f64>, field: &str, cap: usize) -> Result<f64> {
    let schur = Schur::try_new(a.clone(), f64::EPSILON, cap).ok_or_else(|| {
        RfError::iteration_limit(field, "the Schur decomposition (eigenvalues)", cap)
    })?;
    Ok(schur
        .complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0_f64, f64::max))
}

/// Lanzon et al.'s controller (module docs).
#[derive(Debug, Clone)]
pub struct LanzonController {
    model: LanzonModel,
    lin: DiscreteController,
    reference: LanzonReference,
    l_t_inv: DMatrix<f64>,
    m0: Matrix3<f64>,
    xi: DVector<f64>,
    xi_next: DVector<f64>,
    /// The outer loop's position-error integrals (paper frame), m s, over the time between
    /// commands.
    integral: PositionIntegral<3>,
}

impl LanzonController {
    pub fn new(
        model: LanzonModel,
        controller: DiscreteController,
        reference: LanzonReference,
    ) -> Result<Self> {
        model.check()?;
        controller.check()?;
        match &reference {
            LanzonReference::Attitude(r) => require_all_finite("attitude_reference", r)?,
            LanzonReference::Position {
                position_ned_m,
                gains,
            } => {
                require_all_finite("position", position_ned_m)?;
                gains.check()?;
            }
        }
        let n = controller.a.nrows();
        Ok(LanzonController {
            l_t_inv: model.l_t_inv(),
            m0: model.decoupling_matrix(0.0, 0.0),
            model,
            lin: controller,
            reference,
            xi: DVector::zeros(n),
            xi_next: DVector::zeros(n),
            integral: PositionIntegral::default(),
        })
    }

    /// `(alpha(x^), beta(x^))` of (20)-(21) (hat coordinates).
    pub fn rfl(&self, x: &[f64; 5]) -> (Vector3<f64>, Matrix3<f64>) {
        let (phic, b) = self.model.brunovsky_and_lie(x);
        let mut lt = Vector3::zeros();
        for i in 0..3 {
            lt[i] = (0..5).map(|j| self.l_t_inv[(i, j)] * phic[j]).sum();
        }
        let m = self.model.decoupling_matrix(x[0], x[1]);
        // M is upper triangular with a non-zero diagonal (|cos phi| floored): always invertible.
        let m_inv = m.try_inverse().unwrap_or_else(Matrix3::zeros);
        (m_inv * (lt - b), m_inv * self.m0)
    }

    /// Integrates the outer loop's position error (paper frame) over the time since the last
    /// command, each axis clamped to `integral_limit_m_s`; nothing without integral gains.
    fn integrate(&mut self, t_s: f64, pos: [f64; 3]) {
        let Some(dt) = self.integral.advance(t_s) else {
            return;
        };
        if let LanzonReference::Position {
            position_ned_m,
            gains,
        } = &self.reference
        {
            if gains.k_i_xy == 0.0 && gains.k_i_z == 0.0 {
                return;
            }
            let target = [position_ned_m[0], -position_ned_m[1], -position_ned_m[2]];
            let error = std::array::from_fn(|i| pos[i] - target[i]);
            self.integral
                .add_clamped(dt, error, [gains.integral_limit_m_s; 3]);
        }
    }

    /// The inner loop's set points `[phi_d, theta_d, r_d]` for a paper-frame state.
    fn set_points(&self, psi: f64, pos: [f64; 3], vel: [f64; 3]) -> [f64; 3] {
        match &self.reference {
            LanzonReference::Attitude(r) => *r,
            LanzonReference::Position {
                position_ned_m,
                gains,
            } => {
                let m = &self.model;
                let target = [position_ned_m[0], -position_ned_m[1], -position_ned_m[2]];
                let integral = self.integral.sum_m_s();
                let z1 = -gains.k_p_xy * (pos[0] - target[0])
                    - gains.k_d_xy * vel[0]
                    - gains.k_i_xy * integral[0];
                let z2 = -gains.k_p_xy * (pos[1] - target[1])
                    - gains.k_d_xy * vel[1]
                    - gains.k_i_xy * integral[1];
                let az = (-gains.k_p_z * (pos[2] - target[2])
                    - gains.k_d_z * vel[2]
                    - gains.k_i_z * integral[2])
                    .clamp(
                        -gains.max_vertical_accel_m_s2,
                        gains.max_vertical_accel_m_s2,
                    );
                let u3 = m.gravity_m_s2 + m.linear_drag_n_s_m / m.mass_kg * vel[2] + az;
                let u3 = u3.clamp(
                    m.gravity_m_s2 - gains.max_vertical_accel_m_s2,
                    m.gravity_m_s2 + gains.max_vertical_accel_m_s2,
                );
                // (31): [u1; u2] = [[S, C], [-C, S]]^T [z1; z2].
                let (s, c) = psi.sin_cos();
                let u1 = s * z1 - c * z2;
                let u2 = c * z1 + s * z2;
                let tilt = gains.max_tilt_rad;
                [
                    (u1 / u3).clamp(-tilt, tilt),
                    (u2 / u3).clamp(-tilt, tilt),
                    u3 * m.drag_torque_ratio_m * m.mass_kg / m.rotational_drag_n_m_s,
                ]
            }
        }
    }
}

impl Controller for LanzonController {
    fn command_count(&self) -> usize {
        ROTORS
    }

    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        let s = state_vector(measured);
        let (phi, theta, psi) = (s[6], -s[7], -s[8]);
        let (p, q, r) = (s[9], -s[10], -s[11]);
        let pos = [s[0], -s[1], -s[2]];
        let vel = [s[3], -s[4], -s[5]];
        let m = self.model;
        let r0 = m.spin_rate_rad_s();
        self.integrate(t_s, pos);
        let [phi_d, theta_d, r_d] = self.set_points(psi, pos, vel);
        let e = [phi_d - phi, theta_d - theta, r_d - r];
        // v = C xi + D e; xi+ = A xi + B e.
        let mut v = [0.0; 3];
        for (i, vi) in v.iter_mut().enumerate() {
            *vi = (0..self.xi.len())
                .map(|j| self.lin.c[(i, j)] * self.xi[j])
                .sum::<f64>()
                + (0..3).map(|j| self.lin.d[(i, j)] * e[j]).sum::<f64>();
        }
        for i in 0..self.xi.len() {
            self.xi_next[i] = (0..self.xi.len())
                .map(|j| self.lin.a[(i, j)] * self.xi[j])
                .sum::<f64>()
                + (0..3).map(|j| self.lin.b[(i, j)] * e[j]).sum::<f64>();
        }
        std::mem::swap(&mut self.xi, &mut self.xi_next);
        let x = [phi, theta, p, q, r - r0];
        let (alpha, beta) = self.rfl(&x);
        let u_hat = alpha + beta * Vector3::from(v);
        let mg = m.mass_kg * m.gravity_m_s2;
        let (uf, tq, tr) = (
            u_hat[0] + mg,
            u_hat[1],
            u_hat[2] + mg * m.drag_torque_ratio_m,
        );
        let (l, d) = (m.arm_length_m, m.drag_torque_ratio_m);
        // Eq. (9); rotor 2 (the failed one) commanded to zero.
        out[0] = (uf - 2.0 * tq / l + tr / d) / 4.0;
        out[1] = 0.0;
        out[2] = (uf + 2.0 * tq / l + tr / d) / 4.0;
        out[3] = (2.0 * uf - 2.0 * tr / d) / 4.0;
        Ok(())
    }

    fn reset(&mut self) {
        self.xi.fill(0.0);
        self.integral.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn empty() -> DiscreteController {
        DiscreteController {
            a: DMatrix::zeros(0, 0),
            b: DMatrix::zeros(0, 3),
            c: DMatrix::zeros(3, 0),
            d: DMatrix::zeros(3, 3),
        }
    }

    /// `x_r = T^-1 phi_c(x)` with the closed form of `T^-1`.
    fn transform(m: &LanzonModel, x: &[f64; 5]) -> [f64; 5] {
        let (z, _) = m.brunovsky_and_lie(x);
        let r0 = m.spin_rate_rad_s();
        [z[0], z[2], z[1] - r0 * z[2], z[3] + r0 * z[0], z[4]]
    }

    #[test]
    fn rfl_makes_the_transformed_state_linear() {
        // Independent check: the derivative of x_r by central differences along the model's
        // vector field equals A_r x_r + B_r v (eq. (26)), to the differencing error.
        let m = LanzonModel::default();
        let c = LanzonController::new(m, empty(), LanzonReference::Attitude([0.0; 3])).unwrap();
        let (ixx, izz, kr, l, d) = (
            m.inertia_xx_kg_m2,
            m.inertia_zz_kg_m2,
            m.rotational_drag_n_m_s,
            m.arm_length_m,
            m.drag_torque_ratio_m,
        );
        let r0 = m.spin_rate_rad_s();
        let k = r0 * (ixx - izz) / ixx;
        for (x, v) in [
            ([0.3, -0.2, 0.5, -1.0, 0.7], [1.0, -2.0, 0.5]),
            ([-0.785, 0.785, -0.5, 0.5, 0.0], [0.0, 0.3, -0.1]),
        ] {
            let (alpha, beta) = c.rfl(&x);
            let u = alpha + beta * Vector3::from(v);
            let f = m.drift(&x);
            let xdot: Vec<f64> = (0..5)
                .map(|i| {
                    f[i] + match i {
                        2 => l / (2.0 * ixx) * u[0] - l / (2.0 * d * ixx) * u[2],
                        3 => u[1] / ixx,
                        4 => u[2] / izz,
                        _ => 0.0,
                    }
                })
                .collect();
            let h = 1e-6;
            let xp: [f64; 5] = std::array::from_fn(|i| x[i] + h * xdot[i]);
            let xm: [f64; 5] = std::array::from_fn(|i| x[i] - h * xdot[i]);
            let (tp, tm) = (transform(&m, &xp), transform(&m, &xm));
            let xr = transform(&m, &x);
            let lin = [
                r0 * xr[1] + xr[2],
                -r0 * xr[0] + xr[3],
                -kr / ixx * xr[2] + k * xr[3] + l / (2.0 * ixx) * v[0] - l / (2.0 * d * ixx) * v[2],
                -k * xr[2] - kr / ixx * xr[3] + v[1] / ixx,
                -kr / izz * xr[4] + v[2] / izz,
            ];
            for i in 0..5 {
                let fd = (tp[i] - tm[i]) / (2.0 * h);
                assert!(
                    (fd - lin[i]).abs() <= 1e-6 * (1.0 + lin[i].abs()),
                    "{i}: {fd} vs {}",
                    lin[i]
                );
            }
        }
    }

    #[test]
    fn working_point_commands_the_hover_thrusts() {
        let m = LanzonModel::default();
        let mut c = LanzonController::new(
            m,
            empty(),
            LanzonReference::Attitude([0.0, 0.0, m.spin_rate_rad_s()]),
        )
        .unwrap();
        let state = RigidBodyState {
            omega_rad_s: Vector3::new(0.0, 0.0, -m.spin_rate_rad_s()),
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0; 4];
        c.command(0.0, &state, &mut out).unwrap();
        let half = m.mass_kg * m.gravity_m_s2 / 2.0;
        for (o, e) in out.iter().zip([half, 0.0, half, 0.0]) {
            assert!((o - e).abs() < 1e-12, "{out:?}");
        }
    }

    #[test]
    fn integral_action_accumulates_the_error_and_reset_clears_it() {
        // Held 1 m below the setpoint (NED z = 1 m, setpoint 0): the altitude integral grows by
        // -1 m x dt per command (paper frame, z up) and raises the spin-rate set point r_d (the
        // vertical channel: r_d = u~3 d m / k_r); without integral gains, or after a reset, the
        // set points stay the PD ones.
        let m = LanzonModel::default();
        let gains = LanzonOuterLoop {
            k_i_z: 0.2,
            ..LanzonOuterLoop::default()
        };
        let make = |gains| {
            LanzonController::new(
                m,
                empty(),
                LanzonReference::Position {
                    position_ned_m: [0.0, 0.0, 0.0],
                    gains,
                },
            )
            .unwrap()
        };
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, 1.0),
            omega_rad_s: Vector3::new(0.0, 0.0, -m.spin_rate_rad_s()),
            ..RigidBodyState::at_rest()
        };
        let r_d = |c: &mut LanzonController, t: f64| {
            let mut out = [0.0; 4];
            c.command(t, &state, &mut out).unwrap();
            c.set_points(0.0, [0.0, 0.0, -1.0], [0.0; 3])[2]
        };
        let (mut pd, mut pid) = (make(LanzonOuterLoop::default()), make(gains));
        assert_eq!(r_d(&mut pd, 0.0), r_d(&mut pid, 0.0)); // no time has passed yet
        let (r_pd, r_pid) = (r_d(&mut pd, 0.5), r_d(&mut pid, 0.5));
        assert!(
            (pid.integral.sum_m_s()[2] + 0.5).abs() < 1e-12,
            "{:?}",
            pid.integral.sum_m_s()
        );
        assert_eq!(pd.integral.sum_m_s(), [0.0, 0.0, 0.0]);
        let expected = 0.2 * 0.5 * m.drag_torque_ratio_m * m.mass_kg / m.rotational_drag_n_m_s;
        assert!(
            (r_pid - r_pd - expected).abs() < 1e-12,
            "{r_pid} {r_pd} {expected}"
        );
        pid.reset();
        assert_eq!(pid.integral.sum_m_s(), [0.0, 0.0, 0.0]);
        assert_eq!(
            r_d(&mut pid, 1.0),
            r_d(&mut make(LanzonOuterLoop::default()), 1.0)
        );
    }

    /// The outer loop's integral is the rule it had before it moved onto [`PositionIntegral`]
    /// (that code transcribed here), bit for bit, through irregular, repeated and backward
    /// times and the clamp: flights are unchanged.
    #[test]
    fn the_integral_is_the_former_rule_bit_for_bit() {
        let gains = LanzonOuterLoop {
            k_i_xy: 0.03,
            k_i_z: 0.1,
            integral_limit_m_s: 0.05,
            ..LanzonOuterLoop::default()
        };
        let mut c = LanzonController::new(
            LanzonModel::default(),
            empty(),
            LanzonReference::Position {
                position_ned_m: [0.3, -0.2, -1.0],
                gains,
            },
        )
        .unwrap();
        let target = [0.3, 0.2, 1.0]; // the paper frame's
        let (mut sum, mut last, mut clamped) = ([0.0f64; 3], None::<f64>, 0);
        let mut t = 0.0;
        for k in 0..2000 {
            t += [0.0025, 0.0, 0.001, -0.002, 0.0031][k % 5];
            let w = k as f64;
            let pos = [
                (w * 0.037).sin(),
                0.5 * (w * 0.011).cos(),
                1.0 + 0.2 * (w * 0.005).sin(),
            ];
            let dt = last.map_or(0.0, |last| (t - last).max(0.0));
            last = Some(t);
            for i in 0..3 {
                let before = sum[i] + (pos[i] - target[i]) * dt;
                sum[i] = before.clamp(-0.05, 0.05);
                clamped += usize::from(sum[i] != before);
            }
            c.integrate(t, pos);
            assert_eq!(
                c.integral.sum_m_s().map(f64::to_bits),
                sum.map(f64::to_bits),
                "step {k}"
            );
        }
        assert!(clamped > 0);
    }

    #[test]
    fn bad_designs_name_the_field() {
        let m = LanzonModel::default();
        let unstable = DiscreteController {
            a: DMatrix::from_element(1, 1, 1.5),
            b: DMatrix::zeros(1, 3),
            c: DMatrix::zeros(3, 1),
            d: DMatrix::zeros(3, 3),
        };
        let err =
            LanzonController::new(m, unstable, LanzonReference::Attitude([0.0; 3])).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("A_K: the discretised controller must be stable"),
            "{err}"
        );
        let wrong = DiscreteController {
            b: DMatrix::zeros(1, 2),
            ..empty()
        };
        let err = LanzonController::new(m, wrong, LanzonReference::Attitude([0.0; 3])).unwrap_err();
        assert!(err.to_string().starts_with("B_K: expected 0 x 3"), "{err}");
        let mut nan = empty();
        nan.d[(1, 2)] = f64::NAN;
        let err = LanzonController::new(m, nan, LanzonReference::Attitude([0.0; 3])).unwrap_err();
        assert!(
            err.to_string().starts_with("D_K[1, 2]: must be finite"),
            "{err}"
        );
        let bad = LanzonModel {
            rotational_drag_n_m_s: 0.0,
            ..m
        };
        let err =
            LanzonController::new(bad, empty(), LanzonReference::Attitude([0.0; 3])).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("model.rotational_drag_n_m_s: must be > 0"),
            "{err}"
        );
    }
}
