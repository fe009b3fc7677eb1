//! Position sources: motion capture and GNSS. Each samples the true state on its own clock,
//! adds its errors, and delivers the sample `latency_s` later (stamped with both its time of
//! validity and its arrival), or not at all while it is dropped out.
//!
//! Errors per axis (horizontal x, y; vertical z):
//!
//! ```text
//! z_k = p(t_k) + d_k + n_k                    n_k ~ N(0, sigma_white^2)          (white)
//! d_0 ~ N(0, sigma_drift^2),  d_{k+1} = phi d_k + sqrt(1 - phi^2) sigma_drift w_k,
//! phi = exp(-T / tau)                         (first-order Gauss-Markov drift)
//! ```
//!
//! GNSS errors are mostly the slow drift (atmosphere, multipath, orbit and clock residuals, with
//! correlation times of minutes); sample-to-sample noise is much smaller. Velocity (GNSS: from
//! Doppler) has white noise only; motion capture also gives the attitude, with a rotation error
//! `q_m = q Exp(n)`, `n ~ N(0, sigma_att^2 I)`. Dropouts (GNSS under trees, a mocap marker
//! occluded) follow a two-state Markov chain checked at each sample: from available to dropped
//! with probability `1 - exp(-T / mean_interval_s)`, back with `1 - exp(-T / mean_duration_s)`;
//! the source is unavailable `mean_duration / (mean_interval + mean_duration)` of the time.

use std::collections::VecDeque;

use nalgebra::{UnitQuaternion, Vector3};

use crate::error::{require_non_negative, Result};
use crate::flight::random::Gaussian;
use crate::flight::sensors::clock::SampleClock;
use crate::flight::sensors::{require_positive, streams, CEP_TO_SIGMA, MEDIAN_TO_SIGMA};
use crate::state::RigidBodyState;

/// A position source's error model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionSourceProfile {
    pub rate_hz: f64,
    /// Time from validity to arrival, s.
    pub latency_s: f64,
    /// White position noise, per horizontal axis and vertically, m (1 sigma).
    pub horizontal_noise_m: f64,
    pub vertical_noise_m: f64,
    /// Gauss-Markov position drift, per horizontal axis and vertically, m (1 sigma, stationary).
    pub horizontal_drift_m: f64,
    pub vertical_drift_m: f64,
    /// Correlation time of the drift, s.
    pub drift_time_constant_s: f64,
    /// Velocity noise per axis, m/s (1 sigma); `None`: no velocity output.
    pub velocity_noise_m_s: Option<f64>,
    /// Attitude noise per axis, rad (1 sigma); `None`: no attitude output.
    pub attitude_noise_rad: Option<f64>,
    pub dropouts: Option<Dropouts>,
}

/// The two-state dropout chain (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dropouts {
    pub mean_interval_s: f64,
    pub mean_duration_s: f64,
}

impl PositionSourceProfile {
    /// OptiTrack PrimeX 13 motion capture (product specification: 240 FPS native, 4.2 ms
    /// camera latency, +/- 0.20 mm 3D accuracy), streaming the rigid body's pose. Latency 5 ms
    /// in total (camera plus solve and stream; Qualisys measured 6-7 ms end to end at 200 Hz in
    /// ETH's tests). The attitude noise is derived: 0.2 mm markers, four of them 0.1 m from the
    /// centre, `0.2 mm / (0.1 m sqrt(2))` = 0.08 deg.
    pub fn optitrack_primex_13() -> Self {
        PositionSourceProfile {
            rate_hz: 240.0,
            latency_s: 5e-3,
            horizontal_noise_m: 0.2e-3,
            vertical_noise_m: 0.2e-3,
            horizontal_drift_m: 0.0,
            vertical_drift_m: 0.0,
            drift_time_constant_s: 0.0,
            velocity_noise_m_s: None,
            attitude_noise_rad: Some(0.2e-3 / (0.1 * std::f64::consts::SQRT_2)),
            dropouts: None,
        }
    }

    /// u-blox NEO-M8N (data sheet UBX-15031086): 2.5 m CEP horizontal, velocity 0.05 m/s
    /// (50 %), at 5 Hz (up to 10 Hz with concurrent GNSS). Decided here (README, "GNSS"):
    /// the CEP is the Gauss-Markov drift (sigma = CEP / 1.1774, tau = 60 s), vertical 1.5 times
    /// horizontal (PX4's VDOP/HDOP ratio); white noise 0.1 m; latency 110 ms (PX4's
    /// EKF2_GPS_DELAY default); a dropout every 120 s on average, lasting 3 s (an assumption
    /// for flight near trees and buildings, not a datasheet figure).
    pub fn ublox_neo_m8n() -> Self {
        let horizontal_drift_m = 2.5 / CEP_TO_SIGMA;
        PositionSourceProfile {
            rate_hz: 5.0,
            latency_s: 0.110,
            horizontal_noise_m: 0.1,
            vertical_noise_m: 0.15,
            horizontal_drift_m,
            vertical_drift_m: 1.5 * horizontal_drift_m,
            drift_time_constant_s: 60.0,
            velocity_noise_m_s: Some(0.05 / MEDIAN_TO_SIGMA),
            attitude_noise_rad: None,
            dropouts: Some(Dropouts {
                mean_interval_s: 120.0,
                mean_duration_s: 3.0,
            }),
        }
    }

    /// u-blox ZED-F9P with RTK corrections (data sheet UBX-17051259): 0.01 m + 1 ppm CEP
    /// horizontal (0.01 m: a base within 1 km adds 1 mm), velocity 0.05 m/s (50 %), at 10 Hz
    /// (RTK up to 20 Hz). Drift and white split as for the NEO-M8N, at the RTK level; latency
    /// 110 ms; no dropouts (a fixed RTK solution in the open).
    pub fn ublox_zed_f9p_rtk() -> Self {
        let horizontal_drift_m = 0.01 / CEP_TO_SIGMA;
        PositionSourceProfile {
            rate_hz: 10.0,
            latency_s: 0.110,
            horizontal_noise_m: 0.003,
            vertical_noise_m: 0.005,
            horizontal_drift_m,
            vertical_drift_m: 1.5 * horizontal_drift_m,
            drift_time_constant_s: 60.0,
            velocity_noise_m_s: Some(0.05 / MEDIAN_TO_SIGMA),
            attitude_noise_rad: None,
            dropouts: None,
        }
    }

    /// Total position error per horizontal axis and vertically (white and drift), m.
    pub fn position_std_m(&self) -> [f64; 2] {
        [
            self.horizontal_noise_m.hypot(self.horizontal_drift_m),
            self.vertical_noise_m.hypot(self.vertical_drift_m),
        ]
    }

    /// Every rule, naming the field (`position.rate_hz`, ...).
    pub fn check(&self) -> Result<()> {
        require_positive("position.rate_hz", self.rate_hz)?;
        require_non_negative("position.latency_s", self.latency_s)?;
        require_non_negative("position.horizontal_noise_m", self.horizontal_noise_m)?;
        require_non_negative("position.vertical_noise_m", self.vertical_noise_m)?;
        require_non_negative("position.horizontal_drift_m", self.horizontal_drift_m)?;
        require_non_negative("position.vertical_drift_m", self.vertical_drift_m)?;
        if self.horizontal_drift_m > 0.0 || self.vertical_drift_m > 0.0 {
            require_positive("position.drift_time_constant_s", self.drift_time_constant_s)?;
        } else {
            require_non_negative("position.drift_time_constant_s", self.drift_time_constant_s)?;
        }
        if let Some(v) = self.velocity_noise_m_s {
            require_non_negative("position.velocity_noise_m_s", v)?;
        }
        if let Some(a) = self.attitude_noise_rad {
            require_non_negative("position.attitude_noise_rad", a)?;
        }
        if let Some(d) = self.dropouts {
            require_positive("position.dropouts.mean_interval_s", d.mean_interval_s)?;
            require_positive("position.dropouts.mean_duration_s", d.mean_duration_s)?;
        }
        Ok(())
    }
}

/// The OptiTrack PrimeX 13.
impl Default for PositionSourceProfile {
    fn default() -> Self {
        PositionSourceProfile::optitrack_primex_13()
    }
}

/// One position (and, where the source gives them, velocity and attitude) measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionSample {
    /// When the measurement is true (the estimator fuses it there), s.
    pub valid_at_s: f64,
    /// When it reaches the flight computer, s.
    pub arrives_at_s: f64,
    pub position_m: Vector3<f64>,
    pub velocity_m_s: Option<Vector3<f64>>,
    pub attitude: Option<UnitQuaternion<f64>>,
}

/// A seeded position source with its delay line.
#[derive(Debug, Clone)]
pub struct PositionSource {
    profile: PositionSourceProfile,
    clock: SampleClock,
    noise: Gaussian,
    drift_m: Vector3<f64>,
    drift_phi: f64,
    dropped: bool,
    in_flight: VecDeque<PositionSample>,
    dropped_samples: u64,
}

impl PositionSource {
    pub fn new(profile: PositionSourceProfile, seed: u64) -> Result<Self> {
        profile.check()?;
        let mut noise = Gaussian::stream(seed, streams::POSITION);
        let period = 1.0 / profile.rate_hz;
        let drift_std = drift_std(&profile);
        let drift_m = noise.vector3().component_mul(&drift_std);
        let drift_phi = if profile.drift_time_constant_s > 0.0 {
            (-period / profile.drift_time_constant_s).exp()
        } else {
            0.0
        };
        Ok(PositionSource {
            profile,
            clock: SampleClock::new(profile.rate_hz),
            noise,
            drift_m,
            drift_phi,
            dropped: false,
            in_flight: VecDeque::new(),
            dropped_samples: 0,
        })
    }

    pub fn profile(&self) -> &PositionSourceProfile {
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

    /// Measures `truth` at [`PositionSource::next_sample_time_s`] (unless dropped out) and puts
    /// the sample on its way; [`PositionSource::poll`] hands it over when it arrives.
    pub fn sample(&mut self, truth: &RigidBodyState) {
        let valid_at_s = self.clock.tick();
        let p = &self.profile;
        let period = self.clock.period_s();
        if let Some(d) = p.dropouts {
            let switch = if self.dropped {
                1.0 - (-period / d.mean_duration_s).exp()
            } else {
                1.0 - (-period / d.mean_interval_s).exp()
            };
            if self.noise.bernoulli(switch) {
                self.dropped = !self.dropped;
            }
        }
        // The drift moves whether or not the sample is delivered.
        let position_m = truth.position_m
            + self.drift_m
            + self.noise.vector3().component_mul(&Vector3::new(
                p.horizontal_noise_m,
                p.horizontal_noise_m,
                p.vertical_noise_m,
            ));
        self.drift_m = self.drift_m * self.drift_phi
            + self.noise.vector3().component_mul(&drift_std(p))
                * (1.0 - self.drift_phi * self.drift_phi).sqrt();
        let velocity_m_s = p
            .velocity_noise_m_s
            .map(|s| truth.velocity_m_s + self.noise.vector3() * s);
        let attitude = p
            .attitude_noise_rad
            .map(|s| truth.attitude * UnitQuaternion::from_scaled_axis(self.noise.vector3() * s));
        if self.dropped {
            self.dropped_samples += 1;
            return;
        }
        self.in_flight.push_back(PositionSample {
            valid_at_s,
            arrives_at_s: valid_at_s + p.latency_s,
            position_m,
            velocity_m_s,
            attitude,
        });
    }

    /// The oldest sample that has arrived by `t_s`, if any (call until `None`).
    pub fn poll(&mut self, t_s: f64) -> Option<PositionSample> {
        match self.in_flight.front() {
            Some(s) if s.arrives_at_s <= t_s + 1e-9 => self.in_flight.pop_front(),
            _ => None,
        }
    }

    /// `true` while the source is dropped out.
    pub fn is_dropped(&self) -> bool {
        self.dropped
    }

    /// Samples lost to dropouts so far.
    pub fn dropped_samples(&self) -> u64 {
        self.dropped_samples
    }

    /// The current drift (the truth a drift estimate would be scored against), m.
    pub fn drift_m(&self) -> Vector3<f64> {
        self.drift_m
    }
}

fn drift_std(p: &PositionSourceProfile) -> Vector3<f64> {
    Vector3::new(
        p.horizontal_drift_m,
        p.horizontal_drift_m,
        p.vertical_drift_m,
    )
}

#[cfg(test)]
#[path = "position_tests.rs"]
mod tests;
