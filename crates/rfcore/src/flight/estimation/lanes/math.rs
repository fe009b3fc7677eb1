//! Vectors, quaternions and 3 x 3 matrices over a lane type, each operation in the order nalgebra
//! evaluates it for `f64` (so a lane computes the scalar estimator's bits; module docs of
//! [`crate::flight::lanes`]): matrix-vector products summed column by column, `((a0 x0 + a1 x1)
//! + a2 x2)`; the 3-vector norm `0 + ((x^2 + y^2) + z^2)` and the quaternion's `0 + ((x^2 + z^2)
//! + (y^2 + w^2))`; quaternion products term by term; a unit quaternion rotates `v` as
//! `(t w + q x t) + v` with `t = (q x v) 2`. Checked bit for bit against nalgebra by the tests.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use crate::flight::estimation::eskf::{EXP_COS_SERIES, EXP_SERIES_LIMIT_RAD2, EXP_SINC_SERIES};
use crate::flight::lanes::Lanes;
// Shared with the batch lanes' rigid body (`each`: the written-out array constructor).
pub(crate) use crate::flight::lanes::{cross, each, rotate};

/// A 3-vector per lane.
pub(crate) type V3<L> = [L; 3];
/// A quaternion per lane, stored `[x, y, z, w]` (nalgebra's order).
pub(crate) type Q<L> = [L; 4];
/// A 3 x 3 matrix per lane, row-major (`m[row][column]`).
pub(crate) type M3<L> = [[L; 3]; 3];

/// Lanes selected by a bit mask (bit `i`: lane `i`).
pub(crate) type Mask = u32;

/// [`each`] for rows of three.
#[inline(always)]
pub(crate) fn each3<L: Lanes, const N: usize>(f: impl Fn(usize) -> [L; 3]) -> [[L; 3]; N] {
    let mut out = [[L::splat(0.0); 3]; N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
    out
}

/// Every lane of `L`.
#[inline(always)]
pub(crate) fn all<L: Lanes>() -> Mask {
    if L::WIDTH >= 32 {
        Mask::MAX
    } else {
        (1 << L::WIDTH) - 1
    }
}

/// Lane by lane: `a` where `mask` has the lane, `b` elsewhere.
#[inline(always)]
pub(crate) fn select<L: Lanes>(mask: Mask, a: L, b: L) -> L {
    let mut out = b;
    for i in 0..L::WIDTH {
        if mask & (1 << i) != 0 {
            out.set_lane(i, a.lane(i));
        }
    }
    out
}

/// `select` over an array.
#[inline(always)]
pub(crate) fn select_n<L: Lanes, const N: usize>(mask: Mask, a: &[L; N], b: &[L; N]) -> [L; N] {
    each(|k| select(mask, a[k], b[k]))
}

#[inline(always)]
pub(crate) fn splat3<L: Lanes>(v: &Vector3<f64>) -> V3<L> {
    [L::splat(v.x), L::splat(v.y), L::splat(v.z)]
}

#[inline(always)]
pub(crate) fn add<L: Lanes>(a: &V3<L>, b: &V3<L>) -> V3<L> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub(crate) fn sub<L: Lanes>(a: &V3<L>, b: &V3<L>) -> V3<L> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(crate) fn scale<L: Lanes>(a: &V3<L>, s: L) -> V3<L> {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// nalgebra's `norm_squared` of a 3-vector.
#[inline(always)]
pub(crate) fn norm_squared<L: Lanes>(a: &V3<L>) -> L {
    L::splat(0.0) + ((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2])
}

/// `a.lerp(b, t)`: nalgebra's `t b + (1 - t) a` (its `axpy`), which at `t = 1` (a zero `1 - t`)
/// is `b` itself, not `b + 0 a` (they differ in a zero's sign or for an `a` not finite).
#[inline(always)]
pub(crate) fn lerp<L: Lanes>(a: &V3<L>, b: &V3<L>, t: f64) -> V3<L> {
    if t == 1.0 {
        return *b;
    }
    let (t, u) = (L::splat(t), L::splat(1.0 - t));
    [
        t * b[0] + u * a[0],
        t * b[1] + u * a[1],
        t * b[2] + u * a[2],
    ]
}

/// `m v` (nalgebra's gemv: columns accumulated left to right).
#[inline(always)]
pub(crate) fn mat_vec<L: Lanes>(m: &M3<L>, v: &V3<L>) -> V3<L> {
    each(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// `q p` (Hamilton product as nalgebra writes it).
#[inline(always)]
pub(crate) fn quat_mul<L: Lanes>(a: &Q<L>, b: &Q<L>) -> Q<L> {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

/// `renormalize_fast`: `q (3 - |q|^2) / 2`.
#[inline(always)]
pub(crate) fn renormalize_fast<L: Lanes>(q: &Q<L>) -> Q<L> {
    let n2 = L::splat(0.0) + ((q[0] * q[0] + q[2] * q[2]) + (q[1] * q[1] + q[3] * q[3]));
    let s = L::splat(0.5) * (L::splat(3.0) - n2);
    [q[0] * s, q[1] * s, q[2] * s, q[3] * s]
}

/// `to_rotation_matrix` (nalgebra's formula).
#[inline(always)]
pub(crate) fn rotation_matrix<L: Lanes>(q: &Q<L>) -> M3<L> {
    let [i, j, k, w] = *q;
    let two = L::splat(2.0);
    let (ww, ii, jj, kk) = (w * w, i * i, j * j, k * k);
    let ij = i * j * two;
    let wk = w * k * two;
    let wj = w * j * two;
    let ik = i * k * two;
    let jk = j * k * two;
    let wi = w * i * two;
    [
        [ww + ii - jj - kk, ij - wk, wj + ik],
        [wk + ij, ww - ii + jj - kk, jk - wi],
        [ik - wj, wi + jk, ww - ii - jj + kk],
    ]
}

/// The scalar estimator's `exp_quaternion` per lane: its polynomial in lanes when every lane's
/// angle is below its threshold, the scalar function lane by lane otherwise.
#[inline(always)]
pub(crate) fn exp_quaternion<L: Lanes>(phi: &V3<L>) -> Q<L> {
    let angle2 = norm_squared(phi);
    if (0..L::WIDTH).any(|i| angle2.lane(i) >= EXP_SERIES_LIMIT_RAD2) {
        let mut out = [L::splat(0.0); 4];
        for i in 0..L::WIDTH {
            let q = crate::flight::estimation::eskf::exp_quaternion(&lane3(phi, i));
            set_quat(&mut out, i, &q);
        }
        return out;
    }
    let c = |k: usize| L::splat(EXP_COS_SERIES[k]);
    let s = |k: usize| L::splat(EXP_SINC_SERIES[k]);
    let x2 = L::splat(0.25) * angle2;
    let cos = c(0) + x2 * (c(1) + x2 * (c(2) + x2 * (c(3) + x2 * (c(4) + x2 * c(5)))));
    let sinc = s(0) + x2 * (s(1) + x2 * (s(2) + x2 * (s(3) + x2 * s(4))));
    [phi[0] * sinc, phi[1] * sinc, phi[2] * sinc, cos]
}

/// Lane `i` of a 3-vector.
#[inline(always)]
pub(crate) fn lane3<L: Lanes>(v: &V3<L>, i: usize) -> Vector3<f64> {
    Vector3::new(v[0].lane(i), v[1].lane(i), v[2].lane(i))
}

#[inline(always)]
pub(crate) fn set3<L: Lanes>(v: &mut V3<L>, i: usize, x: &Vector3<f64>) {
    for k in 0..3 {
        v[k].set_lane(i, x[k]);
    }
}

/// Lane `i` of a quaternion.
#[inline(always)]
pub(crate) fn lane_quat<L: Lanes>(q: &Q<L>, i: usize) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
        q[3].lane(i),
        q[0].lane(i),
        q[1].lane(i),
        q[2].lane(i),
    ))
}

#[inline(always)]
pub(crate) fn set_quat<L: Lanes>(q: &mut Q<L>, i: usize, x: &UnitQuaternion<f64>) {
    let c = &x.quaternion().coords;
    for k in 0..4 {
        q[k].set_lane(i, c[k]);
    }
}

#[inline(always)]
pub(crate) fn set_mat<L: Lanes>(m: &mut M3<L>, i: usize, x: &Matrix3<f64>) {
    for r in 0..3 {
        for c in 0..3 {
            m[r][c].set_lane(i, x[(r, c)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::lanes::F64x4;
    use crate::flight::random::Gaussian;

    fn vectors(g: &mut Gaussian) -> (V3<F64x4>, [Vector3<f64>; 4]) {
        let v: [Vector3<f64>; 4] =
            std::array::from_fn(|_| Vector3::new(g.sample(), g.sample(), g.sample()) * 3.0);
        let mut out = [F64x4::splat(0.0); 3];
        for (i, x) in v.iter().enumerate() {
            set3(&mut out, i, x);
        }
        (out, v)
    }

    fn quats(g: &mut Gaussian) -> (Q<F64x4>, [UnitQuaternion<f64>; 4]) {
        let q: [UnitQuaternion<f64>; 4] = std::array::from_fn(|_| {
            UnitQuaternion::from_scaled_axis(Vector3::new(g.sample(), g.sample(), g.sample()))
        });
        let mut out = [F64x4::splat(0.0); 4];
        for (i, x) in q.iter().enumerate() {
            set_quat(&mut out, i, x);
        }
        (out, q)
    }

    fn same3(a: &V3<F64x4>, b: &[Vector3<f64>; 4]) {
        for (i, x) in b.iter().enumerate() {
            for k in 0..3 {
                assert_eq!(a[k].lane(i).to_bits(), x[k].to_bits(), "lane {i} entry {k}");
            }
        }
    }

    fn same_quat(a: &Q<F64x4>, b: &[UnitQuaternion<f64>; 4]) {
        for (i, x) in b.iter().enumerate() {
            for k in 0..4 {
                let expected = x.quaternion().coords[k];
                assert_eq!(
                    a[k].lane(i).to_bits(),
                    expected.to_bits(),
                    "lane {i} entry {k}"
                );
            }
        }
    }

    #[test]
    fn every_operation_equals_nalgebra_bit_for_bit() {
        let mut g = Gaussian::new(3);
        for _ in 0..200 {
            let (a, av) = vectors(&mut g);
            let (b, bv) = vectors(&mut g);
            let (q, qv) = quats(&mut g);
            let (p, pv) = quats(&mut g);
            same3(
                &cross(&a, &b),
                &std::array::from_fn(|i| av[i].cross(&bv[i])),
            );
            // Inside, at the ends (nalgebra takes `b` itself at 1), and with a signed zero and an
            // infinity where the ends' arithmetic would show them.
            for t in [0.37, 0.0, 1.0] {
                same3(
                    &lerp(&a, &b, t),
                    &std::array::from_fn(|i| av[i].lerp(&bv[i], t)),
                );
            }
            let (mut odd_a, mut odd_b) = (a, b);
            odd_a[0].set_lane(1, f64::INFINITY);
            odd_b[1].set_lane(2, -0.0);
            for t in [0.0, 1.0] {
                let expected: [Vector3<f64>; 4] =
                    std::array::from_fn(|i| lane3(&odd_a, i).lerp(&lane3(&odd_b, i), t));
                for (i, x) in expected.iter().enumerate() {
                    for k in 0..3 {
                        let got = lerp(&odd_a, &odd_b, t)[k].lane(i);
                        assert!(
                            got.to_bits() == x[k].to_bits() || (got.is_nan() && x[k].is_nan()),
                            "t {t} lane {i}: {got} against {}",
                            x[k]
                        );
                    }
                }
            }
            same3(&rotate(&q, &a), &std::array::from_fn(|i| qv[i] * av[i]));
            let n = norm_squared(&a);
            for i in 0..4 {
                assert_eq!(n.lane(i).to_bits(), av[i].norm_squared().to_bits());
            }
            same_quat(&quat_mul(&q, &p), &std::array::from_fn(|i| qv[i] * pv[i]));
            let mut loose = quat_mul(&q, &p);
            loose[0] = loose[0] * F64x4::splat(1.0 + 1e-9);
            let expected: [UnitQuaternion<f64>; 4] = std::array::from_fn(|i| {
                let mut x = lane_quat(&loose, i);
                x.renormalize_fast();
                x
            });
            same_quat(&renormalize_fast(&loose), &expected);
            let r = rotation_matrix(&q);
            let m: [nalgebra::Matrix3<f64>; 4] =
                std::array::from_fn(|i| qv[i].to_rotation_matrix().into_inner());
            same3(&mat_vec(&r, &a), &std::array::from_fn(|i| m[i] * av[i]));
            for (i, mi) in m.iter().enumerate() {
                for rr in 0..3 {
                    for c in 0..3 {
                        assert_eq!(r[rr][c].lane(i).to_bits(), mi[(rr, c)].to_bits());
                    }
                }
            }
            // Both branches of the exponential: small angles (polynomial) and one lane large.
            let small = scale(&a, F64x4::splat(0.01));
            same_quat(
                &exp_quaternion(&small),
                &std::array::from_fn(|i| {
                    crate::flight::estimation::eskf::exp_quaternion(&lane3(&small, i))
                }),
            );
            same_quat(
                &exp_quaternion(&a),
                &std::array::from_fn(|i| crate::flight::estimation::eskf::exp_quaternion(&av[i])),
            );
        }
    }

    #[test]
    fn select_takes_the_masked_lanes() {
        let a = F64x4::splat(1.0);
        let b = F64x4::splat(2.0);
        let s = select(0b0101, a, b);
        assert_eq!(s.0, [1.0, 2.0, 1.0, 2.0]);
        assert_eq!(all::<F64x4>(), 0b1111);
        assert_eq!(all::<f64>(), 1);
    }
}
