//! The magnetometer: the Earth's field in body axes, with white noise and a residual hard-iron
//! bias (what remains after calibration), on its own clock:
//!
//! ```text
//! m_k = R(t_k)^T m_earth + b + n_k,   b ~ N(0, sigma_b^2 I) once per seed,   n_k ~ N(0, sigma^2 I)
//! ```
//!
//! Soft-iron distortion and motor-current interference are not modelled (they depend on the
//! airframe's wiring; a residual bias stands in for what calibration leaves).

use nalgebra::Vector3;

use crate::error::{require_finite, require_non_negative, Result, RfError};
use crate::flight::random::Gaussian;
use crate::flight::sensors::clock::SampleClock;
use crate::flight::sensors::{require_positive, streams};
use crate::state::RigidBodyState;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagnetometerProfile {
    pub rate_hz: f64,
    /// White noise per axis, uT (1 sigma).
    pub noise_ut: f64,
    /// Residual hard-iron bias per axis after calibration, uT (1 sigma, drawn once per seed).
    pub bias_ut: f64,
    /// The site's field, world NED, uT (the estimator's world model uses the same).
    pub earth_field_ut: Vector3<f64>,
}

impl MagnetometerProfile {
    /// ST LIS3MDL (datasheet DocID024204): RMS noise 3.2 mgauss (x, y) and 4.1 mgauss (z) in
    /// ultra-high-performance mode at +/- 4 gauss, the larger for all axes (1 mgauss = 0.1 uT);
    /// 80 Hz ODR. Residual hard-iron bias 0 (assumed calibrated; set it to study heading
    /// errors). Field: 50 uT at 60 deg inclination, declination 0 (mid-northern latitudes).
    pub fn st_lis3mdl() -> Self {
        let inclination = 60f64.to_radians();
        MagnetometerProfile {
            rate_hz: 80.0,
            noise_ut: 0.41,
            bias_ut: 0.0,
            earth_field_ut: Vector3::new(50.0 * inclination.cos(), 0.0, 50.0 * inclination.sin()),
        }
    }

    pub fn check(&self) -> Result<()> {
        require_positive("magnetometer.rate_hz", self.rate_hz)?;
        require_non_negative("magnetometer.noise_ut", self.noise_ut)?;
        require_non_negative("magnetometer.bias_ut", self.bias_ut)?;
        for (i, &x) in self.earth_field_ut.iter().enumerate() {
            require_finite(&format!("magnetometer.earth_field_ut[{i}]"), x)?;
        }
        if self.earth_field_ut.norm() == 0.0 {
            return Err(RfError::invalid(
                "magnetometer.earth_field_ut",
                "must not be zero (the heading reference)",
            ));
        }
        Ok(())
    }
}

/// The ST LIS3MDL.
impl Default for MagnetometerProfile {
    fn default() -> Self {
        MagnetometerProfile::st_lis3mdl()
    }
}

/// One magnetometer sample (delivered at once: the magnetometer's delay is below a sample).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagnetometerSample {
    pub time_s: f64,
    pub field_ut: Vector3<f64>,
}

#[derive(Debug, Clone)]
pub struct Magnetometer {
    profile: MagnetometerProfile,
    clock: SampleClock,
    noise: Gaussian,
    bias_ut: Vector3<f64>,
}

impl Magnetometer {
    pub fn new(profile: MagnetometerProfile, seed: u64) -> Result<Self> {
        profile.check()?;
        let mut noise = Gaussian::stream(seed, streams::MAGNETOMETER);
        let bias_ut = noise.vector3() * profile.bias_ut;
        Ok(Magnetometer {
            profile,
            clock: SampleClock::new(profile.rate_hz),
            noise,
            bias_ut,
        })
    }

    pub fn profile(&self) -> &MagnetometerProfile {
        &self.profile
    }

    /// Its sample clock (when its samples fall).
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }

    pub fn next_sample_time_s(&self) -> f64 {
        self.clock.next_time_s()
    }

    pub fn is_due(&self, t_s: f64) -> bool {
        self.clock.is_due(t_s)
    }

    pub fn sample(&mut self, truth: &RigidBodyState) -> MagnetometerSample {
        let time_s = self.clock.tick();
        let field_ut = truth
            .attitude
            .inverse_transform_vector(&self.profile.earth_field_ut)
            + self.bias_ut
            + self.noise.vector3() * self.profile.noise_ut;
        MagnetometerSample { time_s, field_ut }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::sensors::{assert_rules_name_fields, RuleCase};
    use nalgebra::UnitQuaternion;

    #[test]
    fn measures_the_field_in_body_axes_with_the_stated_noise() {
        let profile = MagnetometerProfile::st_lis3mdl();
        let mut mag = Magnetometer::new(profile, 5).unwrap();
        let truth = RigidBodyState {
            attitude: UnitQuaternion::from_euler_angles(0.2, -0.1, 1.3),
            ..RigidBodyState::at_rest()
        };
        let expected = truth.attitude.inverse() * profile.earth_field_ut;
        let n = 20_000;
        let mut sum = Vector3::zeros();
        let mut sq = 0.0;
        for k in 0..n {
            let s = mag.sample(&truth);
            assert_eq!(s.time_s, k as f64 / 80.0);
            let e = s.field_ut - expected;
            sum += e;
            sq += e.norm_squared();
        }
        // Mean error within 4 standard errors (0.41 / sqrt(n) = 0.003 uT); variance per axis
        // within 3 % (standard error sqrt(2 / 3n) = 0.6 %).
        assert!((sum / n as f64).amax() < 4.0 * 0.41 / (n as f64).sqrt());
        let var = sq / (3 * n) as f64;
        assert!((var / (0.41 * 0.41) - 1.0).abs() < 0.03, "{var}");
    }

    #[test]
    fn rules_name_the_field() {
        let cases: &[RuleCase<MagnetometerProfile>] = &[
            ("magnetometer.rate_hz", |p| p.rate_hz = 0.0),
            ("magnetometer.noise_ut", |p| p.noise_ut = f64::NAN),
            ("magnetometer.bias_ut", |p| p.bias_ut = -1.0),
            ("magnetometer.earth_field_ut[1]", |p| {
                p.earth_field_ut.y = f64::INFINITY
            }),
            ("magnetometer.earth_field_ut", |p| {
                p.earth_field_ut = Vector3::zeros()
            }),
        ];
        assert_rules_name_fields(&MagnetometerProfile::default(), cases, |p| p.check());
    }
}
