//! Each laned kernel against its scalar counterpart, lane by lane, bit for bit.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::*;
use crate::flight::estimation::eskf::{
    self, Block, Covariance, Fusion, Inputs, Kinematics, NominalState, ProcessNoise, Step,
};
use crate::flight::estimation::lanes::math::{set3, set_mat, set_quat};
use crate::flight::lanes::{detected_path, portable_choices, F64x4};
use crate::flight::random::Gaussian;
use crate::flight::sensors::ImuSample;

type L = F64x4;
const W: usize = 4;

fn vector(g: &mut Gaussian, size: f64) -> Vector3<f64> {
    Vector3::new(g.sample(), g.sample(), g.sample()) * size
}

fn samples(g: &mut Gaussian, time_s: f64) -> ([ImuSample; W], ImuLanes<L>) {
    let s: [ImuSample; W] = std::array::from_fn(|_| ImuSample {
        time_s,
        gyro_rad_s: vector(g, 10.0),
        accel_m_s2: vector(g, 3.0) + Vector3::new(0.0, 0.0, -9.8),
        gyro_saturated: false,
        accel_saturated: false,
    });
    let mut lanes = ImuLanes::splat(&s[0]);
    for (i, x) in s.iter().enumerate() {
        lanes.set_lane(i, x);
    }
    (s, lanes)
}

fn states(g: &mut Gaussian) -> ([NominalState; W], NominalLanes<L>) {
    let s: [NominalState; W] = std::array::from_fn(|_| NominalState {
        position_m: vector(g, 5.0),
        velocity_m_s: vector(g, 2.0),
        attitude: UnitQuaternion::from_scaled_axis(vector(g, 1.0)),
        gyro_bias_rad_s: vector(g, 0.01),
        accel_bias_m_s2: vector(g, 0.1),
    });
    let z = [L::splat(0.0); 3];
    let mut lanes = NominalLanes {
        position_m: z,
        velocity_m_s: z,
        attitude: [L::splat(0.0); 4],
        gyro_bias_rad_s: z,
        accel_bias_m_s2: z,
    };
    for (i, x) in s.iter().enumerate() {
        set3(&mut lanes.position_m, i, &x.position_m);
        set3(&mut lanes.velocity_m_s, i, &x.velocity_m_s);
        set_quat(&mut lanes.attitude, i, &x.attitude);
        set3(&mut lanes.gyro_bias_rad_s, i, &x.gyro_bias_rad_s);
        set3(&mut lanes.accel_bias_m_s2, i, &x.accel_bias_m_s2);
    }
    (s, lanes)
}

fn same(a: f64, b: f64, what: &str) {
    assert_eq!(a.to_bits(), b.to_bits(), "{what}: {a:e} against {b:e}");
}

fn same3(a: &V3<L>, i: usize, b: &Vector3<f64>, what: &str) {
    for k in 0..3 {
        same(a[k].lane(i), b[k], what);
    }
}

fn same_quat(a: &Q<L>, i: usize, b: &UnitQuaternion<f64>, what: &str) {
    for k in 0..4 {
        same(a[k].lane(i), b.quaternion().coords[k], what);
    }
}

fn same_state(a: &NominalLanes<L>, i: usize, b: &NominalState) {
    same3(&a.position_m, i, &b.position_m, "position");
    same3(&a.velocity_m_s, i, &b.velocity_m_s, "velocity");
    same_quat(&a.attitude, i, &b.attitude, "attitude");
    same3(&a.gyro_bias_rad_s, i, &b.gyro_bias_rad_s, "gyro bias");
    same3(&a.accel_bias_m_s2, i, &b.accel_bias_m_s2, "accel bias");
}

fn same_step(a: &StepLanes<L>, i: usize, b: &Step) {
    same(a.dt_s.lane(i), b.dt_s, "dt");
    same_quat(&a.attitude, i, &b.attitude, "step attitude");
    same3(&a.force, i, &b.force, "force");
    same_quat(&a.increment, i, &b.increment, "increment");
    same3(&a.rate_end, i, &b.rate_end, "rate end");
    same3(&a.force_end, i, &b.force_end, "force end");
}

fn covariances(g: &mut Gaussian) -> ([Covariance; W], CovarianceLanes<L>) {
    let p: [Covariance; W] = std::array::from_fn(|_| {
        let l = Covariance::from_fn(|_, _| g.sample());
        l * l.transpose() + Covariance::identity()
    });
    let mut lanes = [L::splat(0.0); ENTRIES];
    for (i, x) in p.iter().enumerate() {
        for (k, v) in x.as_slice().iter().enumerate() {
            lanes[k].set_lane(i, *v);
        }
    }
    (p, lanes)
}

fn same_covariance(a: &CovarianceLanes<L>, i: usize, b: &Covariance) {
    let ai = lane_covariance(a, i);
    for k in 0..ENTRIES {
        same(
            ai.as_slice()[k],
            b.as_slice()[k],
            &format!("covariance entry {k}"),
        );
    }
}

const KIN: Kinematics = Kinematics {
    gravity_m_s2: Vector3::new(0.0, 0.0, 9.81),
    imu_position_m: Vector3::new(0.01, -0.02, 0.03),
};

fn kinematics() -> KinematicsLanes<L> {
    KinematicsLanes {
        gravity_m_s2: crate::flight::estimation::lanes::math::splat3(&KIN.gravity_m_s2),
        imu_position_m: crate::flight::estimation::lanes::math::splat3(&KIN.imu_position_m),
    }
}

/// Both compiled forms of the kernels (the portable one and this CPU's), taken in turn by the
/// rounds of each test: each equals the scalar filter.
fn paths() -> [LanePath; 2] {
    [LanePath::Portable, detected_path()]
}

#[test]
fn propagation_and_blocks_equal_the_scalar_filter() {
    let _serial = portable_choices::serial();
    let mut g = Gaussian::new(21);
    let kin = kinematics();
    for round in 0..50 {
        let (a, al) = samples(&mut g, 0.1);
        let (b, bl) = samples(&mut g, 0.102);
        let (x, xl) = states(&mut g);
        // A whole interval, its first part (to a measurement's time) and the rest.
        let spans = [(0.1, 0.102), (0.1, 0.1013), (0.1013, 0.102)];
        let (t0, t1) = spans[round % 3];
        let path = paths()[round % 2];
        let (next, step) = xl.propagate(&al, &bl, (t0, t1), &kin, path);
        let mut block = BlockLanes::start(&step);
        let (after, step2) = next.propagate(&al, &bl, (t1, 0.102_f64.max(t1 + 1e-4)), &kin, path);
        block = block.extended(&step2);
        for i in 0..W {
            let (n, s, end): (NominalState, Step, Inputs) =
                x[i].propagate_from(None, &a[i], &b[i], t0, t1, &KIN);
            same_state(&next, i, &n);
            same_step(&step, i, &s);
            let (n2, s2, _) =
                n.propagate_from(Some(&end), &a[i], &b[i], t1, 0.102_f64.max(t1 + 1e-4), &KIN);
            same_state(&after, i, &n2);
            same_step(&step2, i, &s2);
            let mut scalar_block = Block::start(&s);
            scalar_block.extend(&s2);
            same_step(&block.step, i, &scalar_block.step);
        }
    }
}

#[test]
fn covariance_propagation_update_and_reset_equal_the_scalar_filter() {
    let _serial = portable_choices::serial();
    let mut g = Gaussian::new(8);
    let kin = kinematics();
    for round in 0..30 {
        let (a, al) = samples(&mut g, 0.0);
        let (b, bl) = samples(&mut g, 0.002);
        let (x, xl) = states(&mut g);
        let path = paths()[round % 2];
        let (_, step) = xl.propagate(&al, &bl, (0.0, 0.002), &kin, path);
        let (mut p, mut pl) = covariances(&mut g);
        let noise = NoiseLanes {
            gyro_psd: L::splat(1e-6),
            accel_psd: L::splat(4e-4),
            gyro_bias_psd: [crate::flight::lanes::F64xN(std::array::from_fn(|i| {
                1e-8 * (i + 1) as f64
            })); 3],
            accel_bias_psd: [L::splat(1e-6); 3],
        };
        propagate_covariance(path, &mut pl, &step, &noise);
        for i in 0..W {
            let (_, s, _) = x[i].propagate_from(None, &a[i], &b[i], 0.0, 0.002, &KIN);
            let scalar_noise = ProcessNoise {
                gyro_psd: 1e-6,
                accel_psd: 4e-4,
                gyro_bias_psd: Vector3::repeat(1e-8 * (i + 1) as f64),
                accel_bias_psd: Vector3::repeat(1e-6),
            };
            eskf::propagate_covariance(&mut p[i], &s, &scalar_noise);
            same_covariance(&pl, i, &p[i]);
        }
        // An update with the identity (position) or a full H (magnetometer), with a gate that
        // refuses lane 2's residual.
        let block = if round % 2 == 0 { POS } else { ATT };
        let h: Option<M3<L>> = (round % 2 == 1).then(|| {
            std::array::from_fn(|r| std::array::from_fn(|c| L::splat(0.3 * (r as f64) - c as f64)))
        });
        let hs = (round % 2 == 1)
            .then(|| nalgebra::Matrix3::from_fn(|r, c| 0.3 * (r as f64) - c as f64));
        let mut r: V3<L> = [L::splat(0.0); 3];
        let residuals: [Vector3<f64>; W] =
            std::array::from_fn(|i| vector(&mut g, if i == 2 { 1e3 } else { 0.5 }));
        for (i, v) in residuals.iter().enumerate() {
            set3(&mut r, i, v);
        }
        let var = Vector3::new(0.3, 0.3, 0.5);
        let gate = 100.0;
        // Every third round lane 3's block is negative definite: no Cholesky factor there.
        if round % 3 == 2 {
            for k in 0..3 {
                let at = (block + k) * ERROR_DIM + block + k;
                p[3].as_mut_slice()[at] = -1.0;
                pl[at].set_lane(3, -1.0);
            }
        }
        let (fused, dx) = update_block(path, &mut pl, block, h.as_ref(), &r, &var, gate, 0b1111);
        for i in 0..W {
            let (fusion, dxs) =
                eskf::update_block(&mut p[i], block, hs.as_ref(), &residuals[i], &var, gate);
            assert_eq!(fusion == Fusion::Fused, fused & (1 << i) != 0, "lane {i}");
            same_covariance(&pl, i, &p[i]);
            for k in 0..ERROR_DIM {
                same(dx[k].lane(i), dxs[k], "dx");
            }
        }
        assert_eq!(fused & 0b0100, 0, "lane 2's residual is outside the gate");
        if round % 3 == 2 {
            assert_eq!(fused & 0b1000, 0, "lane 3 has no factor");
        }
        // The reset and the injection in the fused lanes.
        let dtheta: V3<L> = [dx[ATT], dx[ATT + 1], dx[ATT + 2]];
        reset_covariance(path, &mut pl, &dtheta, fused);
        let mut injected = xl;
        injected.inject(&dx, fused);
        for i in 0..W {
            let mut xi = x[i];
            if fused & (1 << i) != 0 {
                let d = Vector3::new(dx[ATT].lane(i), dx[ATT + 1].lane(i), dx[ATT + 2].lane(i));
                eskf::reset_covariance(&mut p[i], &d);
                let dxs = eskf::ErrorVector::from_fn(|k, _| dx[k].lane(i));
                xi.inject(&dxs);
            }
            same_covariance(&pl, i, &p[i]);
            same_state(&injected, i, &xi);
        }
    }
}

#[test]
fn cholesky_inverse_equals_nalgebra_bit_for_bit() {
    let mut g = Gaussian::new(17);
    for round in 0..100 {
        let mats: [Matrix3<f64>; W] = std::array::from_fn(|i| match i {
            // A diagonal matrix (its inverse's zeros and their signs), one that is not
            // positive definite (no factor), and two random ones.
            0 => Matrix3::from_diagonal(&Vector3::new(0.3, 2.0, 0.7)),
            1 if round % 2 == 0 => Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            _ => {
                let a = Matrix3::from_fn(|_, _| g.sample());
                a * a.transpose() + Matrix3::identity() * 0.1
            }
        });
        let mut lanes: M3<L> = [[L::splat(0.0); 3]; 3];
        for (i, m) in mats.iter().enumerate() {
            set_mat(&mut lanes, i, m);
        }
        let (factored, inverse) = cholesky_inverse(&lanes);
        for (i, m) in mats.iter().enumerate() {
            match m.cholesky() {
                None => assert_eq!(factored & (1 << i), 0, "lane {i} has no factor"),
                Some(chol) => {
                    assert_ne!(factored & (1 << i), 0, "lane {i} has a factor");
                    let expected = chol.inverse();
                    for r in 0..3 {
                        for c in 0..3 {
                            same(inverse[r][c].lane(i), expected[(r, c)], "inverse");
                        }
                    }
                }
            }
        }
    }
}
