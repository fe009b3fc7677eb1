//! Four estimators in lanes against four scalar estimators fed the same samples: every estimate,
//! covariance and count equal bit for bit, through hover, spins, a gyro clamping in one lane
//! only, a fix the gate refuses in one lane only, the magnetometer, and a lane that stops.

use super::*;
use crate::flight::estimation::Estimator;
use crate::flight::lanes::{detected_path, portable_choices, F64x4};
use crate::flight::sensors::reference::AnalyticMotion;
use crate::flight::sensors::{SensorSuite, SensorSuiteProfile};

type L = F64x4;
const W: usize = 4;

struct Case {
    suite: SensorSuiteProfile,
    motions: [AnalyticMotion; W],
    /// Lane 1's fixes valid in this window are moved 5 m (the gate refuses them there only).
    outlier_s: (f64, f64),
    /// Lane 3 stops at this time (its run ended): its counts must stop with it.
    stop_s: f64,
    /// Each lane's body rate scaled by `1 + wobble sin(2 pi 0.7 t)` (a rate that crosses the
    /// gyro's range and back: the clamping switches, and that lane alone flushes its block).
    wobble: [f64; W],
    duration_s: f64,
}

fn same(a: f64, b: f64, what: &str, t: f64, lane: usize) {
    assert_eq!(
        a.to_bits(),
        b.to_bits(),
        "{what} at {t} s, lane {lane}: {a:e} (lanes) against {b:e} (scalar)"
    );
}

/// Every field of two estimates equal bit for bit.
fn same_estimate(a: &Estimate, b: &Estimate, what: &str, t: f64, lane: usize) {
    same(a.time_s, b.time_s, &format!("{what} time"), t, lane);
    let vectors = [
        (a.state.position_m, b.state.position_m, "position"),
        (a.state.velocity_m_s, b.state.velocity_m_s, "velocity"),
        (a.state.omega_rad_s, b.state.omega_rad_s, "rate"),
        (a.gyro_rad_s, b.gyro_rad_s, "gyro"),
        (a.accel_m_s2, b.accel_m_s2, "accel"),
    ];
    for (x, y, name) in vectors {
        for k in 0..3 {
            same(x[k], y[k], &format!("{what} {name}"), t, lane);
        }
    }
    for k in 0..4 {
        let (qa, qb) = (a.state.attitude.coords, b.state.attitude.coords);
        same(qa[k], qb[k], &format!("{what} attitude"), t, lane);
    }
    assert_eq!(
        a.gyro_saturated, b.gyro_saturated,
        "{what} at {t} s, lane {lane}"
    );
}

/// Flies `case` in lanes (in both compiled forms, the portable one and this CPU's) and in four
/// scalar estimators, checking them equal after every IMU sample; the lanes' counts and the
/// lanes' estimator (this CPU's form).
fn check(case: &Case) -> ([FusionCounts; W], EstimatorLanes<L>) {
    let serial = portable_choices::serial();
    let _ = check_on(case, LanePath::Portable);
    drop(serial);
    check_on(case, detected_path())
}

/// [`check`] in the compiled form `path`.
fn check_on(case: &Case, path: LanePath) -> ([FusionCounts; W], EstimatorLanes<L>) {
    let settings = EstimatorSettings::for_sensors(&case.suite);
    let mut sensors: Vec<SensorSuite> = (0..W)
        .map(|i| SensorSuite::new(&case.suite, 4, 40 + i as u64).unwrap())
        .collect();
    let starts: Vec<_> = case.motions.iter().map(|m| m.state_at(0.0)).collect();
    let mut scalar: Vec<Estimator> = starts
        .iter()
        .map(|x| Estimator::new(settings, x).unwrap())
        .collect();
    let mut lanes = EstimatorLanes::<L>::new(settings, &starts, path).unwrap();
    let mut stopped: Option<[FusionCounts; W]> = None;
    loop {
        let t = sensors[0].imu.next_sample_time_s();
        if t > case.duration_s {
            break;
        }
        if t >= case.stop_s && stopped.is_none() {
            lanes.set_active(0b0111);
            stopped = Some(std::array::from_fn(|i| scalar[i].counts()));
        }
        let zero = [L::splat(0.0); 3];
        // The magnetometer's readings (on its clock), then the position fixes due by now.
        loop {
            let due: Vec<bool> = sensors
                .iter()
                .map(|s| s.magnetometer.as_ref().is_some_and(|m| m.is_due(t)))
                .collect();
            if !due[0] {
                break;
            }
            let mut field = zero;
            let mut time = 0.0;
            for (i, s) in sensors.iter_mut().enumerate() {
                let m = s.magnetometer.as_mut().unwrap();
                let at = m.next_sample_time_s();
                let sample = m.sample(&case.motions[i].state_at(at));
                scalar[i].push_magnetometer(&sample);
                set3(&mut field, i, &sample.field_ut);
                time = sample.time_s;
            }
            lanes.push_magnetometer(time, &field);
        }
        for (i, s) in sensors.iter_mut().enumerate() {
            while s.position.is_due(t) {
                let at = s.position.next_sample_time_s();
                s.position.sample(&case.motions[i].state_at(at));
            }
        }
        loop {
            let fixes: Vec<_> = sensors.iter_mut().map(|s| s.position.poll(t)).collect();
            let Some(first) = fixes[0] else {
                assert!(fixes.iter().all(|f| f.is_none()));
                break;
            };
            let mut fix = PositionLanes::splat(&first);
            for (i, f) in fixes.into_iter().enumerate() {
                let mut f = f.unwrap();
                if i == 1 && (case.outlier_s.0..case.outlier_s.1).contains(&f.valid_at_s) {
                    f.position_m.x += 5.0;
                }
                scalar[i].push_position(&f);
                fix.set_lane(i, &f);
            }
            lanes.push_position(&fix);
        }
        let mut imu: Option<ImuLanes<L>> = None;
        for (i, s) in sensors.iter_mut().enumerate() {
            let mut truth = case.motions[i].imu_truth_at(t);
            truth.omega_rad_s *=
                1.0 + case.wobble[i] * (2.0 * std::f64::consts::PI * 0.7 * t).sin();
            let sample = s.imu.sample(&truth);
            imu.get_or_insert_with(|| ImuLanes::splat(&sample))
                .set_lane(i, &sample);
            if stopped.is_none() || i != 3 {
                scalar[i].push_imu(&sample).unwrap();
            }
        }
        lanes.push_imu(&imu.unwrap()).unwrap();
        let live = if stopped.is_some() { 3 } else { W };
        // The estimates carried to a control step 1.3 ms on, in lanes, against the scalar carry.
        let mut carried = Vec::new();
        lanes.estimates_at(t + 1.3e-3, &mut carried);
        for (i, e) in scalar.iter().enumerate().take(live) {
            let b = e.estimate().carried(settings.gravity_m_s2, t + 1.3e-3);
            same_estimate(&carried[i], &b, "carried", t, i);
        }
        for (i, e) in scalar.iter().enumerate().take(live) {
            same_estimate(&lanes.estimate(i), &e.estimate(), "estimate", t, i);
            let (pa, pb) = (lanes.covariance(i), e.covariance());
            for k in 0..ERROR_DIM * ERROR_DIM {
                same(pa.as_slice()[k], pb.as_slice()[k], "covariance", t, i);
            }
            assert_eq!(lanes.counts(i), e.counts(), "counts at {t} s, lane {i}");
            assert_eq!(lanes.saturated_samples(i), e.saturated_samples());
        }
    }
    let stopped = stopped.expect("lane 3 stops within the flight");
    assert_eq!(lanes.counts(3), stopped[3], "a stopped lane's counts stop");
    (std::array::from_fn(|i| lanes.counts(i)), lanes)
}

fn clamped(lanes: &EstimatorLanes<L>) -> Vec<bool> {
    (0..W).map(|i| lanes.saturated_samples(i) > 0).collect()
}

#[test]
fn lanes_equal_four_scalar_estimators_with_motion_capture() {
    let case = Case {
        suite: SensorSuiteProfile::mocap(),
        // Hover, a 30 rad/s spin, a spin past the ICM-42688-P's 34.9 rad/s range (lane 2
        // clamps throughout) and one whose rate crosses it twice a cycle (lane 3: its clamping
        // switches, so its covariance block is flushed when the others' are not).
        motions: [
            AnalyticMotion::hover(),
            AnalyticMotion::spin(30.0, 15f64.to_radians()),
            AnalyticMotion::spin(40.0, 0.0),
            AnalyticMotion::spin(34.0, 0.1),
        ],
        outlier_s: (1.0, 1.2),
        stop_s: 2.5,
        duration_s: 3.0,
        wobble: [0.0, 0.0, 0.0, 0.06],
    };
    let (counts, lanes) = check(&case);
    // The cases the lanes must carry per lane did happen: fixes refused in lane 1 only, the gyro
    // clamping in lanes 2 and 3 only, lane 3's blocks flushed apart from the others'.
    assert!(counts[1].rejected > 10, "{counts:?}");
    assert_eq!(counts[0].rejected, 0, "{counts:?}");
    assert_eq!(clamped(&lanes), [false, false, true, true]);
    assert!(lanes.partial_flushes >= 4, "{}", lanes.partial_flushes);
}

#[test]
fn lanes_equal_four_scalar_estimators_with_rtk_and_the_magnetometer() {
    let case = Case {
        suite: SensorSuiteProfile::rtk(),
        motions: [
            AnalyticMotion::spin(20.0, 0.2),
            AnalyticMotion::hover(),
            AnalyticMotion::spin(36.0, 0.05),
            AnalyticMotion::spin(30.0, 15f64.to_radians()),
        ],
        outlier_s: (1.5, 2.0),
        stop_s: 2.0,
        duration_s: 3.0,
        wobble: [0.0; W],
    };
    let (counts, lanes) = check(&case);
    assert!(counts[1].rejected > 0, "{counts:?}");
    assert_eq!(clamped(&lanes), [false, false, true, false]);
}
