//! The estimator's model of its sensors and of the world, with one `Default` (the motion-capture
//! suite) and a `check()` naming each rule. [`EstimatorSettings::for_sensors`] reads every figure
//! from the sensor profiles, so a filter is matched to its sensors by construction; tuning is a
//! change of these numbers, not of the profiles.

use nalgebra::Vector3;

use crate::error::{require_finite, require_non_negative, Result, RfError};
use crate::flight::sensors::{require_positive, SensorSuiteProfile};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorSettings {
    /// How far the fusion horizon runs behind the newest IMU sample, s: at least the latency of
    /// every measurement source (a later measurement is counted as late and dropped).
    pub fusion_delay_s: f64,
    /// The covariance is propagated in blocks of IMU intervals this long, s (and always up to
    /// a measurement's time of validity before it is fused); 0: every interval.
    pub covariance_period_s: f64,
    /// A position source's fixes are fused at most one per slot of this length, s (slots
    /// `[k T, (k + 1) T)` of the time of validity; the first fix of a slot is fused, the others
    /// are counted as thinned); 0: every fix.
    pub position_fusion_period_s: f64,
    pub gravity_m_s2: f64,
    /// The IMU's position relative to the centre of mass, body axes, m.
    pub imu_position_m: Vector3<f64>,

    pub gyro_noise_density_rad_s_rt_hz: f64,
    pub gyro_bias_walk_rad_s_rt_s: f64,
    pub gyro_scale_error: f64,
    pub gyro_cross_axis: f64,
    pub gyro_range_rad_s: f64,
    pub accel_noise_density_m_s2_rt_hz: f64,
    pub accel_bias_walk_m_s2_rt_s: f64,
    pub accel_scale_error: f64,
    pub accel_cross_axis: f64,
    pub accel_range_m_s2: f64,
    /// Time constant of the input's running mean, s: scale and cross-axis errors of the part of
    /// the rate (specific force) that departs from it feed the bias uncertainty (module docs).
    pub input_mean_time_s: f64,
    /// The unknown excess of a clamped reading, as a fraction of the range (1 sigma): added to
    /// that axis's bias variance when clamping starts and when it ends.
    pub saturation_excess: f64,
    /// While an axis is clamped its hidden excess changes as the true rate (force) does: that
    /// axis's bias walks with density `saturation_walk range` per sqrt(s) (a fraction of the
    /// range per sqrt(s); 0.05: 1.7 rad/s/sqrt(s) for a 2000 deg/s gyro, 0.11 rad/s over the
    /// 4 ms between two 240 Hz fixes. Chosen on two measurements: INDI losing one and two rotors
    /// on mocap (the gyro clamped half the flight, `tests/sensing.rs`) flies with 0.075 deg
    /// attitude RMS at 0.05 against 0.14 deg at 0.25, and a steady clamped 40 rad/s spin stays
    /// below the raw mocap attitude noise at 0.05, not at 0.25; measured with every 240 Hz fix
    /// fused: with one fused per 10 ms (`position_fusion_period_s`) INDI's is 0.104 deg and the
    /// clamped spin's 0.111 deg, against 0.084 deg fusing every fix and 0.14 deg raw).
    pub saturation_walk: f64,

    pub initial_position_std_m: f64,
    pub initial_velocity_std_m_s: f64,
    pub initial_attitude_std_rad: f64,
    pub initial_gyro_bias_std_rad_s: f64,
    pub initial_accel_bias_std_m_s2: f64,

    /// Position measurement noise, horizontal and vertical, m (1 sigma).
    pub position_std_m: [f64; 2],
    pub velocity_std_m_s: f64,
    pub attitude_std_rad: f64,
    pub magnetometer_std_ut: f64,
    /// The field the magnetometer is fused against, world NED, uT.
    pub earth_field_ut: Vector3<f64>,
    /// Largest normalised innovation squared (chi-square, 3 degrees of freedom) a measurement
    /// may have and still be fused.
    pub innovation_gate: f64,
    /// First-order low-pass on the bias-corrected gyro handed to controllers, Hz (`None`: the
    /// bias-corrected samples unfiltered).
    pub gyro_cutoff_hz: Option<f64>,
}

/// 3-degree-of-freedom chi-square quantile at 1 - 1e-4: a measurement this improbable under the
/// filter's own model is refused.
pub const CHI2_3DOF_1E4: f64 = 21.107_513_328_942_02;

impl EstimatorSettings {
    /// The filter matched to `sensors`: noise densities, scale and cross-axis errors and ranges
    /// of its IMU; initial bias uncertainty = the turn-on biases; measurement noise = the
    /// position source's total (white and drift) error; fusion delay = the position source's
    /// latency; covariance in blocks of 10 ms (PX4's EKF2 predicts its covariance at 100 Hz, and
    /// the fixes are fused at most once per 10 ms: with 5 ms blocks a fusion, which first brings
    /// the covariance to its time of validity, fell between two periodic blocks, 3,400
    /// propagations in a 10 s Ke flight against 1,400 now, 4 % of the flight's instructions);
    /// position fixes fused at most once per 10 ms (EKF2 fuses at most one external-vision fix
    /// per 10 ms filter update: a 240 Hz motion-capture stream is fused at 100 Hz, each fix at
    /// its own time of validity; a 5-10 Hz GNSS receiver is not thinned). A fused fix costs
    /// about 25 IMU-sample propagations of work (two updates, the covariance brought to its time,
    /// the output predictor replayed): at 240 Hz this was half the cost of flying on sensors,
    /// while the attitude noise it averages (0.1 deg per fix) is far below what the controllers
    /// respond to. Initial state uncertainty: the position source's error, 0.1 m/s and 2 deg (a
    /// start after a ground alignment).
    pub fn for_sensors(sensors: &SensorSuiteProfile) -> Self {
        let imu = &sensors.imu;
        let position = &sensors.position;
        let [horizontal, vertical] = position.position_std_m();
        let magnetometer = sensors.magnetometer;
        EstimatorSettings {
            fusion_delay_s: position.latency_s,
            covariance_period_s: 0.01,
            position_fusion_period_s: 0.01,
            gravity_m_s2: crate::airframe::DEFAULT_GRAVITY_M_S2,
            imu_position_m: imu.position_m,
            gyro_noise_density_rad_s_rt_hz: imu.gyro.noise_density_rad_s_rt_hz,
            gyro_bias_walk_rad_s_rt_s: imu.gyro.bias_walk_rad_s_rt_s,
            gyro_scale_error: imu.gyro.scale_error,
            gyro_cross_axis: imu.gyro.cross_axis,
            gyro_range_rad_s: imu.gyro.range_rad_s,
            accel_noise_density_m_s2_rt_hz: imu.accel.noise_density_m_s2_rt_hz,
            accel_bias_walk_m_s2_rt_s: imu.accel.bias_walk_m_s2_rt_s,
            accel_scale_error: imu.accel.scale_error,
            accel_cross_axis: imu.accel.cross_axis,
            accel_range_m_s2: imu.accel.range_m_s2,
            input_mean_time_s: 1.0,
            saturation_excess: 0.25,
            saturation_walk: 0.05,
            initial_position_std_m: horizontal.max(vertical),
            initial_velocity_std_m_s: 0.1,
            initial_attitude_std_rad: 2f64.to_radians(),
            initial_gyro_bias_std_rad_s: imu.gyro.turn_on_bias_rad_s,
            initial_accel_bias_std_m_s2: imu.accel.turn_on_bias_m_s2,
            position_std_m: [horizontal, vertical],
            velocity_std_m_s: position.velocity_noise_m_s.unwrap_or(f64::INFINITY),
            attitude_std_rad: position.attitude_noise_rad.unwrap_or(f64::INFINITY),
            magnetometer_std_ut: magnetometer
                .map_or(f64::INFINITY, |m| m.noise_ut.hypot(m.bias_ut)),
            earth_field_ut: magnetometer
                .map_or(Vector3::new(25.0, 0.0, 43.3), |m| m.earth_field_ut),
            innovation_gate: CHI2_3DOF_1E4,
            gyro_cutoff_hz: None,
        }
    }

    /// Every rule, naming the field (`estimator.fusion_delay_s`, ...). Measurement noises may be
    /// infinite (that measurement kind is not expected), never NaN, zero or negative.
    pub fn check(&self) -> Result<()> {
        let positive = [
            ("gravity_m_s2", self.gravity_m_s2),
            ("gyro_range_rad_s", self.gyro_range_rad_s),
            ("accel_range_m_s2", self.accel_range_m_s2),
            ("input_mean_time_s", self.input_mean_time_s),
            ("innovation_gate", self.innovation_gate),
        ];
        for (name, v) in positive {
            if name == "innovation_gate" && v == f64::INFINITY {
                continue;
            }
            require_positive(&format!("estimator.{name}"), v)?;
        }
        let non_negative = [
            ("fusion_delay_s", self.fusion_delay_s),
            ("covariance_period_s", self.covariance_period_s),
            ("position_fusion_period_s", self.position_fusion_period_s),
            (
                "gyro_noise_density_rad_s_rt_hz",
                self.gyro_noise_density_rad_s_rt_hz,
            ),
            ("gyro_bias_walk_rad_s_rt_s", self.gyro_bias_walk_rad_s_rt_s),
            ("gyro_scale_error", self.gyro_scale_error),
            ("gyro_cross_axis", self.gyro_cross_axis),
            (
                "accel_noise_density_m_s2_rt_hz",
                self.accel_noise_density_m_s2_rt_hz,
            ),
            ("accel_bias_walk_m_s2_rt_s", self.accel_bias_walk_m_s2_rt_s),
            ("accel_scale_error", self.accel_scale_error),
            ("accel_cross_axis", self.accel_cross_axis),
            ("saturation_excess", self.saturation_excess),
            ("saturation_walk", self.saturation_walk),
            ("initial_position_std_m", self.initial_position_std_m),
            ("initial_velocity_std_m_s", self.initial_velocity_std_m_s),
            ("initial_attitude_std_rad", self.initial_attitude_std_rad),
            (
                "initial_gyro_bias_std_rad_s",
                self.initial_gyro_bias_std_rad_s,
            ),
            (
                "initial_accel_bias_std_m_s2",
                self.initial_accel_bias_std_m_s2,
            ),
        ];
        for (name, v) in non_negative {
            require_non_negative(&format!("estimator.{name}"), v)?;
        }
        let noises = [
            ("position_std_m[0]", self.position_std_m[0]),
            ("position_std_m[1]", self.position_std_m[1]),
            ("velocity_std_m_s", self.velocity_std_m_s),
            ("attitude_std_rad", self.attitude_std_rad),
            ("magnetometer_std_ut", self.magnetometer_std_ut),
        ];
        for (name, v) in noises {
            if v.is_nan() || v <= 0.0 {
                return Err(RfError::invalid(
                    format!("estimator.{name}"),
                    format!("must be > 0 (infinite: not measured), got {v}"),
                ));
            }
        }
        for i in 0..3 {
            require_finite(
                &format!("estimator.imu_position_m[{i}]"),
                self.imu_position_m[i],
            )?;
            require_finite(
                &format!("estimator.earth_field_ut[{i}]"),
                self.earth_field_ut[i],
            )?;
        }
        if let Some(f) = self.gyro_cutoff_hz {
            require_positive("estimator.gyro_cutoff_hz", f)?;
        }
        Ok(())
    }
}

/// Matched to the motion-capture suite ([`SensorSuiteProfile::mocap`]).
impl Default for EstimatorSettings {
    fn default() -> Self {
        EstimatorSettings::for_sensors(&SensorSuiteProfile::mocap())
    }
}
