//! Sensor noise on what the controller sees ([`SensorNoise`]) and its deterministic Gaussian
//! source.

use crate::error::{Result, RfError};
use crate::state::STATE_DIM;

/// Additive Gaussian noise on each of the 12 measured state components (position, velocity,
/// Euler angles, body rates; see [`crate::state::state_vector`]), with standard deviation
/// `relative_std |x_i| + absolute_std[i]`.
///
/// `relative_std = 10^(-SNR / 20)` is a per-sample signal-to-noise ratio (Wang et al. add noise
/// "with the signal-to-noise ratio as 15 dB ... to all the feedback states" without saying how the
/// signal power is measured; per sample is the causal reading, decided here and documented).
/// Deterministic for a given `seed` on every platform (SplitMix64 and Box-Muller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorNoise {
    pub relative_std: f64,
    pub absolute_std: [f64; STATE_DIM],
    pub seed: u64,
}

impl SensorNoise {
    /// Relative noise at `snr_db` decibels.
    pub fn from_snr_db(snr_db: f64, seed: u64) -> Self {
        SensorNoise {
            relative_std: 10f64.powf(-snr_db / 20.0),
            absolute_std: [0.0; STATE_DIM],
            seed,
        }
    }

    pub(crate) fn check(&self) -> Result<()> {
        if !(self.relative_std.is_finite() && self.relative_std >= 0.0) {
            return Err(RfError::invalid(
                "noise.snr_db",
                "must give a finite, non-negative noise level",
            ));
        }
        for (i, &v) in self.absolute_std.iter().enumerate() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(RfError::invalid(
                    format!("noise.std[{i}]"),
                    format!("must be finite and >= 0, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// Standard normal samples from SplitMix64 through Box-Muller.
pub(crate) struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    pub(crate) fn new(seed: u64) -> Self {
        Gaussian {
            state: seed,
            spare: None,
        }
    }

    fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // 53 random bits in (0, 1]: never 0, so the logarithm below is finite.
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    pub(crate) fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let radius = (-2.0 * u1.ln()).sqrt();
        let angle = 2.0 * std::f64::consts::PI * u2;
        self.spare = Some(radius * angle.sin());
        radius * angle.cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_samples_have_unit_variance_and_are_reproducible() {
        let mut g = Gaussian::new(7);
        let samples: Vec<f64> = (0..200_000).map(|_| g.sample()).collect();
        let mean = samples.iter().sum::<f64>() / samples.len() as f64;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / samples.len() as f64;
        // Standard errors: 1/sqrt(n) = 0.0022 for the mean, sqrt(2/n) = 0.0032 for the variance.
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.015, "{var}");
        let mut again = Gaussian::new(7);
        assert!(samples[..10].iter().all(|&x| x == again.sample()));
    }
}
