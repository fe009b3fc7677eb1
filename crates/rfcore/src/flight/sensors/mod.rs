#![doc = include_str!("README.md")]

use crate::error::{require_finite, Result, RfError};

pub mod allan;
pub mod clock;
pub mod imu;
pub mod magnetometer;
pub mod position;
pub mod reference;
pub mod rotor_speed;
pub mod suite;

pub use clock::SampleClock;
pub use imu::{AccelProfile, GyroProfile, Imu, ImuProfile, ImuSample, ImuTruth, Vibration};
pub use magnetometer::{Magnetometer, MagnetometerProfile, MagnetometerSample};
pub use position::{Dropouts, PositionSample, PositionSource, PositionSourceProfile};
pub use rotor_speed::{RotorSpeedProfile, RotorSpeedSensor};
pub use suite::{SensorSuite, SensorSuiteProfile};

/// One degree, rad (datasheets give rates in deg/s).
pub const DEG: f64 = std::f64::consts::PI / 180.0;
/// Standard gravity, m/s^2: the `g` of datasheet accelerometer figures (mg, ug/sqrt(Hz)).
pub const G0_M_S2: f64 = 9.806_65;
/// CEP (the radius holding 50 % of a circular 2-D Gaussian) over the per-axis sigma:
/// `sqrt(2 ln 2)`.
pub const CEP_TO_SIGMA: f64 = 1.177_410_022_515_474_6;
/// The median of |x| over sigma for a 1-D Gaussian (a "50 %" accuracy figure): 0.6745.
pub const MEDIAN_TO_SIGMA: f64 = 0.674_489_750_196_081_7;

/// How a bias random walk is read off a datasheet (decided once, README "Bias random walk"):
/// consumer MEMS datasheets give no random walk, only how the bias moves with temperature
/// (`per_kelvin`). A flight warms the board by `delta_k` over `duration_s`; the walk whose spread
/// over one flight equals that drift has density `per_kelvin delta_k / sqrt(duration_s)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemperatureWalk {
    pub delta_k: f64,
    pub duration_s: f64,
}

impl TemperatureWalk {
    /// The random-walk density (unit/sqrt(s)) of a bias moving `per_kelvin` (unit/K).
    pub fn walk(&self, per_kelvin: f64) -> f64 {
        per_kelvin * self.delta_k / self.duration_s.sqrt()
    }
}

/// 10 K over a 10-minute flight.
pub const TEMPERATURE_WALK: TemperatureWalk = TemperatureWalk {
    delta_k: 10.0,
    duration_s: 600.0,
};

/// Stream numbers of [`crate::flight::random::Gaussian::stream`], one per sensor.
pub mod streams {
    pub const GYRO: u64 = 1;
    pub const ACCEL: u64 = 2;
    pub const POSITION: u64 = 3;
    pub const MAGNETOMETER: u64 = 4;
    pub const ROTOR_SPEED: u64 = 5;
}

/// Rejects NaN, infinities and values <= 0, naming the field.
pub(crate) fn require_positive(field: &str, value: f64) -> Result<()> {
    require_finite(field, value)?;
    if value <= 0.0 {
        return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
    }
    Ok(())
}

/// A rule test case: the field it names and how to break it.
#[cfg(test)]
pub(crate) type RuleCase<P> = (&'static str, fn(&mut P));

/// Test support: every case breaks one rule of `base` and must be refused by `check` with an
/// error that starts with the case's field name.
#[cfg(test)]
pub(crate) fn assert_rules_name_fields<P: Clone>(
    base: &P,
    cases: &[RuleCase<P>],
    check: impl Fn(&P) -> Result<()>,
) {
    for (field, break_it) in cases {
        let mut p = base.clone();
        break_it(&mut p);
        let err = check(&p).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            err.starts_with(&format!("{field}:")),
            "{field}: got {err:?}"
        );
    }
}
