//! What the controller flies on when it flies on sensors ([`Sensing`]): a named sensor suite
//! (`mocap`, `gnss`, `rtk`), its IMU part and rates, and the seed of the run's sensors. The
//! estimator is matched to the sensors ([`EstimatorSettings::for_sensors`]), so choosing a suite
//! chooses both.
//!
//! A run flies on one of three things (one concept, one name: "sensing"): the truth (no noise, no
//! sensing), the papers' relative noise on the state (`SimulationConfig::noise`, kept to reproduce
//! the papers' scenarios) or sensors with the estimator (`SimulationConfig::sensing`).

use crate::error::{require_scale, Result, RfError};
use crate::flight::estimation::EstimatorSettings;
use crate::flight::sensors::{ImuProfile, SensorSuiteProfile};

/// A sensor suite by name (the profiles of [`SensorSuiteProfile`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SuiteName {
    /// ICM-42688-P, OptiTrack PrimeX 13 pose, DShot rotor speeds: a lab flight.
    Mocap,
    /// ICM-42688-P, u-blox NEO-M8N, ST LIS3MDL, DShot: outdoors.
    Gnss,
    /// As `gnss` with the u-blox ZED-F9P in RTK.
    Rtk,
}

impl SuiteName {
    pub const ALL: [SuiteName; 3] = [SuiteName::Mocap, SuiteName::Gnss, SuiteName::Rtk];

    pub fn name(self) -> &'static str {
        match self {
            SuiteName::Mocap => "mocap",
            SuiteName::Gnss => "gnss",
            SuiteName::Rtk => "rtk",
        }
    }

    /// The suite called `name`, or an error naming `field` and the names.
    pub fn from_name(field: &str, name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|s| s.name() == name)
            .ok_or_else(|| unknown(field, name, &Self::ALL.map(Self::name)))
    }

    pub fn profile(self) -> SensorSuiteProfile {
        match self {
            SuiteName::Mocap => SensorSuiteProfile::mocap(),
            SuiteName::Gnss => SensorSuiteProfile::gnss(),
            SuiteName::Rtk => SensorSuiteProfile::rtk(),
        }
    }
}

/// An IMU part by name (the profiles of [`ImuProfile`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ImuPart {
    Icm42688P,
    Mpu6000,
}

impl ImuPart {
    pub const ALL: [ImuPart; 2] = [ImuPart::Icm42688P, ImuPart::Mpu6000];

    pub fn name(self) -> &'static str {
        match self {
            ImuPart::Icm42688P => "icm-42688-p",
            ImuPart::Mpu6000 => "mpu-6000",
        }
    }

    pub fn from_name(field: &str, name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|s| s.name() == name)
            .ok_or_else(|| unknown(field, name, &Self::ALL.map(Self::name)))
    }

    pub fn profile(self) -> ImuProfile {
        match self {
            ImuPart::Icm42688P => ImuProfile::icm_42688_p(),
            ImuPart::Mpu6000 => ImuProfile::mpu_6000(),
        }
    }
}

fn unknown(field: &str, name: &str, names: &[&str]) -> RfError {
    RfError::invalid(
        field,
        format!("expected one of {}, got {name:?}", names.join(", ")),
    )
}

/// The highest IMU output data rate accepted, Hz: the ICM-42688-P's highest ODR (32 kHz).
pub const MAX_IMU_RATE_HZ: f64 = 32_000.0;
/// The highest position-source rate accepted, Hz (motion-capture systems reach 1 kHz).
pub const MAX_POSITION_RATE_HZ: f64 = 1_000.0;
/// The largest gyroscope range accepted, rad/s: five times the simulator's default body-rate
/// limit (200 rad/s, where a run counts as lost), so any larger range never clamps.
pub const MAX_GYRO_RANGE_RAD_S: f64 = 1_000.0;

/// Sensors and the estimator for one run (module docs). Run `i` of a batch uses `seed + i`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensing {
    pub suite: SuiteName,
    pub imu: ImuPart,
    /// The IMU's output data rate (gyroscope and accelerometer), Hz.
    pub imu_rate_hz: f64,
    /// The position source's rate, Hz; `None`: the suite's (mocap 240, NEO-M8N 5, ZED-F9P 10).
    pub position_rate_hz: Option<f64>,
    /// The gyroscope's range (full scale, +/-), rad/s; `None`: the part's (both parts' largest,
    /// +/-2000 deg/s = 34.9 rad/s). A what-if for a vehicle that spins faster than its gyro reads
    /// (parts with +/-4000 deg/s exist); the part's noise and errors are kept.
    pub gyro_range_rad_s: Option<f64>,
    /// Seeds every sensor's random stream (its own stream per sensor: `flight::random`).
    pub seed: u64,
}

/// The motion-capture suite with the ICM-42688-P at 500 Hz, one of the part's output data rates
/// (DS-000347, ODR table): the datasheet profile's 1 kHz costs twice the IMU samples and estimator
/// steps for a controller running at 400 Hz, which sees one estimate per control step either way
/// (crates/rfcore/benches/sensing.rs measures both).
impl Default for Sensing {
    fn default() -> Self {
        Sensing {
            suite: SuiteName::Mocap,
            imu: ImuPart::Icm42688P,
            imu_rate_hz: 500.0,
            position_rate_hz: None,
            gyro_range_rad_s: None,
            seed: 0,
        }
    }
}

impl Sensing {
    /// The sensors' profiles: the suite's, with this IMU part at `imu_rate_hz` and the position
    /// source at `position_rate_hz` (when given).
    pub fn profile(&self) -> SensorSuiteProfile {
        let mut profile = self.suite.profile();
        profile.imu = ImuProfile {
            rate_hz: self.imu_rate_hz,
            ..self.imu.profile()
        };
        if let Some(rate) = self.position_rate_hz {
            profile.position.rate_hz = rate;
        }
        if let Some(range) = self.gyro_range_rad_s {
            profile.imu.gyro.range_rad_s = range;
        }
        profile
    }

    /// The estimator matched to [`Sensing::profile`].
    pub fn estimator(&self) -> EstimatorSettings {
        EstimatorSettings::for_sensors(&self.profile())
    }

    /// Every rule, naming the field (`sensing.imu_rate_hz`, ...).
    pub fn check(&self) -> Result<()> {
        rate("sensing.imu_rate_hz", self.imu_rate_hz, MAX_IMU_RATE_HZ)?;
        if let Some(r) = self.position_rate_hz {
            rate("sensing.position_rate_hz", r, MAX_POSITION_RATE_HZ)?;
        }
        if let Some(r) = self.gyro_range_rad_s {
            require_scale("sensing.gyro_range_rad_s", r, "rad/s")?;
            if !(r > 0.0 && r <= MAX_GYRO_RANGE_RAD_S) {
                return Err(RfError::invalid(
                    "sensing.gyro_range_rad_s",
                    format!("must be > 0 and at most {MAX_GYRO_RANGE_RAD_S} rad/s, got {r}"),
                ));
            }
        }
        self.profile().check()?;
        self.estimator().check()
    }

    /// What the controller sees, by name: the suite's (`mocap`, `gnss`, `rtk`).
    pub fn name(&self) -> &'static str {
        self.suite.name()
    }
}

/// A rate the sensors divide by (their sample period): a scale (`require_scale`: a subnormal
/// rate's period is infinite, and building the simulator never returned), at most `most`.
fn rate(field: &str, value: f64, most: f64) -> Result<()> {
    require_scale(field, value, "Hz")?;
    if !(value > 0.0 && value <= most) {
        return Err(RfError::invalid(
            field,
            format!("must be > 0 and at most {most} Hz, got {value}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_bad_settings_are_named() {
        for s in SuiteName::ALL {
            assert_eq!(SuiteName::from_name("suite", s.name()).unwrap(), s);
        }
        for p in ImuPart::ALL {
            assert_eq!(ImuPart::from_name("imu", p.name()).unwrap(), p);
        }
        let err = SuiteName::from_name("sensing.suite", "vicon").unwrap_err();
        assert!(err
            .to_string()
            .starts_with("sensing.suite: expected one of mocap, gnss, rtk"));
        Sensing::default().check().unwrap();
        for (field, bad) in [
            (
                "sensing.imu_rate_hz",
                Sensing {
                    imu_rate_hz: 0.0,
                    ..Sensing::default()
                },
            ),
            (
                "sensing.imu_rate_hz",
                Sensing {
                    imu_rate_hz: f64::NAN,
                    ..Sensing::default()
                },
            ),
            (
                "sensing.imu_rate_hz",
                Sensing {
                    imu_rate_hz: 1e6,
                    ..Sensing::default()
                },
            ),
            (
                "sensing.position_rate_hz",
                Sensing {
                    position_rate_hz: Some(-1.0),
                    ..Sensing::default()
                },
            ),
            (
                "sensing.gyro_range_rad_s",
                Sensing {
                    gyro_range_rad_s: Some(0.0),
                    ..Sensing::default()
                },
            ),
            (
                "sensing.gyro_range_rad_s",
                Sensing {
                    gyro_range_rad_s: Some(f64::INFINITY),
                    ..Sensing::default()
                },
            ),
            (
                "sensing.gyro_range_rad_s",
                Sensing {
                    gyro_range_rad_s: Some(2_000.0),
                    ..Sensing::default()
                },
            ),
            // Subnormal rates: an infinite sample period (the simulator never got built).
            (
                "sensing.position_rate_hz",
                Sensing {
                    position_rate_hz: Some(1e-310),
                    ..Sensing::default()
                },
            ),
            (
                "sensing.imu_rate_hz",
                Sensing {
                    imu_rate_hz: 1e-310,
                    ..Sensing::default()
                },
            ),
        ] {
            let err = bad.check().unwrap_err().to_string();
            assert!(err.starts_with(&format!("{field}:")), "{err}");
        }
    }

    #[test]
    fn the_profile_carries_the_chosen_part_and_rates() {
        let s = Sensing {
            suite: SuiteName::Gnss,
            imu: ImuPart::Mpu6000,
            imu_rate_hz: 1000.0,
            position_rate_hz: Some(10.0),
            gyro_range_rad_s: None,
            seed: 3,
        };
        let p = s.profile();
        assert_eq!(p.imu.rate_hz, 1000.0);
        assert_eq!(p.imu.gyro, ImuProfile::mpu_6000().gyro);
        assert_eq!(p.position.rate_hz, 10.0);
        assert!(p.magnetometer.is_some());
        // A range given replaces the part's and nothing else; the estimator is told it.
        let wide = Sensing {
            gyro_range_rad_s: Some(70.0),
            ..s
        };
        let q = wide.profile();
        assert_eq!(q.imu.gyro.range_rad_s, 70.0);
        assert_eq!(
            q.imu.gyro.noise_density_rad_s_rt_hz,
            p.imu.gyro.noise_density_rad_s_rt_hz
        );
        assert_eq!(q.imu.accel, p.imu.accel);
        assert_eq!(wide.estimator().gyro_range_rad_s, 70.0);
        assert_eq!(s.estimator().fusion_delay_s, p.position.latency_s);
    }
}
