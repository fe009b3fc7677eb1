//! Seeded, platform-independent random streams for the flight room (sensor models).
//!
//! One generator: SplitMix64 (Steele, Lea and Flood, OOPSLA 2014) for 64-bit words, and the
//! ziggurat method for standard normal samples in Doornik's form (ZIGNOR: "An Improved Ziggurat
//! Method to Generate Normal Random Samples", 2005): 128 layers, the uniform from the top 53 bits
//! of a word and the layer from its low 7 bits (disjoint bits, the fix of Marsaglia and Tsang's
//! correlated original), the tail beyond r = 3.4426 by Marsaglia's exponential rejection. About
//! 99 % of samples cost one word and one comparison: the sensors draw a dozen normals per IMU
//! sample, where Box-Muller's logarithm, square root and sine/cosine would cost more than the
//! simulated flight itself.
//!
//! Independent streams: every sensor draws from its own stream, whose starting state is the
//! SplitMix64 finaliser of the run's seed mixed with a stream number ([`stream_seed`]). Two
//! streams then start at unrelated points of the 2^64 cycle, so changing one sensor (its rate,
//! its presence) never changes what another one draws.

use std::sync::OnceLock;

use nalgebra::Vector3;

/// SplitMix64's increment (the golden ratio in 64-bit fixed point).
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function: a bijection of u64 with full avalanche.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The starting state of stream `stream` of the run seeded `seed`.
pub fn stream_seed(seed: u64, stream: u64) -> u64 {
    mix(seed ^ mix(stream.wrapping_add(1).wrapping_mul(GOLDEN_GAMMA)))
}

/// Ziggurat layers (ZIGNOR): 128 boxes of equal area `V` under the normal density
/// `exp(-x^2 / 2)`, the bottom one with the tail beyond `R`.
const LAYERS: usize = 128;
const R: f64 = 3.442_619_855_899;
const V: f64 = 9.912_563_035_262_17e-3;

/// Layer edges `x[i]` and the ratios `x[i + 1] / x[i]` below which a sample is accepted at once.
struct Ziggurat {
    x: [f64; LAYERS + 1],
    ratio: [f64; LAYERS],
}

fn ziggurat() -> &'static Ziggurat {
    static TABLE: OnceLock<Ziggurat> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut x = [0.0; LAYERS + 1];
        let mut f = (-0.5 * R * R).exp();
        x[0] = V / f;
        x[1] = R;
        for i in 2..LAYERS {
            x[i] = (-2.0 * (V / x[i - 1] + f).ln()).sqrt();
            f = (-0.5 * x[i] * x[i]).exp();
        }
        let ratio = std::array::from_fn(|i| x[i + 1] / x[i]);
        Ziggurat { x, ratio }
    })
}

/// Standard normal (and uniform) samples from SplitMix64 through the ziggurat.
#[derive(Debug, Clone)]
pub struct Gaussian {
    state: u64,
}

impl Gaussian {
    /// The stream starting at `seed` itself.
    pub fn new(seed: u64) -> Self {
        Gaussian { state: seed }
    }

    /// Stream `stream` of the run seeded `seed` (see [`stream_seed`]).
    pub fn stream(seed: u64, stream: u64) -> Self {
        Gaussian::new(stream_seed(seed, stream))
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix(self.state)
    }

    /// Uniform in (0, 1]: 53 random bits, never 0, so a logarithm of it is finite.
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// A standard normal sample (module docs): the common case (one word, one comparison)
    /// inlined, the wedge and tail in `sample_rejected`.
    #[inline]
    pub fn sample(&mut self) -> f64 {
        let z = ziggurat();
        let (layer, u) = self.layer_and_uniform();
        if u.abs() < z.ratio[layer] {
            return u * z.x[layer];
        }
        self.sample_rejected(z, layer, u)
    }

    /// The layer from the low 7 bits of a word and a uniform in [-1, 1) from its top 53 (below
    /// 2^53 the word converts to f64 exactly through i64, one instruction; the scale is a power
    /// of two, exact).
    #[inline]
    fn layer_and_uniform(&mut self) -> (usize, f64) {
        let bits = self.next_u64();
        let layer = (bits & 0x7F) as usize;
        let top = (bits >> 11) as i64 as f64;
        (layer, 2.0 * (top * (1.0 / (1u64 << 53) as f64)) - 1.0)
    }

    /// The rest of the ziggurat after the box test failed for `layer` and `u`: the tail or
    /// the wedge, then fresh words until one is accepted.
    #[cold]
    #[inline(never)]
    fn sample_rejected(&mut self, z: &Ziggurat, mut layer: usize, mut u: f64) -> f64 {
        loop {
            if layer == 0 {
                // Beyond R: x = R + e with e exponential, accepted with exp(-e^2 / 2).
                loop {
                    let e = -self.uniform().ln() / R;
                    let y = -self.uniform().ln();
                    if 2.0 * y >= e * e {
                        return if u < 0.0 { -(R + e) } else { R + e };
                    }
                }
            }
            // The wedge between the box and the density: accept under exp(-x^2 / 2).
            let x = u * z.x[layer];
            let f0 = (-0.5 * (z.x[layer] * z.x[layer] - x * x)).exp();
            let f1 = (-0.5 * (z.x[layer + 1] * z.x[layer + 1] - x * x)).exp();
            if f1 + self.uniform() * (f0 - f1) < 1.0 {
                return x;
            }
            (layer, u) = self.layer_and_uniform();
            if u.abs() < z.ratio[layer] {
                return u * z.x[layer];
            }
        }
    }

    /// Three independent standard normal samples.
    #[inline]
    pub fn vector3(&mut self) -> Vector3<f64> {
        let x = self.sample();
        let y = self.sample();
        let z = self.sample();
        Vector3::new(x, y, z)
    }

    /// `true` with probability `p` (0 <= p <= 1).
    pub fn bernoulli(&mut self, p: f64) -> bool {
        // uniform() is in (0, 1]: p = 0 never fires, p = 1 always does.
        self.uniform() <= p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The standard normal CDF through erfc (Numerical Recipes' Chebyshev fit, |error| < 1.2e-7):
    /// an independent reference for the sampler.
    fn normal_cdf(x: f64) -> f64 {
        let z = x.abs() / std::f64::consts::SQRT_2;
        let t = 1.0 / (1.0 + 0.5 * z);
        let poly = -z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77))))))));
        let erfc = t * poly.exp();
        if x >= 0.0 {
            1.0 - 0.5 * erfc
        } else {
            0.5 * erfc
        }
    }

    #[test]
    fn samples_are_standard_normal_and_reproducible() {
        let mut g = Gaussian::new(7);
        let n = 400_000;
        let samples: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        let mean = samples.iter().sum::<f64>() / n as f64;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let kurtosis =
            samples.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n as f64 / var.powi(2);
        // Standard errors: 1/sqrt(n) = 0.0016 (mean), sqrt(2/n) = 0.0022 (variance),
        // sqrt(24/n) = 0.0077 (kurtosis 3 of a normal).
        assert!(mean.abs() < 0.008, "{mean}");
        assert!((var - 1.0).abs() < 0.011, "{var}");
        assert!((kurtosis - 3.0).abs() < 0.04, "{kurtosis}");
        // Chi-square against the CDF over 40 bins of equal probability 1/40 (boundaries by
        // bisection of the reference CDF, tails included): 39 degrees of freedom, 99.9 % point
        // 72.1.
        let bins = 40;
        let mut edges = Vec::with_capacity(bins - 1);
        for k in 1..bins {
            let target = k as f64 / bins as f64;
            let (mut lo, mut hi) = (-8.0, 8.0);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if normal_cdf(mid) < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            edges.push(0.5 * (lo + hi));
        }
        let mut counts = vec![0usize; bins];
        for x in &samples {
            counts[edges.partition_point(|e| e < x)] += 1;
        }
        let expected = n as f64 / bins as f64;
        let chi2: f64 = counts
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 72.1, "chi-square {chi2}");
        // The tails, where the ziggurat switches method: P(|x| > 3.4426) = 5.76e-4 (the bottom
        // layer's tail), P(|x| > 4) = 6.33e-5; within 4 standard errors of the counts.
        for (cut, p) in [(R, 2.0 * (1.0 - normal_cdf(R))), (4.0, 6.334e-5)] {
            let hits = samples.iter().filter(|x| x.abs() > cut).count() as f64;
            let expect = p * n as f64;
            assert!(
                (hits - expect).abs() < 4.0 * expect.sqrt(),
                "|x| > {cut}: {hits} vs {expect}"
            );
        }
        let mut again = Gaussian::new(7);
        assert!(samples[..100].iter().all(|&x| x == again.sample()));
    }

    #[test]
    fn consecutive_samples_are_uncorrelated() {
        let mut g = Gaussian::new(31);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        for lag in 1..4 {
            let c = xs.windows(lag + 1).map(|w| w[0] * w[lag]).sum::<f64>() / (n - lag) as f64;
            assert!(c.abs() < 4.0 / (n as f64).sqrt(), "lag {lag}: {c}");
        }
        // Squares too (the layer index and the value come from one word).
        let c2 = xs
            .windows(2)
            .map(|w| (w[0] * w[0] - 1.0) * (w[1] * w[1] - 1.0))
            .sum::<f64>()
            / (n - 1) as f64
            / 2.0;
        assert!(c2.abs() < 4.0 / (n as f64).sqrt(), "{c2}");
    }

    #[test]
    fn streams_are_uncorrelated_and_distinct() {
        // Neighbouring seeds and neighbouring stream numbers: the SplitMix64 states of seeds s
        // and s + k * gamma would be shifted copies of one sequence; the mixed starts are not.
        let n = 100_000;
        let pairs = [
            ((1, 0), (1, 1)),
            ((1, 0), (2, 0)),
            ((0, 3), (GOLDEN_GAMMA, 3)),
        ];
        for ((sa, ka), (sb, kb)) in pairs {
            let mut a = Gaussian::stream(sa, ka);
            let mut b = Gaussian::stream(sb, kb);
            let xs: Vec<f64> = (0..n).map(|_| a.sample()).collect();
            let ys: Vec<f64> = (0..n).map(|_| b.sample()).collect();
            let corr = xs.iter().zip(&ys).map(|(x, y)| x * y).sum::<f64>() / n as f64;
            // 4 standard errors of a zero correlation: 4 / sqrt(n) = 0.013.
            assert!(
                corr.abs() < 0.013,
                "streams ({sa},{ka}) and ({sb},{kb}): {corr}"
            );
            // Not a shifted copy either: no sample of the first 1000 of one appears in the other.
            let set: std::collections::HashSet<u64> =
                xs[..1000].iter().map(|x| x.to_bits()).collect();
            assert!(ys[..1000].iter().all(|y| !set.contains(&y.to_bits())));
        }
    }

    #[test]
    fn bernoulli_frequency() {
        let mut g = Gaussian::new(3);
        let n = 100_000;
        let hits = (0..n).filter(|_| g.bernoulli(0.2)).count() as f64 / n as f64;
        // Standard error sqrt(0.2 * 0.8 / n) = 0.0013.
        assert!((hits - 0.2).abs() < 0.005, "{hits}");
        assert!(!(0..1000).any(|_| g.bernoulli(0.0)));
        assert!((0..1000).all(|_| g.bernoulli(1.0)));
    }
}
