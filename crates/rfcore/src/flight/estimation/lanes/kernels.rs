//! The error-state filter's two halves ([`crate::flight::estimation::eskf`]) over a lane type:
//! the nominal state's propagation through the IMU samples, and the covariance's propagation,
//! measurement update and attitude reset, for `L::WIDTH` filters at once. Each function is its
//! scalar counterpart written over lanes in the same order (checked bit for bit by the tests),
//! down to nalgebra's Cholesky factor and inverse of the 3 x 3 innovation covariance; the right
//! Jacobian of each step's rotation (sines and cosines) is the scalar code, lane by lane.

use nalgebra::Vector3;

use crate::analysis::LanePath;
use crate::flight::estimation::eskf::{ACCEL_BIAS, ATT, ERROR_DIM, GYRO_BIAS, POS, VEL};
use crate::flight::estimation::lanes::math::{
    add, all, cross, each, each3, exp_quaternion, lane_quat, lerp, mat_vec, quat_mul,
    renormalize_fast, rotate, rotation_matrix, scale, select, select_n, set3, set_mat, splat3, sub,
    Mask, M3, Q, V3,
};
use crate::flight::lanes::Lanes;
use crate::flight::sensors::ImuSample;

/// Entries of a covariance.
pub(crate) const ENTRIES: usize = ERROR_DIM * ERROR_DIM;

/// `L::WIDTH` covariances, column-major as [`Covariance`].
pub(crate) type CovarianceLanes<L> = [L; ENTRIES];

/// An IMU sample of every lane (one time; each lane's readings and clamping).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ImuLanes<L> {
    pub time_s: f64,
    pub gyro_rad_s: V3<L>,
    pub accel_m_s2: V3<L>,
    pub gyro_saturated: Mask,
    pub accel_saturated: Mask,
}

impl<L: Lanes> ImuLanes<L> {
    /// `sample` in every lane (lanes are then set one by one, [`ImuLanes::set_lane`]; a lane
    /// left as it is reads this sample).
    #[inline(always)]
    pub(crate) fn splat(sample: &ImuSample) -> Self {
        let mask = |flag: bool| if flag { all::<L>() } else { 0 };
        ImuLanes {
            time_s: sample.time_s,
            gyro_rad_s: splat3(&sample.gyro_rad_s),
            accel_m_s2: splat3(&sample.accel_m_s2),
            gyro_saturated: mask(sample.gyro_saturated),
            accel_saturated: mask(sample.accel_saturated),
        }
    }

    /// Lane `i` set to `sample` (a sample of the same time).
    #[inline(always)]
    pub(crate) fn set_lane(&mut self, i: usize, sample: &ImuSample) {
        set3(&mut self.gyro_rad_s, i, &sample.gyro_rad_s);
        set3(&mut self.accel_m_s2, i, &sample.accel_m_s2);
        let bit = |mask: Mask, flag: bool| (mask & !(1 << i)) | (u32::from(flag) << i);
        self.gyro_saturated = bit(self.gyro_saturated, sample.gyro_saturated);
        self.accel_saturated = bit(self.accel_saturated, sample.accel_saturated);
    }
}

/// [`crate::flight::estimation::NominalState`] per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NominalLanes<L> {
    pub position_m: V3<L>,
    pub velocity_m_s: V3<L>,
    pub attitude: Q<L>,
    pub gyro_bias_rad_s: V3<L>,
    pub accel_bias_m_s2: V3<L>,
}

/// [`crate::flight::estimation::eskf::Step`] per lane (the duration per lane: a block's).
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepLanes<L> {
    pub dt_s: L,
    pub attitude: Q<L>,
    pub force: V3<L>,
    pub increment: Q<L>,
    pub rate_end: V3<L>,
    pub force_end: V3<L>,
}

/// The gravity and the IMU's lever arm, splatted.
#[derive(Debug, Clone, Copy)]
pub(crate) struct KinematicsLanes<L> {
    pub gravity_m_s2: V3<L>,
    pub imu_position_m: V3<L>,
}

impl<L: Lanes> NominalLanes<L> {
    /// `NominalState::inputs`: the corrected rate and centre-of-mass specific force at `t_s`.
    #[inline(always)]
    fn inputs(
        &self,
        a: &ImuLanes<L>,
        b: &ImuLanes<L>,
        t_s: f64,
        kin: &KinematicsLanes<L>,
    ) -> (V3<L>, V3<L>) {
        let span = b.time_s - a.time_s;
        let s = if t_s == b.time_s {
            1.0
        } else if span > 0.0 {
            (t_s - a.time_s) / span
        } else {
            1.0
        };
        let rate = sub(
            &lerp(&a.gyro_rad_s, &b.gyro_rad_s, s),
            &self.gyro_bias_rad_s,
        );
        let r = &kin.imu_position_m;
        let force = sub(
            &sub(
                &lerp(&a.accel_m_s2, &b.accel_m_s2, s),
                &self.accel_bias_m_s2,
            ),
            &cross(&rate, &cross(&rate, r)),
        );
        (rate, force)
    }

    /// `NominalState::propagate_from` without the caller's start inputs (the scalar filter's
    /// cached inputs are these values: its docs), returning the state at `t1`, the step and the
    /// corrected rate and force at `t1`; in the form `path` asks for.
    pub(crate) fn propagate(
        &self,
        a: &ImuLanes<L>,
        b: &ImuLanes<L>,
        (t0, t1): (f64, f64),
        kin: &KinematicsLanes<L>,
        path: LanePath,
    ) -> (NominalLanes<L>, StepLanes<L>) {
        propagate_nominal(path, self, a, b, t0, t1, kin)
    }

    #[inline(always)]
    fn propagate_body(
        &self,
        a: &ImuLanes<L>,
        b: &ImuLanes<L>,
        t0: f64,
        t1: f64,
        kin: &KinematicsLanes<L>,
    ) -> (NominalLanes<L>, StepLanes<L>) {
        let dt = t1 - t0;
        let (rate0, force0) = self.inputs(a, b, t0, kin);
        let acc0 = add(&rotate(&self.attitude, &force0), &kin.gravity_m_s2);
        let (rate1, force1) = self.inputs(a, b, t1, kin);
        let increment = exp_quaternion(&scale(&add(&rate0, &rate1), L::splat(0.5 * dt)));
        let attitude = renormalize_fast(&quat_mul(&self.attitude, &increment));
        let acc1 = add(&rotate(&attitude, &force1), &kin.gravity_m_s2);
        let dtl = L::splat(dt);
        let sixth = L::splat(dt * dt * (1.0 / 6.0));
        let two = L::splat(2.0);
        let half = L::splat(0.5 * dt);
        let next = NominalLanes {
            position_m: each(|k| {
                self.position_m[k] + self.velocity_m_s[k] * dtl + (acc0[k] * two + acc1[k]) * sixth
            }),
            velocity_m_s: each(|k| self.velocity_m_s[k] + (acc0[k] + acc1[k]) * half),
            attitude,
            gyro_bias_rad_s: self.gyro_bias_rad_s,
            accel_bias_m_s2: self.accel_bias_m_s2,
        };
        let step = StepLanes {
            dt_s: dtl,
            attitude: self.attitude,
            force: force0,
            increment,
            rate_end: rate1,
            force_end: force1,
        };
        (next, step)
    }

    /// `NominalState::inject` in the lanes of `mask` (the others unchanged).
    #[inline(always)]
    pub(crate) fn inject(&mut self, dx: &[L; ERROR_DIM], mask: Mask) {
        let part = |k: usize| -> V3<L> { [dx[k], dx[k + 1], dx[k + 2]] };
        let attitude = renormalize_fast(&quat_mul(&self.attitude, &exp_quaternion(&part(ATT))));
        let next = NominalLanes {
            position_m: add(&self.position_m, &part(POS)),
            velocity_m_s: add(&self.velocity_m_s, &part(VEL)),
            attitude,
            gyro_bias_rad_s: add(&self.gyro_bias_rad_s, &part(GYRO_BIAS)),
            accel_bias_m_s2: add(&self.accel_bias_m_s2, &part(ACCEL_BIAS)),
        };
        *self = self.select(mask, &next);
    }

    /// `next` in the lanes of `mask`, `self` elsewhere.
    #[inline(always)]
    pub(crate) fn select(&self, mask: Mask, next: &NominalLanes<L>) -> NominalLanes<L> {
        if mask == all::<L>() {
            return *next;
        }
        NominalLanes {
            position_m: select_n(mask, &next.position_m, &self.position_m),
            velocity_m_s: select_n(mask, &next.velocity_m_s, &self.velocity_m_s),
            attitude: select_n(mask, &next.attitude, &self.attitude),
            gyro_bias_rad_s: select_n(mask, &next.gyro_bias_rad_s, &self.gyro_bias_rad_s),
            accel_bias_m_s2: select_n(mask, &next.accel_bias_m_s2, &self.accel_bias_m_s2),
        }
    }
}

/// [`crate::flight::estimation::eskf::Block`] per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlockLanes<L> {
    pub step: StepLanes<L>,
    force_integral: V3<L>,
}

impl<L: Lanes> BlockLanes<L> {
    #[inline(always)]
    pub(crate) fn start(step: &StepLanes<L>) -> Self {
        BlockLanes {
            step: *step,
            force_integral: scale(&step.force, step.dt_s),
        }
    }

    /// `Block::extend` (every lane).
    #[inline(always)]
    pub(crate) fn extended(&self, step: &StepLanes<L>) -> Self {
        let force_integral = add(
            &self.force_integral,
            &scale(&rotate(&self.step.increment, &step.force), step.dt_s),
        );
        let dt_s = self.step.dt_s + step.dt_s;
        BlockLanes {
            step: StepLanes {
                dt_s,
                attitude: self.step.attitude,
                force: each(|k| force_integral[k] / dt_s),
                increment: quat_mul(&self.step.increment, &step.increment),
                rate_end: step.rate_end,
                force_end: step.force_end,
            },
            force_integral,
        }
    }

    /// `next` in the lanes of `mask`, `self` elsewhere.
    #[inline(always)]
    pub(crate) fn select(&self, mask: Mask, next: &BlockLanes<L>) -> BlockLanes<L> {
        let (a, b) = (&next.step, &self.step);
        BlockLanes {
            step: StepLanes {
                dt_s: select(mask, a.dt_s, b.dt_s),
                attitude: select_n(mask, &a.attitude, &b.attitude),
                force: select_n(mask, &a.force, &b.force),
                increment: select_n(mask, &a.increment, &b.increment),
                rate_end: select_n(mask, &a.rate_end, &b.rate_end),
                force_end: select_n(mask, &a.force_end, &b.force_end),
            },
            force_integral: select_n(mask, &next.force_integral, &self.force_integral),
        }
    }
}

/// [`crate::flight::estimation::eskf::ProcessNoise`] per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NoiseLanes<L> {
    pub gyro_psd: L,
    pub accel_psd: L,
    pub gyro_bias_psd: V3<L>,
    pub accel_bias_psd: V3<L>,
}

/// The map F applies to one 15-vector's p, v, theta entries (`eskf::propagate_covariance`'s
/// `apply`), a function rather than a closure so that it is inlined into the AVX2 body (a
/// closure is compiled once, for the baseline target, with its arrays passed through memory).
struct StepMap<L> {
    dt: L,
    force: V3<L>,
    minus_r_dt: M3<L>,
    phi: M3<L>,
    d: M3<L>,
}

impl<L: Lanes> StepMap<L> {
    #[inline(always)]
    fn apply(&self, x: &[L; ERROR_DIM]) -> [L; 9] {
        let v = [x[VEL], x[VEL + 1], x[VEL + 2]];
        let th = [x[ATT], x[ATT + 1], x[ATT + 2]];
        let bg = [x[GYRO_BIAS], x[GYRO_BIAS + 1], x[GYRO_BIAS + 2]];
        let ba = [x[ACCEL_BIAS], x[ACCEL_BIAS + 1], x[ACCEL_BIAS + 2]];
        let p_new = add(&[x[POS], x[POS + 1], x[POS + 2]], &scale(&v, self.dt));
        let v_new = add(
            &v,
            &mat_vec(&self.minus_r_dt, &add(&cross(&self.force, &th), &ba)),
        );
        let th_new = add(&mat_vec(&self.phi, &th), &mat_vec(&self.d, &bg));
        [
            p_new[0], p_new[1], p_new[2], v_new[0], v_new[1], v_new[2], th_new[0], th_new[1],
            th_new[2],
        ]
    }
}

/// The body of [`propagate_covariance`].
#[inline(always)]
fn propagate_covariance_body<L: Lanes>(
    p: &mut CovarianceLanes<L>,
    step: &StepLanes<L>,
    noise: &NoiseLanes<L>,
) {
    let dt = step.dt_s;
    let rotation = rotation_matrix(&step.attitude);
    let minus_r_dt: M3<L> = each3(|r| each(|c| -rotation[r][c] * dt));
    let increment_matrix = rotation_matrix(&step.increment);
    let phi: M3<L> = each3(|r| each(|c| increment_matrix[c][r]));
    let mut d: M3<L> = [[L::splat(0.0); 3]; 3];
    for i in 0..L::WIDTH {
        let increment = lane_quat(&step.increment, i);
        let di =
            -crate::flight::estimation::eskf::right_jacobian(&increment.scaled_axis()) * dt.lane(i);
        set_mat(&mut d, i, &di);
    }
    let map = StepMap {
        dt,
        force: step.force,
        minus_r_dt,
        phi,
        d,
    };
    for column in p.chunks_exact_mut(ERROR_DIM) {
        let old: [L; ERROR_DIM] = each(|i| column[i]);
        column[..9].copy_from_slice(&map.apply(&old));
    }
    const TOP: usize = GYRO_BIAS;
    for r in 0..TOP {
        let old: [L; ERROR_DIM] = each(|c| p[c * ERROR_DIM + r]);
        for (c, value) in map.apply(&old).into_iter().enumerate() {
            p[c * ERROR_DIM + r] = value;
        }
    }
    for c in 0..TOP {
        for r in TOP..ERROR_DIM {
            p[c * ERROR_DIM + r] = p[r * ERROR_DIM + c];
        }
    }
    let qa = noise.accel_psd;
    let (dt2, dt3) = (dt * dt, dt * dt * dt);
    let (two, three) = (L::splat(2.0), L::splat(3.0));
    let mut add_at = |r: usize, c: usize, v: L| {
        let e = &mut p[c * ERROR_DIM + r];
        *e = *e + v;
    };
    for i in 0..3 {
        add_at(POS + i, POS + i, qa * dt3 / three);
        add_at(POS + i, VEL + i, qa * dt2 / two);
        add_at(VEL + i, POS + i, qa * dt2 / two);
        add_at(VEL + i, VEL + i, qa * dt);
        add_at(ATT + i, ATT + i, noise.gyro_psd * dt);
        add_at(GYRO_BIAS + i, GYRO_BIAS + i, noise.gyro_bias_psd[i] * dt);
        add_at(ACCEL_BIAS + i, ACCEL_BIAS + i, noise.accel_bias_psd[i] * dt);
    }
}

/// The Cholesky factor of each lane's symmetric `m` (nalgebra's `Cholesky::new`: column by
/// column, the lower triangle) and the inverse through it (`Cholesky::inverse`: each column of
/// the identity solved forward with the factor, then back with its transpose, the back
/// substitution's sums as nalgebra's dynamic dot product forms them, from `+0`). Returns the
/// lanes with a factor (a zero or negative pivot, or NaN, has none) and the inverses.
#[inline(always)]
fn cholesky_inverse<L: Lanes>(m: &M3<L>) -> (Mask, M3<L>) {
    let mut l = *m;
    let mut factored = all::<L>();
    for j in 0..3 {
        for k in 0..j {
            let factor = -l[j][k];
            for row in l.iter_mut().skip(j) {
                row[j] = factor * row[k] + row[j];
            }
        }
        let diag = l[j][j];
        for i in 0..L::WIDTH {
            // nalgebra's pivot rule: zero, negative or NaN has no square root to divide by.
            let d = diag.lane(i);
            if d.is_nan() || d <= 0.0 {
                factored &= !(1 << i);
            }
        }
        let denom = diag.sqrt();
        l[j][j] = denom;
        for row in l.iter_mut().skip(j + 1) {
            row[j] = row[j] / denom;
        }
    }
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let mut inverse = [[zero; 3]; 3];
    for c in 0..3 {
        let mut b = [zero; 3];
        b[c] = one;
        for i in 0..3 {
            let coeff = b[i] / l[i][i];
            b[i] = coeff;
            for r in i + 1..3 {
                b[r] = -coeff * l[r][i] + b[r];
            }
        }
        for i in (0..3).rev() {
            let mut dot = zero;
            for r in i + 1..3 {
                dot = dot + l[r][i] * b[r];
            }
            b[i] = (b[i] - dot) / l[i][i];
        }
        for (r, row) in inverse.iter_mut().enumerate() {
            row[c] = b[r];
        }
    }
    (factored, inverse)
}

/// The body of [`update_block`].
#[inline(always)]
fn update_block_body<L: Lanes>(
    p: &mut CovarianceLanes<L>,
    block: usize,
    h: Option<&M3<L>>,
    r: &V3<L>,
    noise_var: &Vector3<f64>,
    gate: f64,
    tried: Mask,
) -> (Mask, [L; ERROR_DIM]) {
    let zero = L::splat(0.0);
    // P H^T: the block's three columns, times H^T (nalgebra's gemm: column j of the product is
    // the columns combined by row j of H).
    let column = |k: usize, i: usize| p[(block + k) * ERROR_DIM + i];
    let pht: [[L; 3]; ERROR_DIM] = each3(|i| match h {
        None => [column(0, i), column(1, i), column(2, i)],
        Some(h) => {
            each(|j| column(0, i) * h[j][0] + column(1, i) * h[j][1] + column(2, i) * h[j][2])
        }
    });
    let hph: M3<L> = match h {
        None => each3(|a| pht[block + a]),
        Some(h) => each3(|a| {
            each(|b| {
                h[a][0] * pht[block][b] + h[a][1] * pht[block + 1][b] + h[a][2] * pht[block + 2][b]
            })
        }),
    };
    // S = H P H^T + R (nalgebra adds the diagonal matrix: `+ 0` off the diagonal), its
    // inverse through its Cholesky factor, and the gate on r^T S^-1 r.
    let s: M3<L> =
        each3(|a| each(|b| hph[a][b] + L::splat(if a == b { noise_var[a] } else { 0.0 })));
    let (factored, s_inv) = cholesky_inverse(&s);
    let s_inv_r = mat_vec(&s_inv, r);
    let nis = r[0] * s_inv_r[0] + r[1] * s_inv_r[1] + r[2] * s_inv_r[2];
    // Refused where there is no factor or the gate is exceeded (NaN passes, as in the scalar).
    let fused = (0..L::WIDTH)
        .filter(|&i| nis.lane(i) > gate)
        .fold(tried & factored, |m, i| m & !(1 << i));
    if fused == 0 {
        return (0, [zero; ERROR_DIM]);
    }
    // K = P H^T S^-1 (gemm order), P <- P - K (P H^T)^T on the lower triangle, mirrored.
    let k: [[L; 3]; ERROR_DIM] = each3(|i| {
        each(|j| pht[i][0] * s_inv[0][j] + pht[i][1] * s_inv[1][j] + pht[i][2] * s_inv[2][j])
    });
    let full = fused == all::<L>();
    for j in 0..ERROR_DIM {
        let (a, b, c) = (pht[j][0], pht[j][1], pht[j][2]);
        for i in j..ERROR_DIM {
            let d = &mut p[j * ERROR_DIM + i];
            let next = *d - (k[i][0] * a + k[i][1] * b + k[i][2] * c);
            *d = if full { next } else { select(fused, next, *d) };
        }
    }
    // The lower triangle mirrored onto the upper in the fused lanes only: a refused lane keeps
    // its covariance as it was (propagation leaves it symmetric only to rounding).
    mirror_lower(p, fused);
    let dx: [L; ERROR_DIM] = each(|i| {
        let v = pht[i][0] * s_inv_r[0] + pht[i][1] * s_inv_r[1] + pht[i][2] * s_inv_r[2];
        select(fused, v, zero)
    });
    (fused, dx)
}

#[inline(always)]
fn mirror_lower<L: Lanes>(p: &mut CovarianceLanes<L>, lanes: Mask) {
    let full = lanes == all::<L>();
    for j in 1..ERROR_DIM {
        for i in 0..j {
            let lower = p[i * ERROR_DIM + j];
            let upper = &mut p[j * ERROR_DIM + i];
            *upper = if full {
                lower
            } else {
                select(lanes, lower, *upper)
            };
        }
    }
}

/// The body of [`reset_covariance`].
#[inline(always)]
fn reset_covariance_body<L: Lanes>(p: &mut CovarianceLanes<L>, dtheta: &V3<L>, mask: Mask) {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let v = scale(dtheta, L::splat(0.5));
    // I - [v]x, entry by entry as nalgebra subtracts the skew matrix from the identity.
    let g: M3<L> = [
        [one - zero, zero - -v[2], zero - v[1]],
        [zero - v[2], one - zero, zero - -v[0]],
        [zero - -v[1], zero - v[0], one - zero],
    ];
    // In the lanes outside `mask` every entry is written back as it was.
    let full = mask == all::<L>();
    let pick = |new: L, old: L| if full { new } else { select(mask, new, old) };
    for column in p.chunks_exact_mut(ERROR_DIM) {
        let x = [column[ATT], column[ATT + 1], column[ATT + 2]];
        let y = mat_vec(&g, &x);
        for k in 0..3 {
            column[ATT + k] = pick(y[k], x[k]);
        }
    }
    for r in 0..ERROR_DIM {
        let at = |c: usize| (ATT + c) * ERROR_DIM + r;
        let (a, b, c) = (p[at(0)], p[at(1)], p[at(2)]);
        p[at(0)] = pick(g[0][0] * a + g[0][1] * b + g[0][2] * c, a);
        p[at(1)] = pick(g[1][0] * a + g[1][1] * b + g[1][2] * c, b);
        p[at(2)] = pick(g[2][0] * a + g[2][1] * b + g[2][2] * c, c);
    }
}

/// `pub(crate) fn $name(path, ...)` calling `$body` compiled for AVX2 and FMA where `path` asks
/// for it and the CPU has them, for the baseline target otherwise (same results: Rust contracts
/// no `a * b + c` into a fused multiply-add; the batch driver's lanes do the same,
/// [`crate::flight::lanes`]). The laned kernels are called from the estimator's control flow,
/// which is not compiled for AVX2: without this a lane operation on four `f64` took two SSE2
/// instructions.
macro_rules! avx2_or_baseline {
    ($(#[$doc:meta])* fn $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)? = $body:expr;) => {
        $(#[$doc])*
        // The form to run, then the kernel's own arguments (update_block's seven).
        #[allow(clippy::too_many_arguments)]
        pub(crate) fn $name<L: Lanes>(path: LanePath, $($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                unsafe fn avx2<L: Lanes>($($arg: $ty),*) $(-> $ret)? {
                    $body($($arg),*)
                }
                if crate::flight::lanes::runs_avx2(path, crate::flight::lanes::Choice::Kernel) {
                    // SAFETY: the CPU has the features `avx2` is compiled for.
                    return unsafe { avx2($($arg),*) };
                }
            }
            let _ = path;
            $body($($arg),*)
        }
    };
}

avx2_or_baseline! {
    /// [`NominalLanes::propagate`].
    fn propagate_nominal(
        x: &NominalLanes<L>,
        a: &ImuLanes<L>,
        b: &ImuLanes<L>,
        t0: f64,
        t1: f64,
        kin: &KinematicsLanes<L>
    ) -> (NominalLanes<L>, StepLanes<L>) = NominalLanes::propagate_body;
}

avx2_or_baseline! {
    /// `eskf::propagate_covariance` for every lane (the right Jacobian of each lane's rotation
    /// by the scalar code).
    fn propagate_covariance(
        p: &mut CovarianceLanes<L>,
        step: &StepLanes<L>,
        noise: &NoiseLanes<L>
    ) = propagate_covariance_body;
}

avx2_or_baseline! {
    /// `eskf::update_block` for every lane of `tried`: lanes whose innovation has no Cholesky
    /// factor or whose normalised innovation squared exceeds `gate` are left unchanged. Returns
    /// the lanes fused and `dx` (zero in the others).
    fn update_block(
        p: &mut CovarianceLanes<L>,
        block: usize,
        h: Option<&M3<L>>,
        r: &V3<L>,
        noise_var: &Vector3<f64>,
        gate: f64,
        tried: Mask
    ) -> (Mask, [L; ERROR_DIM]) = update_block_body;
}

avx2_or_baseline! {
    /// `eskf::reset_covariance` in the lanes of `mask`.
    fn reset_covariance(p: &mut CovarianceLanes<L>, dtheta: &V3<L>, mask: Mask) =
        reset_covariance_body;
}

/// Lane `i` of a covariance (for the tests).
#[cfg(test)]
pub(crate) fn lane_covariance<L: Lanes>(
    p: &CovarianceLanes<L>,
    i: usize,
) -> crate::flight::estimation::Covariance {
    crate::flight::estimation::Covariance::from_column_slice(
        &std::array::from_fn::<f64, ENTRIES, _>(|k| p[k].lane(i)),
    )
}

#[cfg(test)]
#[path = "kernels_tests.rs"]
mod tests;
