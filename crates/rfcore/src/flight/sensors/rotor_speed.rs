//! Rotor speed feedback, as bidirectional DShot eRPM telemetry delivers it: each ESC reports the
//! period of one electrical revolution in microseconds as a 9-bit mantissa and a 3-bit exponent
//! (`period_us = m << e`, frame `eeem mmmm mmmm cccc`), so the speed is quantised to about
//! 0.2-0.4 % of its value; the flight controller gets it one telemetry period later. Before the
//! encoding a relative noise (the ESC's commutation timing jitter) is added:
//!
//! ```text
//! omega_meas = decode(encode(omega (1 + sigma_rel n)))     n ~ N(0, 1)
//! period_us  = floor(2 pi 1e6 / (|omega| pole_pairs))
//! ```
//!
//! A rotor slower than the longest encodable period (511 << 7 us) reads 0; the direction comes
//! from the command, so the measured speed keeps the sign of the true one.

use std::collections::VecDeque;

use crate::error::{require_len, require_non_negative, Result};
use crate::flight::random::Gaussian;
use crate::flight::sensors::clock::SampleClock;
use crate::flight::sensors::{require_positive, streams};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorSpeedProfile {
    pub rate_hz: f64,
    pub latency_s: f64,
    /// Relative noise before the encoding (1 sigma).
    pub relative_noise: f64,
    /// Motor pole pairs (14 magnets: 7); 0 turns the eRPM quantisation off.
    pub pole_pairs: u32,
}

impl RotorSpeedProfile {
    /// Bidirectional DShot eRPM telemetry (Betaflight / Bluejay frame format) from 14-pole
    /// motors, read at 1 kHz with one period of latency; 0.3 % jitter (an assumption of the
    /// order of the encoding's own resolution, not a datasheet figure).
    pub fn bidirectional_dshot() -> Self {
        RotorSpeedProfile {
            rate_hz: 1000.0,
            latency_s: 1e-3,
            relative_noise: 0.003,
            pole_pairs: 7,
        }
    }

    pub fn check(&self) -> Result<()> {
        require_positive("rotor_speed.rate_hz", self.rate_hz)?;
        require_non_negative("rotor_speed.latency_s", self.latency_s)?;
        require_non_negative("rotor_speed.relative_noise", self.relative_noise)?;
        Ok(())
    }
}

/// Bidirectional DShot.
impl Default for RotorSpeedProfile {
    fn default() -> Self {
        RotorSpeedProfile::bidirectional_dshot()
    }
}

/// The speed a DShot eRPM frame carries for `omega_rad_s` (module docs), rad/s.
pub fn dshot_quantised(omega_rad_s: f64, pole_pairs: u32) -> f64 {
    if pole_pairs == 0 {
        return omega_rad_s;
    }
    let electrical = omega_rad_s.abs() * pole_pairs as f64;
    const LONGEST_US: u64 = 511 << 7;
    if electrical * LONGEST_US as f64 <= 2.0 * std::f64::consts::PI * 1e6 {
        return 0.0;
    }
    let period_us = (2.0 * std::f64::consts::PI * 1e6 / electrical).floor() as u64;
    let mut exponent = 0;
    while (period_us >> exponent) > 511 {
        exponent += 1;
    }
    let decoded_us = (period_us >> exponent) << exponent;
    (2.0 * std::f64::consts::PI * 1e6 / (decoded_us as f64 * pole_pairs as f64))
        .copysign(omega_rad_s)
}

/// A seeded rotor speed sensor for `rotor_count` rotors.
#[derive(Debug, Clone)]
pub struct RotorSpeedSensor {
    profile: RotorSpeedProfile,
    clock: SampleClock,
    noise: Gaussian,
    /// (valid at, arrives at, speeds) on their way; spare buffers are reused.
    in_flight: VecDeque<(f64, f64, Vec<f64>)>,
    spare: Vec<Vec<f64>>,
    latest: Vec<f64>,
    latest_valid_at_s: f64,
}

impl RotorSpeedSensor {
    pub fn new(profile: RotorSpeedProfile, rotor_count: usize, seed: u64) -> Result<Self> {
        profile.check()?;
        Ok(RotorSpeedSensor {
            profile,
            clock: SampleClock::new(profile.rate_hz),
            noise: Gaussian::stream(seed, streams::ROTOR_SPEED),
            in_flight: VecDeque::new(),
            spare: Vec::new(),
            latest: vec![f64::NAN; rotor_count],
            latest_valid_at_s: f64::NAN,
        })
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

    /// Measures the true speeds (one per rotor, rad/s) at the next sample time.
    pub fn sample(&mut self, speeds_rad_s: &[f64]) -> Result<()> {
        require_len("speeds_rad_s", speeds_rad_s, self.latest.len())?;
        let valid_at = self.clock.tick();
        let mut out = self.spare.pop().unwrap_or_default();
        out.clear();
        let (sigma, pole_pairs) = (self.profile.relative_noise, self.profile.pole_pairs);
        for &w in speeds_rad_s {
            let noisy = w * (1.0 + sigma * self.noise.sample());
            out.push(dshot_quantised(noisy, pole_pairs));
        }
        self.in_flight
            .push_back((valid_at, valid_at + self.profile.latency_s, out));
        Ok(())
    }

    /// Takes every sample that has arrived by `t_s`; `true` if [`RotorSpeedSensor::latest`]
    /// changed.
    pub fn poll(&mut self, t_s: f64) -> bool {
        let mut changed = false;
        while matches!(self.in_flight.front(), Some((_, arrives, _)) if *arrives <= t_s + 1e-9) {
            if let Some((valid_at, _, speeds)) = self.in_flight.pop_front() {
                let old = std::mem::replace(&mut self.latest, speeds);
                self.spare.push(old);
                self.latest_valid_at_s = valid_at;
                changed = true;
            }
        }
        changed
    }

    /// The newest arrived speeds (NaN before the first arrives), rad/s.
    pub fn latest(&self) -> &[f64] {
        &self.latest
    }

    /// When the newest arrived speeds were measured, s (NaN before the first).
    pub fn latest_valid_at_s(&self) -> f64 {
        self.latest_valid_at_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::sensors::{assert_rules_name_fields, RuleCase};

    #[test]
    fn dshot_encoding_matches_the_frame_format() {
        // 1000 rad/s, 7 pole pairs: 2 pi 1e6 / 7000 = 897.59 us -> 897 us; 897 >> 1 = 448
        // (mantissa < 512), decoded 896 us: 2 pi 1e6 / (896 * 7) = 1001.75 rad/s.
        let w = dshot_quantised(1000.0, 7);
        assert!(
            (w - 2.0 * std::f64::consts::PI * 1e6 / (896.0 * 7.0)).abs() < 1e-9,
            "{w}"
        );
        assert!(dshot_quantised(-1000.0, 7) < 0.0);
        // Resolution: one mantissa step in 256..511 is 0.2 to 0.4 % of the speed, and the
        // decoded period never exceeds the true one (truncation): the reading is never slow.
        for k in 0..2000 {
            let w = 50.0 + k as f64 * 1.7;
            let q = dshot_quantised(w, 7);
            assert!(q >= w && (q - w) / w < 0.0040, "{w} -> {q}");
        }
        // Below the longest encodable period the rotor reads as stopped.
        assert_eq!(dshot_quantised(10.0, 7), 0.0);
        assert_eq!(dshot_quantised(123.4, 0), 123.4);
    }

    #[test]
    fn samples_arrive_after_the_latency_at_the_rate() {
        let profile = RotorSpeedProfile {
            relative_noise: 0.0,
            ..RotorSpeedProfile::bidirectional_dshot()
        };
        let mut sensor = RotorSpeedSensor::new(profile, 2, 1).unwrap();
        assert!(sensor.latest()[0].is_nan());
        sensor.sample(&[900.0, 1100.0]).unwrap();
        assert!(!sensor.poll(0.5e-3));
        sensor.sample(&[950.0, 1150.0]).unwrap();
        assert!(sensor.poll(1e-3));
        assert_eq!(sensor.latest_valid_at_s(), 0.0);
        assert_eq!(
            sensor.latest(),
            &[dshot_quantised(900.0, 7), dshot_quantised(1100.0, 7)]
        );
        assert!(sensor.poll(2e-3));
        assert_eq!(sensor.latest_valid_at_s(), 1e-3);
        let err = sensor.sample(&[1.0]).unwrap_err().to_string();
        assert!(err.starts_with("speeds_rad_s:"), "{err}");
    }

    #[test]
    fn jitter_has_the_stated_relative_spread() {
        let profile = RotorSpeedProfile {
            pole_pairs: 0,
            ..RotorSpeedProfile::bidirectional_dshot()
        };
        let mut sensor = RotorSpeedSensor::new(profile, 1, 9).unwrap();
        let n = 20_000;
        let mut sq = 0.0;
        for k in 0..n {
            sensor.sample(&[800.0]).unwrap();
            sensor.poll(k as f64 * 1e-3 + 1e-3);
            sq += (sensor.latest()[0] / 800.0 - 1.0).powi(2);
        }
        let std = (sq / n as f64).sqrt();
        // Standard error of a standard deviation: 1 / sqrt(2n) = 0.5 %.
        assert!((std / 0.003 - 1.0).abs() < 0.02, "{std}");
    }

    #[test]
    fn rules_name_the_field() {
        let cases: &[RuleCase<RotorSpeedProfile>] = &[
            ("rotor_speed.rate_hz", |p| p.rate_hz = f64::INFINITY),
            ("rotor_speed.latency_s", |p| p.latency_s = -1.0),
            ("rotor_speed.relative_noise", |p| {
                p.relative_noise = f64::NAN
            }),
        ];
        assert_rules_name_fields(&RotorSpeedProfile::default(), cases, |p| p.check());
    }
}
