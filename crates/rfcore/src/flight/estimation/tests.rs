//! The estimator against analytic truth ([`AnalyticMotion`]): error in hover and in a 30 rad/s
//! spin, NEES on a linear case over Monte Carlo runs, latency compensation against a replay
//! fed the same measurements undelayed, saturation, determinism and the settings' rules.

use nalgebra::{SMatrix, Vector3};

use super::eskf::{ACCEL_BIAS, ATT, POS, VEL};
use super::*;
use crate::flight::random::Gaussian;
use crate::flight::sensors::reference::AnalyticMotion;
use crate::flight::sensors::{assert_rules_name_fields, RuleCase};
use crate::flight::sensors::{
    AccelProfile, GyroProfile, ImuProfile, PositionSourceProfile, SensorSuite, SensorSuiteProfile,
};
use crate::state::RigidBodyState;

/// How position measurements reach the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Delivery {
    /// At arrival, stamped with their time of validity (the flight computer's view).
    Compensated,
    /// At their time of validity (a source without latency; same values).
    Undelayed,
    /// At arrival, stamped with the arrival time (no latency compensation).
    Uncompensated,
}

struct Flight {
    motion: AnalyticMotion,
    suite: SensorSuiteProfile,
    settings: EstimatorSettings,
    seed: u64,
    duration_s: f64,
    /// Errors are scored after this.
    settle_s: f64,
    delivery: Delivery,
    /// Position measurements valid within this window never arrive.
    gap_s: Option<(f64, f64)>,
    /// The horizon takes its steps from the output predictor's chain where it can (`false`:
    /// computes every one).
    reuse_trail: bool,
}

impl Flight {
    fn new(motion: AnalyticMotion, suite: SensorSuiteProfile, seed: u64) -> Self {
        Flight {
            motion,
            suite,
            settings: EstimatorSettings::for_sensors(&suite),
            seed,
            duration_s: 20.0,
            settle_s: 5.0,
            delivery: Delivery::Compensated,
            gap_s: None,
            reuse_trail: true,
        }
    }
}

#[derive(Debug, Default)]
struct Outcome {
    attitude_rms_deg: f64,
    position_rms_m: f64,
    velocity_rms_m_s: f64,
    /// RMS over the scored samples of the filter's own sigma (horizon covariance), 3-D.
    predicted_attitude_deg: f64,
    predicted_position_m: f64,
    /// (time, output state) at every IMU sample.
    outputs: Vec<(f64, RigidBodyState)>,
    /// (horizon time, horizon state) after every IMU sample.
    horizons: Vec<(f64, NominalState)>,
    /// (time, 3-D position error of the output, filter's 3-D position sigma) at every sample.
    position_track: Vec<(f64, f64, f64)>,
    counts: FusionCounts,
    /// At the horizon, at the end.
    final_covariance: Covariance,
    saturated_samples: u64,
    saw_saturation_flag: bool,
    /// Horizon steps taken from the output predictor's chain.
    chained_steps: u64,
}

fn fly(f: &Flight) -> Outcome {
    let mut suite = f.suite;
    let mut settings = f.settings;
    if f.delivery != Delivery::Compensated {
        suite.position.latency_s = 0.0;
        settings.fusion_delay_s = 0.0;
    }
    let latency = f.suite.position.latency_s;
    let mut sensors = SensorSuite::new(&suite, 4, f.seed).unwrap();
    let initial = f.motion.state_at(0.0);
    let mut estimator = Estimator::new(settings, &initial).unwrap();
    if !f.reuse_trail {
        estimator = estimator.without_trail_reuse();
    }
    let mut out = Outcome::default();
    let (mut att, mut pos, mut vel, mut p_att, mut p_pos, mut scored) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0);
    // Uncompensated delivery holds samples back by the latency, then restamps them.
    let mut held: Vec<crate::flight::sensors::PositionSample> = Vec::new();
    loop {
        let t = sensors.imu.next_sample_time_s();
        if t > f.duration_s + 1e-9 {
            break;
        }
        while sensors.position.is_due(t) {
            let at = sensors.position.next_sample_time_s();
            sensors.position.sample(&f.motion.state_at(at));
        }
        if let Some(mag) = sensors.magnetometer.as_mut() {
            while mag.is_due(t) {
                let at = mag.next_sample_time_s();
                estimator.push_magnetometer(&mag.sample(&f.motion.state_at(at)));
            }
        }
        while let Some(m) = sensors.position.poll(t) {
            if f.gap_s.is_some_and(|(a, b)| (a..b).contains(&m.valid_at_s)) {
                continue;
            }
            match f.delivery {
                Delivery::Uncompensated => held.push(m),
                _ => estimator.push_position(&m),
            }
        }
        held.retain(|m| {
            let arrives = m.valid_at_s + latency;
            if arrives <= t + 1e-9 {
                let mut late = *m;
                late.valid_at_s = arrives;
                estimator.push_position(&late);
                false
            } else {
                true
            }
        });
        let sample = sensors.imu.sample(&f.motion.imu_truth_at(t));
        estimator.push_imu(&sample).unwrap();
        let e = estimator.estimate();
        out.saw_saturation_flag |= e.gyro_saturated;
        out.outputs.push((e.time_s, e.state));
        out.horizons
            .push((estimator.horizon_time_s(), *estimator.horizon_state()));
        let truth = f.motion.state_at(t);
        let p = estimator.covariance();
        out.position_track.push((
            t,
            (e.state.position_m - truth.position_m).norm(),
            (0..3).map(|i| p[(POS + i, POS + i)]).sum::<f64>().sqrt(),
        ));
        if t >= f.settle_s {
            att += e.state.attitude.angle_to(&truth.attitude).powi(2);
            pos += (e.state.position_m - truth.position_m).norm_squared();
            vel += (e.state.velocity_m_s - truth.velocity_m_s).norm_squared();
            p_att += (0..3).map(|i| p[(ATT + i, ATT + i)]).sum::<f64>();
            p_pos += (0..3).map(|i| p[(POS + i, POS + i)]).sum::<f64>();
            scored += 1;
        }
    }
    let n = scored as f64;
    out.attitude_rms_deg = (att / n).sqrt().to_degrees();
    out.position_rms_m = (pos / n).sqrt();
    out.velocity_rms_m_s = (vel / n).sqrt();
    out.predicted_attitude_deg = (p_att / n).sqrt().to_degrees();
    out.predicted_position_m = (p_pos / n).sqrt();
    out.counts = estimator.counts();
    out.final_covariance = *estimator.covariance_at_horizon();
    out.saturated_samples = estimator.saturated_samples();
    out.chained_steps = estimator.chained_steps;
    out
}

fn report(name: &str, o: &Outcome) {
    println!(
        "{name}: attitude RMS {:.4} deg (filter sigma {:.4}), position RMS {:.3} mm (filter \
         sigma {:.3}), velocity RMS {:.2} mm/s; fused {}, rejected {}, late {}",
        o.attitude_rms_deg,
        o.predicted_attitude_deg,
        1e3 * o.position_rms_m,
        1e3 * o.predicted_position_m,
        1e3 * o.velocity_rms_m_s,
        o.counts.fused,
        o.counts.rejected,
        o.counts.late
    );
}

/// The error the estimator must beat, from the profile: one raw mocap sample's 3-D error.
fn mocap_raw_errors() -> (f64, f64) {
    let p = PositionSourceProfile::optitrack_primex_13();
    let sqrt3 = 3f64.sqrt();
    (
        sqrt3 * p.attitude_noise_rad.unwrap().to_degrees(),
        sqrt3 * p.horizontal_noise_m,
    )
}

/// The filter's error against its own sigma: within a factor 2 either way (a consistent filter
/// sits near 1; an overconfident one far above, a sluggish one far below).
fn assert_consistent(name: &str, rms: f64, sigma: f64) {
    let ratio = rms / sigma;
    assert!(
        (0.5..2.0).contains(&ratio),
        "{name}: RMS {rms:e} vs filter sigma {sigma:e} ({ratio})"
    );
}

#[test]
fn hover_with_motion_capture() {
    let o = fly(&Flight::new(
        AnalyticMotion::hover(),
        SensorSuiteProfile::mocap(),
        1,
    ));
    report("hover, mocap", &o);
    let (raw_att_deg, raw_pos_m) = mocap_raw_errors();
    assert!(o.attitude_rms_deg < raw_att_deg, "{}", o.attitude_rms_deg);
    assert!(o.position_rms_m < raw_pos_m, "{}", o.position_rms_m);
    assert_consistent("attitude", o.attitude_rms_deg, o.predicted_attitude_deg);
    assert_consistent("position", o.position_rms_m, o.predicted_position_m);
    assert_few_rejections(&o.counts);
    assert_eq!(o.counts.late, 0);
}

/// The gate refuses 1e-4 of the measurements of a consistent filter: at most ten times that.
fn assert_few_rejections(counts: &FusionCounts) {
    assert!(
        counts.rejected as f64 <= 1e-3 * counts.fused as f64,
        "{counts:?}"
    );
}

#[test]
fn spinning_at_30_rad_s_with_motion_capture() {
    // 30 rad/s about an axis 15 deg off body z (the thrust tilted 15 deg, the centre of mass on a
    // 2.9 mm circle): 86 % of the gyro's 34.9 rad/s range, where the ICM-42688-P's scale and
    // cross-axis errors (0.5 %, 1.25 %) put 0.15-0.4 rad/s of error on the rate, and the 5 ms
    // mocap latency is 8.6 deg of rotation.
    let o = fly(&Flight::new(
        AnalyticMotion::spin(30.0, 15f64.to_radians()),
        SensorSuiteProfile::mocap(),
        2,
    ));
    report("30 rad/s spin, mocap", &o);
    let (raw_att_deg, raw_pos_m) = mocap_raw_errors();
    assert!(o.attitude_rms_deg < raw_att_deg, "{}", o.attitude_rms_deg);
    assert!(o.position_rms_m < raw_pos_m, "{}", o.position_rms_m);
    assert_consistent("attitude", o.attitude_rms_deg, o.predicted_attitude_deg);
    assert_consistent("position", o.position_rms_m, o.predicted_position_m);
    assert!(!o.saw_saturation_flag);
    assert_few_rejections(&o.counts);
}

#[test]
fn blocked_covariance_matches_the_per_sample_propagation() {
    // 30 rad/s: 0.3 rad of rotation per 10 ms block, so the blocked F differs from the product
    // of the per-sample ones at second order, up to (0.3 rad)^2 = 9 % (measured: 0.7 %, the yaw
    // sigma; 0.15 rad and 1.5 % with 5 ms blocks). Every standard deviation at
    // the end within 3 % of the per-sample propagation's, and the estimates within a tenth of
    // their sigma.
    let mut flight = Flight::new(
        AnalyticMotion::spin(30.0, 15f64.to_radians()),
        SensorSuiteProfile::mocap(),
        8,
    );
    flight.duration_s = 5.0;
    flight.settle_s = 1.0;
    let blocked = fly(&flight);
    flight.settings.covariance_period_s = 0.0;
    let every = fly(&flight);
    for i in 0..ERROR_DIM {
        let (a, b) = (
            blocked.final_covariance[(i, i)].sqrt(),
            every.final_covariance[(i, i)].sqrt(),
        );
        println!("state {i}: sigma blocked / per sample = {:.4}", a / b);
        assert!((a / b - 1.0).abs() < 0.03, "state {i}: {a:e} vs {b:e}");
    }
    let (last_blocked, last_every) = (
        blocked.outputs.last().unwrap().1,
        every.outputs.last().unwrap().1,
    );
    let attitude_sigma = every.final_covariance[(ATT, ATT)].sqrt();
    let gap = last_blocked.attitude.angle_to(&last_every.attitude);
    println!("attitude gap {gap:e} rad, sigma {attitude_sigma:e}");
    assert!(gap < 0.1 * attitude_sigma);
}

#[test]
fn latency_compensation_matches_the_undelayed_replay_and_beats_no_compensation() {
    let mut flight = Flight::new(
        AnalyticMotion::spin(30.0, 15f64.to_radians()),
        SensorSuiteProfile::mocap(),
        3,
    );
    flight.duration_s = 10.0;
    flight.settle_s = 2.0;
    let compensated = fly(&flight);
    flight.delivery = Delivery::Undelayed;
    let undelayed = fly(&flight);
    flight.delivery = Delivery::Uncompensated;
    let uncompensated = fly(&flight);
    report("spin, compensated", &compensated);
    report("spin, undelayed replay", &undelayed);
    report("spin, uncompensated", &uncompensated);
    // The compensated filter's fusion horizon runs 5 ms (five IMU samples) behind; at every
    // time it reaches, it must equal the undelayed filter there: the same measurements fused
    // at the same times of validity, the same propagation.
    let delayed_steps = 5;
    let mut worst: f64 = 0.0;
    for (k, (t, state)) in compensated
        .horizons
        .iter()
        .enumerate()
        .skip(delayed_steps + 1)
    {
        let (t_ref, reference) = &undelayed.horizons[k - delayed_steps];
        assert!((t - t_ref).abs() < 1e-12, "{t} vs {t_ref}");
        worst = worst
            .max(state.attitude.angle_to(&reference.attitude))
            .max((state.position_m - reference.position_m).amax())
            .max((state.velocity_m_s - reference.velocity_m_s).amax());
    }
    println!("largest horizon difference to the undelayed replay: {worst:e}");
    assert!(worst < 1e-9, "{worst:e}");
    // Its output (predicted over the last 5 ms without the measurements still in flight) is
    // within 1.5 times the undelayed filter's error; without compensation the 5 ms-old attitude
    // is fused as current, 8.6 deg off at 30 rad/s.
    assert!(compensated.attitude_rms_deg < 1.5 * undelayed.attitude_rms_deg);
    assert!(compensated.position_rms_m < 1.5 * undelayed.position_rms_m);
    assert!(uncompensated.attitude_rms_deg > 10.0 * compensated.attitude_rms_deg);
}

#[test]
fn nees_is_within_its_95_percent_bounds_on_a_linear_case() {
    let (runs, points, counts) = nees_campaign(1.0);
    println!("NEES (9 states, {runs} runs): {points:?}");
    // chi-square with 9 * runs degrees of freedom, two-sided 95 %: for 50 runs [393.0, 510.8].
    let (low, high) = (393.0 / runs as f64, 510.8 / runs as f64);
    let outside = points
        .iter()
        .filter(|&&m| !(low..=high).contains(&m))
        .count();
    // 20 time points; a consistent filter leaves about one outside.
    assert!(
        outside <= 3,
        "{outside} of {} outside [{low:.2}, {high:.2}]: {points:?}",
        points.len()
    );
    let grand = points.iter().sum::<f64>() / points.len() as f64;
    assert!((grand / 9.0 - 1.0).abs() < 0.1, "mean NEES {grand}");
    assert_few_rejections(&counts);
    assert_eq!(counts.late, 0);
}

#[test]
fn nees_check_fails_for_a_filter_that_understates_its_noise() {
    // The same campaign with the filter told half the accelerometer noise and bias walk: the
    // check above must fail (the NEES test can see an inconsistent filter).
    let (runs, points, _) = nees_campaign(0.5);
    let high = 510.8 / runs as f64;
    let above = points.iter().filter(|&&m| m > high).count();
    assert!(above >= 10, "{points:?}");
}

/// 50 Monte Carlo runs of a linear case: a fixed attitude (no gyro errors, no attitude
/// uncertainty), so the filter reduces to a linear Kalman filter in position, velocity and
/// accelerometer bias; a sinusoidal trajectory; white-noise position fixes at 50 Hz with 20 ms
/// latency (through the delay horizon). Returns the run-averaged NEES of the 9 states at 20
/// times (1 s apart) and the number of gated measurements. `noise_scale` scales the filter's
/// accelerometer noise and walk densities against the truth's.
fn nees_campaign(noise_scale: f64) -> (usize, Vec<f64>, FusionCounts) {
    let imu = ImuProfile {
        rate_hz: 200.0,
        gyro: GyroProfile {
            noise_density_rad_s_rt_hz: 0.0,
            bias_walk_rad_s_rt_s: 0.0,
            turn_on_bias_rad_s: 0.0,
            scale_error: 0.0,
            cross_axis: 0.0,
            range_rad_s: 100.0,
        },
        accel: AccelProfile {
            noise_density_m_s2_rt_hz: 2e-3,
            bias_walk_m_s2_rt_s: 1e-3,
            turn_on_bias_m_s2: 0.05,
            scale_error: 0.0,
            cross_axis: 0.0,
            range_m_s2: 1e3,
            vibration: crate::flight::sensors::Vibration::off(),
        },
        position_m: Vector3::zeros(),
    };
    let position = PositionSourceProfile {
        rate_hz: 50.0,
        latency_s: 0.02,
        horizontal_noise_m: 0.02,
        vertical_noise_m: 0.03,
        horizontal_drift_m: 0.0,
        vertical_drift_m: 0.0,
        drift_time_constant_s: 0.0,
        velocity_noise_m_s: None,
        attitude_noise_rad: None,
        dropouts: None,
    };
    let suite = SensorSuiteProfile {
        imu,
        position,
        ..SensorSuiteProfile::mocap()
    };
    let mut settings = EstimatorSettings::for_sensors(&suite);
    settings.initial_attitude_std_rad = 0.0;
    settings.initial_position_std_m = 0.05;
    settings.accel_noise_density_m_s2_rt_hz *= noise_scale;
    settings.accel_bias_walk_m_s2_rt_s *= noise_scale;
    let motion = AnalyticMotion {
        amplitude_m: Vector3::new(2.0, 1.0, 0.5),
        angular_frequency_rad_s: 0.7,
        ..AnalyticMotion::hover()
    };
    let runs = 50;
    let times: Vec<f64> = (1..=20).map(|k| k as f64).collect();
    let mut sums = vec![0.0; times.len()];
    let mut counts = FusionCounts::default();
    for run in 0..runs {
        let seed = 1000 + run as u64;
        let mut sensors = SensorSuite::new(&suite, 4, seed).unwrap();
        let mut start = motion.state_at(0.0);
        let mut g = Gaussian::stream(seed, 99);
        start.position_m += g.vector3() * settings.initial_position_std_m;
        start.velocity_m_s += g.vector3() * settings.initial_velocity_std_m_s;
        let mut estimator = Estimator::new(settings, &start).unwrap();
        // The true accelerometer bias at each IMU sample time.
        let mut biases: Vec<(f64, Vector3<f64>)> = Vec::new();
        let mut next_point = 0;
        while next_point < times.len() {
            let t = sensors.imu.next_sample_time_s();
            while sensors.position.is_due(t) {
                let at = sensors.position.next_sample_time_s();
                sensors.position.sample(&motion.state_at(at));
            }
            while let Some(m) = sensors.position.poll(t) {
                estimator.push_position(&m);
            }
            biases.push((t, sensors.imu.accel_bias_m_s2()));
            let sample = sensors.imu.sample(&motion.imu_truth_at(t));
            estimator.push_imu(&sample).unwrap();
            let th = estimator.horizon_time_s();
            if th >= times[next_point] - 1e-9 {
                let truth = motion.state_at(th);
                let bias = biases
                    .iter()
                    .rev()
                    .find(|(tb, _)| *tb <= th + 1e-9)
                    .unwrap()
                    .1;
                let x = estimator.horizon_state();
                let mut e = SMatrix::<f64, 9, 1>::zeros();
                e.fixed_rows_mut::<3>(0)
                    .copy_from(&(x.position_m - truth.position_m));
                e.fixed_rows_mut::<3>(3)
                    .copy_from(&(x.velocity_m_s - truth.velocity_m_s));
                e.fixed_rows_mut::<3>(6)
                    .copy_from(&(x.accel_bias_m_s2 - bias));
                let p = estimator.covariance();
                let idx = [
                    POS,
                    POS + 1,
                    POS + 2,
                    VEL,
                    VEL + 1,
                    VEL + 2,
                    ACCEL_BIAS,
                    ACCEL_BIAS + 1,
                    ACCEL_BIAS + 2,
                ];
                let sub = SMatrix::<f64, 9, 9>::from_fn(|i, j| p[(idx[i], idx[j])]);
                let nees = e.dot(&sub.cholesky().unwrap().solve(&e));
                sums[next_point] += nees;
                next_point += 1;
            }
        }
        let c = estimator.counts();
        counts.fused += c.fused;
        counts.rejected += c.rejected;
        counts.late += c.late;
    }
    (runs, sums.iter().map(|s| s / runs as f64).collect(), counts)
}

#[test]
fn saturated_gyro_is_reported_and_its_excess_learned() {
    // 40 rad/s about body z, beyond the 2000 deg/s = 34.9 rad/s range: every gyro sample is
    // clamped. The clamped axis carries an unknown excess of 5.1 rad/s, which the filter learns
    // as a bias from the mocap attitude; told nothing of clamping it diverges.
    let mut flight = Flight::new(
        AnalyticMotion::spin(40.0, 0.0),
        SensorSuiteProfile::mocap(),
        4,
    );
    flight.duration_s = 10.0;
    flight.settle_s = 2.0;
    let o = fly(&flight);
    report("40 rad/s, clamped gyro", &o);
    assert!(o.saw_saturation_flag);
    assert_eq!(o.saturated_samples, 10_001);
    let (raw_att_deg, raw_pos_m) = mocap_raw_errors();
    assert!(o.attitude_rms_deg < raw_att_deg && o.position_rms_m < raw_pos_m);
    assert_consistent("attitude", o.attitude_rms_deg, o.predicted_attitude_deg);
    flight.settings.saturation_excess = 0.0;
    flight.settings.saturation_walk = 0.0;
    let blind = fly(&flight);
    report("40 rad/s, clamping ignored", &blind);
    assert!(blind.attitude_rms_deg > 10.0, "{}", blind.attitude_rms_deg);
}

#[test]
fn imu_off_the_centre_of_mass_in_a_spin() {
    // 2-3 cm off the centre of mass at 30 rad/s: 20-30 m/s^2 of centripetal acceleration on
    // the accelerometer. Known to the filter, the errors are those of a centred IMU; unknown,
    // the position fixes are refused and the estimate leaves by metres.
    let mut suite = SensorSuiteProfile::mocap();
    suite.imu.position_m = Vector3::new(0.02, 0.01, -0.01);
    let mut flight = Flight::new(AnalyticMotion::spin(30.0, 15f64.to_radians()), suite, 5);
    flight.duration_s = 10.0;
    flight.settle_s = 2.0;
    let known = fly(&flight);
    report("spin, IMU 2.4 cm off, known", &known);
    let (raw_att_deg, raw_pos_m) = mocap_raw_errors();
    assert!(known.attitude_rms_deg < raw_att_deg && known.position_rms_m < raw_pos_m);
    assert_consistent("position", known.position_rms_m, known.predicted_position_m);
    flight.settings.imu_position_m = Vector3::zeros();
    let unknown = fly(&flight);
    report("spin, IMU 2.4 cm off, unknown", &unknown);
    assert!(unknown.position_rms_m > 0.1, "{}", unknown.position_rms_m);
}

/// GNSS drift and its 3-D sigma for a profile, m.
fn drift_3d(p: &PositionSourceProfile) -> f64 {
    (2.0 * p.horizontal_drift_m.powi(2) + p.vertical_drift_m.powi(2)).sqrt()
}

#[test]
fn gnss_and_magnetometer_in_hover_and_in_a_spin() {
    // NEO-M8N (2.1 m per horizontal axis of slow drift) and LIS3MDL, one minute. No filter can
    // remove the receiver's own drift: the position error is that of the fixes (bounded here by
    // twice its 3-D sigma); velocity by the Doppler fixes' 3-D sigma. In hover the tilt and the
    // horizontal accelerometer bias are not separately observable, so the attitude sigma is
    // bounded by the turn-on accelerometer bias over g per axis, 1.15 deg; spinning averages the
    // bias out and the attitude is an order of magnitude better.
    let mut suite = SensorSuiteProfile::gnss();
    suite.position.dropouts = None;
    let gnss = suite.position;
    for (name, motion) in [
        ("hover, GNSS", AnalyticMotion::hover()),
        (
            "30 rad/s spin, GNSS",
            AnalyticMotion::spin(30.0, 15f64.to_radians()),
        ),
    ] {
        let mut flight = Flight::new(motion, suite, 6);
        flight.duration_s = 60.0;
        flight.settle_s = 10.0;
        let o = fly(&flight);
        report(name, &o);
        assert!(
            o.position_rms_m < 2.0 * drift_3d(&gnss),
            "{}",
            o.position_rms_m
        );
        let velocity_sigma_3d = 3f64.sqrt() * gnss.velocity_noise_m_s.unwrap();
        assert!(
            o.velocity_rms_m_s < velocity_sigma_3d,
            "{}",
            o.velocity_rms_m_s
        );
        assert!(o.attitude_rms_deg < 2.0 * o.predicted_attitude_deg);
        let tilt_bound = 3f64.sqrt()
            * (suite.imu.accel.turn_on_bias_m_s2 / 9.81)
                .atan()
                .to_degrees();
        assert!(
            o.predicted_attitude_deg < tilt_bound,
            "{}",
            o.predicted_attitude_deg
        );
        if name.contains("spin") {
            assert!(o.attitude_rms_deg < 0.2, "{}", o.attitude_rms_deg);
        }
        assert_few_rejections(&o.counts);
        // The drift is not a state: the filter averages it as if white, and its position sigma
        // is optimistic (printed, decided in the README's "GNSS" section).
        println!(
            "  position RMS / filter sigma = {:.1} (drift not estimated)",
            o.position_rms_m / o.predicted_position_m
        );
    }
}

#[test]
fn rtk_outage_grows_the_covariance_and_recovers() {
    // ZED-F9P RTK with a 10 s outage from t = 20 s: dead reckoning on the IMU and magnetometer.
    // The error stays within three of the filter's sigmas throughout, the sigma grows tenfold
    // in the outage, and both are back within a second of the fixes' return.
    let mut flight = Flight::new(AnalyticMotion::hover(), SensorSuiteProfile::rtk(), 7);
    flight.duration_s = 40.0;
    flight.settle_s = 10.0;
    flight.gap_s = Some((20.0, 30.0));
    let o = fly(&flight);
    report("hover, RTK, 10 s outage", &o);
    let at = |t: f64| *o.position_track.iter().find(|(ti, _, _)| *ti >= t).unwrap();
    let (_, _, before) = at(19.9);
    let (_, error_end, sigma_end) = at(30.1);
    println!(
        "  sigma before {:.1} mm, at the end of the outage {:.1} mm (error {:.1} mm)",
        1e3 * before,
        1e3 * sigma_end,
        1e3 * error_end
    );
    assert!(sigma_end > 10.0 * before);
    for &(t, error, sigma) in o.position_track.iter().filter(|(t, _, _)| *t >= 15.0) {
        // The drift is outside the filter's sigma (see the GNSS test): add it.
        let bound = 3.0 * (sigma * sigma + drift_3d(&flight.suite.position).powi(2)).sqrt();
        assert!(error < bound, "t = {t}: error {error} vs {bound}");
    }
    let (_, error_after, sigma_after) = at(31.5);
    assert!(sigma_after < 2.0 * before && error_after < 3.0 * drift_3d(&flight.suite.position));
}

#[test]
fn deterministic_by_seed() {
    let mut flight = Flight::new(
        AnalyticMotion::spin(20.0, 0.2),
        SensorSuiteProfile::gnss(),
        11,
    );
    flight.duration_s = 3.0;
    flight.settle_s = 0.0;
    let a = fly(&flight);
    let b = fly(&flight);
    flight.seed = 12;
    let c = fly(&flight);
    assert_eq!(a.outputs, b.outputs);
    assert_eq!(a.horizons, b.horizons);
    assert_ne!(a.outputs, c.outputs);
}

#[test]
fn horizon_steps_taken_from_the_output_chain_change_nothing() {
    // Bit for bit against the estimator that computes every horizon step: fused and rejected
    // fixes, a magnetometer, a clamped gyro, an outage and the replays after each correction.
    let mut spin = Flight::new(
        AnalyticMotion::spin(30.0, 0.3),
        SensorSuiteProfile::mocap(),
        3,
    );
    spin.duration_s = 3.0;
    let mut gnss = Flight::new(
        AnalyticMotion::spin(20.0, 0.2),
        SensorSuiteProfile::gnss(),
        5,
    );
    gnss.duration_s = 3.0;
    gnss.gap_s = Some((1.0, 1.5));
    let mut clamped = Flight::new(
        AnalyticMotion::spin(36.0, 0.0),
        SensorSuiteProfile::mocap(),
        4,
    );
    clamped.duration_s = 2.0;
    // A filter that refuses most of its fixes (a gate at chi^2 = 2).
    let mut gated = Flight::new(
        AnalyticMotion::spin(5.0, 0.1),
        SensorSuiteProfile::mocap(),
        6,
    );
    gated.duration_s = 2.0;
    gated.settings.innovation_gate = 2.0;
    for (name, mut flight) in [
        ("spin", spin),
        ("gnss", gnss),
        ("clamped", clamped),
        ("gated", gated),
    ] {
        flight.settle_s = 0.0;
        let reused = fly(&flight);
        flight.reuse_trail = false;
        let computed = fly(&flight);
        assert_eq!(reused.outputs, computed.outputs, "{name}");
        assert_eq!(reused.horizons, computed.horizons, "{name}");
        assert_eq!(reused.final_covariance, computed.final_covariance, "{name}");
        assert_eq!(reused.counts, computed.counts, "{name}");
        assert_eq!(reused.position_track, computed.position_track, "{name}");
        println!(
            "{name}: {:?}, {} saturated samples, {} of {} horizon steps chained",
            reused.counts,
            reused.saturated_samples,
            reused.chained_steps,
            reused.outputs.len()
        );
        assert_eq!(computed.chained_steps, 0, "{name}");
        // Each case exercises what it is there for.
        match name {
            "gated" => assert!(reused.counts.rejected > 0),
            "clamped" => assert!(reused.saturated_samples > 0),
            "gnss" => assert!(reused.counts.fused > 0),
            _ => {}
        }
        // A refused fix leaves the horizon off the output's chain until the next correction.
        let share = if name == "gated" { 50 } else { 2 };
        assert!(
            reused.chained_steps * share > reused.outputs.len() as u64,
            "{name}"
        );
    }
}

#[test]
fn filtered_gyro_is_a_first_order_low_pass() {
    // White gyro noise through y += a (x - y), a = 1 - exp(-2 pi f T): the variance shrinks by
    // a / (2 - a) (the filter's noise gain; independent of the estimator's arithmetic).
    let suite = SensorSuiteProfile::mocap();
    let mut settings = EstimatorSettings::for_sensors(&suite);
    settings.gyro_cutoff_hz = Some(30.0);
    let motion = AnalyticMotion::hover();
    let mut raw = Estimator::new(
        EstimatorSettings::for_sensors(&suite),
        &motion.state_at(0.0),
    )
    .unwrap();
    let mut filtered = Estimator::new(settings, &motion.state_at(0.0)).unwrap();
    let mut imu = crate::flight::sensors::Imu::new(suite.imu, 13).unwrap();
    let (mut raw_x, mut filtered_x) = (Vec::new(), Vec::new());
    for k in 0..21_000 {
        let s = imu.sample(&motion.imu_truth_at(k as f64 * 1e-3));
        raw.push_imu(&s).unwrap();
        filtered.push_imu(&s).unwrap();
        if k >= 1000 {
            raw_x.push(raw.estimate().state.omega_rad_s.x);
            filtered_x.push(filtered.estimate().state.omega_rad_s.x);
        }
    }
    // Variances about the mean: the turn-on bias (no aiding here) is a constant offset.
    let variance = |x: &[f64]| {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64
    };
    let a = 1.0 - (-2.0 * std::f64::consts::PI * 30.0 * 1e-3f64).exp();
    let ratio = variance(&filtered_x) / variance(&raw_x);
    // 20,000 samples, ~2 / a = 20 per correlation time of the filtered series: ~1,000
    // independent values, the variance good to ~5 %.
    assert!(
        (ratio / (a / (2.0 - a)) - 1.0).abs() < 0.15,
        "{ratio} vs {}",
        a / (2.0 - a)
    );
    assert!(raw.estimate().gyro_rad_s == raw.estimate().state.omega_rad_s);
}

#[test]
fn imu_samples_must_come_in_order() {
    let motion = AnalyticMotion::hover();
    let mut estimator =
        Estimator::new(EstimatorSettings::default(), &motion.state_at(0.0)).unwrap();
    let mut imu = crate::flight::sensors::Imu::new(ImuProfile::default(), 1).unwrap();
    let first = imu.sample(&motion.imu_truth_at(0.0));
    estimator.push_imu(&first).unwrap();
    let err = estimator.push_imu(&first).unwrap_err().to_string();
    assert!(err.starts_with("imu.time_s:"), "{err}");
    let mut bad = motion.state_at(0.0);
    bad.velocity_m_s.y = f64::NAN;
    let err = Estimator::new(EstimatorSettings::default(), &bad)
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("initial:"), "{err}");
}

#[test]
fn every_setting_rule_names_its_field() {
    let cases: &[RuleCase<EstimatorSettings>] = &[
        ("estimator.fusion_delay_s", |s| s.fusion_delay_s = -0.1),
        ("estimator.covariance_period_s", |s| {
            s.covariance_period_s = f64::NAN
        }),
        ("estimator.gravity_m_s2", |s| s.gravity_m_s2 = 0.0),
        ("estimator.imu_position_m[1]", |s| {
            s.imu_position_m.y = f64::NAN
        }),
        ("estimator.gyro_noise_density_rad_s_rt_hz", |s| {
            s.gyro_noise_density_rad_s_rt_hz = -1.0
        }),
        ("estimator.gyro_bias_walk_rad_s_rt_s", |s| {
            s.gyro_bias_walk_rad_s_rt_s = f64::NAN
        }),
        ("estimator.gyro_scale_error", |s| s.gyro_scale_error = -1.0),
        ("estimator.gyro_cross_axis", |s| {
            s.gyro_cross_axis = f64::INFINITY
        }),
        ("estimator.gyro_range_rad_s", |s| s.gyro_range_rad_s = 0.0),
        ("estimator.accel_noise_density_m_s2_rt_hz", |s| {
            s.accel_noise_density_m_s2_rt_hz = -1.0
        }),
        ("estimator.accel_bias_walk_m_s2_rt_s", |s| {
            s.accel_bias_walk_m_s2_rt_s = -1.0
        }),
        ("estimator.accel_scale_error", |s| {
            s.accel_scale_error = f64::NAN
        }),
        ("estimator.accel_cross_axis", |s| s.accel_cross_axis = -1.0),
        ("estimator.accel_range_m_s2", |s| s.accel_range_m_s2 = -1.0),
        ("estimator.input_mean_time_s", |s| s.input_mean_time_s = 0.0),
        ("estimator.saturation_excess", |s| {
            s.saturation_excess = -0.5
        }),
        ("estimator.saturation_walk", |s| s.saturation_walk = f64::NAN),
        ("estimator.initial_position_std_m", |s| {
            s.initial_position_std_m = -1.0
        }),
        ("estimator.initial_velocity_std_m_s", |s| {
            s.initial_velocity_std_m_s = f64::NAN
        }),
        ("estimator.initial_attitude_std_rad", |s| {
            s.initial_attitude_std_rad = f64::INFINITY
        }),
        ("estimator.initial_gyro_bias_std_rad_s", |s| {
            s.initial_gyro_bias_std_rad_s = -1.0
        }),
        ("estimator.initial_accel_bias_std_m_s2", |s| {
            s.initial_accel_bias_std_m_s2 = -1.0
        }),
        ("estimator.position_std_m[0]", |s| s.position_std_m[0] = 0.0),
        ("estimator.position_std_m[1]", |s| {
            s.position_std_m[1] = f64::NAN
        }),
        ("estimator.velocity_std_m_s", |s| s.velocity_std_m_s = -1.0),
        ("estimator.attitude_std_rad", |s| s.attitude_std_rad = 0.0),
        ("estimator.magnetometer_std_ut", |s| {
            s.magnetometer_std_ut = f64::NAN
        }),
        ("estimator.earth_field_ut[2]", |s| {
            s.earth_field_ut.z = f64::INFINITY
        }),
        ("estimator.innovation_gate", |s| s.innovation_gate = 0.0),
        ("estimator.gyro_cutoff_hz", |s| {
            s.gyro_cutoff_hz = Some(-3.0)
        }),
    ];
    let start = AnalyticMotion::hover().state_at(0.0);
    let base = EstimatorSettings::default();
    assert_rules_name_fields(&base, cases, |s| Estimator::new(*s, &start).map(|_| ()));
    for suite in [
        SensorSuiteProfile::mocap(),
        SensorSuiteProfile::gnss(),
        SensorSuiteProfile::rtk(),
    ] {
        EstimatorSettings::for_sensors(&suite).check().unwrap();
    }
    // Infinite gate and infinite (absent) measurement noise are allowed.
    let open = EstimatorSettings {
        innovation_gate: f64::INFINITY,
        velocity_std_m_s: f64::INFINITY,
        ..EstimatorSettings::default()
    };
    open.check().unwrap();
}

#[test]
fn a_measurement_older_than_the_horizon_is_counted_late_not_fused() {
    // No fusion delay: a fix valid 10 ms before the newest IMU sample cannot be fused at its
    // time of validity any more; one valid now is.
    let motion = AnalyticMotion::hover();
    let settings = EstimatorSettings {
        fusion_delay_s: 0.0,
        ..EstimatorSettings::default()
    };
    let mut estimator = Estimator::new(settings, &motion.state_at(0.0)).unwrap();
    let mut imu = crate::flight::sensors::Imu::new(ImuProfile::default(), 2).unwrap();
    for k in 0..=20 {
        let s = imu.sample(&motion.imu_truth_at(k as f64 * 1e-3));
        estimator.push_imu(&s).unwrap();
    }
    let fix = |valid_at_s: f64| crate::flight::sensors::PositionSample {
        valid_at_s,
        arrives_at_s: 0.02,
        position_m: motion.state_at(valid_at_s).position_m,
        velocity_m_s: None,
        attitude: None,
    };
    estimator.push_position(&fix(0.010));
    estimator.push_position(&fix(0.0205));
    let s = imu.sample(&motion.imu_truth_at(0.021));
    estimator.push_imu(&s).unwrap();
    assert_eq!(
        estimator.counts(),
        FusionCounts {
            fused: 1,
            rejected: 0,
            late: 1,
            thinned: 0
        }
    );
}

#[test]
fn position_fixes_are_fused_at_most_once_per_fusion_slot() {
    // 10 ms slots: of fixes valid at 11, 14 and 19 ms only the first is taken, the next slot's
    // at 21 ms is taken again; without the limit all four are fused.
    let motion = AnalyticMotion::hover();
    let fly = |period_s: f64| {
        let settings = EstimatorSettings {
            position_fusion_period_s: period_s,
            ..EstimatorSettings::default()
        };
        let mut estimator = Estimator::new(settings, &motion.state_at(0.0)).unwrap();
        let mut imu = crate::flight::sensors::Imu::new(ImuProfile::default(), 2).unwrap();
        for k in 0..=40 {
            let t = k as f64 * 1e-3;
            for valid_at_s in [0.011, 0.014, 0.019, 0.021] {
                if (valid_at_s - t).abs() < 1e-9 {
                    estimator.push_position(&crate::flight::sensors::PositionSample {
                        valid_at_s,
                        arrives_at_s: t,
                        position_m: motion.state_at(valid_at_s).position_m,
                        velocity_m_s: None,
                        attitude: None,
                    });
                }
            }
            let s = imu.sample(&motion.imu_truth_at(t));
            estimator.push_imu(&s).unwrap();
        }
        estimator.counts()
    };
    let limited = fly(0.01);
    assert_eq!((limited.fused, limited.thinned), (2, 2), "{limited:?}");
    let every = fly(0.0);
    assert_eq!((every.fused, every.thinned), (4, 0), "{every:?}");
}

/// Fixes at exactly the slot rate (100 Hz, valid at k / 100 s) each own a slot: none is thinned,
/// though k / 100 / 0.01 falls just under k for k = 29, 47, 57, ... (a reviewer counted 125 of 1000
/// fixes thinned in 10 s with a plain floor). Thinned fixes count their measurements.
#[test]
fn fixes_at_the_slot_rate_are_all_fused() {
    let settings = EstimatorSettings {
        position_fusion_period_s: 0.01,
        ..EstimatorSettings::default()
    };
    let motion = AnalyticMotion::hover();
    let mut estimator = Estimator::new(settings, &motion.state_at(0.0)).unwrap();
    let fix = |valid_at_s: f64, attitude: bool| crate::flight::sensors::PositionSample {
        valid_at_s,
        arrives_at_s: valid_at_s,
        position_m: motion.state_at(0.0).position_m,
        velocity_m_s: None,
        attitude: attitude.then(nalgebra::UnitQuaternion::identity),
    };
    let floored = (1..1000)
        .filter(|&k| ((k as f64 / 100.0) / 0.01).floor() < k as f64)
        .count();
    assert!(floored > 100, "the case the tolerance is for: {floored}");
    for k in 1..1000 {
        estimator.push_position(&fix(k as f64 / 100.0, false));
    }
    assert_eq!(estimator.counts().thinned, 0);
    estimator.push_position(&fix(999.0 / 100.0 + 0.004, true));
    assert_eq!(estimator.counts().thinned, 2, "position and attitude");
}
