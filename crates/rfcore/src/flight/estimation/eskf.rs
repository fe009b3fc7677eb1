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

/// `Exp(phi)` as a unit quaternion. Below 0.2 rad the half-angle sine and cosine come from
/// their Taylor series to the 9th and 10th power, whose truncation (< 3e-18 at 0.1 rad
/// half-angle) is below double rounding: exact to rounding, without the library's sincos (a
/// 1 kHz IMU turns 0.03 rad per sample at 30 rad/s).
pub(crate) fn exp_quaternion(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let angle2 = phi.norm_squared();
    if angle2 >= 0.04 {
        return UnitQuaternion::from_scaled_axis(*phi);
    }
    // x = angle / 2; cos x = sum (-1)^k x^2k / (2k)!, sin x / angle = sum (-1)^k x^2k / (2 (2k+1)!).
    let x2 = 0.25 * angle2;
    let cos = 1.0
        - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0 * (1.0 - x2 / 90.0))));
    let sinc = 0.5 * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
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
        let s = if span > 0.0 {
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
    /// acceleration is linear in time over the step); with the step's linearisation.
    #[inline]
    pub(crate) fn propagate(
        &self,
        a: &ImuSample,
        b: &ImuSample,
        t0: f64,
        t1: f64,
        kin: &Kinematics,
    ) -> (NominalState, Step) {
        let dt = t1 - t0;
        let (rate0, force0) = self.inputs(a, b, t0, kin);
        let (rate1, force1) = self.inputs(a, b, t1, kin);
        // The rate is linear in time within an interval: its midpoint value is the mean.
        let increment = exp_quaternion(&((rate0 + rate1) * (0.5 * dt)));
        let mut attitude = self.attitude * increment;
        attitude.renormalize_fast();
        let acc0 = self.attitude * force0 + kin.gravity_m_s2;
        let acc1 = attitude * force1 + kin.gravity_m_s2;
        let next = NominalState {
            position_m: self.position_m
                + self.velocity_m_s * dt
                + (acc0 / 3.0 + acc1 / 6.0) * (dt * dt),
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
        (next, step)
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
fn right_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
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
/// `M = F P` row-block by row-block in place (p, v, theta: each reads only rows not yet
/// updated); then `F P F^T = M F^T` changes only the columns p, v, theta, of which the top nine
/// rows are computed and the bottom six follow by symmetry (`M F^T` leaves the bias columns of
/// `M` as they are).
pub(crate) fn propagate_covariance(p: &mut Covariance, step: &Step, noise: &ProcessNoise) {
    let dt = step.dt_s;
    let rotation = step.attitude.to_rotation_matrix().into_inner();
    let a = -(rotation * skew(&step.force)) * dt;
    let c = -rotation * dt;
    let phi = step.increment.to_rotation_matrix().into_inner().transpose();
    let d = -right_jacobian(&step.increment.scaled_axis()) * dt;

    let row_v = p.fixed_view::<3, ERROR_DIM>(VEL, 0).into_owned();
    let mut row_p = p.fixed_view_mut::<3, ERROR_DIM>(POS, 0);
    row_p += row_v * dt;
    let row_att = p.fixed_view::<3, ERROR_DIM>(ATT, 0).into_owned();
    let row_ba = p.fixed_view::<3, ERROR_DIM>(ACCEL_BIAS, 0).into_owned();
    let mut row_v_new = p.fixed_view_mut::<3, ERROR_DIM>(VEL, 0);
    row_v_new += a * row_att + c * row_ba;
    let row_bg = p.fixed_view::<3, ERROR_DIM>(GYRO_BIAS, 0).into_owned();
    p.fixed_view_mut::<3, ERROR_DIM>(ATT, 0)
        .copy_from(&(phi * row_att + d * row_bg));

    const TOP: usize = GYRO_BIAS;
    let col_v = p.fixed_view::<TOP, 3>(0, VEL).into_owned();
    let mut col_p = p.fixed_view_mut::<TOP, 3>(0, POS);
    col_p += col_v * dt;
    let col_att = p.fixed_view::<TOP, 3>(0, ATT).into_owned();
    let col_ba = p.fixed_view::<TOP, 3>(0, ACCEL_BIAS).into_owned();
    let mut col_v_new = p.fixed_view_mut::<TOP, 3>(0, VEL);
    col_v_new += col_att * a.transpose() + col_ba * c.transpose();
    let col_bg = p.fixed_view::<TOP, 3>(0, GYRO_BIAS).into_owned();
    p.fixed_view_mut::<TOP, 3>(0, ATT)
        .copy_from(&(col_att * phi.transpose() + col_bg * d.transpose()));
    let corner = p.fixed_view::<TOP, { ERROR_DIM - TOP }>(0, TOP).transpose();
    p.fixed_view_mut::<{ ERROR_DIM - TOP }, TOP>(TOP, 0)
        .copy_from(&corner);

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
    let columns = p.fixed_view::<ERROR_DIM, 3>(0, block).into_owned();
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
    for j in 1..ERROR_DIM {
        for i in 0..j {
            data[j * ERROR_DIM + i] = data[i * ERROR_DIM + j];
        }
    }
    (Fusion::Fused, pht * s_inv_r)
}

/// The covariance after injecting `dtheta` (attitude reset `G = I - [dtheta / 2]x`).
pub(crate) fn reset_covariance(p: &mut Covariance, dtheta: &Vector3<f64>) {
    let g = Matrix3::identity() - skew(&(dtheta * 0.5));
    let rows = g * p.fixed_view::<3, ERROR_DIM>(ATT, 0);
    p.fixed_view_mut::<3, ERROR_DIM>(ATT, 0).copy_from(&rows);
    let cols = p.fixed_view::<ERROR_DIM, 3>(0, ATT) * g.transpose();
    p.fixed_view_mut::<ERROR_DIM, 3>(0, ATT).copy_from(&cols);
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
