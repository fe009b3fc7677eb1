//! The overlapping Allan deviation of a rate record (IEEE Std 952-1997, Annex C) and the fit of
//! the two noise terms of the IMU model to it.
//!
//! For samples `y_k` at period `T`, the angle `theta_j = T sum_{k<j} y_k` (j = 0..N) and cluster
//! time `tau = m T`:
//!
//! ```text
//! sigma^2(tau) = sum_{j=0}^{N-2m} (theta_{j+2m} - 2 theta_{j+m} + theta_j)^2 / (2 tau^2 (N - 2m + 1))
//! ```
//!
//! White noise of density `N` gives `sigma^2 = N^2 / tau`, a random walk of density `B` gives
//! `B^2 tau / 3`; [`fit_white_and_walk`] solves for both by least squares on the relative error
//! of `sigma^2`.

use nalgebra::{Matrix2, Vector2};

use crate::error::{Result, RfError};
use crate::flight::sensors::require_positive;

/// One point of an Allan deviation curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllanPoint {
    pub tau_s: f64,
    pub deviation: f64,
    /// Samples per cluster, `m`.
    pub cluster_size: usize,
    /// Number of overlapping cluster pairs averaged.
    pub terms: usize,
}

/// The overlapping Allan deviation of `samples` (at `rate_hz`) at each cluster size `m` in
/// `cluster_sizes` (each >= 1 and at most (N - 1) / 2).
pub fn overlapping_allan_deviation(
    samples: &[f64],
    rate_hz: f64,
    cluster_sizes: &[usize],
) -> Result<Vec<AllanPoint>> {
    require_positive("rate_hz", rate_hz)?;
    let n = samples.len();
    if let Some(i) = samples.iter().position(|v| !v.is_finite()) {
        return Err(RfError::invalid(
            format!("samples[{i}]"),
            format!("must be finite, got {}", samples[i]),
        ));
    }
    let period = 1.0 / rate_hz;
    let mut theta = Vec::with_capacity(n + 1);
    let mut sum = 0.0;
    theta.push(0.0);
    for &y in samples {
        sum += y * period;
        theta.push(sum);
    }
    cluster_sizes
        .iter()
        .map(|&m| {
            if m == 0 || 2 * m >= n {
                return Err(RfError::invalid(
                    "cluster_sizes",
                    format!("each must be in 1..={}, got {m}", (n.max(1) - 1) / 2),
                ));
            }
            let terms = n + 1 - 2 * m;
            let tau = m as f64 * period;
            let total: f64 = (0..terms)
                .map(|j| (theta[j + 2 * m] - 2.0 * theta[j + m] + theta[j]).powi(2))
                .sum();
            Ok(AllanPoint {
                cluster_size: m,
                tau_s: tau,
                deviation: (total / (2.0 * tau * tau * terms as f64)).sqrt(),
                terms,
            })
        })
        .collect()
}

/// Cluster sizes spaced evenly in log between 1 and `n / 10` (`per_decade` of them per decade):
/// the longest cluster keeps about ten independent pairs in the record.
pub fn log_spaced_clusters(n: usize, per_decade: usize) -> Vec<usize> {
    let top = (n / 10).max(1) as f64;
    let count = (top.log10() * per_decade as f64).ceil() as usize + 1;
    let mut out: Vec<usize> = (0..count)
        .map(|i| 10f64.powf(i as f64 / per_decade as f64).round() as usize)
        .filter(|&m| m as f64 <= top)
        .collect();
    out.dedup();
    out
}

/// White-noise density `N` and random-walk density `B` of `sigma^2(tau) = N^2 / tau +
/// B^2 tau / 3`, fitted to `points` by weighted least squares on the relative error of
/// `sigma^2`: each point weighs its number of independent cluster pairs, `terms / m` (the
/// relative variance of an Allan variance estimate falls as one over it), so the few-cluster
/// points at long tau do not dominate.
pub fn fit_white_and_walk(points: &[AllanPoint]) -> Result<(f64, f64)> {
    let mut normal = Matrix2::zeros();
    let mut rhs = Vector2::zeros();
    for p in points {
        let var = p.deviation * p.deviation;
        if !(var > 0.0 && var.is_finite()) {
            return Err(RfError::invalid(
                "points",
                "deviations must be finite and > 0",
            ));
        }
        let weight = p.terms as f64 / p.cluster_size.max(1) as f64;
        let row = Vector2::new(1.0 / p.tau_s, p.tau_s / 3.0) / var;
        normal += row * row.transpose() * weight;
        rhs += row * weight;
    }
    let solution = normal
        .lu()
        .solve(&rhs)
        .ok_or_else(|| RfError::invalid("points", "need two or more distinct cluster times"))?;
    Ok((solution[0].max(0.0).sqrt(), solution[1].max(0.0).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::random::Gaussian;

    #[test]
    fn white_noise_follows_n_over_sqrt_tau() {
        // Independent reference: white samples of std s at period T have density N = s sqrt(T),
        // and the Allan deviation of white noise at tau = m T is s / sqrt(m) exactly in
        // expectation. Overlapping estimates at m << n have relative error ~ 1 / sqrt(n / m).
        let (n, rate) = (200_000, 100.0);
        let mut g = Gaussian::new(11);
        let samples: Vec<f64> = (0..n).map(|_| 0.3 * g.sample()).collect();
        let points = overlapping_allan_deviation(&samples, rate, &[1, 4, 16, 64]).unwrap();
        for p in &points {
            let m = p.tau_s * rate;
            let expected = 0.3 / m.sqrt();
            // 4 relative standard errors at m = 64: 4 sqrt(0.75 m / n)... bounded by 8 %.
            assert!(
                (p.deviation / expected - 1.0).abs() < 0.08,
                "{p:?} vs {expected}"
            );
        }
        let (density, walk) = fit_white_and_walk(&points).unwrap();
        assert!(
            (density / (0.3 / rate.sqrt()) - 1.0).abs() < 0.03,
            "{density}"
        );
        // No walk in the record: the fitted walk's share of sigma^2 at the longest cluster time
        // (0.64 s) stays below 1 %.
        let tau = 0.64;
        assert!(
            walk * walk * tau / 3.0 < 0.01 * density * density / tau,
            "{walk}"
        );
    }

    #[test]
    fn clusters_are_log_spaced_and_in_range() {
        let c = log_spaced_clusters(100_000, 4);
        assert_eq!(c.first(), Some(&1));
        assert!(*c.last().unwrap() <= 10_000);
        assert!(c.windows(2).all(|w| w[0] < w[1]));
        assert!(c.len() >= 15, "{c:?}");
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let err = overlapping_allan_deviation(&[1.0, 2.0, 3.0], 0.0, &[1]).unwrap_err();
        assert!(err.to_string().starts_with("rate_hz:"), "{err}");
        let err = overlapping_allan_deviation(&[1.0, f64::NAN, 3.0], 1.0, &[1]).unwrap_err();
        assert!(err.to_string().starts_with("samples[1]:"), "{err}");
        let err = overlapping_allan_deviation(&[1.0, 2.0, 3.0, 4.0], 1.0, &[2]).unwrap_err();
        assert!(err.to_string().starts_with("cluster_sizes:"), "{err}");
    }
}
