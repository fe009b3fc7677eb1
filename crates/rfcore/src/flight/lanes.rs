//! Several vehicles stepped at once, one per SIMD lane: the rigid-body RK4 step and the vehicle
//! wrench written once over a lane type [`Lanes`], so the same source computes one vehicle
//! (`f64`) and four ([`F64x4`], one AVX2 register).
//!
//! # Why the lanes equal the scalar simulator bit for bit
//! Every operation here is an elementwise IEEE-754 `+ - * /` or `sqrt`, each correctly rounded,
//! so a lane computes exactly what `f64` computes from the same inputs in the same order. The
//! order is the one of [`crate::flight::rigid_body::RigidBody::rk4_step_nodes`] and
//! [`crate::flight::vehicle::Vehicle::wrench_from`] as nalgebra evaluates them (matrix-vector
//! products summed left to right, quaternion products term by term, the quaternion norm as
//! `(x^2 + z^2) + (y^2 + w^2)`), checked bit for bit by this file's tests. Rust never contracts
//! `a * b + c` into a fused multiply-add, so enabling FMA for the AVX2 build changes nothing;
//! nothing here calls `mul_add`.
//!
//! # Run-time selection
//! [`F64x4`] is four `f64` in an array; its operations are loops LLVM turns into one AVX2
//! instruction each when the caller is compiled for AVX2. The batch driver compiles its group
//! stepper twice, once inside a `#[target_feature(enable = "avx2,fma")]` function chosen when
//! the CPU reports both features, once for the baseline target (SSE2 pairs): same results,
//! different speed. The estimator's laned kernels are compiled and chosen the same way. A group
//! picks its [`LanePath`] once ([`detected_path`], or `Portable` when the batch asks for it:
//! `BatchLanes::Portable`) and every laned choice it makes follows it ([`runs_avx2`]), so a
//! portable group runs the baseline form throughout, as a CPU without AVX2 does: the tests fly
//! both forms on this machine and compare them bit for bit.

use std::ops::{Add, Div, Mul, Neg, Sub};

use crate::analysis::LanePath;
use crate::flight::vehicle::Vehicle;
use crate::state::RigidBodyState;

/// The places where laned code chooses its compiled form ([`runs_avx2`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Choice {
    /// The group stepper (`batch_lanes::fly_group`).
    Group,
    /// The estimators' IMU sample (`EstimatorLanes::push_imu`).
    PushImu,
    /// The estimates handed to the controllers (`EstimatorLanes::estimates_at`).
    EstimatesAt,
    /// The estimator's kernels (propagation, covariance, update, reset).
    Kernel,
}

/// The portable choices made at each [`Choice`] (the tests check that a portable batch reaches
/// every place), and the lock that keeps one test's counts its own under `cargo test`'s threads.
#[cfg(test)]
pub(crate) mod portable_choices {
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::{Mutex, MutexGuard};

    use super::Choice;

    static COUNTS: [AtomicU64; 4] = [const { AtomicU64::new(0) }; 4];
    static SERIAL: Mutex<()> = Mutex::new(());

    pub(crate) fn count(choice: Choice) {
        COUNTS[choice as usize].fetch_add(1, Ordering::Relaxed);
    }

    /// The counts, in the order of [`Choice`].
    pub(crate) fn snapshot() -> [u64; 4] {
        std::array::from_fn(|i| COUNTS[i].load(Ordering::Relaxed))
    }

    /// Held by every test that makes portable choices while it does.
    pub(crate) fn serial() -> MutexGuard<'static, ()> {
        SERIAL
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

/// The form the laned code runs on this CPU: [`LanePath::Avx2`] (compiled for AVX2 and FMA)
/// where it has both, [`LanePath::Portable`] otherwise.
pub(crate) fn detected_path() -> LanePath {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        return LanePath::Avx2;
    }
    LanePath::Portable
}

/// Whether the laned code at `choice` runs its AVX2 and FMA form on `path`: `path` asks for it
/// and the CPU has both (so the form is never run where it cannot be).
#[inline]
pub(crate) fn runs_avx2(path: LanePath, choice: Choice) -> bool {
    match path {
        LanePath::Avx2 => detected_path() == LanePath::Avx2,
        LanePath::Portable => {
            #[cfg(test)]
            portable_choices::count(choice);
            let _ = choice;
            false
        }
    }
}

/// A number type stepped elementwise: `f64` (one vehicle) or [`F64x4`] (four).
pub trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// How many vehicles one value holds.
    const WIDTH: usize;
    /// `v` in every lane.
    fn splat(v: f64) -> Self;
    /// Lane `i`.
    fn lane(self, i: usize) -> f64;
    /// Sets lane `i` to `v`.
    fn set_lane(&mut self, i: usize, v: f64);
    /// Correctly rounded square root per lane.
    fn sqrt(self) -> Self;
}

impl Lanes for f64 {
    const WIDTH: usize = 1;
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn set_lane(&mut self, _i: usize, v: f64) {
        *self = v;
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

/// `N` `f64` lanes: [`F64x4`] is one AVX2 register where the caller is compiled for AVX2.
/// (Eight lanes, two AVX2 registers a value, measured slower on the lanes bench: 1.55x the
/// scalar path against 2.05x for four; the wider group spills registers.)
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub struct F64xN<const N: usize>(pub [f64; N]);

/// Four `f64` lanes (one AVX2 register).
pub type F64x4 = F64xN<4>;

macro_rules! lanewise {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<const N: usize> $trait for F64xN<N> {
            type Output = F64xN<N>;
            #[inline(always)]
            fn $method(self, rhs: F64xN<N>) -> F64xN<N> {
                let mut a = self.0;
                for (x, y) in a.iter_mut().zip(rhs.0) {
                    *x = *x $op y;
                }
                F64xN(a)
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl<const N: usize> Neg for F64xN<N> {
    type Output = F64xN<N>;
    #[inline(always)]
    fn neg(self) -> F64xN<N> {
        let mut a = self.0;
        for x in a.iter_mut() {
            *x = -*x;
        }
        F64xN(a)
    }
}

impl<const N: usize> Lanes for F64xN<N> {
    const WIDTH: usize = N;
    #[inline(always)]
    fn splat(v: f64) -> Self {
        F64xN([v; N])
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.0[i]
    }
    #[inline(always)]
    fn set_lane(&mut self, i: usize, v: f64) {
        self.0[i] = v;
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let mut a = self.0;
        for x in a.iter_mut() {
            *x = x.sqrt();
        }
        F64xN(a)
    }
}

/// The 13 rigid-body states of [`Lanes::WIDTH`] vehicles (quaternion stored `[x, y, z, w]` as
/// nalgebra stores it).
#[derive(Debug, Clone, Copy)]
pub struct BodyLanes<L> {
    pub position_m: [L; 3],
    pub velocity_m_s: [L; 3],
    pub attitude: [L; 4],
    pub omega_rad_s: [L; 3],
}

impl<L: Lanes> BodyLanes<L> {
    /// Every lane at rest (filled by [`BodyLanes::set`]).
    pub fn zeros() -> Self {
        let z = L::splat(0.0);
        BodyLanes {
            position_m: [z; 3],
            velocity_m_s: [z; 3],
            attitude: [z; 4],
            omega_rad_s: [z; 3],
        }
    }

    /// Lane `i` as a state.
    #[inline]
    pub fn get(&self, i: usize) -> RigidBodyState {
        let v = |a: &[L; 3]| nalgebra::Vector3::new(a[0].lane(i), a[1].lane(i), a[2].lane(i));
        let q = &self.attitude;
        RigidBodyState {
            position_m: v(&self.position_m),
            velocity_m_s: v(&self.velocity_m_s),
            attitude: nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
                q[3].lane(i),
                q[0].lane(i),
                q[1].lane(i),
                q[2].lane(i),
            )),
            omega_rad_s: v(&self.omega_rad_s),
        }
    }

    /// What [`crate::flight::simulation::divergence`]'s limits compare, per lane: `n3z`
    /// (`w^2 - x^2 - y^2 + z^2`), the squared speed and the squared body rate, in the order
    /// the scalar check computes them (nalgebra's `0 + ((x^2 + y^2) + z^2)`).
    #[inline(always)]
    pub fn limit_parts(&self) -> (L, L, L) {
        let q = &self.attitude;
        let n3z = q[3] * q[3] - q[0] * q[0] - q[1] * q[1] + q[2] * q[2];
        let norm2 = |v: &[L; 3]| L::splat(0.0) + ((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]);
        (n3z, norm2(&self.velocity_m_s), norm2(&self.omega_rad_s))
    }

    /// Sets lane `i` to `s`.
    #[inline]
    pub fn set(&mut self, i: usize, s: &RigidBodyState) {
        for k in 0..3 {
            self.position_m[k].set_lane(i, s.position_m[k]);
            self.velocity_m_s[k].set_lane(i, s.velocity_m_s[k]);
            self.omega_rad_s[k].set_lane(i, s.omega_rad_s[k]);
        }
        let c = &s.attitude.quaternion().coords;
        for k in 0..4 {
            self.attitude[k].set_lane(i, c[k]);
        }
    }
}

/// The rotors' summed thrust (N, up) and body torque (N m) per lane.
#[derive(Debug, Clone, Copy)]
pub struct TotalsLanes<L> {
    pub thrust_n: L,
    pub torque_body_nm: [L; 3],
}

/// What stays fixed over a group's run: the body, the drag the lanes support, the weight and
/// the (constant) wind, splatted once.
#[derive(Debug, Clone, Copy)]
pub struct VehicleLanes<L> {
    inertia: [[L; 3]; 3],
    inertia_inverse: [[L; 3]; 3],
    inverse_mass: L,
    mass_kg: L,
    weight_n: L,
    linear_drag_n_s_m: L,
    rotational_drag_n_m_s: L,
    wind_m_s: [L; 3],
}

impl<L: Lanes> VehicleLanes<L> {
    /// `None` when `vehicle` has a term the lanes do not model (quadratic drag, rotor inertia):
    /// the batch then flies its runs with the scalar simulator.
    pub fn new(vehicle: &Vehicle, wind_m_s: &nalgebra::Vector3<f64>) -> Option<Self> {
        let aero = vehicle.aero();
        if aero.quadratic_drag_n_s2_m2 != 0.0 || aero.rotor_inertia_kg_m2 != 0.0 {
            return None;
        }
        let body = vehicle.body();
        let m = |a: &nalgebra::Matrix3<f64>| {
            std::array::from_fn(|r| std::array::from_fn(|c| L::splat(a[(r, c)])))
        };
        Some(VehicleLanes {
            inertia: m(body.inertia_kg_m2()),
            inertia_inverse: m(body.inertia_inverse()),
            inverse_mass: L::splat(body.inverse_mass()),
            mass_kg: L::splat(body.mass_kg()),
            weight_n: L::splat(body.mass_kg() * vehicle.gravity_m_s2()),
            linear_drag_n_s_m: L::splat(aero.linear_drag_n_s_m),
            rotational_drag_n_m_s: L::splat(aero.rotational_drag_n_m_s),
            wind_m_s: std::array::from_fn(|k| L::splat(wind_m_s[k])),
        })
    }

    /// The RK4 step of [`crate::flight::rigid_body::RigidBody::rk4_step_nodes`] with the wrench
    /// of [`Vehicle::wrench_from`] under `totals` at the three time nodes.
    #[inline(always)]
    pub fn rk4_step(
        &self,
        s: &BodyLanes<L>,
        dt_s: f64,
        totals: &[TotalsLanes<L>; 3],
    ) -> BodyLanes<L> {
        self.rk4_step_from(s, &self.derivative(s, &totals[0]), dt_s, totals)
    }

    /// [`VehicleLanes::rk4_step`] with its first stage `k1`, the derivative at `s` under
    /// `totals[0]` ([`VehicleLanes::derivative`]), computed by the caller (who also reads it).
    #[inline(always)]
    pub fn rk4_step_from(
        &self,
        s: &BodyLanes<L>,
        k1: &BodyLanes<L>,
        dt_s: f64,
        totals: &[TotalsLanes<L>; 3],
    ) -> BodyLanes<L> {
        let half = L::splat(0.5 * dt_s);
        let k1 = *k1;
        let s2 = advanced(s, &k1, half);
        let k2 = self.derivative(&s2, &totals[1]);
        let s3 = advanced(s, &k2, half);
        let k3 = self.derivative(&s3, &totals[1]);
        let s4 = advanced(s, &k3, L::splat(dt_s));
        let k4 = self.derivative(&s4, &totals[2]);
        let sixth = L::splat(dt_s / 6.0);
        let two = L::splat(2.0);
        let combine = |x: &[L; 3], a: &[L; 3], b: &[L; 3], c: &[L; 3], d: &[L; 3]| {
            each(|i| x[i] + (a[i] + two * b[i] + two * c[i] + d[i]) * sixth)
        };
        let q: [L; 4] = each(|i| {
            s.attitude[i]
                + (k1.attitude[i] + k2.attitude[i] * two + k3.attitude[i] * two + k4.attitude[i])
                    * sixth
        });
        // nalgebra's 4-vector norm: (x^2 + z^2) + (y^2 + w^2), then 0 + that.
        let norm =
            (L::splat(0.0) + ((q[0] * q[0] + q[2] * q[2]) + (q[1] * q[1] + q[3] * q[3]))).sqrt();
        BodyLanes {
            position_m: combine(
                &s.position_m,
                &k1.position_m,
                &k2.position_m,
                &k3.position_m,
                &k4.position_m,
            ),
            velocity_m_s: combine(
                &s.velocity_m_s,
                &k1.velocity_m_s,
                &k2.velocity_m_s,
                &k3.velocity_m_s,
                &k4.velocity_m_s,
            ),
            attitude: each(|i| q[i] / norm),
            omega_rad_s: combine(
                &s.omega_rad_s,
                &k1.omega_rad_s,
                &k2.omega_rad_s,
                &k3.omega_rad_s,
                &k4.omega_rad_s,
            ),
        }
    }

    /// The world force of [`Vehicle::wrench_from`] with constant wind: `weight - c_lin air +
    /// R (0, 0, -T)`.
    #[inline(always)]
    pub fn force_world_n(&self, s: &BodyLanes<L>, totals: &TotalsLanes<L>) -> [L; 3] {
        let air: [L; 3] = each(|i| s.velocity_m_s[i] - self.wind_m_s[i]);
        let zero = L::splat(0.0);
        let weight = [zero, zero, self.weight_n];
        let thrust = rotate(&s.attitude, &[zero, zero, -totals.thrust_n]);
        each(|i| weight[i] - self.linear_drag_n_s_m * air[i] + thrust[i])
    }

    /// What an accelerometer at the centre of mass measures, body FRD ([`Vehicle::specific_force`]
    /// in its order of operations: `R^T ((force - weight) / mass)`, `R^T` the conjugate's
    /// rotation).
    #[inline(always)]
    pub fn specific_force(&self, s: &BodyLanes<L>, totals: &TotalsLanes<L>) -> [L; 3] {
        let force = self.force_world_n(s, totals);
        let zero = L::splat(0.0);
        let weight = [zero, zero, self.weight_n];
        let f: [L; 3] = each(|i| (force[i] - weight[i]) / self.mass_kg);
        let q = &s.attitude;
        rotate(&[-q[0], -q[1], -q[2], q[3]], &f)
    }

    /// Newton-Euler under the vehicle wrench ([`Vehicle::wrench_from`] with constant wind).
    #[inline(always)]
    pub fn derivative(&self, s: &BodyLanes<L>, totals: &TotalsLanes<L>) -> BodyLanes<L> {
        let w = s.omega_rad_s;
        // Wrench: torque = rotors - c_rot omega; force = weight - c_lin air + R (0, 0, -T).
        let torque: [L; 3] = each(|i| totals.torque_body_nm[i] - self.rotational_drag_n_m_s * w[i]);
        let zero = L::splat(0.0);
        let q = &s.attitude;
        let force = self.force_world_n(s, totals);
        // Newton-Euler.
        let j = &self.inertia;
        let j_omega: [L; 3] = each(|r| j[r][0] * w[0] + j[r][1] * w[1] + j[r][2] * w[2]);
        let gyro = cross(&w, &j_omega);
        let net: [L; 3] = each(|i| torque[i] - gyro[i]);
        let ji = &self.inertia_inverse;
        let half = L::splat(0.5);
        // q * (0, omega) term by term as nalgebra writes it (rhs w = 0 kept: same signed zeros).
        let attitude = [
            (q[3] * w[0] + q[0] * zero + q[1] * w[2] - q[2] * w[1]) * half,
            (q[3] * w[1] - q[0] * w[2] + q[1] * zero + q[2] * w[0]) * half,
            (q[3] * w[2] + q[0] * w[1] - q[1] * w[0] + q[2] * zero) * half,
            (q[3] * zero - q[0] * w[0] - q[1] * w[1] - q[2] * w[2]) * half,
        ];
        BodyLanes {
            position_m: s.velocity_m_s,
            velocity_m_s: each(|i| force[i] * self.inverse_mass),
            attitude,
            omega_rad_s: each(|r| ji[r][0] * net[0] + ji[r][1] * net[1] + ji[r][2] * net[2]),
        }
    }
}

/// `a x b` per lane.
#[inline(always)]
pub(crate) fn cross<L: Lanes>(a: &[L; 3], b: &[L; 3]) -> [L; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `q v` for a unit quaternion `q` (`[x, y, z, w]`), as nalgebra's `UnitQuaternion * Vector3`
/// writes it: `(t w + q_v x t) + v` with `t = (q_v x v) 2`.
#[inline(always)]
pub(crate) fn rotate<L: Lanes>(q: &[L; 4], v: &[L; 3]) -> [L; 3] {
    let qv = [q[0], q[1], q[2]];
    let two = L::splat(2.0);
    let t0 = cross(&qv, v);
    let t: [L; 3] = each(|i| t0[i] * two);
    let c = cross(&qv, &t);
    each(|i| t[i] * q[3] + c[i] + v[i])
}

/// `s + h d` (RK4's intermediate states; the quaternion not renormalised).
#[inline(always)]
fn advanced<L: Lanes>(s: &BodyLanes<L>, d: &BodyLanes<L>, h: L) -> BodyLanes<L> {
    BodyLanes {
        position_m: each(|i| s.position_m[i] + d.position_m[i] * h),
        velocity_m_s: each(|i| s.velocity_m_s[i] + d.velocity_m_s[i] * h),
        attitude: each(|i| s.attitude[i] + d.attitude[i] * h),
        omega_rad_s: each(|i| s.omega_rad_s[i] + d.omega_rad_s[i] * h),
    }
}

/// `[f(0), f(1), .., f(N - 1)]`, written out: `std::array::from_fn` over lane values was left
/// out of line by LLVM and compiled for the baseline target (SSE2 pairs, outside the AVX2
/// function; see benches/README.md, "Batches in SIMD lanes").
#[inline(always)]
pub(crate) fn each<L: Lanes, const N: usize>(f: impl Fn(usize) -> L) -> [L; N] {
    let mut out = [L::splat(0.0); N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
    out
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, UnitQuaternion, Vector3};

    use super::*;
    use crate::flight::vehicle::{Drag, RotorTotals};

    /// A reproducible spread of moving, tilted, spinning states (no random crate needed).
    fn state(k: usize) -> RigidBodyState {
        let x = |i: usize| ((k * 7 + i * 13) as f64 * 0.618_033_988_7).sin();
        RigidBodyState {
            position_m: Vector3::new(x(1), x(2), -10.0 + x(3)),
            velocity_m_s: Vector3::new(x(4), 2.0 * x(5), x(6)),
            attitude: UnitQuaternion::from_euler_angles(0.6 * x(7), 0.5 * x(8), 3.0 * x(9)),
            omega_rad_s: Vector3::new(3.0 * x(10), x(11), 2.0 * x(12)),
        }
    }

    #[test]
    fn a_portable_path_never_runs_the_avx2_form_and_the_detected_one_can() {
        let _serial = portable_choices::serial();
        let before = portable_choices::snapshot();
        assert!(!runs_avx2(LanePath::Portable, Choice::Kernel));
        assert_eq!(
            portable_choices::snapshot()[Choice::Kernel as usize],
            before[3] + 1
        );
        let detected = detected_path();
        assert_eq!(
            runs_avx2(detected, Choice::Group),
            detected == LanePath::Avx2
        );
        assert_eq!(
            runs_avx2(LanePath::Avx2, Choice::Group),
            detected == LanePath::Avx2
        );
    }

    fn totals(k: usize, node: usize) -> RotorTotals {
        let x = |i: usize| ((k * 11 + node * 5 + i) as f64 * 0.414_213_562).cos();
        RotorTotals {
            thrust_n: 8.0 + x(0),
            torque_body_nm: Vector3::new(0.1 * x(1), 0.1 * x(2), 0.01 * x(3)),
            spin_rad_s: 0.0,
        }
    }

    /// The limits' quantities per lane are the scalar check's, bit for bit.
    #[test]
    fn limit_parts_equal_the_scalar_check_bit_for_bit() {
        let mut s = BodyLanes::<F64x4>::zeros();
        for i in 0..4 {
            s.set(i, &state(i + 3));
        }
        let (n3z, speed2, rate2) = s.limit_parts();
        for i in 0..4 {
            let x = state(i + 3);
            let q = x.attitude.quaternion();
            let scalar_n3z = q.w * q.w - q.i * q.i - q.j * q.j + q.k * q.k;
            assert_eq!(n3z.lane(i).to_bits(), scalar_n3z.to_bits());
            assert_eq!(
                speed2.lane(i).to_bits(),
                x.velocity_m_s.norm_squared().to_bits()
            );
            assert_eq!(
                rate2.lane(i).to_bits(),
                x.omega_rad_s.norm_squared().to_bits()
            );
        }
    }

    /// Four lanes step exactly (bit for bit) as four scalar `RigidBody::rk4_step_nodes` calls
    /// with `Vehicle::wrench_from`, on a body with a full (non-diagonal) inertia tensor, drag
    /// and wind.
    #[test]
    fn lanes_equal_the_scalar_rk4_step_bit_for_bit() {
        let airframe = crate::fixtures::preset("quad-x");
        let aero = Drag {
            linear_drag_n_s_m: 0.12,
            rotational_drag_n_m_s: 0.013,
            ..Drag::default()
        };
        let mut vehicle = Vehicle::new(&airframe, aero).unwrap();
        let j = Matrix3::new(
            0.030, 0.002, -0.001, 0.002, 0.045, 0.003, -0.001, 0.003, 0.060,
        );
        vehicle.set_body_for_tests(crate::flight::rigid_body::RigidBody::new(1.3, j).unwrap());
        let wind = Vector3::new(1.5, -0.7, 0.2);
        let lanes = VehicleLanes::<F64x4>::new(&vehicle, &wind).unwrap();
        let scalar_lanes = VehicleLanes::<f64>::new(&vehicle, &wind).unwrap();
        for group in 0..8 {
            let mut s = BodyLanes::<F64x4>::zeros();
            let mut tot = [TotalsLanes {
                thrust_n: F64x4::splat(0.0),
                torque_body_nm: [F64x4::splat(0.0); 3],
            }; 3];
            for i in 0..4 {
                s.set(i, &state(4 * group + i));
                for (node, t) in tot.iter_mut().enumerate() {
                    let r = totals(4 * group + i, node);
                    t.thrust_n.set_lane(i, r.thrust_n);
                    for k in 0..3 {
                        t.torque_body_nm[k].set_lane(i, r.torque_body_nm[k]);
                    }
                }
            }
            let dt = 2.5e-3;
            let mut next = lanes.rk4_step(&s, dt, &tot);
            for _ in 0..50 {
                next = lanes.rk4_step(&next, dt, &tot);
            }
            for i in 0..4 {
                let k = 4 * group + i;
                let r: [RotorTotals; 3] = std::array::from_fn(|node| totals(k, node));
                let mut expected = state(k);
                let mut one = BodyLanes::<f64>::zeros();
                one.set(0, &expected);
                for _ in 0..51 {
                    expected = vehicle.body().rk4_step_nodes(&expected, dt, |node, x| {
                        vehicle.wrench_from(x, &r[node], &wind)
                    });
                    let t1: [TotalsLanes<f64>; 3] = std::array::from_fn(|node| TotalsLanes {
                        thrust_n: r[node].thrust_n,
                        torque_body_nm: r[node].torque_body_nm.into(),
                    });
                    one = scalar_lanes.rk4_step(&one, dt, &t1);
                }
                assert_eq!(next.get(i), expected, "group {group} lane {i}");
                assert_eq!(one.get(0), expected, "group {group} lane {i} (f64 lanes)");
            }
        }
    }
}
