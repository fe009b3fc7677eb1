//! A vehicle's sensor suite: one IMU, one position source, an optional magnetometer and rotor
//! speed feedback, as named profiles, and the seeded sensors built from them (each on its own
//! random stream of the run's seed).

use crate::error::Result;
use crate::flight::sensors::{
    Imu, ImuProfile, Magnetometer, MagnetometerProfile, PositionSource, PositionSourceProfile,
    RotorSpeedProfile, RotorSpeedSensor,
};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSuiteProfile {
    pub imu: ImuProfile,
    pub position: PositionSourceProfile,
    /// `None`: no magnetometer (motion capture gives the heading).
    pub magnetometer: Option<MagnetometerProfile>,
    pub rotor_speed: RotorSpeedProfile,
}

impl SensorSuiteProfile {
    /// A lab flight: ICM-42688-P, OptiTrack PrimeX 13 pose, DShot rotor speeds.
    pub fn mocap() -> Self {
        SensorSuiteProfile {
            imu: ImuProfile::icm_42688_p(),
            position: PositionSourceProfile::optitrack_primex_13(),
            magnetometer: None,
            rotor_speed: RotorSpeedProfile::bidirectional_dshot(),
        }
    }

    /// Outdoors: ICM-42688-P, u-blox NEO-M8N, ST LIS3MDL, DShot rotor speeds.
    pub fn gnss() -> Self {
        SensorSuiteProfile {
            position: PositionSourceProfile::ublox_neo_m8n(),
            magnetometer: Some(MagnetometerProfile::st_lis3mdl()),
            ..SensorSuiteProfile::mocap()
        }
    }

    /// Outdoors with RTK: as [`SensorSuiteProfile::gnss`] with the u-blox ZED-F9P.
    pub fn rtk() -> Self {
        SensorSuiteProfile {
            position: PositionSourceProfile::ublox_zed_f9p_rtk(),
            ..SensorSuiteProfile::gnss()
        }
    }

    /// Every sensor's rules (fields named `imu.`, `position.`, `magnetometer.`, `rotor_speed.`).
    pub fn check(&self) -> Result<()> {
        self.imu.check()?;
        self.position.check()?;
        if let Some(m) = &self.magnetometer {
            m.check()?;
        }
        self.rotor_speed.check()
    }
}

/// Motion capture ([`SensorSuiteProfile::mocap`]).
impl Default for SensorSuiteProfile {
    fn default() -> Self {
        SensorSuiteProfile::mocap()
    }
}

/// The seeded sensors of one run.
#[derive(Debug, Clone)]
pub struct SensorSuite {
    pub imu: Imu,
    pub position: PositionSource,
    pub magnetometer: Option<Magnetometer>,
    pub rotor_speed: RotorSpeedSensor,
}

impl SensorSuite {
    pub fn new(profile: &SensorSuiteProfile, rotor_count: usize, seed: u64) -> Result<Self> {
        profile.check()?;
        Ok(SensorSuite {
            imu: Imu::new(profile.imu, seed)?,
            position: PositionSource::new(profile.position, seed)?,
            magnetometer: profile
                .magnetometer
                .map(|m| Magnetometer::new(m, seed))
                .transpose()?,
            rotor_speed: RotorSpeedSensor::new(profile.rotor_speed, rotor_count, seed)?,
        })
    }
}
