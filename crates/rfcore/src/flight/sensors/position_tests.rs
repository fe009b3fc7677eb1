use super::*;
use crate::flight::sensors::{assert_rules_name_fields, RuleCase};

fn truth() -> RigidBodyState {
    RigidBodyState {
        position_m: Vector3::new(1.0, -2.0, -3.0),
        velocity_m_s: Vector3::new(0.5, 0.0, -0.1),
        attitude: UnitQuaternion::from_euler_angles(0.1, 0.2, -2.5),
        omega_rad_s: Vector3::zeros(),
    }
}

/// Samples `n` measurements of a fixed truth, each polled at its arrival.
fn measurements(source: &mut PositionSource, n: usize) -> Vec<PositionSample> {
    let state = truth();
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        source.sample(&state);
        let t = source.next_sample_time_s() + source.profile().latency_s;
        while let Some(s) = source.poll(t) {
            out.push(s);
        }
    }
    out
}

#[test]
fn mocap_samples_at_its_rate_arrive_after_its_latency_with_its_noise() {
    let profile = PositionSourceProfile::optitrack_primex_13();
    let mut mocap = PositionSource::new(profile, 12).unwrap();
    mocap.sample(&truth());
    // Not before 5 ms; at 5 ms it is there.
    assert!(mocap.poll(4.9e-3).is_none());
    let first = mocap.poll(5e-3).unwrap();
    assert_eq!((first.valid_at_s, first.arrives_at_s), (0.0, 5e-3));
    assert!(first.velocity_m_s.is_none() && first.attitude.is_some());
    let n = 20_000;
    let samples = measurements(&mut mocap, n);
    for (k, s) in samples.iter().enumerate().take(100) {
        assert!((s.valid_at_s - (k + 1) as f64 / 240.0).abs() < 1e-12);
    }
    let state = truth();
    let pos_var = samples
        .iter()
        .map(|s| (s.position_m - state.position_m).norm_squared())
        .sum::<f64>()
        / (3 * n) as f64;
    let att_var = samples
        .iter()
        .map(|s| {
            (state.attitude.inverse() * s.attitude.unwrap())
                .scaled_axis()
                .norm_squared()
        })
        .sum::<f64>()
        / (3 * n) as f64;
    // Standard error of a standard deviation over 3n values: 1 / sqrt(6n) = 0.3 %.
    assert!(
        (pos_var.sqrt() / 0.2e-3 - 1.0).abs() < 0.015,
        "{}",
        pos_var.sqrt()
    );
    let att = profile.attitude_noise_rad.unwrap();
    assert!(
        (att_var.sqrt() / att - 1.0).abs() < 0.015,
        "{}",
        att_var.sqrt()
    );
    // 0.2 mm / (0.1 m sqrt 2) = 0.081 deg.
    assert!((att.to_degrees() - 0.081).abs() < 0.001);
}

#[test]
fn gnss_drift_is_first_order_gauss_markov() {
    // A short correlation time (1 s at 5 Hz) so a 20,000 s record holds 20,000 of them.
    let profile = PositionSourceProfile {
        drift_time_constant_s: 1.0,
        dropouts: None,
        ..PositionSourceProfile::ublox_neo_m8n()
    };
    let mut gnss = PositionSource::new(profile, 4).unwrap();
    let state = truth();
    let n = 100_000;
    let drifts: Vec<Vector3<f64>> = (0..n)
        .map(|_| {
            let d = gnss.drift_m();
            gnss.sample(&state);
            d
        })
        .collect();
    let var_x = drifts.iter().map(|d| d.x * d.x).sum::<f64>() / n as f64;
    let var_z = drifts.iter().map(|d| d.z * d.z).sum::<f64>() / n as f64;
    let lag1 = drifts.windows(2).map(|w| w[0].x * w[1].x).sum::<f64>() / (n - 1) as f64 / var_x;
    let phi = (-0.2f64).exp();
    // Effective sample count n (1 - phi) / (1 + phi) = 9,000: sigma good to ~1 %.
    assert!(
        (var_x.sqrt() / profile.horizontal_drift_m - 1.0).abs() < 0.04,
        "{}",
        var_x.sqrt()
    );
    assert!(
        (var_z.sqrt() / profile.vertical_drift_m - 1.0).abs() < 0.04,
        "{}",
        var_z.sqrt()
    );
    assert!((lag1 - phi).abs() < 0.01, "{lag1} vs {phi}");
    // NEO-M8N: 2.5 m CEP -> 2.12 m per horizontal axis; vertical 1.5 times that.
    assert!((PositionSourceProfile::ublox_neo_m8n().horizontal_drift_m - 2.123).abs() < 1e-3);
}

#[test]
fn gnss_velocity_noise_is_the_50_percent_figure_as_sigma() {
    let profile = PositionSourceProfile {
        dropouts: None,
        ..PositionSourceProfile::ublox_neo_m8n()
    };
    let mut gnss = PositionSource::new(profile, 6).unwrap();
    let n = 20_000;
    let samples = measurements(&mut gnss, n);
    let v = truth().velocity_m_s;
    let abs_errors: Vec<f64> = samples
        .iter()
        .map(|s| (s.velocity_m_s.unwrap().x - v.x).abs())
        .collect();
    // The median absolute error per axis is the datasheet's 0.05 m/s.
    let mut sorted = abs_errors.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[n / 2];
    assert!((median / 0.05 - 1.0).abs() < 0.03, "{median}");
}

#[test]
fn dropouts_last_and_recur_as_the_chain_says() {
    let profile = PositionSourceProfile {
        dropouts: Some(Dropouts {
            mean_interval_s: 10.0,
            mean_duration_s: 2.0,
        }),
        ..PositionSourceProfile::ublox_neo_m8n()
    };
    let mut gnss = PositionSource::new(profile, 21).unwrap();
    let state = truth();
    let n = 200_000;
    let mut runs = Vec::new();
    let mut run = 0;
    for _ in 0..n {
        gnss.sample(&state);
        if gnss.is_dropped() {
            run += 1;
        } else if run > 0 {
            runs.push(run);
            run = 0;
        }
        while gnss.poll(f64::INFINITY).is_some() {}
    }
    let fraction = gnss.dropped_samples() as f64 / n as f64;
    let mean_duration = runs.iter().sum::<usize>() as f64 / runs.len() as f64 / 5.0;
    // About 3,300 dropouts in the record: the fraction (2 / 12) and the mean duration (the
    // discrete chain's 1 / (1 - exp(-T / 2 s)) samples = 2.1 s) are good to ~3 %.
    assert!((fraction / (2.0 / 12.0) - 1.0).abs() < 0.06, "{fraction}");
    let expected = 1.0 / (1.0 - (-0.2f64 / 2.0).exp()) / 5.0;
    assert!(
        (mean_duration / expected - 1.0).abs() < 0.06,
        "{mean_duration} vs {expected}"
    );
}

#[test]
fn seeded_and_independent_of_latency() {
    // Latency delays delivery and draws nothing: the same seed gives the same values.
    let delayed = PositionSourceProfile::optitrack_primex_13();
    let prompt = PositionSourceProfile {
        latency_s: 0.0,
        ..delayed
    };
    let a = measurements(&mut PositionSource::new(delayed, 3).unwrap(), 50);
    let b = measurements(&mut PositionSource::new(prompt, 3).unwrap(), 50);
    let c = measurements(&mut PositionSource::new(delayed, 4).unwrap(), 50);
    for ((x, y), z) in a.iter().zip(&b).zip(&c) {
        assert_eq!(
            (x.position_m, x.attitude, x.valid_at_s),
            (y.position_m, y.attitude, y.valid_at_s)
        );
        assert_eq!(x.arrives_at_s, y.arrives_at_s + 5e-3);
        assert_ne!(x.position_m, z.position_m);
    }
}

#[test]
fn every_rule_names_its_field() {
    let cases: &[RuleCase<PositionSourceProfile>] = &[
        ("position.rate_hz", |p| p.rate_hz = -1.0),
        ("position.latency_s", |p| p.latency_s = f64::NAN),
        ("position.horizontal_noise_m", |p| {
            p.horizontal_noise_m = -1.0
        }),
        ("position.vertical_noise_m", |p| {
            p.vertical_noise_m = f64::INFINITY
        }),
        ("position.horizontal_drift_m", |p| {
            p.horizontal_drift_m = -1.0
        }),
        ("position.vertical_drift_m", |p| {
            p.vertical_drift_m = f64::NAN
        }),
        ("position.drift_time_constant_s", |p| {
            p.drift_time_constant_s = 0.0
        }),
        ("position.velocity_noise_m_s", |p| {
            p.velocity_noise_m_s = Some(-0.1)
        }),
        ("position.attitude_noise_rad", |p| {
            p.attitude_noise_rad = Some(f64::NAN)
        }),
        ("position.dropouts.mean_interval_s", |p| {
            p.dropouts = Some(Dropouts {
                mean_interval_s: 0.0,
                mean_duration_s: 1.0,
            })
        }),
        ("position.dropouts.mean_duration_s", |p| {
            p.dropouts = Some(Dropouts {
                mean_interval_s: 1.0,
                mean_duration_s: -1.0,
            })
        }),
    ];
    let base = PositionSourceProfile::ublox_neo_m8n();
    assert_rules_name_fields(&base, cases, |p| PositionSource::new(*p, 0).map(|_| ()));
    for p in [
        PositionSourceProfile::optitrack_primex_13(),
        PositionSourceProfile::ublox_zed_f9p_rtk(),
        PositionSourceProfile::default(),
    ] {
        p.check().unwrap();
    }
}
