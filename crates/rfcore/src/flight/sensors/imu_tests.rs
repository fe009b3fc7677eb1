use super::*;
use crate::flight::sensors::allan::{
    fit_white_and_walk, log_spaced_clusters, overlapping_allan_deviation,
};
use crate::flight::sensors::{assert_rules_name_fields, RuleCase};

fn at_rest() -> ImuTruth {
    ImuTruth {
        omega_rad_s: Vector3::zeros(),
        angular_acceleration_rad_s2: Vector3::zeros(),
        specific_force_m_s2: Vector3::new(0.0, 0.0, -9.81),
    }
}

/// The three gyro axes of `imu` at rest, `n` samples each.
fn gyro_records(imu: &mut Imu, n: usize) -> [Vec<f64>; 3] {
    let truth = at_rest();
    let mut out = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for _ in 0..n {
        let s = imu.sample(&truth);
        for (axis, record) in out.iter_mut().enumerate() {
            record.push(s.gyro_rad_s[axis]);
        }
    }
    out
}

/// Noise density and bias random walk fitted to the Allan variance averaged over `records`
/// (independent axes of one sensor: the average has a third of one axis's scatter).
fn fitted(records: &[Vec<f64>], rate_hz: f64) -> (f64, f64) {
    let clusters = log_spaced_clusters(records[0].len(), 5);
    let mut points = overlapping_allan_deviation(&records[0], rate_hz, &clusters).unwrap();
    for record in &records[1..] {
        let more = overlapping_allan_deviation(record, rate_hz, &clusters).unwrap();
        for (p, q) in points.iter_mut().zip(more) {
            p.deviation = p.deviation.hypot(q.deviation);
        }
    }
    for p in &mut points {
        p.deviation /= (records.len() as f64).sqrt();
    }
    fit_white_and_walk(&points).unwrap()
}

/// The ICM-42688-P sampled at 25 Hz: the Allan deviation depends on the densities, not on the
/// rate, and 25 Hz keeps a 16,000 s record (6,700 crossover times sqrt(3) N / B = 2.4 s) to
/// 400,000 samples per axis. Over seeds 0-11 the fitted walk scattered by 1.1 % (1 sigma) and
/// the density by 0.1 %: 10 % is a nine-sigma check, which the seed cannot pass by luck.
fn allan_profile() -> ImuProfile {
    ImuProfile {
        rate_hz: 25.0,
        ..ImuProfile::icm_42688_p()
    }
}

#[test]
fn allan_deviation_recovers_noise_density_and_bias_walk_within_10_percent() {
    let profile = allan_profile();
    let mut imu = Imu::new(profile, 2024).unwrap();
    let records = gyro_records(&mut imu, 400_000);
    let (density, walk) = fitted(&records, profile.rate_hz);
    let n_err = density / profile.gyro.noise_density_rad_s_rt_hz - 1.0;
    let b_err = walk / profile.gyro.bias_walk_rad_s_rt_s - 1.0;
    println!(
        "Allan fit: N = {density:.4e} rad/s/sqrt(Hz) ({:+.1} %), B = {walk:.4e} rad/s/sqrt(s) ({:+.1} %)",
        100.0 * n_err,
        100.0 * b_err
    );
    assert!(
        n_err.abs() < 0.10,
        "noise density off by {:.1} %",
        100.0 * n_err
    );
    assert!(
        b_err.abs() < 0.10,
        "bias walk off by {:.1} %",
        100.0 * b_err
    );
}

#[test]
fn allan_check_catches_a_walk_scaled_by_dt_instead_of_sqrt_dt() {
    // The classic discretisation slip: b += B dt w instead of B sqrt(dt) w. At 25 Hz it shrinks
    // the walk fivefold; the same fit must see it (the check above can fail).
    let profile = allan_profile();
    let period = 1.0 / profile.rate_hz;
    let mut g = Gaussian::new(2024);
    let white = profile.gyro.noise_density_rad_s_rt_hz / period.sqrt();
    let mut bias = 0.0;
    let record: Vec<f64> = (0..400_000)
        .map(|_| {
            let y = bias + white * g.sample();
            bias += profile.gyro.bias_walk_rad_s_rt_s * period * g.sample();
            y
        })
        .collect();
    let (_, walk) = fitted(&[record], profile.rate_hz);
    assert!(
        (walk / profile.gyro.bias_walk_rad_s_rt_s - 1.0).abs() > 0.5,
        "a walk ten times too small was not seen: {walk:e}"
    );
}

#[test]
fn error_model_is_the_drawn_matrix_plus_bias_and_saturates_with_a_flag() {
    let mut profile = ImuProfile::mpu_6000();
    profile.gyro.noise_density_rad_s_rt_hz = 0.0;
    profile.gyro.bias_walk_rad_s_rt_s = 0.0;
    profile.accel.noise_density_m_s2_rt_hz = 0.0;
    profile.accel.bias_walk_m_s2_rt_s = 0.0;
    let mut imu = Imu::new(profile, 3).unwrap();
    let (mg, ma) = imu.error_matrices();
    let (bg, ba) = (imu.gyro_bias_rad_s(), imu.accel_bias_m_s2());
    let w = Vector3::new(1.0, -2.0, 5.0);
    let f = Vector3::new(0.3, 0.2, -9.0);
    let truth = ImuTruth {
        omega_rad_s: w,
        angular_acceleration_rad_s2: Vector3::zeros(),
        specific_force_m_s2: f,
    };
    let s = imu.sample(&truth);
    assert!((s.gyro_rad_s - (mg * w + bg)).norm() < 1e-12);
    assert!((s.accel_m_s2 - (ma * f + ba)).norm() < 1e-12);
    assert!(!s.gyro_saturated && !s.accel_saturated);
    // The matrices are I + S + E with the datasheet's sizes (3 % and 2 % for the MPU-6000).
    assert!((mg - Matrix3::identity()).amax() < 5.0 * 0.03);
    // 40 rad/s about z is beyond 2000 deg/s = 34.9 rad/s: clamped at the range and flagged.
    let spin = ImuTruth {
        omega_rad_s: Vector3::new(0.0, 0.0, 40.0),
        ..truth
    };
    let s = imu.sample(&spin);
    assert!(s.gyro_saturated && !s.accel_saturated);
    assert_eq!(s.gyro_rad_s.z, profile.gyro.range_rad_s);
    assert_eq!(imu.saturated_samples(), 1);
}

#[test]
fn drawn_errors_have_the_datasheet_spread_across_seeds() {
    // Turn-on bias, scale error and cross-axis terms are 1-sigma figures: over 2000 IMUs their
    // sample standard deviations match within 4 standard errors (1 / sqrt(2 n) relative).
    let profile = ImuProfile::icm_42688_p();
    let (mut on, mut scale, mut cross) = (0.0, 0.0, 0.0);
    let n = 2000;
    for seed in 0..n {
        let imu = Imu::new(profile, seed).unwrap();
        let (mg, _) = imu.error_matrices();
        on += imu.gyro_bias_rad_s().x.powi(2);
        scale += (mg[(0, 0)] - 1.0).powi(2);
        cross += mg[(0, 1)].powi(2);
    }
    let tol = 4.0 / (2.0 * n as f64).sqrt();
    let g = &profile.gyro;
    for (name, var, sigma) in [
        ("turn-on bias", on, g.turn_on_bias_rad_s),
        ("scale error", scale, g.scale_error),
        ("cross axis", cross, g.cross_axis),
    ] {
        let ratio = (var / n as f64).sqrt() / sigma;
        assert!((ratio - 1.0).abs() < tol, "{name}: {ratio}");
    }
}

#[test]
fn white_noise_per_sample_is_density_times_sqrt_rate() {
    let mut profile = ImuProfile::icm_42688_p();
    profile.gyro.bias_walk_rad_s_rt_s = 0.0;
    profile.accel.bias_walk_m_s2_rt_s = 0.0;
    let mut imu = Imu::new(profile, 8).unwrap();
    let n = 50_000;
    let truth = at_rest();
    let samples: Vec<ImuSample> = (0..n).map(|_| imu.sample(&truth)).collect();
    let mean_g: Vector3<f64> =
        samples.iter().map(|s| s.gyro_rad_s).sum::<Vector3<f64>>() / n as f64;
    let var_g = samples
        .iter()
        .map(|s| (s.gyro_rad_s - mean_g).norm_squared())
        .sum::<f64>()
        / (3 * n) as f64;
    let expected = profile.gyro.noise_density_rad_s_rt_hz * profile.rate_hz.sqrt();
    // Standard error of a variance over 3n samples: sqrt(2 / 3n) = 0.4 %.
    assert!(
        (var_g.sqrt() / expected - 1.0).abs() < 0.01,
        "{} vs {expected}",
        var_g.sqrt()
    );
    assert!((mean_g - imu.gyro_bias_rad_s()).amax() < 5.0 * expected / (n as f64).sqrt());
}

#[test]
fn accelerometer_off_the_centre_of_mass_feels_the_centripetal_acceleration() {
    let mut profile = ImuProfile::icm_42688_p();
    profile.accel = AccelProfile {
        noise_density_m_s2_rt_hz: 0.0,
        bias_walk_m_s2_rt_s: 0.0,
        turn_on_bias_m_s2: 0.0,
        scale_error: 0.0,
        cross_axis: 0.0,
        ..profile.accel
    };
    profile.position_m = Vector3::new(0.01, 0.0, 0.0);
    let mut imu = Imu::new(profile, 1).unwrap();
    let truth = ImuTruth {
        omega_rad_s: Vector3::new(0.0, 0.0, 30.0),
        angular_acceleration_rad_s2: Vector3::new(0.0, 0.0, 100.0),
        specific_force_m_s2: Vector3::new(0.0, 0.0, -9.81),
    };
    let s = imu.sample(&truth);
    // omega x (omega x r) = -900 * 0.01 x-hat = -9 m/s^2; alpha x r = 100 * 0.01 y-hat = 1 m/s^2.
    assert!(
        (s.accel_m_s2 - Vector3::new(-9.0, 1.0, -9.81)).norm() < 1e-12,
        "{}",
        s.accel_m_s2
    );
}

#[test]
fn vibration_has_its_rms_and_resonator_spectrum() {
    let mut profile = ImuProfile::icm_42688_p();
    profile.accel.vibration = Vibration {
        rms_m_s2: 2.0,
        frequency_hz: 150.0,
        bandwidth_hz: 30.0,
    };
    profile.check().unwrap();
    let mut g = Gaussian::new(5);
    let mut resonator = Resonator::new(&profile.accel.vibration, profile.rate_hz, &mut g);
    let n = 200_000;
    let xs: Vec<f64> = (0..n).map(|_| resonator.next(&mut g).x).collect();
    let var = xs.iter().map(|x| x * x).sum::<f64>() / n as f64;
    let lag = |k: usize| xs.windows(k + 1).map(|w| w[0] * w[k]).sum::<f64>() / (n - k) as f64 / var;
    let (rho1, rho2) = resonator.autocorrelations();
    // The resonator's bandwidth keeps samples correlated over ~1 / (pi 30 Hz) = 10 ms = 10
    // samples: the effective sample count is ~n / 20, so the variance is good to ~2 %.
    assert!((var.sqrt() / 2.0 - 1.0).abs() < 0.03, "rms {}", var.sqrt());
    assert!((lag(1) - rho1).abs() < 0.02 && (lag(2) - rho2).abs() < 0.02);
    // The lag-1 correlation of a narrow resonator is close to cos(2 pi f / rate).
    assert!(
        (rho1 - (2.0 * std::f64::consts::PI * 0.15).cos()).abs() < 0.1,
        "{rho1}"
    );
    // Off in the datasheet profiles.
    assert!(!ImuProfile::icm_42688_p().accel.vibration.is_on());
}

#[test]
fn streams_are_independent_and_seeded() {
    let truth = at_rest();
    let mut a = Imu::new(ImuProfile::icm_42688_p(), 77).unwrap();
    let mut b = Imu::new(ImuProfile::icm_42688_p(), 77).unwrap();
    let mut c = Imu::new(ImuProfile::icm_42688_p(), 78).unwrap();
    let mut vibrating = ImuProfile::icm_42688_p();
    vibrating.accel.vibration = Vibration {
        rms_m_s2: 1.0,
        frequency_hz: 120.0,
        bandwidth_hz: 20.0,
    };
    let mut d = Imu::new(vibrating, 77).unwrap();
    for _ in 0..100 {
        let (sa, sb, sc, sd) = (
            a.sample(&truth),
            b.sample(&truth),
            c.sample(&truth),
            d.sample(&truth),
        );
        assert_eq!(sa, sb);
        assert_ne!(sa.gyro_rad_s, sc.gyro_rad_s);
        // Turning vibration on changes the accelerometer, never the gyroscope.
        assert_eq!(sa.gyro_rad_s, sd.gyro_rad_s);
        assert_ne!(sa.accel_m_s2, sd.accel_m_s2);
    }
}

#[test]
fn every_rule_names_its_field() {
    let cases: &[RuleCase<ImuProfile>] = &[
        ("imu.rate_hz", |p| p.rate_hz = 0.0),
        ("imu.gyro.noise_density_rad_s_rt_hz", |p| {
            p.gyro.noise_density_rad_s_rt_hz = -1.0
        }),
        ("imu.gyro.bias_walk_rad_s_rt_s", |p| {
            p.gyro.bias_walk_rad_s_rt_s = f64::NAN
        }),
        ("imu.gyro.turn_on_bias_rad_s", |p| {
            p.gyro.turn_on_bias_rad_s = -0.1
        }),
        ("imu.gyro.scale_error", |p| {
            p.gyro.scale_error = f64::INFINITY
        }),
        ("imu.gyro.cross_axis", |p| p.gyro.cross_axis = -0.01),
        ("imu.gyro.range_rad_s", |p| p.gyro.range_rad_s = 0.0),
        ("imu.accel.noise_density_m_s2_rt_hz", |p| {
            p.accel.noise_density_m_s2_rt_hz = -1.0
        }),
        ("imu.accel.bias_walk_m_s2_rt_s", |p| {
            p.accel.bias_walk_m_s2_rt_s = f64::NAN
        }),
        ("imu.accel.turn_on_bias_m_s2", |p| {
            p.accel.turn_on_bias_m_s2 = -1.0
        }),
        ("imu.accel.scale_error", |p| p.accel.scale_error = -1.0),
        ("imu.accel.cross_axis", |p| p.accel.cross_axis = f64::NAN),
        ("imu.accel.range_m_s2", |p| p.accel.range_m_s2 = -5.0),
        ("imu.accel.vibration.rms_m_s2", |p| {
            p.accel.vibration.rms_m_s2 = -1.0
        }),
        ("imu.accel.vibration.frequency_hz", |p| {
            p.accel.vibration = Vibration {
                rms_m_s2: 1.0,
                frequency_hz: 490.0,
                bandwidth_hz: 30.0,
            }
        }),
        ("imu.accel.vibration.bandwidth_hz", |p| {
            p.accel.vibration = Vibration {
                rms_m_s2: 1.0,
                frequency_hz: 100.0,
                bandwidth_hz: 0.0,
            }
        }),
        ("imu.position_m[2]", |p| p.position_m.z = f64::NAN),
    ];
    let base = ImuProfile::icm_42688_p();
    assert_rules_name_fields(&base, cases, |p| Imu::new(*p, 0).map(|_| ()));
    ImuProfile::mpu_6000().check().unwrap();
    ImuProfile::default().check().unwrap();
}
