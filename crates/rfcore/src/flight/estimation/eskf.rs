//! The error-state Kalman filter's two halves: the nominal state, integrated through the IMU
//! samples (exact rotation over each interval), and the covariance of the 15-element error
//! state `[dp, dv, dtheta, dbg, dba]` (module docs of [`crate::flight::estimation`] for the
//! equations).

use nalgebra::{Matrix3, Quaternion, SMatrix, SVector, UnitQuaternion, Vector3};

use crate::flight::sensors::ImuSample;

/// Dimension of the error state.
pub const ERROR_DIM: usize = 15;
/// The error state's covariance, rows and columns `[dp, dv, dtheta, dbg, dba]`.
pub type Covariance = SMatrix<f64, ERROR_DIM, ERROR_DIM>;
pub type ErrorVector = SVector<f64, ERROR_DIM>;

/// Offsets of the error-state blocks.
pub const POS: usize = 0;
pub const VEL: usize = 3;
pub const ATT: usize = 6;
pub const GYRO_BIAS: usize = 9;
pub const ACCEL_BIAS: usize = 12;

/// The exponential's series below its threshold (`exp_quaternion`; the lanes' too): with
/// `x = angle / 2`, `cos x = sum (-1)^k x^2k / (2k)!` and `sin x / angle = sum (-1)^k x^2k /
/// (2 (2k+1)!)`.
pub(crate) const EXP_COS_SERIES: [f64; 6] = [
    1.0,
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
];
pub(crate) const EXP_SINC_SERIES: [f64; 5] = [
    1.0 / 2.0,
    -1.0 / 12.0,
    1.0 / 240.0,
    -1.0 / 10_080.0,
    1.0 / 725_760.0,
];
/// The squared angle from which `exp_quaternion` calls the library (0.2 rad).
pub(crate) const EXP_SERIES_LIMIT_RAD2: f64 = 0.04;

/// `Exp(phi)` as a unit quaternion. Below 0.2 rad the half-angle sine and cosine come from
/// their Taylor series to the 9th and 10th power, whose truncation (< 3e-18 at 0.1 rad
/// half-angle) is below double rounding: exact to rounding, without the library's sincos (a
/// 1 kHz IMU turns 0.03 rad per sample at 30 rad/s). The series in Horner form with constant
/// coefficients: multiplications only (the nested form's eight dependent divisions by constants
/// took longer than the rest of the call; the sensing path calls it about 20,000 times in a
/// 10 s flight).
pub(crate) fn exp_quaternion(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let angle2 = phi.norm_squared();
    if angle2 >= EXP_SERIES_LIMIT_RAD2 {
        return UnitQuaternion::from_scaled_axis(*phi);
    }
    const COS: [f64; 6] = EXP_COS_SERIES;
    const SINC: [f64; 5] = EXP_SINC_SERIES;
    let x2 = 0.25 * angle2;
    let cos =
        COS[0] + x2 * (COS[1] + x2 * (COS[2] + x2 * (COS[3] + x2 * (COS[4] + x2 * COS[5]))));
    let sinc = SINC[0] + x2 * (SINC[1] + x2 * (SINC[2] + x2 * (SINC[3] + x2 * SINC[4])));
    let v = phi * sinc;
    UnitQuaternion::new_unchecked(Quaternion::new(cos, v.x, v.y, v.z))
}

/// Position and velocity (world NED), attitude (body to world) and the IMU biases.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NominalState {
    pub position_m: Vector3<f64>,
    pub velocity_m_s: Vector3<f64>,
    pub attitude: UnitQuaternion<f64>,
    pub gyro_bias_rad_s: Vector3<f64>,
    pub accel_bias_m_s2: Vector3<f64>,
}

/// What the filter knows of the world and the IMU's mounting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Kinematics {
    pub gravity_m_s2: Vector3<f64>,
    pub imu_position_m: Vector3<f64>,
}

/// A state's inputs at one time (those of `NominalState::propagate_from`): the corrected body
/// rate and specific force and the world-frame acceleration `R f + g`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Inputs {
    pub time_s: f64,
    pub rate: Vector3<f64>,
    pub force: Vector3<f64>,
    pub acceleration: Vector3<f64>,
}

/// The linearisation of one propagation step (for the covariance).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Step {
    pub dt_s: f64,
    /// Body to world at the start.
    pub attitude: UnitQuaternion<f64>,
    /// Corrected specific force at the start, body axes.
    pub force: Vector3<f64>,
    /// The step's rotation `Exp(omega dt)` (body at the end in body at the start).
    pub increment: UnitQuaternion<f64>,
    /// Corrected rate and specific force at the end (inputs of the rate-dependent noise).
    pub rate_end: Vector3<f64>,
    pub force_end: Vector3<f64>,
}

impl NominalState {
    /// Bias- and lever-arm-corrected body rate and centre-of-mass specific force at `t_s`,
    /// linearly interpolated between the samples `a` and `b`.
    #[inline]
    fn inputs(
        &self,
        a: &ImuSample,
        b: &ImuSample,
        t_s: f64,
        kin: &Kinematics,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let span = b.time_s - a.time_s;
        // Most steps end at a sample: its fraction is 1 without a division (`span / span`).
        let s = if t_s == b.time_s {
            1.0
        } else if span > 0.0 {
            (t_s - a.time_s) / span
        } else {
            1.0
        };
        let rate = a.gyro_rad_s.lerp(&b.gyro_rad_s, s) - self.gyro_bias_rad_s;
        let r = &kin.imu_position_m;
        // The angular-acceleration term alpha x r is left out: estimating alpha would mean
        // differentiating the gyro; it vanishes in a steady spin.
        let force =
            a.accel_m_s2.lerp(&b.accel_m_s2, s) - self.accel_bias_m_s2 - rate.cross(&rate.cross(r));
        (rate, force)
    }

    /// The state at `t1` from the state at `t0`, both within `[a.time_s, b.time_s]`: rotation by
    /// the exact exponential of the midpoint rate, velocity by the trapezoid of the world-frame
    /// acceleration and position by its exact double integral (both exact when the world-frame
    /// acceleration is linear in time over the step); with the step's linearisation. With this
    /// state's inputs at `t0` when the caller has them
    /// (`start`, used when its time is `t0`: the end inputs of the step that produced this
    /// state, unchanged since), and the new state's inputs at `t1`. A chain of steps then
    /// evaluates each time's inputs once, with the same values: the inputs interpolated at a
    /// sample's own time are that sample (`lerp` at 0 and 1 is exact), and the world-frame
    /// acceleration at `t1` is the next step's at its `t0` (same attitude, same force).
    #[inline]
    pub(crate) fn propagate_from(
        &self,
        start: Option<&Inputs>,
        a: &ImuSample,
        b: &ImuSample,
        t0: f64,
        t1: f64,
        kin: &Kinematics,
    ) -> (NominalState, Step, Inputs) {
        let dt = t1 - t0;
        let (rate0, force0, acc0) = match start {
            Some(s) if s.time_s == t0 => (s.rate, s.force, s.acceleration),
            _ => {
                let (rate, force) = self.inputs(a, b, t0, kin);
                (rate, force, self.attitude * force + kin.gravity_m_s2)
            }
        };
        let (rate1, force1) = self.inputs(a, b, t1, kin);
        // The rate is linear in time within an interval: its midpoint value is the mean.
        let increment = exp_quaternion(&((rate0 + rate1) * (0.5 * dt)));
        let mut attitude = self.attitude * increment;
        attitude.renormalize_fast();
        let acc1 = attitude * force1 + kin.gravity_m_s2;
        let next = NominalState {
            // (a0 / 3 + a1 / 6) dt^2 without dividing (divisions are the slow instructions).
            position_m: self.position_m
                + self.velocity_m_s * dt
                + (acc0 * 2.0 + acc1) * (dt * dt * (1.0 / 6.0)),
            velocity_m_s: self.velocity_m_s + (acc0 + acc1) * (0.5 * dt),
            attitude,
            gyro_bias_rad_s: self.gyro_bias_rad_s,
            accel_bias_m_s2: self.accel_bias_m_s2,
        };
        let step = Step {
            dt_s: dt,
            attitude: self.attitude,
            force: force0,
            increment,
            rate_end: rate1,
            force_end: force1,
        };
        let end = Inputs {
            time_s: t1,
            rate: rate1,
            force: force1,
            acceleration: acc1,
        };
        (next, step, end)
    }

    /// Adds the error estimate `dx` (attitude on the right: `q Exp(dtheta)`).
    pub(crate) fn inject(&mut self, dx: &ErrorVector) {
        self.position_m += dx.fixed_rows::<3>(POS);
        self.velocity_m_s += dx.fixed_rows::<3>(VEL);
        self.attitude *= exp_quaternion(&dx.fixed_rows::<3>(ATT).into_owned());
        self.attitude.renormalize_fast();
        self.gyro_bias_rad_s += dx.fixed_rows::<3>(GYRO_BIAS);
        self.accel_bias_m_s2 += dx.fixed_rows::<3>(ACCEL_BIAS);
    }
}

/// White-noise power spectral densities over one step (per axis for the biases).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ProcessNoise {
    pub gyro_psd: f64,
    pub accel_psd: f64,
    pub gyro_bias_psd: Vector3<f64>,
    pub accel_bias_psd: Vector3<f64>,
}

/// `[v]x`, the cross-product matrix.
pub(crate) fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The right Jacobian of SO(3) at `phi`.
pub(crate) fn right_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    let angle = phi.norm();
    let k = skew(phi);
    if angle < 1e-6 {
        return Matrix3::identity() - 0.5 * k + (k * k) / 6.0;
    }
    let a2 = angle * angle;
    Matrix3::identity() - k * ((1.0 - angle.cos()) / a2)
        + (k * k) * ((angle - angle.sin()) / (a2 * angle))
}

/// Consecutive propagation steps merged into one for the covariance: the total time, the
/// attitude at the start, the total rotation and the mean specific force in start-body axes
/// (`int R0^T R(t) f(t) dt / T`). Propagating the covariance once per block instead of once per
/// IMU sample changes it only at second order in the block's rotation and force change.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Block {
    pub step: Step,
    force_integral: Vector3<f64>,
}

impl Block {
    pub(crate) fn start(step: &Step) -> Self {
        Block {
            step: *step,
            force_integral: step.force * step.dt_s,
        }
    }

    pub(crate) fn extend(&mut self, step: &Step) {
        self.force_integral += self.step.increment * step.force * step.dt_s;
        self.step.dt_s += step.dt_s;
        self.step.increment *= step.increment;
        self.step.force = self.force_integral / self.step.dt_s;
        self.step.rate_end = step.rate_end;
        self.step.force_end = step.force_end;
    }
}

/// `P <- F P F^T + Q` for one step, using the block structure of F:
///
/// ```text
///       dp   dv   dth    dbg   dba
/// dp  [ I   dt I   0      0     0  ]
/// dv  [ 0    I     A      0     C  ]    A = -R [f]x dt,  C = -R dt
/// dth [ 0    0    Phi     D     0  ]    Phi = Exp(w dt)^T,  D = -J_r(w dt) dt
/// dbg [ 0    0     0      I     0  ]
/// dba [ 0    0     0      0     I  ]
/// ```
///
/// `M = F P` column by column in place (each column's p, v, theta entries from its old values:
/// `A x + C y = -R dt (f x x + y)`, one 3 x 3 product instead of two); then `F P F^T = M F^T`,
/// whose row r is the same map applied to row r of `M`, for the top nine rows; the bottom six
/// rows of the p, v, theta columns follow by symmetry (`M F^T` leaves the bias columns of `M` as
/// they are). Plain loops on the column-major storage: a quarter of the instructions of the
/// block-view products.
pub(crate) fn propagate_covariance(p: &mut Covariance, step: &Step, noise: &ProcessNoise) {
    let dt = step.dt_s;
    let rotation = step.attitude.to_rotation_matrix().into_inner();
    let minus_r_dt = -rotation * dt;
    let phi = step.increment.to_rotation_matrix().into_inner().transpose();
    let d = -right_jacobian(&step.increment.scaled_axis()) * dt;
    let f = step.force;
    // The map F applies to one 15-vector's p, v, theta entries (its old values in `x`).
    let apply = |x: &[f64; ERROR_DIM]| -> [f64; 9] {
        let v = Vector3::new(x[VEL], x[VEL + 1], x[VEL + 2]);
        let th = Vector3::new(x[ATT], x[ATT + 1], x[ATT + 2]);
        let bg = Vector3::new(x[GYRO_BIAS], x[GYRO_BIAS + 1], x[GYRO_BIAS + 2]);
        let ba = Vector3::new(x[ACCEL_BIAS], x[ACCEL_BIAS + 1], x[ACCEL_BIAS + 2]);
        let p_new = Vector3::new(x[POS], x[POS + 1], x[POS + 2]) + v * dt;
        let v_new = v + minus_r_dt * (f.cross(&th) + ba);
        let th_new = phi * th + d * bg;
        [
            p_new.x, p_new.y, p_new.z, v_new.x, v_new.y, v_new.z, th_new.x, th_new.y, th_new.z,
        ]
    };
    let data = p.as_mut_slice();
    // M = F P: every column.
    for column in data.chunks_exact_mut(ERROR_DIM) {
        let old: [f64; ERROR_DIM] = std::array::from_fn(|i| column[i]);
        column[..9].copy_from_slice(&apply(&old));
    }
    // M F^T: rows 0..9 (row r is strided by ERROR_DIM in column-major storage).
    const TOP: usize = GYRO_BIAS;
    for r in 0..TOP {
        let old: [f64; ERROR_DIM] = std::array::from_fn(|c| data[c * ERROR_DIM + r]);
        for (c, value) in apply(&old).into_iter().enumerate() {
            data[c * ERROR_DIM + r] = value;
        }
    }
    // Rows 9..15 of columns 0..9: the transpose of rows 0..9 of the bias columns.
    for c in 0..TOP {
        for r in TOP..ERROR_DIM {
            data[c * ERROR_DIM + r] = data[r * ERROR_DIM + c];
        }
    }

    // Continuous white noise integrated over the step: the accelerometer's reaches position as
    // q dt^3 / 3 and the position-velocity cross term as q dt^2 / 2.
    let qa = noise.accel_psd;
    let (dt2, dt3) = (dt * dt, dt * dt * dt);
    for i in 0..3 {
        p[(POS + i, POS + i)] += qa * dt3 / 3.0;
        p[(POS + i, VEL + i)] += qa * dt2 / 2.0;
        p[(VEL + i, POS + i)] += qa * dt2 / 2.0;
        p[(VEL + i, VEL + i)] += qa * dt;
        p[(ATT + i, ATT + i)] += noise.gyro_psd * dt;
        p[(GYRO_BIAS + i, GYRO_BIAS + i)] += noise.gyro_bias_psd[i] * dt;
        p[(ACCEL_BIAS + i, ACCEL_BIAS + i)] += noise.accel_bias_psd[i] * dt;
    }
}

/// The outcome of one measurement update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fusion {
    Fused,
    /// The normalised innovation squared exceeded the gate: not fused.
    Rejected,
}

/// Fuses a three-element measurement whose Jacobian is `h` on the error block at `block` (zero
/// elsewhere; `None`: the identity): residual `r`, noise variances `noise_var`. Gated on the
/// normalised innovation squared `r^T S^-1 r <= gate`. On success `p` is updated and `dx`
/// returned.
pub(crate) fn update_block(
    p: &mut Covariance,
    block: usize,
    h: Option<&Matrix3<f64>>,
    r: &Vector3<f64>,
    noise_var: &Vector3<f64>,
    gate: f64,
) -> (Fusion, ErrorVector) {
    // The block's three columns are contiguous in the column-major storage: copied as one slice
    // (a view's `into_owned` copies element by element through an iterator).
    let mut columns = SMatrix::<f64, ERROR_DIM, 3>::zeros();
    columns
        .as_mut_slice()
        .copy_from_slice(&p.as_slice()[block * ERROR_DIM..(block + 3) * ERROR_DIM]);
    let pht: SMatrix<f64, ERROR_DIM, 3> = match h {
        None => columns,
        Some(h) => columns * h.transpose(),
    };
    let hph = match h {
        None => pht.fixed_view::<3, 3>(block, 0).into_owned(),
        Some(h) => h * pht.fixed_view::<3, 3>(block, 0),
    };
    let Some(chol) = (hph + Matrix3::from_diagonal(noise_var)).cholesky() else {
        return (Fusion::Rejected, ErrorVector::zeros());
    };
    // The 3 x 3 inverse once (its Cholesky factor is well conditioned: S >= R > 0), then
    // products: solving for all 15 rows of K would cost 90 divisions.
    let s_inv = chol.inverse();
    let s_inv_r = s_inv * r;
    if r.dot(&s_inv_r) > gate {
        return (Fusion::Rejected, ErrorVector::zeros());
    }
    // K = P H^T S^-1; P <- P - K S K^T = P - K (P H^T)^T, symmetric: the lower triangle is
    // computed in place and mirrored (no 15 x 15 temporaries, exact symmetry).
    let k: SMatrix<f64, ERROR_DIM, 3> = pht * s_inv;
    let (k0, rest) = k.as_slice().split_at(ERROR_DIM);
    let (k1, k2) = rest.split_at(ERROR_DIM);
    let data = p.as_mut_slice();
    // Column j below the diagonal is contiguous (column-major), as are K's columns: this loop
    // vectorises; the upper triangle is then copied from the lower.
    for j in 0..ERROR_DIM {
        let (a, b, c) = (pht[(j, 0)], pht[(j, 1)], pht[(j, 2)]);
        let column = &mut data[j * ERROR_DIM + j..(j + 1) * ERROR_DIM];
        for (((d, x), y), z) in column.iter_mut().zip(&k0[j..]).zip(&k1[j..]).zip(&k2[j..]) {
            *d -= x * a + y * b + z * c;
        }
    }
    mirror_lower(data);
    (Fusion::Fused, pht * s_inv_r)
}

/// Copies the lower triangle of the column-major `ERROR_DIM` square `data` onto the upper.
fn mirror_lower(data: &mut [f64]) {
    for j in 1..ERROR_DIM {
        for i in 0..j {
            data[j * ERROR_DIM + i] = data[i * ERROR_DIM + j];
        }
    }
}

/// The covariance after injecting `dtheta` (attitude reset `G = I - [dtheta / 2]x`):
/// `P <- G' P G'^T` with `G'` the identity outside the attitude block. On the column-major
/// storage: the attitude rows of every column (a contiguous triple) by `G`, then the attitude
/// columns (three contiguous columns) combined by `G^T`, in place.
pub(crate) fn reset_covariance(p: &mut Covariance, dtheta: &Vector3<f64>) {
    let g = Matrix3::identity() - skew(&(dtheta * 0.5));
    let data = p.as_mut_slice();
    for column in data.chunks_exact_mut(ERROR_DIM) {
        let x = Vector3::new(column[ATT], column[ATT + 1], column[ATT + 2]);
        let y = g * x;
        column[ATT..ATT + 3].copy_from_slice(y.as_slice());
    }
    let attitude_columns = &mut data[ATT * ERROR_DIM..(ATT + 3) * ERROR_DIM];
    let (c0, rest) = attitude_columns.split_at_mut(ERROR_DIM);
    let (c1, c2) = rest.split_at_mut(ERROR_DIM);
    for r in 0..ERROR_DIM {
        let (a, b, c) = (c0[r], c1[r], c2[r]);
        c0[r] = g[(0, 0)] * a + g[(0, 1)] * b + g[(0, 2)] * c;
        c1[r] = g[(1, 0)] * a + g[(1, 1)] * b + g[(1, 2)] * c;
        c2[r] = g[(2, 0)] * a + g[(2, 1)] * b + g[(2, 2)] * c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_covariance(seed: u64) -> Covariance {
        let mut g = crate::flight::random::Gaussian::new(seed);
        let l = Covariance::from_fn(|_, _| g.sample());
        l * l.transpose() + Covariance::identity()
    }

    /// F of the module docs, built densely (the independent reference for the block product).
    fn dense_f(step: &Step) -> Covariance {
        let dt = step.dt_s;
        let rotation = step.attitude.to_rotation_matrix().into_inner();
        let mut f = Covariance::identity();
        f.fixed_view_mut::<3, 3>(POS, VEL)
            .copy_from(&(Matrix3::identity() * dt));
        f.fixed_view_mut::<3, 3>(VEL, ATT)
            .copy_from(&(-(rotation * skew(&step.force)) * dt));
        f.fixed_view_mut::<3, 3>(VEL, ACCEL_BIAS)
            .copy_from(&(-rotation * dt));
        let phi = step.increment.to_rotation_matrix().into_inner().transpose();
        f.fixed_view_mut::<3, 3>(ATT, ATT).copy_from(&phi);
        f.fixed_view_mut::<3, 3>(ATT, GYRO_BIAS)
            .copy_from(&(-right_jacobian(&step.increment.scaled_axis()) * dt));
        f
    }

    #[test]
    fn block_propagation_equals_the_dense_product() {
        let step = Step {
            dt_s: 2e-3,
            attitude: UnitQuaternion::from_euler_angles(0.3, -0.4, 2.0),
            force: Vector3::new(0.5, -1.0, -9.6),
            increment: UnitQuaternion::from_scaled_axis(Vector3::new(0.01, -0.02, 0.06)),
            rate_end: Vector3::zeros(),
            force_end: Vector3::zeros(),
        };
        let noise = ProcessNoise {
            gyro_psd: 0.0,
            accel_psd: 0.0,
            gyro_bias_psd: Vector3::zeros(),
            accel_bias_psd: Vector3::zeros(),
        };
        let p0 = random_covariance(4);
        let mut p = p0;
        propagate_covariance(&mut p, &step, &noise);
        let f = dense_f(&step);
        let expected = f * p0 * f.transpose();
        assert!(
            (p - expected).amax() < 1e-12 * expected.amax(),
            "{}",
            (p - expected).amax()
        );
    }

    #[test]
    fn polynomial_exponential_is_exact_to_rounding() {
        for angle in [1e-9, 1e-4, 0.03, 0.1, 0.199, 0.2, 0.5] {
            let phi = Vector3::new(0.36, -0.48, 0.8) * angle;
            let ours = exp_quaternion(&phi);
            let reference = UnitQuaternion::from_scaled_axis(phi);
            let gap = (ours.coords - reference.coords).amax();
            assert!(gap < 4e-16, "angle {angle}: {gap:e}");
            assert!((ours.norm() - 1.0).abs() < 4e-16);
        }
    }

    #[test]
    fn right_jacobian_matches_the_exponential_to_first_order() {
        // Exp(phi + d) = Exp(phi) Exp(J_r(phi) d) + O(|d|^2): a finite-difference check.
        let phi = Vector3::new(0.4, -0.9, 1.7);
        let d = Vector3::new(1e-6, 2e-6, -1.5e-6);
        let lhs = UnitQuaternion::from_scaled_axis(phi + d);
        let rhs = UnitQuaternion::from_scaled_axis(phi)
            * UnitQuaternion::from_scaled_axis(right_jacobian(&phi) * d);
        assert!(lhs.angle_to(&rhs) < 1e-11, "{}", lhs.angle_to(&rhs));
    }

    #[test]
    fn reset_is_the_dense_congruence() {
        // Against G' P G'^T with G' the 15 x 15 identity carrying G = I - [dtheta / 2]x on the
        // attitude block.
        let p0 = random_covariance(11);
        let dtheta = Vector3::new(0.02, -0.05, 0.1);
        let mut g = Covariance::identity();
        g.fixed_view_mut::<3, 3>(ATT, ATT)
            .copy_from(&(Matrix3::identity() - skew(&(dtheta * 0.5))));
        let expected = g * p0 * g.transpose();
        let mut p = p0;
        reset_covariance(&mut p, &dtheta);
        assert!(
            (p - expected).amax() < 1e-14 * expected.amax(),
            "{}",
            (p - expected).amax()
        );
    }

    #[test]
    fn update_is_the_textbook_kalman_update() {
        // Against K = P H^T (H P H^T + R)^-1, P+ = (I - K H) P with a dense H.
        let p0 = random_covariance(9);
        let h = Matrix3::new(0.0, -2.0, 1.0, 2.0, 0.0, -0.5, -1.0, 0.5, 0.0);
        let r = Vector3::new(0.1, -0.2, 0.05);
        let var = Vector3::new(0.3, 0.3, 0.5);
        let mut p = p0;
        let (fusion, dx) = update_block(&mut p, ATT, Some(&h), &r, &var, f64::INFINITY);
        assert_eq!(fusion, Fusion::Fused);
        let mut hd = SMatrix::<f64, 3, ERROR_DIM>::zeros();
        hd.fixed_view_mut::<3, 3>(0, ATT).copy_from(&h);
        let s = hd * p0 * hd.transpose() + Matrix3::from_diagonal(&var);
        let k = p0 * hd.transpose() * s.try_inverse().unwrap();
        let expected_p = (Covariance::identity() - k * hd) * p0;
        assert!((p - expected_p).amax() < 1e-10 * p0.amax());
        assert!((dx - k * r).amax() < 1e-12);
        // A residual far outside the gate is refused and changes nothing.
        let mut q = p0;
        let (fusion, _) = update_block(&mut q, ATT, Some(&h), &(r * 1e3), &var, 16.0);
        assert_eq!(fusion, Fusion::Rejected);
        assert_eq!(q, p0);
    }
}
